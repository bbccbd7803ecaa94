//! The penalty walls' block of the dense stiff-mode Jacobian, `J_ww`, and its part of the factorised stage matrix.
//!
//! With the paper's penalty walls ([`crate::dynamics::penalty`]) the state carries the wall
//! displacements `d` after the cell's vertices `x`, and the Jacobian has four blocks:
//!
//! ```text
//! J = [[J_cc, J_cw],      J_cc = M_fs K                  the cell's own (super::mobility_jacobian)
//!      [J_wc, J_ww]]      J_ww = -(kappa_W / mu) S + ... the springs relaxing through the wall's
//!                                                        single layer (ChannelStokes::penalty_wall_jacobian)
//!                         J_wc, J_cw                     the walls' answer to the cell and back
//! ```
//!
//! The W-method uses `J = [[J_cc, 0], [0, J_ww]]`, or with `integrator.wall_coupling` the block
//! lower triangular `[[J_cc, 0], [J_wc, J_ww]]`, `J_wc` applied exactly to each stage's cell
//! increment by a difference of the velocity ([`WallCoupling`], session 37: it removes the
//! drift towards the axis that the block-diagonal `J` leaves, at ~1.7-1.8x the cost). `J_ww` is stiff (rates up to 1.4e5 /s at the
//! paper's `kappa_W`, [`crate::channel::ChannelStokes::penalty_rate`]) and must be in `J` for steps
//! beyond the springs' explicit limit (~18 us, where bs23 stays). It does not depend on the cell,
//! and it is exact at `lambda = 1`. Its `I - g J_ww` (`3 Nw`, 1512 unknowns at 2 um wall edges)
//! is factorised per `g` in double precision (~0.1 s, beside the cell's ~0.5 s).
//!
//! **The walls' `g` is the step's own `gamma h`**, unlike the cell's: the cell's `J_mob` only
//! approximates its Jacobian and enters scaled (`local_scale` 1.5, a stability margin), and a kept
//! factor serves retries at other steps. The walls' block is exact, and a W-method whose `J` is
//! `s` times the exact Jacobian of a stiff component that tracks a moving quasi-static state
//! reaches that state only to first order in the step when `s != 1` (ROS34PW2 on
//! `y' = lambda (y - sin t) + cos t`, `lambda = -1e5`, `h` = 0.1 ... 0.0125: error 3.3e-3 ... 4.1e-4
//! at `s = 1.5` against 5e-9 ... 8e-11 at `s = 1`). So `WallStage::set_g` refactorises the walls'
//! part at `gamma h` whenever the step changes, which costs ~0.1 s only on the steps where it does.
//! Measured mid-run (`solver/README.md`, "Session 24"): the cell's lateral drift from bs23 fell
//! 4.4x at the cell's tolerance at the same cost.
//!
//! The walls are a fast variable that tracks a moving quasi-static state (the no-slip traction
//! over `kappa_W`, lagging by the physical slip), and a W-method reaches such a state only to a
//! low order in the step (Hairer & Wanner II, sec. VI.3: it needs the fast equation's dependence
//! on the slow variables in `J` as well). Measured mid-run: the cell drifts laterally from the
//! bs23 run of the same walls at a rate first order or so in the walls' local error, as large as
//! the physical difference between the wall models at the cell's tolerance. So the walls take a
//! tolerance of their own (`integrator.wall_atol_um`, [`crate::run::StepControl::with_tail_atol`]).
//! Tried and dropped (`solver/README.md`, "Session 23"): the walls' answer to the cell in `J`,
//! `J_wc` = the free-space Stokeslet from the cell's vertices times `K` plus the answer to
//! moving the cell's loaded vertices (the stage matrix block lower triangular): ~1.3x longer
//! steps at equal error at 2048 triangles, but 2.8x the error on the coarse 128-triangle cell at
//! lambda = 5, where point forces do not resolve the cell seen from the walls 2 um away.
//! Session 25 (`solver/README.md`, "Session 25"): the walls set every step of a penalty run, and
//! an exact `J_wc u_c` (a finite difference of the penalty velocity) leaves the steps of a
//! settled croissant as they are: the step resolves the traction pattern that travels with the
//! cell past the wall vertices (~0.8 ms a vertex at 2.5 mm/s), which no `J` removes.
//! Session 36 measured what the missing `J_wc` costs in accuracy rather than steps: the cell
//! drifts towards the axis at ~0.09 um/s against bs23 (RosW6S4 at ~2.5-4 mm/s). Session 37 put
//! the exact `J_wc u_c` back ([`WallCoupling`]): the same steps, 1.7-1.8x the cost, the drift
//! 11x smaller (`solver/README.md`, "Session 37").
//! Session 33: so the cell's own factor may serve up to 3 of those steps while the cell is quiet
//! ([`super::ros34pw2::Reuse::PENALTY_WALLS`]), and PI step control damps the walls' error norm,
//! which swings as the pattern passes the wall vertices (`rbc_schema::scene::StepController`).

