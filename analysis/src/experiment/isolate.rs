//! The paper's isolation criterion: a cell counts only when no other object is within 40 um.
//!
//! Guckenberger et al. (methods, "Experimental setup"): hydrodynamic interaction in a
//! channel decays exponentially and is negligible beyond about twice the channel width
//! (~25 um here); "We only used cells that were at least 40 um apart from other entities."
//!
//! Distance is measured between centroids along x (the flow direction), in the same frame,
//! to every other segmented object: other cells, objects touching the image border
//! (counted as neighbours although they are not measured), debris. A track's `gap_um` is the
//! smallest such distance over all its frames (`inf` when it never shares a frame with
//! another object). Objects outside the field of view cannot be seen, so a cell close to
//! the image edge may have an unseen neighbour; only tracks measured over at least
//! [`crate::experiment::track::TrackerConfig::min_frames`] frames are reported, which keeps them away
//! from the edges for a few frames.
//!
//! Touching cells that segmentation merges into one object have no neighbour at all; they
//! are recognised by their shape instead ([`cluster_flags`]). An object is a cluster when
//! - its area exceeds [`IsolationConfig::cluster_area_factor`] times the recording's median
//!   object area, or its length [`IsolationConfig::cluster_length_factor`] times the median
//!   length (two cells in a row), or
//! - it is clearly mirror-asymmetric, clearly concave and notched like two bodies: mirror
//!   asymmetry >= [`IsolationConfig::cluster_min_asymmetry`], solidity <
//!   [`IsolationConfig::cluster_max_solidity`], and either a notch at least
//!   [`IsolationConfig::cluster_min_notch`] of the width deep or a two-sided waist of at
//!   least [`IsolationConfig::cluster_min_waist`] ([`crate::experiment::concavity`]). A croissant is
//!   concave but symmetric, a straight slipper asymmetric but convex; a *bent* slipper is
//!   asymmetric and concave too (solidity 0.76-0.88 when rendered from 3D shapes), but its
//!   concavity is the shallow inside of a bend on one side only. Measured (the numbers are
//!   printed by `analysis/tests/tracks_rtdc.rs` and `analysis/tests/closedloop_*.rs`): on
//!   the real RT-DC frames single red cells have solidity 0.92-0.96, notch <= 0.14 and waist
//!   <= 0.08; the merged objects (a cell with a small cell stuck to its end, overlapping
//!   pairs, two round cells side by side) have solidity 0.83-0.88 and notch 0.38-0.42 or
//!   waist 0.26; rendered bent slippers (analytic shapes) have notch <= 0.28 and waist
//!   <= 0.08, and 23 of 24 rendered solver shapes notch <= 0.29, waist <= 0.14 (the 24th,
//!   a transient whose in-focus section is pinched on both sides, has waist 0.23 and is
//!   flagged). The thresholds 0.33 and 0.14 sit between these groups.
//!
//! A track is a cluster when at least half of its detections are; a cluster is never isolated.

use crate::experiment::track::Track;
use crate::stats::median::median;
use crate::types::Detection;

/// Parameters of the isolation criterion.
#[derive(Debug, Clone, PartialEq)]
pub struct IsolationConfig {
    /// Minimum centroid distance along x to any other object, um (paper: 40 um).
    pub min_gap_um: f64,
    /// A track whose median area exceeds this multiple of the recording's median object area
    /// is a cluster of touching cells (two cells side by side or in a row have about twice the area;
    /// single red cells vary by about +-20 %, so 1.6 separates them).
    pub cluster_area_factor: f64,
    /// Same for the length along the principal axis (two cells in a row).
    pub cluster_length_factor: f64,
    /// Mirror asymmetry above which a concave object is a cluster.
    pub cluster_min_asymmetry: f64,
    /// Solidity below which an asymmetric object may be a cluster.
    pub cluster_max_solidity: f64,
    /// Notch depth / width ([`crate::types::ShapeFeatures::notch`]) from which an asymmetric,
    /// concave object is a cluster.
    pub cluster_min_notch: f64,
    /// Two-sided waist depth / width ([`crate::types::ShapeFeatures::waist`]) from which an
    /// asymmetric, concave object is a cluster.
    pub cluster_min_waist: f64,
}

