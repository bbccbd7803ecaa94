//! The coefficients of the Rosenbrock-W methods that [`super::ros34pw2::Ros34pw2`] steps with: ROS34PW2 (Rang & Angermann 2005), ROS3Pw and ROS34PW3 (the same paper), ROS34PRw (Rang 2015) and RosW6S4 (Rahunanthan & Stanescu 2010), with their order conditions checked in the tests, and the transformed form the stepper uses (Hairer & Wanner II, eq. (7.25); the formulas are in [`super::ros34pw2`]).

// the published 17-digit coefficients are kept verbatim, so that they can be checked against the paper
#![allow(clippy::excessive_precision)]

use nalgebra::{Matrix6, RowVector6};

/// Stages the stepper holds (the six of W6S4; four-stage tableaux leave the rest zero).
pub const MAX_STAGES: usize = 6;

/// A `4 x 4` block padded to [`MAX_STAGES`].
const fn pad(a: [[f64; 4]; 4]) -> [[f64; MAX_STAGES]; MAX_STAGES] {
    let mut o = [[0.0; MAX_STAGES]; MAX_STAGES];
    let mut i = 0;
    while i < 4 {
        let mut j = 0;
        while j < 4 {
            o[i][j] = a[i][j];
            j += 1;
        }
        i += 1;
    }
    o
}

/// A row of 4 padded to [`MAX_STAGES`].
const fn pad_row(b: [f64; 4]) -> [f64; MAX_STAGES] {
    [b[0], b[1], b[2], b[3], 0.0, 0.0]
}

/// Diagonal `gamma` of ROS34PW2.
pub const GAMMA_DIAG: f64 = 4.3586652150845900e-01;
/// `alpha_ij` (strictly lower), Rang & Angermann (2005), ROS34PW2.
pub const ALPHA: [[f64; 4]; 4] = [
    [0.0, 0.0, 0.0, 0.0],
    [8.7173304301691801e-01, 0.0, 0.0, 0.0],
    [8.4457060015369423e-01, -1.1299064236484185e-01, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
];
/// `gamma_ij` (lower, `gamma` on the diagonal).
pub const GAMMA: [[f64; 4]; 4] = [
    [GAMMA_DIAG, 0.0, 0.0, 0.0],
    [-8.7173304301691801e-01, GAMMA_DIAG, 0.0, 0.0],
    [-9.0338057013044082e-01, 5.4180672388095326e-02, GAMMA_DIAG, 0.0],
    [2.4212380706095346e-01, -1.2232505839045147e+00, 5.4526025533510214e-01, GAMMA_DIAG],
];
/// Weights of the third-order solution (equal to the last row of `alpha + gamma`: stiffly accurate).
pub const B: [f64; 4] = [2.4212380706095346e-01, -1.2232505839045147e+00, 1.5452602553351020e+00, 4.3586652150845900e-01];
/// Weights of the embedded second-order solution.
pub const B_HAT: [f64; 4] = [3.7810903145819369e-01, -9.6042292212423178e-02, 5.0000000000000000e-01, 2.1793326075422950e-01];

/// A Rosenbrock-W tableau of at most [`MAX_STAGES`] stages in the form of Hairer & Wanner (module docs):
/// `alpha_ij` (strictly lower), `gamma_ij` (lower, `gamma` on the diagonal), the weights `b` of the
/// solution and `b^` of the embedded one. Unused rows and columns (three- and four-stage methods) are zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tableau {
    pub stages: usize,
    /// The diagonal `gamma` of the stage matrix `I - gamma h J`.
    pub gamma: f64,
    pub alpha: [[f64; MAX_STAGES]; MAX_STAGES],
    pub gamma_ij: [[f64; MAX_STAGES]; MAX_STAGES],
    pub b: [f64; MAX_STAGES],
    pub b_hat: [f64; MAX_STAGES],
}

