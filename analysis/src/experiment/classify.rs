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
//! Features of a track (robust against single bad frames):
//! - `A` = mirror asymmetry of the track's median mask ([`crate::experiment::median_mask`]: the
//!   frames' masks aligned at their centroids and combined by their per-pixel median): 1 - IoU
//!   of that mask and its mirror image about the horizontal line through the centroid (0 =
//!   symmetric). Pixel noise makes single frames' outlines ragged, which reads as asymmetry when
//!   the cell's contrast is a few times the noise (near focus); the median mask outvotes it. Each
//!   frame's own [`ShapeFeatures::mirror_asymmetry`](crate::types::ShapeFeatures) still votes on
//!   whether the shape is steady (below), and is the track's `A` (their median) when the
//!   detections carry no mask.
//! - `|y|` = distance of the mean centroid from the channel axis, um.
//!
//! Each feature gives a vote in [-1, 1] (positive = croissant-like), linear around its
//! threshold and clamped:
//! `s_sym = clamp((A_thr - A) / A_scale)`, `s_off = clamp((y_thr - |y|) / y_scale)`.
//! The score is their weighted mean, `shape_score = (w_sym s_sym + w_off s_off) / (w_sym + w_off)`.
//!
//! **How sure it is.** The score becomes the probability that the cell is a croissant by
//! Platt's sigmoid ([`crate::experiment::calibration::Platt`]),
//! `p_croissant = 1 / (1 + exp(-(a shape_score + b)))`, with [`SHAPE_CALIBRATION`]:
//! a = 6.6143, b = -1.3585, fitted by maximum likelihood
//! ([`crate::experiment::calibration::fit_platt`], Platt's smoothed targets) on 332 labelled
//! synthetic tracks ([`crate::simulated::labelled::FIT_SEEDS`]: the 96 recordings `rbc-bench
//! classifier-features` reads, seeds 90001-90096, pixel sizes 0.15, 0.25, 0.35 um, noise 0.5 and
//! 2 %, 0.1-12 mm/s, and 48 recordings under a lab's conditions drawn at random, seeds
//! 95001-95048: defocus, NA, blur, noise, 0.1-0.4 um/px, walls, debris, neighbours; tracks matched
//! to truth cells by position; truth croissant = 1, slipper and irregular = 0) and checked on a
//! disjoint held-out set (seeds 190001-190096 and 195001-195048: expected calibration error 0.023,
//! Brier score 0.016 over 332 tracks, with `A` the median of the frames' asymmetries; 0.0255 and
//! 0.0117 with the median mask's, where a refit, a = 6.43, b = -1.65, gains 0.0007 and 0.0009 and
//! was not adopted). `rbc-bench shape-calibration` refits them and prints the
//! held-out reliability diagram (table in `analysis/README.md`). The random conditions put cells
//! between the clear cases (on the grid alone croissants and non-croissants are nearly separated
//! and the slope would come from the smoothed targets, not from data). The probability is
//! calibrated for the synthesiser's optics and mix of shapes (about 35 % croissants): another
//! prior shifts b by the log of the ratio of the prior odds.
//!
//! The label is `croissant` when both votes are positive and `p_croissant >= p_croissant_min`
//! (0.8: a score of at least 0.415), `slipper` when both are negative, `p_croissant <=
//! p_slipper_max` (0.05: a score of at most -0.240)
//! and the cell is elongated along the flow (median length/width >= `slipper_min_aspect`
//! and median angle of the long axis to x <= `slipper_max_tilt_deg`: the paper's slippers are
//! stretched along the flow and only slightly tilted, Fig. 6b; an asymmetric, off-centre
//! object that is round or lies across the flow is a tumbling or irregular cell), and `other`
//! otherwise: `other` is the answer when the classifier is unsure. Frames vote individually too:
//! if fewer than `min_agreement` of the frames
//! contradict the track's symmetry vote by at most a quarter of `A_scale`, the shape is
//! changing (tumbling, transient) and the cell is `other`.
//!
//! Thresholds were read off the synthesiser (`rbc-bench classifier-features`, 192
//! tracks over pixel sizes 0.15-0.35 um/px, noise 0.5-2 %, 0.1-12 mm/s): median asymmetry
//! of croissants 0.008-0.077, of slippers 0.123-0.488 (threshold 0.11, between the two);
//! |y| of croissants <= 0.47 um, of slippers >= 1.07 um (paper: slippers 0.8-1.5 um off the
//! axis; threshold 0.65 um between the paper's and the synthesiser's bounds); slipper aspect
//! at least 1.43 and tilt at most 22 deg, irregular cells mostly rounder or tilted at random
//! (1.3 and 40 deg keep a margin below the slippers). On that table, with the score
//! thresholds +-0.2 used before the calibration, croissant vs slipper was 121/121 correct and 64
//! of 71 irregular cells `other` (6 called slipper, 1 croissant).

