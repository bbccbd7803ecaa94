//! The example sweeps: the paper's phase diagram expands into 330 valid scenes, and the quick
//! demo runs end to end with the real solver (a capsule on the axis of an unbounded Poiseuille
//! flow stops at its steady state, centred and mirror-symmetric, at the Faxen velocity of a
//! rigid sphere), and resumes without rerunning anything.

use rbc_schema::results::{read_runs, FinalShape, RunStatus};
use std::path::Path;
use std::process::Command;

fn examples() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/sweeps"))
}

#[test]
fn paper_phase_diagram_expands_into_330_scenes() {
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
        .arg(examples().join("paper-phase-diagram.toml"))
        .arg("--list")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    assert_eq!(text.lines().count(), 331);
    assert!(text.contains("\tdiscocyte_u0.13_r0\t") && text.contains("\tslipper_u10.4_r2.25\t"));
}

#[test]
fn demo_sweep_runs_with_the_solver_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo.h5");
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
            .arg(examples().join("demo-poiseuille.toml"))
            .arg("--out")
            .arg(&out)
            .args(["--jobs", "2"])
            .output()
            .unwrap()
    };
    let o = run();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    let runs = read_runs(&out).unwrap();
    assert_eq!(runs.len(), 4);
    for r in &runs {
        let s = r
            .summary
            .as_ref()
            .unwrap_or_else(|| panic!("{} not finished: {:?}", r.run_id, r.failure));
        if r.attrs.as_ref().unwrap().r_init_um == 0.0 {
            // on the axis: steady, centred, symmetric -> "croissant" by the classifier's definition;
            // a steady capsule moves as a rigid body: Faxen's law for a sphere of radius a in
            // u = umax (1 - r^2/R^2) gives U = umax (1 - 2 a^2 / (3 R^2)); level-2 mesh: 1 %
            assert_eq!(
                (s.status, s.final_shape, s.tank_treading),
                (RunStatus::Steady, FinalShape::Croissant, false),
                "{}",
                r.run_id
            );
            let umax = if r.run_id.contains("_u0.5_") {
                0.5
            } else {
                1.0
            };
            let faxen = umax * (1.0 - 2.0 * 2.5f64.powi(2) / (3.0 * 36.0));
            println!(
                "{}: U = {:.5} mm/s, Faxen {:.5} mm/s",
                r.run_id, s.mean_velocity_mm_s, faxen
            );
            assert!(
                (s.mean_velocity_mm_s / faxen - 1.0).abs() < 0.01,
                "{} vs {faxen}",
                s.mean_velocity_mm_s
            );
            assert!(
                s.evidence["steady_end_s"] < 0.2,
                "stopped before the maximal time"
            );
        }
    }
    let o = run();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        o.status.success() && err.contains("4 of 4 runs already finished") && err.contains("0 to run") && err.contains("4 runs already in") && err.contains("0 done now"),
        "{err}"
    );
}
