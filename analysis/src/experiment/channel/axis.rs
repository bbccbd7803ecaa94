//! The channel's axis as the centre of mirror symmetry of the log row profile, read the same way on
//! both sides of the trial centre (so that walls narrower than a pixel do not pull it).
//!
//! A bright-field image of the channel is `I(y) = B(y) W(y)`: the illumination `B` times the
//! walls' image `W`, which is mirror symmetric about the axis `c` (`W(c + t) = W(c - t)`). In
//! `L = ln I` the illumination is additive, and across the channel's 12-20 um it is smooth, so
//! about `c` its antisymmetric part is a line: `L(c + t) - L(c - t) = 2 b t` (Taylor to first
//! order; a quadratic vignette about any centre only adds a line to it). The axis is the `c` that
//! minimises
//!
//! `E(c) = mean_t [ L(c + t) - L(c - t) - 2 b(c) t ]^2`,  `t = t_k = (k + 1/2) dt` up to the reach,
//!
//! with `b(c)` the least-squares slope of the difference. `L(c + t)` and `L(c - t)` are both
//! read by the same cubic convolution (Keys 1981, `a = -1/2`) of the profile smoothed by a
//! Gaussian of [`SMOOTH_PX`]: either side is interpolated alike, so the interpolation's own
//! smoothing, which depends on the sub-pixel phase, cancels in the difference. Comparing raw rows
//! with interpolated mirror rows (the running-median estimator, [`super::mirror_centre`]) instead
//! leaves a bias that changes sign with the walls' sub-pixel phase: up to 0.025 um at
//! 0.4 um/px in wave-optics images (`analysis/README.md`, "What adapts per recording").
//!
//! The profile is the row level of the background with sub-count precision ([`level_profile`]):
//! the plain median of an 8-bit row is a whole count (0.7 % of a 140-count level), and that
//! rounding, the same on every recording with the same walls' phase, moved the axis by 0.001-0.003 um.

use crate::experiment::segment::background::separable_factors;
use crate::stats::median::upper_median;

/// Standard deviation, px, of the Gaussian that smooths the log profile before it is compared
/// with its mirror image (damps the aliased fringes of walls narrower than a pixel).
pub const SMOOTH_PX: f64 = 1.0;

/// Spacing, px, of the offsets `t` at which the two sides are compared.
pub const STEP_PX: f64 = 0.25;

/// Rows, beyond each wall, that the comparison reaches (3 px of the walls' fringes and PDMS plus
/// 3 [`SMOOTH_PX`] of the smoothing's reach).
pub const BEYOND_WALL_PX: f64 = 3.0 + 3.0 * SMOOTH_PX;

/// Row levels of a background image with sub-count precision.
///
/// Separable model `I(r, c) = m_r f_c` ([`separable_factors`]): `m_r` the median of row `r`,
/// `f_c` the median over rows of `I(r, c) / m_r` (the illumination along the channel), and the
/// level of row `r` the median over columns of `I(r, c) / f_c`. Dividing by `f_c` collapses a
/// row's values onto its level (the along-channel gradient no longer spreads them), so that their
/// median falls between whole counts where the camera's noise dithered them, and it stays robust
/// to dust and cell remnants.
pub fn level_profile(img: &crate::types::Frame) -> Vec<f64> {
    let w = img.width;
    let (row_median, col_factor) = separable_factors(img);
    let mut buf = vec![0f64; w];
    row_median
        .iter()
        .enumerate()
        .map(|(r, &m)| {
            let mut k = 0;
            for (&v, &f) in img.data[r * w..(r + 1) * w].iter().zip(&col_factor) {
                if f > 0.0 {
                    buf[k] = v as f64 / f as f64;
                    k += 1;
                }
            }
            if k == 0 { m as f64 } else { upper_median(&mut buf[..k]).expect("k > 0") }
        })
        .collect()
}

/// Centre `c` (within +-1 px of `c0`) that minimises `E(c)` (module doc) over offsets up to
/// `reach` px: a grid of 0.05 px, then one of 0.005 px around its best point refined by a
/// parabola. `None` when the profile has a row <= 0 (no logarithm) or is too short for the
/// comparison.
pub fn symmetric_centre(profile: &[f64], c0: f64, reach: f64) -> Option<f64> {
    let n = profile.len();
    if n < 8 || profile.iter().any(|&v| v <= 0.0 || !v.is_finite()) {
        return None;
    }
    let log: Vec<f64> = profile.iter().map(|v| v.ln()).collect();
    let l = gaussian_smooth(&log, SMOOTH_PX);
    let offsets: Vec<f64> = (0..).map(|k| (k as f64 + 0.5) * STEP_PX).take_while(|&t| t <= reach).collect();
    let cost = |c: f64| -> f64 {
        // sums for the least-squares slope b = sum(d t) / sum(t^2) and the residual
        // sum (d - b t)^2 = sum d^2 - b sum(d t)
        let (mut dd, mut dt, mut tt, mut k) = (0.0, 0.0, 0.0, 0usize);
        for &t in &offsets {
            if let (Some(a), Some(b)) = (cubic(&l, c + t), cubic(&l, c - t)) {
                let d = a - b;
                dd += d * d;
                dt += d * t;
                tt += t * t;
                k += 1;
            }
        }
        if k < 4 { f64::MAX } else { (dd - dt * dt / tt) / k as f64 }
    };
    // coarse grid of 0.05 px over +-1 px, then 0.005 px over +-0.05 px around its best point,
    // refined by a parabola through the three lowest
    let (c1, _) = grid_min(&cost, c0, 1.0, 40)?;
    let (c2, costs) = grid_min(&cost, c1, 0.05, 20)?;
    let h = 0.1 / 20.0;
    let best = ((c2 - (c1 - 0.05)) / h).round() as usize;
    let mut c = c2;
    if best > 0 && best < costs.len() - 1 {
        let (a, b, d) = (costs[best - 1], costs[best], costs[best + 1]);
        let den = a - 2.0 * b + d;
        if den > 0.0 {
            c += (0.5 * (a - d) / den).clamp(-0.5, 0.5) * h;
        }
    }
    Some(c)
}