use crate::experiment::calibration::Platt;
use crate::experiment::track::Track;
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

/// Platt constants of the shape score fitted on synthetic tracks (module documentation;
/// `rbc-bench shape-calibration` refits them).
pub const SHAPE_CALIBRATION: Platt = Platt { a: 6.6143, b: -1.3585 };

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
    /// Score -> probability of a croissant (see the module documentation).
    pub calibration: Platt,
    /// Smallest `p_croissant` of a croissant.
    pub p_croissant_min: f64,
    /// Largest `p_croissant` of a slipper.
    pub p_slipper_max: f64,
    /// Minimum fraction of frames whose symmetry vote agrees with the track's.
    pub min_agreement: f64,
    /// Smallest median length/width of a slipper.
    pub slipper_min_aspect: f64,
    /// Largest median angle between a slipper's long axis and the flow (x), degrees.
    pub slipper_max_tilt_deg: f64,
}

impl Default for ClassifierConfig {
    fn default() -> Self {
        ClassifierConfig {
            asymmetry_threshold: 0.11,
            asymmetry_scale: 0.08,
            offset_threshold_um: 0.65,
            offset_scale_um: 0.4,
            weight_symmetry: 1.0,
            weight_offset: 1.0,
            calibration: SHAPE_CALIBRATION,
            p_croissant_min: 0.8,
            p_slipper_max: 0.05,
            min_agreement: 0.6,
            slipper_min_aspect: 1.3,
            slipper_max_tilt_deg: 40.0,
        }
    }
}

/// The evidence and the decision for one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Classification {
    pub shape: Shape,
    /// In [-1, 1]: > 0 croissant-like, < 0 slipper-like; |score| is the confidence.
    pub score: f64,
    /// Calibrated probability that the cell is a croissant, `calibration.probability(score)`.
    pub p_croissant: f64,
    /// Mirror asymmetry of the track: its median mask's ([`track_asymmetry`]), or the median of its frames'.
    pub asymmetry: f64,
    /// |mean y|, um.
    pub offset_um: f64,
    /// Fraction of frames whose symmetry vote agrees with the track's.
    pub agreement: f64,
}

fn vote(threshold: f64, value: f64, scale: f64) -> f64 {
    ((threshold - value) / scale).clamp(-1.0, 1.0)
}

/// The projected shape of a cell in one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameShape {
    /// Mirror asymmetry about the horizontal line through the centroid (0 = symmetric).
    pub asymmetry: f64,
    /// Angle of the long axis to +x, radians, in (-pi/2, pi/2].
    pub orientation_rad: f64,
    /// Length / width along and across the long axis (>= 1).
    pub aspect: f64,
}

impl FrameShape {
    /// The shape of a detection.
    pub fn of(d: &Detection) -> FrameShape {
        let aspect = if d.width_um > 0.0 {
            d.length_um / d.width_um
        } else {
            f64::NAN
        };
        FrameShape {
            asymmetry: d.features.mirror_asymmetry,
            orientation_rad: d.features.orientation_rad,
            aspect,
        }
    }
}

fn median_of(values: impl Iterator<Item = f64>) -> Option<f64> {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    crate::stats::median::median(&mut v)
}

/// Classify from the shapes of the cell's frames and its mean lateral position (um from the
/// axis), the track's asymmetry being the median of the frames'.
pub fn classify_frames(
    frames: &[FrameShape],
    y_mean_um: f64,
    cfg: &ClassifierConfig,
) -> Classification {
    classify_frames_with(frames, None, y_mean_um, cfg)
}

