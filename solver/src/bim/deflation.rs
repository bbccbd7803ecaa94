//! Wielandt deflation of the double-layer operator: the rigid-body eigenvalue -1 and the flux eigenvalue +1.
//!
//! Wielandt's deflation (Pozrikidis 1992, ch. 4 and 6; RBC3D `ModVelSolver.F90`): for an
//! eigenpair `K phi = mu phi` and any `psi` with `<psi, phi> = 1`, the operator
//! `K' = K - mu phi <psi, .>` has the eigenvalues of `K` with `mu` replaced by 0.
//! The second-kind equation `u - kappa K u = b`, `kappa = (1 - lambda)/(1 + lambda)`, has the
//! eigenvalues `1 - kappa mu_k`; its worst ones are `1 + kappa` at `mu = -1` (rigid-body motions,
//! vanishing as lambda -> inf) and `1 - kappa` at `mu = +1` (vanishing as lambda -> 0).
//! After deflation both become 1.
//!
//! - Rigid-body motions are exact right eigenvectors (also of the discrete operator), so the
//!   solution `w` of `w - kappa K' w = b` gives the solution of the original equation by
//!   `u = w + sum_i c_i phi_i`, `c_i = kappa mu <psi_i, w> / (1 - kappa mu)` ([`Wielandt::recover`]).
//! - For `mu = +1`, `n` is the left eigenvector (`<n, K u> = <n, u>`: the flux of a double-layer
//!   potential), so with `phi = n / <n, n>`, `psi = n` the deflated equation has the same solution
//!   whenever `<n, b> = 0` (true for the exact right-hand side: the single layer and the
//!   background flow carry no flux through a closed surface), and its solution satisfies
//!   `<n, w> = <n, b>`: the net flux of the computed velocity is that of the discrete
//!   right-hand side, zero to discretisation accuracy (not to rounding).

use nalgebra::Vector3;

use super::surface::Surface;

/// One rank-one term `mu phi <psi, .>_S` (`<a, b>_S = sum_i A_i a_i . b_i`).
#[derive(Debug, Clone)]
pub struct WielandtTerm {
    /// The eigenvalue being removed.
    pub eigenvalue: f64,
    pub phi: Vec<Vector3<f64>>,
    pub psi: Vec<Vector3<f64>>,
    /// `phi` is an exact right eigenvector, so [`Wielandt::recover`] can undo the deflation.
    pub right_eigenvector: bool,
}

/// A sum of rank-one deflation terms.
#[derive(Debug, Clone, Default)]
pub struct Wielandt {
    pub terms: Vec<WielandtTerm>,
}

impl Wielandt {
    /// The requested deflations for `surface`.
    pub fn new(surface: &Surface, rigid_body: bool, flux: bool) -> Self {
        let mut terms = Vec::new();
        if rigid_body {
            for phi in rigid_body_modes(surface) {
                terms.push(WielandtTerm { eigenvalue: -1.0, psi: phi.clone(), phi, right_eigenvector: true });
            }
        }
        if flux {
            let n = surface.vertex_normals.clone();
            let nn = surface.inner(&n, &n);
            let phi = n.iter().map(|v| v / nn).collect();
            terms.push(WielandtTerm { eigenvalue: 1.0, phi, psi: n, right_eigenvector: false });
        }
        Self { terms }
    }

    /// `out -= sum_i mu_i phi_i <psi_i, u>_S`, i.e. turns `out = K u` into `K' u`.
    pub fn apply(&self, surface: &Surface, u: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        for t in &self.terms {
            let c = t.eigenvalue * surface.inner(&t.psi, u);
            out.iter_mut().zip(&t.phi).for_each(|(o, p)| *o -= p * c);
        }
    }

    /// Solution of `u - kappa K u = b` from the solution `w` of `w - kappa K' w = b`.
    pub fn recover(&self, surface: &Surface, kappa: f64, w: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut u = w.to_vec();
        for t in self.terms.iter().filter(|t| t.right_eigenvector) {
            let km = kappa * t.eigenvalue;
            let c = km * surface.inner(&t.psi, w) / (1.0 - km);
            u.iter_mut().zip(&t.phi).for_each(|(u, p)| *u += p * c);
        }
        u
    }
}

