//! Round trips of `results.h5` through the writer and reader: finished, failed and running runs,
//! incremental appends, resume/truncate, merge, and refusal of unknown schema versions.

use rbc_schema::results::*;
use rbc_schema::SchemaError;
use std::collections::BTreeMap;
use std::path::Path;

fn attrs(shape: &str, r: f64) -> RunAttrs {
    // the paper's offset line z = 5 y / 9: y = r * 9 / sqrt(106)
    let y = r * 9.0 / 106f64.sqrt();
    RunAttrs { start_shape: shape.into(), r_init_um: r, y_init_um: y, z_init_um: 5.0 * y / 9.0, lambda: 5.0, scene: "[cell]\nshape = \"discocyte\"\n".into() }
}

fn tetra() -> Vec<[u32; 3]> {
    vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
}

fn sample(i: usize) -> TimeSample {
    let t = i as f64 * 0.01;
    TimeSample {
        t_s: t,
        centroid_um: [t * 6.5, 0.1 * i as f64, -0.05 * i as f64],
        velocity_mm_s: [6.5, 0.0, 1e-3 * i as f64],
        area_um2: 140.0 + i as f64 * 1e-3,
        volume_um3: 100.0,
        asphericity: 0.2,
        extents_um: [8.0, 7.5 - 1e-3 * i as f64, 2.5],
    }
}

fn verts(s: f64) -> Vec<[f64; 3]> {
    vec![[0.0, 0.0, 0.0], [s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]]
}

fn summary(shape: FinalShape, u: f64) -> RunSummary {
    let mut evidence = BTreeMap::new();
    evidence.insert("mirror_y".to_string(), 0.01);
    RunSummary {
        status: RunStatus::Steady,
        final_shape: shape,
        tank_treading: shape == FinalShape::Slipper,
        tumbling: false,
        mean_velocity_mm_s: u,
        min_velocity_mm_s: u - 0.1,
        max_velocity_mm_s: u + 0.1,
        mean_radial_um: 1.2,
        mean_y_um: 1.1,
        mean_z_um: 0.05,
        evidence,
    }
}

/// Writes a file with a finished run (3 samples, 2 snapshots), a failed run and a running run.
fn write_three(path: &Path) {
    let mut f = ResultsFile::create_or_open(path).unwrap();
    let mut w = f.begin_run("done", &attrs("discocyte", 0.5), &tetra()).unwrap();
    for i in 0..3 {
        w.append_sample(&sample(i)).unwrap();
    }
    w.append_snapshot(0.0, &verts(1.0)).unwrap();
    w.append_snapshot(0.02, &verts(2.0)).unwrap();
    w.set_transit(&transit(10.0, FinalShape::Croissant)).unwrap();
    w.finish(&summary(FinalShape::Slipper, 6.5)).unwrap();

    let mut w = f.begin_run("broken", &attrs("croissant", 1.0), &tetra()).unwrap();
    w.append_sample(&sample(0)).unwrap();
    w.fail("GMRES diverged at t = 0.01 s").unwrap();

    let mut w = f.begin_run("ongoing", &attrs("slipper", 1.5), &tetra()).unwrap();
    for i in 0..300 {
        // more than one chunk (256 rows)
        w.append_sample(&sample(i)).unwrap();
    }
    w.set_transit(&transit(2.5, FinalShape::Other)).unwrap();
    w.set_transit(&transit(0.0, FinalShape::Other)).unwrap();
    w.flush().unwrap();
}

fn transit(d: f64, shape: FinalShape) -> Transit {
    Transit { distance_mm: d, t_s: d / 6.5, x_um: d * 1e3 + 0.25, y_um: 0.3, z_um: -0.1 * d, velocity_mm_s: 6.5, shape, from_steady: false }
}

