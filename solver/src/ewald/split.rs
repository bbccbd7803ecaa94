//! Hasimoto's Ewald split of the Stokeslet and the matching split of the stresslet: the real-space kernels and the Fourier-space multipliers.
//!
//! Conventions are those of [`crate::bim::kernels`]: `r = x - y` (target minus source),
//! Stokeslet `G(r) f = f/|r| + r (r . f)/|r|^3`, stresslet contracted with a density `u` and a
//! (weighted) normal `n`: `u . T(r) . n = 6 (u . r)(r . n) r / |r|^5` (Pozrikidis 1992).
//! Periodic sums use `f(r) = (1/V) sum_k f^(k) exp(i k . r)`, `k = 2 pi (n1/Lx, n2/Ly, n3/Lz)`.
//!
//! Fourier transforms (with `phi^ = 1/k^2 <-> 1/(4 pi r)` and `psi^ = 1/k^4 <-> -r/(8 pi)`,
//! `G = 8 pi (delta phi + d_i d_j psi)`, `T_ijl = -8 pi [(delta_il d_j + delta_ij d_l + delta_jl d_i) phi + 2 d_i d_j d_l psi]`):
//!
//! ```text
//! G^(k)      = 8 pi (I - k k / k^2) / k^2
//! T^_ijl(k)  = -(8 pi i / k^2) (delta_il k_j + delta_ij k_l + delta_jl k_i - 2 k_i k_j k_l / k^2)
//! ```
//!
//! Hasimoto's split (Hasimoto, J. Fluid Mech. 5, 317 (1959); in this form Lindbo & Tornberg,
//! J. Comput. Phys. 229, 8994 (2010)) multiplies both by
//! `H(k) = (1 + k^2/(4 xi^2)) exp(-k^2/(4 xi^2))` for the Fourier part and leaves
//! `1 - H` to real space. Transforming `(1 - H)/k^2` and `(1 - H)/k^4` back gives
//! (derived in the module's comments below, checked by the xi-independence tests):
//!
//! ```text
//! G^R(r) f = a(r) f + b(r) r (r . f),
//!   a = erfc(xi r)/r - 2 xi/sqrt(pi) e,     b = erfc(xi r)/r^3 + 2 xi/sqrt(pi) e / r^2,     e = exp(-xi^2 r^2)
//! u . T^R(r) . n = B(r) (u . r)(r . n) r + A(r) [(r . n) u + (u . r) n + (u . n) r],
//!   A = -4 xi^3/sqrt(pi) e,                  B = 6 erfc(xi r)/r^5 + 4 xi/sqrt(pi) (3/r^4 + 2 xi^2/r^2) e
//! ```
//!
//! Limits at `r -> 0`: `G^R(r) - G(r) -> -4 xi/sqrt(pi) I` and `T^R(r) - T(r) -> 0` (odd).
//!
//! Derivation sketch: `phi^R = erfc(xi r)/(4 pi r) - xi/(4 pi^(3/2)) e` (inverse transform of
//! `(1-H)/k^2`, using that of `exp(-k^2/4xi^2)` = `xi^3/pi^(3/2) e`); `nabla^2 psi^R = -phi^R`
//! integrates to `psi^R' = -erfc(xi r)/(8 pi)`. With `g = psi'/r`, `h = g'/r`:
//! `a = 8 pi (phi^R + g)`, `b = 8 pi h`, `A = -8 pi (phi^R'/r + 2 h)`, `B = -16 pi h'/r`.

use nalgebra::Vector3;

use super::erfc::Erfcx;

pub(crate) const FRAC_1_SQRT_PI: f64 = 0.564_189_583_547_756_3; // 1/sqrt(pi)
const EIGHT_PI: f64 = 8.0 * std::f64::consts::PI;

/// `(a, b)` of the real-space Stokeslet at distance `r > 0`, given `erfc(xi r)` and `e = exp(-xi^2 r^2)`.
#[inline(always)]
pub fn stokeslet_ab(xi: f64, r: f64, erfc: f64, e: f64) -> (f64, f64) {
    let ir = 1.0 / r;
    let c = 2.0 * xi * FRAC_1_SQRT_PI * e;
    (erfc * ir - c, (erfc * ir + c) * ir * ir)
}

/// `(A, B)` of the real-space stresslet at distance `r > 0`, given `erfc(xi r)` and `e = exp(-xi^2 r^2)`.
#[inline(always)]
pub fn stresslet_ab(xi: f64, r: f64, erfc: f64, e: f64) -> (f64, f64) {
    let ir = 1.0 / r;
    let ir2 = ir * ir;
    let c = 4.0 * xi * FRAC_1_SQRT_PI * e;
    let a = -xi * xi * c;
    let b = 6.0 * erfc * ir2 * ir2 * ir + c * ir2 * (3.0 * ir2 + 2.0 * xi * xi);
    (a, b)
}

/// Real-space Stokeslet `G^R(r) . f`, one pair at a time (for the direct sums; `erfc` from the table, 1e-14 relative).
pub fn stokeslet_real_reference(xi: f64, r: &Vector3<f64>, f: &Vector3<f64>) -> Vector3<f64> {
    let rn = r.norm();
    let (erfc, e) = erfc_and_gauss(Erfcx::get(), xi * rn);
    let (a, b) = stokeslet_ab(xi, rn, erfc, e);
    f * a + r * (b * r.dot(f))
}

