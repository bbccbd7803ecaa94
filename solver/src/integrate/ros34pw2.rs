//! Rosenbrock-W methods: ROS34PW2 (four stages, third order for any Jacobian approximation, embedded second-order estimate), other W-tableaux of order 3, and RosW6S4 (six stages, order 4).
//!
//! Rang & Angermann, "New Rosenbrock W-methods of order 3 for partial
//! differential algebraic equations of index 1", BIT Numer. Math. 45, 761 (2005),
//! method ROS34PW2 (stiffly accurate, L-stable with the exact Jacobian), the default; the
//! same stepper runs the other tableaux of [`Method`] (ROS3Pw and ROS34PW3 of the same paper,
//! ROS34PRw of Rang, J. Comput. Appl. Math. 286, 128 (2015)) through [`Ros34pw2::with_method`],
//! all W-methods of order 3 with an embedded solution of order 2, and RosW6S4 (Rahunanthan &
//! Stanescu 2010), a W-method of order 4 with six stages and an embedded solution of order 3
//! ([`Method::Rosw6s4`]; with penalty walls it is cheaper and closer to the paper's integrator
//! than ROS34PW2, `solver/README.md` "Session 34"). In the
//! form of Hairer & Wanner (Solving ODEs II, sec. IV.7), with `k_i` increments (um):
//! ```text
//! (I - gamma h J) k_i = h f(y + sum_{j<i} alpha_ij k_j) + h J sum_{j<i} gamma_ij k_j
//! y1 = y + sum b_i k_i            (order 3 for any J: a W-method)
//! y1^ = y + sum b^_i k_i          (order 2, embedded)
//! ```
//! with `gamma = 0.43586652150845900` and the `alpha`, `gamma_ij`, `b`, `b^` of
//! [`ALPHA`], [`GAMMA`], [`B`], [`B_HAT`] (the paper's table, 17 digits as in
//! PETSc's `TSROSWRA34PW2`). The code uses the equivalent transformed form that
//! needs no Jacobian product on the right-hand side (Hairer & Wanner eq. (7.25)):
//! with `u = Gamma k` (`Gamma` the lower triangle of `gamma_ij`, `gamma` on its diagonal),
//! ```text
//! (I - gamma h J) u_i = gamma h f(y + sum_{j<i} (alpha Gamma^-1)_ij u_j) - gamma sum_{j<i} (Gamma^-1)_ij u_j
//! y1 = y + sum (b Gamma^-1)_i u_i,     err = y1 - y1^ = sum ((b - b^) Gamma^-1)_i u_i
//! ```
//! No `h gamma_i df/dt` term: the stages are evaluated at `t + alpha_i h`, which is
//! the method applied to the autonomised system `(y, t)' = (f, 1)` with a `J` that
//! omits the column `df/dt`; as a W-method it keeps order 3 with that `J` too
//! (`tests/integrate_ros34.rs` checks it on the non-autonomous Prothero-Robinson problem).
//!
//! The stage matrix `W = I - gamma h J` is the same for all stages. `J` is
//! either the lagged-mobility Jacobian of [`super::Linearised::jacobian_apply`]
//! (every product a Stokes solve; the systems solved by GMRES, right-preconditioned
//! with the local sparse `W_loc = I - gamma h J_loc` of [`super::precondition`]),
//! or `J_loc` itself ([`StageJacobian::Local`]: each stage one sparse triangular
//! solve, no Stokes solve beyond the stages' velocity evaluations). A stage solve
//! that misses its tolerance, or a singular `W_loc`, rejects the step (error `+inf`), so the
//! controller retries with a smaller step; failure detection (NaN, inverted
//! triangles, area change, step collapse) and the volume-drift correction are
//! those of [`crate::run::Runner`], as for every scheme.

// the published 17-digit coefficients are kept verbatim, so that they can be checked against the paper
#![allow(clippy::excessive_precision)]

use crate::gmres::{gmres_preconditioned, GmresOptions, Tolerance};
use super::mobility_jacobian::DenseStage;
use super::wall_block::WallCoupling;
use super::precondition::StageMatrix;
use super::{flatten, Integrator, Linearised, StateMap, StepContext, StepWork};
use crate::error::SolverError;
use nalgebra::{Matrix6, RowVector6, Vector3};

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

