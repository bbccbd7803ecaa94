//! Single-layer potential `1/(8 pi) Int_S G(x_i, y) . q(y) dS_y` at the vertices, with singularity removal.
//!
//! Quadrature: the 7-point Gauss rule with `q` interpolated linearly on each flat triangle,
//! summed over all nodes by the vectorised [`stokeslet_sum`]. Singularity removal:
//! 1. the normal part `alpha = q(x_i) . n(x_i)` is subtracted through
//!    `Int_S G(x, y) . n(y) dS_y = 0` for `x` on `S` (Pozrikidis 1992, ch. 6; the identity
//!    is the zero flux of a uniform pressure), so that only the tangential part of `q`
//!    leaves a `1/r` singularity;
//! 2. on the triangles touching `x_i` the 7-point contribution is replaced (a local
//!    correction after the vectorised sum) by a Duffy rule ([`super::quadrature::duffy`]) that
//!    integrates the remaining `1/r` singularity to near machine precision.

use nalgebra::Vector3;
use rayon::prelude::*;

use super::kernels::{stokeslet, stokeslet_sum, tiled_sums, SourceChunk, LANES};
use super::near_field::NearField;
use super::quadrature::{duffy, TriangleNode};
use super::surface::{Surface, NODES_PER_TRIANGLE};

/// Single-layer operator on one surface.
#[derive(Debug, Clone)]
pub struct SingleLayer<'a> {
    surface: &'a Surface,
    duffy: Vec<TriangleNode>,
    subtract_normal: bool,
    near: Option<&'a NearField>,
}

impl<'a> SingleLayer<'a> {
    /// `duffy_nodes = (n_s, n_t)` Gauss-Legendre points of the Duffy rule; `subtract_normal`
    /// switches the `Int G . n dS = 0` subtraction.
    pub fn new(surface: &'a Surface, duffy_nodes: (usize, usize), subtract_normal: bool) -> Self {
        Self { surface, duffy: duffy(duffy_nodes.0.max(1), duffy_nodes.1.max(1)), subtract_normal, near: None }
    }

    /// Add the near-singular correction of the non-touching triangles close to each target ([`NearField`], built on the same surface).
    pub fn with_near_field(mut self, near: &'a NearField) -> Self {
        self.near = Some(near);
        self
    }

    /// `v_i = 1/(8 pi) Int_S G(x_i, y) . q(y) dS_y` for the vertex field `q` (Pa -> Pa um;
    /// divide by the viscosity in Pa s to get um/s). Parallel over vertices (rayon).
    pub fn apply(&self, q: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let s = self.surface;
        assert_eq!(q.len(), s.n_vertices(), "one density per vertex");
        let chunks = s.chunks_with_density(q, true);
        let scale = 1.0 / (8.0 * std::f64::consts::PI);
        let alpha: Vec<f64> = if self.subtract_normal {
            q.iter().zip(&s.vertex_normals).map(|(q, n)| q.dot(n)).collect()
        } else {
            vec![0.0; q.len()]
        };
        let mut out = vec![Vector3::zeros(); s.n_vertices()];
        tiled_sums(&chunks, &mut out, |i, tile| stokeslet_sum(&s.vertices[i], alpha[i], tile));
        if let Some(near) = self.near.filter(|n| !n.is_empty()) {
            out.iter_mut().zip(near.single_layer(q, &alpha)).for_each(|(o, c)| *o += c);
        }
        out.par_iter_mut().with_min_len(16).enumerate().for_each(|(i, o)| {
            *o = (*o + self.touching_correction(i, alpha[i], q, &chunks)) * scale;
        });
        out
    }

