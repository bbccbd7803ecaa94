//! `rbc-synth --closed-loop` end to end on the shipped examples/demo-results.h5: every finished run rendered, analysed, tabulated; bad input refused with the file named.

mod output_common;

use output_common::{files_in, hidden_entries};
use rbc_analysis::simulated::closedloop::LOOP_COLUMNS;
use std::path::Path;
use std::process::Command;

fn synth(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rbc-synth")).args(args).output().unwrap()
}

/// The 4 capsule runs of examples/demo-results.h5 (free-space Poiseuille, level 2): the 2 centred
/// ones are croissants for the solver, the 2 off-centre ones (0.8 um, no tank-treading)
/// `other`; the analysis gives the same 4 labels, and closed_loop.csv has one row per run.
#[test]
fn closed_loop_on_the_example_results() {
    let results = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/demo-results.h5");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("loop");
    let o = synth(&["--closed-loop", results.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("agreement 4/4 (croissant 2/2, slipper 0/0, other 2/2)"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("closed_loop.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next().unwrap(), LOOP_COLUMNS.join(","));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4);
    for r in &rows {
        assert_eq!(r[1], r[2], "solver and pipeline labels of {}", r[0]);
        assert!(out.join(r[0]).join("truth.csv").exists(), "recording of {}", r[0]);
    }
    // a file that is not there: one line naming it, non-zero exit, the outputs as they were
    let before = files_in(&out);
    let o = synth(&["--closed-loop", "/nonexistent/results.h5", "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("/nonexistent/results.h5") && err.lines().count() == 1, "{err}");
    // a results file without a finished run is refused after reading it: nothing replaced either
    let unfinished = dir.path().join("unfinished.h5");
    {
        let mut f = rbc_schema::results::ResultsFile::create_or_open(&unfinished).unwrap();
        let attrs = rbc_schema::results::RunAttrs { start_shape: "capsule".into(), r_init_um: 0.0, y_init_um: 0.0, z_init_um: 0.0, lambda: 1.0, scene: String::new() };
        f.begin_run("capsule_u1_r0", &attrs, &[[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]]).unwrap().fail("diverged").unwrap();
    }
    let o = synth(&["--closed-loop", unfinished.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("unfinished.h5") && err.contains("no finished run"), "{err}");
    assert_eq!(files_in(&out), before, "a refused run leaves the earlier outputs byte for byte");
    assert_eq!(hidden_entries(dir.path()), Vec::<String>::new(), "no staging folder left");
}

/// A run moving backwards has no recording to film: refused naming the file and the run. A run
/// too fast to be tracked (40 mm/s: 100 um a frame at 400 fps) is a row whose pipeline saw
/// nothing (`none`), its measures empty cells, never a NaN.
#[test]
fn a_run_moving_backwards_is_refused_and_one_too_fast_to_track_has_empty_measures() {
    let dir = tempfile::tempdir().unwrap();
    let with_velocity = |name: &str, v: f64| {
        let p = dir.path().join(name);
        std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/demo-results.h5"), &p).unwrap();
        let f = hdf5::File::open_rw(&p).unwrap();
        f.group("runs/capsule_u1_r1").unwrap().attr("mean_velocity_mm_s").unwrap().write_scalar(&v).unwrap();
        p
    };
    let back = with_velocity("back.h5", -5.0);
    let out = dir.path().join("back");
    let o = synth(&["--closed-loop", back.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.lines().count() == 1 && err.contains("back.h5") && err.contains("capsule_u1_r1") && err.contains("-5"), "{err}");
    assert!(!out.join("closed_loop.csv").exists());
    let fast = with_velocity("fast.h5", 40.0);
    let out = dir.path().join("fast");
    let o = synth(&["--closed-loop", fast.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("closed_loop.csv")).unwrap();
    assert!(!csv.contains("NaN"), "{csv}");
    let row = csv.lines().find(|l| l.starts_with("capsule_u1_r1,")).unwrap();
    assert!(row.contains(",none,none,") && row.ends_with(",40.0,,,,,"), "{row}");
}