/// [`classify_frames`] with the track's mirror asymmetry given (`Some`: e.g. that of the track's
/// median mask, [`crate::experiment::median_mask`]) instead of the median of the frames'; the frames'
/// own asymmetries still vote on whether the shape is steady (`min_agreement`).
pub fn classify_frames_with(
    frames: &[FrameShape],
    track_asymmetry: Option<f64>,
    y_mean_um: f64,
    cfg: &ClassifierConfig,
) -> Classification {
    let a: Vec<f64> = frames
        .iter()
        .map(|f| f.asymmetry)
        .filter(|v| v.is_finite())
        .collect();
    let offset_um = y_mean_um.abs();
    let track_asymmetry = track_asymmetry.filter(|v| v.is_finite() && !a.is_empty());
    let Some(asymmetry) = track_asymmetry.or_else(|| median_of(a.iter().copied())) else {
        return Classification {
            shape: Shape::Other,
            score: 0.0,
            p_croissant: cfg.calibration.probability(0.0),
            asymmetry: f64::NAN,
            offset_um,
            agreement: 0.0,
        };
    };
    let s_sym = vote(cfg.asymmetry_threshold, asymmetry, cfg.asymmetry_scale);
    let s_off = vote(cfg.offset_threshold_um, offset_um, cfg.offset_scale_um);
    let score = (cfg.weight_symmetry * s_sym + cfg.weight_offset * s_off)
        / (cfg.weight_symmetry + cfg.weight_offset);
    // A frame contradicts the track when its own symmetry vote has the other sign by more than a quarter.
    let agreeing = a
        .iter()
        .filter(|&&v| {
            vote(cfg.asymmetry_threshold, v, cfg.asymmetry_scale) * s_sym.signum() >= -0.25
        })
        .count();
    let agreement = agreeing as f64 / a.len() as f64;
    let aspect = median_of(frames.iter().map(|f| f.aspect)).unwrap_or(f64::NAN);
    let tilt_deg =
        median_of(frames.iter().map(|f| f.orientation_rad.abs().to_degrees())).unwrap_or(f64::NAN);
    let elongated_along_flow =
        aspect >= cfg.slipper_min_aspect && tilt_deg <= cfg.slipper_max_tilt_deg;
    let p_croissant = cfg.calibration.probability(score);
    let shape = if agreement < cfg.min_agreement {
        Shape::Other
    } else if s_sym > 0.0 && s_off > 0.0 && p_croissant >= cfg.p_croissant_min {
        Shape::Croissant
    } else if s_sym < 0.0 && s_off < 0.0 && p_croissant <= cfg.p_slipper_max && elongated_along_flow {
        Shape::Slipper
    } else {
        Shape::Other
    };
    Classification {
        shape,
        score,
        p_croissant,
        asymmetry,
        offset_um,
        agreement,
    }
}

/// Classify a tracked cell from its detections (shape of each frame, mean y): its symmetry is
/// judged on the track's median mask ([`track_asymmetry`]).
pub fn classify(track: &Track, dets: &[Detection], cfg: &ClassifierConfig) -> Classification {
    let frames: Vec<FrameShape> = track
        .detections
        .iter()
        .map(|&i| FrameShape::of(&dets[i]))
        .collect();
    let n = track.detections.len().max(1) as f64;
    let y_mean = track.detections.iter().map(|&i| dets[i].y_um).sum::<f64>() / n;
    classify_frames_with(&frames, track_asymmetry(track, dets), y_mean, cfg)
}

/// Mirror asymmetry of the track's median mask: its frames' masks aligned at their centroids and
/// combined by their per-pixel median ([`crate::experiment::median_mask`]), so that what pixel
/// noise puts in or out of single frames' outlines is outvoted. `None` when the detections carry
/// no mask (built without a segmentation).
pub fn track_asymmetry(track: &Track, dets: &[Detection]) -> Option<f64> {
    crate::experiment::median_mask::track_asymmetry(track.detections.iter().map(|&i| &dets[i].mask))
}
