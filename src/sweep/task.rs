//! One run of a sweep by index (a Slurm array task), written into its own results file.

use super::{RunExecutor, SweepError};
use rbc_schema::results::{ResultsFile, RunStatus};
use rbc_schema::sweep::{Sweep, SweepRun};
use std::path::Path;

/// The threads of a task's rayon pool: the sweep's `threads_per_run`, unless `rayon_num_threads`
/// (the value of `RAYON_NUM_THREADS`, which a Slurm array task sets from its `cpus-per-task`)
/// says how many (`None`: leave the pool to rayon).
///
/// Without it a task takes rayon's default of one thread per core: on a machine running one
/// task per core, each run then spins and switches between more threads than it has cores
/// (measured in solver/README.md, session 13: 4-5 % more core-s per simulated ms at two threads
/// than at one on two loaded cores, with 2-3x the context switches).
pub fn task_threads(sweep: &Sweep, rayon_num_threads: Option<&std::ffi::OsStr>) -> Option<usize> {
    match rayon_num_threads {
        Some(_) => None,
        None => Some(sweep.threads_per_run.max(1)),
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::OsStr;

    /// The study's sweep (one thread per run) and the same sweep at three: a task's pool takes
    /// `threads_per_run`, and leaves the pool to rayon when `RAYON_NUM_THREADS` is set (Slurm).
    #[test]
    fn a_task_takes_the_sweeps_threads_unless_rayon_num_threads_is_set() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies/science-6p5/sweep.toml");
        let text = std::fs::read_to_string(&path).expect("the study's sweep file");
        let one = Sweep::parse(&text, &path).expect("the study's sweep parses");
        assert_eq!(task_threads(&one, None), Some(1));
        assert_eq!(task_threads(&one, Some(OsStr::new("4"))), None);
        let three = Sweep::parse(&text.replace("threads_per_run = 1", "threads_per_run = 3"), &path).expect("parses");
        assert_eq!(task_threads(&three, None), Some(3));
        assert_eq!(task_threads(&three, Some(OsStr::new("1"))), None);
    }
}
