//! Run a sweep on this machine: a pool of worker threads, one run each, resumable after a kill.
//!
//! Files beside the output `DIR/results.h5`: `DIR/.results.h5.parts/<run_id>.h5` (one per run
//! of the current call; removed once copied and the call ends) and `DIR/.results.h5.bak` (the
//! output as it was when the call started; removed at the end of the call).

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
    /// Not to be run: its cell overlaps the channel wall (`SweepRun::overlaps_wall`); recorded
    /// in the output with status `overlaps-wall`.
    Record,
}

/// Decide per run from the statuses already in the output: a run whose cell overlaps the wall
/// is recorded as such (skipped when the output says so already), finished runs are
/// skipped, failed ones too unless `retry_failed`, running ones (a kill during
/// the copy), absent ones and ones recorded as overlapping by a sweep that has changed since
/// are executed.
pub fn plan(
    existing: &BTreeMap<String, RunStatus>,
    runs: &[SweepRun],
    retry_failed: bool,
) -> Vec<Planned> {
    runs.iter()
        .map(|r| match existing.get(&r.run_id) {
            Some(RunStatus::OverlapsWall) if r.overlaps_wall.is_some() => Planned::Skip(RunStatus::OverlapsWall),
            _ if r.overlaps_wall.is_some() => Planned::Record,
            Some(s) if s.is_finished() => Planned::Skip(*s),
            Some(RunStatus::Failed) if !retry_failed => Planned::Skip(RunStatus::Failed),
            _ => Planned::Execute,
        })
        .collect()
}

/// Whether the scene text `stored` with a run describes the run of the scene text `planned`: the
/// same text, or the same simulation up to the step method and end time
/// ([`rbc_schema::scene::Scene::runs_as`], the test `rbc-simulate --resume` applies).
/// `Err` with the reason when the stored text does not parse (the planned one was parsed when the
/// sweep was expanded).
fn same_run_scene(stored: &str, planned: &str, out: &Path) -> Result<bool, rbc_schema::SchemaError> {
    use rbc_schema::scene::Scene;
    match Scene::parse(planned, out) {
        Ok(now) => now.runs_as(stored),
        Err(_) => Ok(stored == planned),
    }
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

/// Backup of output `out` taken at the start of each local sweep: `.<name>.bak` beside it.
pub fn backup_path(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "results.h5".into());
    let dir = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .map(Path::to_path_buf)
        .unwrap_or_default();
    dir.join(format!(".{name}.bak"))
}

fn io(path: &Path, e: impl std::fmt::Display) -> SweepError {
    SweepError::Io {
        path: path.into(),
        message: e.to_string(),
    }
}

