//! Fourier-space part of the Ewald sums by the spectral Ewald method (Lindbo & Tornberg, J. Comput. Phys. 229, 8994 (2010); 230, 8744 (2011)): Gaussian spreading to a uniform grid, FFT, scaling, inverse FFT, Gaussian gathering.
//!
//! The Hasimoto factor `exp(-k^2/(4 xi^2))` is split as
//! `exp(-eta k^2/(8 xi^2)) * exp(-(1 - eta) k^2/(4 xi^2)) * exp(-eta k^2/(8 xi^2))`: the outer
//! factors are the transforms of the Gaussian `g(r) = (2 xi^2/(pi eta))^(3/2) exp(-2 xi^2 r^2/eta)`
//! used to spread the sources to the grid and to gather the result at the targets, the middle one
//! is applied on the grid. With `F(k) ~ h^3 DFT[H]` (trapezoid rule, spectrally accurate for the
//! periodic smooth `H = sum_j g(. - y_j) f_j`):
//!
//! ```text
//! u(x_i) = h^3 sum_m g(x_i - x_m) (1/V) sum_k M(k) F(k) exp(i k . x_m)
//! ```
//!
//! with `M(k) = G^F(k) exp(eta k^2/(4 xi^2))` (or the stresslet's), `k = 0` left out.
//! `g` is truncated to `P` grid points per direction around each point: with the shape
//! parameter `m = 0.95 sqrt(pi P)`, half-width `w = P h / 2` and `eta = (2 w xi / m)^2`, the
//! truncation (`erfc(m/sqrt 2)`-like) and the grid quadrature (`exp(-pi^2 P^2/(2 m^2))`) errors
//! both decay like `exp(-pi P / 2)` (Lindbo & Tornberg 2011, section 4).

use nalgebra::Vector3;
use rayon::prelude::*;
use rustfft::num_complex::Complex;
use rustfft::FftDirection;

use super::fft3::Fft3;
use super::split::{fourier_scalar, project, stresslet_bracket};

/// Ratio `m / sqrt(pi P)` of the Gaussian shape parameter (Lindbo & Tornberg 2011).
pub const SHAPE_FACTOR: f64 = 0.95;

/// The grid, the Gaussian window and the planned FFTs.
#[derive(Debug)]
pub struct SpectralGrid {
    m: [usize; 3],
    h: [f64; 3],
    /// Window points per direction (>= the requested P; more along directions with a finer grid).
    support: [usize; 3],
    xi: f64,
    eta: f64,
    fft: Fft3,
    /// Wavenumbers (1/um) of the FFT indices per direction.
    kvec: [Vec<f64>; 3],
    /// `8 pi H(k) / k^2 * exp(eta k^2 / (4 xi^2))` (Hasimoto's factor with the Gaussians deconvolved) at every grid wavevector, 0 at `k = 0`.
    kscale: Vec<f64>,
}

/// The spreading of fixed sources as a sparse map from nodal values to grid points, `C` weights
/// per entry ([`SpectralGrid::basis_spread`]: 1, the Stokeslet's; [`SpectralGrid::stresslet_basis_spread`]: 3, one per normal component).
#[derive(Debug, Clone)]
pub struct BasisSpread<const C: usize = 1> {
    /// Basis node `v` spreads to the grid points `nodes[v].0[j]` with weights `nodes[v].1[j]`
    /// (a point may appear more than once for a node whose sources span nearly a grid period).
    /// One pair of vectors per node, as built: concatenating them would copy ~20 MB per solve into
    /// fresh pages (measured: 4x the page faults of the whole run). The weights are computed in
    /// double precision and stored in single (6e-8 relative, three orders of magnitude below the
    /// Ewald tolerance): the spreading inside GMRES is bound by reading them.
    nodes: Vec<(Vec<u32>, Vec<[f32; C]>)>,
    grid_len: usize,
}

/// The stresslet's spreading of fixed sources: per entry, the weights of the three normal components ([`SpectralGrid::stresslet_basis_spread`]).
pub type StressletSpread = BasisSpread<3>;

impl<const C: usize> BasisSpread<C> {
    /// Stored (grid point, weights) entries.
    pub fn n_entries(&self) -> usize {
        self.nodes.iter().map(|(i, _)| i.len()).sum()
    }

    /// Basis nodes (nodal values expected by the sums).
    pub fn n_basis(&self) -> usize {
        self.nodes.len()
    }

    /// Heap memory of the map (bytes).
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<(Vec<u32>, Vec<[f32; C]>)>() + self.n_entries() * (std::mem::size_of::<u32>() + std::mem::size_of::<[f32; C]>())
    }
}

