//! The dense periodic single-layer operator of the channel wall, assembled once (column by column with the spectral-Ewald sums, using the translation symmetry of the mesh) and LU-factorised once with faer.
//!
//! For the linear (hat-function) interpolation of a nodal wall traction `q` (Pa) on the flat
//! wall triangles, collocated at the wall vertices `x_i`:
//!
//! ```text
//! (S q)_i = 1/(8 pi) Int_W G_per(x_i - y) . q(y) dS_y        (Pa um; divide by mu for um/s)
//! ```
//!
//! with `G_per` the triply periodic Stokeslet of [`crate::ewald`] (box `L_x x (L_y + 2 gap) x
//! (L_z + 2 gap)`, `k = 0` left out). Quadrature: the 7-point Gauss rule on every triangle, and on
//! the six triangles touching `x_i` the free-space part `G` is integrated by the Duffy rule
//! instead (as in [`crate::bim::single_layer`]); the periodic remainder `G_per - G` is smooth
//! there and stays with the 7-point rule.
//!
//! Assembly cost: column `(j, c)` is one Ewald sum with the 42 quadrature nodes of the six
//! triangles around vertex `j` as sources (force `w_k A_t phi_j(y_k) e_c`) and all wall vertices
//! as targets. The mesh is invariant under a shift by two rings along x, so only the columns of
//! the vertices of rings 0 and 1 are computed (`6 n_s` Ewald sums instead of `3 n_s n_x`); the
//! others are the same columns with the target rings rotated. Then `O(N)` Duffy corrections.
//! Factorisation: partial-pivoting LU (the collocation matrix is not exactly symmetric), `2/3 (3N)^3` flops.

use std::time::Instant;

use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::Mat;
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use super::mesh::ChannelMesh;
use super::ChannelError;
use crate::bim::quadrature::{duffy, gauss7};
use crate::ewald::PeriodicStokes;

/// The free-space Stokeslet as a matrix: `G(r) = I/|r| + r r^T/|r|^3`.
pub fn stokeslet_matrix(r: &Vector3<f64>) -> Matrix3<f64> {
    let ir = 1.0 / r.norm();
    Matrix3::identity() * ir + r * r.transpose() * (ir * ir * ir)
}

/// Quadrature nodes of the wall: position (um) and `w_k A_t` (um^2) for every triangle, with the
/// vertex indices and barycentric weights the nodal density is interpolated with.
#[derive(Debug, Clone)]
pub struct WallNodes {
    pub positions: Vec<Vector3<f64>>,
    pub weights: Vec<f64>,
    /// `(vertex, barycentric)` of the three corners of the node's triangle.
    pub interp: Vec<[(usize, f64); 3]>,
}

impl WallNodes {
    /// Consecutive nodes of one sub-triangle (the 7-point rule), which all interpolate from the
    /// same parent triangle's vertices: the groups of the grouped real-space builds
    /// ([`crate::ewald::PeriodicStokes::stokeslet_real_blocks_grouped`]).
    pub const PER_SUB_TRIANGLE: usize = 7;

    pub fn new(mesh: &ChannelMesh) -> Self {
        Self::refined(mesh, 0)
    }

    /// The 7-point rule on each of the `4^level` sub-triangles of every wall triangle (midpoint
    /// subdivision), with the density still interpolated linearly on the parent triangle: the same
    /// discrete single layer, integrated accurately closer to the wall (a 1/r kernel at distance
    /// `d` needs sub-triangles smaller than ~`d`).
    pub fn refined(mesh: &ChannelMesh, level: usize) -> Self {
        let base = gauss7();
        debug_assert_eq!(base.len(), Self::PER_SUB_TRIANGLE);
        // Sub-triangles of the reference triangle in barycentric coordinates.
        let mut subs: Vec<[[f64; 3]; 3]> =
            vec![[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]];
        for _ in 0..level {
            let mut next = Vec::with_capacity(4 * subs.len());
            for [a, b, c] in subs {
                let mid = |p: [f64; 3], q: [f64; 3]| {
                    [
                        0.5 * (p[0] + q[0]),
                        0.5 * (p[1] + q[1]),
                        0.5 * (p[2] + q[2]),
                    ]
                };
                let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
                next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            }
            subs = next;
        }
        let scale = 1.0 / subs.len() as f64;
        let rule: Vec<crate::bim::quadrature::TriangleNode> = subs
            .iter()
            .flat_map(|[a, b, c]| {
                base.iter().map(move |n| {
                    let l = n.bary;
                    crate::bim::quadrature::TriangleNode {
                        bary: [0, 1, 2].map(|d| a[d] * l[0] + b[d] * l[1] + c[d] * l[2]),
                        weight: n.weight * scale,
                    }
                })
            })
            .collect();
        let nt = mesh.triangles.len();
        let np = rule.len() * nt;
        let mut me = Self {
            positions: Vec::with_capacity(np),
            weights: Vec::with_capacity(np),
            interp: Vec::with_capacity(np),
        };
        for t in 0..nt {
            let c = mesh.corners(t);
            let tri = mesh.triangles[t];
            for node in &rule {
                let [l0, l1, l2] = node.bary;
                me.positions.push(c[0] * l0 + c[1] * l1 + c[2] * l2);
                me.weights.push(node.weight * mesh.triangle_areas[t]);
                me.interp.push([(tri[0], l0), (tri[1], l1), (tri[2], l2)]);
            }
        }
        me
    }