/// Transit records: written at any status, read back by increasing distance (keys `0mm`,
/// `2p5mm`, `10mm`), overwritten when written again, copied by merge (the merge test compares
/// whole records).
#[test]
fn transits_round_trip_and_overwrite() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("r.h5");
    write_three(&path);
    let runs = read_runs(&path).unwrap();
    let by_id = |id: &str| runs.iter().find(|r| r.run_id == id).unwrap().clone();
    assert_eq!(by_id("done").transits, vec![transit(10.0, FinalShape::Croissant)]);
    assert_eq!(by_id("ongoing").transits, vec![transit(0.0, FinalShape::Other), transit(2.5, FinalShape::Other)]);
    assert!(by_id("broken").transits.is_empty());
    assert_eq!((transit_key(10.0), transit_key(0.0), transit_key(2.5)), ("10mm".to_string(), "0mm".to_string(), "2p5mm".to_string()));
    // recorded again (a run replayed from an earlier checkpoint): the same attributes, new values
    let mut f = ResultsFile::create_or_open(&path).unwrap();
    let mut w = f.resume_run("ongoing").unwrap();
    let again = Transit { y_um: 0.5, shape: FinalShape::Slipper, ..transit(2.5, FinalShape::Other) };
    w.set_transit(&again).unwrap();
    w.flush().unwrap();
    drop((w, f));
    let t = read_runs(&path).unwrap().into_iter().find(|r| r.run_id == "ongoing").unwrap().transits;
    assert_eq!(t, vec![transit(0.0, FinalShape::Other), again]);
}

#[test]
fn finished_failed_and_running_runs_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    write_three(&p);
    let runs = read_runs(&p).unwrap();
    let ids: Vec<_> = runs.iter().map(|r| r.run_id.as_str()).collect();
    assert_eq!(ids, ["broken", "done", "ongoing"]);

    let done = &runs[1];
    assert_eq!(done.status, RunStatus::Steady);
    assert_eq!(done.attrs.as_ref().unwrap(), &attrs("discocyte", 0.5));
    assert_eq!(done.summary.as_ref().unwrap(), &summary(FinalShape::Slipper, 6.5));
    assert_eq!((done.n_samples, done.n_snapshots), (3, 2));
    assert_eq!(read_timeseries(&p, "done").unwrap(), (0..3).map(sample).collect::<Vec<_>>());
    let s = read_snapshots(&p, "done").unwrap();
    assert_eq!(s.times_s, vec![0.0, 0.02]);
    assert_eq!(s.vertices_um, vec![verts(1.0), verts(2.0)]);
    assert_eq!(s.triangles, tetra());

    let broken = &runs[0];
    assert_eq!(broken.status, RunStatus::Failed);
    assert!(broken.summary.is_none());
    assert_eq!(broken.failure.as_deref(), Some("GMRES diverged at t = 0.01 s"));
    assert_eq!(broken.n_samples, 1);

    let ongoing = &runs[2];
    assert_eq!(ongoing.status, RunStatus::Running);
    assert!(ongoing.summary.is_none());
    assert_eq!(ongoing.n_samples, 300);
    assert_eq!(read_timeseries(&p, "ongoing").unwrap()[299], sample(299));
}

#[test]
fn reopen_resume_truncate_and_finish() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    write_three(&p);
    let mut f = ResultsFile::create_or_open(&p).unwrap();
    assert!(f.begin_run("ongoing", &attrs("slipper", 1.5), &tetra()).is_err(), "existing run id refused");
    let mut w = f.resume_run("ongoing").unwrap();
    assert_eq!(w.n_samples(), 300);
    // checkpoint at t = 1.0 s: samples 0..=100 survive (t = i * 0.01)
    w.truncate_after(1.0 + 1e-12).unwrap();
    assert_eq!(w.n_samples(), 101);
    w.append_sample(&sample(101)).unwrap();
    w.finish(&summary(FinalShape::Croissant, 2.5)).unwrap();
    drop(f);
    let rec = ResultsFile::open(&p).unwrap().run("ongoing").unwrap();
    assert_eq!(rec.status, RunStatus::Steady);
    assert_eq!(rec.n_samples, 102);
    assert_eq!(rec.summary.unwrap().final_shape, FinalShape::Croissant);
}

