//! The solver executor's observer on analytic motions fed through the solver's `Observer`
//! interface by a stand-in time loop (same protocol as `rbc_solver::run::Runner`): the run stops
//! when the steady state is detected (at the predicted time), is classified, and its summary,
//! evidence and final snapshots land in results.h5.

mod sweep_common;

use nalgebra::{Rotation3, Vector3};
use rbc::sweep::solver_exec::SolverExecutor;
use rbc::sweep::RunExecutor;
use rbc_schema::results::*;
use rbc_schema::scene::Scene;
use rbc_schema::sweep::Sweep;
use rbc_solver::classify::{surface_area, volume_centroid};
use rbc_solver::run::{Observer, RunSummary as SolverSummary, Sample};
use rbc_solver::SolverError;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicUsize, Ordering};
use sweep_common::*;

const SWEEP_FAST: &str = r#"
base_scene = "base.toml"
mean_velocity_mm_s = [2.0]
r_init_um = [0.5]
start_shapes = ["discocyte"]
snapshot_every = 20
[steady]
window_s = 0.05
max_time_s = 0.5
[classify]
frames = 25
frame_interval_s = 0.001
"#;

/// A stand-in for the solver's time loop: samples `shape(t)` every output interval until the
/// scene's end time, stopping (and calling `finish` with the error) when `sample` refuses.
fn drive(
    scene: &Scene,
    obs: &mut dyn Observer,
    triangles: &[[usize; 3]],
    shape: &dyn Fn(f64) -> Vec<[f64; 3]>,
    count: &AtomicUsize,
) -> Result<(), SolverError> {
    drive_failing(scene, obs, triangles, shape, count, None)
}

/// As [`drive`], failing like a blow-up after `fail_after` samples.
fn drive_failing(
    scene: &Scene,
    obs: &mut dyn Observer,
    triangles: &[[usize; 3]],
    shape: &dyn Fn(f64) -> Vec<[f64; 3]>,
    count: &AtomicUsize,
    fail_after: Option<usize>,
) -> Result<(), SolverError> {
    let dt = scene.time.output_interval_s;
    let n = (scene.time.end_s / dt).round() as usize;
    let summary = SolverSummary::default();
    for k in 0..=n {
        if Some(k) == fail_after {
            let e = SolverError::Output(format!("NaN velocity at vertex 3 after {k} samples"));
            obs.finish(&summary, Some(&e))?;
            return Err(e);
        }
        let t = k as f64 * dt;
        let v = shape(t);
        let x: Vec<Vector3<f64>> = v.iter().map(|p| Vector3::from(*p)).collect();
        let (vol, c) = volume_centroid(&v, triangles);
        let s = Sample {
            t_s: t,
            step: k,
            h_s: dt,
            vertices: &x,
            triangles,
            area_um2: surface_area(&v, triangles),
            volume_um3: vol,
            centroid_um: Vector3::from(c),
        };
        count.fetch_add(1, Ordering::SeqCst);
        if let Err(e) = obs.sample(&s) {
            obs.finish(&summary, Some(&e))?;
            return Err(e);
        }
    }
    obs.finish(&summary, None)
}

fn unit_sphere(level: usize) -> (Vec<Vector3<f64>>, Vec<[usize; 3]>) {
    let m = rbc_solver::mesh::sphere(level, 1.0);
    let r = Rotation3::from_euler_angles(0.31, 0.47, 0.83);
    (m.vertices.iter().map(|p| r * p).collect(), m.triangles)
}

