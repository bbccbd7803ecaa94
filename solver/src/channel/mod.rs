//! Stokes flow in the paper's periodic microchannel: wall mesh, duct reference solutions, the dense periodic wall operator and the channel solve with a cell.
//!
//! See [`stokes::ChannelStokes`] for the equations, the driving by a prescribed mean flow and
//! the wall models (exact no-slip, penalty springs).

pub mod bench;
pub mod duct;
pub mod mesh;
pub mod stokes;
pub mod wall;

pub use mesh::{ChannelGeometry, ChannelMesh};
pub use stokes::{ChannelOptions, ChannelStats, ChannelStokes, WallMode};

use crate::bim::BimError;
use crate::ewald::EwaldError;

/// Why a channel solve could not be set up or failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ChannelError {
    #[error("invalid channel parameter {name} = {value}: {reason}")]
    InvalidParameter { name: &'static str, value: f64, reason: &'static str },
    #[error("Ewald sum: {0}")]
    Ewald(#[from] EwaldError),
    #[error("cell mesh: {0}")]
    Cell(#[from] BimError),
    #[error("{what} has {got} entries, expected {expected}")]
    LengthMismatch { what: &'static str, expected: usize, got: usize },
    #[error("cell vertex {vertex} at (y, z) = ({y:.3}, {z:.3}) um is outside the channel or closer than {min_gap_um} um to the wall")]
    CellOutsideChannel { vertex: usize, y: f64, z: f64, min_gap_um: f64 },
    #[error("non-finite {what} at index {index}")]
    NonFinite { what: &'static str, index: usize },
    #[error("the wall operator ({n} x {n}) has a non-finite or zero pivot: the wall mesh is degenerate")]
    SingularWallOperator { n: usize },
    #[error("viscosity ratio lambda = {lambda}: the channel solve supports lambda = 1 only (the periodic double layer with walls is not implemented)")]
    UnsupportedViscosityRatio { lambda: f64 },
}
