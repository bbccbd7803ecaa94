//! Two-grid preconditioner of the second-kind equation `w - kappa K' w = b`: the equation on a
//! coarser mesh of the same cell, solved exactly, corrects the smooth part of the residual.
//!
//! The double layer `K` is compact on a smooth surface: its eigenvalues far from 0 (the ones
//! that spread the spectrum of `I - kappa K` over [0.35, 1.65] on a thin discocyte at
//! lambda = 5, `solver/README.md`, session 16) belong to smooth fields, which a coarser mesh of
//! the same surface represents, while on rough fields `K` is small and `I - kappa K ~ I`. So
//! (Atkinson, *The numerical solution of integral equations of the second kind*, CUP 1997,
//! sec. 6.3, the two-grid iteration of Atkinson and Brakhage; here as a right preconditioner of
//! GMRES instead of a stationary iteration)
//!
//! ```text
//! P^-1 v = v + I_c^f [ (I - kappa K'_c)^-1 - I ] R_f^c v
//! ```
//!
//! with `K'_c` the same discrete operator (7-point rule, subtraction of `u(x)`, the same
//! Wielandt deflation of the rigid-body modes, [`super::deflation`]) on the coarse mesh,
//! assembled as a dense `3 n_c x 3 n_c` matrix and factorised (faer's partial-pivoting LU);
//! `I_c^f` the linear interpolation of the subdivision (a midpoint takes the mean of its edge's
//! two ends, level by level) and `R_f^c` its area-weighted adjoint (`R = A_c^-1 I^T A_f`, `A`
//! the vertex areas), so that `R I = I` on coarse fields up to the ratio of the area weights.
//! A smooth field is corrected by the coarse inverse, a rough one (`R v ~ 0`) passes unchanged.
//!
//! Only the preconditioner is approximate: GMRES still meets its tolerance on the true
//! operator (right preconditioning keeps the residual it measures, [`crate::gmres`]), so the
//! velocity is the same to the solve's tolerance; the coarse equation leaves out the walls and
//! the periodic images.
//!
//! The coarse mesh is the fine one's first vertices: the generators subdivide an octahedron
//! and number the vertices of each level before the next one's midpoints
//! ([`crate::mesh::octahedron_sphere`], [`crate::mesh::octahedron_sphere_with_parents`]), so a cell at level `L` holds its level `l < L`
//! mesh in vertices `0..4 * 4^l + 2` with the octahedron's level-`l` triangles.

use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::Mat;
use nalgebra::{Matrix3, Vector3};

use super::deflation::Wielandt;
use super::kernels::{stresslet_matrix_sum, SourceChunk, LANES};
use super::surface::{Surface, NODES_PER_TRIANGLE};
use super::BimError;
use crate::mesh::{octahedron_sphere, octahedron_sphere_with_parents, triangle_count, vertex_count, Mesh};

/// The coarse equation of one surface and the transfers to and from it.
#[derive(Debug)]
pub struct TwoGrid {
    /// Vertices of the coarse mesh (the fine mesh's first `n_coarse`).
    n_coarse: usize,
    /// Edge ends of every fine vertex beyond the coarse ones, in creation order.
    parents: Vec<[usize; 2]>,
    /// Vertex areas of the fine and coarse surfaces (um^2).
    fine_areas: Vec<f64>,
    coarse_areas: Vec<f64>,
    /// `I - kappa K'_c`, factorised in double precision: GMRES's Arnoldi relation assumes one
    /// linear `P^-1`, and single-precision rounding (~1e-7) would show in the true residual.
    lu: PartialPivLu<f64>,
}