    /// Weighted node forces `w_k A_t q(y_k)` (Pa um^2) of the nodal density `q` (Pa).
    pub fn forces(&self, q: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        self.interp
            .iter()
            .zip(&self.weights)
            .map(|(ip, w)| {
                (q[ip[0].0] * ip[0].1 + q[ip[1].0] * ip[1].1 + q[ip[2].0] * ip[2].1) * *w
            })
            .collect()
    }
}

/// Assembled and factorised wall operator `S` (see the module docs).
pub struct WallOperator {
    /// `S` (Pa um per Pa), row/column `3 i + c`.
    pub matrix: Mat<f64>,
    lu: PartialPivLu<f64>,
    pub nodes: WallNodes,
    /// Wall time of the assembly and of the factorisation (s).
    pub assembly_seconds: f64,
    pub factor_seconds: f64,
    /// Ewald sums used in the assembly.
    pub ewald_sums: usize,
}

impl std::fmt::Debug for WallOperator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "WallOperator({} x {})",
            self.matrix.nrows(),
            self.matrix.ncols()
        )
    }
}

impl WallOperator {
    /// Assemble `S` on `mesh` with the periodic sums `ewald` (whose box must contain the channel
    /// cross-section) and the Duffy rule `duffy_nodes = (n_s, n_t)`, then factorise it.
    /// `refine`: the regular quadrature of the matrix uses [`WallNodes::refined`] at this level
    /// (0: the 7-point rule per triangle; 1: on 4 sub-triangles), which sharpens the
    /// near-singular integrals over the neighbours of the touching triangles.
    pub fn new(
        mesh: &ChannelMesh,
        ewald: &PeriodicStokes,
        duffy_nodes: (usize, usize),
        refine: usize,
    ) -> Result<Self, ChannelError> {
        let t0 = Instant::now();
        let (n_s, n_x) = (mesh.n_s, mesh.n_x);
        let nv = mesh.n_vertices();
        let n = 3 * nv;
        let nodes = WallNodes::refined(mesh, refine);
        let npt = nodes.positions.len() / mesh.triangles.len();
        let scale = 1.0 / (8.0 * std::f64::consts::PI);
        // Base columns: vertices of rings 0 and 1, three components each.
        let base: Vec<(usize, usize)> = (0..2 * n_s)
            .flat_map(|j| (0..3).map(move |c| (j, c)))
            .collect();
        let columns: Vec<Result<Vec<Vector3<f64>>, ChannelError>> = base
            .par_iter()
            .map(|&(j, c)| {
                let mut src = Vec::with_capacity(6 * npt);
                let mut f = Vec::with_capacity(6 * npt);
                for &(t, corner) in &mesh.incident[j] {
                    for p in npt * t..npt * (t + 1) {
                        src.push(nodes.positions[p]);
                        let mut e = Vector3::zeros();
                        e[c] = nodes.weights[p] * nodes.interp[p][corner].1;
                        f.push(e);
                    }
                }
                let mut out = vec![Vector3::zeros(); nv];
                ewald.stokeslet(&mesh.vertices, &src, &f, &mut out)?;
                Ok(out)
            })
            .collect();
        let mut matrix = Mat::<f64>::zeros(n, n);
        for (b, col) in base.iter().zip(columns) {
            let col = col?;
            let (j0, c) = *b;
            let (k0, js) = (j0 / n_s, j0 % n_s);
            for shift in (0..n_x).step_by(2) {
                let j = ((k0 + shift) % n_x) * n_s + js;
                let dst = matrix.col_as_slice_mut(3 * j + c);
                for kt in 0..n_x {
                    let src_ring = (kt + n_x - shift) % n_x;
                    for jt in 0..n_s {
                        let v = col[src_ring * n_s + jt];
                        let row = 3 * (kt * n_s + jt);
                        dst[row] = v.x * scale;
                        dst[row + 1] = v.y * scale;
                        dst[row + 2] = v.z * scale;
                    }
                }
            }
        }
        // Touching triangles: replace the 7-point free-space part by the Duffy rule.
        let duffy_rule = duffy(duffy_nodes.0.max(1), duffy_nodes.1.max(1));
        let corrections: Vec<Vec<(usize, Matrix3<f64>)>> = (0..nv)
            .into_par_iter()
            .map(|i| {
                let mut out = Vec::with_capacity(18);
                for &(t, k) in &mesh.incident[i] {
                    let c = mesh.corners(t);
                    let tri = mesh.triangles[t];
                    let area = mesh.triangle_areas[t];
                    let x = c[k];
                    let mut blocks = [Matrix3::zeros(); 3];
                    for p in npt * t..npt * (t + 1) {
                        let g = stokeslet_matrix(&(x - nodes.positions[p])) * nodes.weights[p];
                        for (blk, (_, l)) in blocks.iter_mut().zip(&nodes.interp[p]) {
                            *blk -= g * *l;
                        }
                    }
                    let (a, b, cc) = (c[k], c[(k + 1) % 3], c[(k + 2) % 3]);
                    for node in &duffy_rule {
                        let [la, lb, lc] = node.bary;
                        let r = -((b - a) * lb + (cc - a) * lc);
                        let g = stokeslet_matrix(&r) * (node.weight * area);
                        blocks[k] += g * la;
                        blocks[(k + 1) % 3] += g * lb;
                        blocks[(k + 2) % 3] += g * lc;
                    }
                    for m in 0..3 {
                        out.push((tri[m], blocks[m] * scale));
                    }
                }
                out
            })
            .collect();
        for (i, blocks) in corrections.iter().enumerate() {
            for (j, blk) in blocks {
                for a in 0..3 {
                    for b in 0..3 {
                        matrix[(3 * i + a, 3 * j + b)] += blk[(a, b)];
                    }
                }
            }
        }
        let assembly_seconds = t0.elapsed().as_secs_f64();
        if let Some(p) = (0..n).find(|&p| !matrix.col_as_slice(p).iter().all(|v| v.is_finite())) {
            return Err(ChannelError::NonFinite {
                what: "wall operator column",
                index: p,
            });
        }
        let t1 = Instant::now();
        let lu = matrix.partial_piv_lu();
        let factor_seconds = t1.elapsed().as_secs_f64();
        let me = Self {
            matrix,
            lu,
            nodes,
            assembly_seconds,
            factor_seconds,
            ewald_sums: base.len(),
        };
        // A singular factor shows up as non-finite solutions.
        let probe = me.solve(&vec![Vector3::new(1.0, 0.5, -0.25); nv]);
        if !probe.iter().all(|v| v.iter().all(|c| c.is_finite())) {
            return Err(ChannelError::SingularWallOperator { n });
        }
        Ok(me)
    }

