//! The real-space stresslet kernels of one triangle's quadrature nodes at once, in eight SIMD lanes, summed into the triangle's three vertex blocks (for [`super::blocks::BlockRows::stresslet_grouped`]).
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
//! Agreement with the scalar path to rounding: test `grouped_stresslet_blocks_match_real_space`.

use super::blocks::{Sym, SYM_PQ};
use super::erfc::Erfcx;
use super::split::{stokeslet_ab, stresslet_ab};

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
        self.blocks_portable::<SL>(t, nodes)
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
