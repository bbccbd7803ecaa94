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
//! The W-method uses `J = [[J_cc, 0], [0, J_ww]]`. `J_ww` is stiff (rates up to 1.4e5 /s at the
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
//! at `s = 1.5` against 5e-9 ... 8e-11 at `s = 1`). So [`WallStage::set_g`] refactorises the walls'
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
//! Session 33: so the cell's own factor may serve up to 3 of those steps while the cell is quiet
//! ([`super::ros34pw2::Reuse::PENALTY_WALLS`]), and PI step control damps the walls' error norm,
//! which swings as the pattern passes the wall vertices (`rbc_schema::scene::StepController`).

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
        assert!(j_ww.nrows() == j_ww.ncols() && j_ww.nrows() % 3 == 0, "J_ww is 3m x 3m");
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