#[test]
fn writer_refuses_nan_wrong_vertex_count_and_running_finish() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    let mut f = ResultsFile::create_or_open(&p).unwrap();
    let mut w = f.begin_run("r", &attrs("discocyte", 0.5), &tetra()).unwrap();
    let mut bad = sample(1);
    bad.centroid_um[1] = f64::NAN;
    let e = w.append_sample(&bad).unwrap_err().to_string();
    assert!(e.contains("results.h5") && e.contains("non-finite"), "{e}");
    assert_eq!(w.n_samples(), 0);
    let e = w.append_snapshot(0.0, &verts(1.0)[..3]).unwrap_err().to_string();
    assert!(e.contains("3 vertices, the mesh has 4"), "{e}");
    let mut s = summary(FinalShape::Slipper, 1.0);
    s.status = RunStatus::Running;
    assert!(w.finish(&s).is_err());
    let e = f.begin_run("a/b", &attrs("discocyte", 0.5), &tetra()).err().unwrap().to_string();
    assert!(e.contains("a/b"), "{e}");
}

#[test]
fn merge_combines_runs_and_refuses_duplicates() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.h5");
    let b = dir.path().join("b.h5");
    write_three(&a);
    {
        let mut f = ResultsFile::create_or_open(&b).unwrap();
        let mut w = f.begin_run("extra", &attrs("croissant", 0.2), &tetra()).unwrap();
        w.append_sample(&sample(0)).unwrap();
        w.append_snapshot(0.0, &verts(3.0)).unwrap();
        w.finish(&summary(FinalShape::Croissant, 2.4)).unwrap();
    }
    let out = dir.path().join("all.h5");
    assert_eq!(merge_files(&[a.clone(), b.clone()], &out).unwrap(), 4);
    let merged = read_runs(&out).unwrap();
    let original: Vec<_> = read_runs(&a).unwrap().into_iter().chain(read_runs(&b).unwrap()).collect();
    let mut original = original;
    original.sort_by(|x, y| x.run_id.cmp(&y.run_id));
    assert_eq!(merged, original);
    assert_eq!(read_snapshots(&out, "extra").unwrap().vertices_um, vec![verts(3.0)]);

    let out2 = dir.path().join("dup.h5");
    let e = merge_files(&[a.clone(), a.clone()], &out2).unwrap_err().to_string();
    assert!(e.contains("a.h5") && e.contains("also in"), "{e}");
    assert!(!out2.exists(), "no partial output");
}

#[test]
fn unknown_schema_version_is_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("future.h5");
    {
        let f = hdf5::File::create(&p).unwrap();
        f.new_attr::<u32>().shape(()).create("schema_version").unwrap().write_scalar(&7u32).unwrap();
        f.create_group("runs").unwrap();
    }
    let e = read_runs(&p).unwrap_err();
    assert!(matches!(e, SchemaError::SchemaVersion { .. }), "{e:?}");
    let msg = e.to_string();
    assert!(msg.contains("future.h5") && msg.contains('7') && !msg.contains('\n'), "{msg}");
    assert!(ResultsFile::create_or_open(&p).is_err(), "writer refuses it too");

    // no version at all (some other HDF5 file)
    let q = dir.path().join("other.h5");
    hdf5::File::create(&q).unwrap();
    assert!(matches!(read_runs(&q).unwrap_err(), SchemaError::SchemaVersion { .. }));
    // not HDF5 at all
    let r = dir.path().join("text.h5");
    std::fs::write(&r, "hello").unwrap();
    let msg = read_runs(&r).unwrap_err().to_string();
    assert!(msg.contains("text.h5"), "{msg}");
}

