//! Double-layer operator `K[u](x_i) = 1/(4 pi) PV Int_S u(y) . T(x_i, y) . n(y) dS_y` at the vertices.
//!
//! With Pozrikidis' stresslet (`r = x - y`, `u . T . n = 6 (u . r)(r . n) r / |r|^5`, see
//! [`super::kernels`]) and the outward normal, `PV Int_S T . n dS = -4 pi I` for `x` on a
//! closed surface (`-8 pi I` inside, `0` outside; Pozrikidis 1992, ch. 2), so
//!
//! ```text
//! K[u](x) = 1/(4 pi) Int_S (u(y) - u(x)) . T(x, y) . n(y) dS_y - u(x)
//! ```
//!
//! and the remaining integrand is bounded. Consequences used elsewhere: rigid-body motions
//! are eigenfunctions with eigenvalue -1 (exactly, also in the discrete operator: a rigid
//! field is linear, so its interpolation is exact, and `(u(y) - u(x)) . r = 0` for
//! `u = U + omega x y`); `n` is a left eigenfunction with eigenvalue +1.
//! On the flat triangles touching `x_i`, `r . n = 0` exactly (the target is a vertex of
//! the plane triangle), so they contribute nothing and need no local correction.

use nalgebra::Vector3;

use super::kernels::{stresslet_sum, tiled_sums};
use super::near_field::NearField;
use super::surface::Surface;

/// Double-layer operator on one surface.
#[derive(Debug, Clone, Copy)]
pub struct DoubleLayer<'a> {
    surface: &'a Surface,
    near: Option<&'a NearField>,
}

impl<'a> DoubleLayer<'a> {
    pub fn new(surface: &'a Surface) -> Self {
        Self { surface, near: None }
    }

    /// Add the near-singular correction of the non-touching triangles close to each target ([`NearField`], built on the same surface).
    pub fn with_near_field(mut self, near: &'a NearField) -> Self {
        self.near = Some(near);
        self
    }

    /// `K[u]` at every vertex (same units as `u`). Parallel over vertices (rayon).
    pub fn apply(&self, u: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut out = vec![Vector3::zeros(); u.len()];
        self.apply_into(u, &mut out);
        out
    }

    /// `K[u]` written into `out` (no allocation besides the interpolated density).
    pub fn apply_into(&self, u: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        let s = self.surface;
        assert_eq!(u.len(), s.n_vertices(), "one velocity per vertex");
        assert_eq!(out.len(), s.n_vertices(), "one output per vertex");
        let chunks = s.chunks_with_density(u, false);
        let scale = 1.0 / (4.0 * std::f64::consts::PI);
        tiled_sums(&chunks, out, |i, tile| stresslet_sum(&s.vertices[i], &u[i], tile));
        if let Some(near) = self.near {
            near.add_double_layer(u, 1.0, out);
        }
        out.iter_mut().zip(u).for_each(|(o, u)| *o = *o * scale - u);
    }

    /// The raw quadrature `Int_S u(y) . T(x, y) . n(y) dS_y` at arbitrary points `x` off the
    /// surface, without subtraction (for tests of the identity: `-8 pi u` inside for uniform `u`, `0` outside).
    pub fn raw_at(&self, u: &[Vector3<f64>], points: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let chunks = self.surface.chunks_with_density(u, false);
        points.iter().map(|x| stresslet_sum(x, &Vector3::zeros(), &chunks)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::sphere;

    /// The identity that fixes the sign convention: `Int_S T . n dS` is `-8 pi I` for a point
    /// inside and `0` outside (the volume integral of a delta function, Pozrikidis 1992 ch. 2).
    #[test]
    fn stresslet_flux_identity_inside_and_outside() {
        let s = Surface::new(&sphere(4, 1.0)).unwrap();
        let dl = DoubleLayer::new(&s);
        for e in [Vector3::x(), Vector3::y(), Vector3::z()] {
            let u = vec![e; s.n_vertices()];
            let inside = dl.raw_at(&u, &[Vector3::new(0.1, -0.2, 0.15), Vector3::zeros()]);
            for v in inside {
                assert!((v + e * 8.0 * std::f64::consts::PI).norm() < 1e-2 * 8.0 * std::f64::consts::PI, "{v}");
            }
            let outside = dl.raw_at(&u, &[Vector3::new(2.0, 1.0, -1.5)]);
            assert!(outside[0].norm() < 1e-3, "{}", outside[0]);
        }
    }

    /// On the surface the principal value is `-4 pi I` (half of the inside value): the raw
    /// quadrature at the vertices converges to it, at first order only (measured relative errors
    /// 0.41, 0.22, 0.11), because the flat touching triangles contribute exactly zero where the curved
    /// surface contributes O(h) and the 7-point rule meets a 1/r integrand on the next ring.
    /// With the opposite sign convention the error would be 2. This is the identity the
    /// subtraction in [`DoubleLayer::apply_into`] uses, which removes that O(h) error.
    #[test]
    fn stresslet_flux_identity_on_the_surface() {
        let four_pi = 4.0 * std::f64::consts::PI;
        let mut errs = Vec::new();
        for level in [2, 3, 4] {
            let s = Surface::new(&sphere(level, 1.5)).unwrap();
            let dl = DoubleLayer::new(&s);
            let mut err: f64 = 0.0;
            for e in [Vector3::x(), Vector3::y(), Vector3::z()] {
                let u = vec![e; s.n_vertices()];
                for v in dl.raw_at(&u, &s.vertices) {
                    err = err.max((v + e * four_pi).norm() / four_pi);
                }
            }
            errs.push(err);
        }
        eprintln!("PV Int T.n dS + 4 pi I at the vertices, levels 2,3,4: {errs:?}");
        assert!(errs[2] < 0.15 && errs[0] / errs[1] > 1.8 && errs[1] / errs[2] > 1.8, "{errs:?}");
    }

    /// Rigid-body motions are eigenfunctions of K with eigenvalue -1 (to rounding).
    #[test]
    fn rigid_body_motion_has_eigenvalue_minus_one() {
        let s = Surface::new(&sphere(3, 1.3)).unwrap();
        let dl = DoubleLayer::new(&s);
        let (uu, om, c) = (Vector3::new(0.3, -1.0, 0.5), Vector3::new(0.7, 0.2, -0.4), Vector3::new(0.1, 0.2, 0.3));
        let u: Vec<_> = s.vertices.iter().map(|x| uu + om.cross(&(x - c))).collect();
        let k = dl.apply(&u);
        for (ki, ui) in k.iter().zip(&u) {
            assert!((ki + ui).norm() < 1e-12, "{ki} vs {ui}");
        }
    }

    /// On a sphere `K[n] = n` (eigenvalue +1, computed in closed form at the pole:
    /// `6 * 2 pi / 3 = 4 pi`); the discrete operator converges to it at second order.
    #[test]
    fn normal_field_on_sphere_has_eigenvalue_plus_one() {
        let mut errs = Vec::new();
        for level in [2, 3, 4] {
            let s = Surface::new(&sphere(level, 2.0)).unwrap();
            let n: Vec<_> = s.vertices.iter().map(|x| x.normalize()).collect();
            let k = DoubleLayer::new(&s).apply(&n);
            let err = k.iter().zip(&n).map(|(k, n)| (k - n).norm()).fold(0.0, f64::max);
            errs.push(err);
        }
        eprintln!("K[n] - n, max error per level 2,3,4: {errs:?}");
        assert!(errs[2] < 1e-2, "{errs:?}");
        assert!(errs[0] / errs[1] > 3.0 && errs[1] / errs[2] > 3.0, "{errs:?}");
    }
}
