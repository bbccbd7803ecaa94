//! Kernel density estimate with MATLAB `ksdensity` semantics (R2017a defaults, bounded support by log transform).
//!
//! The paper (Guckenberger et al., section "Experimental results") estimates the
//! density of the cells' y-positions with MATLAB R2017a
//! `ksdensity(y, 'Support', [-6 6])` and otherwise default settings. This module
//! reproduces that estimator to rounding error (checked to 1e-10 against an
//! independent reference, `scripts/ksdensity_reference.py`, and against GNU
//! Octave's statistics package; fixture `analysis/tests/fixtures/ksdensity_reference.txt`):
//!
//! 1. **Transform.** With support `(L, U)` each value is mapped to the real line,
//!    $t = \log(y - L) - \log(U - y)$; without support $t = y$.
//! 2. **Bandwidth** (normal reference rule with a robust scale, Bowman & Azzalini
//!    1997), computed on $t$: $\sigma = \mathrm{MAD}/0.6745$ with
//!    $\mathrm{MAD} = \mathrm{median}|t_i - \mathrm{median}(t)|$, and
//!    $h = \sigma\,(4/(3n))^{1/5}$. If $\sigma = 0$ MATLAB uses the range
//!    $\max t - \min t$ instead, and $h = 1$ if that is zero too.
//! 3. **Evaluation points** (MATLAB's default grid): `n_points` (MATLAB: 100)
//!    equally spaced in **y**, from $y(\min t - 3h)$ to $y(\max t + 3h)$, where
//!    $y(t) = (U e^t + L)/(e^t + 1)$ is the inverse transform. For a bounded
//!    support the grid therefore lies strictly inside `(L, U)` and covers the
//!    data plus three bandwidths (in t) on each side.
//! 4. **Estimate** in t with a Gaussian kernel, mapped back with the Jacobian
//!    $dt/dy = (U - L)/((y - L)(U - y))$:
//!    $$\hat f(y) = \frac{1}{n h}\sum_i \varphi\!\left(\frac{t(y) - t_i}{h}\right)\frac{U - L}{(y - L)(U - y)}.$$
//!    MATLAB sums over all data when `n * n_points <= 30000`; above that it
//!    sums, for each evaluation point, only over the sorted data from the first
//!    $t_i \ge t(y) - 4h$ to the first $t_i > t(y) + 4h$ (inclusive, MATLAB's
//!    kernel cutoff of 4 bandwidths). We do the same, so large groups
//!    (n > 300 at 100 points) also match MATLAB.
//!
//! Units: y and the support in um give a density in 1/um; the bandwidth is in
//! transformed units (dimensionless) when a support is given, as MATLAB reports it.

use crate::stats::median::median;
use std::f64::consts::PI;

/// MATLAB's default number of evaluation points.
pub const DEFAULT_POINTS: usize = 100;

/// Above this many kernel evaluations (`n * n_points`) MATLAB switches to the truncated sum.
const MATLAB_BLOCK_SIZE: usize = 30_000;

/// MATLAB's cutoff of the normal kernel in the truncated sum, in bandwidths.
const NORMAL_CUTOFF: f64 = 4.0;

/// Width of the default grid beyond the data, in bandwidths (MATLAB: `min(cutoff, 3)`).
const GRID_MARGIN: f64 = 3.0;

/// A density evaluated on a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Kde {
    /// Evaluation points (units of the sample, e.g. um), increasing.
    pub y: Vec<f64>,
    /// Probability density at `y` (1 / units of the sample).
    pub density: Vec<f64>,
    /// Kernel bandwidth, in the transformed variable t when a support is given (as MATLAB's third output).
    pub bandwidth: f64,
}

/// Why a density could not be estimated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KdeError {
    #[error("density estimate of an empty sample")]
    Empty,
    #[error("sample value {index} is {value}, not a finite number")]
    NotFinite { index: usize, value: f64 },
    #[error("sample value {index} = {value} lies outside the open support ({lower}, {upper})")]
    OutsideSupport {
        index: usize,
        value: f64,
        lower: f64,
        upper: f64,
    },
    #[error("support ({lower}, {upper}) is not a finite interval with lower < upper")]
    BadSupport { lower: f64, upper: f64 },
    #[error("evaluation point {index} is {value}, not a finite number")]
    BadPoint { index: usize, value: f64 },
    #[error("a density needs at least one evaluation point")]
    NoPoints,
}

