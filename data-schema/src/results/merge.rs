//! One-call readers of a results file, and runs copied between files.

use super::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Every run of `path` with its attributes; failed and running runs are listed with `summary: None`.
pub fn read_runs(path: &Path) -> Result<Vec<RunRecord>> {
    ResultsFile::open(path)?.runs()
}

/// One run's timeseries.
pub fn read_timeseries(path: &Path, run_id: &str) -> Result<Vec<TimeSample>> {
    ResultsFile::open(path)?.timeseries(run_id)
}

/// One run's snapshots.
pub fn read_snapshots(path: &Path, run_id: &str) -> Result<Snapshots> {
    ResultsFile::open(path)?.snapshots(run_id)
}

/// Merge the runs of `inputs` into a new file `out`, written atomically (a
/// temporary file renamed into place). Refuses a run id that occurs twice,
/// naming both files. Returns the number of runs written.
pub fn merge_files(inputs: &[PathBuf], out: &Path) -> Result<usize> {
    let mut seen: BTreeMap<String, PathBuf> = BTreeMap::new();
    let mut sources = Vec::new();
    for p in inputs {
        if p.as_path() == out {
            return Err(invalid(out, "merge output is also one of its inputs"));
        }
        let f = ResultsFile::open(p)?;
        for id in f.run_ids()? {
            if let Some(first) = seen.insert(id.clone(), p.clone()) {
                return Err(invalid(p, format!("run `{id}` is also in {}", first.display())));
            }
        }
        sources.push(f);
    }
    crate::atomic::write_via(out, |tmp| {
        let mut dst = ResultsFile::create_or_open_by(tmp, concat!("rbc-toolkit ", env!("CARGO_PKG_VERSION"), " merge"))?;
        let mut n = 0;
        for src in &sources {
            for rec in src.runs()? {
                copy_run(src, &rec.run_id, &mut dst)?;
                n += 1;
            }
        }
        dst.flush()?;
        Ok(n)
    })
}

/// Copy run `run_id` of `src` into `dst` (rows, snapshots, transits, and the summary or the
/// failure), replacing a run of that id in `dst`; returns the run's status.
pub fn copy_run(src: &ResultsFile, run_id: &str, dst: &mut ResultsFile) -> Result<RunStatus> {
    let rec = src.run(run_id)?;
    let attrs = rec
        .attrs
        .clone()
        .ok_or_else(|| invalid(src.path(), format!("run `{}` has no start attributes (interrupted while created)", rec.run_id)))?;
    if rec.status == RunStatus::OverlapsWall {
        dst.record_overlaps_wall(run_id, &attrs, rec.not_run.as_deref().unwrap_or("overlaps the wall"))?;
        return Ok(rec.status);
    }
    let snaps = src.snapshots(&rec.run_id)?;
    if dst.has_run(run_id) {
        dst.remove_run(run_id)?;
    }
    let mut w = dst.begin_run(&rec.run_id, &attrs, &snaps.triangles)?;
    for s in src.timeseries(&rec.run_id)? {
        w.append_sample(&s)?;
    }
    for (k, (t, v)) in snaps.times_s.iter().zip(&snaps.vertices_um).enumerate() {
        let fields: Vec<(&str, &[f64])> = snaps.fields.iter().map(|(n, rows)| (n.as_str(), rows[k].as_slice())).collect();
        w.append_snapshot_with(*t, v, &fields)?;
    }
    for t in &rec.transits {
        w.set_transit(t)?;
    }
    match (&rec.summary, rec.status) {
        (Some(s), _) => w.finish(s)?,
        (None, RunStatus::Failed) => w.fail(rec.failure.as_deref().unwrap_or("failed"))?,
        _ => w.flush()?,
    }
    if let Some(c) = &rec.copied_from {
        dst.set_copied_from(run_id, c)?;
    }
    Ok(rec.status)
}
