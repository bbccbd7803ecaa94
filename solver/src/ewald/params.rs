//! Ewald parameters from an error target: splitting parameter, real-space cutoff, grid size and Gaussian support, with the error estimates they rest on.
//!
//! Error model (relative to the size of the sums; each part decays like a Gaussian in its
//! own "number of standard deviations" `s`, Lindbo & Tornberg, J. Comput. Phys. 229, 8994 (2010),
//! sections 4-5, and 230, 8744 (2011), section 4):
//! - real space, truncated at `r_cut`: `~ exp(-(xi r_cut)^2)`, so `xi r_cut = s_r`;
//! - Fourier space, truncated at the grid's Nyquist wavenumber `k_inf = pi M_d / L_d`:
//!   `~ exp(-k_inf^2 / (4 xi^2))`, so `M_d >= 2 s_k xi L_d / pi`;
//! - Gaussian gridding with `P` points per direction: `~ exp(-pi P / 2)`.
//!
//! Measured prefactors (300 random sources in a 6 x 3 x 2.5 box, one part varied at a time with
//! the others converged; the Fourier truncation with the window capped at the grid period; relative rms error, the max error over the max value is smaller):
//! real space `~0.3 exp(-s_r^2)` (Stokeslet), `~0.7 exp(-s_r^2)` (stresslet); Fourier truncation
//! `~0.35 exp(-s_k^2)`; window `~2..6 exp(-pi P/2)` on a fine grid, `~10 exp(-pi P/2)` on the grid used. Each part is made `<= tol/3`:
//! `s_r^2 = ln(1/tol) + 1.0`, `s_k^2 = ln(1/tol) + 0.5`, `P = ceil(2 (ln(1/tol) + 3.0) / pi)`.
//! The parts do not simply add: on the grid of the truncation estimate alone, the Gaussian shape
//! comes out at `eta ~ 0.7`, and the window's truncation error (broadband) is amplified near the
//! Nyquist wavenumber by the deconvolution `exp(eta k^2/(4 xi^2))`; the total then reached `~tol`.
//! A grid 1.2 times finer (`eta ~ 0.5`) brought it to `~tol/8` at 1e-3, 1e-5 and 1e-7, so the grid
//! uses `1.2 s_k`. The ignored test `error_parts_calibration` in `tests/ewald_accuracy.rs` reruns the study.
//! The test `ewald_accuracy` checks the total against the direct sums at 1e-3 ... 1e-7. `xi` is then the value that minimises a simple cost model of one
//! stresslet application (the more expensive one): real-space pairs
//! `N^2 (4 pi / 3) r_cut^3 / V` at ~40 ns, grid work `9 N P^3` at ~1 ns, and 9 FFTs of
//! `M^3 log2 M^3` at ~1.5 ns (measured orders of magnitude on the development machine).

use super::{Coincident, EwaldError, EwaldParams};

/// Offset added to `ln(1/tol)` for `(xi r_cut)^2`.
const REAL_OFFSET: f64 = 1.0;
/// Offset added to `ln(1/tol)` for `(k_inf / 2 xi)^2`.
const FOURIER_OFFSET: f64 = 0.5;
/// Grid refinement beyond the Fourier truncation estimate (see the module documentation).
const GRID_REFINEMENT: f64 = 1.2;
/// Offset added to `ln(1/tol)` in `P = 2 (ln(1/tol) + c) / pi`.
const WINDOW_OFFSET: f64 = 3.0;

/// Largest grid accepted (points), ~ 1.3 GB of complex values for the stresslet.
const MAX_GRID: usize = 1 << 24;

/// Smallest `n >= m` of the form `2^a 3^b 5^c` (fast sizes for rustfft).
pub fn fft_size(m: usize) -> usize {
    let mut n = m.max(1);
    loop {
        let mut k = n;
        for p in [2, 3, 5] {
            while k.is_multiple_of(p) {
                k /= p;
            }
        }
        if k == 1 {
            return n;
        }
        n += 1;
    }
}

/// `(s_r, s_k, P)` for a relative error target `tol`.
pub fn accuracy_numbers(tol: f64) -> (f64, f64, usize) {
    let l = (1.0 / tol).ln();
    let s_r = (l + REAL_OFFSET).sqrt();
    let s_k = GRID_REFINEMENT * (l + FOURIER_OFFSET).sqrt();
    let p = (2.0 * (l + WINDOW_OFFSET) / std::f64::consts::PI).ceil() as usize;
    (s_r, s_k, p.max(4))
}