impl TwoGrid {
    /// The two-grid preconditioner of `w - kappa K' w` on `surface` (a level-`L` octahedron
    /// subdivision), with the coarse equation at `coarse_level < L`; `deflate_rigid_body` as in
    /// the fine equation. `None` when the surface is not such a subdivision (another mesh) or
    /// `coarse_level` is not below its level.
    pub fn new(surface: &Surface, kappa: f64, coarse_level: usize, deflate_rigid_body: bool) -> Result<Option<Self>, BimError> {
        // the level of an octahedron subdivision numbered as the generators number it
        let Some(level) = (0..8).find(|&l| triangle_count(l) == surface.triangles.len()) else { return Ok(None) };
        if coarse_level >= level {
            return Ok(None);
        }
        let (fine, parents) = octahedron_sphere_with_parents(level);
        if surface.n_vertices() != vertex_count(level) || surface.triangles != fine.triangles {
            return Ok(None);
        }
        let n_coarse = vertex_count(coarse_level);
        let coarse_mesh = Mesh { vertices: surface.vertices[..n_coarse].to_vec(), triangles: octahedron_sphere(coarse_level).triangles };
        let coarse = Surface::new(&coarse_mesh)?;
        let n = 3 * n_coarse;
        let mut m = double_layer_matrix(&coarse);
        if deflate_rigid_body {
            // K' = K - mu phi <psi, .>_S: a rank-one update per term, (A psi) the row vector
            for t in Wielandt::new(&coarse, true, false).terms {
                let row: Vec<f64> = t.psi.iter().zip(&coarse.vertex_areas).flat_map(|(p, a)| [p.x * a, p.y * a, p.z * a]).collect();
                for (r, out) in m.chunks_exact_mut(n).enumerate() {
                    let c = t.eigenvalue * t.phi[r / 3][r % 3];
                    out.iter_mut().zip(&row).for_each(|(o, w)| *o -= c * w);
                }
            }
        }
        // I - kappa K'_c
        let a = Mat::<f64>::from_fn(n, n, |r, c| f64::from(u8::from(r == c)) - kappa * m[r * n + c]);
        let parents = parents[n_coarse - 6..].to_vec();
        Ok(Some(Self { n_coarse, parents, fine_areas: surface.vertex_areas.clone(), coarse_areas: coarse.vertex_areas.clone(), lu: a.partial_piv_lu() }))
    }

    /// `v <- P^-1 v` (see the module documentation).
    pub fn apply(&self, v: &mut [Vector3<f64>]) {
        let nc = self.n_coarse;
        // R v = A_c^-1 I^T A_f v: the adjoint of the interpolation, finest vertices first
        let mut r: Vec<Vector3<f64>> = v.iter().zip(&self.fine_areas).map(|(v, a)| v * *a).collect();
        for (k, [a, b]) in self.parents.iter().enumerate().rev() {
            let x = r[nc + k] * 0.5;
            r[*a] += x;
            r[*b] += x;
        }
        r.truncate(nc);
        r.iter_mut().zip(&self.coarse_areas).for_each(|(r, a)| *r /= *a);
        // d = (I - kappa K'_c)^-1 R v - R v
        let mut x = Mat::from_fn(3 * nc, 1, |i, _| r[i / 3][i % 3]);
        self.lu.solve_in_place(&mut x);
        let mut d: Vec<Vector3<f64>> = (0..nc).map(|i| Vector3::new(x[(3 * i, 0)], x[(3 * i + 1, 0)], x[(3 * i + 2, 0)]) - r[i]).collect();
        // v += I d: coarse vertices take d, every midpoint the mean of its edge's ends
        d.reserve(self.parents.len());
        for [a, b] in &self.parents {
            let m = (d[*a] + d[*b]) * 0.5;
            d.push(m);
        }
        v.iter_mut().zip(&d).for_each(|(v, d)| *v += d);
    }
}

