//! Complementary error function: a slow reference to ~1e-15 and a fast table of the scaled `erfcx(x) = exp(x^2) erfc(x)` for the real-space sums.
//!
//! Written here because the solver crate has no special-function dependency (std has no
//! `erfc`; `statrs` is only a dependency of the analysis crate) and the Ewald real-space
//! kernels need `erfc(x)` with a relative accuracy far below the Ewald error targets.
//!
//! Reference ([`erfc_reference`]), Abramowitz & Stegun 7.1.6 and 7.1.14:
//! - `x < 0.5`: `erf(x) = 2/sqrt(pi) exp(-x^2) sum_n 2^n x^(2n+1) / (1 3 5 ... (2n+1))`
//!   (all terms positive: no cancellation), `erfc = 1 - erf` (>= 0.48: no loss of digits);
//! - `x >= 0.5`: the continued fraction
//!   `erfc(x) = exp(-x^2)/sqrt(pi) * 1/(x + (1/2)/(x + 1/(x + (3/2)/(x + 2/(x + ...)))))`,
//!   evaluated backwards from depth 1000 (converged to 1e-16 for `x >= 0.5`).
//!
//! Fast path ([`Erfcx`]): piecewise Chebyshev interpolation of `erfcx` on `[0, 8)` in
//! intervals of width 1/16, degree 7 (a short Clenshaw chain in the hot loop), built once from the reference (relative accuracy
//! ~1e-15, checked by a test); `erfc(x) = erfcx(x) exp(-x^2)`, and the Ewald kernels need
//! `exp(-x^2)` anyway.

use std::sync::OnceLock;

const FRAC_2_SQRT_PI: f64 = std::f64::consts::FRAC_2_SQRT_PI;

/// `erfc(x)` to ~1e-15 relative (slow: up to 1000 iterations).
pub fn erfc_reference(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x < 0.0 {
        return 2.0 - erfc_reference(-x);
    }
    if x < 0.5 {
        let x2 = x * x;
        let mut term = x;
        let mut sum = x;
        let mut n = 0.0;
        while term > 1e-17 * sum {
            n += 1.0;
            term *= 2.0 * x2 / (2.0 * n + 1.0);
            sum += term;
        }
        1.0 - FRAC_2_SQRT_PI * (-x2).exp() * sum
    } else if x > 27.0 {
        0.0 // below the smallest subnormal
    } else {
        (-x * x).exp() * erfcx_continued_fraction(x)
    }
}

/// `exp(x^2) erfc(x)` by the continued fraction, for `x >= 0.5`.
fn erfcx_continued_fraction(x: f64) -> f64 {
    let mut f = x;
    for n in (1..=1000).rev() {
        f = x + (n as f64 * 0.5) / f;
    }
    1.0 / (std::f64::consts::PI.sqrt() * f)
}

/// `erfcx(x) = exp(x^2) erfc(x)` to ~1e-15 relative, `x >= 0` (slow).
pub fn erfcx_reference(x: f64) -> f64 {
    if x < 0.5 {
        erfc_reference(x) * (x * x).exp()
    } else {
        erfcx_continued_fraction(x)
    }
}

/// Upper end of the tabulated range of [`Erfcx`].
const X_MAX: f64 = 8.0;
/// Intervals per unit length.
const PER_UNIT: f64 = 16.0;
/// Chebyshev coefficients per interval (degree + 1).
const NC: usize = 8;

/// Piecewise Chebyshev table of `erfcx(x) = exp(x^2) erfc(x)` on `[0, 8)`.
#[derive(Debug)]
pub struct Erfcx {
    coef: Vec<[f64; NC]>,
}

impl Erfcx {
    fn build() -> Self {
        let n_int = (X_MAX * PER_UNIT) as usize;
        let h = 1.0 / PER_UNIT;
        let coef = (0..n_int)
            .map(|i| {
                let (a, b) = (i as f64 * h, (i + 1) as f64 * h);
                // Values at the Chebyshev points of the first kind, then the discrete cosine transform.
                let nodes: Vec<f64> = (0..NC)
                    .map(|k| {
                        let t = (std::f64::consts::PI * (k as f64 + 0.5) / NC as f64).cos();
                        let x = 0.5 * (a + b) + 0.5 * (b - a) * t;
                        erfcx_reference(x)
                    })
                    .collect();
                let mut c = [0.0; NC];
                for (j, cj) in c.iter_mut().enumerate() {
                    let s: f64 = (0..NC)
                        .map(|k| nodes[k] * (std::f64::consts::PI * j as f64 * (k as f64 + 0.5) / NC as f64).cos())
                        .sum();
                    *cj = s * 2.0 / NC as f64;
                }
                c[0] *= 0.5;
                c
            })
            .collect();
        Self { coef }
    }

