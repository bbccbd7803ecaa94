//! One run of a sweep by index (a Slurm array task), written into its own results file.

use super::{RunExecutor, SweepError};
use rbc_schema::results::{ResultsFile, RunStatus};
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

/// Execute run `index` of `runs` into `out`, unless `out` already holds it finished or failed; a
/// run whose cell overlaps the wall ([`SweepRun::overlaps_wall`]) is recorded as `overlaps-wall` instead.
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
            let overlap_recorded = rec.status == RunStatus::OverlapsWall;
            // a run an earlier build recorded (as failed, or as overlapping under another sweep) is
            // decided again below
            if (run.overlaps_wall.is_some() && overlap_recorded) || (run.overlaps_wall.is_none() && !overlap_recorded && (rec.status.is_finished() || rec.status == RunStatus::Failed)) {
                return Ok(TaskOutcome::AlreadyDone {
                    run_id: run.run_id.clone(),
                    status: rec.status.as_str().into(),
                });
            }
        }
    }
    if run.overlaps_wall.is_some() {
        super::record_overlap(sweep, run, &mut ResultsFile::create_or_open(out)?)?;
        return Ok(TaskOutcome::Ran { run_id: run.run_id.clone(), status: RunStatus::OverlapsWall.as_str().into() });
    }
    if out.exists() && ResultsFile::open(out)?.run(&run.run_id).is_ok_and(|r| r.status == RunStatus::OverlapsWall) {
        ResultsFile::create_or_open(out)?.remove_run(&run.run_id)?;
    }
    exec.execute(sweep, run, out)?;
    let status = ResultsFile::open(out)?.run(&run.run_id)?.status;
    Ok(TaskOutcome::Ran {
        run_id: run.run_id.clone(),
        status: status.as_str().into(),
    })
}
