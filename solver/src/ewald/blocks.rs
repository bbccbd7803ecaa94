//! Real-space Ewald sums frozen into block-sparse matrices over a nodal basis: for sources that are quadrature nodes of linearly interpolated densities, the real-space part of a Stokeslet or stresslet sum is a fixed linear map from the nodal values to the targets, built once and applied as a mat-vec.
//!
//! Source `k` carries the density `sum_{(v, l) in interp_k} l q_v` (nodal values `q_v`, barycentric
//! weights `l`), times a scalar quadrature weight `w_k` (Stokeslet) or with a weighted normal `n_k`
//! (stresslet). The real-space kernels of [`super::split`] then give, for each target `i` and node `v`,
//! a 3 x 3 block `B_iv` with `out_i = sum_v B_iv q_v`:
//!
//! ```text
//! Stokeslet:  B_iv = sum_k l_kv w_k [a(r) I + b(r) r r^T]                       (r = x_i - y_k, |r| < r_cut)
//! stresslet:  B_iv = sum_k l_kv [B(r) (r . n_k) r r^T + A(r) (r n_k^T + (r . n_k) I + n_k r^T)]
//! ```
//!
//! the same sums as [`super::real_space`] regrouped (equal up to rounding, test `blocks_match_real_space`).
//! Within one boundary-integral solve the geometry is fixed while GMRES applies the sums ~10
//! times: one build (a real-space sum's work plus 27 multiply-adds per pair) replaces them all, and
//! each application costs `9 x` (number of blocks) multiply-adds.

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use super::erfc::Erfcx;
use super::real_space::CellList;
use super::split::{erfc_and_gauss, stokeslet_ab, stresslet_ab};

/// Barycentric interpolation of a source node from (up to) three nodal values: `(node index, weight)`.
pub type Interp = [(usize, f64); 3];

/// Block-sparse matrix: row `i` (a target) holds 3 x 3 blocks `blocks[j]` for the basis nodes `cols[j]`, `j in start[i]..start[i + 1]`.
#[derive(Debug, Clone, Default)]
pub struct BlockRows {
    start: Vec<usize>,
    cols: Vec<u32>,
    blocks: Vec<[f64; 9]>,
    n_basis: usize,
}

impl BlockRows {
    /// Number of stored 3 x 3 blocks.
    pub fn n_blocks(&self) -> usize {
        self.blocks.len()
    }

