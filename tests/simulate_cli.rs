//! `rbc-simulate` end to end: a scene runs and lands in results.h5; bad scenes fail with a one-line error naming file and field.

use std::path::Path;
use std::process::Command;

fn simulate(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rbc-simulate")).args(args).current_dir(dir).output().expect("run rbc-simulate")
}

const DROP: &str = r#"
name = "tiny-drop"
[cell]
shape = "sphere"
level = 1
radius_um = 4.0
[membrane.tension]
gamma_n_m = 5e-6
[fluid]
viscosity_pa_s = 1.2e-3
lambda = 1.0
[flow]
kind = "shear"
shear_rate_1_s = 10.0
[integrator]
kinematics = "normal"
[time]
end_s = 0.002
output_interval_s = 0.0005
"#;

#[test]
fn runs_a_scene_and_appends_runs_to_results() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("drop.toml"), DROP).unwrap();
    for _ in 0..2 {
        let out = simulate(&["drop.toml", "--out", "res.h5"], dir.path());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let runs = rbc_schema::results::read_runs(&dir.path().join("res.h5")).unwrap();
    let ids: Vec<&str> = runs.iter().map(|r| r.run_id.as_str()).collect();
    assert_eq!(ids, ["tiny-drop", "tiny-drop-2"]);
    let r = &runs[0];
    assert_eq!(r.status.as_str(), "unsteady");
    assert_eq!(r.n_samples, 5, "t = 0, 0.5, 1, 1.5, 2 ms");
    assert!(r.attrs.as_ref().unwrap().scene.contains("tiny-drop"));
    let ts = rbc_schema::results::read_timeseries(&dir.path().join("res.h5"), "tiny-drop").unwrap();
    assert!((ts.last().unwrap().t_s - 0.002).abs() < 1e-12);
    // the volume correction holds the volume to the rescaling threshold
    assert!((ts.last().unwrap().volume_um3 / ts[0].volume_um3 - 1.0).abs() < 1e-8);
    // every snapshot carries the mean curvature of its vertices (cotangent formula; > 0 on the drop)
    let snaps = rbc_schema::results::read_snapshots(&dir.path().join("res.h5"), "tiny-drop").unwrap();
    let tri: Vec<[usize; 3]> = snaps.triangles.iter().map(|t| t.map(|i| i as usize)).collect();
    let h = &snaps.fields[rbc_solver::run::results::MEAN_CURVATURE_FIELD];
    assert_eq!(h.len(), snaps.times_s.len());
    for (k, v) in snaps.vertices_um.iter().enumerate() {
        assert_eq!(h[k], rbc_solver::run::results::mean_curvature(v, &tri), "snapshot {k}");
        assert!(h[k].iter().all(|&x| x > 0.0), "snapshot {k}: {:?}", h[k]);
    }
}

#[test]
fn bad_scene_fails_with_file_and_field_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.toml"), DROP.replace("lambda = 1.0", "lambda = -2.0")).unwrap();
    let out = simulate(&["bad.toml", "--out", "res.h5"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.toml") && err.contains("fluid.lambda"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!dir.path().join("res.h5").exists());
    let out = simulate(&["missing.toml"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.toml"));
}

/// A step log it cannot write (a directory, a missing folder) is refused before the results file
/// is created or gains a run: the file a first run made holds that run alone afterwards, and a new
/// path is not created; an earlier step log is only replaced once a run starts.
#[test]
fn a_step_log_it_cannot_write_is_refused_before_the_results_gain_a_run() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("drop.toml"), DROP).unwrap();
    std::fs::create_dir(dir.path().join("adir")).unwrap();
    let out = simulate(&["drop.toml", "--out", "new.h5", "--step-log", "adir"], dir.path());
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(!dir.path().join("new.h5").exists());
    assert!(simulate(&["drop.toml", "--out", "res.h5"], dir.path()).status.success());
    let out = simulate(&["drop.toml", "--out", "res.h5", "--step-log", "adir"], dir.path());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("adir"), "{err}");
    let runs = rbc_schema::results::read_runs(&dir.path().join("res.h5")).unwrap();
    assert_eq!(runs.iter().map(|r| r.run_id.as_str()).collect::<Vec<_>>(), ["tiny-drop"]);
    // a folder that does not exist, likewise
    let out = simulate(&["drop.toml", "--out", "res.h5", "--step-log", "nowhere/steps.csv"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nowhere"));
    // a step log an earlier run wrote stays as it was when a resume is refused (the run ended)
    std::fs::write(dir.path().join("steps.csv"), "an earlier log\n").unwrap();
    let out = simulate(&["drop.toml", "--out", "res.h5", "--resume", "--step-log", "steps.csv"], dir.path());
    assert_ne!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read_to_string(dir.path().join("steps.csv")).unwrap(), "an earlier log\n");
    assert_eq!(rbc_schema::results::read_runs(&dir.path().join("res.h5")).unwrap().len(), 1);
}

#[test]
fn periodic_channel_with_a_bad_field_is_refused_before_anything_is_written() {
    // (the channel itself runs: tests/channel_scene.rs)
    let dir = tempfile::tempdir().unwrap();
    let text = DROP.replace("[flow]\nkind = \"shear\"\nshear_rate_1_s = 10.0\n", "")
        + "[walls]\nkind = \"periodic-channel\"\nlength_x_um = 42.7\nwidth_y_um = 12.0\nheight_z_um = 10.0\nmean_velocity_um_s = 1000.0\nwall_model = \"penalty\"\n";
    std::fs::write(dir.path().join("channel.toml"), text).unwrap();
    let out = simulate(&["channel.toml", "--out", "res.h5"], dir.path());
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("walls.kappa_w_n_m3") && err.contains("channel.toml"), "{err}");
    assert!(!dir.path().join("res.h5").exists());
}