/// The Rosenbrock-W tableaux the stepper can run (`[integrator] scheme` chooses one with the
/// Jacobian, e.g. `ros3pw-mobility`). Their orders differ with an approximate `J` (a W-method's
/// order, valid for any `J`) and with the exact Jacobian (classical): [`Method::orders`]. The step
/// controller treats all as 3(2) (the classical orders).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// ROS34PW2 (Rang & Angermann 2005; 4 stages, L-stable, stiffly
    /// accurate, embedded `R(inf) = 0.48`), the default: W-order 3 (embedded 2).
    Ros34pw2,
    /// ROS3Pw (Rang & Angermann 2005): 3 stages, `gamma = (3 + sqrt 3)/6 = 0.7887`, strongly
    /// A-stable with `R(inf) = sqrt 3 - 1 = 0.73` (solution and embedded): one velocity evaluation
    /// per step less than the four-stage methods. Classical order 3 (embedded 2), but W-order 2
    /// (embedded 1) only: its `alpha_32 = 0` makes `b alpha alpha 1 = 0`, not 1/6, so order 3 needs
    /// `J = f' + O(h)`. (No three-stage tableau with `alpha_32 = 0` can be a W-method of order 3.)
    Ros3pw,
    /// ROS34PW3 (Rang & Angermann 2005): 4 stages, W-order 3 (embedded 2) and classical order 4
    /// (embedded 2) with the exact Jacobian, `gamma = 1.0686`, strongly A-stable with `R(inf) = 0.63`.
    Ros34pw3,
    /// ROS34PRw (Rang, "Improved traditional Rosenbrock-Wanner methods for stiff ODEs and DAEs",
    /// J. Comput. Appl. Math. 286, 128 (2015)): 4 stages, W-order 3, L-stable, stiffly accurate,
    /// `B_PR` consistent of order 3 (no order reduction on Prothero-Robinson problems), embedded
    /// `R(inf) = 0.25`, the same `gamma` as ROS34PW2. Its embedded solution is of classical order 2
    /// but W-order 1 only (`b^ alpha 1 != 1/2`): with an approximate `J` the estimate is `O(h^2)`.
    Ros34prw,
    /// RosW6S4 (Rahunanthan & Stanescu, J. Comput. Appl. Math. 233, 1607 (2010), "High-order
    /// W-methods"): 6 stages, W-order 4 (order 4 for any `J`), `gamma = 1/4`, `R(inf) = 0`, published
    /// without an embedded formula (fixed step). Its stages leave a one-parameter family of weights
    /// of W-order 3; the embedded solution here is `b^ = b - 0.5 n` (`R^(inf) = 0.496`; ROS34PW2's
    /// embedded one has 0.48) with `n` the unit null vector of the order-3
    /// conditions (the eight order-3 conditions have rank 5 on the six weights). Its classical
    /// fourth-order error terms are about half those of ROS34PW2's solution, and the estimate
    /// `y1 - y1^` is `O(h^4)` (controller exponent 1/4; `solver/README.md`, "Session 34").
    Rosw6s4,
}

impl Method {
    pub const ALL: [Method; 5] = [Method::Ros34pw2, Method::Ros3pw, Method::Ros34pw3, Method::Ros34prw, Method::Rosw6s4];