/// Largest window (points per direction); `P = 32` would be a tolerance of ~1e-20.
pub const MAX_SUPPORT: usize = 40;

/// Window of one point: wrapped grid indices and 1D Gaussian factors per direction, and whether
/// the z indices are one contiguous run (no wrap), which lets the innermost loop run over a slice.
struct Window {
    idx: [[usize; MAX_SUPPORT]; 3],
    w: [[f64; MAX_SUPPORT]; 3],
    z_contiguous: bool,
}

impl SpectralGrid {
    /// `m` grid points per direction, window of `p` points (along the coarsest direction), splitting `xi` (1/um).
    pub fn new(box_len: [f64; 3], m: [usize; 3], p: usize, xi: f64) -> Self {
        let h = [box_len[0] / m[0] as f64, box_len[1] / m[1] as f64, box_len[2] / m[2] as f64];
        let hmax = h.iter().cloned().fold(0.0, f64::max);
        let half_width = p as f64 * hmax / 2.0;
        let shape = SHAPE_FACTOR * (std::f64::consts::PI * p as f64).sqrt();
        let eta = (2.0 * half_width * xi / shape).powi(2);
        let support = [0, 1, 2].map(|d| ((2.0 * half_width / h[d]).round() as usize).max(p));
        let kvec = [0, 1, 2].map(|d| {
            (0..m[d])
                .map(|i| {
                    let n = if i <= m[d] / 2 { i as i64 } else { i as i64 - m[d] as i64 };
                    2.0 * std::f64::consts::PI * n as f64 / box_len[d]
                })
                .collect::<Vec<f64>>()
        });
        let q = eta / (4.0 * xi * xi);
        let mut kscale = vec![0.0; m[0] * m[1] * m[2]];
        kscale.par_chunks_mut(m[1] * m[2]).enumerate().for_each(|(x, plane)| {
            for y in 0..m[1] {
                for z in 0..m[2] {
                    let k2 = kvec[0][x].powi(2) + kvec[1][y].powi(2) + kvec[2][z].powi(2);
                    if k2 > 0.0 {
                        plane[y * m[2] + z] = fourier_scalar(xi, k2) * (q * k2).exp();
                    }
                }
            }
        });
        Self { m, h, support, xi, eta, fft: Fft3::new(m), kvec, kscale }
    }

    /// Whether every window is shorter than its grid period (else a point would see its own image) and at most [`MAX_SUPPORT`] points.
    pub fn window_fits(&self) -> bool {
        (0..3).all(|d| self.support[d] < self.m[d] && self.support[d] <= MAX_SUPPORT)
    }

    pub fn eta(&self) -> f64 {
        self.eta
    }

    pub fn support(&self) -> [usize; 3] {
        self.support
    }

    /// The 1D window factors `exp(-alpha (x_i - p_d)^2)` along direction `d` into `w` (`support[d]` of them);
    /// returns the unwrapped grid index `i` of the first.
    fn factors(&self, p: &Vector3<f64>, d: usize, w: &mut [f64]) -> i64 {
        let alpha = 2.0 * self.xi * self.xi / self.eta;
        let s = (p[d] / self.h[d] - self.support[d] as f64 / 2.0).ceil() as i64;
        for (q, w) in w[..self.support[d]].iter_mut().enumerate() {
            let dx = (s + q as i64) as f64 * self.h[d] - p[d];
            *w = (-alpha * dx * dx).exp();
        }
        s
    }

    fn window(&self, p: &Vector3<f64>) -> Window {
        let mut win = Window { idx: [[0; MAX_SUPPORT]; 3], w: [[0.0; MAX_SUPPORT]; 3], z_contiguous: false };
        for d in 0..3 {
            let pd = self.support[d];
            let m = self.m[d] as i64;
            let s = self.factors(p, d, &mut win.w[d]);
            for q in 0..pd {
                win.idx[d][q] = (s + q as i64).rem_euclid(m) as usize;
            }
            if d == 2 {
                win.z_contiguous = win.idx[2][0] + pd <= self.m[2] && win.idx[2][pd - 1] == win.idx[2][0] + pd - 1;
            }
        }
        win
    }

