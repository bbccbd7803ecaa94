//! Time integrators of the kinematic condition `dx_i/dt = u_i(x)` for the membrane vertices.
//!
//! Each scheme implements [`Integrator`] and is only its update formula plus an
//! embedded error estimate; step-size control, failure detection, volume
//! correction, output and timing live once in [`crate::run`].
//!
//! - [`bs23::BogackiShampine`]: explicit adaptive Bogacki-Shampine 3(2)
//!   (Bogacki & Shampine, Appl. Math. Lett. 2, 321 (1989)), the paper's scheme.
//! - [`rosenbrock::Ros2`]: the linearly implicit two-stage Rosenbrock-W method
//!   ROS2 (Verwer, Spee, Blom & Hundsdorfer, SIAM J. Sci. Comput. 20, 1456 (1999)),
//!   second order for *any* approximation of the Jacobian; with the membrane
//!   force linearised and the mobility lagged (cf. Veerapaneni et al., J. Comput.
//!   Phys. 228, 2334 (2009)) it is implicit in the stiff membrane modes.
//! - [`ros34pw2::Ros34pw2`]: the 4-stage Rosenbrock-W method ROS34PW2 (Rang & Angermann,
//!   BIT 45, 761 (2005)), third order for any `J` with a second-order embedded estimate;
//!   stage solves preconditioned (or `J` replaced) by the local sparse Jacobian of
//!   [`precondition`].
//! - [`check`]: failure detection on a proposed state; [`precondition`]: the local sparse
//!   Jacobian that preconditions (or replaces) the stage solves; [`mobility_jacobian`]: the
//!   dense stiff-mode Jacobian of the `ros34pw2-mobility` W-method. The implicit stages are solved
//!   matrix-free by the solver's one GMRES, [`crate::gmres`].
//!
//! The right-hand sides the schemes advance (a cell through a Stokes solve, a cell with
//! penalty walls, the volume and kinematic projections) implement [`Dynamics`] and
//! [`Linearised`] in [`crate::dynamics`]; this module imports neither the operators nor the runner.

pub mod bs23;
pub mod check;
pub mod error;
pub mod mobility_jacobian;
pub mod wall_block;
pub mod precondition;
pub mod ros34pw2;
pub mod w_tableaux;
pub mod rosenbrock;

pub use error::IntegrateError;
/// The checkpoint state of the schemes (defined in [`crate::state`]).
pub use crate::state::{flatten, state_vectors, unflatten, StateMap};

use crate::error::SolverError;
use nalgebra::Vector3;

/// The right-hand side of the kinematic condition: vertex velocities (um/s) at time `t_s` (s)
/// for vertex positions `x` (um).
pub trait Dynamics {
    /// Write `u(t, x)` into `u` (same length as `x`).
    fn velocity(&mut self, t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError>;
    /// Save whatever later velocities depend on besides `(t, x)` (e.g. the initial guess of
    /// an iterative Stokes solve) under keys starting with `prefix`, so that a run resumed from a
    /// checkpoint continues bit-for-bit. Stateless dynamics keep the default (nothing).
    fn save_state(&self, _prefix: &str, _out: &mut StateMap) {}
    /// Restore what [`Dynamics::save_state`] saved (missing keys leave the state as it is).
    fn restore_state(&mut self, _prefix: &str, _state: &StateMap) -> Result<(), SolverError> {
        Ok(())
    }
}

/// A [`Dynamics`] that can apply an approximation `J` of its Jacobian `du/dx` (1/s) to a
/// displacement `w` (um), as needed by linearly implicit schemes.
///
/// For the membrane: `J w = M(x_n) [dF/dx(x_n) w]`, the force density linearised
/// at the start of the step and the Stokes mobility `M` lagged. The approximation
/// only has to capture the stiff modes: [`rosenbrock::Ros2`] is second order for any `J`.
pub trait Linearised: Dynamics {
    /// Fix the linearisation point `(t_s, x)` for the following [`Linearised::jacobian_apply`] calls.
    fn linearise(&mut self, t_s: f64, x: &[Vector3<f64>]) -> Result<(), SolverError>;
    /// Write `J w` (um/s) into `out`.
    fn jacobian_apply(&mut self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), SolverError>;
    /// A sparse local approximation `J_loc` of `J` at the linearisation point
    /// ([`precondition::LocalJacobian`]: membrane stiffness times self-mobility), if this
    /// dynamics can assemble one; it preconditions the stage solves or replaces `J`.
    fn local_jacobian(&mut self) -> Result<Option<&precondition::LocalJacobian>, SolverError> {
        Ok(None)
    }
    /// The dense stiff-mode Jacobian `J_mob` at the linearisation point
    /// ([`mobility_jacobian::MobilityJacobian`]: the free-space two-fluid mobility of every vertex
    /// pair times the membrane stiffness), if this dynamics can assemble one; the `J` of the
    /// `ros34pw2-mobility` W-method.
    fn mobility_jacobian(&mut self) -> Result<Option<mobility_jacobian::MobilityJacobian>, SolverError> {
        Ok(None)
    }
    /// The velocity (um/s) at `x`, a state close to the linearisation point, for a difference
    /// against the velocity there ([`wall_block::WallCoupling`]): as [`Dynamics::velocity`], but
    /// an iterative solve starts from the linearisation point's solution, so that the two
    /// solves' errors largely cancel in the difference, and the next ordinary evaluation starts
    /// where it would have without this one.
    fn velocity_near_linearisation(&mut self, t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        self.velocity(t_s, x, u)
    }
}

/// Work done by one attempted step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepWork {
    /// Evaluations of [`Dynamics::velocity`].
    pub velocity_evals: usize,
    /// Applications of the Jacobian (inner iterations of implicit stages).
    pub jacobian_applies: usize,
}