#[test]
fn converging_croissant_stops_at_the_steady_state_and_is_classified() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP_FAST)).unwrap();
    let run = &sweep.runs().unwrap()[0];
    let out = dir.path().join("run.h5");
    let (u, tri) = unit_sphere(3);
    // an axisymmetric cup (croissant-like) moving at 2 mm/s whose radial offset decays as 0.5 exp(-t/0.02) um
    let (u_um_s, tau, r0) = (2000.0, 0.02, 0.5);
    let shape = move |t: f64| -> Vec<[f64; 3]> {
        let r = r0 * (-t / tau).exp();
        let (y, z) = rbc_schema::sweep::offset_yz(r);
        u.iter()
            .map(|p| {
                [
                    u_um_s * t + 1.2 * p.x + 0.18 * 3.6 * 3.6 * (p.y * p.y + p.z * p.z),
                    3.6 * p.y + y,
                    3.6 * p.z + z,
                ]
            })
            .collect()
    };
    let count = AtomicUsize::new(0);
    let exec = SolverExecutor {
        solve: |scene: &Scene, obs: &mut dyn Observer| drive(scene, obs, &tri, &shape, &count),
    };
    exec.execute(&sweep, run, &out).unwrap();

    // range of r over [t - W, t] is r0 e^{-(t-W)/tau} (1 - e^{-W/tau}) <= 0.05 um (default position tolerance)
    let w = 0.05;
    let t_star = w + tau * (r0 * (1.0 - (-w / tau).exp()) / 0.05).ln();
    let samples = count.load(Ordering::SeqCst);
    let t_stop = (samples - 1) as f64 * 1e-3;
    println!("croissant: stopped at {t_stop:.3} s, predicted first sample >= {t_star:.4} s");
    assert!(
        t_stop >= t_star - 1e-9 && t_stop < t_star + 1e-3,
        "stopped at {t_stop}, predicted {t_star}"
    );

    let rec = read_runs(&out).unwrap().remove(0);
    assert_eq!(rec.run_id, run.run_id);
    assert_eq!(rec.n_samples, samples);
    let s = rec.summary.unwrap();
    assert_eq!(
        (s.status, s.final_shape, s.tank_treading, s.tumbling),
        (RunStatus::Steady, FinalShape::Croissant, false, false)
    );
    // centroid displacement over the window / duration: exactly the translation speed
    assert!(
        (s.mean_velocity_mm_s - 2.0).abs() < 1e-9,
        "{}",
        s.mean_velocity_mm_s
    );
    assert!(
        (s.evidence["steady_end_s"] - t_stop).abs() < 1e-12
            && (s.evidence["steady_start_s"] - (t_stop - w)).abs() < 1e-9
    );
    for key in [
        "mirror_y_rel",
        "mirror_z_rel",
        "offset_r_um",
        "tt_frequency_hz",
        "radial_max_um",
        "extent_x_mean_um",
        "steps_accepted",
    ] {
        assert!(
            s.evidence.contains_key(key),
            "evidence `{key}` missing: {:?}",
            s.evidence.keys()
        );
    }
    // snapshots: every 20th sample before the 25 classification frames, then all of these
    let snaps = read_snapshots(&out, &run.run_id).unwrap();
    let n = samples; // samples 0..n-1 at k ms
    let mut expected: Vec<f64> = (0..n - 25)
        .filter(|k| k % 20 == 0)
        .map(|k| k as f64 * 1e-3)
        .collect();
    expected.extend((n - 25..n).map(|k| k as f64 * 1e-3));
    assert_eq!(snaps.times_s.len(), expected.len());
    assert!(
        snaps
            .times_s
            .iter()
            .zip(&expected)
            .all(|(a, b)| (a - b).abs() < 1e-12),
        "{:?}",
        snaps.times_s
    );
}

/// A fixed off-centre slipper-like surface (bent, sheared, tilted ellipsoid) whose membrane
/// points circulate about z at `f_tt` (Hz) while it moves at 2 mm/s.
fn slipper(u: Vec<Vector3<f64>>, f_tt: f64) -> impl Fn(f64) -> Vec<[f64; 3]> {
    move |t: f64| -> Vec<[f64; 3]> {
        let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), 2.0 * PI * f_tt * t);
        let tilt = Rotation3::from_axis_angle(&Vector3::z_axis(), 25f64.to_radians());
        u.iter()
            .map(|p| {
                let q = rz * p;
                let (x, y, z) = (4.0 * q.x, 2.2 * q.y, 1.4 * q.z);
                let y = y + 0.15 * x * x;
                let x = x + 0.4 * y;
                let v = tilt * Vector3::new(x, y, z) + Vector3::new(2000.0 * t, 1.2, 0.1);
                [v.x, v.y, v.z]
            })
            .collect()
    }
}

