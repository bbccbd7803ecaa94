//! `rbc-sweep --figures`: every figure of a synthetic results.h5 (phase diagrams per start shape,
//! radial positions, slipper extents, shape views with cross-sections) is written as PNG and SVG
//! and shows what it should (coloured symbols and surfaces).

mod output_common;

use output_common::{files_in, hidden_entries, pixels_like};
use rbc_schema::results::*;
use std::collections::BTreeMap;
use std::process::Command;

type Vertices = Vec<[f64; 3]>;

/// Croissant-like cup and slipper-like bent ellipsoid on a level-3 sphere mesh (um, channel frame).
fn shapes() -> (Vertices, Vertices, Vec<[u32; 3]>) {
    let m = rbc_solver::mesh::sphere(3, 1.0);
    let cup = m
        .vertices
        .iter()
        .map(|p| {
            [
                1.2 * p.x + 0.18 * 13.0 * (p.y * p.y + p.z * p.z),
                3.6 * p.y,
                3.6 * p.z,
            ]
        })
        .collect();
    let slipper = m
        .vertices
        .iter()
        .map(|p| {
            let (x, y, z) = (4.0 * p.x, 2.2 * p.y, 1.4 * p.z);
            [x + 0.4 * y, y + 0.15 * x * x + 1.2, z]
        })
        .collect();
    let tri = m
        .triangles
        .iter()
        .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
        .collect();
    (cup, slipper, tri)
}

fn write_results(path: &std::path::Path) {
    let (cup, slipper, tri) = shapes();
    let mut f = ResultsFile::create_or_open(path).unwrap();
    let scene = "[walls]\nkind = \"periodic-channel\"\nwidth_y_um = 12.0\nheight_z_um = 10.0\n";
    for start in ["discocyte", "croissant"] {
        for (k, u) in [1.0, 2.5, 5.2].into_iter().enumerate() {
            for r in [0.2, 0.6, 1.0, 1.4] {
                let r_trans = if start == "croissant" {
                    1.2
                } else {
                    0.7 - 0.2 * k as f64
                };
                let shape = if r < r_trans {
                    FinalShape::Croissant
                } else {
                    FinalShape::Slipper
                };
                let id = format!("{start}_u{u}_r{r}");
                let attrs = RunAttrs {
                    start_shape: start.into(),
                    r_init_um: r,
                    y_init_um: r * 0.874,
                    z_init_um: r * 0.486,
                    lambda: 5.0,
                    scene: scene.into(),
                };
                let mut w = f.begin_run(&id, &attrs, &tri).unwrap();
                let verts = if shape == FinalShape::Croissant {
                    &cup
                } else {
                    &slipper
                };
                w.append_snapshot(1.0, verts).unwrap();
                let slip = shape == FinalShape::Slipper;
                let radial = if slip { 0.8 + 0.1 * u } else { 0.02 };
                let mut ev = BTreeMap::new();
                ev.insert("steady_duration_s".to_string(), 1.0 + r);
                ev.insert("radial_min_um".to_string(), radial - 0.05);
                ev.insert("radial_max_um".to_string(), radial + 0.05);
                for (axis, e) in [("x", 9.0 + 0.2 * u), ("y", 6.0), ("z", 3.5 - 0.1 * u)] {
                    ev.insert(format!("extent_{axis}_mean_um"), e);
                    ev.insert(format!("extent_{axis}_min_um"), e - 0.1);
                    ev.insert(format!("extent_{axis}_max_um"), e + 0.1);
                }
                w.finish(&RunSummary {
                    status: if slip {
                        RunStatus::Periodic
                    } else {
                        RunStatus::Steady
                    },
                    final_shape: shape,
                    tank_treading: slip,
                    tumbling: false,
                    mean_velocity_mm_s: u * if slip { 1.02 } else { 1.0 },
                    min_velocity_mm_s: u * 0.97,
                    max_velocity_mm_s: u * 1.05,
                    mean_radial_um: radial,
                    mean_y_um: radial,
                    mean_z_um: 0.0,
                    evidence: ev,
                })
                .unwrap();
            }
        }
    }
    // a failed run is reported and left out
    let attrs = RunAttrs {
        start_shape: "discocyte".into(),
        r_init_um: 2.0,
        y_init_um: 1.7,
        z_init_um: 1.0,
        lambda: 5.0,
        scene: scene.into(),
    };
    f.begin_run("discocyte_u9_r2", &attrs, &tri)
        .unwrap()
        .fail("blow-up")
        .unwrap();
}