/// Which `J` the stage matrix `I - gamma h J` uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StageJacobian {
    /// The lagged-mobility Jacobian of [`Linearised::jacobian_apply`], solved by GMRES
    /// (preconditioned with the local Jacobian when the dynamics provides one and `precondition` is set).
    Lagged,
    /// The local sparse Jacobian of [`Linearised::local_jacobian`] only, solved directly.
    Local,
    /// The dense mobility Jacobian of [`Linearised::mobility_jacobian`] (every vertex pair's
    /// free-space two-fluid mobility times the stiffness), factorised densely and kept for
    /// several steps ([`Ros34pw2::reuse`]).
    Mobility,
}

/// When [`StageJacobian::Mobility`] keeps its factorised `W = I - g_0 J_mob` for a step of
/// `gamma h`: a W-method with `J' = g_0/(s gamma h) s J_mob` (its W-order for any `J`); stability needs
/// `J'` to stay above ~0.7 of the true `J` on the stiff modes, accuracy that it stays close.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reuse {
    /// Keep the factor while `h / h_0` lies in `[min_ratio, max_ratio]` ...
    pub min_ratio: f64,
    pub max_ratio: f64,
    /// ... and for at most this many accepted steps (the shape, hence `J`, moves on).
    pub max_age: usize,
    /// ... or for at most `quiet_max_age` accepted steps while the cell is quiet: its own error
    /// norm at the last accepted step, the largest vertex error of the cell (not of the penalty
    /// walls' displacements after it) over the tolerance `atol_um`, at most `quiet_cell_error`.
    pub quiet_cell_error: f64,
    pub quiet_max_age: usize,
}

impl Reuse {
    /// With penalty walls: the walls set every step (their traction pattern travels with the
    /// cell past the wall vertices, `solver/README.md` "Session 25"), at 0.3-0.4 of the step the
    /// cell's error alone would allow, and a factor refactorised every step is ~15 % of a step's
    /// cost. On a settled croissant the cell's error norm stays at 0.03-0.10 and a factor kept
    /// over 3 steps cost 0.86 of the core-s at equal deviations from bs23 (u3.8 and u1.5); on a
    /// tank-treading slipper (0.11-0.16) it cost 0.95 but with 4x the rejections and dy 1.14x
    /// farther from bs23, so the cell's error decides (`solver/README.md`, "Session 33"). The
    /// threshold 0.1 sits just above the largest value measured on a settled croissant (0.099 at
    /// u1.5) and below the smallest on the slipper (0.109): a busier croissant falls back to a
    /// factor a step, which costs time, not accuracy.
    pub const PENALTY_WALLS: Reuse = Reuse { min_ratio: 0.5, max_ratio: 1.3, max_age: 1, quiet_cell_error: 0.1, quiet_max_age: 3 };
}

impl Default for Reuse {
    /// A factor serves the step it was built for and its retries only (`max_age` 1): material
    /// flows through the rear rim's fold within a few steps, and a factor kept over several
    /// accepted steps left a mode there unstable (measured mid-run at atol 1e-2 um: steps in a
    /// 250 -> 480 us limit cycle with 13 rejections in 54 attempts and an error growing 3x per
    /// step at constant `h`; rebuilt every step, 26 + 2 steps of 470-540 us and 0.63 of the
    /// core-s, `solver/README.md`).
    fn default() -> Self {
        Self { min_ratio: 0.5, max_ratio: 1.3, max_age: 1, quiet_cell_error: 0.0, quiet_max_age: 1 }
    }
}

/// The dense stage factor and where it was built (kept in checkpoints as its linearisation
/// point, `g` and age, so that a resumed run refactorises the same matrix).
#[derive(Debug)]
struct DenseFactor {
    stage: DenseStage,
    x: Vec<Vector3<f64>>,
    t: f64,
    age: usize,
}

