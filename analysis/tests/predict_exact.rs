//! Exact answers of the prediction: uniform entrance samples, r_trans = inf / 0, brackets,
//! interpolation and projection, the phase diagram from run records, pressure groups.

use rbc_analysis::predict::fraction::{fraction_below, wilson, BINOMIAL_Z};
use rbc_analysis::predict::input::pressure_groups;
use rbc_analysis::predict::*;
use rbc_analysis::simulated::phase::{phase_points, DEFAULT_VELOCITY_REL_TOL};
use rbc_analysis::simulated::threshold::{thresholds, Threshold};
use rbc_analysis::types::prediction::{PredictConfig, VelocitySource};
use rbc_schema::results::{FinalShape, RunAttrs, RunRecord, RunStatus, RunSummary};
use rbc_schema::tables::{EntryRow, KdeRow, SummaryRow};
use std::path::Path;

/// n evenly spaced midpoints of [-a, a]: the fraction with |y| < t is t / a up to 1/n.
fn uniform(a: f64, n: usize) -> Vec<f64> {
    (0..n).map(|i| -a + 2.0 * a * (i as f64 + 0.5) / n as f64).collect()
}

fn node(u: f64, r: f64, lo: f64, hi: f64) -> Threshold {
    Threshold { start_shape: "discocyte".into(), velocity_mm_s: u, r_trans_um: r, r_lo_um: lo, r_hi_um: hi, n_croissant: 1, n_slipper: 1 }
}

#[test]
fn uniform_entrance_gives_y_trans_over_6() {
    let n = 1200;
    let ys = uniform(6.0, n);
    for r in [0.3, 0.7, 1.0, 2.5, 4.0] {
        let curve = ThresholdCurve::new(&[node(5.0, r, r, r)], "discocyte").unwrap();
        let p = predict_phi(&curve, &ys, 5.0, 0.0, 0.0);
        let yt = r * 9.0 / 106f64.sqrt();
        assert_eq!(p.y_trans_um, yt);
        assert!((p.phi - yt / 6.0).abs() <= 1.0 / n as f64, "r = {r}: phi {} vs {}", p.phi, yt / 6.0);
        // zero-width bracket, no velocity spread, no position error: only the binomial interval remains
        let (lo, hi) = wilson(p.phi, n, BINOMIAL_Z);
        assert!((p.phi_lo - lo).abs() < 1e-15 && (p.phi_hi - hi).abs() < 1e-15);
    }
}

#[test]
fn infinite_threshold_gives_one_and_zero_gives_zero() {
    let ys = uniform(6.0, 500);
    let inf = ThresholdCurve::new(&[node(2.5, f64::INFINITY, 5.5, f64::INFINITY)], "discocyte").unwrap();
    let p = predict_phi(&inf, &ys, 2.5, 0.0, 0.1);
    assert_eq!((p.phi, p.phi_hi, p.r_trans_um, p.y_trans_um), (1.0, 1.0, f64::INFINITY, f64::INFINITY));
    // lower end from the largest croissant offset 5.5 um minus s_P, then Wilson
    let f = fraction_below(&ys, 5.5 * 9.0 / 106f64.sqrt() - 0.1);
    assert_eq!(p.phi_lo, wilson(f, 500, 1.0).0);

    let zero = ThresholdCurve::new(&[node(0.2, 0.0, 0.0, 0.4)], "discocyte").unwrap();
    let p = predict_phi(&zero, &ys, 0.2, 0.0, 0.1);
    assert_eq!((p.phi, p.phi_lo, p.y_trans_um), (0.0, 0.0, 0.0));
    let f = fraction_below(&ys, 0.4 * 9.0 / 106f64.sqrt() + 0.1);
    assert_eq!(p.phi_hi, wilson(f, 500, 1.0).1);
}

#[test]
fn bracket_velocity_spread_and_position_error_combine_as_documented() {
    // columns at 5.5 (0.7, [0.6, 0.8]), 6.5 (0.7, [0.6, 0.8]), 8.0 (0.5, [0.4, 0.6])
    let curve = ThresholdCurve::new(&[node(5.5, 0.7, 0.6, 0.8), node(6.5, 0.7, 0.6, 0.8), node(8.0, 0.5, 0.4, 0.6)], "discocyte").unwrap();
    let n = 4000;
    let ys = uniform(4.0, n);
    let p = predict_phi(&curve, &ys, 6.5, 0.65, 0.1);
    // over u in [5.85, 7.15]: lower end 0.6 - 0.2 * (0.65 / 1.5) at 7.15, upper end 0.8
    let r_lo = 0.6 - 0.2 * 0.65 / 1.5;
    assert!((p.r_lo_um - r_lo).abs() < 1e-12 && (p.r_hi_um - 0.8).abs() < 1e-12, "{p:?}");
    let y = |r: f64| r * 9.0 / 106f64.sqrt();
    // uniform on [-4, 4]: F(t) = t / 4 (up to 1/n)
    let lo = wilson(((y(r_lo) - 0.1) / 4.0).max(0.0), n, 1.0).0;
    let hi = wilson((y(0.8) + 0.1) / 4.0, n, 1.0).1;
    assert!((p.phi - y(0.7) / 4.0).abs() <= 1.0 / n as f64);
    assert!((p.phi_lo - lo).abs() <= 2.0 / n as f64 && (p.phi_hi - hi).abs() <= 2.0 / n as f64, "{p:?} {lo} {hi}");
    assert!(!p.extrapolated);
    // leaving the simulated range is flagged
    assert!(predict_phi(&curve, &ys, 7.8, 0.5, 0.1).extrapolated);
}