use super::Linearised;
use crate::error::SolverError;
use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::Mat;
use nalgebra::Vector3;
use std::sync::Arc;

/// The walls' block `J_ww` (1/s, `3m x 3m`, row and column `3 i + c`), shared by the Jacobians of every step.
#[derive(Debug)]
pub struct WallBlock {
    j_ww: Mat<f64>,
}

impl WallBlock {
    /// `j_ww` (`3m x 3m`, 1/s) on `m` wall vertices.
    pub fn new(j_ww: Mat<f64>) -> Self {
        assert!(j_ww.nrows() == j_ww.ncols() && j_ww.nrows().is_multiple_of(3), "J_ww is 3m x 3m");
        Self { j_ww }
    }

    /// Number of wall vertices.
    pub fn vertices(&self) -> usize {
        self.j_ww.nrows() / 3
    }

    /// `out = J_ww w` (um/s for `w` in um).
    pub(super) fn apply(&self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        let y = &self.j_ww * Mat::from_fn(self.j_ww.nrows(), 1, |r, _| w[r / 3][r % 3]);
        for (i, o) in out.iter_mut().enumerate() {
            *o = Vector3::new(y[(3 * i, 0)], y[(3 * i + 1, 0)], y[(3 * i + 2, 0)]);
        }
    }
}

/// The walls' part of a factorised stage matrix: the LU of `I - g J_ww`.
#[derive(Debug)]
pub struct WallStage {
    block: Arc<WallBlock>,
    /// `g` (s) of the factor.
    g: f64,
    lu: PartialPivLu<f64>,
}

impl WallStage {
    /// Factorise `I - g J_ww`.
    pub(super) fn factorise(block: &Arc<WallBlock>, g: f64) -> Self {
        Self { block: Arc::clone(block), g, lu: Self::lu(block, g) }
    }

    fn lu(block: &WallBlock, g: f64) -> PartialPivLu<f64> {
        let j = &block.j_ww;
        Mat::from_fn(j.nrows(), j.ncols(), |r, c| f64::from(r == c) - g * j[(r, c)]).partial_piv_lu()
    }

    /// Refactorise at `g` (s) when the factor is of another `g` (see the module docs: the walls'
    /// `g` is the step's `gamma h`).
    pub(super) fn set_g(&mut self, g: f64) {
        if g != self.g {
            self.lu = Self::lu(&self.block, g);
            self.g = g;
        }
    }

    /// True when this is the factor of `block`'s walls.
    pub(super) fn is_of(&self, block: &Arc<WallBlock>) -> bool {
        Arc::ptr_eq(&self.block, block)
    }

    /// Number of wall vertices.
    pub fn vertices(&self) -> usize {
        self.block.vertices()
    }

    /// `v <- (I - g J_ww)^-1 v` on the walls' part of a stage.
    pub(super) fn solve_in_place(&self, v: &mut [Vector3<f64>]) {
        let m = self.vertices();
        let mut y = Mat::from_fn(3 * m, 1, |r, _| v[r / 3][r % 3]);
        self.lu.solve_in_place(&mut y);
        for (i, o) in v.iter_mut().enumerate() {
            *o = Vector3::new(y[(3 * i, 0)], y[(3 * i + 1, 0)], y[(3 * i + 2, 0)]);
        }
    }
}