    /// Number of wall vertices.
    pub fn n_vertices(&self) -> usize {
        self.matrix.nrows() / 3
    }

    /// `S q` (Pa um) for the nodal traction `q` (Pa).
    pub fn apply(&self, q: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let x = Mat::from_fn(self.matrix.nrows(), 1, |r, _| q[r / 3][r % 3]);
        let y = &self.matrix * &x;
        (0..self.n_vertices())
            .map(|i| Vector3::new(y[(3 * i, 0)], y[(3 * i + 1, 0)], y[(3 * i + 2, 0)]))
            .collect()
    }

    /// `S^-1 v` (Pa) for `v` in Pa um, by the stored LU factors.
    pub fn solve(&self, v: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut x = Mat::from_fn(self.matrix.nrows(), 1, |r, _| v[r / 3][r % 3]);
        self.lu.solve_in_place(&mut x);
        (0..self.n_vertices())
            .map(|i| Vector3::new(x[(3 * i, 0)], x[(3 * i + 1, 0)], x[(3 * i + 2, 0)]))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::channel::{ChannelGeometry, ChannelMesh};

    /// Refined nodes integrate the same linear interpolant: weights sum to the wall area, and the
    /// integral of `q(x) = x_i` (interpolated) is the same at every refinement level (exactly:
    /// the interpolant is linear on each parent triangle).
    #[test]
    fn refined_nodes_integrate_the_same_interpolant() {
        let mesh = ChannelMesh::new(ChannelGeometry::default(), 12, 8).unwrap();
        let q: Vec<Vector3<f64>> = mesh
            .vertices
            .iter()
            .map(|v| Vector3::new(v.y, v.z * v.z, 1.0))
            .collect();
        let mut first = None;
        for level in 0..3 {
            let nodes = WallNodes::refined(&mesh, level);
            assert_eq!(
                nodes.positions.len(),
                7 * mesh.triangles.len() * 4usize.pow(level as u32)
            );
            let w: f64 = nodes.weights.iter().sum();
            assert!((w - mesh.area()).abs() < 1e-10 * mesh.area());
            let total: Vector3<f64> = nodes.forces(&q).iter().sum();
            match first {
                None => first = Some(total),
                Some(t) => assert!((total - t).norm() < 1e-10 * t.norm(), "{total} vs {t}"),
            }
        }
    }
}