/// The discrete double layer `K` of [`super::double_layer::DoubleLayer`] without the near-field
/// correction as a dense row-major matrix (row `3 i + r`, column `3 j + k`, `3 n` each):
/// `K[u](x_i) = 1/(4 pi) sum_p 6 ((u(y_p) - u_i) . r)(r . n_p) r / |r|^5 - u_i`, `u(y_p)` the
/// linear interpolation of the vertex values, `u(y_p) = sum_j phi_j(y_p) u_j`. So block `(i, j)`
/// is `1/(4 pi)` times the stresslet matrix sum ([`stresslet_matrix_sum`], the kernel of the
/// periodic double layer's self term) at `x_i` over the nodes of `j`'s triangles, each weighted
/// normal times `phi_j` there (`hat_weighted_nodes`); the diagonal block also loses the row's
/// sum of blocks (the `- u_i` in the integrand) and the identity. Each node enters the three
/// blocks of its triangle's corners, so the kernel runs three times per node; at level 2 (66
/// vertices) this took 0.5 ms against 1.5 ms for the former per-node loop, which had its own copy
/// of the kernel. The entries carry the kernel's rounding: with the portable kernel they matched
/// that copy's to 3e-15, with the AVX-512 one (`1/sqrt` to 6e-13) to 2e-13 (entries up to 0.63).
pub fn double_layer_matrix(surface: &Surface) -> Vec<f64> {
    let n = surface.n_vertices();
    let dim = 3 * n;
    let scale = 1.0 / (4.0 * std::f64::consts::PI);
    let sources: Vec<Vec<SourceChunk>> = (0..n).map(|j| hat_weighted_nodes(surface, j)).collect();
    let mut m = vec![0.0; dim * dim];
    for (i, (x, rows)) in surface.vertices.iter().zip(m.chunks_exact_mut(3 * dim)).enumerate() {
        let mut total = Matrix3::zeros();
        for (j, chunks) in sources.iter().enumerate() {
            let b = stresslet_matrix_sum(x, chunks) * scale;
            total += b;
            for r in 0..3 {
                rows[r * dim + 3 * j..r * dim + 3 * j + 3].copy_from_slice(&[b[(r, 0)], b[(r, 1)], b[(r, 2)]]);
            }
        }
        let d = total + Matrix3::identity();
        for r in 0..3 {
            for k in 0..3 {
                rows[r * dim + 3 * i + k] -= d[(r, k)];
            }
        }
    }
    m
}

