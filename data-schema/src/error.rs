//! Typed errors of the schema crate: each names the file and the offending field, row or column.

use crate::unstage::{rebased, renamed_in, Unstage};
use std::path::PathBuf;

/// An error reading or writing one of rbc-toolkit's files.
///
/// Display is a single line that names the file (and field, row or column),
/// suitable as the one-line message of a command-line tool.
#[derive(Debug, thiserror::Error)]
pub enum SchemaError {
    /// (The I/O error is part of the one line, not a separate source, so that a binary's
    /// `{:#}` does not print it twice.)
    #[error("{path}: {cause}")]
    Io { path: PathBuf, cause: std::io::Error },
    #[error("{path}: invalid TOML: {message}")]
    Toml { path: PathBuf, message: String },
    #[error("{path}: field `{field}`: {message}")]
    Field { path: PathBuf, field: String, message: String },
    #[error("{path}: missing column `{column}`")]
    MissingColumn { path: PathBuf, column: String },
    #[error("{path}: row {row}, column `{column}`: {message}")]
    Cell { path: PathBuf, row: usize, column: String, message: String },
    #[error("{path}: {message}")]
    Csv { path: PathBuf, message: String },
    #[error("{path}: HDF5: {message}")]
    Hdf5 { path: PathBuf, message: String },
    #[error("{path}: schema_version {found} is not supported (this build reads {supported})")]
    SchemaVersion { path: PathBuf, found: String, supported: String },
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
    /// A file of ours whose integrity check failed (e.g. a checkpoint's checksum): it was changed or
    /// damaged after it was written, and none of it was parsed.
    #[error("{path}: {what} damaged ({message})")]
    Damaged { path: PathBuf, what: &'static str, message: String },
}

impl SchemaError {
    /// Error for a field of a configuration file that is missing or out of range.
    pub fn field(path: impl Into<PathBuf>, field: impl Into<String>, message: impl Into<String>) -> Self {
        SchemaError::Field { path: path.into(), field: field.into(), message: message.into() }
    }

    /// I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        SchemaError::Io { path: path.into(), cause: source }
    }
}

/// The same error naming `to` wherever it named `from` or a path under it: a temporary file's or
/// a staging folder's error reported as its target's, the file or folder the user asked for
/// (`atomic::write_via`, `output_set::write_set`).
impl Unstage for SchemaError {
    fn unstaged(mut self, from: &std::path::Path, to: &std::path::Path) -> Self {
        use SchemaError::*;
        let (path, text) = match &mut self {
            Io { path, .. } | SchemaVersion { path, .. } | MissingColumn { path, .. } => (path, None),
            Toml { path, message } | Csv { path, message } | Hdf5 { path, message } | Invalid { path, message } | Damaged { path, message, .. } | Field { path, message, .. } | Cell { path, message, .. } => (path, Some(message)),
        };
        *path = rebased(path, from, to);
        if let Some(m) = text {
            *m = renamed_in(m, from, to);
        }
        self
    }
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, SchemaError>;