/// Open the output; when it is unreadable (a kill while HDF5 was writing it) and a backup
/// exists, put the damaged file aside (`.<name>.damaged`) and restore the backup. Returns the
/// file and whether it was restored.
fn open_output(out: &Path) -> Result<(ResultsFile, bool), SweepError> {
    let created_by = concat!("rbc-sweep ", env!("CARGO_PKG_VERSION"));
    match ResultsFile::create_or_open_by(out, created_by) {
        Ok(f) => Ok((f, false)),
        Err(e @ rbc_schema::SchemaError::SchemaVersion { .. }) => Err(e.into()),
        Err(e) => {
            let bak = backup_path(out);
            if !bak.exists() {
                return Err(e.into());
            }
            let damaged = bak.with_extension("damaged");
            std::fs::rename(out, &damaged).map_err(|e| io(out, e))?;
            std::fs::copy(&bak, out).map_err(|e| io(out, e))?;
            Ok((ResultsFile::create_or_open_by(out, created_by)?, true))
        }
    }
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
    /// The output was unreadable and was restored from its backup (runs finished since are
    /// copied again from their part files).
    pub restored: bool,
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
    let (mut dst, restored) = open_output(out)?;
    let records = dst.runs()?;
    let existing: BTreeMap<String, RunStatus> = records.iter().map(|r| (r.run_id.clone(), r.status)).collect();
    let planned = plan(&existing, runs, opts.retry_failed);
    // a run kept from an earlier call must be the run the sweep asks for now: one run from another
    // scene (the base scene or the sweep edited since) would be reported as if it were this one
    // (a run recorded as overlapping the wall was never run: its record is not checked)
    for (run, p) in runs.iter().zip(&planned) {
        let stored = records.iter().find(|r| r.run_id == run.run_id).and_then(|r| r.attrs.as_ref()).map(|a| a.scene.as_str());
        if let (Planned::Skip(status), Some(stored)) = (p, stored) {
            if *status == RunStatus::OverlapsWall {
                continue;
            }
            let why = match same_run_scene(stored, &run.scene_text, out) {
                Ok(true) => continue,
                Ok(false) => "was run from another scene than the sweep's now (the base scene or the sweep changed)".to_string(),
                Err(e) => format!("has a stored scene this build does not read ({e})"),
            };
            return Err(SweepError::Io { path: out.to_path_buf(), message: format!("run {} {why}: write to a new --out", run.run_id) });
        }
    }
    let mut report = LocalReport {
        restored,
        ..LocalReport::default()
    };
    let parts = parts_dir(out);
    let part_of = |r: &SweepRun| parts.join(format!("{}.h5", r.run_id));
    let mut todo = Vec::new();
    let mut record = Vec::new();
    for (run, p) in runs.iter().zip(&planned) {
        match p {
            Planned::Record => record.push(run),
            Planned::Skip(s) => {
                report.skipped.push((run.run_id.clone(), *s));
                // a part of a run the output already holds is a leftover of an earlier call
                let part = part_of(run);
                if part.exists() {
                    std::fs::remove_file(&part).map_err(|e| io(&part, e))?;
                }
            }
            Planned::Execute => todo.push(run),
        }
    }
    if todo.is_empty() && record.is_empty() {
        let _ = std::fs::remove_dir(&parts); // only when empty
        return Ok(report);
    }
    // The output is written only by this thread, one complete run at a time. A kill during
    // such a write could leave the HDF5 file unreadable: the backup holds everything finished
    // before this call and the parts of this call's runs are kept until its end, so
    // `open_output` and the parts rebuild the output next time without rerunning anything.
    dst.flush()?;
    let bak = backup_path(out);
    std::fs::copy(out, &bak).map_err(|e| io(&bak, e))?;
    // runs whose cell overlaps the wall: recorded, never executed (a record made again after a
    // kill is the same record)
    for run in record {
        let outcome = super::record_overlap(sweep, run, &mut dst);
        let shown = outcome.as_ref().map(|_| RunStatus::OverlapsWall).map_err(|e| e.to_string());
        on_done(&run.run_id, &shown);
        match shown {
            Ok(s) => report.done.push((run.run_id.clone(), s)),
            Err(e) => report.errors.push((run.run_id.clone(), e)),
        }
    }
    if !todo.is_empty() {
        std::fs::create_dir_all(&parts).map_err(|e| io(&parts, e))?;
    }
    let mut copied = Vec::new();
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
                Ok(status)
            });
            let shown = outcome.as_ref().map(|s| *s).map_err(|e| e.to_string());
            on_done(&run.run_id, &shown);
            match shown {
                Ok(s) => {
                    copied.push(part);
                    report.done.push((run.run_id.clone(), s));
                }
                Err(e) => report.errors.push((run.run_id.clone(), e)),
            }
        }
    });
    // everything copied is in the flushed output, which reads back: the safety copies can go
    dst.flush()?;
    drop(dst);
    ResultsFile::open(out)?;
    for part in &copied {
        std::fs::remove_file(part).map_err(|e| io(part, e))?;
    }
    std::fs::remove_file(&bak).map_err(|e| io(&bak, e))?;
    let _ = std::fs::remove_dir(&parts); // only when empty
    Ok(report)
}