/// The quadrature nodes of the triangles at vertex `j` in lanes ([`Surface::node`]), each
/// `weight * area * normal` times `j`'s interpolation weight at the node (its barycentric
/// coordinate there), the density lanes zero; padded to whole chunks.
fn hat_weighted_nodes(surface: &Surface, j: usize) -> Vec<SourceChunk> {
    let incident = surface.incident(j);
    let mut chunks = vec![SourceChunk::padding(); (NODES_PER_TRIANGLE * incident.len()).div_ceil(LANES)];
    let nodes = incident.iter().flat_map(|c| (0..NODES_PER_TRIANGLE).map(move |k| (c.triangle, c.corner, k)));
    for (p, (t, corner, k)) in nodes.enumerate() {
        let (y, nw) = surface.node(t, k);
        let nw = nw * surface.rule[k].bary[corner];
        let (ch, l) = (&mut chunks[p / LANES], p % LANES);
        (ch.x[l], ch.y[l], ch.z[l]) = (y.x, y.y, y.z);
        (ch.nx[l], ch.ny[l], ch.nz[l]) = (nw.x, nw.y, nw.z);
    }
    chunks
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bim::double_layer::DoubleLayer;
    use crate::mesh::discocyte;

    /// The dense matrix is the operator `DoubleLayer` applies (without the near field).
    #[test]
    fn dense_matrix_is_the_applied_double_layer() {
        let s = Surface::new(&discocyte(2)).unwrap();
        let m = double_layer_matrix(&s);
        let u: Vec<Vector3<f64>> = s.vertices.iter().map(|x| Vector3::new(x.y.sin(), x.z * x.x, 1.0 + x.x)).collect();
        let k = DoubleLayer::new(&s).apply(&u);
        let flat: Vec<f64> = u.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
        for (row, out) in m.chunks_exact(flat.len()).enumerate() {
            let y: f64 = out.iter().zip(&flat).map(|(a, b)| a * b).sum();
            let k = k[row / 3][row % 3];
            assert!((y - k).abs() < 1e-12 * (1.0 + k.abs()), "row {row}: {y} vs {k}");
        }
    }

    /// The free-space second-kind equation of a discocyte at lambda = 5 (512 triangles, the
    /// rigid modes deflated) solved by GMRES with and without the level-2 two-grid
    /// preconditioner: the same solution to the tolerance (1e-10), in at most 0.8 of the
    /// iterations (measured 12 against 16, at 2048 triangles too; in the channel, where the
    /// fine equation also has walls and near-field corrections, 0.66-0.83).
    #[test]
    fn preconditioned_solve_has_the_same_solution_in_fewer_iterations() {
        use crate::gmres::{gmres, gmres_preconditioned, GmresOptions, Tolerance};
        use std::convert::Infallible;
        let s = Surface::new(&discocyte(3)).unwrap();
        let kappa = -2.0 / 3.0;
        let deflation = Wielandt::new(&s, true, false);
        let dl = DoubleLayer::new(&s);
        // w - kappa K' w, K' = K - mu phi <psi, .>
        let op = |w: &[Vector3<f64>], y: &mut [Vector3<f64>]| -> Result<(), Infallible> {
            let mut k = dl.apply(w);
            deflation.apply(&s, w, &mut k);
            y.iter_mut().zip(w).zip(&k).for_each(|((y, w), k)| *y = w - k * kappa);
            Ok(())
        };
        let b: Vec<Vector3<f64>> = s.vertices.iter().map(|x| Vector3::new(1.0 + 0.3 * x.y * x.y, 0.2 * x.x * x.z, (0.5 * x.x).sin())).collect();
        let opts = GmresOptions { tolerance: Tolerance::Relative(1e-10), restart: 60, max_iterations: 200 };
        let mut plain = vec![Vector3::zeros(); b.len()];
        let p = gmres(op, &b, &mut plain, &opts).unwrap();
        let tg = TwoGrid::new(&s, kappa, 2, true).unwrap().expect("a level-3 subdivision");
        let mut pre = vec![Vector3::zeros(); b.len()];
        let q = gmres_preconditioned(op, |v| tg.apply(v), &b, &mut pre, &opts).unwrap();
        assert!(p.converged() && q.converged(), "{p:?} {q:?}");
        let d = pre.iter().zip(&plain).map(|(a, b)| (a - b).norm_squared()).sum::<f64>().sqrt() / plain.iter().map(|a| a.norm_squared()).sum::<f64>().sqrt();
        eprintln!("iterations {} plain, {} two-grid; solutions differ by {d:e}", p.iterations, q.iterations);
        assert!(d < 1e-8, "{d:e}");
        assert!(10 * q.iterations <= 8 * p.iterations, "{} against {}", q.iterations, p.iterations);
    }

    /// Only an octahedron subdivision numbered as the generators number it has its coarse mesh
    /// in its first vertices, and only a coarser level is one.
    #[test]
    fn only_a_finer_subdivision_gets_a_coarse_equation() {
        let fine = discocyte(3);
        let s = Surface::new(&fine).unwrap();
        assert!(TwoGrid::new(&s, 0.5, 2, true).unwrap().is_some());
        assert!(TwoGrid::new(&s, 0.5, 3, true).unwrap().is_none(), "not coarser");
        let mut turned = fine.clone();
        turned.triangles.iter_mut().for_each(|t| t.rotate_left(1));
        turned.triangles.swap(0, 1);
        assert!(TwoGrid::new(&Surface::new(&turned).unwrap(), 0.5, 2, true).unwrap().is_none(), "renumbered triangles");
    }

    /// Without a double layer (`kappa = 0`) the coarse equation is the identity, so the
    /// correction `I [(I - kappa K'_c)^-1 - I] R` vanishes and `P^-1` is the identity to rounding,
    /// whatever the transfers do.
    #[test]
    fn with_no_double_layer_the_preconditioner_is_the_identity() {
        let s = Surface::new(&discocyte(3)).unwrap();
        let tg = TwoGrid::new(&s, 0.0, 2, false).unwrap().unwrap();
        let v0: Vec<Vector3<f64>> = s.vertices.iter().map(|x| Vector3::new(x.x, x.y * x.z, 1.0)).collect();
        let mut v = v0.clone();
        tg.apply(&mut v);
        for (a, b) in v.iter().zip(&v0) {
            assert!((a - b).norm() < 1e-13 * (1.0 + b.norm()), "{a} vs {b}");
        }
    }
}
