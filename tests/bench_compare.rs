//! `rbc-bench compare`: runs of one scene against a reference, as a table and (`--plot`) the
//! work-precision figure (`scripts/bench_speed.sh`, `scripts/work_precision.sh`).

use std::path::Path;
use std::process::Command;

fn fixture() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/fixtures/science-6p5-r1.2.h5")
}

/// The fixture against itself: every deviation and the drift of y are exactly 0, the cost per simulated ms is the
/// given CPU seconds over the run's span, the ratio is to the first run's, and `--plot` writes
/// the figure (PNG and SVG) under the name given.
#[test]
fn a_run_against_itself_deviates_by_zero_and_the_plot_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let f = fixture();
    let f = f.display();
    let out = Command::new(env!("CARGO_BIN_EXE_rbc-bench"))
        .args(["compare", &format!("{f}@100"), &format!("ros@2e-3={f}@40"), &format!("ros@1e-3={f}@80"), &format!("bs23@4e-5={f}@400"), "--plot"])
        .arg(dir.path().join("figs/wp"))
        .args(["--title", "self"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<Vec<&str>> = text.lines().filter(|l| l.starts_with("| ros") || l.starts_with("| bs23")).map(|l| l.split('|').map(str::trim).collect()).collect();
    assert_eq!(rows.len(), 3, "{text}");
    let span_ms: f64 = rows[0][3].parse().unwrap();
    assert!(span_ms > 0.0);
    for (row, cpu, ratio) in [(&rows[0], 40.0, "1.00"), (&rows[1], 80.0, "2.00"), (&rows[2], 400.0, "10.00")] {
        assert_eq!(row[2], format!("{cpu:.0}"));
        assert_eq!(row[4], format!("{:.1}", cpu / span_ms));
        assert_eq!(row[5], ratio);
        assert_eq!(&row[6..11], ["0.0e0"; 5], "{text}");
    }
    for ext in ["png", "svg"] {
        let p = dir.path().join(format!("figs/wp.{ext}"));
        assert!(std::fs::metadata(&p).map(|m| m.len() > 1000).unwrap_or(false), "{} missing", p.display());
    }
}

/// `--from-s T` counts a run's simulated ms from `T` on (runs resumed from one checkpoint share
/// their history before it): the fixture's span from its middle sample to its end, and one line
/// naming the file when no two rows are left.
#[test]
fn from_s_counts_the_simulated_time_from_its_start() {
    let f = fixture();
    let rows = rbc_schema::results::read_timeseries(&f, "discocyte_u3.8_r1.2").unwrap();
    let (mid, end) = (rows[rows.len() / 2].t_s, rows[rows.len() - 1].t_s);
    let compare = |from: f64| {
        Command::new(env!("CARGO_BIN_EXE_rbc-bench"))
            .args(["compare", &format!("{}@100", f.display()), &format!("ros={}@40", f.display()), "--from-s", &format!("{from:e}")])
            .output()
            .unwrap()
    };
    let out = compare(mid);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let row: Vec<&str> = text.lines().find(|l| l.starts_with("| ros")).unwrap().split('|').map(str::trim).collect();
    assert_eq!(row[3], format!("{:.2}", (end - mid) * 1e3), "{text}");
    let out = compare(end + 1.0);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("science-6p5-r1.2.h5") && err.contains("--from-s") && err.trim().lines().count() == 1, "{err}");
}

/// A run given without its CPU seconds is refused in one line naming the argument, and nothing is drawn.
#[test]
fn a_run_without_its_cpu_seconds_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let f = fixture();
    let out = Command::new(env!("CARGO_BIN_EXE_rbc-bench"))
        .args(["compare", &format!("{}@10", f.display()), &format!("ros={}", f.display()), "--plot"])
        .arg(dir.path().join("wp"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("expected FILE.h5@CPU_S") && err.contains("ros="), "{err}");
    assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none(), "something was written");
}
