//! Free-space Stokeslet and stresslet sums over quadrature nodes stored in lanes: the hot loops of the boundary-integral operators.
//!
//! Sources are stored as an array of [`SourceChunk`]s, each holding [`LANES`] nodes as
//! separate `[f64; LANES]` arrays (structure of arrays per chunk). The inner loop over the
//! lanes of one chunk is independent per lane, so the compiler maps it to one AVX-512
//! (or two AVX2) vector operations per line, and the per-lane accumulators keep the
//! floating-point sums vectorised without reassociation. `rbc-bench solver` measures
//! the throughput of these loops against the naive per-pair version [`stokeslet`]/[`stresslet`].
//!
//! Kernels (Pozrikidis, "Boundary integral and singularity methods", 1992, ch. 2), with
//! `r = x - y` (target minus source):
//! - Stokeslet `G_ij(r) = delta_ij / |r| + r_i r_j / |r|^3`;
//! - stresslet contracted with a density and a normal, in Pozrikidis' convention
//!   `T_ijk(xhat) = -6 xhat_i xhat_j xhat_k / |xhat|^5` with `xhat = y - x = -r`:
//!   `u_i T_ijk n_k = +6 (u . r)(r . n) r_j / |r|^5`.

use nalgebra::Vector3;

/// Number of quadrature nodes processed together (one AVX-512 register of f64).
pub const LANES: usize = 8;

/// Far-away position of padding lanes (um): its contributions are exactly zero because the
/// weights are zero, and `1/r`, `1/r^5` stay finite (no `0 * inf`).
const PAD_POSITION: f64 = 1e30;

/// [`LANES`] quadrature nodes: positions `x, y, z` (um), `n = weight * area * unit normal`
/// (um^2) and a density `d` (single layer: `weight * area * traction`; double layer: velocity).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(64))]
pub struct SourceChunk {
    pub x: [f64; LANES],
    pub y: [f64; LANES],
    pub z: [f64; LANES],
    pub nx: [f64; LANES],
    pub ny: [f64; LANES],
    pub nz: [f64; LANES],
    pub dx: [f64; LANES],
    pub dy: [f64; LANES],
    pub dz: [f64; LANES],
}

impl SourceChunk {
    /// A chunk of padding lanes (zero weight, far away).
    pub fn padding() -> Self {
        Self {
            x: [PAD_POSITION; LANES],
            y: [PAD_POSITION; LANES],
            z: [PAD_POSITION; LANES],
            nx: [0.0; LANES],
            ny: [0.0; LANES],
            nz: [0.0; LANES],
            dx: [0.0; LANES],
            dy: [0.0; LANES],
            dz: [0.0; LANES],
        }
    }
}

/// `sum_p G(x - y_p) . (d_p - alpha n_p)` over all lanes of `chunks` (units of `d / length`).
///
/// With `d_p = w_p q(y_p)` and `n_p = w_p n(y_p)` this is the quadrature of the single layer
/// `Int_S G(x, y) . (q(y) - alpha n(y)) dS_y`; `alpha = q(x) . n(x)` removes the normal part of the
/// `1/r` singularity through `Int_S G . n dS = 0` (Pozrikidis 1992, ch. 6; `alpha = 0` turns it off).
#[inline]
pub fn stokeslet_sum(target: &Vector3<f64>, alpha: f64, chunks: &[SourceChunk]) -> Vector3<f64> {
    let (tx, ty, tz) = (target.x, target.y, target.z);
    let mut ax = [0.0f64; LANES];
    let mut ay = [0.0f64; LANES];
    let mut az = [0.0f64; LANES];
    for ch in chunks {
        for l in 0..LANES {
            let rx = tx - ch.x[l];
            let ry = ty - ch.y[l];
            let rz = tz - ch.z[l];
            let r2 = rx.mul_add(rx, ry.mul_add(ry, rz * rz));
            let ir = 1.0 / r2.sqrt();
            let fx = (-alpha).mul_add(ch.nx[l], ch.dx[l]);
            let fy = (-alpha).mul_add(ch.ny[l], ch.dy[l]);
            let fz = (-alpha).mul_add(ch.nz[l], ch.dz[l]);
            let rf = rx.mul_add(fx, ry.mul_add(fy, rz * fz));
            let c = rf * (ir * ir * ir);
            ax[l] = fx.mul_add(ir, rx.mul_add(c, ax[l]));
            ay[l] = fy.mul_add(ir, ry.mul_add(c, ay[l]));
            az[l] = fz.mul_add(ir, rz.mul_add(c, az[l]));
        }
    }
    Vector3::new(ax.iter().sum(), ay.iter().sum(), az.iter().sum())
}

