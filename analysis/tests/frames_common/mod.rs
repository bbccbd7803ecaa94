//! Helpers shared by the frames_* integration tests: matching detections to the synthesiser's truth.
#![allow(dead_code)]

use rbc_analysis::experiment::recording::RecordingDetections;
use rbc_analysis::simulated::synth::{Truth, TruthRow};
use rbc_analysis::types::Detection;

/// Pairs (truth, detection) for every visible truth cell with a non-border detection
/// in the same frame within `max_um` of it (the nearest one).
pub fn matches<'a>(truth: &'a Truth, det: &'a RecordingDetections, max_um: f64) -> Vec<(&'a TruthRow, &'a Detection)> {
    let mut out = Vec::new();
    for t in truth.rows.iter().filter(|t| t.visible) {
        let best = det
            .detections
            .iter()
            .filter(|d| d.frame as u64 == t.frame && !d.touches_border)
            .map(|d| (((d.x_um - t.x_um).powi(2) + (d.y_um - t.y_um).powi(2)).sqrt(), d))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((dist, d)) = best {
            if dist <= max_um {
                out.push((t, d));
            }
        }
    }
    out
}

/// Quantile `q` in [0, 1] of `v` (nearest rank).
pub fn quantile(v: &[f64], q: f64) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    s[((q * (s.len() - 1) as f64).round() as usize).min(s.len() - 1)]
}