    /// The tableau, with the published 17-digit coefficients (as also listed by PETSc's `TSROSW`
    /// types `ra34pw2`, `ra3pw` and `r34prw`; ROS34PW3 as in Rang & Angermann 2005). The tests check
    /// them against the W-method order conditions to 1e-15.
    pub fn tableau(self) -> Tableau {
        match self {
            Method::Ros34pw2 => Tableau { stages: 4, gamma: GAMMA_DIAG, alpha: pad(ALPHA), gamma_ij: pad(GAMMA), b: pad_row(B), b_hat: pad_row(B_HAT) },
            Method::Ros3pw => {
                let g = 7.8867513459481287e-01;
                Tableau {
                    stages: 3,
                    gamma: g,
                    alpha: pad([[0.0; 4], [1.5773502691896257e+00, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0], [0.0; 4]]),
                    gamma_ij: pad([[g, 0.0, 0.0, 0.0], [-1.5773502691896257e+00, g, 0.0, 0.0], [-6.7075317547305480e-01, -1.7075317547305482e-01, g, 0.0], [0.0; 4]]),
                    b: pad_row([1.0566243270259355e-01, 4.9038105676657971e-02, 8.4529946162074843e-01, 0.0]),
                    b_hat: pad_row([-1.7863279495408180e-01, 1.0 / 3.0, 8.4529946162074843e-01, 0.0]),
                }
            }
            Method::Ros34pw3 => {
                let g = 1.0685790213016289e+00;
                Tableau {
                    stages: 4,
                    gamma: g,
                    alpha: pad([
                        [0.0; 4],
                        [2.5155456020628817e+00, 0.0, 0.0, 0.0],
                        [5.0777280103144085e-01, 7.5000000000000000e-01, 0.0, 0.0],
                        [1.3959081404277204e-01, -3.3111001065419338e-01, 8.2040559712714178e-01, 0.0],
                    ]),
                    gamma_ij: pad([
                        [g, 0.0, 0.0, 0.0],
                        [-2.5155456020628817e+00, g, 0.0, 0.0],
                        [-8.7991339217106512e-01, -9.6014187766190695e-01, g, 0.0],
                        [-4.1731389379448741e-01, 4.1091047035857703e-01, -1.3558873204765276e+00, g],
                    ]),
                    b: pad_row([2.2047681286931747e-01, 2.7828278331185935e-03, 7.1844787635140066e-03, 7.6955588053404989e-01]),
                    b_hat: pad_row([3.1300297285209688e-01, -2.8946895245112692e-01, 9.7646597959903003e-01, 0.0]),
                }
            }
            Method::Ros34prw => Tableau {
                stages: 4,
                gamma: GAMMA_DIAG,
                alpha: pad([
                    [0.0; 4],
                    [8.7173304301691801e-01, 0.0, 0.0, 0.0],
                    [1.4722022879435914e+00, -3.1840250568090289e-01, 0.0, 0.0],
                    [8.1505192016694938e-01, 5.0000000000000000e-01, -3.1505192016694938e-01, 0.0],
                ]),
                gamma_ij: pad([
                    [GAMMA_DIAG, 0.0, 0.0, 0.0],
                    [-8.7173304301691801e-01, GAMMA_DIAG, 0.0, 0.0],
                    [-1.2855347382089872e+00, 5.0507005541550687e-01, GAMMA_DIAG, 0.0],
                    [-4.8201449182864348e-01, 2.1793326075422950e-01, -1.7178529043404503e-01, GAMMA_DIAG],
                ]),
                b: pad_row([3.3303742833830591e-01, 7.1793326075422947e-01, -4.8683721060099439e-01, 4.3586652150845900e-01]),
                b_hat: pad_row([2.5000000000000000e-01, 7.4276119608319180e-01, -3.1472922970066219e-01, 3.2196803361747034e-01]),
            },
            Method::Rosw6s4 => rosw6s4(),
        }
    }

    /// `(W-order, embedded W-order, classical order, embedded classical order)`: the order of the
    /// solution and of the embedded one for any `J`, and with the exact Jacobian (checked by the tests
    /// against the order conditions and by convergence on linear and nonlinear problems).
    pub fn orders(self) -> (u32, u32, u32, u32) {
        match self {
            Method::Ros34pw2 => (3, 2, 3, 2),
            Method::Ros3pw => (2, 1, 3, 2),
            Method::Ros34pw3 => (3, 2, 4, 2),
            Method::Ros34prw => (3, 1, 3, 2),
            Method::Rosw6s4 => (4, 3, 4, 3),
        }
    }

    /// Short name of the tableau (the prefix of the scheme's name).
    pub fn name(self) -> &'static str {
        match self {
            Method::Ros34pw2 => "ros34pw2",
            Method::Ros3pw => "ros3pw",
            Method::Ros34pw3 => "ros34pw3",
            Method::Ros34prw => "ros34prw",
            Method::Rosw6s4 => "rosw6s4",
        }
    }

    /// The order `q` of the embedded solution with the exact Jacobian: the error estimate scales
    /// as `h^(q+1)`, the step controller's exponent.
    pub fn embedded_order(self) -> u32 {
        self.orders().3
    }
}