    /// The shared table (built on first use, 1024 reference evaluations, ~1 ms).
    pub fn get() -> &'static Self {
        static TABLE: OnceLock<Erfcx> = OnceLock::new();
        TABLE.get_or_init(Self::build)
    }

    /// [`Self::eval`] of eight values in `[0, 8)` at once (a lane beyond the table is clamped to its
    /// last interval, so the caller must keep `x < 8`); the recurrence steps all lanes together,
    /// which vectorises (one gather of coefficients per step).
    #[inline(always)]
    pub fn eval_lanes(&self, x: &[f64; 8]) -> [f64; 8] {
        let last = self.coef.len() - 1;
        let mut idx = [0usize; 8];
        let mut t = [0.0f64; 8];
        for l in 0..8 {
            let s = x[l] * PER_UNIT;
            idx[l] = (s as usize).min(last);
            t[l] = 2.0 * (s - idx[l] as f64) - 1.0;
        }
        let (mut b1, mut b2) = ([0.0f64; 8], [0.0f64; 8]);
        for j in (1..NC).rev() {
            for l in 0..8 {
                let b0 = (2.0 * t[l]).mul_add(b1[l], self.coef[idx[l]][j] - b2[l]);
                b2[l] = b1[l];
                b1[l] = b0;
            }
        }
        std::array::from_fn(|l| t[l].mul_add(b1[l], self.coef[idx[l]][0] - b2[l]))
    }

    /// [`Self::eval_lanes`] in one AVX-512 register: the same intervals, the same Clenshaw
    /// recurrence with the coefficients gathered (`vgatherdpd`), so the same values up to the
    /// order of rounding of `t` (the caller keeps every lane in `[0, 8)`).
    ///
    /// # Safety
    /// The CPU must have AVX-512F (`crate::bim::kernels::avx512_available`).
    #[cfg(target_arch = "x86_64")]
    #[inline]
    #[target_feature(enable = "avx512f")]
    pub(crate) unsafe fn eval_zmm(&self, x: std::arch::x86_64::__m512d) -> std::arch::x86_64::__m512d {
        use std::arch::x86_64::*;
        let s = _mm512_mul_pd(x, _mm512_set1_pd(PER_UNIT));
        let i = _mm512_min_pd(_mm512_roundscale_pd::<{ _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC }>(s), _mm512_set1_pd((self.coef.len() - 1) as f64));
        let t = _mm512_fmsub_pd(_mm512_set1_pd(2.0), _mm512_sub_pd(s, i), _mm512_set1_pd(1.0));
        // the first coefficient of each lane's interval, as an index into the flat table
        let idx = _mm512_cvttpd_epi32(_mm512_mul_pd(i, _mm512_set1_pd(NC as f64)));
        let base = self.coef.as_ptr() as *const f64;
        let two_t = _mm512_add_pd(t, t);
        let (mut b1, mut b2) = (_mm512_setzero_pd(), _mm512_setzero_pd());
        for j in (1..NC).rev() {
            // SAFETY: every index is `NC i + j` with `i <= len - 1`, inside the table
            let c = unsafe { _mm512_i32gather_pd::<8>(idx, base.add(j)) };
            let b0 = _mm512_fmadd_pd(two_t, b1, _mm512_sub_pd(c, b2));
            b2 = b1;
            b1 = b0;
        }
        let c0 = unsafe { _mm512_i32gather_pd::<8>(idx, base) };
        _mm512_fmadd_pd(t, b1, _mm512_sub_pd(c0, b2))
    }

    /// `erfcx(x)` for `x >= 0` (falls back to the reference beyond the table).
    #[inline]
    pub fn eval(&self, x: f64) -> f64 {
        if x >= X_MAX || x.is_nan() {
            return erfcx_reference(x);
        }
        let s = x * PER_UNIT;
        let i = s as usize; // x >= 0
        let t = 2.0 * (s - i as f64) - 1.0;
        let c = &self.coef[i];
        // Clenshaw recurrence.
        let (mut b1, mut b2) = (0.0f64, 0.0f64);
        for &cj in c[1..].iter().rev() {
            let b0 = (2.0 * t).mul_add(b1, cj - b2);
            b2 = b1;
            b1 = b0;
        }
        t.mul_add(b1, c[0] - b2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Published values (Abramowitz & Stegun table 7.1; the same digits from any arbitrary-precision package).
    #[test]
    fn reference_matches_tabulated_values() {
        let cases = [
            (0.0, 1.0),
            (0.5, 0.479_500_122_186_953_5),
            (1.0, 0.157_299_207_050_285_13),
            (2.0, 0.004_677_734_981_047_266),
            (2.5, 4.069_520_174_449_589e-4),
            (3.0, 2.209_049_699_858_544e-5),
            (5.0, 1.537_459_794_428_035e-12),
        ];
        for (x, want) in cases {
            let got = erfc_reference(x);
            assert!((got - want).abs() <= 2e-15 * want, "erfc({x}) = {got:e}, want {want:e}");
        }
        // Continuity where the series hands over to the continued fraction.
        let (lo, hi) = (erfc_reference(0.5 - 1e-12), erfc_reference(0.5));
        let slope = FRAC_2_SQRT_PI * (-0.25f64).exp(); // -d erfc/dx at 0.5
        assert!((lo - hi - slope * 1e-12).abs() < 1e-15, "{lo:e} vs {hi:e}");
        assert!((erfc_reference(-1.0) - (2.0 - 0.157_299_207_050_285_13)).abs() < 1e-15);
    }

    /// The Chebyshev table reproduces the reference to 1e-14 relative over its whole range.
    #[test]
    fn table_matches_reference() {
        let t = Erfcx::get();
        let mut worst: f64 = 0.0;
        for i in 0..20_000 {
            let x = i as f64 * 8.5 / 20_000.0;
            let want = erfcx_reference(x);
            worst = worst.max((t.eval(x) - want).abs() / want);
        }
        assert!(worst < 1e-14, "worst relative error {worst:e}");
    }
}
