//! Settings of the periodic-channel Stokes solve ([`super::ChannelStokes`]): the wall model, the numerical options and how the Ewald sums inside GMRES are split.

use crate::bim::near_field::NearFieldOptions;
use crate::ewald::lanes32::BlockPrecision;

/// Wall model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WallMode {
    /// Exact no-slip (first-kind equation for the wall traction, dense LU).
    NoSlip,
    /// Penalty springs of stiffness `kappa_w` (N/m^3; the paper: 1.9e7).
    Penalty { kappa_w_n_per_m3: f64 },
}

/// Numerical options.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelOptions {
    /// Relative error of the Ewald sums (the paper: 5e-5).
    pub ewald_tol: f64,
    /// Wall mesh edge length (um): 1.38 gives 30 x 36 points, 2160 triangles (the paper: 2166).
    pub wall_edge_um: f64,
    /// Fluid gap (um) between the channel wall and the periodic box in y and z, on each side.
    pub box_gap_um: f64,
    /// Duffy rule (radial, angular points), as [`crate::bim::BimOptions::duffy_nodes`].
    pub duffy_nodes: (usize, usize),
    /// Remove the normal part of the cell's single-layer singularity.
    pub subtract_normal_singularity: bool,
    /// Adaptive quadrature of the cell's non-touching triangles close to a cell vertex, as
    /// [`crate::bim::BimOptions::near_field`] (folding cells whose dimples come within an edge).
    pub near_field: NearFieldOptions,
    /// Grid spacing (um) of the finite-difference flux of the rounded duct (calibration of the driving).
    pub flux_grid_um: f64,
    /// Smallest distance (um) of a cell vertex from the wall accepted by a solve.
    pub min_wall_gap_um: f64,
    /// Expected cell quadrature nodes (for the Ewald cost model): 7 x 2048 triangles.
    pub cell_nodes_hint: usize,
    /// Expected membrane area (um^2) of the cell, for the Ewald cost model (real-space pairs of
    /// the clustered membrane nodes): 135, the paper's red blood cell.
    pub cell_area_hint_um2: f64,
    /// Midpoint subdivisions of the wall triangles (`4^level` sub-triangles with the 7-point rule
    /// each) when the wall single layer is evaluated off the wall (at the cell, at sample
    /// points): 1 keeps the quadrature error small down to ~h/2 from the wall.
    pub wall_eval_refine: usize,
    /// Midpoint subdivisions of the regular quadrature inside the dense wall operator.
    pub wall_matrix_refine: usize,
    /// Viscosity contrast (lambda != 1): GMRES stops at `|b - L u| <= tol |b|` (the paper: 1e-5).
    pub gmres_tolerance: f64,
    /// Krylov dimension between restarts and total iterations before
    /// [`super::ChannelError::GmresDiverged`].
    pub gmres_restart: usize,
    pub gmres_max_iterations: usize,
    /// Wielandt deflation of the rigid-body eigenvalue (see [`super::double_layer`]): without it
    /// the iterations grow with lambda.
    pub deflate_rigid_body: bool,
    /// Viscosity contrast: how the Ewald sums inside GMRES (the cell's double layer, the wall's
    /// answer at the cell) are done ([`IterationSums`]).
    pub iteration_sums: IterationSums,
    /// Viscosity contrast, [`crate::bim::Stokes`] interface: start GMRES from the velocity
    /// predicted from the path of the last [`super::secant_guess::HISTORY`] solves (their secant
    /// relations, [`super::secant_guess::predict`]) instead of the last velocity. Only the starting point
    /// changes (the stopping rule is relative to the right-hand side); the path is saved in
    /// checkpoints ([`crate::bim::Stokes::save_state`]), so a resumed run repeats the uninterrupted
    /// one bit for bit. On by default (measured: 0.85 of the GMRES iterations of a late-run window,
    /// see the module docs).
    pub extrapolate_guess: bool,
    /// Viscosity contrast, frozen sums: the precision of the kernels of the cell's stresslet
    /// blocks, rebuilt for every solve ([`BlockPrecision`]; single: two triangles per 16-lane
    /// register where the CPU has AVX-512, each kernel value within a few 1e-7 of the double one).
    pub block_precision: BlockPrecision,
    /// Viscosity contrast: right-precondition GMRES with the second-kind equation on the cell's
    /// own mesh at this coarser subdivision level ([`crate::bim::two_grid::TwoGrid`], rebuilt for every solve; a cell
    /// that is no octahedron subdivision, or not finer, goes without). Only the iterations change:
    /// the velocity meets the same tolerance. Default level 2 (128 triangles, ~3 ms a build):
    /// measured on the paper's 2048-triangle cell at lambda = 5 in the channel, 0.83 of the GMRES
    /// iterations late in a run and 0.66 from rest (`solver/README.md`, session 19); level 3 saves
    /// more iterations but its build (~25 ms) eats the gain.
    pub two_grid_level: Option<usize>,
}

impl Default for ChannelOptions {
    fn default() -> Self {
        Self {
            ewald_tol: 5e-5,
            wall_edge_um: 1.38,
            box_gap_um: 2.0,
            duffy_nodes: (1, 10),
            subtract_normal_singularity: true,
            near_field: NearFieldOptions::default(),
            flux_grid_um: 0.05,
            min_wall_gap_um: 0.1,
            cell_nodes_hint: 7 * 2048,
            cell_area_hint_um2: 135.0,
            wall_eval_refine: 1,
            wall_matrix_refine: 1,
            gmres_tolerance: 1e-5,
            gmres_restart: 40,
            gmres_max_iterations: 300,
            deflate_rigid_body: true,
            iteration_sums: IterationSums::Model,
            extrapolate_guess: true,
            block_precision: BlockPrecision::Single,
            two_grid_level: Some(2),
        }
    }
}

/// The Ewald sums inside GMRES (viscosity contrast): with their own splitting, their real-space
/// parts built once per solve as block-sparse matrices and the wall's spreading precomputed
/// ([`crate::ewald::blocks`]), or plainly with the parameters of the other sums.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum IterationSums {
    /// Every application is a full Ewald sum (the parameters of the other sums).
    Plain,
    /// Frozen real-space blocks, the cutoff from the cost model [`crate::ewald::params::sums_cost`]
    /// with a real-space pair costing ~8 ns per application (a ~40 ns build shared by ~6
    /// applications of a warm-started solve, plus the mat-vec) instead of ~25 ns.
    Model,
    /// Frozen real-space blocks with this real-space cutoff (um); `xi = s_r / r_cut` at the same tolerance.
    Cutoff(f64),
}