impl Wielandt {
    /// Inverse of [`Wielandt::recover`]: the deflated unknown `w` whose recovery is `u`
    /// (`<phi_i, u> = <phi_i, w> / (1 - kappa mu)` for orthonormal exact eigenvectors, so
    /// `w = u - sum_i kappa mu phi_i <psi_i, u>`). Used to start GMRES from a velocity guess.
    pub fn deflate_guess(&self, surface: &Surface, kappa: f64, u: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut w = u.to_vec();
        for t in self.terms.iter().filter(|t| t.right_eigenvector) {
            let c = kappa * t.eigenvalue * surface.inner(&t.psi, u);
            w.iter_mut().zip(&t.phi).for_each(|(w, p)| *w -= p * c);
        }
        w
    }
}

/// The six rigid-body motions on the vertices (translations, rotations about the area
/// centroid), orthonormalised in `<., .>_S` by modified Gram-Schmidt (twice, for rounding).
pub fn rigid_body_modes(surface: &Surface) -> Vec<Vec<Vector3<f64>>> {
    let c = surface.centroid();
    let mut modes: Vec<Vec<Vector3<f64>>> = Vec::with_capacity(6);
    for k in 0..6 {
        let e = Vector3::ith(k % 3, 1.0);
        let mut m: Vec<Vector3<f64>> =
            surface.vertices.iter().map(|x| if k < 3 { e } else { e.cross(&(x - c)) }).collect();
        for _ in 0..2 {
            for p in &modes {
                let d = surface.inner(p, &m);
                m.iter_mut().zip(p).for_each(|(m, p)| *m -= p * d);
            }
        }
        let norm = surface.inner(&m, &m).sqrt();
        m.iter_mut().for_each(|v| *v /= norm);
        modes.push(m);
    }
    modes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::sphere;
    use crate::bim::double_layer::DoubleLayer;

    /// `deflate_guess` inverts `recover` (the rigid modes are orthonormal, so the terms decouple).
    #[test]
    fn deflate_guess_inverts_recover() {
        let s = Surface::new(&sphere(2, 1.0)).unwrap();
        let defl = Wielandt::new(&s, true, true);
        let u: Vec<_> = s.vertices.iter().map(|x| Vector3::new(x.y + 0.3, x.z * x.x, 1.0 - x.x)).collect();
        for kappa in [-0.9, -2.0 / 3.0, 0.5] {
            let back = defl.recover(&s, kappa, &defl.deflate_guess(&s, kappa, &u));
            let err = back.iter().zip(&u).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            assert!(err < 1e-13, "kappa {kappa}: {err}");
        }
    }

    #[test]
    fn rigid_modes_are_orthonormal() {
        let mut mesh = sphere(2, 1.0);
        mesh.vertices.iter_mut().for_each(|v| *v += Vector3::new(3.0, -1.0, 2.0)); // off-origin
        let s = Surface::new(&mesh).unwrap();
        let m = rigid_body_modes(&s);
        for i in 0..6 {
            for j in 0..6 {
                let d = s.inner(&m[i], &m[j]);
                assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12, "<{i},{j}> = {d}");
            }
        }
    }

    /// Deflation removes exactly the eigenvalue: `K' phi = 0` for rigid modes, and `<n, K' u> = 0`
    /// up to the discretisation error of `<n, K u> = <n, u>`.
    #[test]
    fn deflated_operator_annihilates_rigid_modes() {
        let s = Surface::new(&sphere(3, 1.0)).unwrap();
        let dl = DoubleLayer::new(&s);
        let defl = Wielandt::new(&s, true, false);
        for phi in rigid_body_modes(&s) {
            let mut k = dl.apply(&phi);
            defl.apply(&s, &phi, &mut k);
            let r = s.inner(&k, &k).sqrt();
            assert!(r < 1e-12, "|K' phi| = {r}");
        }
    }
}