/// Grid points per direction for splitting `xi`, Fourier accuracy `s_k` and window `p`: a common
/// spacing `h = min(pi / (2 s_k xi), L_min / (p + 2))` (Nyquist `pi/h >= 2 s_k xi`, and the window of
/// `p h` stays shorter than the smallest side, so a point's window never meets its own periodic image),
/// `M_d = ceil(L_d / h)` rounded up to a fast FFT size.
pub fn grid_for(box_len: [f64; 3], xi: f64, s_k: f64, p: usize) -> [usize; 3] {
    let lmin = box_len.iter().cloned().fold(f64::INFINITY, f64::min);
    let h = (std::f64::consts::PI / (2.0 * s_k * xi)).min(lmin / (p as f64 + 2.0));
    box_len.map(|l| fft_size(((l / h).ceil() as usize).max(4)))
}

/// Model cost (s) of one stresslet application with `n` sources and targets.
fn model_cost(box_len: [f64; 3], n: usize, xi: f64, s_r: f64, s_k: f64, p: usize) -> f64 {
    let v = box_len[0] * box_len[1] * box_len[2];
    let r_cut = s_r / xi;
    let pairs = (n as f64).powi(2) * 4.0 / 3.0 * std::f64::consts::PI * r_cut.powi(3) / v;
    let m = grid_for(box_len, xi, s_k, p);
    let mt = (m[0] * m[1] * m[2]) as f64;
    40e-9 * pairs + 1e-9 * 9.0 * n as f64 * (p as f64).powi(3) + 1.5e-9 * 9.0 * mt * mt.log2()
}

/// How the real-space pairs of a sum grow with the cutoff `r`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairModel {
    /// Sources spread evenly through the box: `N_t N_s (4 pi/3) r^3 / V` pairs.
    Uniform,
    /// Sources on a surface of area `area_um2` that the targets lie on or near (a cell's membrane
    /// seen from its own vertices, a wall seen from a cell beside it): `N_t N_s min(1, pi r^2 / area)` pairs.
    Surface { area_um2: f64 },
}

/// The shape of one sum for [`EwaldParams::for_sums`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SumShape {
    /// Points spread to or gathered from the grid (targets plus sources, without precomputed spreading).
    pub grid_points: usize,
    /// Components spread per point (3 Stokeslet, 6 stresslet) and complex FFTs (4 and 5).
    pub components: usize,
    pub ffts: usize,
    /// Targets and sources of the real-space pairs and how their count grows.
    pub pair_targets: usize,
    pub pair_sources: usize,
    pub pairs: PairModel,
    /// Cost of one real-space pair (ns): ~25 for a plain sum, less when the pairs are frozen
    /// into a matrix that several applications share.
    pub pair_ns: f64,
}

impl SumShape {
    fn pairs(&self, box_len: [f64; 3], r: f64) -> f64 {
        let n = self.pair_targets as f64 * self.pair_sources as f64;
        match self.pairs {
            PairModel::Uniform => n * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) / (box_len[0] * box_len[1] * box_len[2]),
            PairModel::Surface { area_um2 } => n * (std::f64::consts::PI * r * r / area_um2).min(1.0),
        }
    }
}

/// Model cost (s) of the sums `sums` at splitting `xi`: [`SumShape::pair_ns`] per real-space pair (~25 ns), 1 ns per
/// window point and component (spreading, gathering), 1.5 ns per `M^3 log2 M^3` and FFT (the
/// orders of magnitude measured by `rbc-bench channel-cost` on the development machine).
pub fn sums_cost(box_len: [f64; 3], sums: &[SumShape], xi: f64, s_r: f64, s_k: f64, p: usize) -> f64 {
    let r_cut = s_r / xi;
    let m = grid_for(box_len, xi, s_k, p);
    let mt = (m[0] * m[1] * m[2]) as f64;
    sums.iter()
        .map(|s| 1e-9 * s.pair_ns * s.pairs(box_len, r_cut) + 1e-9 * (s.components * s.grid_points) as f64 * (p as f64).powi(3) + 1.5e-9 * s.ffts as f64 * mt * mt.log2())
        .sum()
}

impl EwaldParams {
    /// Parameters meeting the relative error `tol` (e.g. 5e-5, the paper's) for about `n_sources`
    /// sources in a box of sides `box_len` (um), with `xi` minimising the model cost.
    pub fn for_tolerance(box_len: [f64; 3], n_sources: usize, tol: f64) -> Result<Self, EwaldError> {
        Self::cheapest(box_len, tol, |xi, s_r, s_k, p| model_cost(box_len, n_sources.max(1), xi, s_r, s_k, p))
    }

    /// Parameters meeting the relative error `tol` with `xi` minimising [`sums_cost`] of the
    /// sums one application does (clustered points: the real-space pairs of a cell's membrane grow
    /// like `r^2`, not like the `r^3` of evenly spread points).
    pub fn for_sums(box_len: [f64; 3], sums: &[SumShape], tol: f64) -> Result<Self, EwaldError> {
        Self::cheapest(box_len, tol, |xi, s_r, s_k, p| sums_cost(box_len, sums, xi, s_r, s_k, p))
    }