/// MATLAB `[f, xi, bw] = ksdensity(sample, 'Support', [L U], 'NumPoints', n_points)`
/// (`support = None`: MATLAB's default unbounded support).
///
/// Errors: empty sample, NaN or infinite values, a value on or outside the
/// support (MATLAB requires the data strictly inside), a bad support, `n_points = 0`.
pub fn ksdensity(
    sample: &[f64],
    support: Option<(f64, f64)>,
    n_points: usize,
) -> Result<Kde, KdeError> {
    if n_points == 0 {
        return Err(KdeError::NoPoints);
    }
    let tr = Transform::new(support)?;
    let t = transformed_sample(sample, &tr)?;
    let h = default_bandwidth(&t);
    let (tmin, tmax) = t
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let lo = tr.inverse(tmin - GRID_MARGIN * h);
    let hi = tr.inverse(tmax + GRID_MARGIN * h);
    let y = linspace(lo, hi, n_points);
    let density = evaluate(&t, h, &tr, &y);
    Ok(Kde {
        y,
        density,
        bandwidth: h,
    })
}

/// MATLAB `ksdensity(sample, points, 'Support', [L U])`: the same estimate at given points.
/// Points on or outside the support get density 0, as in MATLAB.
pub fn ksdensity_at(
    sample: &[f64],
    support: Option<(f64, f64)>,
    points: &[f64],
) -> Result<Kde, KdeError> {
    if points.is_empty() {
        return Err(KdeError::NoPoints);
    }
    if let Some((index, &value)) = points.iter().enumerate().find(|(_, v)| v.is_nan()) {
        return Err(KdeError::BadPoint { index, value });
    }
    let tr = Transform::new(support)?;
    let t = transformed_sample(sample, &tr)?;
    let h = default_bandwidth(&t);
    let density = evaluate(&t, h, &tr, points);
    Ok(Kde {
        y: points.to_vec(),
        density,
        bandwidth: h,
    })
}

/// MATLAB's default bandwidth of (already transformed) data:
/// $h = \sigma (4/(3n))^{1/5}$ with $\sigma = \mathrm{median}|t - \mathrm{median}(t)| / 0.6745$,
/// falling back to $\sigma = \max t - \min t$ when the MAD is 0, and to $h = 1$ when that is 0 too.
/// `t` must be non-empty and finite.
pub fn default_bandwidth(t: &[f64]) -> f64 {
    let n = t.len() as f64;
    let med = median(&mut t.to_vec()).expect("t is non-empty");
    let mut dev: Vec<f64> = t.iter().map(|v| (v - med).abs()).collect();
    let mut sigma = median(&mut dev).expect("t is non-empty") / 0.6745;
    if sigma <= 0.0 {
        let (a, b) = t
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        sigma = b - a;
    }
    if sigma > 0.0 {
        sigma * (4.0 / (3.0 * n)).powf(0.2)
    } else {
        1.0
    }
}

/// MATLAB `linspace(a, b, n)`: `a + i (b - a)/(n - 1)`, last point exactly `b` (n = 1 gives `[b]`).
pub fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    if n == 1 {
        return vec![b];
    }
    let step = (b - a) / (n - 1) as f64;
    let mut v: Vec<f64> = (0..n).map(|i| a + i as f64 * step).collect();
    v[n - 1] = b;
    v
}

/// The map of the support onto the real line.
#[derive(Debug, Clone, Copy)]
enum Transform {
    Identity,
    /// $t = \log(y - L) - \log(U - y)$ on `(L, U)`.
    Logit {
        lower: f64,
        upper: f64,
    },
}

impl Transform {
    fn new(support: Option<(f64, f64)>) -> Result<Self, KdeError> {
        match support {
            None => Ok(Transform::Identity),
            Some((lower, upper)) => {
                if lower.is_finite() && upper.is_finite() && lower < upper {
                    Ok(Transform::Logit { lower, upper })
                } else {
                    Err(KdeError::BadSupport { lower, upper })
                }
            }
        }
    }

    /// `true` if the density can be non-zero at `y`.
    fn contains(&self, y: f64) -> bool {
        match *self {
            Transform::Identity => y.is_finite(),
            Transform::Logit { lower, upper } => y > lower && y < upper,
        }
    }