/// Counters of the stage solves.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageStats {
    /// Linear stage solves.
    pub solves: usize,
    /// GMRES iterations (Jacobian applications) over all stage solves.
    pub iterations: usize,
    /// Sparse LU factorisations of `I - gamma h J_loc`.
    pub factorisations: usize,
    /// Stage solves that missed their tolerance (or singular `W_loc`): rejected steps.
    pub failed: usize,
}

/// ROS34PW2 stepper; owns its stage buffers.
#[derive(Debug)]
pub struct Ros34pw2 {
    pub jacobian: StageJacobian,
    /// Right-precondition the GMRES stage solves with `I - gamma h J_loc` (Lagged only).
    pub precondition: bool,
    /// Krylov dimension before restart, maximal Jacobian applications per stage solve.
    pub restart: usize,
    pub max_iterations: usize,
    /// The stage residual (um, 2-norm) is driven below this fraction of the absolute tolerance (default 0.05, as ROS2).
    pub linear_tol_fraction: f64,
    /// The local Jacobian enters the stage matrix as `local_scale J_loc`. Preconditioner:
    /// 0.5 (the disc self-mobility over-estimates the lambda = 5 mobility of the mid-wavelength
    /// modes that dominate the iterations; measured 43 -> 14 iterations at 0.5, 29 at 1, 300 at 4 on
    /// the stiff 512-triangle cell, `tests/integrate_precondition.rs`). Local W-method: 2, a
    /// stability margin (the W-method is stable on modes where `local_scale J_loc >= 0.7 J`).
    pub local_scale: f64,
    /// Reuse of the dense factor ([`StageJacobian::Mobility`]).
    pub reuse: Reuse,
    /// Step across output times and let the runner interpolate the samples (default): the
    /// velocity at the end of a step is the first stage of the next, so the cubic Hermite
    /// interpolant costs no evaluation ([`Integrator::end_velocity`]).
    pub dense_output: bool,
    pub stats: StageStats,
    /// The walls' answer to the cell in the stage matrix ([`StageJacobian::Mobility`] with
    /// penalty walls; [`WallCoupling`], `integrator.wall_coupling`); `None`: `J` block diagonal.
    pub wall_coupling: Option<WallCoupling>,
    /// The tableau ([`Ros34pw2::with_method`]).
    method: Method,
    tab: Transformed,
    f0: Vec<Vector3<f64>>,
    u: [Vec<Vector3<f64>>; MAX_STAGES],
    y: Vec<Vector3<f64>>,
    rhs: Vec<Vector3<f64>>,
    /// `f0` and the linearisation are valid for the state at this time.
    valid_at: Option<f64>,
    /// Factorised local stage matrix for the current linearisation.
    stage: Option<StageMatrix>,
    /// Factorised dense stage matrix ([`StageJacobian::Mobility`]) and a factor to rebuild after a restore.
    dense: Option<DenseFactor>,
    /// Buffers of an invalidated dense factor, reused by the next factorisation.
    spare: Option<DenseStage>,
    restored: Option<(Vec<Vector3<f64>>, f64, f64, usize)>,
    /// `f0` was restored from a checkpoint for this time (the state is not yet linearised).
    restored_f0: Option<f64>,
    /// Time of the last attempt (a second attempt at the same time follows a rejection).
    last_attempt_t: Option<f64>,
    /// The cell's error norm of the last attempt and of the last accepted step ([`Reuse`]).
    attempt_cell_error: Option<f64>,
    cell_error: Option<f64>,
}

impl Ros34pw2 {
    /// Lagged-mobility Jacobian, preconditioned stage solves.
    pub fn new() -> Self {
        Self::with(StageJacobian::Lagged, true)
    }

    /// Choose the Jacobian and whether GMRES is preconditioned.
    pub fn with(jacobian: StageJacobian, precondition: bool) -> Self {
        Self {
            jacobian,
            precondition,
            restart: 30,
            max_iterations: 200,
            linear_tol_fraction: 0.05,
            local_scale: match jacobian {
                StageJacobian::Local => 2.0,
                StageJacobian::Mobility => 1.5,
                StageJacobian::Lagged => 0.5,
            },
            reuse: Reuse::default(),
            dense_output: true,
            stats: StageStats::default(),
            wall_coupling: None,
            method: Method::Ros34pw2,
            tab: Transformed::ros34pw2(),
            f0: Vec::new(),
            u: Default::default(),
            y: Vec::new(),
            rhs: Vec::new(),
            valid_at: None,
            stage: None,
            dense: None,
            spare: None,
            restored: None,
            restored_f0: None,
            last_attempt_t: None,
            attempt_cell_error: None,
            cell_error: None,
        }
    }