    /// The parameters meeting `tol` whose splitting `xi` minimises `cost(xi, s_r, s_k, p)`:
    /// r_cut scanned geometrically from `min(box_len) / 40` to `2 max(box_len)` (201 values),
    /// grids above [`MAX_GRID`] points skipped.
    fn cheapest(box_len: [f64; 3], tol: f64, cost: impl Fn(f64, f64, f64, usize) -> f64) -> Result<Self, EwaldError> {
        super::check_box(box_len)?;
        if !(1e-14..0.1).contains(&tol) {
            return Err(EwaldError::InvalidParameter { name: "tol", value: tol, reason: "must lie in [1e-14, 0.1)" });
        }
        let (s_r, s_k, p) = accuracy_numbers(tol);
        let lmax = box_len.iter().cloned().fold(0.0, f64::max);
        let lmin = box_len.iter().cloned().fold(f64::INFINITY, f64::min);
        let mut best: Option<(f64, f64)> = None;
        let (lo, hi) = (lmin / 40.0, 2.0 * lmax);
        for i in 0..=200 {
            let r_cut = lo * (hi / lo).powf(i as f64 / 200.0);
            let xi = s_r / r_cut;
            let m = grid_for(box_len, xi, s_k, p);
            if m[0] * m[1] * m[2] > MAX_GRID {
                continue;
            }
            let c = cost(xi, s_r, s_k, p);
            if best.is_none_or(|(_, b)| c < b) {
                best = Some((xi, c));
            }
        }
        let (xi, _) = best.ok_or(EwaldError::InvalidParameter { name: "tol", value: tol, reason: "needs a grid larger than 2^24 points" })?;
        Ok(Self { xi, r_cut: s_r / xi, grid: grid_for(box_len, xi, s_k, p), support: p, coincident: Coincident::Regular })
    }

    /// Parameters for a given splitting `xi` (1/um) and tolerance (cutoff, grid, support from the same estimates).
    pub fn with_xi(box_len: [f64; 3], xi: f64, tol: f64) -> Result<Self, EwaldError> {
        super::check_box(box_len)?;
        if !(xi > 0.0 && xi.is_finite()) {
            return Err(EwaldError::InvalidParameter { name: "xi", value: xi, reason: "must be positive" });
        }
        if !(1e-14..0.1).contains(&tol) {
            return Err(EwaldError::InvalidParameter { name: "tol", value: tol, reason: "must lie in [1e-14, 0.1)" });
        }
        let (s_r, s_k, p) = accuracy_numbers(tol);
        Ok(Self { xi, r_cut: s_r / xi, grid: grid_for(box_len, xi, s_k, p), support: p, coincident: Coincident::Regular })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `for_sums` keeps the accuracy relations of `for_tolerance` (`xi r_cut = s_r`, the grid of
    /// `grid_for`), returns the minimum of its cost model, and follows the pair cost: a dearer
    /// real-space pair never gives a longer cutoff.
    #[test]
    fn for_sums_keeps_accuracy_relations_and_follows_the_pair_cost() {
        let box_len = [42.7, 16.0, 14.0];
        let tol = 1e-4;
        let (s_r, s_k, p) = accuracy_numbers(tol);
        let shape = |pair_ns| SumShape { grid_points: 4000, components: 3, ffts: 4, pair_targets: 258, pair_sources: 3584, pairs: PairModel::Surface { area_um2: 135.0 }, pair_ns };
        let cheap = EwaldParams::for_sums(box_len, &[shape(8.0)], tol).unwrap();
        let dear = EwaldParams::for_sums(box_len, &[shape(25.0)], tol).unwrap();
        for q in [cheap, dear] {
            assert!((q.xi * q.r_cut - s_r).abs() < 1e-12 * s_r);
            assert_eq!(q.grid, grid_for(box_len, q.xi, s_k, p));
            assert_eq!(q.support, p);
        }
        assert!(cheap.r_cut >= dear.r_cut, "{} vs {}", cheap.r_cut, dear.r_cut);
        // the chosen cutoff is the scan's minimum of the model
        let c = |q: &EwaldParams, ns| sums_cost(box_len, &[shape(ns)], q.xi, s_r, s_k, p);
        assert!(c(&dear, 25.0) <= c(&cheap, 25.0) && c(&cheap, 8.0) <= c(&dear, 8.0));
        assert!(EwaldParams::for_sums(box_len, &[shape(8.0)], 0.5).is_err());
    }
}
