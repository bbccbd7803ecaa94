//! Copy one run between results files: [`rbc_schema::results::copy_run`] with the sweep's error type.

use super::SweepError;
use rbc_schema::results::{ResultsFile, RunStatus};

/// Copy run `run_id` of `src` into `dst`, replacing a run of that id in `dst`.
/// Returns the copied run's status.
pub fn copy_run(src: &ResultsFile, run_id: &str, dst: &mut ResultsFile) -> Result<RunStatus, SweepError> {
    Ok(rbc_schema::results::copy_run(src, run_id, dst)?)
}