fn record(id: &str, shape: &str, u: f64, r: f64, fin: Option<FinalShape>, status: RunStatus) -> RunRecord {
    let attrs = RunAttrs { start_shape: shape.into(), r_init_um: r, y_init_um: r * 9.0 / 106f64.sqrt(), z_init_um: r * 5.0 / 106f64.sqrt(), lambda: 5.0, scene: String::new() };
    let summary = fin.map(|f| RunSummary {
        status,
        final_shape: f,
        tank_treading: f == FinalShape::Slipper,
        tumbling: false,
        mean_velocity_mm_s: u,
        min_velocity_mm_s: u * 0.97,
        max_velocity_mm_s: u * 1.03,
        mean_radial_um: 1.0,
        mean_y_um: if f == FinalShape::Slipper { -1.2 } else { 0.0 },
        mean_z_um: 0.05,
        evidence: Default::default(),
    });
    RunRecord { run_id: id.into(), status, attrs: Some(attrs), summary, failure: None, not_run: None, copied_from: None, transits: Vec::new(), n_samples: 0, n_snapshots: 0 }
}

#[test]
fn thresholds_from_runs_group_velocities_and_skip_unfinished() {
    use FinalShape::*;
    use RunStatus::*;
    let runs = vec![
        // column at ~6.5 mm/s: mean velocities vary by 2 % with r_init
        record("a", "discocyte", 6.45, 0.2, Some(Croissant), Steady),
        record("b", "discocyte", 6.55, 0.6, Some(Croissant), Steady),
        record("c", "discocyte", 6.40, 0.8, Some(Slipper), Periodic),
        record("d", "discocyte", 6.60, 1.4, Some(Slipper), Periodic),
        record("e", "discocyte", 6.50, 1.0, Some(Other), Steady),
        // croissant-only column at 2.5
        record("f", "discocyte", 2.5, 0.5, Some(Croissant), Steady),
        record("g", "discocyte", 2.52, 1.9, Some(Croissant), Steady),
        // not used
        record("h", "discocyte", 2.5, 1.0, None, Failed),
        record("i", "discocyte", 2.5, 1.2, None, Running),
        record("j", "discocyte", 2.5, 1.4, Some(Slipper), Unsteady),
    ];
    let (points, skipped) = phase_points(&runs);
    assert_eq!(points.len(), 7);
    let ids: Vec<_> = skipped.iter().map(|s| s.run_id.as_str()).collect();
    assert_eq!(ids, ["h", "i", "j"]);
    let th = thresholds(&points, DEFAULT_VELOCITY_REL_TOL);
    assert_eq!(th.len(), 2);
    assert!((th[0].velocity_mm_s - 2.51).abs() < 1e-12);
    assert_eq!((th[0].r_trans_um, th[0].r_lo_um, th[0].r_hi_um), (f64::INFINITY, 1.9, f64::INFINITY));
    assert!((th[1].velocity_mm_s - 6.5).abs() < 1e-12, "mean of the 5 runs incl. `other`");
    assert!((th[1].r_trans_um - 0.7).abs() < 1e-12 && th[1].r_lo_um == 0.6 && th[1].r_hi_um == 0.8);
    assert_eq!((th[1].n_croissant, th[1].n_slipper), (2, 2));
    // single linkage: 1 % still chains the 0.8 % steps of the 6.5 column, 0.5 % splits it
    assert_eq!(thresholds(&points, 0.01).len(), 2);
    assert!(thresholds(&points, 0.005).len() > 2, "0.5 % splits the column (steps are 0.8 %)");
}

fn entry(p: f64, y: f64, v: f64) -> EntryRow {
    EntryRow { pressure_mbar: p, y_um: y, velocity_mm_s: v }
}