#[test]
fn figures_of_a_synthetic_phase_diagram() {
    let dir = tempfile::tempdir().unwrap();
    let results = dir.path().join("results.h5");
    write_results(&results);
    let out = dir.path().join("figs");
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
        .arg("--figures")
        .arg(&results)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("discocyte_u9_r2") && err.contains("failed"),
        "the failed run is reported: {err}"
    );
    for name in [
        "phase_diagram_discocyte",
        "phase_diagram_croissant",
        "radial_position",
        "slipper_extents",
        "shape_croissant",
        "shape_slipper",
    ] {
        for ext in ["png", "svg"] {
            assert!(
                out.join(format!("{name}.{ext}")).is_file(),
                "{name}.{ext} missing"
            );
        }
    }
    // RBC_SWEEP_KEEP=DIR keeps the figures for a look
    if let Ok(keep) = std::env::var("RBC_SWEEP_KEEP") {
        std::fs::create_dir_all(&keep).unwrap();
        for e in std::fs::read_dir(&out).unwrap() {
            let e = e.unwrap();
            std::fs::copy(e.path(), std::path::Path::new(&keep).join(e.file_name())).unwrap();
        }
    }
    let blue = [0x1f, 0x77, 0xb4];
    let red = [0xd6, 0x27, 0x28];
    // phase diagrams hold croissant (blue) and slipper (red) symbols
    assert!(pixels_like(&out.join("phase_diagram_discocyte.png"), blue) > 50);
    assert!(pixels_like(&out.join("phase_diagram_discocyte.png"), red) > 50);
    // the shaded slipper surface is drawn in shades of red: many reddish pixels, no blue surface
    let reddish = |p: &std::path::Path| {
        image::open(p)
            .unwrap()
            .to_rgb8()
            .pixels()
            .filter(|q| q.0[0] > 60 && q.0[0] as u32 > 2 * q.0[2] as u32 + 20)
            .count()
    };
    assert!(
        reddish(&out.join("shape_slipper.png")) > 5000,
        "{}",
        reddish(&out.join("shape_slipper.png"))
    );
    assert!(reddish(&out.join("shape_croissant.png")) < 100);
    let svg = std::fs::read_to_string(out.join("shape_slipper.svg")).unwrap();
    assert!(svg.contains("mid-plane cross-section") && svg.contains("slipper"));
    // no steady run at all: a one-line error naming the file
    let empty = dir.path().join("empty.h5");
    ResultsFile::create_or_open(&empty).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
        .arg("--figures")
        .arg(&empty)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("empty.h5"));
}

/// `rbc-sweep --figures` replaces its figures as a set. A results file whose shape views cannot be
/// drawn (the runs' triangles are gone) fails after the phase diagrams and the radial figure were
/// drawn, and the folder keeps the previous figures byte for byte; a file with the croissant
/// starts removed replaces them all: the croissant start's phase diagram of the first run is gone,
/// a file that is not a figure stays, and no staging folder is left.
#[test]
fn figures_are_replaced_as_a_set() {
    let dir = tempfile::tempdir().unwrap();
    let results = dir.path().join("results.h5");
    write_results(&results);
    let out = dir.path().join("figs");
    let figures = |h5: &std::path::Path| Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).arg("--figures").arg(h5).arg("--out").arg(&out).output().unwrap();
    let o = figures(&results);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let before = files_in(&out);

    let damaged = dir.path().join("damaged.h5");
    std::fs::copy(&results, &damaged).unwrap();
    {
        let f = hdf5::File::open_rw(&damaged).unwrap();
        for id in f.group("runs").unwrap().member_names().unwrap() {
            if let Ok(sn) = f.group(&format!("runs/{id}/snapshots")) {
                sn.unlink("triangles").unwrap();
            }
        }
    }
    let o = figures(&damaged);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("damaged.h5") && err.contains("triangles"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert_eq!(files_in(&out), before, "a failed run leaves the previous figures byte for byte");
    assert_eq!(hidden_entries(dir.path()), Vec::<String>::new());

    let discocyte_only = dir.path().join("discocyte.h5");
    std::fs::copy(&results, &discocyte_only).unwrap();
    {
        let f = hdf5::File::open_rw(&discocyte_only).unwrap();
        let runs = f.group("runs").unwrap();
        for id in runs.member_names().unwrap().into_iter().filter(|id| id.starts_with("croissant_")) {
            runs.unlink(&id).unwrap();
        }
    }
    let o = figures(&discocyte_only);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let after = files_in(&out);
    assert!(!after.contains_key(std::path::Path::new("phase_diagram_croissant.png")), "a figure not drawn again is removed");
    assert_eq!(after[std::path::Path::new("notes.txt")], b"mine");
    let changed = after.iter().filter(|(p, bytes)| before.get(*p) != Some(*bytes)).count();
    assert!(changed >= 2, "the phase diagram and the radial figure are redrawn from the other runs ({changed} changed)");
    assert_eq!(after.len() + 2, before.len());
    assert_eq!(hidden_entries(dir.path()), Vec::<String>::new());
}

