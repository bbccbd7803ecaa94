//! Real-space part of the Ewald sums: a periodic cell list over the sources and direct structure-of-arrays sums over the neighbours within the cutoff.
//!
//! Sources are wrapped into the box and sorted by cell (counting sort); each cell's sources are
//! a contiguous range of plain `f64` arrays. Cells are at least `r_cut / 2` wide, and a target visits
//! the `(2 reach + 1)^3` cells around its own with the periodic shift of each visit, so every
//! image within `r_cut` is seen exactly once, also when `r_cut` exceeds half the box.
//! The kernels are those of [`super::split`] with the tabulated `erfc` ([`super::erfc::Erfcx`]).

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use super::erfc::Erfcx;
use super::lanes::StokesletLanes;
use super::split::{erfc_and_gauss, stresslet_ab};

/// Sources sorted into periodic cells.
#[derive(Debug, Clone)]
pub struct CellList {
    box_len: [f64; 3],
    n: [usize; 3],
    width: [f64; 3],
    reach: [i64; 3],
    /// Sources of cell `c` are `start[c]..start[c + 1]` in the sorted arrays.
    start: Vec<usize>,
    /// `order[s]` = original index of sorted source `s`.
    pub order: Vec<usize>,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub z: Vec<f64>,
}

fn wrap_coord(v: f64, l: f64) -> f64 {
    let w = v - l * (v / l).floor();
    if w >= l {
        0.0
    } else {
        w
    }
}

impl CellList {
    /// Bin `sources` (um) into cells at least `r_cut / 2` (um) wide (a target then scans
    /// `(5 r_cut / 2)^3` instead of `(3 r_cut)^3` around itself: 42 % fewer distance checks).
    pub fn new(box_len: [f64; 3], r_cut: f64, sources: &[Vector3<f64>]) -> Self {
        let n = box_len.map(|l| ((2.0 * l / r_cut).floor() as usize).clamp(1, 512));
        let width = [box_len[0] / n[0] as f64, box_len[1] / n[1] as f64, box_len[2] / n[2] as f64];
        let reach = [0, 1, 2].map(|d| (r_cut / width[d]).ceil() as i64);
        let mut me = Self {
            box_len,
            n,
            width,
            reach,
            start: vec![0; n[0] * n[1] * n[2] + 1],
            order: vec![0; sources.len()],
            x: vec![0.0; sources.len()],
            y: vec![0.0; sources.len()],
            z: vec![0.0; sources.len()],
        };
        let cells: Vec<usize> = sources.iter().map(|p| me.cell_index(&me.wrap(p))).collect();
        for &c in &cells {
            me.start[c + 1] += 1;
        }
        for c in 0..me.start.len() - 1 {
            me.start[c + 1] += me.start[c];
        }
        let mut fill = me.start.clone();
        for (i, &c) in cells.iter().enumerate() {
            let s = fill[c];
            fill[c] += 1;
            let w = me.wrap(&sources[i]);
            me.order[s] = i;
            (me.x[s], me.y[s], me.z[s]) = (w.x, w.y, w.z);
        }
        me
    }

    fn wrap(&self, p: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(wrap_coord(p.x, self.box_len[0]), wrap_coord(p.y, self.box_len[1]), wrap_coord(p.z, self.box_len[2]))
    }

    fn cell_coords(&self, w: &Vector3<f64>) -> [i64; 3] {
        [0, 1, 2].map(|d| ((w[d] / self.width[d]) as i64).min(self.n[d] as i64 - 1))
    }

    fn cell_index(&self, w: &Vector3<f64>) -> usize {
        let c = self.cell_coords(w);
        (c[0] as usize * self.n[1] + c[1] as usize) * self.n[2] + c[2] as usize
    }

    /// Gather a per-source array into the sorted order.
    pub fn sorted<T: Copy>(&self, v: &[T]) -> Vec<T> {
        self.order.iter().map(|&i| v[i]).collect()
    }

    /// Calls `visit(shifted_target, range)` for every (cell, periodic shift) a target must see:
    /// `shifted_target = x - shift`, so `r = shifted_target - y_s` for the sorted sources `s` in `range`.
    #[inline]
    pub fn for_each_neighbour(&self, target: &Vector3<f64>, mut visit: impl FnMut([f64; 3], std::ops::Range<usize>)) {
        let w = self.wrap(target);
        let c = self.cell_coords(&w);
        for ox in -self.reach[0]..=self.reach[0] {
            let (cx, sx) = self.wrap_cell(0, c[0] + ox);
            for oy in -self.reach[1]..=self.reach[1] {
                let (cy, sy) = self.wrap_cell(1, c[1] + oy);
                // The z-neighbours of one (x, y) column are consecutive in the sorted arrays: one
                // range per periodic image of the column instead of one per cell (longer inner loops).
                let (lo, hi) = (c[2] - self.reach[2], c[2] + self.reach[2]);
                let nz = self.n[2] as i64;
                for q in lo.div_euclid(nz)..=hi.div_euclid(nz) {
                    let (a, b) = ((lo.max(q * nz) - q * nz) as usize, (hi.min(q * nz + nz - 1) - q * nz) as usize);
                    let col = (cx * self.n[1] + cy) * self.n[2];
                    let range = self.start[col + a]..self.start[col + b + 1];
                    if !range.is_empty() {
                        visit([w.x - sx, w.y - sy, w.z - q as f64 * self.box_len[2]], range);
                    }
                }
            }
        }
    }

