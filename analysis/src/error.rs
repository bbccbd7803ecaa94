//! Typed errors of the analysis library: each names the file (and frame, field or row).

use std::path::PathBuf;

/// A failure of the analysis pipeline that the user can act on.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    #[error(transparent)]
    Schema(#[from] rbc_schema::SchemaError),
    #[error("{path}: {message}")]
    Input { path: PathBuf, message: String },
    #[error("{path}: figure: {message}")]
    Plot { path: PathBuf, message: String },
}