#[test]
fn tank_treading_slipper_is_recorded_with_its_frequency() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP_FAST)).unwrap();
    let run = &sweep.runs().unwrap()[0];
    let out = dir.path().join("run.h5");
    let (u, tri) = unit_sphere(4);
    let f_tt = 25.0;
    let shape = slipper(u, f_tt);
    let count = AtomicUsize::new(0);
    let exec = SolverExecutor {
        solve: |scene: &Scene, obs: &mut dyn Observer| drive(scene, obs, &tri, &shape, &count),
    };
    exec.execute(&sweep, run, &out).unwrap();
    let s = read_runs(&out).unwrap().remove(0).summary.unwrap();
    println!(
        "slipper: status {:?}, f_TT {:.3} Hz, evidence {:?}",
        s.status, s.evidence["tt_frequency_hz"], s.evidence
    );
    // the surface is fixed, but its sampling by the sliding vertices changes the bounding box a
    // little: steady, or periodic with the mesh's rotational period
    assert!(matches!(s.status, RunStatus::Steady | RunStatus::Periodic));
    assert_eq!(
        (s.final_shape, s.tank_treading, s.tumbling),
        (FinalShape::Slipper, true, false)
    );
    // 25 frames at 1 ms: 0.6 of a turn; the mean over vertex phases keeps it unbiased (measured 0.3 %)
    assert!(
        (s.evidence["tt_frequency_hz"] / f_tt - 1.0).abs() < 0.01,
        "{}",
        s.evidence["tt_frequency_hz"]
    );
    assert!(s.mean_radial_um > 0.8);
}

/// A slow tank-treading (2 Hz, as slow as the study's ~1 mm/s slippers' 1.2-1.3 Hz or slower)
/// turns by 0.048 turn over 25 consecutive outputs of 1 ms: half the classifier's least turn
/// (`min_tt_turns`, 0.1), too little to call it tank-treading, so the cell is `other`. With the
/// frames 10 ms apart (every 10th output) the same 25 frames span 0.48 turn: a tank-treading
/// slipper, its frequency within 1 %. The snapshots (every 15th output, not
/// a multiple of the frame spacing) and all the frames of the final ring are stored, in time order.
/// The same spacing given as the mean flow's travel (`frame_travel_um = 20`: 10 ms at the run's 2
/// mm/s) gives the same frames and the same label.
#[test]
fn a_slow_tank_treading_is_seen_over_frames_spread_in_time() {
    let classify = |frame_spacing: &str| {
        let text = SWEEP_FAST
            .replace("snapshot_every = 20", "snapshot_every = 15")
            .replace("window_s = 0.05", "window_s = 0.3")
            .replace("frame_interval_s = 0.001", frame_spacing);
        let dir = tempfile::tempdir().unwrap();
        let sweep = Sweep::read(&write_sweep(dir.path(), &text)).unwrap();
        let run = &sweep.runs().unwrap()[0];
        let out = dir.path().join("run.h5");
        let (u, tri) = unit_sphere(4);
        let shape = slipper(u, 2.0);
        let count = AtomicUsize::new(0);
        let exec = SolverExecutor {
            solve: |scene: &Scene, obs: &mut dyn Observer| drive(scene, obs, &tri, &shape, &count),
        };
        exec.execute(&sweep, run, &out).unwrap();
        let s = read_runs(&out).unwrap().remove(0).summary.unwrap();
        let n = count.load(Ordering::SeqCst);
        (s, read_snapshots(&out, &run.run_id).unwrap().times_s, n)
    };
    let (consecutive, _, _) = classify("frame_interval_s = 0.001");
    assert!((consecutive.evidence["classify_window_s"] - 0.024).abs() < 1e-12);
    assert_eq!((consecutive.final_shape, consecutive.tank_treading), (FinalShape::Other, false), "{:?}", consecutive.evidence);
    let turns = consecutive.evidence["tt_frequency_hz"] * consecutive.evidence["classify_window_s"];
    assert!(turns < 0.6 * rbc_solver::classify::ClassifyConfig::default().min_tt_turns, "{turns} turn");

    let (spread, times, n) = classify("frame_interval_s = 0.01");
    let (by_travel, times_by_travel, _) = classify("frame_travel_um = 20.0");
    assert_eq!((&by_travel.evidence, &times_by_travel), (&spread.evidence, &times), "10 ms from 20 um at 2 mm/s");
    assert!((spread.evidence["classify_window_s"] - 0.24).abs() < 1e-12, "{:?}", spread.evidence);
    assert_eq!((spread.final_shape, spread.tank_treading), (FinalShape::Slipper, true), "{:?}", spread.evidence);
    assert!((spread.evidence["tt_frequency_hz"] / 2.0 - 1.0).abs() < 0.01, "{}", spread.evidence["tt_frequency_hz"]);
    // samples 0..n-1 at k ms: every 15th before the ring, then every 15th or 10th in the ring, and the last
    let last = n - 1;
    let first_frame = (last / 10 - 24) * 10;
    let expected: Vec<f64> = (0..n)
        .filter(|k| k % 15 == 0 || (*k >= first_frame && k % 10 == 0) || *k == last)
        .map(|k| k as f64 * 1e-3)
        .collect();
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
    assert_eq!(times.len(), expected.len(), "{times:?}");
    assert!(times.iter().zip(&expected).all(|(a, b)| (a - b).abs() < 1e-12), "{times:?}");
}