#[test]
fn a_blow_up_is_recorded_as_failed_with_its_diagnosis_and_exit_code_1() {
    // a drop at Ca = 0.4 stretches past the 5 % area limit (see solver/tests/integrate_extreme.rs)
    let dir = tempfile::tempdir().unwrap();
    let text = DROP.replace("shear_rate_1_s = 10.0", "shear_rate_1_s = 416.7").replace("end_s = 0.002", "end_s = 0.05");
    std::fs::write(dir.path().join("stretch.toml"), text).unwrap();
    let out = simulate(&["stretch.toml", "--out", "res.h5"], dir.path());
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stderr));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.lines().last().unwrap().contains("area change"), "{err}");
    let runs = rbc_schema::results::read_runs(&dir.path().join("res.h5")).unwrap();
    assert_eq!(runs.len(), 1);
    assert_eq!(runs[0].status.as_str(), "failed");
    assert!(runs[0].failure.as_deref().unwrap().contains("area change"));
    // the samples before the blow-up are stored, every one finite and within the limit
    let ts = rbc_schema::results::read_timeseries(&dir.path().join("res.h5"), &runs[0].run_id).unwrap();
    assert!(ts.len() >= 3, "{} samples stored", ts.len());
    assert!(ts.iter().all(|s| s.centroid_um.iter().chain(&s.velocity_mm_s).chain([&s.area_um2, &s.volume_um3, &s.asphericity]).all(|v| v.is_finite())));
    assert!(ts.iter().all(|s| (s.area_um2 / ts[0].area_um2 - 1.0).abs() <= 0.05));
}

/// A fold sharper than `integrator.max_fold_deg` stops the run with the diagnosis: a
/// 128-triangle drop at Ca = 0.4 (area check off) sharpens its tips from 22 degrees between
/// adjacent normals to the 40-degree limit within ~2.4 ms; exit code 1, the last line names the
/// edge and the fix, results.h5 holds the failed run, and no stored snapshot passes the limit.
#[test]
fn a_fold_sharper_than_the_mesh_resolves_stops_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let text = DROP
        .replace("level = 1", "level = 2")
        .replace("shear_rate_1_s = 10.0", "shear_rate_1_s = 416.7")
        .replace("end_s = 0.002", "end_s = 0.05")
        .replace("kinematics = \"normal\"", "kinematics = \"normal\"\nmax_area_change = 1.0\nmax_fold_deg = 40.0");
    std::fs::write(dir.path().join("fold.toml"), text).unwrap();
    let out = simulate(&["fold.toml", "--out", "res.h5", "--snapshot-every", "1"], dir.path());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    let last = err.lines().last().unwrap();
    assert!(last.contains("no longer resolves the shape") && last.contains("limit 40.0") && last.contains("cell.level"), "{err}");
    let path = dir.path().join("res.h5");
    let runs = rbc_schema::results::read_runs(&path).unwrap();
    assert_eq!(runs[0].status.as_str(), "failed");
    assert!(runs[0].failure.as_deref().unwrap().contains("no longer resolves"));
    let snaps = rbc_schema::results::read_snapshots(&path, &runs[0].run_id).unwrap();
    let tris: Vec<[usize; 3]> = snaps.triangles.iter().map(|t| t.map(|i| i as usize)).collect();
    assert!(snaps.times_s.len() >= 3, "{:?}", snaps.times_s);
    for v in &snaps.vertices_um {
        let x: Vec<nalgebra::Vector3<f64>> = v.iter().map(|p| nalgebra::Vector3::new(p[0], p[1], p[2])).collect();
        assert!(rbc_solver::integrate::check::sharpest_fold(&x, &tris).0.to_degrees() <= 40.0);
    }
}
