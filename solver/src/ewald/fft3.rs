//! Three-dimensional complex FFT of a row-major `[x][y][z]` grid by three passes of 1D `rustfft` transforms, parallel over lines with rayon.
//!
//! rustfft only does 1D transforms; a 3D transform is the 1D transform along z (contiguous
//! lines), then along y (each x-plane transposed to `[z][y]`, transformed, transposed back), then
//! along x (for each y, its `mz` x-lines gathered into a `[z][x]` slab, transformed, scattered
//! back). Unnormalised in both directions (rustfft's convention: forward
//! `sum_n a_n exp(-2 pi i k n / M)`).

use std::sync::Arc;

use rayon::prelude::*;
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftDirection, FftPlanner};

/// Planned 1D transforms for a grid of `m = [mx, my, mz]` points.
pub struct Fft3 {
    m: [usize; 3],
    forward: [Arc<dyn Fft<f64>>; 3],
    inverse: [Arc<dyn Fft<f64>>; 3],
}

impl std::fmt::Debug for Fft3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Fft3").field("m", &self.m).finish()
    }
}

impl Fft3 {
    pub fn new(m: [usize; 3]) -> Self {
        let mut planner = FftPlanner::new();
        let forward = m.map(|n| planner.plan_fft_forward(n));
        let inverse = m.map(|n| planner.plan_fft_inverse(n));
        Self { m, forward, inverse }
    }

    pub fn len(&self) -> usize {
        self.m[0] * self.m[1] * self.m[2]
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// In-place unnormalised transform of `data` (`mx * my * mz` values, z fastest).
    pub fn process(&self, data: &mut [Complex<f64>], direction: FftDirection) {
        let [mx, my, mz] = self.m;
        assert_eq!(data.len(), mx * my * mz, "grid size");
        let plans = match direction {
            FftDirection::Forward => &self.forward,
            FftDirection::Inverse => &self.inverse,
        };
        let scratch = |d: usize| move || vec![Complex::new(0.0, 0.0); plans[d].get_inplace_scratch_len()];
        // z: contiguous lines, one x-plane per task.
        data.par_chunks_mut(my * mz).for_each_init(scratch(2), |sc, plane| plans[2].process_with_scratch(plane, sc));
        // y: transpose each plane to [z][y], transform, transpose back.
        data.par_chunks_mut(my * mz).for_each_init(
            || (vec![Complex::new(0.0, 0.0); my * mz], scratch(1)()),
            |(buf, sc), plane| {
                for y in 0..my {
                    for z in 0..mz {
                        buf[z * my + y] = plane[y * mz + z];
                    }
                }
                plans[1].process_with_scratch(buf, sc);
                for y in 0..my {
                    for z in 0..mz {
                        plane[y * mz + z] = buf[z * my + y];
                    }
                }
            },
        );
        // x: for each y, the slab of the x-lines at that y gathered as [z][x] (mz lines of mx,
        // contiguous), transformed, scattered back. The same transforms of the same slabs as a
        // transpose of the whole grid to [y][z][x] (the same values bit for bit), without that
        // grid: no allocation and zeroing of a second full grid per transform, and the
        // scattering reads the slab from cache instead of striding through the whole grid.
        let mut by_y: Vec<Vec<&mut [Complex<f64>]>> = (0..my).map(|_| Vec::with_capacity(mx)).collect();
        for plane in data.chunks_mut(my * mz) {
            for (y, row) in plane.chunks_mut(mz).enumerate() {
                by_y[y].push(row);
            }
        }
        by_y.par_iter_mut().for_each_init(
            || (vec![Complex::new(0.0, 0.0); mz * mx], scratch(0)()),
            |(slab, sc), rows| {
                for (x, row) in rows.iter().enumerate() {
                    for (z, v) in row.iter().enumerate() {
                        slab[z * mx + x] = *v;
                    }
                }
                plans[0].process_with_scratch(slab, sc);
                for (x, row) in rows.iter_mut().enumerate() {
                    for (z, v) in row.iter_mut().enumerate() {
                        *v = slab[z * mx + x];
                    }
                }
            },
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every line transformed on its own with the same plans, pass by pass (z, y, x): the 3D
    /// transform equals it bit for bit (the passes only move values; the slabs are the same lines
    /// processed by the same plans), on an odd and an even grid, both directions.
    #[test]
    fn equals_line_by_line_transforms_bit_for_bit() {
        for m in [[7usize, 5, 9], [12, 6, 10]] {
            let [mx, my, mz] = m;
            let f = Fft3::new(m);
            for direction in [FftDirection::Forward, FftDirection::Inverse] {
                let plans = match direction {
                    FftDirection::Forward => &f.forward,
                    FftDirection::Inverse => &f.inverse,
                };
                let mut data: Vec<Complex<f64>> = (0..mx * my * mz)
                    .map(|i| Complex::new(((i * 7919) % 1013) as f64 / 1013.0 - 0.4, ((i * 104729) % 997) as f64 / 997.0 - 0.6))
                    .collect();
                let mut want = data.clone();
                let at = |x: usize, y: usize, z: usize| (x * my + y) * mz + z;
                let mut line_pass = |d: usize, len: usize, index: &dyn Fn(usize, usize, usize) -> usize, others: [usize; 2]| {
                    for a in 0..others[0] {
                        for b in 0..others[1] {
                            let mut line: Vec<Complex<f64>> = (0..len).map(|k| want[index(a, b, k)]).collect();
                            plans[d].process(&mut line);
                            for (k, v) in line.into_iter().enumerate() {
                                want[index(a, b, k)] = v;
                            }
                        }
                    }
                };
                line_pass(2, mz, &|x, y, z| at(x, y, z), [mx, my]);
                line_pass(1, my, &|x, z, y| at(x, y, z), [mx, mz]);
                line_pass(0, mx, &|y, z, x| at(x, y, z), [my, mz]);
                f.process(&mut data, direction);
                for (i, (a, b)) in data.iter().zip(&want).enumerate() {
                    assert!(a.re.to_bits() == b.re.to_bits() && a.im.to_bits() == b.im.to_bits(), "grid {m:?}, index {i}: {a} against {b}");
                }
            }
        }
    }

    /// The 3D transform of a single plane wave is one spike of height M at its wavenumber; the inverse returns M times the input.
    #[test]
    fn plane_wave_and_round_trip() {
        let m = [6, 5, 8];
        let n = m[0] * m[1] * m[2];
        let f = Fft3::new(m);
        let (k0, k1, k2) = (2usize, 4usize, 3usize);
        let tau = 2.0 * std::f64::consts::PI;
        let mut data: Vec<Complex<f64>> = (0..n)
            .map(|i| {
                let (x, y, z) = (i / (m[1] * m[2]), (i / m[2]) % m[1], i % m[2]);
                let ph = tau * (k0 * x) as f64 / m[0] as f64 + tau * (k1 * y) as f64 / m[1] as f64 + tau * (k2 * z) as f64 / m[2] as f64;
                Complex::from_polar(1.0, ph)
            })
            .collect();
        let orig = data.clone();
        f.process(&mut data, FftDirection::Forward);
        for (i, v) in data.iter().enumerate() {
            let want = if i == (k0 * m[1] + k1) * m[2] + k2 { n as f64 } else { 0.0 };
            assert!((v - Complex::new(want, 0.0)).norm() < 1e-11, "index {i}: {v}");
        }
        f.process(&mut data, FftDirection::Inverse);
        for (a, b) in data.iter().zip(&orig) {
            assert!((a / n as f64 - b).norm() < 1e-14);
        }
    }
}