#[test]
fn finished_run_missing_a_summary_attribute_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    write_three(&p);
    {
        let f = hdf5::File::open_rw(&p).unwrap();
        f.group("runs/done").unwrap().delete_attr("mean_velocity_mm_s").unwrap();
    }
    let msg = read_runs(&p).unwrap_err().to_string();
    assert!(msg.contains("results.h5") && msg.contains("runs/done.mean_velocity_mm_s"), "{msg}");
}

#[test]
fn buffered_samples_are_written_on_drop_and_before_snapshots() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    let mut f = ResultsFile::create_or_open(&p).unwrap();
    let mut w = f.begin_run("r", &attrs("discocyte", 0.5), &tetra()).unwrap();
    for i in 0..10 {
        w.append_sample(&sample(i)).unwrap();
    }
    assert_eq!(w.n_samples(), 10);
    // a snapshot is a checkpoint: the samples before it are in the file
    w.append_snapshot(0.1, &verts(1.0)).unwrap();
    assert_eq!(f.run("r").unwrap().n_samples, 10);
    for i in 10..20 {
        w.append_sample(&sample(i)).unwrap();
    }
    drop(w);
    drop(f);
    assert_eq!(read_timeseries(&p, "r").unwrap(), (0..20).map(sample).collect::<Vec<_>>());
    assert_eq!(read_runs(&p).unwrap()[0].status, RunStatus::Running);
}

/// Per-vertex fields: created with the first snapshot, read back, cut by resume truncation,
/// copied by merge; a run begun without them (an older build) resumes without them; a snapshot
/// that leaves out a field the run has, or gives the wrong count, is refused.
#[test]
fn per_vertex_fields_round_trip_truncate_merge_and_stay_absent_in_old_runs() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("r.h5");
    let h = |k: usize| vec![k as f64, 0.5, -0.25 * k as f64, 1e-3];
    let mut f = ResultsFile::create_or_open(&p).unwrap();
    let mut w = f.begin_run("new", &attrs("discocyte", 0.5), &tetra()).unwrap();
    for k in 0..3 {
        w.append_sample(&sample(k)).unwrap();
        w.append_snapshot_with(k as f64 * 0.01, &verts(1.0 + k as f64), &[("h_per_um", &h(k))]).unwrap();
    }
    assert_eq!(w.fields(), ["h_per_um".to_string()]);
    let e = w.append_snapshot(0.03, &verts(1.0)).unwrap_err().to_string();
    assert!(e.contains("h_per_um") && e.contains("r.h5"), "{e}");
    let e = w.append_snapshot_with(0.03, &verts(1.0), &[("h_per_um", &[1.0, 2.0])]).unwrap_err().to_string();
    assert!(e.contains("2 values") && e.contains("4 vertices"), "{e}");
    w.flush().unwrap();
    // an old run: positions only; resumed, a field offered later is left out
    let mut w = f.begin_run("old", &attrs("discocyte", 0.7), &tetra()).unwrap();
    w.append_snapshot(0.0, &verts(1.0)).unwrap();
    drop(w);
    let mut w = f.resume_run("old").unwrap();
    w.append_snapshot_with(0.01, &verts(2.0), &[("h_per_um", &h(1))]).unwrap();
    assert!(w.fields().is_empty());
    drop(w);
    drop(f);

    let s = read_snapshots(&p, "new").unwrap();
    assert_eq!(s.fields["h_per_um"], vec![h(0), h(1), h(2)]);
    let old = read_snapshots(&p, "old").unwrap();
    assert!(old.fields.is_empty() && old.times_s == [0.0, 0.01]);
    let layout = ResultsFile::open(&p).unwrap().snapshot_layout("new").unwrap();
    assert_eq!(layout.fields, vec![VertexField { name: "h_per_um".into(), components: 1, rows: 3 }]);

    let merged = dir.path().join("m.h5");
    merge_files(std::slice::from_ref(&p), &merged).unwrap();
    assert_eq!(read_snapshots(&merged, "new").unwrap(), s);
    assert_eq!(read_snapshots(&merged, "old").unwrap(), old);

    let mut f = ResultsFile::create_or_open(&p).unwrap();
    let mut w = f.resume_run("new").unwrap();
    w.truncate_to(2, 2).unwrap();
    w.append_snapshot_with(0.05, &verts(9.0), &[("h_per_um", &h(9))]).unwrap();
    drop(w);
    drop(f);
    let s = read_snapshots(&p, "new").unwrap();
    assert_eq!((s.times_s.clone(), s.fields["h_per_um"].clone()), (vec![0.0, 0.01, 0.05], vec![h(0), h(1), h(9)]));
}