/// RosW6S4 from its published transformed coefficients (Hairer & Wanner's `a = alpha Gamma^-1`,
/// `C = diag(1/gamma) - Gamma^-1`, `m = b Gamma^-1`, as listed by OrdinaryDiffEq.jl's
/// `RosenbrockW6S4OS`), converted back to `alpha`, `Gamma` and `b`.
fn rosw6s4() -> Tableau {
    const G: f64 = 0.25;
    const A: [[f64; 5]; 6] = [
        [0.0; 5],
        [0.5812383407115008, 0.0, 0.0, 0.0, 0.0],
        [0.9039624413714670, 1.8615191555345010, 0.0, 0.0, 0.0],
        [2.0765797196750000, 0.1884255381414796, 1.8701589674910320, 0.0, 0.0],
        [4.4355506384843120, 5.4571817986101890, 4.6163507880689300, 3.1181119524023610, 0.0],
        [10.791701698483260, -10.05691522584131, 14.995644854284190, 5.2743399543909430, 1.4297308712611900],
    ];
    const C: [[f64; 5]; 6] = [
        [0.0; 5],
        [-2.661294105131369, 0.0, 0.0, 0.0, 0.0],
        [-3.128450202373838, 0.0, 0.0, 0.0, 0.0],
        [-6.920335474535658, -1.202675288266817, -9.733561811413620, 0.0, 0.0],
        [-28.09530629102695, 20.371262954793770, -41.04375275302869, -19.66373175620895, 0.0],
        [9.7998186780974000, 11.935792886603180, 3.6738749290132010, 14.807828541095500, 0.8318583998690680],
    ];
    const M: [f64; 6] = [6.4562170746532350, -4.853141317768053, 9.7653183340692600, 2.0810841772787230, 0.6603936866352417, 0.6000000000000000];
    // the embedded weights (module docs of `Method::Rosw6s4`), W-order 3 to 1e-15
    const B_HAT6: [f64; 6] = [0.2676787733612481, -0.20144131910792412, 0.461357709299328, 0.2042509073205536, 0.14920361425003653, 0.11895031487675865];
    let gamma_inv = Matrix6::from_fn(|i, j| if i == j { 1.0 / G } else if j < i { -C[i][j] } else { 0.0 });
    let gamma = gamma_inv.try_inverse().expect("lower triangular with 1/gamma on the diagonal");
    let a = Matrix6::from_fn(|i, j| if j < i { A[i][j] } else { 0.0 });
    let alpha = a * gamma;
    let b = RowVector6::from_row_slice(&M) * gamma;
    Tableau {
        stages: 6,
        gamma: G,
        alpha: std::array::from_fn(|i| std::array::from_fn(|j| if j < i { alpha[(i, j)] } else { 0.0 })),
        gamma_ij: std::array::from_fn(|i| std::array::from_fn(|j| if j < i { gamma[(i, j)] } else if i == j { G } else { 0.0 })),
        b: std::array::from_fn(|i| b[i]),
        b_hat: B_HAT6,
    }
}

/// Coefficients of the transformed form (see the module docs), computed from a tableau
/// (padded to [`MAX_STAGES`]: a tableau of fewer stages leaves the last rows and columns unused).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transformed {
    /// Stages in use.
    pub stages: usize,
    /// The diagonal `gamma`.
    pub gamma: f64,
    /// `alpha Gamma^-1` (strictly lower).
    pub a: Matrix6<f64>,
    /// `Gamma^-1` (lower).
    pub gamma_inv: Matrix6<f64>,
    /// `b Gamma^-1` and `(b - b^) Gamma^-1`.
    pub m: RowVector6<f64>,
    pub e: RowVector6<f64>,
    /// Stage times `c_i = sum_j alpha_ij`.
    pub c: [f64; MAX_STAGES],
}

impl Transformed {
    /// Transform the tableau of ROS34PW2.
    pub fn ros34pw2() -> Self {
        Self::of(&Method::Ros34pw2.tableau())
    }

