//! Centroid, size and channel accuracy of the frame pipeline against the synthesiser's ground truth.
//! The signed error per truth shape (bias) is a table: `rbc-bench centroid-bias`.

mod frames_common;

use frames_common::{matches, quantile};
use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::simulated::synth::{random_spec, write_recording};

/// One study point: returns the centroid errors (um) of all matched detections and the numbers of visible / matched truths.
fn study(seed: u64, um_per_px: f64, noise: f64, v: f64) -> (Vec<f64>, usize, usize, f64) {
    let dir = tempfile::tempdir().unwrap();
    let spec = random_spec(seed, um_per_px, noise, v);
    let truth = write_recording(dir.path(), &spec, seed).unwrap();
    let rec = Recording::open(dir.path()).unwrap();
    let det = detect_recording(&rec).unwrap();
    let (axis, _) = truth.channel_rows();
    let m = matches(&truth, &det, 2.0);
    let errs: Vec<f64> = m.iter().map(|(t, d)| ((d.x_um - t.x_um).powi(2) + (d.y_um - t.y_um).powi(2)).sqrt()).collect();
    let visible = truth.rows.iter().filter(|t| t.visible).count();
    (errs, visible, m.len(), (det.channel.axis_row_px - axis) * um_per_px)
}

#[test]
fn centroid_accuracy_across_seeds_pixel_sizes_noise_and_velocities() {
    let mut all = Vec::new();
    for (i, &(px, noise, v)) in [(0.15, 0.005, 0.1), (0.2, 0.01, 1.0), (0.25, 0.02, 3.0), (0.3, 0.01, 6.0), (0.35, 0.015, 12.0), (0.35, 0.005, 0.5)].iter().enumerate() {
        let (errs, visible, matched, axis_err) = study(11 + i as u64, px, noise, v);
        println!(
            "px {px:.2} noise {noise:.3} v {v:5.1}: matched {matched}/{visible}, median {:.4} um, p95 {:.4} um, axis error {axis_err:+.4} um",
            quantile(&errs, 0.5),
            quantile(&errs, 0.95)
        );
        assert!(matched as f64 >= 0.9 * visible as f64, "too few visible cells found: {matched}/{visible}");
        all.extend(errs);
    }
    let (med, p95) = (quantile(&all, 0.5), quantile(&all, 0.95));
    println!("all: n = {}, median {med:.4} um, p95 {p95:.4} um", all.len());
    assert!(med <= 0.05, "median centroid error {med} um > 0.05 um");
}

/// The full study: 5 pixel sizes x 3 noise levels x 4 velocities x 2 seeds (seeded: the same
/// numbers every run; ~20 s).
/// `cargo test -p rbc-analysis --test frames_accuracy full_study -- --ignored --nocapture`
///
/// Measured (session 57): every visible cell found (5775 of 5775); centroid error median 0.0055
/// um, p95 0.0168, max 0.0478; the median rises with the pixel size (0.0033, 0.0046, 0.0054,
/// 0.0071, 0.0092 um at 0.15-0.35 um/px) and with the noise (0.0041, 0.0054, 0.0077 um at 0.005,
/// 0.015, 0.03). Asserted with ~20 % margins.
#[test]
#[ignore]
fn full_study() {
    use std::collections::BTreeMap;
    let mut by_px: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut by_noise: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut by_v: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut all = Vec::new();
    let (mut vis, mut found) = (0, 0);
    for &px in &[0.15, 0.2, 0.25, 0.3, 0.35] {
        for &noise in &[0.005, 0.015, 0.03] {
            for &v in &[0.1, 1.0, 4.0, 12.0] {
                for seed in 0..2u64 {
                    let (errs, visible, matched, _) = study(1000 + seed * 7 + (px * 100.0) as u64 + (v * 10.0) as u64, px, noise, v);
                    vis += visible;
                    found += matched;
                    by_px.entry(format!("{px:.2}")).or_default().extend(&errs);
                    by_noise.entry(format!("{noise:.3}")).or_default().extend(&errs);
                    by_v.entry(format!("{v:5.1}")).or_default().extend(&errs);
                    all.extend(errs);
                }
            }
        }
    }
    for (name, m) in [("um/px", &by_px), ("noise", &by_noise), ("v mm/s", &by_v)] {
        for (k, e) in m {
            println!("{name:7} {k}: n {:5}, median {:.4} um, p95 {:.4} um", e.len(), quantile(e, 0.5), quantile(e, 0.95));
        }
    }
    println!("all: n {}, found {found}/{vis} visible, median {:.4} um, p95 {:.4} um, max {:.4} um", all.len(), quantile(&all, 0.5), quantile(&all, 0.95), quantile(&all, 1.0));
    assert_eq!(found, vis, "every visible cell found");
    assert!(quantile(&all, 0.5) <= 0.0066 && quantile(&all, 0.95) <= 0.02 && quantile(&all, 1.0) <= 0.06, "all: median {}, p95 {}, max {}", quantile(&all, 0.5), quantile(&all, 0.95), quantile(&all, 1.0));
    // coarser pixels and more noise cost accuracy, monotonically (the maps iterate in key order)
    for m in [&by_px, &by_noise] {
        let medians: Vec<f64> = m.values().map(|e| quantile(e, 0.5)).collect();
        assert!(medians.windows(2).all(|w| w[0] < w[1]), "{medians:?}");
    }
    assert!(quantile(&by_px["0.35"], 0.5) <= 0.011 && quantile(&by_px["0.35"], 0.95) <= 0.03, "the coarsest pixels");
}
