//! Reference Ewald sums: explicit real-space image sums and explicit reciprocal sums, both truncated where the terms fall below ~1e-17 (slow; for tests and for the self-image constant).
//!
//! For every target `x_i` and source `y_j` (see [`super::split`] for the kernels):
//!
//! ```text
//! u_i = sum_j sum_n G^R(x_i - y_j + n L) f_j  +  (1/V) sum_{k != 0} G^F(k) S(k) exp(i k . x_i),
//! S(k) = sum_j f_j exp(-i k . y_j)
//! ```
//!
//! with the real sum over all lattice shifts `n L` within `r_cut = 6.5/xi`
//! (`erfc(6.5) ~ 4e-20`) and the reciprocal sum over `|k| <= 13 xi`
//! (`(1 + 42.25) exp(-42.25) ~ 2e-17`). The `k = 0` term is left out: the
//! mean velocity over the box is zero and the net force is balanced by a uniform
//! mean pressure gradient (see [`super`]). `k` and `-k` are summed together (half space).

use nalgebra::{Matrix3, Vector3};
use rustfft::num_complex::Complex;

use super::split::{
    fourier_scalar, project, stokeslet_real_reference, stokeslet_real_self, stresslet_bracket, stresslet_real_reference,
    sym_outer,
};
use super::Coincident;

/// `xi r_cut` and `k_cut / (2 xi)` of the reference sums.
const REFERENCE_CUT: f64 = 6.5;

/// A splitting parameter that balances the real and reciprocal work: `xi = sqrt(pi) / V^(1/3)` (1/um).
pub fn balanced_xi(box_len: [f64; 3]) -> f64 {
    std::f64::consts::PI.sqrt() / (box_len[0] * box_len[1] * box_len[2]).cbrt()
}

/// Distance below which a target and a source count as coincident: `1e-12` of the smallest box side (um).
pub fn coincidence_radius(box_len: [f64; 3]) -> f64 {
    1e-12 * box_len.iter().cloned().fold(f64::INFINITY, f64::min)
}

/// Lattice shifts `n L` with `|r0 + n L| < r_cut` possible for any `r0` in the box.
fn shifts(box_len: [f64; 3], r_cut: f64) -> Vec<Vector3<f64>> {
    let n: Vec<i64> = box_len.iter().map(|l| (r_cut / l).ceil() as i64 + 1).collect();
    let mut out = Vec::new();
    for a in -n[0]..=n[0] {
        for b in -n[1]..=n[1] {
            for c in -n[2]..=n[2] {
                out.push(Vector3::new(a as f64 * box_len[0], b as f64 * box_len[1], c as f64 * box_len[2]));
            }
        }
    }
    out
}

/// Half of the reciprocal lattice (one of each `+-k`), `0 < |k| <= k_cut`: `(k, k^2)`.
fn half_k(box_len: [f64; 3], k_cut: f64) -> Vec<([f64; 3], f64)> {
    let tau = 2.0 * std::f64::consts::PI;
    let n: Vec<i64> = box_len.iter().map(|l| (k_cut * l / tau).floor() as i64).collect();
    let mut out = Vec::new();
    for a in 0..=n[0] {
        for b in -n[1]..=n[1] {
            for c in -n[2]..=n[2] {
                let first_nonzero_positive = a > 0 || (a == 0 && (b > 0 || (b == 0 && c > 0)));
                if !first_nonzero_positive {
                    continue;
                }
                let k = [tau * a as f64 / box_len[0], tau * b as f64 / box_len[1], tau * c as f64 / box_len[2]];
                let k2 = k[0] * k[0] + k[1] * k[1] + k[2] * k[2];
                if k2 <= k_cut * k_cut {
                    out.push((k, k2));
                }
            }
        }
    }
    out
}

fn wrap(r: Vector3<f64>, box_len: [f64; 3]) -> Vector3<f64> {
    Vector3::from_fn(|d, _| r[d] - box_len[d] * (r[d] / box_len[d]).round())
}

