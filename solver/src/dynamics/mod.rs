//! The right-hand sides the time integrators advance: vertex velocities of a cell from its membrane force through a Stokes operator, and the projections applied to them.
//!
//! Each implements [`crate::integrate::Dynamics`] (and [`crate::integrate::Linearised`] for
//! the implicit schemes) on the state vector of a run; the operators come in through the
//! [`crate::bim::Stokes`] trait (free space, the no-slip channel) or directly
//! ([`crate::channel::ChannelStokes`] with penalty walls).
//!
//! - [`cell::CellDynamics`]: one cell, `u = u_inf + M[f(x)]` (membrane force through a Stokes solve).
//! - [`penalty::PenaltyChannelDynamics`]: one cell in the periodic channel with penalty walls
//!   (state: the cell's vertices followed by the wall displacements).
//! - [`projected::Projected`]: a wrapper applying a velocity projection; [`volume`]: the no-flux
//!   projection and the rescaling that counter the volume drift; [`kinematics`]: normal-only
//!   kinematics (drops).

pub mod cell;
pub mod kinematics;
pub mod penalty;
pub mod projected;
pub mod volume;
