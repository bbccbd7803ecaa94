//! The predicted croissant fraction phi of one pressure group: the entrance y-sample below y_trans, with its uncertainty.
//!
//! Paper, section "Comparison of the phase diagrams", and physics.md
//! ("Prediction"): `y_trans = r_trans 9 / sqrt(106)` (the projection of the
//! initial-offset line `z = 5 y / 9` onto y: `r^2 = y^2 + z^2 = y^2 106 / 81`),
//! and `phi` = fraction of entering cells with `|y| < y_trans`.

use super::threshold::ThresholdCurve;
use crate::types::prediction::Phi;

/// Normal quantile of the binomial interval: 1, a 68 % (one sigma) interval,
/// the same level as the velocity spread `sigma_u` it is combined with.
pub const BINOMIAL_Z: f64 = 1.0;

/// Project an offset along `z = 5 y / 9` onto y: `y = r 9 / sqrt(106)` (um; `inf` stays `inf`).
pub fn y_trans(r_trans_um: f64) -> f64 {
    r_trans_um * 9.0 / 106f64.sqrt()
}

/// Fraction of `ys` with `|y| < y_t` (0 for an empty sample; 1 for `y_t = inf`).
pub fn fraction_below(ys: &[f64], y_t: f64) -> f64 {
    if ys.is_empty() {
        return 0.0;
    }
    ys.iter().filter(|y| y.abs() < y_t).count() as f64 / ys.len() as f64
}

/// Wilson score interval of a binomial proportion `p` from `n` trials at normal quantile `z`.
///
/// `(p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)` (Wilson 1927). Unlike
/// `p -+ z sqrt(p(1-p)/n)` it stays inside [0, 1] and has non-zero width at p = 0 or 1.
/// statrs has no proportion interval, hence this function.
pub fn wilson(p: f64, n: usize, z: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let n = n as f64;
    let z2 = z * z;
    let centre = p + z2 / (2.0 * n);
    let half = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    let d = 1.0 + z2 / n;
    (((centre - half) / d).max(0.0), ((centre + half) / d).min(1.0))
}

/// Predict phi for a group of entering cells `entry_y_um` moving at
/// `u_mm_s +- sigma_u_mm_s`, from the threshold curve of one start shape.
///
/// Uncertainty, combined as an interval (worst case), then widened by sampling:
/// 1. r_trans interval `[r_lo, r_hi]` = the widest bracket of r_trans over the
///    velocities `[u - sigma_u, u + sigma_u]` ([`ThresholdCurve::interval_over`]:
///    the simulation's bracket and the velocity spread together);
/// 2. projected to y and widened by the position uncertainty `s_P`:
///    `phi_sys_lo = F(y(r_lo) - s_P)`, `phi_sys_hi = F(y(r_hi) + s_P)`, with
///    F the fraction of the sample below (the sample's positions may be shifted
///    by up to `s_P` relative to the threshold);
/// 3. the finite sample: `phi_lo` is the lower end of the Wilson interval
///    ([`BINOMIAL_Z`] = 1 sigma) of `phi_sys_lo`, `phi_hi` the upper end of that of `phi_sys_hi`.
///
/// Adding the systematic interval and the statistical one end to end is
/// conservative; it keeps `phi_lo <= phi <= phi_hi` and needs no distributional
/// assumption on the bracket (which is a range, not a standard deviation).
pub fn predict_phi(curve: &ThresholdCurve, entry_y_um: &[f64], u_mm_s: f64, sigma_u_mm_s: f64, s_p_um: f64) -> Phi {
    let b = curve.at(u_mm_s);
    let (r_lo, r_hi) = curve.interval_over(u_mm_s - sigma_u_mm_s.abs(), u_mm_s + sigma_u_mm_s.abs());
    let r_lo = r_lo.min(b.r_trans_um);
    let r_hi = r_hi.max(b.r_trans_um);
    let y_t = y_trans(b.r_trans_um);
    let phi = fraction_below(entry_y_um, y_t);
    let n = entry_y_um.len();
    let sys_lo = fraction_below(entry_y_um, (y_trans(r_lo) - s_p_um).max(0.0));
    let sys_hi = fraction_below(entry_y_um, y_trans(r_hi) + s_p_um);
    let first = curve.nodes()[0].velocity_mm_s;
    let last = curve.nodes()[curve.nodes().len() - 1].velocity_mm_s;
    Phi {
        r_trans_um: b.r_trans_um,
        y_trans_um: y_t,
        phi,
        phi_lo: wilson(sys_lo, n, BINOMIAL_Z).0.min(phi),
        phi_hi: wilson(sys_hi, n, BINOMIAL_Z).1.max(phi),
        r_lo_um: r_lo,
        r_hi_um: r_hi,
        extrapolated: u_mm_s - sigma_u_mm_s.abs() < first || u_mm_s + sigma_u_mm_s.abs() > last,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_known_values() {
        // p = 0.5, n = 100, z = 1.96: 0.4038 .. 0.5962 (standard table value)
        let (lo, hi) = wilson(0.5, 100, 1.96);
        assert!((lo - 0.4038).abs() < 1e-4 && (hi - 0.5962).abs() < 1e-4, "{lo} {hi}");
        // p = 0: lower end exactly 0, upper z^2 / (n + z^2)
        let (lo, hi) = wilson(0.0, 10, 1.0);
        assert_eq!(lo, 0.0);
        assert!((hi - 1.0 / 11.0).abs() < 1e-15);
        let (lo, hi) = wilson(1.0, 10, 1.0);
        assert!((lo - 10.0 / 11.0).abs() < 1e-15 && hi == 1.0);
    }

    #[test]
    fn projection_is_along_z_equals_5y_over_9() {
        let r = 1.3;
        let y = y_trans(r);
        let z = 5.0 * y / 9.0;
        assert!(((y * y + z * z).sqrt() - r).abs() < 1e-15);
        assert_eq!(y_trans(f64::INFINITY), f64::INFINITY);
        assert_eq!(y_trans(0.0), 0.0);
    }
}
