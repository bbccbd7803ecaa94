//! Start shapes from ended runs: the last shape of a run that reached its steady state, copied
//! under a new run id into a results file that sweeps read as `mesh-from-results` start shapes.
//!
//! Guckenberger et al. (Sec. 4.1) start their phase diagrams of Fig. 5 b and c from "a typical
//! croissant as well as a typical slipper", "obtained from previous simulations that started
//! with the discocyte form". [`copy_last_shape`] makes such a start: the run `as_id` in `dst`
//! holds the source run's start attributes (its scene: how the shape was made) and summary (what
//! it is: `final_shape`, evidence), the output sample and the snapshot (with its per-vertex fields)
//! at the time of the source's last snapshot, and `copied_from` naming the source file, run and
//! time. A sweep's `[start_shape.NAME]` table then reads it with `shape = "mesh-from-results"`,
//! `run = as_id` (`rbc_schema::sweep`).

use crate::error::{Result, SchemaError};
use crate::results::{invalid, ResultsFile, RunStatus};
use std::path::Path;

/// Copy the last shape of the ended run `run_id` of `src` into `dst` as run `as_id` (see the
/// module documentation); `dst` is created when missing and replaced atomically (a copy written
/// beside it and renamed), so a failure leaves it as it was. Returns the time of the shape (s).
///
/// Refused, naming the file and run: a source run that has not ended (running, failed, not run:
/// a start shape is a settled one), one without snapshots, an `as_id` that `dst` already holds,
/// and `dst` being `src`.
pub fn copy_last_shape(src: &Path, run_id: &str, dst: &Path, as_id: &str) -> Result<f64> {
    if dst == src {
        return Err(invalid(dst, "the start shapes' file is also the source of the shape"));
    }
    let from = ResultsFile::open(src)?;
    let rec = from.run(run_id)?;
    let (Some(attrs), Some(summary)) = (rec.attrs.clone(), rec.summary.clone()) else {
        return Err(SchemaError::field(
            src,
            format!("runs/{run_id}.status"),
            format!("a start shape is the settled shape of a run that ended (steady, periodic or unsteady); this one is {}", rec.status.as_str()),
        ));
    };
    if rec.status == RunStatus::OverlapsWall {
        return Err(invalid(src, format!("run `{run_id}` was not run (it overlaps the wall)")));
    }
    let snaps = from.snapshots(run_id)?;
    let (Some(&t), Some(vertices)) = (snaps.times_s.last(), snaps.vertices_um.last()) else {
        return Err(invalid(src, format!("run `{run_id}` has no snapshot to start from")));
    };
    let k = snaps.times_s.len() - 1;
    let sample = from.timeseries(run_id)?.into_iter().rev().find(|s| s.t_s <= t * (1.0 + 1e-12));
    // the file of start shapes is checked where it is (errors name it, not the copy written beside it)
    if !crate::results::is_valid_run_id(as_id) {
        return Err(invalid(dst, format!("`{as_id}` cannot name a run (--as): it must not be empty, hold `/`, or be `.` or `..`")));
    }
    if dst.exists() && ResultsFile::open(dst)?.has_run(as_id) {
        return Err(invalid(dst, format!("run `{as_id}` already exists (choose another name, or remove the file to make it again)")));
    }
    crate::atomic::write_via(dst, |tmp| {
        if dst.exists() {
            std::fs::copy(dst, tmp).map_err(|e| SchemaError::io(dst, e))?;
        }
        let mut out = ResultsFile::create_or_open_by(tmp, concat!("rbc-toolkit ", env!("CARGO_PKG_VERSION"), " start shapes"))?;
        let mut w = out.begin_run(as_id, &attrs, &snaps.triangles)?;
        if let Some(s) = sample {
            w.append_sample(&s)?;
        }
        let fields: Vec<(&str, &[f64])> = snaps.fields.iter().map(|(n, rows)| (n.as_str(), rows[k].as_slice())).collect();
        w.append_snapshot_with(t, vertices, &fields)?;
        w.finish(&summary)?;
        let name = src.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        out.set_copied_from(as_id, &format!("{name}: run {run_id}, its last snapshot (t = {t} s)"))?;
        out.flush()
    })?;
    Ok(t)
}
