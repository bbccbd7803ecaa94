//! Typed errors of the solver: each variant carries the context needed for a diagnosis.

use crate::integrate::IntegrateError;

/// A failure of the solver, with the evidence for a diagnosis.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    /// Time integration stopped (blow-up, inverted triangle, area change, step collapse...).
    #[error(transparent)]
    Integrate(#[from] IntegrateError),
    /// A scene file failed validation (names the file and field).
    #[error(transparent)]
    Scene(#[from] rbc_schema::SchemaError),
    /// The scene is valid but asks for something this build cannot assemble yet.
    #[error("scene field `{field}`: {message}")]
    Unsupported { field: String, message: String },
    /// A velocity evaluation failed inside a step.
    #[error("at t = {t_s:.6e} s, step {step}: {source}")]
    AtStep { t_s: f64, step: usize, source: Box<SolverError> },
    /// Writing output failed.
    #[error("output: {0}")]
    Output(String),
}
