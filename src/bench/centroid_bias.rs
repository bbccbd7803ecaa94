//! `rbc-bench centroid-bias`: the signed centroid error of frame detection per truth shape and
//! pixel size (bias and spread along x and y, um), against the synthesiser's truth.
//!
//! Usage: `rbc-bench centroid-bias [--px 0.15,0.25,0.35] [--seeds 8]`. Per pixel size, `--seeds`
//! random recordings (seeds from 100, noise 0.005, 2 mm/s: `random_spec`), detected frame by
//! frame; each visible truth cell is paired with the nearest detection not cut by the border in
//! its frame within 2 um. Moved here from the ignored test `bias_by_shape` of
//! `analysis/tests/frames_accuracy.rs` (a table, not a check; issue 13 item 7); the accuracy
//! checks stay there.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Context};

use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::simulated::synth::{random_spec, write_recording};

pub fn run(args: &[String]) -> anyhow::Result<()> {
    let (mut pixel_sizes, mut seeds) = (vec![0.15, 0.25, 0.35], 8u64);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("rbc-bench centroid-bias: {a} needs a value"));
        match a.as_str() {
            "--px" => pixel_sizes = val()?.split(',').map(|s| s.trim().parse()).collect::<Result<_, _>>().context("--px")?,
            "--seeds" => seeds = val()?.parse().context("--seeds")?,
            other => bail!("rbc-bench centroid-bias: unknown option {other:?} (expected --px, --seeds)"),
        }
    }
    // A scratch folder removed at the end (std only: tempfile is a dev-dependency of this package).
    let tmp = std::env::temp_dir().join(format!("rbc-bench-centroid-bias-{}", std::process::id()));
    let result = table(&tmp, &pixel_sizes, seeds);
    let _ = std::fs::remove_dir_all(&tmp);
    result
}

/// Signed errors `(detected - truth)` in x and y (um) of the visible truth cells of one recording, by shape.
type ErrorsByShape = BTreeMap<String, Vec<(f64, f64)>>;

fn table(tmp: &Path, pixel_sizes: &[f64], seeds: u64) -> anyhow::Result<()> {
    println!("## Signed centroid error by truth shape (noise 0.005, 2 mm/s, {seeds} recordings per pixel size)\n");
    println!("| um/px | shape | n | mean dx (um) | sd dx (um) | mean dy (um) | sd dy (um) |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for &px in pixel_sizes {
        let mut by = ErrorsByShape::new();
        for seed in 0..seeds {
            let dir = tmp.join(format!("px{px}-seed{seed}"));
            let spec = random_spec(100 + seed, px, 0.005, 2.0);
            let truth = write_recording(&dir, &spec, seed)?;
            let det = detect_recording(&Recording::open(&dir)?)?;
            for t in truth.rows.iter().filter(|t| t.visible) {
                let nearest = det
                    .detections
                    .iter()
                    .filter(|d| !d.touches_border && d.frame as u64 == t.frame)
                    .map(|d| (d.x_um - t.x_um, d.y_um - t.y_um))
                    .min_by(|a, b| a.0.hypot(a.1).total_cmp(&b.0.hypot(b.1)));
                if let Some(e) = nearest.filter(|e| e.0.hypot(e.1) <= 2.0) {
                    by.entry(t.shape.clone()).or_default().push(e);
                }
            }
            let _ = std::fs::remove_dir_all(&dir);
        }
        for (shape, v) in by {
            let n = v.len() as f64;
            let (mx, my) = (v.iter().map(|e| e.0).sum::<f64>() / n, v.iter().map(|e| e.1).sum::<f64>() / n);
            let sx = (v.iter().map(|e| (e.0 - mx).powi(2)).sum::<f64>() / n).sqrt();
            let sy = (v.iter().map(|e| (e.1 - my).powi(2)).sum::<f64>() / n).sqrt();
            println!("| {px:.2} | {shape} | {} | {mx:+.4} | {sx:.4} | {my:+.4} | {sy:.4} |", v.len());
        }
    }
    Ok(())
}