    /// The same stepper with another tableau (default ROS34PW2).
    pub fn with_method(mut self, method: Method) -> Self {
        self.method = method;
        self.tab = Transformed::of(&method.tableau());
        self
    }

    /// The tableau in use.
    pub fn method(&self) -> Method {
        self.method
    }

    /// Buffers sized for `n` vertices, `f0 = f(t, x)` and the linearisation at `(t, x)` (kept
    /// until the next accepted step); returns the velocity evaluations it took (0 or 1).
    fn prepare<D: Linearised + ?Sized>(&mut self, f: &mut D, t: f64, x: &[Vector3<f64>]) -> Result<usize, SolverError> {
        let n = x.len();
        if self.f0.len() != n {
            self.f0.resize(n, Vector3::zeros());
            self.valid_at = None;
            self.restored_f0 = None;
        }
        for v in [&mut self.y, &mut self.rhs] {
            v.resize(n, Vector3::zeros());
        }
        for v in &mut self.u {
            v.resize(n, Vector3::zeros());
        }
        if self.jacobian == StageJacobian::Mobility {
            self.rebuild_restored(f, n)?;
        }
        if self.valid_at == Some(t) {
            return Ok(0);
        }
        let evals = if self.restored_f0 == Some(t) {
            0
        } else {
            f.velocity(t, x, &mut self.f0)?;
            1
        };
        self.restored_f0 = None;
        f.linearise(t, x)?;
        self.valid_at = Some(t);
        self.stage = None;
        Ok(evals)
    }

    /// Make sure a dense factor usable for `g = local_scale gamma h` exists (reusing the kept one
    /// under [`Reuse`], refactorising at the current linearisation point otherwise); `false` when
    /// `I - g J_mob` is singular (the step is then rejected).
    /// The walls' part (penalty walls) is factorised at `g_wall`, the step's own `gamma h`, also
    /// when the cell's factor is kept ([`super::wall_block`]).
    fn dense_stage<D: Linearised + ?Sized>(&mut self, f: &mut D, t: f64, x: &[Vector3<f64>], g: f64, g_wall: f64, retry: bool) -> Result<bool, SolverError> {
        if let Some(d) = &mut self.dense {
            let ratio = g / d.stage.g;
            let fresh = d.t == t;
            let quiet = self.cell_error.is_some_and(|e| e <= self.reuse.quiet_cell_error);
            let max_age = if quiet { self.reuse.quiet_max_age.max(self.reuse.max_age) } else { self.reuse.max_age };
            let in_band = ratio >= self.reuse.min_ratio && ratio <= self.reuse.max_ratio && d.age < max_age;
            // after a rejection, an old factor is rebuilt at the current state
            if in_band && (fresh || !retry) {
                d.stage.set_wall_g(g_wall);
                return Ok(true);
            }
        }
        let mut stage = self.take_dense_buffers();
        let Some(j) = f.mobility_jacobian()? else {
            return Err(SolverError::Unsupported {
                field: "integrator.scheme".into(),
                message: "the mobility-Jacobian W-method needs a membrane with an assembled stiffness (Skalak or tension) and a Stokes operator with known viscosities".into(),
            });
        };
        match stage.factorise_with_wall_g(&j, g, g_wall) {
            Ok(()) => {
                self.stats.factorisations += 1;
                self.dense = Some(DenseFactor { stage, x: x.to_vec(), t, age: 0 });
                Ok(true)
            }
            Err(_) => {
                self.spare = Some(stage);
                Ok(false)
            }
        }
    }

    /// The buffers of the current dense factor (invalidated) or of a spare one, to refactorise
    /// into without allocating (76 MB each at 2048 triangles).
    fn take_dense_buffers(&mut self) -> DenseStage {
        match self.dense.take() {
            Some(d) => d.stage,
            None => self.spare.take().unwrap_or_else(DenseStage::empty),
        }
    }