    /// `H_c(x_m) = sum_j exp(-alpha |x_m - y_j|^2) v_j[c]` (no normalisation), interleaved: `grid[C m + c]`.
    ///
    /// Interleaving the components makes the innermost loop one contiguous run of `C P` values per
    /// `(x, y)` grid line (vectorisable), instead of `C` runs of `P`.
    fn spread<const C: usize>(&self, points: &[Vector3<f64>], values: &[[f64; C]]) -> Vec<f64> {
        let n = self.fft.len();
        let [_, my, mz] = self.m;
        let threads = rayon::current_num_threads().max(1);
        let chunk = points.len().div_ceil(threads).max(1);
        let [px, py, pz] = self.support;
        let add = |mut grid: Vec<f64>, (pts, vals): (&[Vector3<f64>], &[[f64; C]])| {
            let mut wzv = [0.0f64; MAX_SUPPORT * 6];
            for (p, v) in pts.iter().zip(vals) {
                let win = self.window(p);
                for q in 0..pz {
                    for k in 0..C {
                        wzv[q * C + k] = win.w[2][q] * v[k];
                    }
                }
                let run = &wzv[..pz * C];
                for (&a, &gx) in win.idx[0][..px].iter().zip(&win.w[0][..px]) {
                    for (&b, &gy) in win.idx[1][..py].iter().zip(&win.w[1][..py]) {
                        let base = (a * my + b) * mz;
                        let gxy = gx * gy;
                        if win.z_contiguous {
                            let z0 = (base + win.idx[2][0]) * C;
                            for (g, &w) in grid[z0..z0 + pz * C].iter_mut().zip(run) {
                                *g = gxy.mul_add(w, *g);
                            }
                        } else {
                            for q in 0..pz {
                                let z0 = (base + win.idx[2][q]) * C;
                                for k in 0..C {
                                    grid[z0 + k] = gxy.mul_add(run[q * C + k], grid[z0 + k]);
                                }
                            }
                        }
                    }
                }
            }
            grid
        };
        points
            .par_chunks(chunk)
            .zip(values.par_chunks(chunk))
            .fold(|| vec![0.0; C * n], add)
            .reduce(|| vec![0.0; C * n], |mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            })
    }

    /// `out_i += scale sum_m exp(-alpha |x_i - x_m|^2) U_c(x_m)` from an interleaved 3-component real grid.
    fn gather(&self, grid: &[f64], targets: &[Vector3<f64>], scale: f64, out: &mut [Vector3<f64>]) {
        let [_, my, mz] = self.m;
        let [px, py, pz] = self.support;
        out.par_iter_mut().with_min_len(16).zip(targets.par_iter()).for_each(|(o, p)| {
            let win = self.window(p);
            // acc[3 q + c] = sum over the (x, y) window of gx gy U_c at the q-th z point.
            let mut acc = [0.0f64; MAX_SUPPORT * 3];
            let acc_run = &mut acc[..pz * 3];
            for (&a, &gx) in win.idx[0][..px].iter().zip(&win.w[0][..px]) {
                for (&b, &gy) in win.idx[1][..py].iter().zip(&win.w[1][..py]) {
                    let base = (a * my + b) * mz;
                    let gxy = gx * gy;
                    if win.z_contiguous {
                        let z0 = (base + win.idx[2][0]) * 3;
                        for (s, &u) in acc_run.iter_mut().zip(&grid[z0..z0 + pz * 3]) {
                            *s = gxy.mul_add(u, *s);
                        }
                    } else {
                        for q in 0..pz {
                            let z0 = (base + win.idx[2][q]) * 3;
                            for c in 0..3 {
                                acc_run[q * 3 + c] = gxy.mul_add(grid[z0 + c], acc_run[q * 3 + c]);
                            }
                        }
                    }
                }
            }
            let mut u = [0.0f64; 3];
            for q in 0..pz {
                for c in 0..3 {
                    u[c] = win.w[2][q].mul_add(acc_run[q * 3 + c], u[c]);
                }
            }
            *o += Vector3::new(u[0], u[1], u[2]) * scale;
        });
    }

    /// Transform the interleaved component grids, multiply by `mult(k, k^2, values)` times the precomputed
    /// scalar (zero at `k = 0`), keep 3 outputs, transform back; returns the interleaved real parts.
    ///
    /// The grids are real, so two of them share one complex FFT (`z = a + i b`, then
    /// `A(k) = (Z(k) + conj Z(-k))/2`, `B(k) = (Z(k) - conj Z(-k))/(2i)`), and the three real
    /// outputs go back in two (`U_0 + i U_1`, `U_2`): 5 FFTs instead of 9 for the stresslet, 4
    /// instead of 6 for the Stokeslet. On the Nyquist planes of even grids the wavevector is not
    /// mirrored by the index, so there the outputs are symmetrised, `(U(k) + conj U(-k))/2`, which
    /// is what keeping the real part of an unpaired inverse transform does (equal to
    /// [`Self::convolve_unpaired`] up to rounding, test `paired_fft_matches_unpaired`).
    fn convolve<const C: usize>(
        &self,
        real: Vec<f64>,
        mult: impl Fn([f64; 3], f64, [Complex<f64>; C]) -> [Complex<f64>; 3] + Sync,
    ) -> Vec<f64> {
        let n = self.fft.len();
        let pairs = C.div_ceil(2);
        // one pass over the interleaved grid fills every pair (instead of one strided pass per pair)
        let mut z: Vec<Vec<Complex<f64>>> = (0..pairs).map(|_| Vec::with_capacity(n)).collect();
        for cell in real.chunks_exact(C) {
            for (p, zp) in z.iter_mut().enumerate() {
                let (a, b) = (2 * p, 2 * p + 1);
                zp.push(Complex::new(cell[a], if b < C { cell[b] } else { 0.0 }));
            }
        }
        drop(real);
        for g in z.iter_mut() {
            self.fft.process(g, FftDirection::Forward);
        }
        let [mx, my, mz] = self.m;
        let mirror = |i: usize, m: usize| (m - i) % m;
        let nyquist = |i: usize, m: usize| m.is_multiple_of(2) && i == m / 2;
        let z = &z;
        // the components at grid index `idx` with mirror `jdx`
        let components = |idx: usize, jdx: usize| -> [Complex<f64>; C] {
            std::array::from_fn(|c| {
                let (zk, zm) = (z[c / 2][idx], z[c / 2][jdx].conj());
                if c % 2 == 0 {
                    (zk + zm) * 0.5
                } else {
                    (zk - zm) * Complex::new(0.0, -0.5)
                }
            })
        };
        let mut w0 = vec![Complex::new(0.0, 0.0); n];
        let mut w1 = vec![Complex::new(0.0, 0.0); n];
        w0.par_chunks_mut(my * mz).zip(w1.par_chunks_mut(my * mz)).enumerate().for_each(|(x, (p0, p1))| {
            let (kx, xm) = (self.kvec[0][x], mirror(x, mx));
            for y in 0..my {
                let (ky, ym) = (self.kvec[1][y], mirror(y, my));
                for zz in 0..mz {
                    let idx = y * mz + zz;
                    let s = self.kscale[x * my * mz + idx];
                    if s == 0.0 {
                        continue;
                    }
                    let kz = self.kvec[2][zz];
                    let k2 = kx * kx + ky * ky + kz * kz;
                    let (gi, gj) = (x * my * mz + idx, (xm * my + ym) * mz + mirror(zz, mz));
                    let mut r = mult([kx, ky, kz], k2, components(gi, gj));
                    if nyquist(x, mx) || nyquist(y, my) || nyquist(zz, mz) {
                        // the mirror's own output, with the wavevector its index stands for
                        let km = [self.kvec[0][xm], self.kvec[1][ym], self.kvec[2][mirror(zz, mz)]];
                        let rm = mult(km, km[0] * km[0] + km[1] * km[1] + km[2] * km[2], components(gj, gi));
                        for c in 0..3 {
                            r[c] = (r[c] + rm[c].conj()) * 0.5;
                        }
                    }
                    p0[idx] = (r[0] + r[1] * Complex::new(0.0, 1.0)) * s;
                    p1[idx] = r[2] * s;
                }
            }
        });
        self.fft.process(&mut w0, FftDirection::Inverse);
        self.fft.process(&mut w1, FftDirection::Inverse);
        let mut out = vec![0.0; 3 * n];
        out.par_chunks_mut(3 * 4096).enumerate().for_each(|(b, chunk)| {
            for (j, o) in chunk.chunks_mut(3).enumerate() {
                let i = b * 4096 + j;
                o[0] = w0[i].re;
                o[1] = w0[i].im;
                o[2] = w1[i].re;
            }
        });
        out
    }

    /// The reference of [`Self::convolve`]: one complex FFT per component. Transform the interleaved component grids, multiply by `mult(k, k^2, values)` times the precomputed
    /// scalar (zero at `k = 0`), keep 3 outputs, transform back; returns the interleaved real parts.
    #[cfg(test)]
    fn convolve_unpaired<const C: usize>(
        &self,
        real: Vec<f64>,
        mult: impl Fn([f64; 3], f64, [Complex<f64>; C]) -> [Complex<f64>; 3] + Sync,
    ) -> Vec<f64> {
        let n = self.fft.len();
        let mut grids: Vec<Vec<Complex<f64>>> =
            (0..C).map(|c| (0..n).map(|i| Complex::new(real[i * C + c], 0.0)).collect()).collect();
        drop(real);
        for g in grids.iter_mut() {
            self.fft.process(g, FftDirection::Forward);
        }
        let [_, my, mz] = self.m;
        {
            // Process x-planes in parallel: split every component grid into planes.
            let mut planes: Vec<Vec<&mut [Complex<f64>]>> = (0..self.m[0]).map(|_| Vec::with_capacity(C)).collect();
            for g in grids.iter_mut() {
                for (x, pl) in g.chunks_mut(my * mz).enumerate() {
                    planes[x].push(pl);
                }
            }
            planes.par_iter_mut().enumerate().for_each(|(x, comps)| {
                let kx = self.kvec[0][x];
                for y in 0..my {
                    let ky = self.kvec[1][y];
                    for z in 0..mz {
                        let kz = self.kvec[2][z];
                        let idx = y * mz + z;
                        let s = self.kscale[x * my * mz + idx];
                        if s == 0.0 {
                            for c in comps.iter_mut() {
                                c[idx] = Complex::new(0.0, 0.0);
                            }
                            continue;
                        }
                        let k2 = kx * kx + ky * ky + kz * kz;
                        let v: [Complex<f64>; C] = std::array::from_fn(|c| comps[c][idx]);
                        let r = mult([kx, ky, kz], k2, v);
                        for c in 0..3 {
                            comps[c][idx] = r[c] * s;
                        }
                    }
                }
            });
        }
        grids.truncate(3);
        for g in grids.iter_mut() {
            self.fft.process(g, FftDirection::Inverse);
        }
        let mut out = vec![0.0; 3 * n];
        out.par_chunks_mut(3 * 4096).enumerate().for_each(|(b, chunk)| {
            for (j, o) in chunk.chunks_mut(3).enumerate() {
                let i = b * 4096 + j;
                for c in 0..3 {
                    o[c] = grids[c][i].re;
                }
            }
        });
        out
    }

    /// Normalisation of spread-convolve-gather: both Gaussians' prefactors, `h^3` and the `1/V` of the
    /// Fourier series with the `h^3` of the trapezoid rule (`h^3 / V = 1 / M^3`).
    fn scale(&self) -> f64 {
        let pref = (2.0 * self.xi * self.xi / (std::f64::consts::PI * self.eta)).powf(1.5);
        pref * pref * self.h[0] * self.h[1] * self.h[2] / self.fft.len() as f64
    }

    /// The spread grid of fixed sources as a sparse map from nodal values: for basis node `v`, the
    /// grid points and weights `sum_k l_kv w_k exp(-alpha |x_m - y_k|^2)` over the sources `k` that
    /// interpolate from it (`interp`, barycentric), `w_k` their quadrature weights. Spreading nodal
    /// values `q_v` then costs one multiply-add per stored entry and component instead of `P^3` per source.
    pub fn basis_spread(&self, sources: &[Vector3<f64>], weights: &[f64], interp: &[[(usize, f64); 3]], n_basis: usize) -> BasisSpread {
        self.basis_lists(sources, interp, n_basis, |k| [weights[k]])
    }

    /// The stresslet's spread grid of fixed sources as a sparse map from nodal densities: for basis
    /// node `v` and normal component `b`, `B_vb(x_m) = sum_k l_kv n_kb exp(-alpha |x_m - y_k|^2)`
    /// over the sources `k` that interpolate from it, `n_k` their weighted normals (um^2). The grid
    /// of `q_k = sym(u_k n_k^T)`, `u_k = sum_v l_kv u_v`, is then `q_ab = (1/2) sum_v (u_va B_vb + u_vb B_va)`
    /// ([`Self::stresslet_add_basis`]): 9 multiply-adds per stored entry instead of `6 P^3` per source.
    pub fn stresslet_basis_spread(&self, sources: &[Vector3<f64>], normals_weighted: &[Vector3<f64>], interp: &[[(usize, f64); 3]], n_basis: usize) -> StressletSpread {
        self.basis_lists(sources, interp, n_basis, |k| normals_weighted[k].into())
    }

    /// For each basis node `v`, the grid points and weights `sum_k l_kv c_k exp(-alpha |x_m - y_k|^2)`
    /// (`C` components of `c_k = coef(k)`) over the sources `k` that interpolate from it, the
    /// nonzero ones. The window factors are computed once per source; the windows of a node's
    /// sources are summed in a dense box that bounds them (unwrapped grid indices, components
    /// interleaved: one contiguous run of `C P` values per `(x, y)` line), then mapped to the periodic grid.
    fn basis_lists<const C: usize>(&self, sources: &[Vector3<f64>], interp: &[[(usize, f64); 3]], n_basis: usize, coef: impl Fn(usize) -> [f64; C]) -> BasisSpread<C> {
        const { assert!(C <= 3, "at most 3 weights per entry") };
        let mut by_basis: Vec<Vec<(usize, [f64; C])>> = vec![Vec::new(); n_basis];
        for (k, ip) in interp.iter().enumerate() {
            for &(v, l) in ip {
                if l != 0.0 {
                    by_basis[v].push((k, coef(k).map(|c| l * c)));
                }
            }
        }
        let [mx, my, mz] = self.m.map(|m| m as i64);
        let [px, py, pz] = self.support;
        // per source: the first unwrapped index and the factors (x, then y, then z) of its window
        let stride = px + py + pz;
        let mut start = vec![[0i64; 3]; sources.len()];
        let mut factors = vec![0.0; stride * sources.len()];
        start.par_iter_mut().zip(factors.par_chunks_mut(stride)).zip(sources.par_iter()).for_each(|((s, f), p)| {
            let (fx, fyz) = f.split_at_mut(px);
            let (fy, fz) = fyz.split_at_mut(py);
            *s = [self.factors(p, 0, fx), self.factors(p, 1, fy), self.factors(p, 2, fz)];
        });
        let lists: Vec<(Vec<u32>, Vec<[f32; C]>)> = by_basis
            .par_iter()
            .map_init(Vec::<f64>::new, |acc, nodes| {
                let Some(lo) = nodes.iter().map(|&(k, _)| start[k]).reduce(|a, b| [0, 1, 2].map(|d| a[d].min(b[d]))) else {
                    return (Vec::new(), Vec::new());
                };
                let hi = nodes.iter().fold(lo, |a, &(k, _)| [0, 1, 2].map(|d| a[d].max(start[k][d])));
                let [ex, ey, ez] = [0, 1, 2].map(|d| (hi[d] - lo[d]) as usize + self.support[d]);
                let len = ex * ey * ez;
                acc.clear();
                acc.resize(C * len, 0.0);
                // per z run, interleaved as the box: `c` and the z factors repeated, `c gx` per x
                let (mut crep, mut wzrep, mut cgx) = ([0.0; 3 * MAX_SUPPORT], [0.0; 3 * MAX_SUPPORT], [0.0; 3 * MAX_SUPPORT]);
                let run = C * pz;
                for &(k, c) in nodes {
                    let [ox, oy, oz] = [0, 1, 2].map(|d| (start[k][d] - lo[d]) as usize);
                    let f = &factors[k * stride..(k + 1) * stride];
                    let (wx, wy, wz) = (&f[..px], &f[px..px + py], &f[px + py..]);
                    for i in 0..run {
                        (crep[i], wzrep[i]) = (c[i % C], wz[i / C]);
                    }
                    for (a, &gx) in wx.iter().enumerate() {
                        for (g, &c) in cgx[..run].iter_mut().zip(&crep[..run]) {
                            *g = c * gx;
                        }
                        for (b, &gy) in wy.iter().enumerate() {
                            let z0 = C * (((ox + a) * ey + oy + b) * ez + oz);
                            for ((s, &g), &gz) in acc[z0..z0 + run].iter_mut().zip(&cgx[..run]).zip(&wzrep[..run]) {
                                *s = (g * gy).mul_add(gz, *s);
                            }
                        }
                    }
                }
                let (mut idx, mut w) = (Vec::with_capacity(len), Vec::with_capacity(len));
                let mut cells = acc.chunks_exact(C);
                for a in 0..ex as i64 {
                    let ga = (lo[0] + a).rem_euclid(mx);
                    for b in 0..ey as i64 {
                        let base = (ga * my + (lo[1] + b).rem_euclid(my)) * mz;
                        for z in 0..ez as i64 {
                            let s = cells.next().expect("ex ey ez cells");
                            if s.iter().any(|&x| x != 0.0) {
                                idx.push((base + (lo[2] + z).rem_euclid(mz)) as u32);
                                w.push(std::array::from_fn(|c| s[c] as f32));
                            }
                        }
                    }
                }
                (idx, w)
            })
            .collect();
        BasisSpread { nodes: lists, grid_len: self.fft.len() }
    }

    /// As [`Self::stokeslet_add`] for the sources of `spread` carrying the nodal forces `q` (the
    /// source forces are `w_k sum_v l_kv q_v`).
    pub fn stokeslet_add_basis(&self, spread: &BasisSpread, q: &[Vector3<f64>], targets: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        assert_eq!(spread.grid_len, self.fft.len(), "basis spread of another grid");
        assert_eq!(q.len(), spread.n_basis(), "nodal forces: basis length");
        let mut grid = vec![0.0; 3 * spread.grid_len];
        for (v, f) in q.iter().enumerate() {
            let (idx, ws) = &spread.nodes[v];
            for (&i, &[w]) in idx.iter().zip(ws) {
                let (i, w) = (3 * i as usize, w as f64);
                grid[i] = w.mul_add(f.x, grid[i]);
                grid[i + 1] = w.mul_add(f.y, grid[i + 1]);
                grid[i + 2] = w.mul_add(f.z, grid[i + 2]);
            }
        }
        let u = self.convolve::<3>(grid, project);
        self.gather(&u, targets, self.scale(), out);
    }

    /// As [`Self::stresslet_add`] for the sources of `spread` carrying the nodal densities `u`
    /// (the source densities are `sum_v l_kv u_v`): the grid `q_ab = (1/2) sum_v (u_va B_vb + u_vb B_va)`
    /// in the order `[xx, yy, zz, xy, xz, yz]`, then the same transforms and gathering.
    pub fn stresslet_add_basis(&self, spread: &StressletSpread, u: &[Vector3<f64>], targets: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        assert_eq!(spread.grid_len, self.fft.len(), "basis spread of another grid");
        assert_eq!(u.len(), spread.n_basis(), "nodal densities: basis length");
        let n = spread.grid_len;
        let chunk = u.len().div_ceil(rayon::current_num_threads().max(1)).max(1);
        let add = |mut grid: Vec<f64>, (ci, us): (usize, &[Vector3<f64>])| {
            for (dv, u) in us.iter().enumerate() {
                let v = ci * chunk + dv;
                let h = u * 0.5;
                let (idx, ws) = &spread.nodes[v];
                for (&i, b) in idx.iter().zip(ws) {
                    let (i, b) = (6 * i as usize, b.map(f64::from));
                    let g = &mut grid[i..i + 6];
                    g[0] = u.x.mul_add(b[0], g[0]);
                    g[1] = u.y.mul_add(b[1], g[1]);
                    g[2] = u.z.mul_add(b[2], g[2]);
                    g[3] = h.x.mul_add(b[1], h.y.mul_add(b[0], g[3]));
                    g[4] = h.x.mul_add(b[2], h.z.mul_add(b[0], g[4]));
                    g[5] = h.y.mul_add(b[2], h.z.mul_add(b[1], g[5]));
                }
            }
            grid
        };
        let grid = u
            .par_chunks(chunk)
            .enumerate()
            .fold(|| vec![0.0; 6 * n], add)
            .reduce_with(|mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                a
            })
            .unwrap_or_else(|| vec![0.0; 6 * n]);
        self.stresslet_from_grid(grid, targets, out);
    }

    /// Adds the Fourier-space Stokeslet sum `(1/V) sum_{k != 0} G^F(k) S(k) exp(i k . x_i)` to `out`.
    pub fn stokeslet_add(&self, targets: &[Vector3<f64>], sources: &[Vector3<f64>], forces: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        let vals: Vec<[f64; 3]> = forces.iter().map(|f| [f.x, f.y, f.z]).collect();
        let grid = self.spread(sources, &vals);
        let u = self.convolve::<3>(grid, project);
        self.gather(&u, targets, self.scale(), out);
    }

    /// Adds the Fourier-space stresslet sum to `out`; `q_j = sym(u_j n_j^T)` as `[xx, yy, zz, xy, xz, yz]`.
    pub fn stresslet_add(&self, targets: &[Vector3<f64>], sources: &[Vector3<f64>], q: &[[f64; 6]], out: &mut [Vector3<f64>]) {
        let grid = self.spread(sources, q);
        self.stresslet_from_grid(grid, targets, out);
    }

    /// The transforms and the gathering of the stresslet sum from the interleaved 6-component spread grid.
    fn stresslet_from_grid(&self, grid: Vec<f64>, targets: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        let minus_i = Complex::new(0.0, -1.0);
        let u = self.convolve::<6>(grid, |k, k2, v| stresslet_bracket(k, k2, v).map(|b| b * minus_i));
        self.gather(&u, targets, self.scale(), out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ewald::split::sym_outer;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The stresslet's precomputed spreading of the nodal densities gives the spreading of the
    /// interpolated densities up to the rounding of its single-precision weights, on even and odd grids: a closed latitude-longitude
    /// sphere around the box corner (its windows wrap), 7 random barycentric nodes per triangle
    /// with area normals times random weights, and one vertex no node interpolates from.
    #[test]
    fn stresslet_basis_matches_spreading() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let (nt, np, r) = (6, 10, 0.8);
        let mut verts = vec![Vector3::new(0.0, 0.0, r), Vector3::new(0.0, 0.0, -r)];
        for i in 1..nt {
            for j in 0..np {
                let (th, ph) = (std::f64::consts::PI * i as f64 / nt as f64, std::f64::consts::TAU * j as f64 / np as f64);
                verts.push(Vector3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()) * r);
            }
        }
        let vid = |i: usize, j: usize| if i == 0 { 0 } else if i == nt { 1 } else { 2 + (i - 1) * np + j % np };
        let mut tris = Vec::new();
        for i in 0..nt {
            for j in 0..np {
                let [a, b, c, d] = [vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)];
                tris.extend([[a, b, c], [a, c, d]].into_iter().filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]));
            }
        }
        let n_basis = verts.len() + 1;
        let (mut sources, mut normals, mut interp) = (Vec::new(), Vec::new(), Vec::new());
        for t in &tris {
            let area_normal = (verts[t[1]] - verts[t[0]]).cross(&(verts[t[2]] - verts[t[0]])) * 0.5;
            for _ in 0..7 {
                let l: [f64; 3] = std::array::from_fn(|_| 0.05 + rng.random::<f64>());
                let l = l.map(|x| x / (l[0] + l[1] + l[2]));
                sources.push(verts[t[0]] * l[0] + verts[t[1]] * l[1] + verts[t[2]] * l[2]);
                normals.push(area_normal * rng.random::<f64>());
                interp.push([0, 1, 2].map(|c| (t[c], l[c])));
            }
        }
        let nodal: Vec<Vector3<f64>> = (0..n_basis).map(|_| Vector3::from_fn(|_, _| rng.random::<f64>() - 0.5)).collect();
        let q: Vec<[f64; 6]> = interp
            .iter()
            .zip(&normals)
            .map(|(ip, n)| sym_outer(&ip.iter().map(|&(v, l)| nodal[v] * l).sum(), n))
            .collect();
        let mut targets = verts.clone();
        targets.extend((0..30).map(|_| Vector3::from_fn(|d, _| [3.0, 2.5, 2.0][d] * rng.random::<f64>())));
        for m in [[16, 12, 10], [15, 11, 9]] {
            let g = SpectralGrid::new([3.0, 2.5, 2.0], m, 6, 2.0);
            assert!(g.window_fits());
            let mut plain = vec![Vector3::zeros(); targets.len()];
            g.stresslet_add(&targets, &sources, &q, &mut plain);
            let spread = g.stresslet_basis_spread(&sources, &normals, &interp, n_basis);
            assert_eq!(spread.n_basis(), n_basis);
            let mut out = vec![Vector3::zeros(); targets.len()];
            g.stresslet_add_basis(&spread, &nodal, &targets, &mut out);
            let scale = plain.iter().fold(0.0f64, |s, v| s.max(v.norm()));
            let err = out.iter().zip(&plain).fold(0.0f64, |s, (a, b)| s.max((a - b).norm()));
            // the map's weights are stored in single precision (6e-8 relative): 5e-9 of the
            // largest value here, bar 1e-6, two orders of magnitude below the Ewald tolerance
            assert!(scale > 0.0 && err < 1e-6 * scale, "grid {m:?}: {err:e} of {scale:e}");
        }
    }

    /// The paired transforms give the unpaired ones' result up to rounding, on even and odd
    /// grids (Nyquist planes), for the Stokeslet (3 components) and the stresslet (6).
    #[test]
    fn paired_fft_matches_unpaired() {
        for m in [[8, 6, 10], [9, 7, 5], [12, 5, 6]] {
            let g = SpectralGrid::new([3.0, 2.5, 2.0], m, 4, 2.0);
            let n = m[0] * m[1] * m[2];
            let vals = |c: usize| (0..c * n).map(|i| ((i * 7919) % 1013) as f64 / 1013.0 - 0.4).collect::<Vec<f64>>();
            let minus_i = Complex::new(0.0, -1.0);
            let stresslet = |k: [f64; 3], k2: f64, v: [Complex<f64>; 6]| stresslet_bracket(k, k2, v).map(|b| b * minus_i);
            let pairs: [(Vec<f64>, Vec<f64>); 2] = [
                (g.convolve::<3>(vals(3), project), g.convolve_unpaired::<3>(vals(3), project)),
                (g.convolve::<6>(vals(6), stresslet), g.convolve_unpaired::<6>(vals(6), stresslet)),
            ];
            for (a, b) in pairs {
                let scale = b.iter().fold(0.0f64, |s, v| s.max(v.abs()));
                let err = a.iter().zip(&b).fold(0.0f64, |s, (x, y)| s.max((x - y).abs()));
                assert!(scale > 0.0 && err < 1e-13 * scale, "grid {m:?}: {err:e} of {scale:e}");
            }
        }
    }
}
