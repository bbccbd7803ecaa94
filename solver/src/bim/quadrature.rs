//! Quadrature rules on flat triangles: the 7-point Gauss rule for regular integrands and a Duffy rule for a 1/r singularity at a vertex.
//!
//! Rules are given in barycentric coordinates `(l0, l1, l2)` with weights that sum to 1,
//! so that `Int_T f dS ~= area(T) * sum_k w_k f(l0_k a + l1_k b + l2_k c)`.

/// One quadrature node of a triangle rule: barycentric coordinates and weight (weights of a rule sum to 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleNode {
    pub bary: [f64; 3],
    pub weight: f64,
}

/// The symmetric 7-point Gauss rule on a triangle, exact for polynomials of degree 5
/// (Radon 1948; tabulated by Dunavant, Int. J. Numer. Meth. Eng. 21, 1129 (1985), rule 5;
/// closed forms with `sqrt(15)` from Stroud, "Approximate calculation of multiple integrals", T2:5-1).
pub fn gauss7() -> [TriangleNode; 7] {
    let s15 = 15f64.sqrt();
    let a1 = (6.0 - s15) / 21.0; // 0.10128650732345633
    let b1 = 1.0 - 2.0 * a1; // 0.79742698535308731
    let w1 = (155.0 - s15) / 1200.0; // 0.12593918054482717
    let a2 = (6.0 + s15) / 21.0; // 0.47014206410511505
    let b2 = 1.0 - 2.0 * a2; // 0.05971587178976989
    let w2 = (155.0 + s15) / 1200.0; // 0.13239415278850619
    let n = |bary: [f64; 3], weight: f64| TriangleNode { bary, weight };
    [
        n([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 9.0 / 40.0),
        n([b1, a1, a1], w1),
        n([a1, b1, a1], w1),
        n([a1, a1, b1], w1),
        n([b2, a2, a2], w2),
        n([a2, b2, a2], w2),
        n([a2, a2, b2], w2),
    ]
}

/// Gauss-Legendre nodes and weights on `[0, 1]` (`n >= 1` points, exact to degree `2n - 1`).
///
/// Nodes are the roots of the Legendre polynomial `P_n` found by Newton's method from
/// the Chebyshev-like start `cos(pi (i + 3/4) / (n + 1/2))` (Press et al., Numerical
/// Recipes, `gauleg`). None of the workspace crates (nalgebra, faer, statrs) exposes
/// Gauss-Legendre rules, hence this small routine.
pub fn gauss_legendre_01(n: usize) -> Vec<(f64, f64)> {
    assert!(n >= 1, "Gauss-Legendre needs at least one node");
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // Three-term recurrence for P_n(x) and its derivative.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { x } else { p1 };
            let pnm1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * pn - pnm1) / (x * x - 1.0);
            let dx = pn / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        // Recompute the derivative at the converged root for the weight.
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push((0.5 * (1.0 - x), 0.5 * w));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// Duffy rule for an integrand with a `1/r` singularity at vertex 0 of the triangle.
///
/// The square `(s, t) in [0,1]^2` maps to the triangle by
/// `y = a + s (b - a) + s t (c - b)`, i.e. barycentric `(1 - s, s (1 - t), s t)`, with
/// Jacobian `2 area s` (Duffy, SIAM J. Numer. Anal. 19, 1260 (1982)). The factor `s`
/// cancels the `1/|x - y| ~ 1/s` of the Stokeslet, so a tensor Gauss-Legendre rule with
/// `n_s x n_t` points integrates `G(a, y) q(y)` for linear `q` to high accuracy:
/// in `s` the transformed integrand is linear (exact for `n_s >= 1`); in `t` it is
/// smooth (`1/|d(t)|`, `d(t) = b - a + t (c - b)`), converging exponentially in `n_t`.
pub fn duffy(n_s: usize, n_t: usize) -> Vec<TriangleNode> {
    let gs = gauss_legendre_01(n_s);
    let gt = gauss_legendre_01(n_t);
    let mut nodes = Vec::with_capacity(n_s * n_t);
    for &(s, ws) in &gs {
        for &(t, wt) in &gt {
            nodes.push(TriangleNode {
                bary: [1.0 - s, s * (1.0 - t), s * t],
                weight: 2.0 * s * ws * wt,
            });
        }
    }
    nodes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact integral of `l0^i l1^j l2^k` over a triangle divided by its area:
    /// `2 i! j! k! / (i + j + k + 2)!`.
    fn monomial_mean(i: u32, j: u32, k: u32) -> f64 {
        let f = |n: u32| (1..=n).map(f64::from).product::<f64>();
        2.0 * f(i) * f(j) * f(k) / f(i + j + k + 2)
    }

    #[test]
    fn gauss7_is_exact_to_degree_5_and_not_6() {
        let rule = gauss7();
        let wsum: f64 = rule.iter().map(|n| n.weight).sum();
        assert!((wsum - 1.0).abs() < 1e-15);
        for i in 0..=6u32 {
            for j in 0..=(6 - i) {
                let k = 0;
                let q: f64 = rule
                    .iter()
                    .map(|n| n.weight * n.bary[0].powi(i as i32) * n.bary[1].powi(j as i32) * n.bary[2].powi(k))
                    .sum();
                let err = (q - monomial_mean(i, j, k as u32)).abs();
                if i + j <= 5 {
                    assert!(err < 1e-15, "degree {} monomial l0^{i} l1^{j}: error {err}", i + j);
                }
            }
        }
        // Degree 6 is not integrated exactly: the rule's order is 5, not more.
        let q6: f64 = rule.iter().map(|n| n.weight * n.bary[0].powi(6)).sum();
        assert!((q6 - monomial_mean(6, 0, 0)).abs() > 1e-6);
    }

    #[test]
    fn gauss_legendre_exact_to_degree_2n_minus_1() {
        for n in 1..=10usize {
            let rule = gauss_legendre_01(n);
            for p in 0..(2 * n) as i32 {
                let q: f64 = rule.iter().map(|(x, w)| w * x.powi(p)).sum();
                assert!((q - 1.0 / (p as f64 + 1.0)).abs() < 1e-14, "n={n} p={p}: {q}");
            }
            let p = 2 * n as i32;
            let q: f64 = rule.iter().map(|(x, w)| w * x.powi(p)).sum();
            assert!((q - 1.0 / (p as f64 + 1.0)).abs() > 1e-12, "n={n} should not be exact at degree {p}");
        }
    }

    /// `Int_T 1/|y - a| dS` over the right triangle a=(0,0), b=(1,0), c=(0,1): in polar
    /// coordinates about `a` this is `h Int sec(phi) dphi` over `phi in [-pi/4, pi/4]`, with
    /// `h = 1/sqrt(2)` the distance from `a` to the opposite edge: `sqrt(2) ln(1 + sqrt(2))`.
    #[test]
    fn duffy_integrates_inverse_distance_from_a_vertex() {
        let exact = std::f64::consts::SQRT_2 * (1.0 + std::f64::consts::SQRT_2).ln();
        let area = 0.5;
        let quad = |n_t| -> f64 {
            duffy(2, n_t)
                .iter()
                .map(|n| {
                    let (x, y) = (n.bary[1], n.bary[2]);
                    n.weight * area / (x * x + y * y).sqrt()
                })
                .sum()
        };
        // Exponential convergence in the angular order (the transformed integrand is analytic).
        let errs: Vec<f64> = [4, 8, 16].iter().map(|&n| (quad(n) - exact).abs() / exact).collect();
        assert!(errs[0] < 1e-3 && errs[1] < 1e-6 && errs[2] < 1e-12, "{errs:?}"); // measured 3.9e-4, 2.5e-7, 1.4e-13
        // The 7-point rule on the same singular integrand is off by percent: this is why Duffy is needed.
        let q7: f64 = gauss7()
            .iter()
            .map(|n| n.weight * area / (n.bary[1].powi(2) + n.bary[2].powi(2)).sqrt())
            .sum();
        assert!((q7 - exact).abs() / exact > 1e-2);
    }
}