impl Default for IsolationConfig {
    fn default() -> Self {
        IsolationConfig {
            min_gap_um: 40.0,
            cluster_area_factor: 1.6,
            cluster_length_factor: 1.6,
            cluster_min_asymmetry: 0.2,
            cluster_max_solidity: 0.88,
            cluster_min_notch: 0.33,
            cluster_min_waist: 0.14,
        }
    }
}

/// Isolation of one track.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Isolation {
    /// Smallest centroid distance along x to another object in the same frame, um (`inf` when none).
    pub gap_um: f64,
    /// The object is much larger than a single cell (merged touching cells).
    pub cluster: bool,
    /// `gap_um >= min_gap_um` and not a cluster.
    pub isolated: bool,
}

/// For every detection, the smallest centroid distance along x to another detection of the same frame, um.
pub fn gaps_per_detection(dets: &[Detection]) -> Vec<f64> {
    let n_frames = dets.iter().map(|d| d.frame + 1).max().unwrap_or(0);
    let mut by_frame: Vec<Vec<usize>> = vec![Vec::new(); n_frames];
    for (i, d) in dets.iter().enumerate() {
        by_frame[d.frame].push(i);
    }
    let mut gaps = vec![f64::INFINITY; dets.len()];
    for idx in &by_frame {
        for &i in idx {
            for &j in idx {
                if i != j {
                    let g = (dets[i].x_um - dets[j].x_um).abs();
                    if g < gaps[i] {
                        gaps[i] = g;
                    }
                }
            }
        }
    }
    gaps
}

/// For every detection: does it look like several touching cells merged into one object?
/// (See the module documentation; the reference area and length are the medians over the
/// non-border detections of `dets`.)
pub fn cluster_flags(dets: &[Detection], cfg: &IsolationConfig) -> Vec<bool> {
    let inner = || dets.iter().filter(|d| !d.touches_border);
    let ref_area = median(&mut inner().map(|d| d.area_um2).collect::<Vec<_>>());
    let ref_length = median(&mut inner().map(|d| d.length_um).collect::<Vec<_>>());
    dets.iter()
        .map(|d| {
            let big = ref_area.is_some_and(|r| r > 0.0 && d.area_um2 > cfg.cluster_area_factor * r)
                || ref_length
                    .is_some_and(|r| r > 0.0 && d.length_um > cfg.cluster_length_factor * r);
            let f = &d.features;
            let pinched = f.mirror_asymmetry >= cfg.cluster_min_asymmetry
                && f.solidity > 0.0
                && f.solidity < cfg.cluster_max_solidity
                && (f.notch >= cfg.cluster_min_notch || f.waist >= cfg.cluster_min_waist);
            big || pinched
        })
        .collect()
}

/// Isolation of every track of one recording (`dets` are all the recording's detections, border objects included).
pub fn isolate(tracks: &[Track], dets: &[Detection], cfg: &IsolationConfig) -> Vec<Isolation> {
    let gaps = gaps_per_detection(dets);
    let clusters = cluster_flags(dets, cfg);
    tracks
        .iter()
        .map(|t| {
            let gap_um = t
                .detections
                .iter()
                .map(|&i| gaps[i])
                .fold(f64::INFINITY, f64::min);
            let n_cluster = t.detections.iter().filter(|&&i| clusters[i]).count();
            let cluster = !t.detections.is_empty() && 2 * n_cluster >= t.detections.len();
            Isolation {
                gap_um,
                cluster,
                isolated: !cluster && gap_um >= cfg.min_gap_um,
            }
        })
        .collect()
}
