//! Typed errors of the analysis library: each names the file (and frame, field or row).

use rbc_schema::unstage::Unstage;
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

impl Unstage for AnalysisError {
    fn unstaged(self, from: &std::path::Path, to: &std::path::Path) -> Self {
        use rbc_schema::unstage::{rebased, renamed_in};
        match self {
            AnalysisError::Schema(e) => AnalysisError::Schema(e.unstaged(from, to)),
            AnalysisError::Input { path, message } => AnalysisError::Input { path: rebased(&path, from, to), message: renamed_in(&message, from, to) },
            AnalysisError::Plot { path, message } => AnalysisError::Plot { path: rebased(&path, from, to), message: renamed_in(&message, from, to) },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// Each kind of analysis error names the output folder where it named the staging folder.
    #[test]
    fn every_kind_names_the_output_not_the_staging_folder() {
        let (staging, out) = (Path::new("/r/.out.staging-7"), Path::new("/r/out"));
        let input = AnalysisError::Input { path: staging.join("f.png"), message: format!("see {}", staging.join("g").display()) };
        assert_eq!(input.unstaged(staging, out).to_string(), "/r/out/f.png: see /r/out/g");
        let plot = AnalysisError::Plot { path: staging.join("figures"), message: "no room".into() };
        assert_eq!(plot.unstaged(staging, out).to_string(), "/r/out/figures: figure: no room");
        let schema = AnalysisError::Schema(rbc_schema::SchemaError::Csv { path: staging.join("t.csv"), message: "short".into() });
        assert_eq!(schema.unstaged(staging, out).to_string(), "/r/out/t.csv: short");
    }
}
