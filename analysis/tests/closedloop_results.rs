//! A simulated cell read from results.h5 (snapshot, label, velocity) is rendered and analysed; bad runs are refused with the file and run named.

use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::simulated::render3d::{cell_from_results, cell_image, single_cell_spec, write_recording_3d, CellMotion, Render3dParams};
use rbc_analysis::simulated::synth::{OpticsSpec, Truth};
use rbc_schema::results::{FinalShape, ResultsFile, RunAttrs, RunStatus, RunSummary};

fn attrs() -> RunAttrs {
    RunAttrs { start_shape: "discocyte".into(), r_init_um: 1.2, y_init_um: 1.0, z_init_um: 0.55, lambda: 5.0, scene: String::new() }
}

/// Ellipsoid (3.5, 2.2, 1.2) um at (40, 1.1, 0.2), shifted by `dx` along x.
fn ellipsoid(dx: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let m = rbc_solver::mesh::sphere(4, 1.0);
    let v = m.vertices.iter().map(|p| [40.0 + dx + 3.5 * p.x, 1.1 + 2.2 * p.y, 0.2 + 1.2 * p.z]).collect();
    let t = m.triangles.iter().map(|t| [t[0] as u32, t[1] as u32, t[2] as u32]).collect();
    (v, t)
}

#[test]
fn snapshot_from_results_is_rendered_with_the_solver_label_and_found_by_the_analysis() {
    let dir = tempfile::tempdir().unwrap();
    let h5 = dir.path().join("results.h5");
    let (v0, tri) = ellipsoid(0.0);
    let (v1, _) = ellipsoid(0.9); // 0.9 um in 0.5 ms: 1.8 mm/s
    {
        let mut f = ResultsFile::create_or_open(&h5).unwrap();
        let mut w = f.begin_run("finished", &attrs(), &tri).unwrap();
        w.append_snapshot(0.010, &v0).unwrap();
        w.append_snapshot(0.0105, &v1).unwrap();
        let summary = RunSummary {
            status: RunStatus::Steady,
            final_shape: FinalShape::Slipper,
            tank_treading: true,
            tumbling: false,
            mean_velocity_mm_s: 1.5,
            min_velocity_mm_s: 1.4,
            max_velocity_mm_s: 1.6,
            mean_radial_um: 1.12,
            mean_y_um: 1.1,
            mean_z_um: 0.2,
            evidence: Default::default(),
        };
        w.finish(&summary).unwrap();
        let mut w = f.begin_run("running", &attrs(), &tri).unwrap();
        w.append_snapshot(0.0, &v0).unwrap();
        w.append_snapshot(0.0005, &v1).unwrap();
        w.flush().unwrap();
        f.begin_run("empty", &attrs(), &tri).unwrap().flush().unwrap();
    }
    // finished run: the last snapshot, the run's label and mean velocity
    let c = cell_from_results(&h5, "finished", None).unwrap();
    assert_eq!((c.label.as_str(), c.velocity_mm_s, c.t_s), ("slipper", 1.5, 0.0105));
    assert_eq!(c.mesh.vertices[0], v1[0]);
    // unfinished run: unlabelled, velocity from the last two snapshots' centroids (0.9 um / 0.5 ms)
    let r = cell_from_results(&h5, "running", Some(0)).unwrap();
    assert_eq!(r.label, "unlabelled");
    assert!((r.velocity_mm_s - 1.8).abs() < 1e-9, "{}", r.velocity_mm_s);
    // refused: unknown run, run without snapshots, snapshot out of range; each names file and run
    for (run, k, what) in [("nope", None, "no such run"), ("empty", None, "no snapshots"), ("finished", Some(2), "snapshot 2")] {
        let e = cell_from_results(&h5, run, k).unwrap_err().to_string();
        assert!(e.contains("results.h5") && e.contains(run) && e.contains(what), "{e}");
    }
    // render and analyse: the truth is the in-focus section of the ellipsoid at its centroid's z
    // (semi-axes scaled by sqrt(1 - (0.674 sigma / 1.2)^2)), the analysis finds it at the truth
    let img = cell_image(&c.mesh, &OpticsSpec::default(), &Render3dParams::default()).unwrap();
    let k = (1.0 - (0.674_489_75 * 0.5 / 1.2f64).powi(2)).sqrt();
    let area = std::f64::consts::PI * 3.5 * 2.2 * k * k;
    assert!((img.area_um2 / area - 1.0).abs() < 5e-3, "{} vs {area}", img.area_um2);
    let (spec, x0) = single_cell_spec(0.25, 0.01, c.velocity_mm_s, img.length_um);
    let out = dir.path().join("rec");
    write_recording_3d(&out, &spec, &img, &CellMotion { x0_um: x0, velocity_mm_s: c.velocity_mm_s }, &c.label, 3).unwrap();
    let truth = Truth::read(&out).unwrap();
    assert!(truth.rows.iter().all(|r| r.shape == "slipper" && (r.y_um - 1.1).abs() < 0.01));
    let det = detect_recording(&Recording::open(&out).unwrap()).unwrap();
    let found = truth.rows.iter().filter(|t| det.detections.iter().any(|d| d.frame as u64 == t.frame && (d.x_um - t.x_um).hypot(d.y_um - t.y_um) < 0.2)).count();
    assert_eq!(found, truth.rows.len(), "detected within 0.2 um in every frame");
}
