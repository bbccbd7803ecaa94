//! Stokes flow in the paper's periodic microchannel: wall mesh, duct reference solutions, the dense periodic wall operator and the channel solve with a cell.
//!
//! See [`stokes::ChannelStokes`] for the equations, the driving by a prescribed mean flow and
//! the wall models (exact no-slip, penalty springs); [`options`] holds its settings and
//! [`stats`] what a solve returns and did.
//!
//! Choices (documented where they are made): corner radius 1.5 um ([`mesh::ChannelGeometry`]),
//! wall edge 1.38 um = 2160 wall triangles (the paper: 2166), a 2 um fluid gap between the wall
//! and the periodic box in y and z ([`options::ChannelOptions::box_gap_um`]). Viscosity ratio
//! `lambda != 1`: the periodic double layer of the cell ([`double_layer`]) coupled to the wall
//! solve, deflated GMRES; `lambda = 1` builds no double layer.
//!
//! Measured (tests `channel_duct`, `channel_cell`; `rbc-bench periodic`, accuracy by [`duct::duct_profile_error`]):
//! the empty channel reproduces the rounded-corner duct flow within 1.3 %, 0.62 %, 0.39 %, 0.28 %
//! of the centre velocity (interior points >= 2 um from the walls) at wall edges 2.0, 1.38, 1.1,
//! 0.9 um (about second order); the dense wall operator of 2160 triangles (3240 unknowns, 84 MB)
//! assembles in ~2 s (180 Ewald sums thanks to the translation symmetry) and factorises in ~2 s;
//! a velocity solve with a 2048-triangle cell costs three Ewald sums and one LU back-substitution,
//! ~1-2 s on this 2-core machine at tolerance 1e-6.
//! With viscosity contrast (pushed discocyte, GMRES 1e-5, load ~6-8 on 2 cores): 9 iterations at
//! lambda = 5 and 14-15 at lambda = 20 for 128, 512 and 2048 triangles from a zero start. Before
//! the frozen GMRES sums (see [`stokes`], "Cost"), one lambda = 5 solve took 4.9 s (512 triangles)
//! and 6.2 s (2048), two Ewald sums per iteration > 93 % of the time. Now, in the paper's coarse
//! scene (2 um wall edges, Ewald 1e-4, one thread, CPU time): one cold lambda = 5 solve 0.22 s
//! (was 1.03-1.10 s), and a bs23 run 31-32.5 core-s per simulated ms (was 134-145; `rbc-bench channel`).
//! One lambda = 1 solve (`rbc-bench channel-cost`, 1.38 um wall edges, Ewald 5e-5): Ewald parts
//! 0.050 / 0.231 / 1.28 CPU s at 512 / 2048 / 8192 triangles (were 0.221 / 0.426 / ~1.4), i.e.
//! 1.09 / 1.08 / 1.31 us per `N log2 N` with `N` the cell's nodes plus vertices: `N log N` up to
//! 2048 triangles, then the `~N^1.2` of a uniform grid balanced against the real-space pairs of a
//! surface cluster (`~N^2 r^2`).

pub mod cell_layer;
pub mod double_layer;
pub mod duct;
pub mod mesh;
pub mod options;
pub mod periodic_box;
pub mod secant_guess;
pub mod stats;
pub mod stokes;
pub mod wall;

pub use mesh::{ChannelGeometry, ChannelMesh};
pub use options::{ChannelOptions, IterationSums, WallMode};
pub use stats::{ChannelStats, SolveTimes};
pub use stokes::ChannelStokes;

use crate::bim::BimError;
use crate::ewald::EwaldError;

/// Why a channel solve could not be set up or failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ChannelError {
    #[error("invalid channel parameter {name} = {value}: {reason}")]
    InvalidParameter {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    #[error("Ewald sum: {0}")]
    Ewald(EwaldError),
    #[error("cell mesh: {0}")]
    Cell(BimError),
    #[error("{what} has {got} entries, expected {expected}")]
    LengthMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("cell vertex {vertex} at (y, z) = ({y:.3}, {z:.3}) um is outside the channel or closer than {min_gap_um} um to the wall")]
    CellOutsideChannel {
        vertex: usize,
        y: f64,
        z: f64,
        min_gap_um: f64,
    },
    #[error("non-finite {what} at index {index}")]
    NonFinite { what: &'static str, index: usize },
    #[error(
        "the wall operator ({n} x {n}) has a non-finite or zero pivot: the wall mesh is degenerate"
    )]
    SingularWallOperator { n: usize },
    #[error("viscosity ratio {lambda}: GMRES did not reach the relative residual {tolerance:e} after {iterations} iterations (residual {residual:e})")]
    GmresDiverged {
        lambda: f64,
        iterations: usize,
        residual: f64,
        tolerance: f64,
    },
    #[error("viscosity ratio {lambda}: GMRES produced a non-finite value at iteration {iteration}")]
    GmresNonFinite { lambda: f64, iteration: usize },
}

/// The inner error's line is part of the variant's own, so it is not handed on as a source too
/// (see `crate::error`).
impl From<EwaldError> for ChannelError {
    fn from(e: EwaldError) -> Self {
        ChannelError::Ewald(e)
    }
}

impl From<BimError> for ChannelError {
    fn from(e: BimError) -> Self {
        ChannelError::Cell(e)
    }
}
