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
use rayon::prelude::*;

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

/// Source chunks per tile of [`tiled_sums`]: 64 x 576 B = 36 KiB, inside the 48 KiB L1 data
/// cache of this CPU (Sapphire Rapids). Without tiling, 2048 triangles (1 MiB of chunks) stream
/// from L2 and 8192 triangles (4 MiB) from L3 for every target, which made the latter 4x slower per pair.
pub const TILE_CHUNKS: usize = 64;

/// Targets that share one pass over a tile; also the unit of parallel work (rayon).
pub const TARGET_BLOCK: usize = 32;

/// `out[i] = sum over tiles of kernel(i, tile)`, parallel over blocks of [`TARGET_BLOCK`]
/// targets; each tile of [`TILE_CHUNKS`] source chunks is reused by all targets of a block
/// while it sits in L1.
pub fn tiled_sums<F>(chunks: &[SourceChunk], out: &mut [Vector3<f64>], kernel: F)
where
    F: Fn(usize, &[SourceChunk]) -> Vector3<f64> + Sync,
{
    out.par_chunks_mut(TARGET_BLOCK).enumerate().for_each(|(b, block)| {
        let i0 = b * TARGET_BLOCK;
        block.iter_mut().for_each(|o| *o = Vector3::zeros());
        for tile in chunks.chunks(TILE_CHUNKS) {
            for (k, o) in block.iter_mut().enumerate() {
                *o += kernel(i0 + k, tile);
            }
        }
    });
}

/// `sum_p G(x - y_p) . (d_p - alpha n_p)` over all lanes of `chunks` (units of `d / length`).
///
/// With `d_p = w_p q(y_p)` and `n_p = w_p n(y_p)` this is the quadrature of the single layer
/// `Int_S G(x, y) . (q(y) - alpha n(y)) dS_y`; `alpha = q(x) . n(x)` removes the normal part of the
/// `1/r` singularity through `Int_S G . n dS = 0` (Pozrikidis 1992, ch. 6; `alpha = 0` turns it off).
#[inline]
pub fn stokeslet_sum(target: &Vector3<f64>, alpha: f64, chunks: &[SourceChunk]) -> Vector3<f64> {
    #[cfg(target_arch = "x86_64")]
    if avx512_available() {
        // SAFETY: the CPU supports AVX-512F (checked at run time).
        return unsafe { avx512::stokeslet_sum(target, alpha, chunks) };
    }
    stokeslet_sum_portable(target, alpha, chunks)
}

/// [`stokeslet_sum`] in plain Rust (exact `1/sqrt`; vectorised by the compiler): the fallback
/// without AVX-512 and the reference for the AVX-512 version.
#[inline]
pub fn stokeslet_sum_portable(target: &Vector3<f64>, alpha: f64, chunks: &[SourceChunk]) -> Vector3<f64> {
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
    #[cfg(target_arch = "x86_64")]
    if avx512_available() {
        // SAFETY: the CPU supports AVX-512F (checked at run time).
        return unsafe { avx512::stresslet_sum(target, u0, chunks) };
    }
    stresslet_sum_portable(target, u0, chunks)
}