    /// Rebuild the dense factor saved in a checkpoint: linearise at its point, factorise with its `g`.
    fn rebuild_restored<D: Linearised + ?Sized>(&mut self, f: &mut D, n: usize) -> Result<(), SolverError> {
        let Some((x, t, g, age)) = self.restored.take() else { return Ok(()) };
        if x.len() != n {
            return Err(SolverError::Output(format!("checkpoint field dense_x: {} vertices, the state has {n}", x.len())));
        }
        f.linearise(t, &x)?;
        self.valid_at = None;
        let Some(j) = f.mobility_jacobian()? else { return Ok(()) };
        let mut stage = self.take_dense_buffers();
        if stage.factorise(&j, g).is_ok() {
            self.stats.factorisations += 1;
            self.dense = Some(DenseFactor { stage, x, t, age });
        } else {
            self.spare = Some(stage);
        }
        Ok(())
    }
}

impl Default for Ros34pw2 {
    fn default() -> Self {
        Self::new()
    }
}

/// Build (or reuse) the factorised `I - gamma h J_loc` for `gh`; `None` when the dynamics has no local Jacobian.
fn stage_matrix<D: Linearised + ?Sized>(f: &mut D, stage: &mut Option<StageMatrix>, gh: f64, stats: &mut StageStats) -> Result<bool, SolverError> {
    // (gh already carries local_scale: I - (s gamma h) J_loc)
    if stage.as_ref().is_some_and(|s| s.gamma_h == gh) {
        return Ok(true);
    }
    *stage = None;
    let Some(j) = f.local_jacobian()? else { return Ok(false) };
    match j.stage_matrix(gh) {
        Ok(s) => {
            stats.factorisations += 1;
            *stage = Some(s);
            Ok(true)
        }
        // a singular W_loc (a geometric-stiffness mode with gamma h lambda = 1): reject the step
        Err(_) => Ok(false),
    }
}

