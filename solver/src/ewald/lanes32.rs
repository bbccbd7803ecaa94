//! The real-space stresslet blocks of two triangles at once in sixteen single-precision AVX-512
//! lanes: the kernel of [`super::lanes`] (`B (r . n) r r^T + A (r n^T + (r . n) I + n r^T)`, with
//! the fused real-space Stokeslet of the forces) for the stresslet blocks the channel's double
//! layer rebuilds for every solve ([`super::blocks::BlockRows::stresslet_grouped`] with
//! [`BlockPrecision::Single`]).
//!
//! What stays in double precision: the separations `r = t - y` and `r . n` (the target and the
//! nodes are ~10 um from the origin, the nearest pairs ~0.1 um apart, and `r . n` of two
//! neighbouring nodes of a smooth surface cancels to ~`|r| |n| / 30`), the exponent `-xi^2 r^2`,
//! and the sums over a triangle's three vertex blocks and over the triangles of a row. What runs
//! in single precision: `1/r` (`vrsqrt14ps` and one Newton step, relative error ~1e-8), `exp`
//! (Cody & Waite reduction, Taylor to degree 7, `< 1e-8`), `erfcx` (below), the kernel's products
//! and the sums over a triangle's nodes. Each kernel value then carries a relative error of a few
//! 1e-7 (the exponent's rounding to single precision, `|x| <= (xi r_cut)^2 ~ 10` times 6e-8, is
//! the largest part, and only at pairs near the cutoff, where the kernel is ~1e-4 of its size at
//! the nearest pairs): two orders of magnitude below the Ewald tolerance these sums meet (1e-4 in
//! the paper's channel) and the GMRES tolerance (1e-5). Test
//! `single_precision_blocks_match_double_ones`: within 1e-6 of each block's largest entry.
//!
//! `erfcx(x) = exp(x^2) erfc(x)` on `[0, 4)` (the splitting keeps `xi r < xi r_cut`, which is
//! `sqrt(ln(1/tol) + 1)`, 3.2 at tol 1e-4; a build whose cutoff reaches beyond 4 keeps double
//! precision): 16 intervals of 1/4, each a polynomial of degree [`DEGREE`] in the interval's
//! local variable `t in [-1, 1]` (Chebyshev interpolation of the double table [`super::erfc::Erfcx`],
//! rewritten in powers of `t`), its coefficients for all 16 intervals held in one register per
//! power and picked per lane by `vpermps`: no gathers.

use std::sync::OnceLock;

use super::erfc::Erfcx;

/// Upper end (exclusive) of the single-precision `erfcx` table.
pub const X_MAX: f64 = 4.0;
/// Intervals of the table (one per lane of a single-precision register).
const INTERVALS: usize = 16;
/// Polynomial degree per interval.
pub const DEGREE: usize = 6;

/// How a stresslet block build evaluates its kernels ([`super::blocks::BlockRows::stresslet_grouped`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BlockPrecision {
    /// Double precision throughout (the blocks to rounding of the plain sums).
    #[default]
    Double,
    /// The kernel in single precision, two triangles per 16-lane register (this module), where
    /// the CPU has AVX-512 and the cutoff keeps `xi r_cut < 4`; double precision elsewhere.
    Single,
}

/// `erfcx` on `[0, 4)` by intervals, in single precision: `coef[j][i]` is the coefficient of `t^j`
/// in interval `i`, `t = 2 (4 x - i) - 1`.
#[derive(Debug)]
pub struct ErfcxF32 {
    pub coef: [[f32; INTERVALS]; DEGREE + 1],
}

