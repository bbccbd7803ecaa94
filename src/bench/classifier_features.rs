//! `rbc-bench classifier-features`: the calibration table of the shape classifier, per-track features against the synthesiser's truth shape, as CSV on stdout.
//!
//! Usage: `rbc-bench classifier-features > features.csv`. 96 synthetic recordings (pixel sizes
//! 0.15, 0.25, 0.35 um; noise 0.005, 0.02; 0.1, 1, 3 and 12 mm/s; 4 seeds each, seeds from
//! 90001: `rbc_analysis::simulated::labelled::FIT_SEEDS`), each through detection, tracking and classification; one row per track: truth shape,
//! predicted shape, score and the median features the classifier reads. The thresholds in
//! `analysis/src/experiment/classify.rs` were read off this table (see its documentation).
//! Moved here from the ignored test `analysis/tests/tracks_calibrate.rs` (a table, not a check;
//! issue 13 item 7).

use rbc_analysis::stats::median::median;
use rbc_analysis::experiment::pipeline::{analyse_detections, StageConfig};
use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::experiment::track::link;
use rbc_analysis::simulated::labelled::FIT_SEEDS;
use rbc_analysis::simulated::synth::{random_spec, write_recording};
use rbc_analysis::types::Detection;
use std::path::Path;

pub fn run(args: &[String]) -> anyhow::Result<()> {
    if let Some(a) = args.first() {
        anyhow::bail!("rbc-bench classifier-features takes no options, got `{a}`");
    }
    // A scratch folder removed at the end (std only: tempfile is a dev-dependency of this package).
    let tmp = std::env::temp_dir().join(format!("rbc-bench-classifier-features-{}", std::process::id()));
    let result = table(&tmp);
    let _ = std::fs::remove_dir_all(&tmp);
    result
}

fn table(tmp: &Path) -> anyhow::Result<()> {
    println!("truth,predicted,score,asym,abs_y,skew_y,orientation_deg,solidity,aspect,px,noise,v");
    for case in FIT_SEEDS.recordings() {
        let (seed, px, noise, v) = (case.seed, case.um_per_px, case.noise_sigma, case.velocity_mm_s);
        let dir = tmp.join(format!("rec{seed}"));
        let spec = random_spec(seed, px, noise, v);
        let truth = write_recording(&dir, &spec, seed)?;
        let rec = Recording::open(&dir)?;
        let det = detect_recording(&rec)?;
        let stages = StageConfig::default();
        let tables = analyse_detections("r", &rec.config, &det.detections, &stages);
        let tracks = link(&det.detections, rec.config.fps, &stages.tracker);
        // the rows are the tracks that passed the area filter and have a motion: pair by id
        let pairs = tracks.iter().filter_map(|t| tables.tracks.iter().find(|r| r.track_id == t.id).map(|r| (t, r)));
        for (t, row) in pairs {
            let d0 = &det.detections[t.detections[0]];
            let Some(tr) = truth
                .rows
                .iter()
                .filter(|r| r.frame as usize == d0.frame)
                .min_by(|a, b| (a.x_um - d0.x_um).abs().total_cmp(&(b.x_um - d0.x_um).abs()))
            else {
                continue;
            };
            let f = |g: &dyn Fn(&Detection) -> f64| {
                let mut v: Vec<f64> = t.detections.iter().map(|&i| g(&det.detections[i])).collect();
                median(&mut v).unwrap_or(f64::NAN)
            };
            println!(
                "{},{},{:.3},{:.4},{:.3},{:.3},{:.1},{:.3},{:.3},{px},{noise},{v}",
                tr.shape,
                row.shape,
                row.shape_score,
                f(&|d| d.features.mirror_asymmetry),
                row.y_mean_um.abs(),
                f(&|d| d.features.skew_y),
                f(&|d| d.features.orientation_rad.to_degrees()),
                f(&|d| d.features.solidity),
                f(&|d| d.length_um / d.width_um),
            );
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(())
}