/// `sum_p 6 ((d_p - u0) . r)(r . n_p) r / |r|^5`, `r = x - y_p` (units of `d`).
///
/// With `d_p = u(y_p)` and `n_p = w_p n(y_p)` this is the quadrature of
/// `Int_S (u(y) - u(x)) . T(x, y) . n(y) dS_y` (Pozrikidis' `T`), the double layer after
/// removing `u(x)` with `PV Int_S T . n dS = -4 pi I`.
#[inline]
pub fn stresslet_sum(target: &Vector3<f64>, u0: &Vector3<f64>, chunks: &[SourceChunk]) -> Vector3<f64> {
    let (tx, ty, tz) = (target.x, target.y, target.z);
    let (ux, uy, uz) = (u0.x, u0.y, u0.z);
    let mut ax = [0.0f64; LANES];
    let mut ay = [0.0f64; LANES];
    let mut az = [0.0f64; LANES];
    for ch in chunks {
        for l in 0..LANES {
            let rx = tx - ch.x[l];
            let ry = ty - ch.y[l];
            let rz = tz - ch.z[l];
            let r2 = rx.mul_add(rx, ry.mul_add(ry, rz * rz));
            let ir = 1.0 / r2.sqrt();
            let ir2 = ir * ir;
            let dux = ch.dx[l] - ux;
            let duy = ch.dy[l] - uy;
            let duz = ch.dz[l] - uz;
            let ru = rx.mul_add(dux, ry.mul_add(duy, rz * duz));
            let rn = rx.mul_add(ch.nx[l], ry.mul_add(ch.ny[l], rz * ch.nz[l]));
            let c = ru * rn * (ir2 * ir2 * ir);
            ax[l] = rx.mul_add(c, ax[l]);
            ay[l] = ry.mul_add(c, ay[l]);
            az[l] = rz.mul_add(c, az[l]);
        }
    }
    Vector3::new(6.0 * ax.iter().sum::<f64>(), 6.0 * ay.iter().sum::<f64>(), 6.0 * az.iter().sum::<f64>())
}

/// One Stokeslet `G(r) . f = f / |r| + r (r . f) / |r|^3` (reference and local corrections).
#[inline]
pub fn stokeslet(r: &Vector3<f64>, f: &Vector3<f64>) -> Vector3<f64> {
    let r2 = r.norm_squared();
    let ir = 1.0 / r2.sqrt();
    f * ir + r * (r.dot(f) * ir * ir * ir)
}

/// One stresslet `u . T . n = 6 (u . r)(r . n) r / |r|^5` (Pozrikidis' sign, `r = x - y`).
#[inline]
pub fn stresslet(r: &Vector3<f64>, u: &Vector3<f64>, n: &Vector3<f64>) -> Vector3<f64> {
    let r2 = r.norm_squared();
    let ir = 1.0 / r2.sqrt();
    r * (6.0 * r.dot(u) * r.dot(n) * ir * ir * ir * ir * ir)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn random_chunks(n: usize, seed: u64) -> (Vec<SourceChunk>, Vec<[Vector3<f64>; 3]>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut chunks = vec![SourceChunk::padding(); n.div_ceil(LANES)];
        let mut pts = Vec::new();
        for p in 0..n {
            let mut v = || Vector3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let (y, nn, d) = (v() * 3.0, v(), v());
            let (c, l) = (&mut chunks[p / LANES], p % LANES);
            (c.x[l], c.y[l], c.z[l]) = (y.x, y.y, y.z);
            (c.nx[l], c.ny[l], c.nz[l]) = (nn.x, nn.y, nn.z);
            (c.dx[l], c.dy[l], c.dz[l]) = (d.x, d.y, d.z);
            pts.push([y, nn, d]);
        }
        (chunks, pts)
    }

    /// The lane sums equal the per-pair formulas (padding lanes add exactly zero).
    #[test]
    fn lane_sums_match_pairwise_formulas() {
        let (chunks, pts) = random_chunks(61, 7); // 61 = 7 chunks + 5 lanes: padding is exercised
        let x = Vector3::new(5.0, -4.0, 4.5); // outside the cloud
        let alpha = 0.3;
        let u0 = Vector3::new(0.2, -0.1, 0.4);
        let mut g = Vector3::zeros();
        let mut t = Vector3::zeros();
        for [y, n, d] in &pts {
            g += stokeslet(&(x - y), &(d - n * alpha));
            t += stresslet(&(x - y), &(d - u0), n);
        }
        let gs = stokeslet_sum(&x, alpha, &chunks);
        let ts = stresslet_sum(&x, &u0, &chunks);
        assert!((gs - g).norm() < 1e-13 * g.norm(), "{gs} vs {g}");
        assert!((ts - t).norm() < 1e-13 * t.norm(), "{ts} vs {t}");
    }

    /// Symmetry of the Stokeslet (`G(r) = G(-r)`, symmetric tensor) and oddness of the stresslet.
    #[test]
    fn kernel_symmetries() {
        let r = Vector3::new(0.3, -1.2, 0.7);
        let (a, b) = (Vector3::new(1.0, 2.0, -0.5), Vector3::new(-0.3, 0.1, 0.9));
        assert!((stokeslet(&r, &a).dot(&b) - stokeslet(&r, &b).dot(&a)).abs() < 1e-14);
        assert_eq!(stokeslet(&r, &a), stokeslet(&-r, &a));
        assert!((stresslet(&r, &a, &b) + stresslet(&-r, &a, &b)).norm() < 1e-15);
        // A Stokeslet decays like 1/r: at 10x the distance it is 10x smaller.
        assert!((stokeslet(&(r * 10.0), &a) * 10.0 - stokeslet(&r, &a)).norm() < 1e-14);
    }
}