/// The lowest of `cost` on `steps + 1` points evenly spread over `[centre - half, centre + half]`,
/// with every point's cost; `None` when no point has a finite cost.
fn grid_min(cost: &impl Fn(f64) -> f64, centre: f64, half: f64, steps: usize) -> Option<(f64, Vec<f64>)> {
    let h = 2.0 * half / steps as f64;
    let costs: Vec<f64> = (0..=steps).map(|i| cost(centre - half + i as f64 * h)).collect();
    let (best, &low) = costs.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1))?;
    (low < f64::MAX).then_some((centre - half + best as f64 * h, costs))
}

/// Convolution with a normalised Gaussian of standard deviation `sigma` px, truncated at
/// `4 sigma`; the ends are extended by their edge values.
fn gaussian_smooth(v: &[f64], sigma: f64) -> Vec<f64> {
    let r = (4.0 * sigma).ceil() as isize;
    let kernel: Vec<f64> = (-r..=r).map(|x| (-0.5 * (x as f64 / sigma).powi(2)).exp()).collect();
    let norm: f64 = kernel.iter().sum();
    let n = v.len() as isize;
    (0..n)
        .map(|i| (-r..=r).zip(&kernel).map(|(k, w)| w * v[(i + k).clamp(0, n - 1) as usize]).sum::<f64>() / norm)
        .collect()
}

/// Keys' cubic convolution kernel (`a = -1/2`; Keys, IEEE Trans. ASSP 29, 1153, 1981).
fn keys(x: f64) -> f64 {
    let x = x.abs();
    if x <= 1.0 {
        1.5 * x.powi(3) - 2.5 * x * x + 1.0
    } else if x < 2.0 {
        -0.5 * x.powi(3) + 2.5 * x * x - 4.0 * x + 2.0
    } else {
        0.0
    }
}

/// The profile at row position `y` by cubic convolution, `None` outside `[1, n - 2]`.
fn cubic(v: &[f64], y: f64) -> Option<f64> {
    let n = v.len();
    if !(1.0..=(n - 2) as f64).contains(&y) {
        return None;
    }
    let i = (y.floor() as usize).min(n - 3);
    let t = y - i as f64;
    Some(v[i - 1] * keys(t + 1.0) + v[i] * keys(t) + v[i + 1] * keys(1.0 - t) + v[i + 2] * keys(2.0 - t))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cubic convolution reproduces a quadratic exactly (Keys' kernel is third-order accurate).
    #[test]
    fn cubic_convolution_is_exact_on_a_quadratic() {
        let v: Vec<f64> = (0..10).map(|i| 0.3 + 0.2 * i as f64 - 0.05 * (i * i) as f64).collect();
        for y in [1.0, 2.25, 4.5, 7.999] {
            let exact = 0.3 + 0.2 * y - 0.05 * y * y;
            assert!((cubic(&v, y).unwrap() - exact).abs() < 1e-12, "{y}");
        }
        assert!(cubic(&v, 0.5).is_none() && cubic(&v, 8.5).is_none());
    }

    /// A mirror-symmetric profile times a multiplicative ramp: the centre comes out within
    /// 0.002 px of the true one for every sub-pixel phase (the ramp is the fitted line in `ln I`).
    #[test]
    fn centre_of_a_symmetric_profile_under_a_ramp() {
        for k in 0..10 {
            let c = 40.0 + 0.1 * k as f64;
            let p: Vec<f64> = (0..81)
                .map(|r| {
                    let u = (r as f64 - c).abs() - 25.0;
                    let walls = 1.0 - 0.3 * (-0.5 * (u / 1.5).powi(2)).exp() - 0.1 * (0.5 + 0.5 * (u / 0.8).tanh());
                    walls * (1.0 + 0.004 * r as f64)
                })
                .collect();
            let got = symmetric_centre(&p, c.round() + 0.3, 31.0).unwrap();
            assert!((got - c).abs() < 2e-3, "c {c}: {got}");
        }
        assert!(symmetric_centre(&[1.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0], 4.0, 3.0).is_none());
    }

    /// The level of a row is its value over the column factor: a separable image gives its
    /// row factor back to within the column factor's rounding (no whole-count median).
    #[test]
    fn level_profile_recovers_the_row_factor_of_a_separable_image() {
        let (w, h) = (64, 12);
        let rows: Vec<f64> = (0..h).map(|r| 100.0 + 7.3 * r as f64).collect();
        let data: Vec<f32> = (0..w * h).map(|i| (rows[i / w] * (0.9 + 0.2 * (i % w) as f64 / w as f64)) as f32).collect();
        let lv = level_profile(&crate::types::Frame { width: w, height: h, data });
        let scale = lv[0] / rows[0];
        for (a, b) in lv.iter().zip(&rows) {
            assert!((a / b - scale).abs() < 1e-5, "{a} {b}");
        }
    }
}