/// A triangle index beyond the vertices (a damaged file: `rbc-bench fuzz --format results --seed 1
/// --case 57` found such a file) made `rbc-sweep --study-status` and the shape classifier index out of
/// bounds; the reader now refuses it, naming the file, the dataset and the triangle.
#[test]
fn triangle_index_beyond_the_vertices_is_refused_naming_the_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    write_three(&p);
    assert_eq!(read_snapshots(&p, "done").unwrap().triangles, tetra());
    {
        let f = hdf5::File::open_rw(&p).unwrap();
        let d = f.dataset("runs/done/snapshots/triangles").unwrap();
        let mut t = d.read_2d::<u32>().unwrap();
        t[[2, 1]] = 3_405_775_530;
        d.write(&t).unwrap();
    }
    let msg = read_snapshots(&p, "done").unwrap_err().to_string();
    assert!(msg.contains("results.h5") && msg.contains("runs/done/snapshots/triangles") && msg.contains("triangle 2"), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
    // the lazy layout (`rbc-sweep xdmf`) refuses it too
    let msg = ResultsFile::open(&p).unwrap().snapshot_layout("done").map(|_| ()).unwrap_err().to_string();
    assert!(msg.contains("runs/done/snapshots/triangles") && msg.contains("triangle 2"), "{msg}");
}

/// A stored shape with a vertex that is not finite (a damaged or hand-made file) is refused where
/// the shapes enter, naming the file, the dataset, the snapshot and the vertex, as a timeseries
/// row is: `start-shape` and `merge` copied it and then named only their temporary output.
#[test]
fn a_snapshot_vertex_that_is_not_finite_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    write_three(&p);
    {
        let f = hdf5::File::open_rw(&p).unwrap();
        let d = f.dataset("runs/done/snapshots/vertices_um").unwrap();
        let mut v = d.read_raw::<f64>().unwrap();
        let n = v.len();
        v[n - 2] = f64::NAN;
        d.write_raw(&v).unwrap();
    }
    let msg = read_snapshots(&p, "done").unwrap_err().to_string();
    let last = read_timeseries(&p, "done").map(|_| ()).is_ok();
    assert!(last, "the timeseries is untouched");
    assert!(msg.contains("results.h5") && msg.contains("runs/done/snapshots/vertices_um") && msg.contains("vertex 3 is not finite") && msg.contains("snapshot"), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
}