/// The walls' answer to the cell in the stage matrix (`integrator.wall_coupling`): `J` block
/// lower triangular, `[[J_cc, 0], [J_wc, J_ww]]`, so that a stage solves the cell first and then
/// `(I - gamma h J_ww) u_w = r_w + gamma h J_wc u_c`.
///
/// `J_wc u_c` is the change of the walls' velocity as the cell moves along its stage increment
/// `u_c`, the walls' displacements held: a forward difference of the full velocity (one solve
/// more a stage), `(u_w(x + eps u_c) - u_w(x)) / eps` with `eps max_i |u_c,i| = delta_um`. A
/// W-method whose `J` holds the fast component's exact dependence on the slow one reaches the
/// fast component's moving quasi-static state at the scheme's order (Hairer & Wanner II, sec.
/// VI.3): on the tracking wall of `tests/integrate_ros34.rs` ROS34PW2's wall error falls
/// 110-420x and becomes third order, RosW6S4's 3e5x. In the channel the increment is mostly the cell's
/// advection along the axis (~0.3 um a stage at ~4 mm/s), which carries the walls' traction
/// pattern with it.
///
/// **`delta_um`** ([`WallCoupling::DELTA_UM`], 1e-2 um) balances the forward difference's
/// curvature against the solve's noise: the velocity comes from GMRES at a tolerance relative to
/// the whole right-hand side (1e-5), ~0.04 um/s a vertex, which the difference divides by `eps`;
/// so the difference's solve starts from the step's solution
/// ([`Linearised::velocity_near_linearisation`]), where the two solves' errors largely cancel.
/// Measured on the ~4 mm/s slipper (`solver/README.md`, "Session 37"), with the difference's
/// solve started from the last stage's: 1e-3 um left most of the drift and cost 2.5x (noisy wall
/// estimates, 96 steps against 69), 1e-1 um a drift of +0.036 um/s (the curvature), 1e-2 um
/// +0.0077 against RosW6S4's -0.085 at 1.73x its cost; started from the step's, 1e-2 um: +0.011
/// at 1.72x, the solve's noise in z halved (3e-3 um then: +0.022, more steps). Chosen for the
/// walls at the study's 1e-4 um: a much tighter `wall_atol_um` would meet the difference's noise.
///
/// **A difference every stage** (session 40): answering a stage from the span of the step's
/// earlier differences when its increment lies within 1-5 % of it took ~1.4 differences a step
/// instead of RosW6S4's 6 (1.17-1.23x the uncoupled cost instead of 1.66x), but kept only ~55 %
/// of the coupling's cut of the drift: the small differences between a step's stage increments
/// are what the walls must answer (`solver/README.md`, "Session 40").
///
/// **No answer without the solve** (session 41): half or more of `J_wc u` comes through the cell's
/// velocity change (the double layer, `-2 E[du_cell]` at lambda = 5), which the dense mobility
/// Jacobian misses by 38-49 %; free-space layers to the wall vertices are 64-68 % off even with
/// the exact one (`solver/README.md`, "Session 41").
#[derive(Debug, Clone)]
pub struct WallCoupling {
    /// Largest cell vertex displacement of the difference (um).
    pub delta_um: f64,
    x: Vec<Vector3<f64>>,
    v: Vec<Vector3<f64>>,
}

impl WallCoupling {
    /// The displacement of the difference (um): see the type's docs.
    pub const DELTA_UM: f64 = 1e-2;

    /// The coupling with the difference's displacement `delta_um` (um).
    pub fn new(delta_um: f64) -> Self {
        assert!(delta_um > 0.0 && delta_um.is_finite(), "the difference's displacement is > 0");
        Self { delta_um, x: Vec::new(), v: Vec::new() }
    }

    /// `u[n_cell..] += g J_wc u[..n_cell]` at the linearisation point `(t, x)` with velocity
    /// `f_x` (um/s), for a stage whose cell part `u[..n_cell]` (um) is solved and whose walls'
    /// part is the right-hand side still to solve; `g` (s) the walls' `gamma h`. Returns the
    /// velocity evaluations it took (0 for a cell increment of zero).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn add<D: Linearised + ?Sized>(&mut self, f: &mut D, t: f64, x: &[Vector3<f64>], f_x: &[Vector3<f64>], u: &mut [Vector3<f64>], n_cell: usize, g: f64) -> Result<usize, SolverError> {
        let largest = u[..n_cell].iter().map(|v| v.norm()).fold(0.0, f64::max);
        if !(largest > 0.0 && largest.is_finite()) {
            return Ok(0);
        }
        let eps = self.delta_um / largest;
        self.x.clear();
        self.x.extend(x[..n_cell].iter().zip(&u[..n_cell]).map(|(p, d)| p + eps * d));
        self.x.extend_from_slice(&x[n_cell..]);
        self.v.resize(x.len(), Vector3::zeros());
        f.velocity_near_linearisation(t, &self.x, &mut self.v)?;
        for ((w, v), v0) in u[n_cell..].iter_mut().zip(&self.v[n_cell..]).zip(&f_x[n_cell..]) {
            *w += g * (v - v0) / eps;
        }
        Ok(1)
    }
}