impl<D: Linearised + ?Sized> Integrator<D> for Ros34pw2 {
    fn name(&self) -> &'static str {
        // [tableau][ros34pw2-local, -mobility, (lagged, preconditioned), -plain]
        const NAMES: [[&str; 4]; 5] = [
            ["ros34pw2-local", "ros34pw2-mobility", "ros34pw2", "ros34pw2-plain"],
            ["ros3pw-local", "ros3pw-mobility", "ros3pw", "ros3pw-plain"],
            ["ros34pw3-local", "ros34pw3-mobility", "ros34pw3", "ros34pw3-plain"],
            ["ros34prw-local", "ros34prw-mobility", "ros34prw", "ros34prw-plain"],
            ["rosw6s4-local", "rosw6s4-mobility", "rosw6s4", "rosw6s4-plain"],
        ];
        let row = Method::ALL.iter().position(|m| *m == self.method).expect("every method is listed");
        let col = match (self.jacobian, self.precondition) {
            (StageJacobian::Local, _) => 0,
            (StageJacobian::Mobility, _) => 1,
            (StageJacobian::Lagged, true) => 2,
            (StageJacobian::Lagged, false) => 3,
        };
        NAMES[row][col]
    }

    fn embedded_order(&self) -> u32 {
        // the classical order of the embedded solution (the step controller's exponent); ROS34PRw's
        // W-order-1 embedded one is still run as order 2 (session 25's measurements)
        self.method.embedded_order()
    }

    fn attempt(
        &mut self,
        f: &mut D,
        t: f64,
        x: &[Vector3<f64>],
        h: f64,
        ctx: StepContext,
        x_new: &mut [Vector3<f64>],
        err: &mut [Vector3<f64>],
    ) -> Result<StepWork, SolverError> {
        let n = x.len();
        let mut work = StepWork::default();
        let retry = self.last_attempt_t == Some(t);
        self.last_attempt_t = Some(t);
        // (set at the end of an attempt that ran its stages: an early return leaves none)
        self.attempt_cell_error = None;
        work.velocity_evals += self.prepare(f, t, x)?;
        let gh = self.tab.gamma * h;
        if self.jacobian == StageJacobian::Mobility && !self.dense_stage(f, t, x, self.local_scale * gh, gh, retry)? {
            self.stats.failed += 1;
            err.iter_mut().for_each(|e| *e = Vector3::repeat(f64::INFINITY));
            x_new.copy_from_slice(x);
            return Ok(work);
        }
        let want_local = self.jacobian == StageJacobian::Local || (self.jacobian == StageJacobian::Lagged && self.precondition);
        let have_local = want_local && stage_matrix(f, &mut self.stage, self.local_scale * gh, &mut self.stats)?;
        if self.jacobian == StageJacobian::Local && !have_local {
            if f.local_jacobian()?.is_none() {
                return Err(SolverError::Unsupported {
                    field: "integrator.scheme".into(),
                    message: "the local-Jacobian W-method needs a membrane with an assembled stiffness (Skalak or tension) and a Stokes operator with known viscosities".into(),
                });
            }
            self.stats.failed += 1;
            err.iter_mut().for_each(|e| *e = Vector3::repeat(f64::INFINITY));
            x_new.copy_from_slice(x);
            return Ok(work);
        }
        let opts = GmresOptions { restart: self.restart, max_iterations: self.max_iterations, tolerance: Tolerance::Absolute(self.linear_tol_fraction * ctx.atol_um) };
        let tab = self.tab;
        let mut converged = true;
        for i in 0..tab.stages {
            // stage value and its velocity
            let fi: &[Vector3<f64>] = if i == 0 {
                &self.f0
            } else {
                for (p, (yi, xi)) in self.y.iter_mut().zip(x).enumerate() {
                    let mut s = *xi;
                    for j in 0..i {
                        s += tab.a[(i, j)] * self.u[j][p];
                    }
                    *yi = s;
                }
                f.velocity(t + tab.c[i] * h, &self.y, &mut self.rhs)?;
                work.velocity_evals += 1;
                &self.rhs
            };
            // right-hand side gamma h f_i - gamma sum_j (Gamma^-1)_ij u_j, written into y (free now)
            for (p, (yp, fp)) in self.y.iter_mut().zip(fi).enumerate() {
                let mut s = gh * fp;
                for j in 0..i {
                    s -= tab.gamma * tab.gamma_inv[(i, j)] * self.u[j][p];
                }
                *yp = s;
            }
            let (done, rest) = self.u.split_at_mut(i);
            let _ = done;
            let ui = &mut rest[0];
            ui.copy_from_slice(&self.y);
            self.stats.solves += 1;
            match (self.jacobian, self.stage.as_ref().filter(|_| have_local)) {
                (StageJacobian::Mobility, _) => {
                    let stage = &self.dense.as_ref().expect("factorised above").stage;
                    match self.wall_coupling.as_mut().filter(|_| stage.wall_vertices() > 0) {
                        None => stage.solve_in_place(ui),
                        Some(coupling) => {
                            // block lower triangular: the cell first, then the walls with gamma h J_wc u_c
                            let nc = stage.cell_vertices();
                            stage.solve_cell_in_place(&mut ui[..nc]);
                            work.velocity_evals += coupling.add(f, t, x, &self.f0, ui, nc, gh)?;
                            stage.solve_wall_in_place(&mut ui[nc..]);
                        }
                    }
                }
                (StageJacobian::Local, Some(s)) => s.solve_in_place(ui),
                (StageJacobian::Local, None) => unreachable!("checked above"),
                (StageJacobian::Lagged, pre) => {
                    // initial guess: W_loc^-1 r when preconditioned, else r (exact for non-stiff components as h -> 0)
                    if let Some(s) = pre {
                        s.solve_in_place(ui);
                    }
                    let mut applies = 0usize;
                    let rep = gmres_preconditioned::<_, _, SolverError>(
                        |v, out| {
                            f.jacobian_apply(v, out)?;
                            applies += 1;
                            for (o, vi) in out.iter_mut().zip(v) {
                                *o = vi - gh * *o;
                            }
                            Ok(())
                        },
                        |v| {
                            if let Some(s) = pre {
                                s.solve_in_place(v)
                            }
                        },
                        &self.y,
                        ui,
                        &opts,
                    )?;
                    work.jacobian_applies += applies;
                    self.stats.iterations += rep.iterations;
                    converged &= rep.converged();
                }
            }
        }
        for p in 0..n {
            let (mut s, mut e) = (x[p], Vector3::zeros());
            for j in 0..tab.stages {
                s += tab.m[j] * self.u[j][p];
                e += tab.e[j] * self.u[j][p];
            }
            x_new[p] = s;
            err[p] = e;
        }
        if !converged {
            self.stats.failed += 1;
            err.iter_mut().for_each(|e| *e = Vector3::repeat(f64::INFINITY));
        }
        if self.reuse.quiet_max_age > self.reuse.max_age {
            if let Some(d) = self.dense.as_ref().filter(|_| self.jacobian == StageJacobian::Mobility) {
                let cell = d.stage.cell_vertices();
                self.attempt_cell_error = Some(err[..cell].iter().map(|e| e.norm()).fold(0.0, f64::max) / ctx.atol_um);
            }
        }
        Ok(work)
    }

    fn accepted(&mut self) {
        self.valid_at = None;
        self.last_attempt_t = None;
        self.cell_error = self.attempt_cell_error.take();
        if let Some(d) = &mut self.dense {
            d.age += 1;
        }
    }

    fn dense_output(&self) -> bool {
        self.dense_output
    }

    fn end_velocity(&mut self, f: &mut D, t: f64, x: &[Vector3<f64>]) -> Result<Option<(Vec<Vector3<f64>>, usize)>, SolverError> {
        if !self.dense_output {
            return Ok(None);
        }
        let evals = self.prepare(f, t, x)?;
        Ok(Some((self.f0.clone(), evals)))
    }

    /// The first stage of the next step when it is already evaluated (dense output), the
    /// dense factor's linearisation point, time, `g` and age ([`StageJacobian::Mobility`]), and
    /// the cell's error norm of the last accepted step when [`Reuse`] reads it (`cell_error`).
    fn save_state(&self, prefix: &str, out: &mut StateMap) {
        if let Some(t) = self.valid_at {
            out.insert(format!("{prefix}f0_um_s"), flatten(&self.f0));
            out.insert(format!("{prefix}f0_t_s"), vec![t]);
        }
        if let Some(d) = &self.dense {
            out.insert(format!("{prefix}dense_x"), flatten(&d.x));
            out.insert(format!("{prefix}dense_t_g_age"), vec![d.t, d.stage.g, d.age as f64]);
        }
        if let Some(e) = self.cell_error {
            out.insert(format!("{prefix}cell_error"), vec![e]);
        }
    }

    fn restore_state(&mut self, prefix: &str, state: &StateMap) -> Result<(), SolverError> {
        self.valid_at = None;
        self.restored_f0 = None;
        if let (Some(f0), Some(t)) = (super::state_vectors(state, &format!("{prefix}f0_um_s"))?, state.get(&format!("{prefix}f0_t_s"))) {
            let [t] = t[..] else {
                return Err(SolverError::Output(format!("checkpoint field {prefix}f0_t_s: {} values, expected 1", t.len())));
            };
            self.f0 = f0;
            self.restored_f0 = Some(t);
        }
        self.dense = None;
        self.restored = None;
        if let (Some(x), Some(tga)) = (super::state_vectors(state, &format!("{prefix}dense_x"))?, state.get(&format!("{prefix}dense_t_g_age"))) {
            let [t, g, age] = tga[..] else {
                return Err(SolverError::Output(format!("checkpoint field {prefix}dense_t_g_age: {} values, expected 3", tga.len())));
            };
            self.restored = Some((x, t, g, age as usize));
        }
        // (a checkpoint from before session 33 has none: the first step then keeps `max_age`)
        self.cell_error = match state.get(&format!("{prefix}cell_error")).map(|v| &v[..]) {
            None => None,
            Some([e]) => Some(*e),
            Some(v) => return Err(SolverError::Output(format!("checkpoint field {prefix}cell_error: {} values, expected 1", v.len()))),
        };
        Ok(())
    }

    fn invalidate(&mut self) {
        self.valid_at = None;
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
