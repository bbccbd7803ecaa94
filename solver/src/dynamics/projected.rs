//! A dynamics wrapper that applies a fixed velocity projection to every velocity and Jacobian product.
//!
//! Used for the no-flux correction of the volume drift ([`super::volume::remove_flux`])
//! and for normal-only kinematics of drops ([`super::kinematics::project_normal`]):
//! both project the velocity with the unit volume gradient of the current surface,
//! and the Jacobian of a [`Linearised`] inner dynamics is projected the same way,
//! with the projection frozen at the linearisation point.

use crate::integrate::{Dynamics, Linearised};
use crate::state::StateMap;
use crate::error::SolverError;
use nalgebra::Vector3;

/// A projection of vertex velocities `u` (um/s) on the surface `x` (um) with
/// connectivity `triangles`; the last argument is scratch of length `x.len()`.
pub type Projection = fn(&[Vector3<f64>], &[[usize; 3]], &mut [Vector3<f64>], &mut [Vector3<f64>]);

/// Wraps a [`Dynamics`] so that every velocity it returns goes through `project`.
pub struct Projected<'a, D> {
    pub inner: D,
    pub triangles: &'a [[usize; 3]],
    project: Projection,
    g: Vec<Vector3<f64>>,
    x_lin: Vec<Vector3<f64>>,
}

impl<'a, D> Projected<'a, D> {
    /// Wrap `inner`, projecting its velocities with `project` on the surface with connectivity `triangles`.
    pub fn new(inner: D, triangles: &'a [[usize; 3]], project: Projection) -> Self {
        Self { inner, triangles, project, g: Vec::new(), x_lin: Vec::new() }
    }
}

/// `project` of the velocities `u` on the surface `x`, with `g` as its scratch (sized here).
fn project_with(project: Projection, x: &[Vector3<f64>], triangles: &[[usize; 3]], u: &mut [Vector3<f64>], g: &mut Vec<Vector3<f64>>) {
    g.resize(x.len(), Vector3::zeros());
    project(x, triangles, u, g);
}

impl<D: Dynamics> Dynamics for Projected<'_, D> {
    fn velocity(&mut self, t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        self.inner.velocity(t_s, x, u)?;
        project_with(self.project, x, self.triangles, u, &mut self.g);
        Ok(())
    }
    fn save_state(&self, prefix: &str, out: &mut StateMap) {
        self.inner.save_state(prefix, out)
    }
    fn restore_state(&mut self, prefix: &str, state: &StateMap) -> Result<(), SolverError> {
        self.inner.restore_state(prefix, state)
    }
}

impl<D: Linearised> Linearised for Projected<'_, D> {
    fn linearise(&mut self, t_s: f64, x: &[Vector3<f64>]) -> Result<(), SolverError> {
        self.x_lin.clear();
        self.x_lin.extend_from_slice(x);
        self.inner.linearise(t_s, x)
    }
    fn jacobian_apply(&mut self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        self.inner.jacobian_apply(w, out)?;
        project_with(self.project, &self.x_lin, self.triangles, out, &mut self.g);
        Ok(())
    }
    /// The inner local Jacobian, unprojected: the projection removes one uniform normal
    /// mode (rank one), which a preconditioner or a W-method's `J` need not contain.
    fn local_jacobian(&mut self) -> Result<Option<&crate::integrate::precondition::LocalJacobian>, SolverError> {
        self.inner.local_jacobian()
    }
    fn velocity_near_linearisation(&mut self, t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        self.inner.velocity_near_linearisation(t_s, x, u)?;
        project_with(self.project, x, self.triangles, u, &mut self.g);
        Ok(())
    }
    /// The inner dense Jacobian, unprojected (as [`Linearised::local_jacobian`]).
    fn mobility_jacobian(&mut self) -> Result<Option<crate::integrate::mobility_jacobian::MobilityJacobian>, SolverError> {
        self.inner.mobility_jacobian()
    }
}
