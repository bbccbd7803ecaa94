//! The real-space stresslet (or Stokeslet) kernels of one triangle's quadrature nodes at once, in eight SIMD lanes, summed into the triangle's three vertex blocks (for [`super::blocks::BlockRows::stresslet_grouped`] and [`super::blocks::BlockRows::stokeslet_grouped`]).
//!
//! Per pair the kernel is that of [`super::split::stresslet_ab`],
//! `B (r . n) r r^T + A (r n^T + (r . n) I + n r^T)` with
//! `A = -4 xi^3/sqrt(pi) e`, `B = 6 erfc(s)/r^5 + 4 xi/sqrt(pi) (3/r^4 + 2 xi^2/r^2) e`,
//! `s = xi r`, `e = exp(-s^2)`. The scalar path calls libm's `exp` per pair, which keeps a loop
//! scalar. Here the loop over a triangle's nodes (7, padded to 8 lanes) vectorises:
//! - `exp(x)`, `x <= 0`: `x = m ln 2 + q`, `|q| <= ln 2 / 2`, `exp(q)` by its Taylor series to
//!   degree 13 (remainder `< 5e-18` relative), `2^m` built in the exponent bits (Cody & Waite;
//!   Muller, "Elementary Functions", ch. 11), branch-free;
//! - `erfc(s) = erfcx(s) e` with `erfcx` from the piecewise Chebyshev table of
//!   [`super::erfc::Erfcx`], all lanes stepped together ([`Erfcx::eval_lanes`]: one gather of
//!   coefficients per step). `s = xi r < xi r_cut` stays inside the table (`< 8`).
//!
//! On a CPU with AVX-512 the same kernels run from explicit intrinsics (`zmm`: every
//! intermediate in registers, `1/r` by `vrsqrt14pd` refined to rounding, the lane sums as
//! transposing reductions), 0.90 of the portable build's core-s in the paper's channel.
//!
//! Agreement with the scalar path to rounding: tests `grouped_stresslet_blocks_match_real_space`,
//! `grouped_stokeslet_blocks_match_real_space`; the two paths here agree entry by entry within
//! 1e-13 of a block's largest entry (`the_avx512_blocks_match_the_portable_ones`).

use super::erfc::Erfcx;
use super::split::{stokeslet_ab, stresslet_ab};

/// A symmetric 3 x 3 block by its upper triangle, `[xx, xy, xz, yy, yz, zz]`.
pub type Sym = [f64; 6];

/// `(p, q)` of the upper-triangle entries of a [`Sym`], in its order.
pub const SYM_PQ: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// Lanes per vector (one AVX-512 register of `f64`).
pub const LANES: usize = 8;
const _: () = assert!(LANES == 8, "the lane sums of `Kernel::blocks` are a tree over 8 lanes");


/// `exp(x)` for `-700 <= x <= 0`, branch-free (see the module docs); relative error ~2e-16.
#[inline(always)]
pub fn exp_nonpositive(x: f64) -> f64 {
    const LN2_HI: f64 = 6.931_471_803_691_238e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    let m = (x * std::f64::consts::LOG2_E).round();
    let q = m.mul_add(-LN2_LO, m.mul_add(-LN2_HI, x));
    // Taylor coefficients 1/k!, k = 13 .. 0 (Horner)
    const C: [f64; 14] = [
        1.0 / 6_227_020_800.0,
        1.0 / 479_001_600.0,
        1.0 / 39_916_800.0,
        1.0 / 3_628_800.0,
        1.0 / 362_880.0,
        1.0 / 40_320.0,
        1.0 / 5_040.0,
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        0.5,
        1.0,
        1.0,
    ];
    let mut p = C[0];
    for &c in &C[1..] {
        p = p.mul_add(q, c);
    }
    // 2^m: m + 1023 + 2^52 holds m + 1023 in its low mantissa bits
    let two_m = f64::from_bits((m + 4_503_599_627_371_519.0).to_bits() << 52);
    p * two_m
}

/// [`exp_nonpositive`] of each lane, the loops over the lanes innermost.
#[inline(always)]
fn exp_lanes(x: [f64; LANES]) -> [f64; LANES] {
    let mut out = [0.0; LANES];
    for l in 0..LANES {
        out[l] = exp_nonpositive(x[l]);
    }
    out
}

/// One triangle's nodes in lanes: positions (um, in the frame of the shifted target), weighted
/// normals (um^2) and, for a single layer fused into the build, the weighted forces
/// `w_k f(y_k)` (pN; zero otherwise); padding lanes have `valid = 0`.
#[derive(Debug, Clone, Copy, Default)]
pub struct NodeLanes {
    pub x: [[f64; LANES]; 3],
    pub n: [[f64; LANES]; 3],
    pub f: [[f64; LANES]; 3],
    pub valid: [f64; LANES],
}