/// Real-space stresslet `u . T^R(r) . n`, one pair at a time (for the direct sums; `erfc` from the table).
pub fn stresslet_real_reference(xi: f64, r: &Vector3<f64>, u: &Vector3<f64>, n: &Vector3<f64>) -> Vector3<f64> {
    let rn = r.norm();
    let (erfc, e) = erfc_and_gauss(Erfcx::get(), xi * rn);
    let (a, b) = stresslet_ab(xi, rn, erfc, e);
    let (ur, rnn) = (u.dot(r), r.dot(n));
    r * (b * ur * rnn) + (u * rnn + n * ur + r * u.dot(n)) * a
}

/// Fast `(erfc(x), exp(-x^2))` for `x >= 0` from the [`Erfcx`] table.
#[inline(always)]
pub fn erfc_and_gauss(table: &Erfcx, x: f64) -> (f64, f64) {
    let e = (-x * x).exp();
    (table.eval(x) * e, e)
}

/// Limit of `G^R(r) - G(r)` at `r -> 0`: `-4 xi / sqrt(pi)` times the identity.
pub fn stokeslet_real_self(xi: f64) -> f64 {
    -4.0 * xi * FRAC_1_SQRT_PI
}

/// Hasimoto's factor `H(k) = (1 + k^2/(4 xi^2)) exp(-k^2/(4 xi^2))` times `8 pi / k^2` (`k2 = k^2 > 0`):
/// the scalar in front of `(I - k k/k^2)` in the Fourier-space Stokeslet, and in front of the bracket
/// in `T^F = -i (8 pi H / k^2) [...]`.
#[inline(always)]
pub fn fourier_scalar(xi: f64, k2: f64) -> f64 {
    let q = k2 / (4.0 * xi * xi);
    EIGHT_PI * (1.0 + q) * (-q).exp() / k2
}

/// Fourier-space Stokeslet applied to `f`: `(I - k k / k^2) f` (multiply by [`fourier_scalar`]).
#[inline(always)]
pub fn project<T>(k: [f64; 3], k2: f64, f: [T; 3]) -> [T; 3]
where
    T: Copy + std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T> + std::ops::Sub<Output = T>,
{
    let kf = (f[0] * k[0] + f[1] * k[1] + f[2] * k[2]) * (1.0 / k2);
    [f[0] - kf * k[0], f[1] - kf * k[1], f[2] - kf * k[2]]
}

/// Fourier-space stresslet bracket contracted with a symmetric density `q` (`q_il = sym(u_i n_l)`), without the factor `-i 8 pi H / k^2`:
/// `tr(q) k + 2 q k - 2 (k . q . k) k / k^2`. `q` = `[q_xx, q_yy, q_zz, q_xy, q_xz, q_yz]`.
#[inline(always)]
pub fn stresslet_bracket<T>(k: [f64; 3], k2: f64, q: [T; 6]) -> [T; 3]
where
    T: Copy + std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T> + std::ops::Sub<Output = T>,
{
    let [xx, yy, zz, xy, xz, yz] = q;
    let tr = xx + yy + zz;
    let qk = [xx * k[0] + xy * k[1] + xz * k[2], xy * k[0] + yy * k[1] + yz * k[2], xz * k[0] + yz * k[1] + zz * k[2]];
    let kqk = (qk[0] * k[0] + qk[1] * k[1] + qk[2] * k[2]) * (2.0 / k2);
    [tr * k[0] + qk[0] * 2.0 - kqk * k[0], tr * k[1] + qk[1] * 2.0 - kqk * k[1], tr * k[2] + qk[2] * 2.0 - kqk * k[2]]
}

/// The symmetric part of `u n^T` as `[xx, yy, zz, xy, xz, yz]` (only it couples to the fully symmetric `T`).
#[inline(always)]
pub fn sym_outer(u: &Vector3<f64>, n: &Vector3<f64>) -> [f64; 6] {
    [
        u.x * n.x,
        u.y * n.y,
        u.z * n.z,
        0.5 * (u.x * n.y + u.y * n.x),
        0.5 * (u.x * n.z + u.z * n.x),
        0.5 * (u.y * n.z + u.z * n.y),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bim::kernels::{stokeslet, stresslet};

    /// As xi -> 0 the real-space kernels become the free-space ones; the r -> 0 limit of the
    /// Stokeslet difference is -4 xi/sqrt(pi) I; the real-space stresslet is symmetric in (u, n).
    #[test]
    fn real_space_limits() {
        let r = Vector3::new(0.3, -0.7, 0.4);
        let (f, n) = (Vector3::new(1.0, 0.5, -2.0), Vector3::new(-0.2, 0.9, 0.3));
        let xi = 1e-9;
        assert!((stokeslet_real_reference(xi, &r, &f) - stokeslet(&r, &f)).norm() < 1e-8);
        assert!((stresslet_real_reference(xi, &r, &f, &n) - stresslet(&r, &f, &n)).norm() < 1e-8);
        let xi = 1.3;
        let rs = r * 1e-5;
        let d = stokeslet_real_reference(xi, &rs, &f) - stokeslet(&rs, &f) - f * stokeslet_real_self(xi);
        assert!(d.norm() < 1e-4 * f.norm(), "{d}");
        let s1 = stresslet_real_reference(xi, &r, &f, &n);
        let s2 = stresslet_real_reference(xi, &r, &n, &f);
        assert!((s1 - s2).norm() < 1e-14 * s1.norm());
    }
}