/// Context of the step being attempted, for error messages and tolerances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepContext {
    /// Accepted steps so far.
    pub step: usize,
    /// Absolute tolerance on the local error of a vertex position (um).
    pub atol_um: f64,
}

/// One time-stepping scheme: its update formula and embedded error estimate.
pub trait Integrator<D: ?Sized> {
    /// Short name used in logs and tables (`bs23`, `ros2`).
    fn name(&self) -> &'static str;
    /// Order `q` of the lower-order (embedded) solution: the local error estimate
    /// scales as `h^(q+1)`, which sets the exponent `1/(q+1)` of the step-size controller.
    fn embedded_order(&self) -> u32;
    /// Advance `(t_s, x)` by `h_s`: write the new positions into `x_new` and the
    /// local error estimate (um, per vertex) into `err`. (The outputs are caller-owned
    /// buffers so that the runner never allocates per step.)
    #[allow(clippy::too_many_arguments)]
    fn attempt(
        &mut self,
        dynamics: &mut D,
        t_s: f64,
        x: &[Vector3<f64>],
        h_s: f64,
        ctx: StepContext,
        x_new: &mut [Vector3<f64>],
        err: &mut [Vector3<f64>],
    ) -> Result<StepWork, SolverError>;
    /// The last attempt was accepted: `x_new` is now the state (schemes may keep stages, e.g. first-same-as-last).
    fn accepted(&mut self) {}
    /// Whether the runner may step across output times and interpolate the samples there
    /// (cubic Hermite from the states and velocities at both ends of the step, [`crate::run`]);
    /// such a scheme implements [`Integrator::end_velocity`]. Otherwise every output time ends a step.
    fn dense_output(&self) -> bool {
        false
    }
    /// The velocity (um/s) at `(t_s, x)`, the state the next step starts from, and how many velocity
    /// evaluations it took (0 when the scheme had it): a dense-output scheme keeps it as the first
    /// stage of its next step, so the interpolation costs nothing. `None` without dense output.
    fn end_velocity(&mut self, _dynamics: &mut D, _t_s: f64, _x: &[Vector3<f64>]) -> Result<Option<(Vec<Vector3<f64>>, usize)>, SolverError> {
        Ok(None)
    }
    /// The state was changed outside the scheme (volume rescaling): drop cached stages.
    fn invalidate(&mut self) {}
    /// Save the stages the next step reuses (e.g. the first-same-as-last derivative) under keys
    /// starting with `prefix`, for checkpoints ([`crate::run::checkpoint`]); called after an
    /// accepted step. A scheme that keeps stages across steps must implement it (and
    /// [`Integrator::restore_state`]) or a resumed run is no longer bit-for-bit the uninterrupted one.
    fn save_state(&self, _prefix: &str, _out: &mut StateMap) {}
    /// Restore what [`Integrator::save_state`] saved.
    fn restore_state(&mut self, _prefix: &str, _state: &StateMap) -> Result<(), SolverError> {
        Ok(())
    }
}

/// `y = x + h sum_j c_j k_j` over vertex slices.
pub(crate) fn axpy_stages(y: &mut [Vector3<f64>], x: &[Vector3<f64>], h: f64, terms: &[(f64, &[Vector3<f64>])]) {
    for (i, yi) in y.iter_mut().enumerate() {
        let mut s = Vector3::zeros();
        for (c, k) in terms {
            s += *c * k[i];
        }
        *yi = x[i] + h * s;
    }
}