/// A timeseries row the writer would not have stored (a NaN, a time not after the previous row's:
/// a damaged or hand-made file) is refused where the rows enter, naming the file, the dataset and
/// the row, so that no reader (the steady detector, the events, the figures) meets it.
#[test]
fn a_timeseries_row_with_a_nan_or_a_time_running_back_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    write_three(&p);
    assert_eq!(read_timeseries(&p, "done").unwrap().len(), 3);
    for (dataset, row, value, says) in [("t_s", 2usize, 0.005, "after the previous row's 0.01"), ("t_s", 1, f64::NAN, "NaN is not a finite time"), ("asphericity", 2, f64::INFINITY, "not finite")] {
        std::fs::remove_file(&p).unwrap();
        write_three(&p);
        {
            let f = hdf5::File::open_rw(&p).unwrap();
            let d = f.dataset(&format!("runs/done/timeseries/{dataset}")).unwrap();
            let mut v = d.read_raw::<f64>().unwrap();
            v[row] = value;
            d.write_raw(&v).unwrap();
        }
        let msg = read_timeseries(&p, "done").unwrap_err().to_string();
        assert!(msg.contains("results.h5") && msg.contains(&format!("runs/done/timeseries/{dataset}")) && msg.contains(&format!("row {row}")) && msg.contains(says), "{msg}");
        assert!(!msg.contains('\n'), "{msg}");
    }
    // a vector column too
    std::fs::remove_file(&p).unwrap();
    write_three(&p);
    {
        let f = hdf5::File::open_rw(&p).unwrap();
        let d = f.dataset("runs/done/timeseries/extents_um").unwrap();
        let mut e = d.read_2d::<f64>().unwrap();
        e[[1, 0]] = f64::NAN;
        d.write(&e).unwrap();
    }
    let msg = read_timeseries(&p, "done").unwrap_err().to_string();
    assert!(msg.contains("runs/done/timeseries/extents_um") && msg.contains("row 1: not finite"), "{msg}");
}

/// A dataset whose dataspace claims far more elements than the file holds (a damaged file:
/// `rbc-bench fuzz --format results --seed 3 --case 64` asked for 3.8e17 bytes) aborted the process
/// in the allocation; the reader refuses it, naming the file and the dataset.
#[test]
fn a_dataset_larger_than_its_file_is_refused_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("results.h5");
    write_three(&p);
    {
        let f = hdf5::File::open_rw(&p).unwrap();
        // chunked and resizable: the shape grows, no chunk is written, the file stays small
        f.dataset("runs/done/snapshots/vertices_um").unwrap().resize((1usize << 40, 4, 3)).unwrap();
    }
    assert!(std::fs::metadata(&p).unwrap().len() < 1 << 20);
    let msg = read_snapshots(&p, "done").unwrap_err().to_string();
    assert!(msg.contains("results.h5") && msg.contains("runs/done/snapshots/vertices_um") && msg.contains("damaged"), "{msg}");
}

/// A run recorded as not run because its cell overlaps the wall: status `overlaps-wall`, the start
/// attributes and the reason, no rows and no snapshots (the readers return none); it replaces a run
/// of that id (an earlier build's failed attempt), a merge copies it, h5py-style readers see the
/// status string.
#[test]
fn overlaps_wall_runs_round_trip_and_merge() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("r.h5");
    let mut f = ResultsFile::create_or_open(&p).unwrap();
    let w = f.begin_run("disco_r2.25", &attrs("discocyte", 2.25), &tetra()).unwrap();
    w.fail("cell vertex 3 at (y, z) = (1.97, 5.09) um is outside the channel").unwrap();
    f.record_overlaps_wall("disco_r2.25", &attrs("discocyte", 2.25), "r_init_um = 2.25: the cell reaches 0.09 um into the wall").unwrap();
    drop(f);
    let check = |path: &Path| {
        let runs = read_runs(path).unwrap();
        assert_eq!(runs.len(), 1);
        let r = &runs[0];
        assert_eq!((r.status, r.status.as_str(), r.status.is_finished()), (RunStatus::OverlapsWall, "overlaps-wall", false));
        assert_eq!(RunStatus::parse("overlaps-wall"), Some(RunStatus::OverlapsWall));
        assert_eq!(r.not_run.as_deref(), Some("r_init_um = 2.25: the cell reaches 0.09 um into the wall"));
        assert_eq!((r.failure.as_deref(), r.summary.is_none(), r.n_samples, r.n_snapshots), (None, true, 0, 0));
        assert_eq!(r.attrs.as_ref().unwrap(), &attrs("discocyte", 2.25));
        assert!(read_timeseries(path, "disco_r2.25").unwrap().is_empty());
        let s = read_snapshots(path, "disco_r2.25").unwrap();
        assert!(s.times_s.is_empty() && s.triangles.is_empty());
    };
    check(&p);
    let merged = dir.path().join("m.h5");
    assert_eq!(merge_files(&[p], &merged).unwrap(), 1);
    check(&merged);
}

