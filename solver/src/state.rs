//! The state a part of a run keeps between steps (a scheme's stages, a dynamics' last solve, an operator's solve history), as named arrays saved in a checkpoint.
//!
//! A resumed run continues bit for bit only when every part that carries state across steps
//! saves and restores it ([`crate::run::checkpoint`]); the parts do so through [`StateMap`].

use crate::error::SolverError;
use nalgebra::Vector3;
use std::collections::BTreeMap;

/// Private state of a scheme, a dynamics or an operator saved in a checkpoint ([`crate::run::checkpoint`]):
/// named arrays of `f64` (vectors flattened as x, y, z per vertex; `usize` counters as exact `f64`).
pub type StateMap = BTreeMap<String, Vec<f64>>;

/// Flatten vertex vectors into `[x0, y0, z0, x1, ...]` (checkpoint arrays).
pub fn flatten(v: &[Vector3<f64>]) -> Vec<f64> {
    v.iter().flat_map(|p| [p.x, p.y, p.z]).collect()
}

/// Inverse of [`flatten`]; `None` when the length is not a multiple of 3.
#[allow(clippy::manual_is_multiple_of)] // usize::is_multiple_of needs Rust 1.87; rust-version is 1.85
pub fn unflatten(f: &[f64]) -> Option<Vec<Vector3<f64>>> {
    if f.len() % 3 != 0 {
        return None;
    }
    Some(f.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect())
}

/// The vertex vectors saved under `key` in a checkpoint's state (`None` when absent); a length
/// that is not a multiple of 3 is an error naming the field.
pub fn state_vectors(state: &StateMap, key: &str) -> Result<Option<Vec<Vector3<f64>>>, SolverError> {
    state
        .get(key)
        .map(|f| unflatten(f).ok_or_else(|| SolverError::Output(format!("checkpoint field {key}: length {} is not a multiple of 3", f.len()))))
        .transpose()
}
