//! The Stokes operator a cell sees: vertex velocities of a membrane for the force density it exerts on the fluid.
//!
//! Implemented by the free-space solve with its background flow ([`crate::scene::FreeSpace`],
//! on [`super::FreeSpaceStokes`]) and by the periodic channel
//! ([`crate::channel::ChannelStokes`]); the right-hand sides of [`crate::dynamics`] take any of them.

use crate::error::SolverError;
use crate::mesh::Mesh;
use crate::state::StateMap;
use crate::viscosity::ViscosityContrast;
use nalgebra::Vector3;

/// A Stokes solve for a membrane: velocities (um/s) at the vertices of `mesh`
/// for the traction jump `f` (Pa, the force per area the membrane exerts on the fluid).
pub trait Stokes {
    /// `u = u_inf + M(mesh)[f]` when `with_background`, else `M(mesh)[f]`.
    /// `guess` may start an iterative solve (e.g. the last velocity).
    fn velocity(&self, mesh: &Mesh, f: &[Vector3<f64>], with_background: bool, guess: Option<&[Vector3<f64>]>) -> Result<Vec<Vector3<f64>>, SolverError>;
    /// Outer viscosity (Pa s) and the viscosity contrast, if this operator has them: the
    /// operator's own values, which set the stiff-mode preconditioner's mobilities
    /// ([`crate::integrate::precondition::self_mobility`], [`crate::integrate::mobility_jacobian`]).
    fn viscosities(&self) -> Option<(f64, ViscosityContrast)> {
        None
    }
    /// State an operator keeps between solves (e.g. the path of earlier solves that extrapolates
    /// the next GMRES guess), saved under keys starting with `prefix` so that a resumed run
    /// continues bit for bit. Stateless operators keep the default (nothing).
    fn save_state(&self, _prefix: &str, _out: &mut StateMap) {}
    /// Restore what [`Stokes::save_state`] saved (missing keys: no state).
    fn restore_state(&self, _prefix: &str, _state: &StateMap) -> Result<(), SolverError> {
        Ok(())
    }
}