    /// Wrapped cell index along `d` and the shift (um) of the image it stands for.
    #[inline]
    fn wrap_cell(&self, d: usize, c: i64) -> (usize, f64) {
        let n = self.n[d] as i64;
        let q = c.div_euclid(n);
        ((c - q * n) as usize, q as f64 * self.box_len[d])
    }
}

/// Real-space Stokeslet sum `out_i = sum_{|r| < r_cut} G^R(r) f` over all sources and images
/// (`f` sorted like the cell list, SoA); a source within `eps` of the target adds `self_term * f`.
#[allow(clippy::too_many_arguments)]
pub fn stokeslet(
    cells: &CellList,
    xi: f64,
    r_cut: f64,
    eps: f64,
    self_term: &Matrix3<f64>,
    targets: &[Vector3<f64>],
    f: [&[f64]; 3],
    out: &mut [Vector3<f64>],
) {
    let (rc2, eps2) = (r_cut * r_cut, eps * eps);
    let [fx, fy, fz] = f;
    let avx512 = crate::bim::kernels::avx512_available();
    // the pairs inside the cutoff are queued and evaluated eight at a time in SIMD lanes
    out.par_iter_mut().with_min_len(8).zip(targets.par_iter()).for_each_init(
        || StokesletLanes::new(xi, avx512),
        |lanes, (o, x)| {
            let mut coincident = Vector3::zeros();
            cells.for_each_neighbour(x, |t, range| {
                for s in range {
                    let r = [t[0] - cells.x[s], t[1] - cells.y[s], t[2] - cells.z[s]];
                    let r2 = r[0].mul_add(r[0], r[1].mul_add(r[1], r[2] * r[2]));
                    if r2 >= rc2 {
                        continue;
                    }
                    if r2 <= eps2 {
                        coincident += self_term * Vector3::new(fx[s], fy[s], fz[s]);
                        continue;
                    }
                    lanes.push(r, [fx[s], fy[s], fz[s]]);
                }
            });
            let [a, b, c] = lanes.total();
            *o = Vector3::new(a, b, c) + coincident;
        },
    );
}

/// Real-space stresslet sum `out_i = sum_{|r| < r_cut} u . T^R(r) . n` (SoA, sorted like the cell list);
/// sources within `eps` of the target add nothing (the odd `T^R - T` vanishes at 0).
#[allow(clippy::too_many_arguments)]
pub fn stresslet(
    cells: &CellList,
    xi: f64,
    r_cut: f64,
    eps: f64,
    targets: &[Vector3<f64>],
    u: [&[f64]; 3],
    n: [&[f64]; 3],
    out: &mut [Vector3<f64>],
) {
    let table = Erfcx::get();
    let (rc2, eps2) = (r_cut * r_cut, eps * eps);
    let [ux, uy, uz] = u;
    let [nx, ny, nz] = n;
    out.par_iter_mut().with_min_len(8).zip(targets.par_iter()).for_each(|(o, x)| {
        let mut acc = [0.0f64; 3];
        cells.for_each_neighbour(x, |t, range| {
            for s in range {
                let (rx, ry, rz) = (t[0] - cells.x[s], t[1] - cells.y[s], t[2] - cells.z[s]);
                let r2 = rx.mul_add(rx, ry.mul_add(ry, rz * rz));
                if r2 >= rc2 || r2 <= eps2 {
                    continue;
                }
                let r = r2.sqrt();
                let (erfc, e) = erfc_and_gauss(table, xi * r);
                let (a, b) = stresslet_ab(xi, r, erfc, e);
                let (vx, vy, vz) = (ux[s], uy[s], uz[s]);
                let (mx, my, mz) = (nx[s], ny[s], nz[s]);
                let ur = rx.mul_add(vx, ry.mul_add(vy, rz * vz));
                let rn = rx.mul_add(mx, ry.mul_add(my, rz * mz));
                let un = vx.mul_add(mx, vy.mul_add(my, vz * mz));
                let cr = b * ur * rn + a * un;
                let (cu, cn) = (a * rn, a * ur);
                acc[0] += cr.mul_add(rx, cu.mul_add(vx, cn * mx));
                acc[1] += cr.mul_add(ry, cu.mul_add(vy, cn * my));
                acc[2] += cr.mul_add(rz, cu.mul_add(vz, cn * mz));
            }
        });
        *o = Vector3::new(acc[0], acc[1], acc[2]);
    });
}