    /// Transform a tableau.
    pub fn of(t: &Tableau) -> Self {
        let s = t.stages;
        let alpha = Matrix6::from_fn(|i, j| t.alpha[i][j]);
        // pad the unused stages with gamma on the diagonal (the used block's inverse is unchanged)
        let gamma = Matrix6::from_fn(|i, j| if i >= s && i == j { t.gamma } else { t.gamma_ij[i][j] });
        // Gamma is lower triangular with a non-zero diagonal: always invertible
        let gamma_inv = gamma.try_inverse().expect("Gamma has gamma on its diagonal");
        let b = RowVector6::from_row_slice(&t.b);
        let bh = RowVector6::from_row_slice(&t.b_hat);
        let c = std::array::from_fn(|i| t.alpha[i].iter().sum());
        Self { stages: s, gamma: t.gamma, a: alpha * gamma_inv, gamma_inv, m: b * gamma_inv, e: (b - bh) * gamma_inv, c }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The order conditions of a W-method up to order 3 (Steihaug & Wolfbrandt, Math. Comp. 33,
    /// 521 (1979); Hairer & Wanner II, sec. IV.7): expanding
    /// `k_i = h f(y + sum_j alpha_ij k_j) + h J sum_{j<=i} Gamma_ij k_j` in `h` with `J` unrelated
    /// to `f'`, every elementary differential containing `J` must vanish and the others match the
    /// Taylor series of the exact flow. With `a = alpha 1`:
    ///   order 1: `w 1 = 1`;  order 2: `w a = 1/2`, `w Gamma 1 = 0`;
    ///   order 3: `w a^2 = 1/3`, `w alpha a = 1/6`, `w alpha Gamma 1 = 0`, `w Gamma a = 0`, `w Gamma Gamma 1 = 0`.
    /// Returns the residuals of order 1-2 and of order 3.
    fn w_conditions(t: &Tableau, w: &[f64; MAX_STAGES]) -> ([f64; 3], [f64; 5]) {
        let alpha = Matrix6::from_fn(|i, j| t.alpha[i][j]);
        let gamma = Matrix6::from_fn(|i, j| t.gamma_ij[i][j]);
        let w = RowVector6::from_row_slice(w);
        let one = nalgebra::Vector6::repeat(1.0);
        let a = alpha * one;
        let g1 = gamma * one;
        (
            [(w * one)[0] - 1.0, (w * a)[0] - 0.5, (w * g1)[0]],
            [(w * a.component_mul(&a))[0] - 1.0 / 3.0, (w * alpha * a)[0] - 1.0 / 6.0, (w * alpha * g1)[0], (w * gamma * a)[0], (w * gamma * g1)[0]],
        )
    }

    /// The order conditions of a Rosenbrock method with the exact Jacobian up to order 4 (Hairer &
    /// Wanner II, table IV.7.1), in `beta = alpha + Gamma` without its diagonal and `alpha_i = sum_j alpha_ij`.
    fn classical_conditions(t: &Tableau, w: &[f64; MAX_STAGES]) -> [f64; 8] {
        let g = t.gamma;
        let alpha = Matrix6::from_fn(|i, j| t.alpha[i][j]);
        let beta = Matrix6::from_fn(|i, j| if i > j { t.alpha[i][j] + t.gamma_ij[i][j] } else { 0.0 });
        let w = RowVector6::from_row_slice(w);
        let one = nalgebra::Vector6::repeat(1.0);
        let a = alpha * one;
        let bt = beta * one;
        let a2 = a.component_mul(&a);
        [
            (w * one)[0] - 1.0,
            (w * bt)[0] - (0.5 - g),
            (w * a2)[0] - 1.0 / 3.0,
            (w * beta * bt)[0] - (1.0 / 6.0 - g + g * g),
            (w * a2.component_mul(&a))[0] - 0.25,
            (w * a.component_mul(&(alpha * bt)))[0] - (1.0 / 8.0 - g / 3.0),
            (w * beta * a2)[0] - (1.0 / 12.0 - g / 3.0),
            (w * beta * beta * bt)[0] - (1.0 / 24.0 - g / 2.0 + 1.5 * g * g - g * g * g),
        ]
    }

    /// The order a residual list proves: the conditions of orders `1..=k` hold to `tol` (`per_order[k-1]`
    /// the number of conditions of order `k`), and the next order's fail.
    fn proven_order(residuals: &[f64], per_order: &[usize], tol: f64) -> u32 {
        let mut start = 0;
        for (k, n) in per_order.iter().enumerate() {
            if residuals[start..start + n].iter().any(|r| r.abs() > tol) {
                return k as u32;
            }
            start += n;
        }
        per_order.len() as u32
    }

    #[test]
    fn every_tableau_has_its_w_orders_and_classical_orders() {
        for m in Method::ALL {
            let t = m.tableau();
            // the diagonal is gamma on the stages in use
            for i in 0..t.stages {
                assert_eq!(t.gamma_ij[i][i], t.gamma, "{m:?}");
            }
            let (w, w_hat, p, p_hat) = m.orders();
            // W-conditions: 1 of order 1, 2 of order 2, 5 of order 3
            let wc = |x: &[f64; MAX_STAGES]| {
                let (c2, c3) = w_conditions(&t, x);
                c2.iter().chain(&c3).copied().collect::<Vec<_>>()
            };
            // (the conditions here reach order 3; RosW6S4's fourth W-order is shown by convergence
            // with wrong and perturbed Jacobians, `tests/integrate_ros34.rs`)
            assert_eq!(proven_order(&wc(&t.b), &[1, 2, 5], 4e-15), w.min(3), "{m:?}: W-order of the solution {:?}", wc(&t.b));
            assert_eq!(proven_order(&wc(&t.b_hat), &[1, 2, 5], 4e-15), w_hat, "{m:?}: W-order of the embedded one {:?}", wc(&t.b_hat));
            // classical conditions: 1, 1, 2, 4 of orders 1-4
            let cc = |x: &[f64; MAX_STAGES]| classical_conditions(&t, x);
            assert_eq!(proven_order(&cc(&t.b), &[1, 1, 2, 4], 1e-14), p, "{m:?}: classical order {:?}", cc(&t.b));
            assert_eq!(proven_order(&cc(&t.b_hat), &[1, 1, 2, 4], 1e-14), p_hat, "{m:?}: classical embedded order {:?}", cc(&t.b_hat));
        }
        // stiffly accurate: b_i = alpha_4i + gamma_4i
        for m in [Method::Ros34pw2, Method::Ros34prw] {
            let t = m.tableau();
            for i in 0..4 {
                assert!((t.b[i] - (t.alpha[3][i] + t.gamma_ij[3][i])).abs() < 4e-16, "{m:?}");
            }
        }
    }

    #[test]
    fn no_three_stage_tableau_with_alpha_32_zero_is_a_w_method_of_order_3() {
        // b alpha a = b_3 alpha_32 a_2 (a_1 = 0): with alpha_32 = 0 it is 0, never 1/6
        let t = Method::Ros3pw.tableau();
        assert_eq!(t.alpha[2][1], 0.0);
        let (_, c3) = w_conditions(&t, &t.b);
        assert!((c3[1] + 1.0 / 6.0).abs() < 1e-15, "{c3:?}");
    }

    #[test]
    fn stability_at_infinity_is_the_published_one() {
        // R(z) = 1 + z b (I - z (alpha + Gamma))^-1 1 (Hairer & Wanner II, sec. IV.7); at infinity
        // R = 1 - b beta^-1 1 with beta = alpha + Gamma (lower triangular, gamma on the diagonal)
        for (m, r_inf, r_inf_hat) in [(Method::Ros34pw2, 0.0, 0.48), (Method::Ros3pw, 0.73, 0.73), (Method::Ros34pw3, 0.63, f64::NAN), (Method::Ros34prw, 0.0, 0.25), (Method::Rosw6s4, 0.0, 0.50)] {
            let t = m.tableau();
            let beta = Matrix6::from_fn(|i, j| if i >= t.stages && i == j { 1.0 } else { t.alpha[i][j] + t.gamma_ij[i][j] });
            let bi = beta.try_inverse().unwrap();
            let one = nalgebra::Vector6::repeat(1.0);
            let r = 1.0 - (RowVector6::from_row_slice(&t.b) * bi * one)[0];
            let rh = 1.0 - (RowVector6::from_row_slice(&t.b_hat) * bi * one)[0];
            assert!((r.abs() - r_inf).abs() < 0.01, "{m:?}: R(inf) = {r}");
            if r_inf_hat.is_finite() {
                assert!((rh.abs() - r_inf_hat).abs() < 0.01, "{m:?}: embedded R(inf) = {rh}");
            }
        }
    }

    #[test]
    fn transformed_form_reproduces_the_weights() {
        let t = Transformed::ros34pw2();
        let gamma = Matrix6::from_fn(|i, j| if i < 4 && j < 4 { GAMMA[i][j] } else if i == j { GAMMA_DIAG } else { 0.0 });
        // m Gamma = b, e Gamma = b - b^
        let b = t.m * gamma;
        let e = t.e * gamma;
        for i in 0..4 {
            assert!((b[i] - B[i]).abs() < 1e-14);
            assert!((e[i] - (B[i] - B_HAT[i])).abs() < 1e-14);
        }
        assert!((t.c[1] - 0.87173304301691801).abs() < 1e-16 && t.c[3] == 1.0);
    }
}
