//! Typed errors of the solver: each variant carries the context needed for a diagnosis.

/// A failure of the solver, with the evidence for a diagnosis.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    #[error("invalid scene: {0}")]
    Scene(String),
}
