//! `rbc-bench shape-calibration`: fits the shape score's probability calibration (Platt's
//! sigmoid) on labelled synthetic tracks and prints its reliability on a held-out set.
//!
//! Usage: `rbc-bench shape-calibration [--seeds N] [--random M] [--bins K]`. The fit set is
//! `rbc_analysis::simulated::labelled::FIT_SEEDS` (the 96 grid recordings `rbc-bench
//! classifier-features` reads, plus recordings under random lab conditions), the held-out set
//! `HELD_OUT_SEEDS` (no seed in common), `N` seeds per grid condition (default 4: 96 recordings)
//! and `M` random-conditions recordings (default 48) each. Prints, as Markdown:
//! the fitted `a`, `b` beside the shipped `classify::SHAPE_CALIBRATION`; the held-out reliability
//! diagram in `K` equal bins of p (default 10: count, mean predicted p, observed croissant
//! fraction) with the fitted and with the shipped constants, and the expected calibration error
//! and Brier score of each; the labels the shipped classifier gave against the truth.

use rbc_analysis::experiment::calibration::{brier_score, expected_calibration_error, fit_platt, reliability, Platt};
use rbc_analysis::experiment::classify::ClassifierConfig;
use rbc_analysis::simulated::labelled::{labelled_tracks, LabelledTrack, SeedSet, FIT_SEEDS, HELD_OUT_SEEDS};
use std::path::Path;

struct Options {
    per_condition: usize,
    random: usize,
    bins: usize,
}

fn parse(args: &[String]) -> anyhow::Result<Options> {
    let mut o = Options { per_condition: FIT_SEEDS.per_condition, random: FIT_SEEDS.random, bins: 10 };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| -> anyhow::Result<usize> {
            let v = it.next().ok_or_else(|| anyhow::anyhow!("{name} needs a value"))?;
            let n: usize = v.parse().map_err(|_| anyhow::anyhow!("{name} takes a positive integer, got `{v}`"))?;
            anyhow::ensure!(n > 0, "{name} takes a positive integer, got `{v}`");
            Ok(n)
        };
        match a.as_str() {
            "--seeds" => o.per_condition = value("--seeds")?,
            "--bins" => o.bins = value("--bins")?,
            "--random" => o.random = value("--random")?,
            other => anyhow::bail!("rbc-bench shape-calibration: unknown option `{other}` (--seeds N, --random M, --bins K)"),
        }
    }
    Ok(o)
}

pub fn run(args: &[String]) -> anyhow::Result<()> {
    let o = parse(args)?;
    // A scratch folder removed at the end (std only: tempfile is a dev-dependency of this package).
    let tmp = std::env::temp_dir().join(format!("rbc-bench-shape-calibration-{}", std::process::id()));
    std::fs::create_dir_all(&tmp)?;
    let result = report(&tmp, &o);
    let _ = std::fs::remove_dir_all(&tmp);
    result
}

fn describe(name: &str, s: &SeedSet, tracks: &[LabelledTrack]) {
    let n_rec = s.recordings().len() as u64;
    let r = s.random_seeds();
    let croissants = tracks.iter().filter(|t| t.is_croissant()).count();
    println!(
        "{name}: grid seeds {}-{} ({n_rec} recordings), random-conditions seeds {}-{} ({} recordings), {} tracks matched to a truth cell, {croissants} of them croissants",
        s.first,
        s.first + n_rec - 1,
        r.start,
        r.end.saturating_sub(1),
        s.random,
        tracks.len()
    );
}

fn table(title: &str, m: &Platt, tracks: &[LabelledTrack], bins: usize) -> anyhow::Result<()> {
    let p: Vec<f64> = tracks.iter().map(|t| m.probability(t.score)).collect();
    let y: Vec<bool> = tracks.iter().map(LabelledTrack::is_croissant).collect();
    let diagram = reliability(&p, &y, bins)?;
    println!("\n{title} (a = {:.4}, b = {:.4}):\n", m.a, m.b);
    println!("| predicted p | tracks | mean predicted | observed croissant fraction |");
    println!("| --- | --- | --- | --- |");
    for b in &diagram {
        if b.count == 0 {
            println!("| {:.1}-{:.1} | 0 | - | - |", b.lo, b.hi);
        } else {
            println!("| {:.1}-{:.1} | {} | {:.3} | {:.3} |", b.lo, b.hi, b.count, b.mean_predicted, b.observed);
        }
    }
    println!("\nECE = {:.4}, Brier = {:.4}", expected_calibration_error(&diagram), brier_score(&p, &y)?);
    Ok(())
}

fn report(tmp: &Path, o: &Options) -> anyhow::Result<()> {
    let fit_set = SeedSet { per_condition: o.per_condition, random: o.random, ..FIT_SEEDS };
    let held_set = SeedSet { per_condition: o.per_condition, random: o.random, ..HELD_OUT_SEEDS };
    let fit_tracks = labelled_tracks(&tmp.join("fit"), &fit_set)?;
    let held = labelled_tracks(&tmp.join("held-out"), &held_set)?;
    println!("# Shape score calibration (Platt scaling)\n");
    describe("fit set", &fit_set, &fit_tracks);
    describe("held-out set", &held_set, &held);
    let scores: Vec<f64> = fit_tracks.iter().map(|t| t.score).collect();
    let labels: Vec<bool> = fit_tracks.iter().map(LabelledTrack::is_croissant).collect();
    let fitted = fit_platt(&scores, &labels)?;
    let cfg = ClassifierConfig::default();
    let shipped = cfg.calibration;
    println!("\nfitted on the fit set: a = {:.4}, b = {:.4}; shipped: a = {:.4}, b = {:.4}", fitted.a, fitted.b, shipped.a, shipped.b);
    println!(
        "shipped thresholds: croissant p >= {} (score >= {:.3}), slipper p <= {} (score <= {:.3})",
        cfg.p_croissant_min,
        shipped.score_at(cfg.p_croissant_min),
        cfg.p_slipper_max,
        shipped.score_at(cfg.p_slipper_max)
    );
    table("Held-out reliability, fitted constants", &fitted, &held, o.bins)?;
    if fitted != shipped {
        table("Held-out reliability, shipped constants", &shipped, &held, o.bins)?;
    }
    println!("\nHeld-out labels of the shipped classifier (rows: truth):\n");
    println!("| truth | croissant | slipper | other |");
    println!("| --- | --- | --- | --- |");
    for truth in ["croissant", "slipper", "other"] {
        let n = |label: &str| held.iter().filter(|t| t.truth == truth && t.label == label).count();
        println!("| {truth} | {} | {} | {} |", n("croissant"), n("slipper"), n("other"));
    }
    Ok(())
}