    fn forward(&self, y: f64) -> f64 {
        match *self {
            Transform::Identity => y,
            Transform::Logit { lower, upper } => (y - lower).ln() - (upper - y).ln(),
        }
    }

    /// Inverse map; the two algebraically equal forms avoid overflow of `exp` for large |t|.
    fn inverse(&self, t: f64) -> f64 {
        match *self {
            Transform::Identity => t,
            Transform::Logit { lower, upper } => {
                if t < 0.0 {
                    let e = t.exp();
                    (upper * e + lower) / (e + 1.0)
                } else {
                    let e = (-t).exp();
                    (upper + lower * e) / (1.0 + e)
                }
            }
        }
    }

    /// $dt/dy$, the Jacobian that maps a density in t back to y.
    fn jacobian(&self, y: f64) -> f64 {
        match *self {
            Transform::Identity => 1.0,
            Transform::Logit { lower, upper } => (upper - lower) / ((y - lower) * (upper - y)),
        }
    }
}

/// Check the sample and map it to t.
fn transformed_sample(sample: &[f64], tr: &Transform) -> Result<Vec<f64>, KdeError> {
    if sample.is_empty() {
        return Err(KdeError::Empty);
    }
    for (index, &value) in sample.iter().enumerate() {
        if !value.is_finite() {
            return Err(KdeError::NotFinite { index, value });
        }
        if let Transform::Logit { lower, upper } = *tr {
            if value <= lower || value >= upper {
                return Err(KdeError::OutsideSupport {
                    index,
                    value,
                    lower,
                    upper,
                });
            }
        }
    }
    Ok(sample.iter().map(|&v| tr.forward(v)).collect())
}

/// Standard normal density.
#[inline]
fn phi(z: f64) -> f64 {
    (-0.5 * z * z).exp() / (2.0 * PI).sqrt()
}

/// The estimate at `points` (density 0 outside the support), full or truncated sum as MATLAB chooses.
fn evaluate(t: &[f64], h: f64, tr: &Transform, points: &[f64]) -> Vec<f64> {
    let n = t.len();
    let w = 1.0 / n as f64;
    let truncated = n * points.len() > MATLAB_BLOCK_SIZE;
    let mut sorted = t.to_vec();
    sorted.sort_by(f64::total_cmp);
    points
        .iter()
        .map(|&y| {
            if !tr.contains(y) {
                return 0.0;
            }
            let ty = tr.forward(y);
            let data: &[f64] = if truncated {
                window(&sorted, ty, NORMAL_CUTOFF * h)
            } else {
                t
            };
            let s: f64 = data.iter().map(|&ti| w * phi((ty - ti) / h)).sum();
            s * tr.jacobian(y) / h
        })
        .collect()
}

/// MATLAB's neighbourhood of an evaluation point `x` in the truncated sum, on sorted data:
/// from the first value `>= x - half` (or the last value) to the first value `> x + half`
/// (or the last value), inclusive.
fn window(sorted: &[f64], x: f64, half: f64) -> &[f64] {
    let last = sorted.len() - 1;
    let start = sorted.partition_point(|&v| v < x - half).min(last);
    let end = sorted
        .partition_point(|&v| v <= x + half)
        .min(last)
        .max(start);
    &sorted[start..=end]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linspace_ends_exactly() {
        let v = linspace(-1.0, 2.0, 4);
        assert_eq!(v, vec![-1.0, 0.0, 1.0, 2.0]);
        assert_eq!(linspace(0.0, 5.0, 1), vec![5.0]);
    }

    #[test]
    fn inverse_undoes_forward() {
        let tr = Transform::Logit {
            lower: -6.0,
            upper: 6.0,
        };
        for y in [-5.999, -3.0, 0.0, 0.1, 4.5, 5.999] {
            assert!((tr.inverse(tr.forward(y)) - y).abs() < 1e-12);
        }
    }

    #[test]
    fn window_includes_first_point_beyond_the_cutoff() {
        let s = [0.0, 1.0, 2.0, 3.0, 10.0];
        assert_eq!(window(&s, 1.5, 1.0), &[1.0, 2.0, 3.0]);
        assert_eq!(window(&s, 0.0, 0.5), &[0.0, 1.0]);
        assert_eq!(window(&s, 20.0, 1.0), &[10.0]);
    }
}
