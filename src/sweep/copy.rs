//! Copy one run between results files (through the public reader/writer of `rbc_schema::results`).

use super::SweepError;
use rbc_schema::results::{ResultsFile, RunStatus};

/// Copy run `run_id` of `src` into `dst`, replacing a run of that id in `dst`.
/// Returns the copied run's status.
pub fn copy_run(
    src: &ResultsFile,
    run_id: &str,
    dst: &mut ResultsFile,
) -> Result<RunStatus, SweepError> {
    let rec = src.run(run_id)?;
    let attrs = rec.attrs.clone().ok_or_else(|| SweepError::Run {
        run_id: run_id.to_string(),
        message: format!(
            "{}: the run has no start attributes (interrupted while created)",
            src.path().display()
        ),
    })?;
    let snaps = src.snapshots(run_id)?;
    if dst.has_run(run_id) {
        dst.remove_run(run_id)?;
    }
    let mut w = dst.begin_run(run_id, &attrs, &snaps.triangles)?;
    for s in src.timeseries(run_id)? {
        w.append_sample(&s)?;
    }
    for (t, v) in snaps.times_s.iter().zip(&snaps.vertices_um) {
        w.append_snapshot(*t, v)?;
    }
    match (&rec.summary, rec.status) {
        (Some(s), _) => w.finish(s)?,
        (None, RunStatus::Failed) => w.fail(rec.failure.as_deref().unwrap_or("failed"))?,
        _ => w.flush()?,
    }
    Ok(rec.status)
}