fn summary(p: f64, pos: f64, u: f64, f: f64) -> SummaryRow {
    SummaryRow {
        pressure_mbar: p, position_mm: pos, n_cells: 50, velocity_mean_mm_s: u, velocity_std_mm_s: 0.1 * u,
        frac_croissant: f, frac_slipper: 1.0 - f, frac_other: 0.0,
        frac_croissant_lo: None, frac_croissant_hi: None, frac_slipper_lo: None, frac_slipper_hi: None,
        frac_croissant_expected: None, frac_croissant_expected_sd: None,
    }
}

#[test]
fn pressure_groups_take_velocity_from_observed_or_entry() {
    let e = vec![entry(100.0, 0.5, 2.0), entry(100.0, -1.0, 4.0), entry(200.0, 0.1, 5.0), entry(100.0, 2.0, 3.0)];
    let s = vec![summary(200.0, 0.0, 1.0, 0.9), summary(200.0, 10.0, 6.5, 0.3), summary(200.0, 5.0, 6.0, 0.4), summary(300.0, 10.0, 8.0, 0.1)];
    let (g, w) = pressure_groups(&e, Path::new("entry.csv"), Some((&s, Path::new("summary.csv")))).unwrap();
    assert_eq!(g.len(), 2);
    assert_eq!(g[0].entry_y_um, vec![0.5, -1.0, 2.0]);
    assert_eq!(g[0].velocity_source, VelocitySource::Entry);
    // mean 3, sample std 1
    assert_eq!((g[0].velocity_mm_s, g[0].velocity_std_mm_s), (3.0, 1.0));
    let o = g[1].observed.as_ref().unwrap();
    assert_eq!((o.position_mm, o.frac_croissant), (10.0, 0.3));
    assert_eq!((g[1].velocity_mm_s, g[1].velocity_source), (6.5, VelocitySource::Observed));
    assert!(o.frac_croissant_lo < 0.3 && o.frac_croissant_hi > 0.3);
    assert_eq!(w.len(), 1, "300 mbar has no entering cells: {w:?}");
}

#[test]
fn malformed_tables_give_one_line_errors_with_file_and_row() {
    let e = vec![entry(100.0, 0.5, 2.0), entry(100.0, f64::INFINITY, 2.0)];
    let msg = pressure_groups(&e, Path::new("data/entry.csv"), None).unwrap_err().to_string();
    assert!(msg.contains("data/entry.csv") && msg.contains("row 2") && msg.contains("y_um") && !msg.contains('\n'), "{msg}");
    let msg = pressure_groups(&[], Path::new("entry.csv"), None).unwrap_err().to_string();
    assert!(msg.contains("entry.csv") && msg.contains("no cells"), "{msg}");
    let s = vec![summary(100.0, 10.0, 2.0, 1.5)];
    let msg = pressure_groups(&[entry(100.0, 0.0, 1.0)], Path::new("entry.csv"), Some((&s, Path::new("summary.csv")))).unwrap_err().to_string();
    assert!(msg.contains("summary.csv") && msg.contains("row 1") && msg.contains("frac_croissant"), "{msg}");
}

#[test]
fn predict_runs_end_to_end_in_memory_and_reports_offsets() {
    use FinalShape::*;
    use RunStatus::*;
    let runs = vec![
        record("a", "discocyte", 6.5, 0.2, Some(Croissant), Steady),
        record("b", "discocyte", 6.5, 0.6, Some(Croissant), Steady),
        record("c", "discocyte", 6.5, 0.8, Some(Slipper), Periodic),
        record("d", "discocyte", 6.5, 1.4, Some(Slipper), Periodic),
    ];
    let ys = uniform(4.0, 400);
    let e: Vec<EntryRow> = ys.iter().map(|&y| entry(150.0, y, 6.5)).collect();
    // slipper density with peaks at -1.0 and +1.2 -> offset 1.1
    let grid: Vec<f64> = (0..100).map(|i| -6.0 + 12.0 * i as f64 / 99.0).collect();
    let kde: Vec<KdeRow> = grid
        .iter()
        .map(|&y| KdeRow { pressure_mbar: 150.0, position_mm: 10.0, shape: "slipper".into(), y_um: y, density: (-(y + 1.0f64).powi(2) / 0.18).exp() + (-(y - 1.2f64).powi(2) / 0.18).exp() })
        .collect();
    let inputs = PredictInputs { runs: &runs, sims_path: Path::new("results.h5"), entry: &e, entry_path: Path::new("entry.csv"), observed: None, kde: Some(&kde) };
    let pred = predict(&inputs, PredictConfig::default()).unwrap();
    assert_eq!(pred.rows.len(), 1);
    let r = &pred.rows[0];
    assert!((r.r_trans_um - 0.7).abs() < 1e-12 && r.phi_observed.is_none());
    assert!((r.phi - r.y_trans_um / 4.0).abs() <= 1.0 / 400.0);
    assert_eq!(pred.experiment_offsets.len(), 1);
    assert!((pred.experiment_offsets[0].offset_um - 1.1).abs() < 1e-4, "{:?}", pred.experiment_offsets);
    assert_eq!(pred.simulated_offsets.len(), 1);
    assert_eq!(pred.simulated_offsets[0].abs_y_um, 1.2);

    // no usable run: one-line error naming the simulations file
    let bad = vec![record("h", "discocyte", 2.5, 1.0, None, Failed)];
    let inputs = PredictInputs { runs: &bad, ..inputs };
    let msg = predict(&inputs, PredictConfig::default()).unwrap_err().to_string();
    assert!(msg.contains("results.h5") && msg.contains("no finished run"), "{msg}");
}

