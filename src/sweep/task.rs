//! One run of a sweep by index (a Slurm array task), written into its own results file.

use super::{RunExecutor, SweepError};
use rbc_schema::results::ResultsFile;
use rbc_schema::sweep::{Sweep, SweepRun};
use std::path::Path;

/// What [`run_task`] did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TaskOutcome {
    /// The file already held the run finished (or failed): nothing done.
    AlreadyDone { run_id: String, status: String },
    /// The run was executed; its final status.
    Ran { run_id: String, status: String },
}

/// Execute run `index` of `runs` into `out`, unless `out` already holds it finished or failed.
pub fn run_task(
    sweep: &Sweep,
    runs: &[SweepRun],
    index: usize,
    out: &Path,
    exec: &dyn RunExecutor,
) -> Result<TaskOutcome, SweepError> {
    let run = runs.get(index).ok_or(SweepError::TaskIndex {
        index,
        len: runs.len(),
    })?;
    if out.exists() {
        let f = ResultsFile::open(out)?;
        if f.has_run(&run.run_id) {
            let rec = f.run(&run.run_id)?;
            if rec.status.is_finished() || rec.status == rbc_schema::results::RunStatus::Failed {
                return Ok(TaskOutcome::AlreadyDone {
                    run_id: run.run_id.clone(),
                    status: rec.status.as_str().into(),
                });
            }
        }
    }
    exec.execute(sweep, run, out)?;
    let status = ResultsFile::open(out)?.run(&run.run_id)?.status;
    Ok(TaskOutcome::Ran {
        run_id: run.run_id.clone(),
        status: status.as_str().into(),
    })
}