    /// Duffy integral minus the 7-point sum over the triangles incident to vertex `i`,
    /// for the density `q - alpha n_T`.
    fn touching_correction(
        &self,
        i: usize,
        alpha: f64,
        q: &[Vector3<f64>],
        chunks: &[SourceChunk],
    ) -> Vector3<f64> {
        let s = self.surface;
        let x = s.vertices[i];
        let mut corr = Vector3::zeros();
        for inc in s.incident(i) {
            let t = inc.triangle;
            let tri = s.triangles[t];
            let k = inc.corner;
            let (ia, ib, ic) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let (a, b, c) = (s.vertices[ia], s.vertices[ib], s.vertices[ic]);
            let n_t = s.triangle_normals[t];
            let area = s.triangle_areas[t];
            // Remove what the vectorised sum added for this triangle (same node values).
            for node in 0..NODES_PER_TRIANGLE {
                let p = NODES_PER_TRIANGLE * t + node;
                let (ch, l) = (&chunks[p / LANES], p % LANES);
                let y = Vector3::new(ch.x[l], ch.y[l], ch.z[l]);
                let f = Vector3::new(ch.dx[l], ch.dy[l], ch.dz[l]) - Vector3::new(ch.nx[l], ch.ny[l], ch.nz[l]) * alpha;
                corr -= stokeslet(&(x - y), &f);
            }
            // Add the Duffy rule with the singular vertex at corner `a = x`.
            let (qa, qb, qc) = (q[ia] - n_t * alpha, q[ib] - n_t * alpha, q[ic] - n_t * alpha);
            for node in &self.duffy {
                let [la, lb, lc] = node.bary;
                // r = x - y = -(lb (b - a) + lc (c - a)): exact even very close to the vertex.
                let r = -((b - a) * lb + (c - a) * lc);
                let f = (qa * la + qb * lb + qc * lc) * (node.weight * area);
                corr += stokeslet(&r, &f);
            }
        }
        corr
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bim::surface::Surface;
    use crate::mesh::sphere;


    /// A uniform force density on a sphere: `1/(8 pi) Int G . e dS = (2 a / 3) e` at every
    /// point of the sphere (the rigid sphere of Stokes: `F = 4 pi a^2 e = 6 pi mu a U`).
    /// Without the normal subtraction (tangential singularity handled by Duffy alone) and with it.
    #[test]
    fn uniform_density_on_sphere_gives_stokes_velocity() {
        let a = 2.0;
        let mut errs = Vec::new();
        for level in [2, 3, 4] {
            let s = Surface::new(&sphere(level, a)).unwrap();
            let e = Vector3::new(0.3, -0.5, 0.8);
            let q = vec![e; s.n_vertices()];
            for subtract in [false, true] {
                let v = SingleLayer::new(&s, (3, 8), subtract).apply(&q);
                let exact = e * (2.0 * a / 3.0);
                let err = v.iter().map(|v| (v - exact).norm()).fold(0.0, f64::max) / exact.norm();
                errs.push((level, subtract, err));
            }
        }
        eprintln!("uniform density, max relative error (level, subtract, err): {errs:?}");
        // Flat triangles make an O(h^2) geometric error: 2048 triangles (h ~ 0.08 a) gives < 1%.
        for &(level, _, err) in &errs {
            if level == 4 {
                assert!(err < 1e-2, "{errs:?}");
            }
        }
        // Second-order convergence: each level (h/2) divides the error by about 4 (at least 3).
        for w in errs.chunks(2).collect::<Vec<_>>().windows(2) {
            for (coarse, fine) in w[0].iter().zip(w[1]) {
                assert!(coarse.2 / fine.2 > 3.0, "{errs:?}");
            }
        }
    }

    /// After the Duffy map the integrand is linear in the radial variable `s` (the `1/s` of the
    /// Stokeslet cancels the Jacobian `s`, the density is linear), so one radial Gauss point is
    /// exact: the default rule (1 x 10) agrees with a (4 x 20) rule to the angular error (~1e-9).
    #[test]
    fn duffy_default_rule_is_converged() {
        let s = Surface::new(&sphere(3, 2.0)).unwrap();
        let q: Vec<_> = s.vertices.iter().map(|x| Vector3::new(x.y.sin(), 1.0 + x.z * x.x, 0.3 * x.x)).collect();
        let coarse = SingleLayer::new(&s, crate::bim::BimOptions::default().duffy_nodes, true).apply(&q);
        let fine = SingleLayer::new(&s, (4, 20), true).apply(&q);
        let scale = fine.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let diff = coarse.iter().zip(&fine).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        assert!(diff < 1e-8 * scale, "{diff} vs {scale}");
    }

    /// `Int_S G(x, y) . n(y) dS_y = 0` for x on any closed surface (here the polyhedron itself,
    /// with its flat-triangle normals): the discrete sum, 7-point rule plus Duffy on the
    /// touching triangles, converges to zero. Without the near-field correction what remains
    /// is the near-singular error of the 7-point rule on the next rings (a 1/r kernel at
    /// distance ~h: first order); the adaptive rule of [`super::near_field`], applied to the next
    /// ring too ([`NearFieldOptions::with_next_ring`]), removes most of it.
    #[test]
    fn stokeslet_times_normal_integrates_to_zero() {
        use crate::bim::near_field::{NearField, NearFieldOptions};
        let a = 1.0;
        let mut errs = Vec::new();
        let mut errs_near = Vec::new();
        for level in [2, 3, 4] {
            let s = Surface::new(&sphere(level, a)).unwrap();
            let sl = SingleLayer::new(&s, (3, 8), true);
            let zero = vec![Vector3::zeros(); s.n_vertices()];
            // Density 0 with alpha = -1 integrates G . n_T (see `stokeslet_sum`).
            let chunks = s.chunks_with_density(&zero, true);
            let near = NearField::new(&s, &NearFieldOptions::with_next_ring()).single_layer(&zero, &vec![-1.0; s.n_vertices()]);
            let (mut err, mut err_near) = (0.0f64, 0.0f64);
            for i in 0..s.n_vertices() {
                let v = stokeslet_sum(&s.vertices[i], -1.0, &chunks) + sl.touching_correction(i, -1.0, &zero, &chunks);
                err = err.max(v.norm() / (8.0 * std::f64::consts::PI));
                err_near = err_near.max((v + near[i]).norm() / (8.0 * std::f64::consts::PI));
            }
            errs.push(err);
            errs_near.push(err_near);
        }
        eprintln!("Int G.n dS / (8 pi a), levels 2,3,4: 7-point {errs:?}, with the near field {errs_near:?}");
        // Measured: 1.3e-5, 7.6e-6, 3.9e-6 (about first order: the 7-point rule on the
        // neighbours of the touching triangles sees a 1/r kernel at distance ~h).
        assert!(errs[2] < 1e-5, "{errs:?}");
        assert!(errs[0] / errs[1] > 1.5 && errs[1] / errs[2] > 1.5, "{errs:?}");
        // With the near field (measured: 8.7e-8, 6.5e-8, 2.4e-8) at least 100 times smaller.
        for (e, n) in errs.iter().zip(&errs_near) {
            assert!(n * 100.0 < *e, "{errs:?} {errs_near:?}");
        }
    }
}
