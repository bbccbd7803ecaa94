//! The README's chain on the shipped examples: `rbc-analyze examples/frames/` then
//! `rbc-predict --sims examples/results.h5 --entry rbc-analysis/entry.csv --observed rbc-analysis/summary.csv`.
//!
//! `examples/results.h5` is the ended runs of the study `examples/studies/science-6p5`
//! (the paper's channel at ~6.5 mm/s: a discocyte started 0.4 um off the axis ended a
//! croissant, one started 1.2 um off a slipper). The test derives the expected prediction
//! from the inputs themselves: per start shape, r_trans is bracketed by the largest r_init of
//! a croissant and the smallest of a slipper (its midpoint), or `inf` when no run ends as a
//! slipper (then every entering cell counts, `phi = 1`); phi is the fraction of the group's
//! entering cells within the threshold's y; a group whose velocity spread leaves the
//! simulated columns says `extrapolated` and is warned about by name; `phi_observed` must
//! equal the croissant fraction that `rbc-analyze` wrote for the same pressure at 10 mm.

use rbc_schema::results::read_runs;
use rbc_schema::tables::{columns, read_entry, read_summary, read_table, PredictionRow, ThresholdRow};
use std::path::Path;
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn analyze_then_predict_on_the_shipped_examples() {
    let dir = tempfile::tempdir().unwrap();
    let analysis = dir.path().join("rbc-analysis");
    let prediction = dir.path().join("rbc-prediction");

    let out = Command::new(env!("CARGO_BIN_EXE_rbc-analyze"))
        .arg(root().join("examples/frames"))
        .arg("--out")
        .arg(&analysis)
        .output()
        .unwrap();
    assert!(out.status.success(), "rbc-analyze failed: {}", String::from_utf8_lossy(&out.stderr));

    let sims = root().join("examples/results.h5");
    let out = Command::new(env!("CARGO_BIN_EXE_rbc-predict"))
        .arg("--sims")
        .arg(&sims)
        .arg("--entry")
        .arg(analysis.join("entry.csv"))
        .arg("--observed")
        .arg(analysis.join("summary.csv"))
        .arg("--out")
        .arg(&prediction)
        .output()
        .unwrap();
    assert!(out.status.success(), "rbc-predict failed: {}", String::from_utf8_lossy(&out.stderr));
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();

    // Expected thresholds from the results file itself.
    let runs = read_runs(&sims).unwrap();
    assert!(!runs.is_empty());
    let thresholds: Vec<ThresholdRow> = read_table(&prediction.join("thresholds.csv"), columns::THRESHOLDS).unwrap();
    let predictions: Vec<PredictionRow> = read_table(&prediction.join("prediction.csv"), columns::PREDICTION).unwrap();
    let entry = read_entry(&analysis.join("entry.csv")).unwrap();
    let summary = read_summary(&analysis.join("summary.csv")).unwrap();
    assert!(!entry.is_empty() && !summary.is_empty());

    let mut pressures: Vec<f64> = entry.iter().map(|e| e.pressure_mbar).collect();
    pressures.sort_by(f64::total_cmp);
    pressures.dedup();

    let shapes: std::collections::BTreeSet<String> = runs.iter().filter_map(|r| r.attrs.as_ref()).map(|a| a.start_shape.clone()).collect();
    let mut brackets_checked = 0;
    for shape in &shapes {
        let has_slipper = runs
            .iter()
            .filter(|r| r.attrs.as_ref().is_some_and(|a| &a.start_shape == shape))
            .any(|r| r.summary.as_ref().is_some_and(|s| s.final_shape.as_str() == "slipper"));
        let rows: Vec<&ThresholdRow> = thresholds.iter().filter(|t| &t.start_shape == shape).collect();
        assert!(!rows.is_empty(), "no threshold for {shape}");
        // the bracket of r_trans in every velocity column from its runs' offsets and final shapes
        // (a run belongs to the column whose mean velocity is nearest its own)
        let column_of = |u: f64| {
            (0..rows.len()).min_by(|&a, &b| (rows[a].velocity_mm_s - u).abs().total_cmp(&(rows[b].velocity_mm_s - u).abs())).unwrap()
        };
        for (c, row) in rows.iter().enumerate() {
            let ended = |f: &str| -> Vec<f64> {
                runs.iter()
                    .filter(|r| r.attrs.as_ref().is_some_and(|a| &a.start_shape == shape))
                    .filter_map(|r| r.summary.as_ref().map(|s| (r, s)))
                    .filter(|(_, s)| s.final_shape.as_str() == f && column_of(s.mean_velocity_mm_s) == c)
                    .map(|(r, _)| r.attrs.as_ref().unwrap().r_init_um)
                    .collect()
            };
            let (croissants, slippers) = (ended("croissant"), ended("slipper"));
            let lo = croissants.iter().copied().fold(f64::MIN, f64::max);
            let hi = slippers.iter().copied().fold(f64::MAX, f64::min);
            match (croissants.is_empty(), slippers.is_empty()) {
                (true, true) => panic!("{shape}: a threshold row without croissants or slippers: {row:?}"),
                (false, true) => assert_eq!((row.r_trans_um, row.r_lo_um, row.r_hi_um), (f64::INFINITY, lo, f64::INFINITY), "{row:?}"),
                (true, false) => assert_eq!((row.r_trans_um, row.r_lo_um, row.r_hi_um), (0.0, 0.0, hi), "{row:?}"),
                (false, false) if lo < hi => {
                    assert_eq!((row.r_lo_um, row.r_hi_um), (lo, hi), "{row:?}");
                    assert!((row.r_trans_um - 0.5 * (lo + hi)).abs() < 1e-12, "{row:?}");
                    brackets_checked += 1;
                }
                // overlapping offsets: the least-misclassifying cut, somewhere between the two
                (false, false) => assert!(hi <= row.r_trans_um && row.r_trans_um <= lo, "{row:?}"),
            }
        }
        let (u_first, u_last) = rows.iter().fold((f64::MAX, f64::MIN), |(a, b), t| (a.min(t.velocity_mm_s), b.max(t.velocity_mm_s)));
        let preds: Vec<&PredictionRow> = predictions.iter().filter(|p| &p.start_shape == shape).collect();
        assert_eq!(preds.len(), pressures.len(), "one prediction per pressure group for {shape}");
        for p in &preds {
            assert!(0.0 <= p.phi_lo && p.phi_lo <= p.phi && p.phi <= p.phi_hi && p.phi_hi <= 1.0, "{p:?}");
            // phi: the fraction of the group's entering cells closer to the axis than y_trans
            let ys: Vec<f64> = entry.iter().filter(|e| e.pressure_mbar == p.pressure_mbar).map(|e| e.y_um).collect();
            assert!(!ys.is_empty(), "{p:?}");
            let below = ys.iter().filter(|y| y.abs() < p.y_trans_um).count() as f64 / ys.len() as f64;
            assert_eq!(p.phi, below, "{p:?}");
            let outside = p.velocity_mm_s - p.velocity_std_mm_s < u_first || p.velocity_mm_s + p.velocity_std_mm_s > u_last;
            if outside && !(p.phi_lo <= 0.0 && p.phi_hi >= 1.0) {
                assert_eq!(p.status, "extrapolated", "{p:?}");
                let warning = format!("start shape {shape}, {} mbar: velocity", p.pressure_mbar);
                assert!(stderr.contains(&warning) && stderr.contains("nearest column used"), "no warning naming the group: {stderr}");
            }
            if !has_slipper {
                assert!(p.r_trans_um.is_infinite(), "{p:?}");
                assert_eq!(p.phi, 1.0, "{p:?}");
            }
            // phi's interval covers [0, 1]: the runs decide nothing, and the table says so
            if p.phi_lo <= 0.0 && p.phi_hi >= 1.0 {
                assert_eq!(p.status, "unbracketed", "{p:?}");
                let warning = format!("start shape {shape}, {} mbar: the simulated runs do not bracket", p.pressure_mbar);
                assert!(stderr.contains(&warning), "no warning naming the group: {stderr}");
            }
            // the observed fraction is the croissant fraction at 10 mm of the same pressure
            let obs = summary
                .iter()
                .find(|s| s.pressure_mbar == p.pressure_mbar && s.position_mm == 10.0)
                .map(|s| s.frac_croissant);
            assert_eq!(p.phi_observed, obs, "{p:?}");
        }
    }
    // the shipped study has croissants below slippers in every discocyte column (README)
    assert!(brackets_checked >= 4, "{brackets_checked} cleanly bracketed columns checked: {thresholds:?}");
    // the shipped runs decide something: the group at the study's velocity (600 mbar) gets a phi
    // whose interval is narrower than [0, 1]
    assert!(predictions.iter().any(|p| p.pressure_mbar == 600.0 && p.phi_hi - p.phi_lo < 1.0), "{predictions:?}");
    for shape in &shapes {
        for ext in ["png", "svg"] {
            let path = prediction.join("figures").join(format!("phi_{shape}.{ext}"));
            assert!(std::fs::metadata(&path).map(|m| m.len() > 1000).unwrap_or(false), "{}", path.display());
        }
    }
    // the README prints this table: it is today's (a study run that ends moves it)
    let printed = String::from_utf8_lossy(&out.stdout).into_owned();
    let table: Vec<&str> = printed.lines().skip_while(|l| !l.starts_with("start_shape")).take_while(|l| !l.trim().is_empty() && !l.ends_with(':')).collect();
    assert!(table.len() > 1, "{printed}");
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let block = readme.split("```text\n").find(|b| b.starts_with(table[0])).unwrap_or_else(|| panic!("the README has no block starting with `{}`", table[0]));
    let shown: Vec<&str> = block.lines().take_while(|l| !l.starts_with("```")).collect();
    assert_eq!(shown, table, "the README's rbc-predict table is stale: rbc-predict prints\n{}", table.join("\n"));
}
