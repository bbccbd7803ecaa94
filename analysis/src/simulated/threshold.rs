//! The transition offset r_trans per start shape and velocity column of the simulated phase diagram, with its bracket.
//!
//! Paper, section "Comparison of the phase diagrams": r_trans separates
//! croissants (below) from slippers (above); r_trans = inf in the
//! croissant-only window, 0 where no croissant exists. The prediction
//! interpolates it in u ([`crate::predict::ThresholdCurve`]); the phase diagram
//! figures draw it.

use super::phase::{bin_velocities, start_shapes, PhasePoint};
use rbc_schema::results::FinalShape;

/// r_trans of one velocity column, with its bracket.
///
/// `r_lo_um` is the largest croissant offset and `r_hi_um` the smallest slipper
/// offset (`inf` when the column has no slipper, 0 and the smallest slipper
/// offset when it has no croissant). When the column is not cleanly separated
/// (a croissant above a slipper), `r_lo_um > r_hi_um`; the uncertainty interval
/// of r_trans is then `[r_hi_um, r_lo_um]` ([`Threshold::interval`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Threshold {
    pub start_shape: String,
    /// Mean of the column's run velocities, mm/s.
    pub velocity_mm_s: f64,
    pub r_trans_um: f64,
    pub r_lo_um: f64,
    pub r_hi_um: f64,
    pub n_croissant: usize,
    pub n_slipper: usize,
}

impl Threshold {
    /// The uncertainty interval of r_trans, `[min(r_lo, r_hi), max(r_lo, r_hi)]`, um.
    pub fn interval(&self) -> (f64, f64) {
        (self.r_lo_um.min(self.r_hi_um), self.r_lo_um.max(self.r_hi_um))
    }
}

/// r_trans and its bracket from the croissant and slipper offsets of one column (um).
///
/// - no slipper: `(inf, max croissant, inf)`;
/// - no croissant: `(0, 0, min slipper)`;
/// - cleanly separated (`max croissant < min slipper`): the midpoint of the bracket;
/// - overlapping: the offset that misclassifies the fewest runs (croissants above
///   plus slippers below), the middle one of the tied candidates.
///
/// Returns `None` when the column has neither croissants nor slippers.
pub fn column_threshold(croissants: &[f64], slippers: &[f64]) -> Option<(f64, f64, f64)> {
    let max_c = croissants.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min_s = slippers.iter().copied().fold(f64::INFINITY, f64::min);
    match (croissants.is_empty(), slippers.is_empty()) {
        (true, true) => None,
        (false, true) => Some((f64::INFINITY, max_c, f64::INFINITY)),
        (true, false) => Some((0.0, 0.0, min_s)),
        (false, false) if max_c < min_s => Some((0.5 * (max_c + min_s), max_c, min_s)),
        (false, false) => {
            // candidate thresholds: midpoints between consecutive distinct offsets
            let mut all: Vec<f64> = croissants.iter().chain(slippers).copied().collect();
            all.sort_by(f64::total_cmp);
            all.dedup();
            let cands: Vec<f64> = all.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
            let errors = |t: f64| croissants.iter().filter(|&&c| c > t).count() + slippers.iter().filter(|&&s| s < t).count();
            let best = cands.iter().map(|&t| errors(t)).min()?;
            let tied: Vec<f64> = cands.iter().copied().filter(|&t| errors(t) == best).collect();
            Some((tied[tied.len() / 2], max_c, min_s))
        }
    }
}

/// Thresholds of every start shape and velocity column, sorted by start shape then velocity.
///
/// Columns are built per start shape with [`bin_velocities`] (`rel_tol`, see
/// [`DEFAULT_VELOCITY_REL_TOL`](super::phase::DEFAULT_VELOCITY_REL_TOL)); runs that ended as `other` do
/// not vote; a column with neither croissant nor slipper is left out.
pub fn thresholds(points: &[PhasePoint], rel_tol: f64) -> Vec<Threshold> {
    let mut out = Vec::new();
    for shape in start_shapes(points) {
        let pts: Vec<&PhasePoint> = points.iter().filter(|p| p.start_shape == shape).collect();
        let u: Vec<f64> = pts.iter().map(|p| p.velocity_mm_s).collect();
        let bins = bin_velocities(&u, rel_tol);
        let nb = bins.iter().copied().max().map_or(0, |m| m + 1);
        for b in 0..nb {
            let col: Vec<&&PhasePoint> = pts.iter().zip(&bins).filter(|(_, &bb)| bb == b).map(|(p, _)| p).collect();
            let velocity_mm_s = col.iter().map(|p| p.velocity_mm_s).sum::<f64>() / col.len() as f64;
            let of = |s: FinalShape| -> Vec<f64> { col.iter().filter(|p| p.final_shape == s).map(|p| p.r_init_um).collect() };
            let (c, s) = (of(FinalShape::Croissant), of(FinalShape::Slipper));
            if let Some((r_trans_um, r_lo_um, r_hi_um)) = column_threshold(&c, &s) {
                out.push(Threshold {
                    start_shape: shape.clone(),
                    velocity_mm_s,
                    r_trans_um,
                    r_lo_um,
                    r_hi_um,
                    n_croissant: c.len(),
                    n_slipper: s.len(),
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn column_cases() {
        assert_eq!(column_threshold(&[0.2, 0.6], &[0.8, 1.2]), Some((0.7, 0.6, 0.8)));
        assert_eq!(column_threshold(&[0.2, 1.8], &[]), Some((f64::INFINITY, 1.8, f64::INFINITY)));
        assert_eq!(column_threshold(&[], &[0.4, 1.0]), Some((0.0, 0.0, 0.4)));
        assert_eq!(column_threshold(&[], &[]), None);
        // one croissant above the slippers (the "protrusion"): offsets 0.2 c, 0.4 c, 0.6 s, 0.8 c, 1.0 s, 1.2 s.
        // errors: t=0.5 -> 1 (0.8 c above), t=0.7 -> 2, t=0.9 -> 1 (0.6 s below); tied 0.5 and 0.9 -> middle = 0.9
        let (r, lo, hi) = column_threshold(&[0.2, 0.4, 0.8], &[0.6, 1.0, 1.2]).unwrap();
        assert_eq!((lo, hi), (0.8, 0.6));
        assert!((r - 0.9).abs() < 1e-12, "{r}");
    }
}