/// The study's committed state (real runs in progress) draws as trajectories: the figure's series
/// are the runs' time series (thinned to at most MAX_POINTS, first and last sample kept), and
/// `rbc-sweep --trajectories` writes the PNG and the SVG.
#[test]
fn study_state_draws_as_trajectories() {
    use rbc_analysis::plot::trajectory::{TrajectoryFigure, MAX_POINTS};
    let state = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies/science-6p5/state");
    let files: Vec<std::path::PathBuf> = std::fs::read_dir(&state).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|e| e == "h5")).collect();
    assert!(!files.is_empty(), "{}: no study state", state.display());
    let refs: Vec<&std::path::Path> = files.iter().map(|p| p.as_path()).collect();
    let fig = TrajectoryFigure::read(&refs).unwrap();
    assert_eq!(fig.runs.len(), files.len());
    for (r, f) in fig.runs.iter().zip(&files) {
        let ts = rbc_schema::results::read_timeseries(f, &r.run_id).unwrap();
        // every stride-th sample from the first, plus the last when the stride skips it
        let stride = ts.len().div_ceil(MAX_POINTS).max(1);
        let expected = (ts.len() - 1) / stride + 1 + usize::from(!(ts.len() - 1).is_multiple_of(stride));
        assert!(r.t_ms.len() == expected && expected <= MAX_POINTS + 1, "{} points of {} (expected {expected})", r.t_ms.len(), ts.len());
        assert_eq!(r.t_ms[1], ts[stride].t_s * 1e3);
        assert_eq!((r.t_ms[0], *r.t_ms.last().unwrap()), (ts[0].t_s * 1e3, ts.last().unwrap().t_s * 1e3));
        assert_eq!(*r.y_um.last().unwrap(), ts.last().unwrap().centroid_um[1]);
        assert!(r.t_ms.windows(2).all(|w| w[1] > w[0]));
    }
    let dir = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).arg("--trajectories").args(&files).arg("--out").arg(dir.path()).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for ext in ["png", "svg"] {
        assert!(std::fs::metadata(dir.path().join(format!("trajectories.{ext}"))).unwrap().len() > 1000);
    }
}

/// Two studies of the same grid hold runs of the same id: the legend tells them apart by the
/// folder their files differ in (`science-6p5/state/x.h5` and `science-6p5-penalty/state/x.h5`),
/// and a run whose id is unique keeps its id.
#[test]
fn runs_of_the_same_id_in_two_studies_are_labelled_by_their_study() {
    use rbc_analysis::plot::trajectory::{folder_tags, TrajectoryFigure};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies");
    let exact = root.join("science-6p5/state/discocyte_u1.5_r0.8.h5");
    let penalty = root.join("science-6p5-penalty/state/discocyte_u1.5_r0.8.h5");
    let other = root.join("science-6p5/state/discocyte_u1.5_r0.4.h5");
    let fig = TrajectoryFigure::read(&[exact.as_path(), penalty.as_path(), other.as_path()]).unwrap();
    let labels: Vec<&str> = fig.runs.iter().map(|r| r.label.as_str()).collect();
    assert_eq!(labels, ["discocyte_u1.5_r0.8 (science-6p5)", "discocyte_u1.5_r0.8 (science-6p5-penalty)", "discocyte_u1.5_r0.4"]);
    // the same files named from inside one study (`state/x.h5` beside `../science-6p5/state/x.h5`)
    let inside = root.join("science-6p5-penalty/state/../state/discocyte_u1.5_r0.8.h5");
    let fig = TrajectoryFigure::read(&[exact.as_path(), inside.as_path()]).unwrap();
    assert_eq!(fig.runs[1].label, "discocyte_u1.5_r0.8 (science-6p5-penalty)");
    let p = |s: &'static str| std::path::Path::new(s);
    assert_eq!(folder_tags(&[p("a/x.h5"), p("a/y.h5")]), ["x.h5", "y.h5"]);
    assert_eq!(folder_tags(&[p("x.h5"), p("x.h5")]), ["#1", "#2"]);
    assert_eq!(folder_tags(&[p("d/a/s/x.h5"), p("a/s/x.h5")]), ["d", "a/s"]);
}