/// Periodic Stokeslet sum `u_i = sum_j G_per(x_i - y_j) f_j` to ~1e-15 relative, Ewald-split at `xi` (1/um).
///
/// Units: `f` in any force unit, `u` in force / length (the caller divides by `8 pi mu`).
/// A source coincident with a target contributes per `coincident` (see [`Coincident`]).
pub fn stokeslet(
    box_len: [f64; 3],
    xi: f64,
    targets: &[Vector3<f64>],
    sources: &[Vector3<f64>],
    forces: &[Vector3<f64>],
    coincident: Coincident,
) -> Vec<Vector3<f64>> {
    let r_cut = REFERENCE_CUT / xi;
    let eps = coincidence_radius(box_len);
    let images = shifts(box_len, r_cut);
    let s0 = match coincident {
        Coincident::Exclude => self_image_tensor(box_len),
        Coincident::Regular => Matrix3::zeros(),
    };
    let mut out: Vec<Vector3<f64>> = targets
        .iter()
        .map(|x| {
            let mut u = Vector3::zeros();
            for (y, f) in sources.iter().zip(forces) {
                let r0 = wrap(x - y, box_len);
                for s in &images {
                    let r = r0 + s;
                    let rn = r.norm();
                    if rn >= r_cut {
                        continue;
                    }
                    if rn < eps {
                        u += f * stokeslet_real_self(xi) - s0 * f;
                    } else {
                        u += stokeslet_real_reference(xi, &r, f);
                    }
                }
            }
            u
        })
        .collect();
    let volume = box_len[0] * box_len[1] * box_len[2];
    for (k, k2) in half_k(box_len, 2.0 * REFERENCE_CUT * xi) {
        let mut s = [Complex::new(0.0, 0.0); 3];
        for (y, f) in sources.iter().zip(forces) {
            let e = Complex::from_polar(1.0, -(k[0] * y.x + k[1] * y.y + k[2] * y.z));
            for d in 0..3 {
                s[d] += e * f[d];
            }
        }
        let p = project(k, k2, s);
        let c = 2.0 * fourier_scalar(xi, k2) / volume;
        for (x, u) in targets.iter().zip(out.iter_mut()) {
            let e = Complex::from_polar(1.0, k[0] * x.x + k[1] * x.y + k[2] * x.z);
            for d in 0..3 {
                u[d] += c * (p[d] * e).re;
            }
        }
    }
    out
}

/// Periodic stresslet sum `u_i = sum_j u_j . T_per(x_i - y_j) . n_j` to ~1e-15 relative, split at `xi` (1/um).
///
/// `n_j` carries the quadrature weight (um^2) and `T ~ 1/um^2`, so the result has the units of `u`.
/// Coincident pairs contribute nothing (the limit of the odd `T_per - T` at 0 is zero), for either
/// [`Coincident`] choice.
pub fn stresslet(
    box_len: [f64; 3],
    xi: f64,
    targets: &[Vector3<f64>],
    sources: &[Vector3<f64>],
    strengths: &[Vector3<f64>],
    normals: &[Vector3<f64>],
) -> Vec<Vector3<f64>> {
    let r_cut = REFERENCE_CUT / xi;
    let eps = coincidence_radius(box_len);
    let images = shifts(box_len, r_cut);
    let mut out: Vec<Vector3<f64>> = targets
        .iter()
        .map(|x| {
            let mut v = Vector3::zeros();
            for ((y, u), n) in sources.iter().zip(strengths).zip(normals) {
                let r0 = wrap(x - y, box_len);
                for s in &images {
                    let r = r0 + s;
                    let rn = r.norm();
                    if rn < r_cut && rn >= eps {
                        v += stresslet_real_reference(xi, &r, u, n);
                    }
                }
            }
            v
        })
        .collect();
    let volume = box_len[0] * box_len[1] * box_len[2];
    for (k, k2) in half_k(box_len, 2.0 * REFERENCE_CUT * xi) {
        let mut q = [Complex::new(0.0, 0.0); 6];
        for ((y, u), n) in sources.iter().zip(strengths).zip(normals) {
            let e = Complex::from_polar(1.0, -(k[0] * y.x + k[1] * y.y + k[2] * y.z));
            for (qc, s) in q.iter_mut().zip(sym_outer(u, n)) {
                *qc += e * s;
            }
        }
        let b = stresslet_bracket(k, k2, q);
        // -i c [B e^{ikx} - conj(B e^{ikx})] = 2 c Im(B e^{ikx}) for the pair (k, -k).
        let c = 2.0 * fourier_scalar(xi, k2) / volume;
        for (x, v) in targets.iter().zip(out.iter_mut()) {
            let e = Complex::from_polar(1.0, k[0] * x.x + k[1] * x.y + k[2] * x.z);
            for d in 0..3 {
                v[d] += c * (b[d] * e).im;
            }
        }
    }
    out
}

/// `S0 = lim_{r -> 0} [G_per(r) - G(r)]` (1/um): the velocity (times `8 pi mu`) that a unit point force's
/// periodic images and the zero-mean-flow convention induce at the force itself.
///
/// For a cube of side `L`, `S0 = -(4/3) 2.837297 / L I`, which is Hasimoto's (1959) point-force mobility
/// correction `U / (F / 6 pi mu a) = 1 - 2.837297 a / L + ...` (constant as quoted by Yeh & Hummer,
/// J. Phys. Chem. B 108, 15873 (2004)).
pub fn self_image_tensor(box_len: [f64; 3]) -> Matrix3<f64> {
    let xi = balanced_xi(box_len);
    let x = [Vector3::zeros()];
    let mut m = Matrix3::zeros();
    for d in 0..3 {
        let f = [Vector3::from_fn(|i, _| if i == d { 1.0 } else { 0.0 })];
        let u = stokeslet(box_len, xi, &x, &x, &f, Coincident::Regular)[0];
        m.set_column(d, &u);
    }
    m
}