/// [`stresslet_sum`] in plain Rust (exact `1/sqrt`): fallback and reference.
#[inline]
pub fn stresslet_sum_portable(target: &Vector3<f64>, u0: &Vector3<f64>, chunks: &[SourceChunk]) -> Vector3<f64> {
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

/// `sum_p 6 (r . n_p) r r^T / |r|^5`, `r = x - y_p`: the stresslet contracted with the weighted
/// normals as a symmetric matrix, so that `M u = sum_p u . T(x, y_p) . n_p` for a constant `u`
/// (dimensionless). One pass over the sources for the three unit densities that
/// [`stresslet_sum`] would need three passes for (the periodic double layer's self term).
/// Plain Rust over the lanes (the compiler vectorises it); the distance prologue repeats the
/// other kernels' on purpose: a shared helper would hide the lane loop from the vectoriser.
#[inline]
pub fn stresslet_matrix_sum(target: &Vector3<f64>, chunks: &[SourceChunk]) -> nalgebra::Matrix3<f64> {
    #[cfg(target_arch = "x86_64")]
    if avx512_available() {
        // SAFETY: the CPU supports AVX-512F (checked at run time).
        return unsafe { avx512::stresslet_matrix_sum(target, chunks) };
    }
    stresslet_matrix_sum_portable(target, chunks)
}

/// [`stresslet_matrix_sum`] in plain Rust (exact `1/sqrt`): the fallback without AVX-512 and the
/// reference for the AVX-512 version.
#[allow(clippy::needless_range_loop)] // one lane index runs over the chunk's arrays and the six accumulators
pub fn stresslet_matrix_sum_portable(target: &Vector3<f64>, chunks: &[SourceChunk]) -> nalgebra::Matrix3<f64> {
    let (tx, ty, tz) = (target.x, target.y, target.z);
    let mut a = [[0.0f64; LANES]; 6];
    for ch in chunks {
        for l in 0..LANES {
            let rx = tx - ch.x[l];
            let ry = ty - ch.y[l];
            let rz = tz - ch.z[l];
            let r2 = rx.mul_add(rx, ry.mul_add(ry, rz * rz));
            let ir = 1.0 / r2.sqrt();
            let ir2 = ir * ir;
            let rn = rx.mul_add(ch.nx[l], ry.mul_add(ch.ny[l], rz * ch.nz[l]));
            let c = rn * (ir2 * ir2 * ir);
            let (cx, cy) = (c * rx, c * ry);
            a[0][l] = cx.mul_add(rx, a[0][l]);
            a[1][l] = cx.mul_add(ry, a[1][l]);
            a[2][l] = cx.mul_add(rz, a[2][l]);
            a[3][l] = cy.mul_add(ry, a[3][l]);
            a[4][l] = cy.mul_add(rz, a[4][l]);
            a[5][l] = (c * rz).mul_add(rz, a[5][l]);
        }
    }
    let m: Vec<f64> = a.iter().map(|v| 6.0 * v.iter().sum::<f64>()).collect();
    nalgebra::Matrix3::new(m[0], m[1], m[2], m[1], m[3], m[4], m[2], m[4], m[5])
}

/// Whether the AVX-512 kernels run (the CPU has AVX-512F; `std` caches the answer).
#[inline]
pub fn avx512_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Explicit AVX-512 versions of the sums. The only change from the portable loops is the
/// inverse square root: `vrsqrt14pd` refined by one third-order step (relative error < 6e-13,
/// see `rsqrt`), instead of `vsqrtpd` + `vdivpd`, which cost ~30 cycles per 8 lanes and bound
/// the portable loop. What remains is ~27 vector operations per 8 pairs on the two FMA ports.
#[cfg(target_arch = "x86_64")]
pub(crate) mod avx512 {
    use super::{SourceChunk, LANES};
    use nalgebra::Vector3;
    use std::arch::x86_64::*;

    const _: () = assert!(LANES == 8, "one __m512d per lane array");

    /// `1/sqrt(r2)`: `vrsqrt14pd` (relative error `d < 2^-14`) refined by one third-order
    /// (Householder) step `y <- y (1 + e/2 + 3 e^2/8)`, `e = 1 - r2 y^2`, the series of
    /// `(1 - e)^(-1/2)` to second order: relative error `5 e^3 / 16 < 6e-13` (6 vector operations;
    /// two Newton steps would cost 7 for ~1e-16 and `vsqrtpd` + `vdivpd` ~30 cycles).
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(crate) fn rsqrt(r2: __m512d) -> __m512d {
        let y = _mm512_rsqrt14_pd(r2);
        let e = _mm512_fnmadd_pd(_mm512_mul_pd(r2, y), y, _mm512_set1_pd(1.0));
        let p = _mm512_fmadd_pd(e, _mm512_set1_pd(0.375), _mm512_set1_pd(0.5));
        _mm512_fmadd_pd(_mm512_mul_pd(y, e), p, y)
    }

    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(crate) fn load(a: &[f64; LANES]) -> __m512d {
        // A by-value transmute instead of `_mm512_loadu_pd`: the latter goes through a raw-pointer
        // copy that debug assertions (on in our optimised test profile) wrap in checks, which
        // made the loop 7x slower. SAFETY: `[f64; 8]` and `__m512d` have the same size and every
        // bit pattern is valid for both.
        unsafe { std::mem::transmute::<[f64; LANES], __m512d>(*a) }
    }

    /// `r = t - y` of the chunk's lanes and `1/|r|^5` (the stresslet sums' common prologue).
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn separation_ir5(tx: __m512d, ty: __m512d, tz: __m512d, ch: &SourceChunk) -> (__m512d, __m512d, __m512d, __m512d) {
        let rx = _mm512_sub_pd(tx, load(&ch.x));
        let ry = _mm512_sub_pd(ty, load(&ch.y));
        let rz = _mm512_sub_pd(tz, load(&ch.z));
        let r2 = _mm512_fmadd_pd(rx, rx, _mm512_fmadd_pd(ry, ry, _mm512_mul_pd(rz, rz)));
        let ir = rsqrt(r2);
        let ir2 = _mm512_mul_pd(ir, ir);
        (rx, ry, rz, _mm512_mul_pd(_mm512_mul_pd(ir2, ir2), ir))
    }

    /// See [`super::stokeslet_sum`].
    #[target_feature(enable = "avx512f")]
    pub fn stokeslet_sum(target: &Vector3<f64>, alpha: f64, chunks: &[SourceChunk]) -> Vector3<f64> {
        let (tx, ty, tz) = (_mm512_set1_pd(target.x), _mm512_set1_pd(target.y), _mm512_set1_pd(target.z));
        let na = _mm512_set1_pd(-alpha);
        let (mut ax, mut ay, mut az) = (_mm512_setzero_pd(), _mm512_setzero_pd(), _mm512_setzero_pd());
        for ch in chunks {
            let rx = _mm512_sub_pd(tx, load(&ch.x));
            let ry = _mm512_sub_pd(ty, load(&ch.y));
            let rz = _mm512_sub_pd(tz, load(&ch.z));
            let r2 = _mm512_fmadd_pd(rx, rx, _mm512_fmadd_pd(ry, ry, _mm512_mul_pd(rz, rz)));
            let ir = rsqrt(r2);
            let fx = _mm512_fmadd_pd(na, load(&ch.nx), load(&ch.dx));
            let fy = _mm512_fmadd_pd(na, load(&ch.ny), load(&ch.dy));
            let fz = _mm512_fmadd_pd(na, load(&ch.nz), load(&ch.dz));
            let rf = _mm512_fmadd_pd(rx, fx, _mm512_fmadd_pd(ry, fy, _mm512_mul_pd(rz, fz)));
            let ir3 = _mm512_mul_pd(_mm512_mul_pd(ir, ir), ir);
            let c = _mm512_mul_pd(rf, ir3);
            ax = _mm512_fmadd_pd(fx, ir, _mm512_fmadd_pd(rx, c, ax));
            ay = _mm512_fmadd_pd(fy, ir, _mm512_fmadd_pd(ry, c, ay));
            az = _mm512_fmadd_pd(fz, ir, _mm512_fmadd_pd(rz, c, az));
        }
        Vector3::new(_mm512_reduce_add_pd(ax), _mm512_reduce_add_pd(ay), _mm512_reduce_add_pd(az))
    }

    /// See [`super::stresslet_sum`].
    #[target_feature(enable = "avx512f")]
    pub fn stresslet_sum(target: &Vector3<f64>, u0: &Vector3<f64>, chunks: &[SourceChunk]) -> Vector3<f64> {
        let (tx, ty, tz) = (_mm512_set1_pd(target.x), _mm512_set1_pd(target.y), _mm512_set1_pd(target.z));
        let (ux, uy, uz) = (_mm512_set1_pd(u0.x), _mm512_set1_pd(u0.y), _mm512_set1_pd(u0.z));
        let (mut ax, mut ay, mut az) = (_mm512_setzero_pd(), _mm512_setzero_pd(), _mm512_setzero_pd());
        for ch in chunks {
            let (rx, ry, rz, ir5) = separation_ir5(tx, ty, tz, ch);
            let dux = _mm512_sub_pd(load(&ch.dx), ux);
            let duy = _mm512_sub_pd(load(&ch.dy), uy);
            let duz = _mm512_sub_pd(load(&ch.dz), uz);
            let ru = _mm512_fmadd_pd(rx, dux, _mm512_fmadd_pd(ry, duy, _mm512_mul_pd(rz, duz)));
            let rn = _mm512_fmadd_pd(rx, load(&ch.nx), _mm512_fmadd_pd(ry, load(&ch.ny), _mm512_mul_pd(rz, load(&ch.nz))));
            let c = _mm512_mul_pd(_mm512_mul_pd(ru, rn), ir5);
            ax = _mm512_fmadd_pd(rx, c, ax);
            ay = _mm512_fmadd_pd(ry, c, ay);
            az = _mm512_fmadd_pd(rz, c, az);
        }
        let six = 6.0;
        Vector3::new(six * _mm512_reduce_add_pd(ax), six * _mm512_reduce_add_pd(ay), six * _mm512_reduce_add_pd(az))
    }

    /// See [`super::stresslet_matrix_sum`].
    #[target_feature(enable = "avx512f")]
    pub fn stresslet_matrix_sum(target: &Vector3<f64>, chunks: &[SourceChunk]) -> nalgebra::Matrix3<f64> {
        let (tx, ty, tz) = (_mm512_set1_pd(target.x), _mm512_set1_pd(target.y), _mm512_set1_pd(target.z));
        let mut a = [_mm512_setzero_pd(); 6];
        for ch in chunks {
            let (rx, ry, rz, ir5) = separation_ir5(tx, ty, tz, ch);
            let rn = _mm512_fmadd_pd(rx, load(&ch.nx), _mm512_fmadd_pd(ry, load(&ch.ny), _mm512_mul_pd(rz, load(&ch.nz))));
            let c = _mm512_mul_pd(rn, ir5);
            let (cx, cy) = (_mm512_mul_pd(c, rx), _mm512_mul_pd(c, ry));
            a[0] = _mm512_fmadd_pd(cx, rx, a[0]);
            a[1] = _mm512_fmadd_pd(cx, ry, a[1]);
            a[2] = _mm512_fmadd_pd(cx, rz, a[2]);
            a[3] = _mm512_fmadd_pd(cy, ry, a[3]);
            a[4] = _mm512_fmadd_pd(cy, rz, a[4]);
            a[5] = _mm512_fmadd_pd(_mm512_mul_pd(c, rz), rz, a[5]);
        }
        let m = a.map(|v| 6.0 * _mm512_reduce_add_pd(v));
        nalgebra::Matrix3::new(m[0], m[1], m[2], m[1], m[3], m[4], m[2], m[4], m[5])
    }
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

    /// The per-pair formulas summed over `pts` at `x`: the Stokeslet of `d - alpha n`, the
    /// stresslet of `d - u0`, and the stresslet of `u0` alone.
    fn pair_sums(pts: &[[Vector3<f64>; 3]], x: &Vector3<f64>, alpha: f64, u0: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let (mut g, mut t, mut m) = (Vector3::zeros(), Vector3::zeros(), Vector3::zeros());
        for [y, n, d] in pts {
            g += stokeslet(&(x - y), &(d - n * alpha));
            t += stresslet(&(x - y), &(d - u0), n);
            m += stresslet(&(x - y), u0, n);
        }
        (g, t, m)
    }

    /// The lane sums equal the per-pair formulas (padding lanes add exactly zero).
    #[test]
    fn lane_sums_match_pairwise_formulas() {
        let (chunks, pts) = random_chunks(61, 7); // 61 = 7 chunks + 5 lanes: padding is exercised
        let x = Vector3::new(5.0, -4.0, 4.5); // outside the cloud
        let alpha = 0.3;
        let u0 = Vector3::new(0.2, -0.1, 0.4);
        let (g, t, _) = pair_sums(&pts, &x, alpha, &u0);
        // Portable lanes: exact arithmetic up to summation order.
        let gs = stokeslet_sum_portable(&x, alpha, &chunks);
        let ts = stresslet_sum_portable(&x, &u0, &chunks);
        assert!((gs - g).norm() < 1e-13 * g.norm(), "{gs} vs {g}");
        assert!((ts - t).norm() < 1e-13 * t.norm(), "{ts} vs {t}");
        // Dispatched (AVX-512 when available): within the inverse-square-root error (< 3e-12 per 1/r^5).
        let gs = stokeslet_sum(&x, alpha, &chunks);
        let ts = stresslet_sum(&x, &u0, &chunks);
        assert!((gs - g).norm() < 1e-11 * g.norm(), "{gs} vs {g}");
        assert!((ts - t).norm() < 1e-11 * t.norm(), "{ts} vs {t}");
    }

    /// The dispatched sums (AVX-512 where the CPU has it: approximate inverse square root + one
    /// third-order step, relative error < 6e-13 per `1/r`, < 3e-12 per `1/r^5`) agree with the
    /// per-pair formulas and with the portable lanes (exact `1/sqrt`), the stresslet matrix applied
    /// to a density with the stresslet sum, including a target very close to a source. On a CPU
    /// without AVX-512 the dispatch is the portable code and the pair formulas are what it meets.
    #[test]
    fn dispatched_sums_match_pair_formulas_and_portable_lanes() {
        let (chunks, pts) = random_chunks(203, 11);
        let u0 = Vector3::new(0.2, -0.1, 0.4);
        let near = pts[17][0] + Vector3::new(1e-4, -2e-4, 5e-5);
        for x in [Vector3::new(0.1, 0.2, -0.3), near, Vector3::new(40.0, 1.0, 2.0)] {
            let (g, t, m) = pair_sums(&pts, &x, 0.7, &u0);
            let (a, b) = (stokeslet_sum(&x, 0.7, &chunks), stokeslet_sum_portable(&x, 0.7, &chunks));
            assert!((a - b).norm() <= 1e-11 * b.norm() && (a - g).norm() <= 1e-11 * g.norm(), "{a} vs {b} vs {g}");
            let (a, b) = (stresslet_sum(&x, &u0, &chunks), stresslet_sum_portable(&x, &u0, &chunks));
            assert!((a - b).norm() <= 1e-11 * b.norm() && (a - t).norm() <= 1e-11 * t.norm(), "{a} vs {b} vs {t}");
            let (a, b) = (stresslet_matrix_sum(&x, &chunks), stresslet_matrix_sum_portable(&x, &chunks));
            assert!((a - b).norm() <= 1e-11 * b.norm(), "{a} vs {b}");
            assert!((a * u0 - m).norm() <= 1e-11 * m.norm(), "{} vs {m}", a * u0);
        }
        eprintln!("AVX-512 kernels in use: {}", avx512_available());
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

    /// The one-pass matrix equals three passes of the vector sum with unit densities (the
    /// padding lanes add exactly zero to both).
    #[test]
    fn stresslet_matrix_sum_matches_three_vector_sums() {
        let (chunks, _) = random_chunks(203, 11);
        let target = Vector3::new(0.31, -0.17, 0.42);
        let m = stresslet_matrix_sum_portable(&target, &chunks);
        for c in 0..3 {
            let mut unit = chunks.clone();
            for ch in &mut unit {
                for l in 0..LANES {
                    let e = Vector3::ith(c, 1.0);
                    (ch.dx[l], ch.dy[l], ch.dz[l]) = (e.x, e.y, e.z);
                }
            }
            let v = stresslet_sum_portable(&target, &Vector3::zeros(), &unit);
            let col = m.column(c).into_owned();
            assert!((v - col).norm() <= 1e-12 * v.norm().max(1.0), "column {c}: {v} vs {col}");
        }
    }
}