/// What one triangle gives one target: its three vertex blocks ([`Sym`]) and, when the build
/// carries a single layer, the real-space Stokeslet sum `sum_k G^R(t - y_k) w_k f_k` (pN/um).
pub type TriangleAtTarget = ([Sym; 3], [f64; 3]);

/// One group of Stokeslet sources in lanes (the quadrature nodes of one flat triangle, which all
/// interpolate from its three vertices): positions (um, in the frame of the shifted target) and,
/// per vertex `v`, the weights `c_vk = l_kv w_k` (barycentric weight times quadrature weight,
/// um^2); padding lanes have `valid = 0`.
#[derive(Debug, Clone, Copy, Default)]
pub struct WeightedLanes {
    pub x: [[f64; LANES]; 3],
    pub c: [[f64; LANES]; 3],
    pub valid: [f64; LANES],
}

/// What one Stokeslet group gives one target ([`Kernel::stokeslet_blocks`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GroupAtTarget {
    /// No source within the cutoff.
    Outside,
    /// The three vertex blocks ([`Sym`]).
    Blocks([Sym; 3]),
    /// A source within the coincidence radius: its self term is the plain build's business.
    Coincident,
}

/// The constants of a build: splitting, cutoff, coincidence radius, the `erfcx` table and the
/// barycentric weights of the nodes on the three vertices, in lanes (`0` in padding lanes).
#[derive(Debug, Clone)]
pub struct Kernel {
    pub xi: f64,
    pub rc2: f64,
    pub eps2: f64,
    pub erfcx: &'static Erfcx,
    pub bary: [[f64; LANES]; 3],
}