/// A start shape is the last snapshot of an ended run, copied under a new id with the source's
/// start attributes, summary, the sample at that time and where it came from; the run reads back
/// (and a second shape joins the file); a run that has not ended, a name taken twice and the
/// source as its own target are refused, the target left as it was.
#[test]
fn the_last_shape_of_an_ended_run_becomes_a_start_shape() {
    use rbc_schema::start_shape::copy_last_shape;
    let dir = tempfile::tempdir().unwrap();
    let (src, starts) = (dir.path().join("runs.h5"), dir.path().join("starts.h5"));
    write_three(&src);
    assert_eq!(copy_last_shape(&src, "done", &starts, "slipper-start").unwrap(), 0.02);
    let runs = read_runs(&starts).unwrap();
    assert_eq!(runs.len(), 1);
    let (run, done) = (&runs[0], ResultsFile::open(&src).unwrap().run("done").unwrap());
    assert_eq!((run.run_id.as_str(), run.status), ("slipper-start", RunStatus::Steady));
    assert_eq!((&run.attrs, &run.summary), (&done.attrs, &done.summary), "what made it and what it is");
    assert_eq!(run.copied_from.as_deref(), Some("runs.h5: run done, its last snapshot (t = 0.02 s)"));
    assert!(run.transits.is_empty());
    let snaps = read_snapshots(&starts, "slipper-start").unwrap();
    assert_eq!((snaps.times_s, snaps.vertices_um, snaps.triangles), (vec![0.02], vec![verts(2.0)], tetra()));
    assert_eq!(read_timeseries(&starts, "slipper-start").unwrap(), vec![sample(2)], "the sample at the shape's time");
    // a second shape joins the file; a merge keeps where each came from
    copy_last_shape(&src, "done", &starts, "another").unwrap();
    let merged = dir.path().join("merged.h5");
    merge_files(std::slice::from_ref(&starts), &merged).unwrap();
    let ids: Vec<(String, Option<String>)> = read_runs(&merged).unwrap().into_iter().map(|r| (r.run_id, r.copied_from)).collect();
    assert_eq!(ids.len(), 2);
    assert!(ids.iter().all(|(_, c)| c.as_deref() == Some("runs.h5: run done, its last snapshot (t = 0.02 s)")), "{ids:?}");
    // refusals, each naming the file; the target is unchanged
    let before = std::fs::read(&starts).unwrap();
    let taken = copy_last_shape(&src, "done", &starts, "another").unwrap_err().to_string();
    assert!(taken.contains("starts.h5") && taken.contains("`another` already exists"), "{taken}");
    for (run, said) in [("ongoing", "this one is running"), ("broken", "this one is failed")] {
        let e = copy_last_shape(&src, run, &starts, "new").unwrap_err().to_string();
        assert!(e.contains("runs.h5") && e.contains(&format!("runs/{run}.status")) && e.contains(said), "{e}");
    }
    let text = dir.path().join("notes.h5");
    std::fs::write(&text, "not HDF5").unwrap();
    let e = copy_last_shape(&src, "done", &text, "x").unwrap_err().to_string();
    assert!(e.starts_with(&text.display().to_string()) && !e.contains(".notes.h5."), "names the file, not its copy: {e}");
    assert_eq!(std::fs::read(&text).unwrap(), b"not HDF5");
    std::fs::remove_file(&text).unwrap();
    let own = copy_last_shape(&src, "done", &src, "x").unwrap_err().to_string();
    assert!(own.contains("also the source"), "{own}");
    assert_eq!(std::fs::read(&starts).unwrap(), before);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3, "no temporary file left");
}
