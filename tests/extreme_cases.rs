//! The stiff and extreme cases of the paper's channel at 2048 triangles (issue 11), with both wall
//! models: `scripts/extreme_cases.sh` (the one home of the cases) run for 2 ms each, and what it
//! found asserted. About 3 minutes with exact walls and 5 with the paper's penalty walls on one
//! core, so ignored by default:
//!
//! ```sh
//! cargo nextest run --release --run-ignored only -E 'binary(extreme_cases)'
//! ```

use std::path::Path;
use std::process::Command;

/// Run the script for `walls` (`exact` or `penalty`) into `work` and return its table's rows:
/// `(case, outcome, simulated ms, sharpest fold in degrees)`.
fn run_cases(walls: &str, work: &Path) -> Vec<(String, String, f64, f64)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("bash")
        .arg(root.join("scripts/extreme_cases.sh"))
        .args(["--ms", "2", "--walls", walls])
        .env("RBC_BENCH_WORK", work)
        // the script builds its binaries where this test's were built
        .env("CARGO_TARGET_DIR", Path::new(env!("CARGO_BIN_EXE_rbc-simulate")).parent().and_then(Path::parent).unwrap())
        .current_dir(root)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "extreme_cases.sh --walls {walls}: {}\n{stdout}", String::from_utf8_lossy(&out.stderr));
    eprintln!("{walls} walls:\n{stdout}");
    stdout
        .lines()
        .skip(2)
        .map(|l| {
            let c: Vec<&str> = l.split('|').map(str::trim).collect();
            (c[1].to_string(), c[2].to_string(), c[3].parse().unwrap(), c[5].parse().unwrap())
        })
        .collect()
}

/// Every case (a nearly area-incompressible membrane, a rim 0.5 um from the side wall, lambda =
/// 10, the paper's highest velocity) runs its 2 ms with either wall model, folds no more sharply
/// than 60 degrees (the runs stop at 120; session 42 measured 31-47), and writes only finite
/// samples, its area within 5 % of the start.
#[test]
#[ignore]
fn every_extreme_case_runs_2_ms_with_either_wall_model() {
    let dir = tempfile::tempdir().unwrap();
    for walls in ["exact", "penalty"] {
        let rows = run_cases(walls, dir.path());
        let names: Vec<&str> = rows.iter().map(|r| r.0.as_str()).collect();
        assert_eq!(names, ["stiff-area", "near-wall", "lambda10", "fast"], "{walls}");
        for (case, outcome, ms, fold) in &rows {
            assert_eq!((outcome.as_str(), *ms), ("ran 2 ms", 2.0), "{walls} walls, {case}");
            assert!(*fold < 60.0, "{walls} walls, {case}: a fold of {fold} degrees");
            let file = dir.path().join(walls).join(format!("{case}.h5"));
            let samples = rbc_schema::results::read_timeseries(&file, case).unwrap();
            assert!(samples.len() >= 10 && (samples.last().unwrap().t_s - 2e-3).abs() < 1e-9, "{walls} walls, {case}: {} samples", samples.len());
            for s in &samples {
                let values = [s.centroid_um.as_slice(), &s.velocity_mm_s, &s.extents_um, &[s.area_um2, s.volume_um3, s.asphericity]].concat();
                assert!(values.iter().all(|v| v.is_finite()), "{walls} walls, {case}: {s:?}");
                assert!((s.area_um2 / samples[0].area_um2 - 1.0).abs() < 0.05, "{walls} walls, {case}: area {} at {} s", s.area_um2, s.t_s);
            }
        }
    }
}