impl Kernel {
    /// The three symmetric 3 x 3 blocks ([`Sym`]) `sum_k l_kv K(t - y_k, n_k)` of one triangle at target `t`
    /// (pairs with `|r| >= r_cut` or `|r| <= eps` add nothing) and, with `SL`, the real-space
    /// Stokeslet sum of its weighted forces `sum_k (a f_k + b r (r . f_k))` of the same pairs
    /// ([`super::split::stokeslet_ab`]: `r`, `erfc` and `exp` are shared); `None` when no pair is inside.
    #[inline(always)]
    fn blocks_portable<const SL: bool>(&self, t: [f64; 3], nodes: &NodeLanes) -> Option<TriangleAtTarget> {
        // every loop runs over the lanes innermost, so that it vectorises
        let mut r = [[0.0f64; LANES]; 3];
        let mut inside = [0.0f64; LANES];
        let mut rn = [0.0f64; LANES];
        for l in 0..LANES {
            for d in 0..3 {
                r[d][l] = t[d] - nodes.x[d][l];
            }
            let r2 = r[0][l].mul_add(r[0][l], r[1][l].mul_add(r[1][l], r[2][l] * r[2][l]));
            // (`&`, not `&&`: no branches, so that the loop vectorises)
            let take = (nodes.valid[l] != 0.0) & (r2 < self.rc2) & (r2 > self.eps2);
            inside[l] = if take { 1.0 } else { 0.0 };
            rn[l] = if take { r2 } else { 1.0 }.sqrt();
        }
        if inside.iter().all(|&i| i == 0.0) {
            return None;
        }
        let xi = self.xi;
        let s: [f64; LANES] = std::array::from_fn(|l| xi * rn[l]);
        let e = exp_lanes(std::array::from_fn(|l| -s[l] * s[l]));
        let erfcx = self.erfcx.eval_lanes(&s);
        // the kernel is symmetric: its upper triangle only
        let mut k = [[0.0f64; LANES]; 6];
        let mut sl = [[0.0f64; LANES]; 3];
        for l in 0..LANES {
            if SL {
                let (a, b) = stokeslet_ab(xi, rn[l], erfcx[l] * e[l], e[l]);
                let (a, b) = (a * inside[l], b * inside[l]);
                let f = [nodes.f[0][l], nodes.f[1][l], nodes.f[2][l]];
                let c = b * r[0][l].mul_add(f[0], r[1][l].mul_add(f[1], r[2][l] * f[2]));
                for d in 0..3 {
                    sl[d][l] = a.mul_add(f[d], c * r[d][l]);
                }
            }
            let (a, b) = stresslet_ab(xi, rn[l], erfcx[l] * e[l], e[l]);
            let (a, b) = (a * inside[l], b * inside[l]);
            let rl = [r[0][l], r[1][l], r[2][l]];
            let n = [nodes.n[0][l], nodes.n[1][l], nodes.n[2][l]];
            let rdn = rl[0] * n[0] + rl[1] * n[1] + rl[2] * n[2];
            let (brn, arn) = (b * rdn, a * rdn);
            for (i, &(p, q)) in SYM_PQ.iter().enumerate() {
                k[i][l] = brn * rl[p] * rl[q] + a * (rl[p] * n[q] + n[p] * rl[q]) + if p == q { arn } else { 0.0 };
            }
        }
        // sums over the lanes as a tree (halves, quarters, pairs), which maps onto vector adds;
        // plain loops (nested `array::from_fn` closures were left out of line, their results
        // moved through the stack: a third of the build's time)
        let mut out = [[0.0f64; 6]; 3];
        for (o, bary) in out.iter_mut().zip(&self.bary) {
            for (oi, ki) in o.iter_mut().zip(&k) {
                let mut w = [0.0f64; LANES];
                for l in 0..LANES {
                    w[l] = bary[l] * ki[l];
                }
                let h = [w[0] + w[4], w[1] + w[5], w[2] + w[6], w[3] + w[7]];
                *oi = (h[0] + h[2]) + (h[1] + h[3]);
            }
        }
        let mut single = [0.0f64; 3];
        if SL {
            for (o, w) in single.iter_mut().zip(&sl) {
                let h = [w[0] + w[4], w[1] + w[5], w[2] + w[6], w[3] + w[7]];
                *o = (h[0] + h[2]) + (h[1] + h[3]);
            }
        }
        Some((out, single))
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn blocks_avx512<const SL: bool>(&self, t: [f64; 3], nodes: &NodeLanes) -> Option<TriangleAtTarget> {
        zmm::blocks::<SL>(self, t, nodes)
    }

    /// The three vertex blocks of one triangle at target `t`, with the real-space Stokeslet sum
    /// of its forces when `SL` (see `blocks_portable`), compiled for AVX-512 when the CPU has it.
    #[inline]
    pub fn blocks<const SL: bool>(&self, t: [f64; 3], nodes: &NodeLanes, avx512: bool) -> Option<TriangleAtTarget> {
        #[cfg(target_arch = "x86_64")]
        if avx512 {
            // SAFETY: the caller checked the CPU has AVX-512F (`crate::bim::kernels::avx512_available`).
            return unsafe { self.blocks_avx512::<SL>(t, nodes) };
        }
        let _ = avx512;
        self.blocks_portable::<SL>(t, nodes)
    }

    /// The three vertex blocks `sum_k c_vk G^R(t - y_k)` of one Stokeslet group at target `t`
    /// (`G^R = a I + b r r^T`, [`super::split::stokeslet_ab`]; pairs beyond the cutoff add nothing;
    /// `bary` is not used: the weights are the group's). Lanes innermost, as `blocks_portable`.
    #[inline(always)]
    fn stokeslet_portable(&self, t: [f64; 3], g: &WeightedLanes) -> GroupAtTarget {
        let mut r = [[0.0f64; LANES]; 3];
        let mut inside = [0.0f64; LANES];
        let mut rn = [0.0f64; LANES];
        let mut coincident = false;
        for l in 0..LANES {
            for d in 0..3 {
                r[d][l] = t[d] - g.x[d][l];
            }
            let r2 = r[0][l].mul_add(r[0][l], r[1][l].mul_add(r[1][l], r[2][l] * r[2][l]));
            let valid = g.valid[l] != 0.0;
            coincident |= valid & (r2 <= self.eps2);
            let take = valid & (r2 < self.rc2) & (r2 > self.eps2);
            inside[l] = if take { 1.0 } else { 0.0 };
            rn[l] = if take { r2 } else { 1.0 }.sqrt();
        }
        if coincident {
            return GroupAtTarget::Coincident;
        }
        if inside.iter().all(|&i| i == 0.0) {
            return GroupAtTarget::Outside;
        }
        let xi = self.xi;
        let s: [f64; LANES] = std::array::from_fn(|l| xi * rn[l]);
        let e = exp_lanes(std::array::from_fn(|l| -s[l] * s[l]));
        let erfcx = self.erfcx.eval_lanes(&s);
        let mut k = [[0.0f64; LANES]; 6];
        for l in 0..LANES {
            let (a, b) = stokeslet_ab(xi, rn[l], erfcx[l] * e[l], e[l]);
            let (a, b) = (a * inside[l], b * inside[l]);
            for (i, &(p, q)) in SYM_PQ.iter().enumerate() {
                k[i][l] = b * r[p][l] * r[q][l] + if p == q { a } else { 0.0 };
            }
        }
        let mut out = [[0.0f64; 6]; 3];
        for (o, c) in out.iter_mut().zip(&g.c) {
            for (oi, ki) in o.iter_mut().zip(&k) {
                let mut w = [0.0f64; LANES];
                for l in 0..LANES {
                    w[l] = c[l] * ki[l];
                }
                let h = [w[0] + w[4], w[1] + w[5], w[2] + w[6], w[3] + w[7]];
                *oi = (h[0] + h[2]) + (h[1] + h[3]);
            }
        }
        GroupAtTarget::Blocks(out)
    }

    /// `Self::stokeslet_portable`, compiled for AVX-512 registers when the CPU has them (`zmm`).
    #[inline]
    pub fn stokeslet_blocks(&self, t: [f64; 3], g: &WeightedLanes, avx512: bool) -> GroupAtTarget {
        #[cfg(target_arch = "x86_64")]
        if avx512 {
            // SAFETY: the caller checked the CPU has AVX-512F (`crate::bim::kernels::avx512_available`).
            return unsafe { self.stokeslet_avx512(t, g) };
        }
        let _ = avx512;
        self.stokeslet_portable(t, g)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn stokeslet_avx512(&self, t: [f64; 3], g: &WeightedLanes) -> GroupAtTarget {
        zmm::stokeslet(self, t, g)
    }
}

/// `Kernel::blocks` written for AVX-512 registers: the eight lanes of a triangle in one `__m512d`
/// each, every intermediate kept in registers (32 of them), `1/r` by `vrsqrt14pd` refined to
/// rounding instead of a square root and a division, and the 21 lane sums (three vertex blocks of six entries, the single layer's three
/// components) as three transposing reductions of eight registers each (21 vector operations per
/// eight sums, against ~6 per sum one by one, whose stores and reloads dominated the portable
/// build). The same kernel as `blocks_portable`, to rounding (test `the_avx512_blocks_match_the_portable_ones`).
#[cfg(target_arch = "x86_64")]
mod zmm {
    use super::{GroupAtTarget, Kernel, NodeLanes, TriangleAtTarget, WeightedLanes, LANES};
    use std::arch::x86_64::*;
    use super::super::split::FRAC_1_SQRT_PI;

    use crate::bim::kernels::avx512::load;

    #[inline]
    #[target_feature(enable = "avx512f")]
    fn store(v: __m512d) -> [f64; LANES] {
        // SAFETY: `[f64; 8]` and `__m512d` have the same size and every bit pattern is valid for both
        unsafe { std::mem::transmute::<__m512d, [f64; LANES]>(v) }
    }

    /// `1/sqrt(r2)` to rounding: the free-space sums' `vrsqrt14pd` with a third-order step
    /// (`< 6e-13`, `crate::bim::kernels`) and one Newton step more (`3/2 (6e-13)^2`, below
    /// rounding). Full precision matters here: `exp(-s^2)` multiplies the relative error of
    /// `s = xi r` by `2 s^2` (~110 at the cutoff), which a 6e-13 `1/r` would carry into the kernel
    /// as 7e-11.
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn rsqrt(r2: __m512d) -> __m512d {
        let y = crate::bim::kernels::avx512::rsqrt(r2);
        let e = _mm512_fnmadd_pd(_mm512_mul_pd(r2, y), y, _mm512_set1_pd(1.0));
        _mm512_fmadd_pd(_mm512_mul_pd(y, e), _mm512_set1_pd(0.5), y)
    }

    /// [`super::exp_nonpositive`] of each lane (the same reduction and polynomial; `m` rounded to
    /// even at exact halves instead of away from zero, which changes `q` by `ln 2` and nothing else).
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn exp_nonpositive(x: __m512d) -> __m512d {
        const LN2_HI: f64 = 6.931_471_803_691_238e-1;
        const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
        let m = _mm512_roundscale_pd::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(_mm512_mul_pd(x, _mm512_set1_pd(std::f64::consts::LOG2_E)));
        let q = _mm512_fnmadd_pd(m, _mm512_set1_pd(LN2_LO), _mm512_fnmadd_pd(m, _mm512_set1_pd(LN2_HI), x));
        let mut p = _mm512_set1_pd(1.0 / 6_227_020_800.0);
        for c in INV_FACTORIAL.iter().rev() {
            p = _mm512_fmadd_pd(p, q, _mm512_set1_pd(*c));
        }
        let bits = _mm512_castpd_si512(_mm512_add_pd(m, _mm512_set1_pd(4_503_599_627_371_519.0)));
        _mm512_mul_pd(p, _mm512_castsi512_pd(_mm512_slli_epi64::<52>(bits)))
    }

    /// `1/k!`, `k = 0 .. 12` (the Taylor coefficients below the leading `1/13!`).
    const INV_FACTORIAL: [f64; 13] = [
        1.0,
        1.0,
        0.5,
        1.0 / 6.0,
        1.0 / 24.0,
        1.0 / 120.0,
        1.0 / 720.0,
        1.0 / 5_040.0,
        1.0 / 40_320.0,
        1.0 / 362_880.0,
        1.0 / 3_628_800.0,
        1.0 / 39_916_800.0,
        1.0 / 479_001_600.0,
    ];

    /// The sums of eight registers' lanes: lane `i` of the result is the sum of the lanes of `v[i]`
    /// (a transposing tree: pairs within 128-bit chunks, then chunks; 21 operations).
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn sums8(v: [__m512d; 8]) -> __m512d {
        // level 1: chunk c of `p_k` holds (lanes 2c + 2c+1 of v[2k], of v[2k+1])
        let p = [0, 1, 2, 3].map(|k| _mm512_add_pd(_mm512_unpacklo_pd(v[2 * k], v[2 * k + 1]), _mm512_unpackhi_pd(v[2 * k], v[2 * k + 1])));
        // level 2: chunks (0 + 1, 2 + 3) of two such registers side by side
        let half = |a: __m512d, b: __m512d| _mm512_add_pd(_mm512_shuffle_f64x2::<0b10_00_10_00>(a, b), _mm512_shuffle_f64x2::<0b11_01_11_01>(a, b));
        let q0 = half(p[0], p[1]);
        let q1 = half(p[2], p[3]);
        // level 3: chunk k of the result holds the totals of v[2k], v[2k+1]
        half(q0, q1)
    }

    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(super) fn blocks<const SL: bool>(k: &Kernel, t: [f64; 3], nodes: &NodeLanes) -> Option<TriangleAtTarget> {
        let rx = _mm512_sub_pd(_mm512_set1_pd(t[0]), load(&nodes.x[0]));
        let ry = _mm512_sub_pd(_mm512_set1_pd(t[1]), load(&nodes.x[1]));
        let rz = _mm512_sub_pd(_mm512_set1_pd(t[2]), load(&nodes.x[2]));
        let r2 = _mm512_fmadd_pd(rx, rx, _mm512_fmadd_pd(ry, ry, _mm512_mul_pd(rz, rz)));
        let valid = _mm512_cmp_pd_mask::<_CMP_NEQ_OQ>(load(&nodes.valid), _mm512_setzero_pd());
        let inside = valid & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(r2, _mm512_set1_pd(k.rc2)) & _mm512_cmp_pd_mask::<_CMP_GT_OQ>(r2, _mm512_set1_pd(k.eps2));
        if inside == 0 {
            return None;
        }
        let one = _mm512_set1_pd(1.0);
        let r2 = _mm512_mask_blend_pd(inside, one, r2);
        let ir = rsqrt(r2);
        let rn = _mm512_mul_pd(r2, ir);
        let xi = _mm512_set1_pd(k.xi);
        let s = _mm512_mul_pd(xi, rn);
        let e = exp_nonpositive(_mm512_sub_pd(_mm512_setzero_pd(), _mm512_mul_pd(s, s)));
        // SAFETY: this function runs only where AVX-512F is enabled; `s < xi r_cut < 8`
        let erfc = _mm512_mul_pd(unsafe { k.erfcx.eval_zmm(s) }, e);
        let ir2 = _mm512_mul_pd(ir, ir);
        // the stresslet's A and B ([`super::super::split::stresslet_ab`]), zero outside
        let c = _mm512_mul_pd(_mm512_set1_pd(4.0 * k.xi * FRAC_1_SQRT_PI), e);
        let a = _mm512_maskz_mul_pd(inside, _mm512_set1_pd(-k.xi * k.xi), c);
        let b5 = _mm512_mul_pd(_mm512_mul_pd(_mm512_set1_pd(6.0), erfc), _mm512_mul_pd(_mm512_mul_pd(ir2, ir2), ir));
        let b = _mm512_maskz_mov_pd(inside, _mm512_fmadd_pd(_mm512_mul_pd(c, ir2), _mm512_fmadd_pd(_mm512_set1_pd(3.0), ir2, _mm512_set1_pd(2.0 * k.xi * k.xi)), b5));
        let (nx, ny, nz) = (load(&nodes.n[0]), load(&nodes.n[1]), load(&nodes.n[2]));
        let rdn = _mm512_fmadd_pd(rx, nx, _mm512_fmadd_pd(ry, ny, _mm512_mul_pd(rz, nz)));
        let (brn, arn) = (_mm512_mul_pd(b, rdn), _mm512_mul_pd(a, rdn));
        let r = [rx, ry, rz];
        let n = [nx, ny, nz];
        // the upper triangle `(p, q)` of [`super::SYM_PQ`]
        let entry = |p: usize, q: usize| {
            let cross = _mm512_mul_pd(a, _mm512_fmadd_pd(r[p], n[q], _mm512_mul_pd(n[p], r[q])));
            let v = _mm512_fmadd_pd(_mm512_mul_pd(brn, r[p]), r[q], cross);
            if p == q {
                _mm512_add_pd(v, arn)
            } else {
                v
            }
        };
        let kk = [entry(0, 0), entry(0, 1), entry(0, 2), entry(1, 1), entry(1, 2), entry(2, 2)];
        let sl = if SL {
            // the Stokeslet's a and b ([`super::super::split::stokeslet_ab`]), zero outside
            let cs = _mm512_mul_pd(_mm512_set1_pd(2.0 * k.xi * FRAC_1_SQRT_PI), e);
            let eir = _mm512_mul_pd(erfc, ir);
            let sa = _mm512_maskz_sub_pd(inside, eir, cs);
            let sb = _mm512_maskz_mul_pd(inside, _mm512_add_pd(eir, cs), ir2);
            let f = [load(&nodes.f[0]), load(&nodes.f[1]), load(&nodes.f[2])];
            let cc = _mm512_mul_pd(sb, _mm512_fmadd_pd(rx, f[0], _mm512_fmadd_pd(ry, f[1], _mm512_mul_pd(rz, f[2]))));
            [0, 1, 2].map(|d| _mm512_fmadd_pd(sa, f[d], _mm512_mul_pd(cc, r[d])))
        } else {
            [_mm512_setzero_pd(); 3]
        };
        let w = [load(&k.bary[0]), load(&k.bary[1]), load(&k.bary[2])];
        let bk = |v: usize, i: usize| _mm512_mul_pd(w[v], kk[i]);
        let s0 = store(sums8([bk(0, 0), bk(0, 1), bk(0, 2), bk(0, 3), bk(0, 4), bk(0, 5), bk(1, 0), bk(1, 1)]));
        let s1 = store(sums8([bk(1, 2), bk(1, 3), bk(1, 4), bk(1, 5), bk(2, 0), bk(2, 1), bk(2, 2), bk(2, 3)]));
        let zero = _mm512_setzero_pd();
        let s2 = store(sums8([bk(2, 4), bk(2, 5), sl[0], sl[1], sl[2], zero, zero, zero]));
        let out = [[s0[0], s0[1], s0[2], s0[3], s0[4], s0[5]], [s0[6], s0[7], s1[0], s1[1], s1[2], s1[3]], [s1[4], s1[5], s1[6], s1[7], s2[0], s2[1]]];
        Some((out, [s2[2], s2[3], s2[4]]))
    }

    /// See `Kernel::stokeslet_portable`.
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(super) fn stokeslet(k: &Kernel, t: [f64; 3], g: &WeightedLanes) -> GroupAtTarget {
        let rx = _mm512_sub_pd(_mm512_set1_pd(t[0]), load(&g.x[0]));
        let ry = _mm512_sub_pd(_mm512_set1_pd(t[1]), load(&g.x[1]));
        let rz = _mm512_sub_pd(_mm512_set1_pd(t[2]), load(&g.x[2]));
        let r2 = _mm512_fmadd_pd(rx, rx, _mm512_fmadd_pd(ry, ry, _mm512_mul_pd(rz, rz)));
        let valid = _mm512_cmp_pd_mask::<_CMP_NEQ_OQ>(load(&g.valid), _mm512_setzero_pd());
        if valid & _mm512_cmp_pd_mask::<_CMP_LE_OQ>(r2, _mm512_set1_pd(k.eps2)) != 0 {
            return GroupAtTarget::Coincident;
        }
        let inside = valid & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(r2, _mm512_set1_pd(k.rc2)) & _mm512_cmp_pd_mask::<_CMP_GT_OQ>(r2, _mm512_set1_pd(k.eps2));
        if inside == 0 {
            return GroupAtTarget::Outside;
        }
        let r2 = _mm512_mask_blend_pd(inside, _mm512_set1_pd(1.0), r2);
        let ir = rsqrt(r2);
        let s = _mm512_mul_pd(_mm512_set1_pd(k.xi), _mm512_mul_pd(r2, ir));
        let e = exp_nonpositive(_mm512_sub_pd(_mm512_setzero_pd(), _mm512_mul_pd(s, s)));
        // SAFETY: this function runs only where AVX-512F is enabled; `s < xi r_cut < 8`
        let erfc = _mm512_mul_pd(unsafe { k.erfcx.eval_zmm(s) }, e);
        // the Stokeslet's a and b ([`super::super::split::stokeslet_ab`]), zero outside
        let cs = _mm512_mul_pd(_mm512_set1_pd(2.0 * k.xi * FRAC_1_SQRT_PI), e);
        let eir = _mm512_mul_pd(erfc, ir);
        let a = _mm512_maskz_sub_pd(inside, eir, cs);
        let b = _mm512_maskz_mul_pd(inside, _mm512_add_pd(eir, cs), _mm512_mul_pd(ir, ir));
        let r = [rx, ry, rz];
        let entry = |p: usize, q: usize| {
            let v = _mm512_mul_pd(_mm512_mul_pd(b, r[p]), r[q]);
            if p == q {
                _mm512_add_pd(v, a)
            } else {
                v
            }
        };
        let kk = [entry(0, 0), entry(0, 1), entry(0, 2), entry(1, 1), entry(1, 2), entry(2, 2)];
        let w = [load(&g.c[0]), load(&g.c[1]), load(&g.c[2])];
        let ck = |v: usize, i: usize| _mm512_mul_pd(w[v], kk[i]);
        let s0 = store(sums8([ck(0, 0), ck(0, 1), ck(0, 2), ck(0, 3), ck(0, 4), ck(0, 5), ck(1, 0), ck(1, 1)]));
        let s1 = store(sums8([ck(1, 2), ck(1, 3), ck(1, 4), ck(1, 5), ck(2, 0), ck(2, 1), ck(2, 2), ck(2, 3)]));
        let zero = _mm512_setzero_pd();
        let s2 = store(sums8([ck(2, 4), ck(2, 5), zero, zero, zero, zero, zero, zero]));
        GroupAtTarget::Blocks([[s0[0], s0[1], s0[2], s0[3], s0[4], s0[5]], [s0[6], s0[7], s1[0], s1[1], s1[2], s1[3]], [s1[4], s1[5], s1[6], s1[7], s2[0], s2[1]]])
    }
}

/// Pairs of a real-space Stokeslet sum gathered eight at a time (separation `r`, um, and force
/// `f`), then evaluated together in lanes: `G^R(r) f = a f + b r (r . f)` with
/// `a = erfc(s)/r - 2 xi/sqrt(pi) e`, `b = (erfc(s)/r + 2 xi/sqrt(pi) e)/r^2` ([`super::split::stokeslet_ab`]).
/// The caller pushes only pairs with `eps < |r| < r_cut` (the same pairs as the scalar sum).
#[derive(Debug, Clone)]
pub struct StokesletLanes {
    xi: f64,
    erfcx: &'static Erfcx,
    avx512: bool,
    r: [[f64; LANES]; 3],
    f: [[f64; LANES]; 3],
    len: usize,
    /// Per-lane partial sums of the target's velocity (before [`Self::total`]).
    acc: [[f64; LANES]; 3],
}

impl StokesletLanes {
    pub fn new(xi: f64, avx512: bool) -> Self {
        Self { xi, erfcx: Erfcx::get(), avx512, r: [[0.0; LANES]; 3], f: [[0.0; LANES]; 3], len: 0, acc: [[0.0; LANES]; 3] }
    }

    /// Queue one pair; evaluates the batch when it is full.
    #[inline(always)]
    pub fn push(&mut self, r: [f64; 3], f: [f64; 3]) {
        let l = self.len;
        for d in 0..3 {
            self.r[d][l] = r[d];
            self.f[d][l] = f[d];
        }
        self.len += 1;
        if self.len == LANES {
            self.flush();
        }
    }

    /// Evaluate the queued pairs (unused lanes carry `f = 0` at `r = (1, 0, 0)` um: they add nothing).
    pub fn flush(&mut self) {
        if self.len == 0 {
            return;
        }
        for l in self.len..LANES {
            self.r[0][l] = 1.0;
            self.r[1][l] = 0.0;
            self.r[2][l] = 0.0;
            for d in 0..3 {
                self.f[d][l] = 0.0;
            }
        }
        #[cfg(target_arch = "x86_64")]
        if self.avx512 {
            // SAFETY: `avx512` was set from `crate::bim::kernels::avx512_available`.
            unsafe { self.flush_avx512() };
            self.len = 0;
            return;
        }
        self.flush_portable();
        self.len = 0;
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn flush_avx512(&mut self) {
        self.flush_portable()
    }

    #[inline(always)]
    fn flush_portable(&mut self) {
        let xi = self.xi;
        let r = &self.r;
        let rn: [f64; LANES] = std::array::from_fn(|l| r[0][l].mul_add(r[0][l], r[1][l].mul_add(r[1][l], r[2][l] * r[2][l])).sqrt());
        let s: [f64; LANES] = std::array::from_fn(|l| xi * rn[l]);
        let e = exp_lanes(std::array::from_fn(|l| -s[l] * s[l]));
        let erfcx = self.erfcx.eval_lanes(&s);
        for l in 0..LANES {
            let (a, b) = stokeslet_ab(xi, rn[l], erfcx[l] * e[l], e[l]);
            let (r, f) = ([self.r[0][l], self.r[1][l], self.r[2][l]], [self.f[0][l], self.f[1][l], self.f[2][l]]);
            let c = b * r[0].mul_add(f[0], r[1].mul_add(f[1], r[2] * f[2]));
            for d in 0..3 {
                self.acc[d][l] += a.mul_add(f[d], c * r[d]);
            }
        }
    }

    /// Flush and return the target's sum; the accumulators start again from zero.
    pub fn total(&mut self) -> [f64; 3] {
        self.flush();
        let t = [0, 1, 2].map(|d| self.acc[d].iter().sum());
        self.acc = [[0.0; LANES]; 3];
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AVX-512 blocks (`zmm::blocks`) against the portable ones, with and without the fused
    /// single layer: triangles of 7 nodes and a padding lane around targets from coincident
    /// (`<= eps`, skipped) through the cutoff (partly inside) to beyond it (`None`), `xi r` up to
    /// the table's end. Entry by entry within 1e-13 of the block's largest entry (`exp(-s^2)`
    /// amplifies the rounding of `s` by up to ~110 near the cutoff), the same pairs taken.
    #[test]
    fn the_avx512_blocks_match_the_portable_ones() {
        // (through the dispatch: on a CPU without AVX-512 both sides are the portable path, and
        // the pairs taken, the coincident target and the cases' coverage are still checked)
        let avx = crate::bim::kernels::avx512_available();
        let erfcx = Erfcx::get();
        let bary7: [[f64; 3]; 7] = [[1.0 / 3.0; 3], [0.6, 0.2, 0.2], [0.2, 0.6, 0.2], [0.2, 0.2, 0.6], [0.05, 0.475, 0.475], [0.475, 0.05, 0.475], [0.475, 0.475, 0.05]];
        let kernel = Kernel {
            xi: 2.1,
            rc2: 3.6f64.powi(2),
            eps2: 1e-10,
            erfcx,
            bary: std::array::from_fn(|v| std::array::from_fn(|k| if k < 7 { bary7[k][v] } else { 0.0 })),
        };
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut compared, mut skipped) = (0, 0);
        for case in 0..4000 {
            let mut nodes = NodeLanes::default();
            let centre = [uniform() * 8.0 - 4.0, uniform() * 8.0 - 4.0, uniform() * 8.0 - 4.0];
            for l in 0..7 {
                for d in 0..3 {
                    nodes.x[d][l] = centre[d] + 0.6 * (uniform() - 0.5);
                    nodes.n[d][l] = 0.05 * (uniform() - 0.5);
                    nodes.f[d][l] = uniform() - 0.5;
                }
                nodes.valid[l] = 1.0;
            }
            // a target on a node now and then: that pair is left out by both
            let t = if case % 50 == 0 { [nodes.x[0][3], nodes.x[1][3], nodes.x[2][3]] } else { [0.0; 3] };
            let portable = kernel.blocks_portable::<true>(t, &nodes);
            let fast = kernel.blocks::<true>(t, &nodes, avx);
            let plain = kernel.blocks::<false>(t, &nodes, avx);
            match (portable, fast, plain) {
                (None, None, None) => skipped += 1,
                (Some((pb, ps)), Some((fb, fs)), Some((qb, qs))) => {
                    let scale = pb.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
                    for (p, f) in pb.iter().flatten().zip(fb.iter().flatten()) {
                        assert!((p - f).abs() <= 1e-13 * scale, "case {case}: block entry {p:e} against {f:e}");
                    }
                    assert_eq!(fb, qb, "case {case}: the blocks do not depend on the fused single layer");
                    assert_eq!(qs, [0.0; 3]);
                    let scale = ps.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    for (p, f) in ps.iter().zip(&fs) {
                        // (the seven forces' terms cancel in part: 1e-12 of the largest component)
                        assert!((p - f).abs() <= 1e-12 * scale, "case {case}: single layer {p:e} against {f:e}");
                    }
                    compared += 1;
                }
                other => panic!("case {case}: the paths disagree on whether any pair is inside: {other:?}"),
            }
            // the Stokeslet groups of the same nodes, weights `l_kv w_k`
            let mut group = WeightedLanes { x: nodes.x, valid: nodes.valid, ..Default::default() };
            for v in 0..3 {
                for l in 0..7 {
                    group.c[v][l] = kernel.bary[v][l] * (0.5 + uniform());
                }
            }
            let portable = kernel.stokeslet_portable(t, &group);
            let fast = kernel.stokeslet_blocks(t, &group, avx);
            match (portable, fast) {
                (GroupAtTarget::Blocks(pb), GroupAtTarget::Blocks(fb)) => {
                    let scale = pb.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
                    for (p, f) in pb.iter().flatten().zip(fb.iter().flatten()) {
                        assert!((p - f).abs() <= 1e-13 * scale, "case {case}: Stokeslet block entry {p:e} against {f:e}");
                    }
                }
                (p, f) => assert_eq!(p, f, "case {case}: the Stokeslet paths disagree"),
            }
            if case % 50 == 0 {
                assert_eq!(fast, GroupAtTarget::Coincident, "case {case}: a target on a node");
            }
        }
        assert!(compared > 1000 && skipped > 100, "the cases span inside and beyond the cutoff: {compared} compared, {skipped} skipped");
    }
    
    /// The branch-free `exp` against libm's, and the lanes of the `erfcx` table against its scalar path.
    #[test]
    fn exp_and_erfcx_lanes_match() {
        let mut worst: f64 = 0.0;
        for i in 0..=20_000 {
            let x = -40.0 * i as f64 / 20_000.0;
            worst = worst.max((exp_nonpositive(x) - x.exp()).abs() / x.exp());
        }
        assert!(worst < 4e-16, "exp: worst relative error {worst:e}");
        let table = Erfcx::get();
        for i in 0..1000 {
            let x: [f64; LANES] = std::array::from_fn(|l| 7.999 * ((i * LANES + l) as f64 / (1000 * LANES) as f64));
            let lanes = table.eval_lanes(&x);
            for l in 0..LANES {
                assert_eq!(lanes[l], table.eval(x[l]), "erfcx({})", x[l]);
            }
        }
    }
}