impl ErfcxF32 {
    /// The shared table (built on first use from [`Erfcx`]).
    pub fn get() -> &'static Self {
        static TABLE: OnceLock<ErfcxF32> = OnceLock::new();
        TABLE.get_or_init(Self::build)
    }

    fn build() -> Self {
        const N: usize = DEGREE + 1;
        let table = Erfcx::get();
        let width = X_MAX / INTERVALS as f64;
        let mut coef = [[0.0f32; INTERVALS]; N];
        for i in 0..INTERVALS {
            let a = i as f64 * width;
            // Chebyshev interpolation at the points of the first kind
            let values: Vec<f64> = (0..N)
                .map(|k| {
                    let t = (std::f64::consts::PI * (k as f64 + 0.5) / N as f64).cos();
                    table.eval(a + 0.5 * width * (t + 1.0))
                })
                .collect();
            let mut cheb = [0.0f64; N];
            for (j, c) in cheb.iter_mut().enumerate() {
                let s: f64 = (0..N).map(|k| values[k] * (std::f64::consts::PI * j as f64 * (k as f64 + 0.5) / N as f64).cos()).sum();
                *c = s * 2.0 / N as f64;
            }
            cheb[0] *= 0.5;
            // powers of t: T_0 = 1, T_1 = t, T_{j+1} = 2 t T_j - T_{j-1}
            let mut power = [0.0f64; N];
            let (mut prev, mut cur) = ([0.0f64; N], [0.0f64; N]);
            prev[0] = 1.0;
            cur[1] = 1.0;
            for (j, &c) in cheb.iter().enumerate() {
                let t_j = match j {
                    0 => prev,
                    1 => cur,
                    _ => {
                        let mut next = [0.0f64; N];
                        for p in 0..N {
                            next[p] = if p > 0 { 2.0 * cur[p - 1] } else { 0.0 } - prev[p];
                        }
                        prev = cur;
                        cur = next;
                        next
                    }
                };
                for p in 0..N {
                    power[p] += c * t_j[p];
                }
            }
            for p in 0..N {
                coef[p][i] = power[p] as f32;
            }
        }
        Self { coef }
    }

    /// `erfcx(x)`, `0 <= x < 4`, from the single-precision coefficients (in double arithmetic:
    /// what the lanes compute up to their own rounding).
    pub fn eval(&self, x: f64) -> f64 {
        let u = x * (INTERVALS as f64 / X_MAX);
        let i = (u.floor() as usize).min(INTERVALS - 1);
        let t = 2.0 * (u - i as f64) - 1.0;
        self.coef.iter().rev().fold(0.0, |p, c| p * t + c[i] as f64)
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) mod zmm {
    use std::arch::x86_64::*;

    use super::super::lanes::{Kernel, NodeLanes};
    use super::super::split::FRAC_1_SQRT_PI;
    use super::{ErfcxF32, DEGREE, INTERVALS, X_MAX};
    use crate::bim::kernels::avx512::load;

    /// Two f64 registers rounded to single precision side by side (lanes 0-7, 8-15).
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn join(lo: __m512d, hi: __m512d) -> __m512 {
        let lo = _mm512_castps256_ps512(_mm512_cvtpd_ps(lo));
        _mm512_castpd_ps(_mm512_insertf64x4::<1>(_mm512_castps_pd(lo), _mm256_castps_pd(_mm512_cvtpd_ps(hi))))
    }

    /// `exp(x)`, `x <= 0` (and `>= -87`), in single precision: `x = m ln 2 + q`, `|q| <= ln 2 / 2`,
    /// `exp(q)` by its Taylor series to degree 7 (remainder `< 6e-9` relative), `2^m` by `vscalefps`.
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn exp_nonpositive(x: __m512) -> __m512 {
        const LN2_HI: f32 = 0.693_145_75;
        const LN2_LO: f32 = 1.428_606_8e-6;
        let m = _mm512_roundscale_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(_mm512_mul_ps(x, _mm512_set1_ps(std::f32::consts::LOG2_E)));
        let q = _mm512_fnmadd_ps(m, _mm512_set1_ps(LN2_LO), _mm512_fnmadd_ps(m, _mm512_set1_ps(LN2_HI), x));
        let mut p = _mm512_set1_ps(1.0 / 5040.0);
        for c in [1.0 / 720.0, 1.0 / 120.0, 1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0] {
            p = _mm512_fmadd_ps(p, q, _mm512_set1_ps(c));
        }
        _mm512_scalef_ps(p, m)
    }

    /// [`ErfcxF32::eval`] of each lane (`0 <= x < 4`).
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn erfcx(tab: &ErfcxF32, x: __m512) -> __m512 {
        let u = _mm512_mul_ps(x, _mm512_set1_ps((INTERVALS as f64 / X_MAX) as f32));
        let i = _mm512_min_ps(_mm512_roundscale_ps::<{ _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC }>(u), _mm512_set1_ps((INTERVALS - 1) as f32));
        let t = _mm512_fmsub_ps(_mm512_set1_ps(2.0), _mm512_sub_ps(u, i), _mm512_set1_ps(1.0));
        let idx = _mm512_cvttps_epi32(i);
        // SAFETY (both loads): `[f32; 16]` and `__m512` have the same size; unaligned loads
        let pick = |j: usize| _mm512_permutexvar_ps(idx, unsafe { _mm512_loadu_ps(tab.coef[j].as_ptr()) });
        let mut p = pick(DEGREE);
        for j in (0..DEGREE).rev() {
            p = _mm512_fmadd_ps(p, t, pick(j));
        }
        p
    }

    /// The sums of the two halves (lanes 0-7, 8-15) of eight registers: lane `4 c + p` of the
    /// result is the sum of half `c % 2` of `v[4 (c / 2) + p]` (a transposing tree: 21 operations
    /// for 16 sums).
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn half_sums8(v: [__m512; 8]) -> __m512 {
        // level 1, per 128-bit chunk: (a0 + a2, b0 + b2, a1 + a3, b1 + b3)
        let l1 = [0, 1, 2, 3].map(|k| _mm512_add_ps(_mm512_unpacklo_ps(v[2 * k], v[2 * k + 1]), _mm512_unpackhi_ps(v[2 * k], v[2 * k + 1])));
        // level 2, per chunk: the chunk sums of four registers
        let l2 = [0, 1].map(|j| {
            let (p, q) = (_mm512_castps_pd(l1[2 * j]), _mm512_castps_pd(l1[2 * j + 1]));
            _mm512_add_ps(_mm512_castpd_ps(_mm512_unpacklo_pd(p, q)), _mm512_castpd_ps(_mm512_unpackhi_pd(p, q)))
        });
        // level 3: chunks (0 + 1) and (2 + 3), the two halves
        _mm512_add_ps(_mm512_shuffle_f32x4::<0b10_00_10_00>(l2[0], l2[1]), _mm512_shuffle_f32x4::<0b11_01_11_01>(l2[0], l2[1]))
    }

    /// One triangle's separations from its target in double precision (um): `r`, `r^2` (1 outside),
    /// `r . n` and the mask of the node lanes within the cutoff and outside the coincidence radius.
    #[inline]
    #[target_feature(enable = "avx512f")]
    fn separations(k: &Kernel, t: [f64; 3], nodes: &NodeLanes) -> ([__m512d; 3], __m512d, __m512d, __mmask8) {
        let r = [0, 1, 2].map(|d| _mm512_sub_pd(_mm512_set1_pd(t[d]), load(&nodes.x[d])));
        let r2 = _mm512_fmadd_pd(r[0], r[0], _mm512_fmadd_pd(r[1], r[1], _mm512_mul_pd(r[2], r[2])));
        let valid = _mm512_cmp_pd_mask::<_CMP_NEQ_OQ>(load(&nodes.valid), _mm512_setzero_pd());
        let inside = valid & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(r2, _mm512_set1_pd(k.rc2)) & _mm512_cmp_pd_mask::<_CMP_GT_OQ>(r2, _mm512_set1_pd(k.eps2));
        let r2 = _mm512_mask_blend_pd(inside, _mm512_set1_pd(1.0), r2);
        let rdn = _mm512_fmadd_pd(r[0], load(&nodes.n[0]), _mm512_fmadd_pd(r[1], load(&nodes.n[1]), _mm512_mul_pd(r[2], load(&nodes.n[2]))));
        (r, r2, rdn, inside)
    }

    /// What two triangles, `a` at target `ta` and `b` at `tb`, give their targets, with the single
    /// layer when `SL`: the kernel of `super::super::lanes::Kernel::blocks` in single precision (see
    /// the module documentation). `out[h]` receives triangle `h`'s [`TriangleAtTarget`] as 24
    /// numbers (the three vertex blocks' 18 entries, the single layer's 3, 3 unused); the result
    /// says which of the two had a pair inside (the other's `out` is left as it was). `bary` holds
    /// the barycentric weights of [`Kernel::bary`] twice over (lanes 0-7, 8-15).
    #[inline]
    #[target_feature(enable = "avx512f")]
    #[allow(clippy::too_many_arguments)]
    pub fn blocks_x2<const SL: bool>(k: &Kernel, tab: &ErfcxF32, bary: &[[f32; 16]; 3], ta: [f64; 3], a: &NodeLanes, tb: [f64; 3], b: &NodeLanes, out: &mut [[f64; 24]; 2]) -> [bool; 2] {
        let (ra, r2a, rdna, ia) = separations(k, ta, a);
        let (rb, r2b, rdnb, ib) = separations(k, tb, b);
        if ia == 0 && ib == 0 {
            return [false, false];
        }
        let inside: __mmask16 = ia as u16 | (ib as u16) << 8;
        let neg_xi2 = _mm512_set1_pd(-k.xi * k.xi);
        let x = join(_mm512_mul_pd(neg_xi2, r2a), _mm512_mul_pd(neg_xi2, r2b));
        let r2 = join(r2a, r2b);
        let y = _mm512_rsqrt14_ps(r2);
        // one Newton step: y (3 - r2 y^2) / 2
        let ir = _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(0.5), y), _mm512_fnmadd_ps(_mm512_mul_ps(r2, y), y, _mm512_set1_ps(3.0)));
        let xi = k.xi as f32;
        let s = _mm512_mul_ps(_mm512_set1_ps(xi), _mm512_mul_ps(r2, ir));
        let e = exp_nonpositive(x);
        let erfc = _mm512_mul_ps(erfcx(tab, s), e);
        let ir2 = _mm512_mul_ps(ir, ir);
        // the stresslet's A and B ([`super::super::split::stresslet_ab`]), zero outside
        let c = _mm512_mul_ps(_mm512_set1_ps((4.0 * k.xi * FRAC_1_SQRT_PI) as f32), e);
        let av = _mm512_maskz_mul_ps(inside, _mm512_set1_ps((-k.xi * k.xi) as f32), c);
        let b5 = _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(6.0), erfc), _mm512_mul_ps(_mm512_mul_ps(ir2, ir2), ir));
        let bv = _mm512_maskz_mov_ps(inside, _mm512_fmadd_ps(_mm512_mul_ps(c, ir2), _mm512_fmadd_ps(_mm512_set1_ps(3.0), ir2, _mm512_set1_ps((2.0 * k.xi * k.xi) as f32)), b5));
        let r = [0, 1, 2].map(|d| join(ra[d], rb[d]));
        let n = [0, 1, 2].map(|d| join(load(&a.n[d]), load(&b.n[d])));
        let rdn = join(rdna, rdnb);
        let (brn, arn) = (_mm512_mul_ps(bv, rdn), _mm512_mul_ps(av, rdn));
        let entry = |p: usize, q: usize| {
            let cross = _mm512_mul_ps(av, _mm512_fmadd_ps(r[p], n[q], _mm512_mul_ps(n[p], r[q])));
            let v = _mm512_fmadd_ps(_mm512_mul_ps(brn, r[p]), r[q], cross);
            if p == q {
                _mm512_add_ps(v, arn)
            } else {
                v
            }
        };
        let kk = [entry(0, 0), entry(0, 1), entry(0, 2), entry(1, 1), entry(1, 2), entry(2, 2)];
        let zero = _mm512_setzero_ps();
        let sl = if SL {
            // the Stokeslet's a and b ([`super::super::split::stokeslet_ab`]), zero outside
            let cs = _mm512_mul_ps(_mm512_set1_ps((2.0 * k.xi * FRAC_1_SQRT_PI) as f32), e);
            let eir = _mm512_mul_ps(erfc, ir);
            let sa = _mm512_maskz_sub_ps(inside, eir, cs);
            let sb = _mm512_maskz_mul_ps(inside, _mm512_add_ps(eir, cs), ir2);
            let f = [0, 1, 2].map(|d| join(load(&a.f[d]), load(&b.f[d])));
            let cc = _mm512_mul_ps(sb, _mm512_fmadd_ps(r[0], f[0], _mm512_fmadd_ps(r[1], f[1], _mm512_mul_ps(r[2], f[2]))));
            [0, 1, 2].map(|d| _mm512_fmadd_ps(sa, f[d], _mm512_mul_ps(cc, r[d])))
        } else {
            [zero; 3]
        };
        // SAFETY: `[f32; 16]` and `__m512` have the same size; unaligned loads
        let w = bary.each_ref().map(|b| unsafe { _mm512_loadu_ps(b.as_ptr()) });
        let bk = |j: usize| _mm512_mul_ps(w[j / 6], kk[j % 6]);
        // registers 0-17: the vertex blocks (vertex j / 6, entry j % 6); 18-20: the single layer
        // lanes 0-7 of each result: registers 8 m .. 8 m + 8 for triangle a, lanes 8-15 for b
        let order = _mm512_setr_epi32(0, 1, 2, 3, 8, 9, 10, 11, 4, 5, 6, 7, 12, 13, 14, 15);
        let sums = [
            half_sums8([bk(0), bk(1), bk(2), bk(3), bk(4), bk(5), bk(6), bk(7)]),
            half_sums8([bk(8), bk(9), bk(10), bk(11), bk(12), bk(13), bk(14), bk(15)]),
            half_sums8([bk(16), bk(17), sl[0], sl[1], sl[2], zero, zero, zero]),
        ]
        .map(|v| _mm512_castps_pd(_mm512_permutexvar_ps(order, v)));
        for (m, v) in sums.into_iter().enumerate() {
            let halves = [_mm512_castpd512_pd256(v), _mm512_extractf64x4_pd::<1>(v)].map(|h| _mm512_cvtps_pd(_mm256_castpd_ps(h)));
            for (o, h) in out.iter_mut().zip(halves) {
                // SAFETY: `o[8 m .. 8 m + 8]` lies inside the 24 numbers; unaligned store
                unsafe { _mm512_storeu_pd(o.as_mut_ptr().add(8 * m), h) };
            }
        }
        [ia != 0, ib != 0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ewald::erfc::erfcx_reference;

    #[test]
    fn single_precision_erfcx_is_accurate_to_float_rounding() {
        let tab = ErfcxF32::get();
        let mut worst = 0.0f64;
        for i in 0..40_000 {
            let x = X_MAX * i as f64 / 40_000.0;
            let exact = erfcx_reference(x);
            worst = worst.max((tab.eval(x) - exact).abs() / exact);
        }
        assert!(worst < 2e-7, "relative error {worst:e}");
    }
}