/// Invariants over 2000 random curves, samples and velocities (seeded): the interval contains the
/// estimate, and more velocity spread or position uncertainty never narrows it.
#[test]
fn intervals_contain_the_estimate_and_grow_with_each_source() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for _ in 0..2000 {
        let n_nodes = rng.random_range(1..6);
        let mut u = 0.2;
        let nodes: Vec<Threshold> = (0..n_nodes)
            .map(|_| {
                u *= rng.random_range(1.1..2.0);
                let kind = rng.random_range(0..4);
                let (lo, hi) = {
                    let a: f64 = rng.random_range(0.2..2.0);
                    (a, a + rng.random_range(0.0..0.6))
                };
                match kind {
                    0 => node(u, f64::INFINITY, hi, f64::INFINITY),
                    1 => node(u, 0.0, 0.0, lo),
                    2 => node(u, 0.5 * (lo + hi), lo, hi),
                    _ => node(u, 0.5 * (lo + hi), hi, lo), // overlapping column: lo > hi
                }
            })
            .collect();
        let curve = ThresholdCurve::new(&nodes, "discocyte").unwrap();
        let n = rng.random_range(5..200);
        let ys: Vec<f64> = (0..n).map(|_| rng.random_range(-5.9..5.9)).collect();
        let uq = rng.random_range(0.1..1.2 * u);
        let s = rng.random_range(0.0..0.3) * uq;
        let p = predict_phi(&curve, &ys, uq, s, 0.1);
        assert!(0.0 <= p.phi_lo && p.phi_lo <= p.phi && p.phi <= p.phi_hi && p.phi_hi <= 1.0, "{p:?}");
        assert!(p.r_lo_um <= p.r_trans_um && p.r_trans_um <= p.r_hi_um, "{p:?}");
        let wider_u = predict_phi(&curve, &ys, uq, 2.0 * s + 0.01, 0.1);
        let wider_p = predict_phi(&curve, &ys, uq, s, 0.3);
        for w in [wider_u, wider_p] {
            assert_eq!(w.phi, p.phi);
            assert!(w.phi_lo <= p.phi_lo && w.phi_hi >= p.phi_hi, "{p:?} vs {w:?}");
        }
        // phi grows with the threshold: the interval ends bound phi at the bracket ends
        assert!(fraction_below(&ys, y_trans(p.r_lo_um)) <= p.phi && p.phi <= fraction_below(&ys, y_trans(p.r_hi_um)));
    }
}

/// The status column: bracketed inside a bracketing curve, extrapolated outside its velocity
/// range, unbracketed when r_trans may lie anywhere in [0, inf] (a croissant-only column next to
/// a slipper-only one) or phi anywhere in [0, 1].
#[test]
fn status_says_whether_phi_is_a_result() {
    let ys = uniform(4.0, 2000);
    let curve = ThresholdCurve::new(&[node(5.5, 0.7, 0.6, 0.8), node(6.5, 0.7, 0.6, 0.8)], "discocyte").unwrap();
    assert_eq!(predict_phi(&curve, &ys, 6.0, 0.2, 0.1).status(), "bracketed");
    assert_eq!(predict_phi(&curve, &ys, 6.5, 0.5, 0.1).status(), "extrapolated");
    // croissant-only at 2.5 (largest croissant offset 1.9), slipper-only at 6.5 (smallest slipper 0.0)
    let open = ThresholdCurve::new(&[node(2.5, f64::INFINITY, 1.9, f64::INFINITY), node(6.5, 0.0, 0.0, 0.0)], "discocyte").unwrap();
    let p = predict_phi(&open, &ys, 4.5, 2.0, 0.1);
    assert_eq!((p.r_lo_um, p.r_hi_um), (0.0, f64::INFINITY), "{p:?}");
    assert_eq!(p.status(), "unbracketed");
    // a croissant-only column alone is a result where its bracket excludes small offsets
    let inf = ThresholdCurve::new(&[node(2.5, f64::INFINITY, 5.5, f64::INFINITY)], "discocyte").unwrap();
    assert_eq!(predict_phi(&inf, &ys, 2.5, 0.0, 0.1).status(), "bracketed");
}