#[test]
fn a_blow_up_is_recorded_as_failed_and_a_refused_scene_is_not_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP_FAST)).unwrap();
    let run = &sweep.runs().unwrap()[0];
    let out = dir.path().join("run.h5");
    let (u, tri) = unit_sphere(2);
    let shape =
        move |t: f64| -> Vec<[f64; 3]> { u.iter().map(|p| [p.x * (1.0 + t), p.y, p.z]).collect() };
    let count = AtomicUsize::new(0);
    // blows up after 10 samples (the time loop reports a failure and calls finish with it)
    let exec = SolverExecutor {
        solve: |scene: &Scene, obs: &mut dyn Observer| {
            drive_failing(scene, obs, &tri, &shape, &count, Some(10))
        },
    };
    exec.execute(&sweep, run, &out).unwrap();
    let rec = read_runs(&out).unwrap().remove(0);
    assert_eq!(rec.status, RunStatus::Failed);
    assert!(rec.failure.unwrap().contains("NaN velocity"));
    assert_eq!(rec.n_samples, 10);
    // the regular snapshot (every 20th: sample 0) and the last state before the failure
    assert_eq!(
        read_snapshots(&out, &run.run_id).unwrap().times_s,
        vec![0.0, 9.0 * 1e-3]
    );
    // the solver refuses the scene before any sample: an error, nothing written
    let out2 = dir.path().join("none.h5");
    let refuse = SolverExecutor {
        solve: |_: &Scene, _: &mut dyn Observer| {
            Err(SolverError::Unsupported {
                field: "walls.kind".into(),
                message: "not yet".into(),
            })
        },
    };
    let e = refuse.execute(&sweep, run, &out2).unwrap_err().to_string();
    assert!(e.contains(&run.run_id) && e.contains("walls.kind"), "{e}");
}

/// A centred cup (croissant) translating rigidly at `u_um_s` along x at r_init 0.2 um, run through
/// the sweep `sweep_toml`: its temporary folder, results file, run id, and (y, z) offset.
fn cup_run(sweep_toml: &str, u_um_s: f64) -> (tempfile::TempDir, std::path::PathBuf, String, (f64, f64)) {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), sweep_toml)).unwrap();
    let run = &sweep.runs().unwrap()[0];
    let out = dir.path().join("run.h5");
    let (u, tri) = unit_sphere(3);
    let (y, z) = rbc_schema::sweep::offset_yz(0.2);
    let shape = move |t: f64| -> Vec<[f64; 3]> {
        u.iter()
            .map(|p| [u_um_s * t + 1.2 * p.x + 0.18 * 3.6 * 3.6 * (p.y * p.y + p.z * p.z), 3.6 * p.y + y, 3.6 * p.z + z])
            .collect()
    };
    let count = AtomicUsize::new(0);
    let exec = SolverExecutor {
        solve: |scene: &Scene, obs: &mut dyn Observer| drive(scene, obs, &tri, &shape, &count),
    };
    exec.execute(&sweep, run, &out).unwrap();
    (dir, out, run.run_id.clone(), (y, z))
}

/// The sweep of the cup runs below: one run, a shape every 100 outputs, the steady state
/// judged over `window_s` (s) up to 0.5 s, classification frames 1 ms apart.
fn cup_sweep(window_s: f64) -> String {
    format!(
        "base_scene = \"base.toml\"\nmean_velocity_mm_s = [2.0]\nr_init_um = [0.2]\nstart_shapes = [\"discocyte\"]\nsnapshot_every = 100\n[steady]\nwindow_s = {window_s}\nmax_time_s = 0.5\n[classify]\nframes = 25\nframe_interval_s = 0.001\n"
    )
}

