//! Croissant / slipper / other from the projected shape of a tracked cell.
//!
//! The paper (Guckenberger et al., "Experimental results" and "Numerical results")
//! distinguishes the two steady shapes by symmetry and position: a croissant is
//! mirror-symmetric about the x-z plane through its centroid and flows on the channel
//! axis; a slipper breaks that symmetry and flows 0.8 to 1.5 um off the axis. Seen from
//! above (the camera looks along z) the croissant's projection is mirror-symmetric about
//! its own y-centre line, the slipper's is not. Everything not clearly one of the two,
//! including cases where the two cues disagree, is `other`.
//!
//! Features of a track (medians over its frames, robust against single bad frames):
//! - `A` = [`ShapeFeatures::mirror_asymmetry`](crate::types::ShapeFeatures): 1 - IoU of the mask and its mirror image
//!   about the horizontal line through the centroid (0 = symmetric).
//! - `|y|` = distance of the mean centroid from the channel axis, um.
//!
//! Each feature gives a vote in [-1, 1] (positive = croissant-like), linear around its
//! threshold and clamped:
//! `s_sym = clamp((A_thr - A) / A_scale)`, `s_off = clamp((y_thr - |y|) / y_scale)`.
//! The score is their weighted mean, `shape_score = (w_sym s_sym + w_off s_off) / (w_sym + w_off)`.
//! The label is `croissant` when both votes are positive and the score is at least
//! `min_confidence`, `slipper` when both are negative and the score at most `-min_confidence`,
//! and `other` otherwise. Frames vote individually too: if fewer than `min_agreement` of
//! the frames' symmetry votes agree with the track's, the shape is changing (tumbling, transient)
//! and the cell is `other`.

use crate::track::Track;
use crate::types::Detection;

/// Shape class of a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Shape {
    Croissant,
    Slipper,
    Other,
}

impl Shape {
    /// Name used in the CSV tables.
    pub fn as_str(self) -> &'static str {
        match self {
            Shape::Croissant => "croissant",
            Shape::Slipper => "slipper",
            Shape::Other => "other",
        }
    }
}

impl std::fmt::Display for Shape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Thresholds of the classifier (see the module documentation for the formulas).
#[derive(Debug, Clone, PartialEq)]
pub struct ClassifierConfig {
    /// Mirror asymmetry separating symmetric from asymmetric projections.
    pub asymmetry_threshold: f64,
    /// Asymmetry difference from the threshold that gives a full vote.
    pub asymmetry_scale: f64,
    /// Offset from the axis separating centred from off-centre cells, um
    /// (paper: croissants ~0, slippers 0.8 to 1.5 um; halfway at 0.5 um).
    pub offset_threshold_um: f64,
    /// Offset difference from the threshold that gives a full vote, um.
    pub offset_scale_um: f64,
    /// Weight of the symmetry vote.
    pub weight_symmetry: f64,
    /// Weight of the offset vote.
    pub weight_offset: f64,
    /// Minimum |score| for croissant or slipper.
    pub min_confidence: f64,
    /// Minimum fraction of frames whose symmetry vote agrees with the track's.
    pub min_agreement: f64,
}

impl Default for ClassifierConfig {
    fn default() -> Self {
        ClassifierConfig {
            asymmetry_threshold: 0.12,
            asymmetry_scale: 0.08,
            offset_threshold_um: 0.5,
            offset_scale_um: 0.4,
            weight_symmetry: 1.0,
            weight_offset: 1.0,
            min_confidence: 0.2,
            min_agreement: 0.6,
        }
    }
}

/// The evidence and the decision for one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Classification {
    pub shape: Shape,
    /// In [-1, 1]: > 0 croissant-like, < 0 slipper-like; |score| is the confidence.
    pub score: f64,
    /// Median mirror asymmetry over the track.
    pub asymmetry: f64,
    /// |mean y|, um.
    pub offset_um: f64,
    /// Fraction of frames whose symmetry vote agrees with the track's.
    pub agreement: f64,
}

fn vote(threshold: f64, value: f64, scale: f64) -> f64 {
    ((threshold - value) / scale).clamp(-1.0, 1.0)
}

/// Classify from per-frame asymmetries and the mean lateral position (um from the axis).
pub fn classify_features(asymmetries: &[f64], y_mean_um: f64, cfg: &ClassifierConfig) -> Classification {
    let mut a: Vec<f64> = asymmetries.iter().copied().filter(|v| v.is_finite()).collect();
    let offset_um = y_mean_um.abs();
    let Some(asymmetry) = crate::isolate::median(&mut a) else {
        return Classification { shape: Shape::Other, score: 0.0, asymmetry: f64::NAN, offset_um, agreement: 0.0 };
    };
    let s_sym = vote(cfg.asymmetry_threshold, asymmetry, cfg.asymmetry_scale);
    let s_off = vote(cfg.offset_threshold_um, offset_um, cfg.offset_scale_um);
    let score = (cfg.weight_symmetry * s_sym + cfg.weight_offset * s_off) / (cfg.weight_symmetry + cfg.weight_offset);
    let symmetric = asymmetry < cfg.asymmetry_threshold;
    let agreement = a.iter().filter(|&&v| (v < cfg.asymmetry_threshold) == symmetric).count() as f64 / a.len() as f64;
    let shape = if agreement < cfg.min_agreement {
        Shape::Other
    } else if s_sym > 0.0 && s_off > 0.0 && score >= cfg.min_confidence {
        Shape::Croissant
    } else if s_sym < 0.0 && s_off < 0.0 && score <= -cfg.min_confidence {
        Shape::Slipper
    } else {
        Shape::Other
    };
    Classification { shape, score, asymmetry, offset_um, agreement }
}

/// Classify a tracked cell from its detections (features of each frame, mean y).
pub fn classify(track: &Track, dets: &[Detection], cfg: &ClassifierConfig) -> Classification {
    let a: Vec<f64> = track.detections.iter().map(|&i| dets[i].features.mirror_asymmetry).collect();
    let n = track.detections.len().max(1) as f64;
    let y_mean = track.detections.iter().map(|&i| dets[i].y_um).sum::<f64>() / n;
    classify_features(&a, y_mean, cfg)
}
