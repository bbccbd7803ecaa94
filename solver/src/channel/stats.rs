//! What a periodic-channel Stokes solve returns and did ([`super::ChannelStokes`]): the velocities and wall traction, the solve's statistics and the time a run's solves spent in each part.

use crate::viscosity::ViscosityContrast;
use nalgebra::Vector3;

/// What a solve did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ChannelStats {
    /// `k = 0` mode of the box (um/s) and mean pressure gradient `-dp/dx` (Pa/um).
    pub u0_um_s: f64,
    pub pressure_gradient_pa_per_um: f64,
    /// Net x-force of the wall traction (Pa um^2 = pN).
    pub wall_force_x_pn: f64,
    /// Ewald sums and their wall time (s), wall solves (LU back-substitutions) and total (s).
    pub ewald_sums: usize,
    pub ewald_seconds: f64,
    pub wall_solve_seconds: f64,
    pub total_seconds: f64,
    /// Wall time (s) of the near-singular quadrature of the cell ([`crate::bim::near_field`]).
    pub near_field_seconds: f64,
    /// Viscosity contrast: wall time (s) of building the cell's double layer for the solve (with
    /// the frozen sums: its real-space blocks, which carry the single layer's real-space part, and
    /// its spreading to the grid).
    pub double_layer_build_seconds: f64,
    /// Wall time (s) of the cell's single layer at the cell and wall vertices (with the frozen
    /// sums: its Fourier part and the free-space corrections; the real-space part is in the
    /// double layer's build).
    pub single_layer_seconds: f64,
    /// Viscosity contrast: GMRES iterations, final relative residual and wall time (s,
    /// including the Ewald sums and wall solves of its operator applications); 0 for lambda = 1.
    pub gmres_iterations: usize,
    pub gmres_residual: f64,
    pub gmres_seconds: f64,
    /// The viscosity contrast of the solve.
    pub viscosity_ratio: ViscosityContrast,
}

/// Where the velocity solves of a time integration spent their wall time (s), summed over the
/// solves of the [`crate::bim::Stokes`] interface ([`super::ChannelStokes::solve_times`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveTimes {
    pub solves: usize,
    /// Whole solves.
    pub total_s: f64,
    /// The cell's near-singular quadrature ([`ChannelStats::near_field_seconds`]).
    pub near_field_s: f64,
    /// GMRES with its operator applications ([`ChannelStats::gmres_seconds`]).
    pub gmres_s: f64,
    /// The wall's LU back-substitutions, inside GMRES and out ([`ChannelStats::wall_solve_seconds`]).
    pub wall_solve_s: f64,
    /// The cell's double layer built for each solve ([`ChannelStats::double_layer_build_seconds`]).
    pub double_layer_build_s: f64,
    /// The cell's single layer ([`ChannelStats::single_layer_seconds`]).
    pub single_layer_s: f64,
}

impl SolveTimes {
    /// Count one solve with its statistics.
    pub(super) fn add(&mut self, st: &ChannelStats) {
        self.solves += 1;
        self.total_s += st.total_seconds;
        self.near_field_s += st.near_field_seconds;
        self.gmres_s += st.gmres_seconds;
        self.wall_solve_s += st.wall_solve_seconds;
        self.double_layer_build_s += st.double_layer_build_seconds;
        self.single_layer_s += st.single_layer_seconds;
    }

    /// The solves' time outside the parts above (the right-hand side's wall single layer, the
    /// surface and set-up), s.
    pub fn rest_s(&self) -> f64 {
        self.total_s - self.gmres_s - self.double_layer_build_s - self.single_layer_s - self.near_field_s
    }
}

/// Membrane velocities (um/s) and the wall traction of one solve.
#[derive(Debug, Clone)]
pub struct ChannelSolution {
    pub cell_velocity: Vec<Vector3<f64>>,
    /// Wall traction at the wall vertices (Pa).
    pub wall_traction: Vec<Vector3<f64>>,
    /// Velocity of the wall vertices (um/s): zero up to the collocation for no-slip; the
    /// displacement rate for the penalty walls.
    pub wall_velocity: Vec<Vector3<f64>>,
    pub stats: ChannelStats,
}