/// Transit records: a centred cup translating at 24 mm/s is recorded at 0 mm when the ring of
/// classification frames is first full (the 25th output) and at 10 mm at the first output with
/// `x - x0 >= 10 mm` (t = 10 mm / u = 0.41667 s -> the output at 0.417 s), as a croissant at its
/// centroid, moving at 24 mm/s; the run's own end is unchanged by them.
#[test]
fn transits_are_recorded_at_the_entrance_and_10_mm_downstream() {
    let (_dir, out, id, (y, z)) = cup_run(&cup_sweep(0.45), 24_000.0);
    let rec = read_runs(&out).unwrap().remove(0);
    let rows = read_timeseries(&out, &id).unwrap();
    let x0 = rows[0].centroid_um[0];
    assert_eq!(rec.transits.len(), 2, "{:?}", rec.transits);
    let (entry, ten) = (&rec.transits[0], &rec.transits[1]);
    assert_eq!((entry.distance_mm, entry.t_s), (0.0, 24.0 * 0.001), "the first full ring of 25 frames");
    assert_eq!((ten.distance_mm, ten.t_s), (10.0, 417.0 * 0.001));
    assert!(ten.x_um - x0 >= 10_000.0 && ten.x_um - x0 < 10_000.0 + 24.0 + 1e-9);
    for t in [entry, ten] {
        let row = rows.iter().find(|r| r.t_s == t.t_s).unwrap();
        assert_eq!([t.x_um, t.y_um, t.z_um], row.centroid_um, "the centroid of that output");
        assert!((t.y_um - y).abs() < 0.05 && (t.z_um - z).abs() < 0.05, "{t:?}");
        assert!((t.velocity_mm_s - 24.0).abs() < 1e-9, "{t:?}");
        assert_eq!(t.shape, FinalShape::Croissant, "{t:?}");
    }
    assert_eq!(rec.summary.unwrap().final_shape, FinalShape::Croissant);
}

/// A run that ends steady before it has travelled 10 mm (a cup at 6 mm/s, steady after a 0.2 s
/// window, ~1.3 mm) gets its steady state carried to 10 mm (`Transit::from_steady`): the final
/// label, the window's mean y, z and velocity, x = x0 + 10 mm, t = its end + the rest of the way
/// at the mean velocity; the 0 mm record is the one made as it passed.
#[test]
fn a_run_that_ends_steady_before_10_mm_carries_its_steady_state_there() {
    let (_dir, out, id, _) = cup_run(&cup_sweep(0.2), 6_000.0);
    let rec = read_runs(&out).unwrap().remove(0);
    let summary = rec.summary.clone().unwrap();
    assert_eq!((summary.status, summary.final_shape), (RunStatus::Steady, FinalShape::Croissant));
    let rows = read_timeseries(&out, &id).unwrap();
    let (first, last) = (&rows[0], rows.last().unwrap());
    assert!(last.t_s < 0.5 && last.centroid_um[0] - first.centroid_um[0] < 5_000.0, "ended early: {last:?}");
    assert_eq!(rec.transits.len(), 2, "{:?}", rec.transits);
    let (entry, ten) = (&rec.transits[0], &rec.transits[1]);
    assert!(!entry.from_steady && entry.distance_mm == 0.0);
    assert!(ten.from_steady && ten.distance_mm == 10.0, "{ten:?}");
    assert_eq!(ten.shape, FinalShape::Croissant);
    assert_eq!([ten.y_um, ten.z_um, ten.velocity_mm_s], [summary.mean_y_um, summary.mean_z_um, summary.mean_velocity_mm_s]);
    assert!((ten.velocity_mm_s - 6.0).abs() < 1e-9, "{ten:?}");
    assert!((ten.x_um - first.centroid_um[0] - 10_000.0).abs() < 1e-9);
    // the cup moves at exactly 6 mm/s: it reaches 10 mm at t0 + 10 mm / u
    assert!((ten.t_s - (first.t_s + 10.0 / 6.0)).abs() < 1e-9, "{ten:?}");
    // reopened, the run continues and will pass 10 mm itself: the carried record goes
    rbc_schema::results::ResultsFile::create_or_open(&out).unwrap().resume_run(&id).unwrap();
    let again = read_runs(&out).unwrap().remove(0);
    assert_eq!(again.transits.len(), 1, "only the record made as it passed stays: {:?}", again.transits);
}