    pub fn n_rows(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// `out_i = sum_j B_ij q_cols[j]` (overwrites `out`).
    pub fn apply(&self, q: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        assert_eq!(q.len(), self.n_basis, "BlockRows::apply: basis length");
        assert_eq!(out.len(), self.n_rows(), "BlockRows::apply: output length");
        out.par_iter_mut().with_min_len(16).enumerate().for_each(|(i, o)| {
            let mut acc = [0.0f64; 3];
            for j in self.start[i]..self.start[i + 1] {
                let b = &self.blocks[j];
                let v = &q[self.cols[j] as usize];
                acc[0] += b[0] * v.x + b[1] * v.y + b[2] * v.z;
                acc[1] += b[3] * v.x + b[4] * v.y + b[5] * v.z;
                acc[2] += b[6] * v.x + b[7] * v.y + b[8] * v.z;
            }
            *o = Vector3::new(acc[0], acc[1], acc[2]);
        });
    }

    /// Build from a per-target kernel: `pair(r, r^2, s)` returns the 3 x 3 kernel (row-major) of
    /// sorted source `s` at separation `r` (or `None` to skip it), distributed over the source's
    /// interpolation nodes.
    fn build(
        cells: &CellList,
        targets: &[Vector3<f64>],
        interp: &[Interp],
        n_basis: usize,
        pair: impl Fn([f64; 3], f64, usize) -> Option<[f64; 9]> + Sync,
    ) -> Self {
        let rows: Vec<(Vec<u32>, Vec<[f64; 9]>)> = targets
            .par_iter()
            .with_min_len(8)
            .map_init(
                || (vec![[0.0f64; 9]; n_basis], vec![false; n_basis], Vec::<u32>::new()),
                |(acc, seen, touched), x| {
                    cells.for_each_neighbour(x, |t, range| {
                        for s in range {
                            let r = [t[0] - cells.x[s], t[1] - cells.y[s], t[2] - cells.z[s]];
                            let r2 = r[0].mul_add(r[0], r[1].mul_add(r[1], r[2] * r[2]));
                            let Some(k) = pair(r, r2, s) else { continue };
                            for &(v, l) in &interp[s] {
                                if l == 0.0 {
                                    continue;
                                }
                                if !seen[v] {
                                    seen[v] = true;
                                    touched.push(v as u32);
                                }
                                let a = &mut acc[v];
                                for (c, kc) in a.iter_mut().zip(&k) {
                                    *c = l.mul_add(*kc, *c);
                                }
                            }
                        }
                    });
                    touched.sort_unstable();
                    let blocks: Vec<[f64; 9]> = touched
                        .iter()
                        .map(|&v| {
                            let b = acc[v as usize];
                            acc[v as usize] = [0.0; 9];
                            seen[v as usize] = false;
                            b
                        })
                        .collect();
                    (std::mem::take(touched), blocks)
                },
            )
            .collect();
        let mut me = Self { start: Vec::with_capacity(targets.len() + 1), n_basis, ..Self::default() };
        me.start.push(0);
        for (c, b) in rows {
            me.cols.extend_from_slice(&c);
            me.blocks.extend_from_slice(&b);
            me.start.push(me.cols.len());
        }
        me
    }

    /// Real-space Stokeslet blocks (`weights`: scalar quadrature weights of the sources, sorted like
    /// `cells`; `interp` sorted likewise). A source within `eps` of a target adds `self_term w`.
    #[allow(clippy::too_many_arguments)]
    pub fn stokeslet(
        cells: &CellList,
        xi: f64,
        r_cut: f64,
        eps: f64,
        self_term: &Matrix3<f64>,
        targets: &[Vector3<f64>],
        weights: &[f64],
        interp: &[Interp],
        n_basis: usize,
    ) -> Self {
        let table = Erfcx::get();
        let (rc2, eps2) = (r_cut * r_cut, eps * eps);
        Self::build(cells, targets, interp, n_basis, |r, r2, s| {
            if r2 >= rc2 {
                return None;
            }
            let w = weights[s];
            if r2 <= eps2 {
                let m = self_term * w;
                return Some(std::array::from_fn(|i| m[(i / 3, i % 3)]));
            }
            let rn = r2.sqrt();
            let (erfc, e) = erfc_and_gauss(table, xi * rn);
            let (a, b) = stokeslet_ab(xi, rn, erfc, e);
            let (a, b) = (a * w, b * w);
            Some(std::array::from_fn(|i| {
                let (p, q) = (i / 3, i % 3);
                b * r[p] * r[q] + if p == q { a } else { 0.0 }
            }))
        })
    }

    /// Real-space stresslet blocks (`normals`: weighted normals of the sources, sorted like `cells`;
    /// `interp` sorted likewise). Sources within `eps` of a target add nothing (as [`super::real_space::stresslet`]).
    #[allow(clippy::too_many_arguments)]
    pub fn stresslet(
        cells: &CellList,
        xi: f64,
        r_cut: f64,
        eps: f64,
        targets: &[Vector3<f64>],
        normals: &[Vector3<f64>],
        interp: &[Interp],
        n_basis: usize,
    ) -> Self {
        let table = Erfcx::get();
        let (rc2, eps2) = (r_cut * r_cut, eps * eps);
        Self::build(cells, targets, interp, n_basis, |r, r2, s| {
            if r2 >= rc2 || r2 <= eps2 {
                return None;
            }
            let rn = r2.sqrt();
            let (erfc, e) = erfc_and_gauss(table, xi * rn);
            let (a, b) = stresslet_ab(xi, rn, erfc, e);
            let n = normals[s];
            let n = [n.x, n.y, n.z];
            let rdn = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
            let (brn, arn) = (b * rdn, a * rdn);
            Some(std::array::from_fn(|i| {
                let (p, q) = (i / 3, i % 3);
                brn * r[p] * r[q] + a * (r[p] * n[q] + n[p] * r[q]) + if p == q { arn } else { 0.0 }
            }))
        })
    }
}
