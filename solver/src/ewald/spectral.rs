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
    box_len: [f64; 3],
    m: [usize; 3],
    h: [f64; 3],
    /// Window points per direction (>= the requested P; more along directions with a finer grid).
    support: [usize; 3],
    xi: f64,
    eta: f64,
    fft: Fft3,
}

/// Window of one point: first (unwrapped) grid index per direction and the 1D Gaussian factors.
struct Window {
    start: [i64; 3],
    w: [Vec<f64>; 3],
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
        Self { box_len, m, h, support, xi, eta, fft: Fft3::new(m) }
    }

    /// Whether every window is shorter than its grid period (else a point would see its own image).
    pub fn window_fits(&self) -> bool {
        (0..3).all(|d| self.support[d] < self.m[d])
    }

    pub fn eta(&self) -> f64 {
        self.eta
    }

    pub fn support(&self) -> [usize; 3] {
        self.support
    }

    fn window(&self, p: &Vector3<f64>) -> Window {
        let alpha = 2.0 * self.xi * self.xi / self.eta;
        let mut start = [0i64; 3];
        let w = [0, 1, 2].map(|d| {
            let pd = self.support[d];
            let s = (p[d] / self.h[d] - pd as f64 / 2.0).ceil() as i64;
            start[d] = s;
            (0..pd)
                .map(|q| {
                    let dx = (s + q as i64) as f64 * self.h[d] - p[d];
                    (-alpha * dx * dx).exp()
                })
                .collect()
        });
        Window { start, w }
    }

    /// Wrapped grid indices of a window along `d`.
    fn indices(&self, d: usize, start: i64) -> Vec<usize> {
        let m = self.m[d] as i64;
        (0..self.support[d] as i64).map(|q| (start + q).rem_euclid(m) as usize).collect()
    }

    /// `H_c(x_m) = sum_j exp(-alpha |x_m - y_j|^2) v_j[c]` (no normalisation), component blocks of `len()`.
    fn spread<const C: usize>(&self, points: &[Vector3<f64>], values: &[[f64; C]]) -> Vec<f64> {
        let n = self.fft.len();
        let [_, my, mz] = self.m;
        let threads = rayon::current_num_threads().max(1);
        let chunk = points.len().div_ceil(threads).max(1);
        let add = |mut grid: Vec<f64>, (pts, vals): (&[Vector3<f64>], &[[f64; C]])| {
            for (p, v) in pts.iter().zip(vals) {
                let win = self.window(p);
                let (ix, iy, iz) = (self.indices(0, win.start[0]), self.indices(1, win.start[1]), self.indices(2, win.start[2]));
                for (a, &gx) in ix.iter().zip(&win.w[0]) {
                    for (b, &gy) in iy.iter().zip(&win.w[1]) {
                        let base = (a * my + b) * mz;
                        let gxy = gx * gy;
                        for (c, &gz) in iz.iter().zip(&win.w[2]) {
                            let g = gxy * gz;
                            for k in 0..C {
                                grid[k * n + base + c] += g * v[k];
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

    /// `out_i = sum_m exp(-alpha |x_i - x_m|^2) U_c(x_m)` for 3 component grids (real parts).
    fn gather(&self, grids: &[Vec<Complex<f64>>], targets: &[Vector3<f64>], scale: f64, out: &mut [Vector3<f64>]) {
        let [_, my, mz] = self.m;
        out.par_iter_mut().with_min_len(16).zip(targets.par_iter()).for_each(|(o, p)| {
            let win = self.window(p);
            let (ix, iy, iz) = (self.indices(0, win.start[0]), self.indices(1, win.start[1]), self.indices(2, win.start[2]));
            let mut acc = [0.0f64; 3];
            for (a, &gx) in ix.iter().zip(&win.w[0]) {
                for (b, &gy) in iy.iter().zip(&win.w[1]) {
                    let base = (a * my + b) * mz;
                    let gxy = gx * gy;
                    for (c, &gz) in iz.iter().zip(&win.w[2]) {
                        let g = gxy * gz;
                        for k in 0..3 {
                            acc[k] += g * grids[k][base + c].re;
                        }
                    }
                }
            }
            *o += Vector3::new(acc[0], acc[1], acc[2]) * scale;
        });
    }

    /// Wavenumber (1/um) of FFT index `i` along `d`.
    fn k(&self, d: usize, i: usize) -> f64 {
        let m = self.m[d];
        let n = if i <= m / 2 { i as i64 } else { i as i64 - m as i64 };
        2.0 * std::f64::consts::PI * n as f64 / self.box_len[d]
    }

    /// Transform component grids, multiply by `mult(k, k^2, values) * factor(k^2)` (k = 0 set to zero), keep 3 outputs, transform back.
    fn convolve<const C: usize>(
        &self,
        real: Vec<f64>,
        mult: impl Fn([f64; 3], f64, [Complex<f64>; C]) -> [Complex<f64>; 3] + Sync,
    ) -> Vec<Vec<Complex<f64>>> {
        let n = self.fft.len();
        let mut grids: Vec<Vec<Complex<f64>>> =
            (0..C).map(|c| real[c * n..(c + 1) * n].iter().map(|&v| Complex::new(v, 0.0)).collect()).collect();
        for g in grids.iter_mut() {
            self.fft.process(g, FftDirection::Forward);
        }
        let [_, my, mz] = self.m;
        let q = self.eta / (4.0 * self.xi * self.xi);
        {
            // Process x-planes in parallel: split every component grid into planes.
            let mut planes: Vec<Vec<&mut [Complex<f64>]>> = (0..self.m[0]).map(|_| Vec::with_capacity(C)).collect();
            for g in grids.iter_mut() {
                for (x, pl) in g.chunks_mut(my * mz).enumerate() {
                    planes[x].push(pl);
                }
            }
            planes.par_iter_mut().enumerate().for_each(|(x, comps)| {
                let kx = self.k(0, x);
                for y in 0..my {
                    let ky = self.k(1, y);
                    for z in 0..mz {
                        let kz = self.k(2, z);
                        let idx = y * mz + z;
                        let k2 = kx * kx + ky * ky + kz * kz;
                        if k2 == 0.0 {
                            for c in comps.iter_mut() {
                                c[idx] = Complex::new(0.0, 0.0);
                            }
                            continue;
                        }
                        let v: [Complex<f64>; C] = std::array::from_fn(|c| comps[c][idx]);
                        let r = mult([kx, ky, kz], k2, v);
                        let s = fourier_scalar(self.xi, k2) * (q * k2).exp();
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
        grids
    }

    /// Normalisation of spread-convolve-gather: both Gaussians' prefactors, `h^3` and the `1/V` of the
    /// Fourier series with the `h^3` of the trapezoid rule (`h^3 / V = 1 / M^3`).
    fn scale(&self) -> f64 {
        let pref = (2.0 * self.xi * self.xi / (std::f64::consts::PI * self.eta)).powf(1.5);
        pref * pref * self.h[0] * self.h[1] * self.h[2] / self.fft.len() as f64
    }

    /// Adds the Fourier-space Stokeslet sum `(1/V) sum_{k != 0} G^F(k) S(k) exp(i k . x_i)` to `out`.
    pub fn stokeslet_add(&self, targets: &[Vector3<f64>], sources: &[Vector3<f64>], forces: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        let vals: Vec<[f64; 3]> = forces.iter().map(|f| [f.x, f.y, f.z]).collect();
        let grid = self.spread(sources, &vals);
        let grids = self.convolve::<3>(grid, |k, k2, f| project(k, k2, f));
        self.gather(&grids, targets, self.scale(), out);
    }

    /// Adds the Fourier-space stresslet sum to `out`; `q_j = sym(u_j n_j^T)` as `[xx, yy, zz, xy, xz, yz]`.
    pub fn stresslet_add(&self, targets: &[Vector3<f64>], sources: &[Vector3<f64>], q: &[[f64; 6]], out: &mut [Vector3<f64>]) {
        let grid = self.spread(sources, q);
        let minus_i = Complex::new(0.0, -1.0);
        let grids = self.convolve::<6>(grid, |k, k2, v| stresslet_bracket(k, k2, v).map(|b| b * minus_i));
        self.gather(&grids, targets, self.scale(), out);
    }
}
