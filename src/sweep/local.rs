//! Run a sweep on this machine: a pool of worker threads, one run each, resumable after a kill.

use super::copy::copy_run;
use super::{RunExecutor, SweepError};
use rbc_schema::results::{ResultsFile, RunStatus};
use rbc_schema::sweep::{Sweep, SweepRun};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

/// Options of a local sweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LocalOptions {
    /// Runs executed at the same time (worker threads).
    pub jobs: usize,
    /// Execute again runs the output holds as failed (default: keep them).
    pub retry_failed: bool,
}

/// What happens to one run of the grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Planned {
    /// The output already holds it with this status.
    Skip(RunStatus),
    /// To be executed (or copied from a finished part file).
    Execute,
}

/// Decide per run from the statuses already in the output: finished runs are
/// skipped, failed ones too unless `retry_failed`, running ones (a kill during
/// the copy) and absent ones are executed.
pub fn plan(
    existing: &BTreeMap<String, RunStatus>,
    runs: &[SweepRun],
    retry_failed: bool,
) -> Vec<Planned> {
    runs.iter()
        .map(|r| match existing.get(&r.run_id) {
            Some(s) if s.is_finished() => Planned::Skip(*s),
            Some(RunStatus::Failed) if !retry_failed => Planned::Skip(RunStatus::Failed),
            _ => Planned::Execute,
        })
        .collect()
}

/// Folder of the per-run part files of output `out`: `.<name>.parts` beside it.
pub fn parts_dir(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "results.h5".into());
    let dir = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .map(Path::to_path_buf)
        .unwrap_or_default();
    dir.join(format!(".{name}.parts"))
}

/// Outcome of a local sweep.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LocalReport {
    /// Runs the output already held (id, status).
    pub skipped: Vec<(String, RunStatus)>,
    /// Runs executed (or copied from a part left by a kill) in this call, with their status.
    pub done: Vec<(String, RunStatus)>,
    /// Runs that could not be executed or copied, with the reason (they are retried next time).
    pub errors: Vec<(String, String)>,
}

/// Execute (in the part file) unless the part already holds the run finished or failed.
fn execute_part(
    sweep: &Sweep,
    run: &SweepRun,
    part: &Path,
    exec: &dyn RunExecutor,
) -> Result<(), SweepError> {
    if part.exists() {
        let done = match ResultsFile::open(part) {
            Ok(f) => {
                f.has_run(&run.run_id)
                    && f.run(&run.run_id)
                        .map(|r| r.status.is_finished() || r.status == RunStatus::Failed)
                        .unwrap_or(false)
            }
            Err(_) => false,
        };
        if done {
            return Ok(());
        }
        // an unreadable part (killed while HDF5 was writing) is started afresh; a readable
        // one with an unfinished run is handed to the executor to resume or replace
        if ResultsFile::open(part).is_err() {
            std::fs::remove_file(part).map_err(|e| SweepError::Io {
                path: part.into(),
                message: e.to_string(),
            })?;
        }
    }
    exec.execute(sweep, run, part)
}

/// Run every planned run of `runs` with `opts.jobs` workers and gather them in `out`.
///
/// `on_done(run_id, outcome)` is called on the calling thread after each run
/// (status written to `out`, or the error). Returns the report; errors of single
/// runs are collected, not returned (the others continue).
pub fn run_local(
    sweep: &Sweep,
    runs: &[SweepRun],
    out: &Path,
    exec: &dyn RunExecutor,
    opts: &LocalOptions,
    on_done: &mut dyn FnMut(&str, &Result<RunStatus, String>),
) -> Result<LocalReport, SweepError> {
    let mut dst =
        ResultsFile::create_or_open_by(out, concat!("rbc-sweep ", env!("CARGO_PKG_VERSION")))?;
    let existing: BTreeMap<String, RunStatus> = dst
        .runs()?
        .into_iter()
        .map(|r| (r.run_id, r.status))
        .collect();
    let planned = plan(&existing, runs, opts.retry_failed);
    let mut report = LocalReport::default();
    let mut todo = Vec::new();
    for (run, p) in runs.iter().zip(&planned) {
        match p {
            Planned::Skip(s) => report.skipped.push((run.run_id.clone(), *s)),
            Planned::Execute => todo.push(run),
        }
    }
    if todo.is_empty() {
        return Ok(report);
    }
    let parts = parts_dir(out);
    std::fs::create_dir_all(&parts).map_err(|e| SweepError::Io {
        path: parts.clone(),
        message: e.to_string(),
    })?;
    let part_of = |r: &SweepRun| parts.join(format!("{}.h5", r.run_id));
    let next = AtomicUsize::new(0);
    let workers = opts.jobs.max(1).min(todo.len());
    std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel::<(usize, Result<(), SweepError>)>();
        for _ in 0..workers {
            let tx = tx.clone();
            let (next, todo, part_of) = (&next, &todo, &part_of);
            s.spawn(move || loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(run) = todo.get(i) else { break };
                let r = execute_part(sweep, run, &part_of(run), exec);
                if tx.send((i, r)).is_err() {
                    break;
                }
            });
        }
        drop(tx);
        for (i, r) in rx {
            let run = todo[i];
            let part = part_of(run);
            let outcome = r.and_then(|()| {
                let src = ResultsFile::open(&part)?;
                let status = copy_run(&src, &run.run_id, &mut dst)?;
                dst.flush()?;
                drop(src);
                std::fs::remove_file(&part).map_err(|e| SweepError::Io {
                    path: part.clone(),
                    message: e.to_string(),
                })?;
                Ok(status)
            });
            let shown = outcome.as_ref().map(|s| *s).map_err(|e| e.to_string());
            on_done(&run.run_id, &shown);
            match shown {
                Ok(s) => report.done.push((run.run_id.clone(), s)),
                Err(e) => report.errors.push((run.run_id.clone(), e)),
            }
        }
    });
    if report.errors.is_empty() {
        let _ = std::fs::remove_dir(&parts); // only when empty
    }
    Ok(report)
}
