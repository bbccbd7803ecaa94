//! The shapes a run has stored: its results file's snapshots (every `snapshot_every`-th sample)
//! and, for a run still open, the later such samples its checkpoint's ring holds (the ring
//! reaches the checkpoint; they become snapshots as they leave it), in time order.

use super::observer_state::stored_ring;
use super::SweepError;
use rbc_schema::checkpoint;
use rbc_schema::results::ResultsFile;
use std::path::Path;

/// A run's stored shapes: the cell's vertices (um) at each time (s), on one triangulation.
#[derive(Debug, Clone)]
pub struct StoredShapes {
    pub times_s: Vec<f64>,
    pub vertices_um: Vec<Vec<[f64; 3]>>,
    pub triangles: Vec<[usize; 3]>,
}

/// The shapes run `run_id` has stored in the results file `path` and, when the run has a
/// checkpoint beside it, the ring's regular samples after the last snapshot. A checkpoint whose
/// ring does not fit the run's mesh is an error naming the checkpoint and the field.
pub fn stored_shapes(path: &Path, run_id: &str) -> Result<StoredShapes, SweepError> {
    let s = ResultsFile::open(path)?.snapshots(run_id)?;
    let triangles: Vec<[usize; 3]> = s.triangles.iter().map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
    let (mut times_s, mut vertices_um) = (s.times_s, s.vertices_um);
    let ck_path = checkpoint::checkpoint_path(path, run_id);
    if ck_path.exists() && !vertices_um.is_empty() {
        let ck = checkpoint::read(&ck_path)?;
        let own = rbc_solver::run::persist::observer_fields(&ck.fields);
        // a checkpoint written without the sweep's observer (rbc-simulate) holds no ring
        if own.contains_key("frame_t_s") {
            let nv = vertices_um[0].len();
            let ring = stored_ring(&own, nv).map_err(|field| SweepError::Io {
                path: ck_path.clone(),
                message: format!("field `{}{field}` does not fit the run's {nv} vertices", rbc_solver::run::persist::OBSERVER_PREFIX),
            })?;
            let last = times_s.last().copied().unwrap_or(f64::NEG_INFINITY);
            for e in ring.into_iter().filter(|e| e.regular && e.t_s > last + 1e-9) {
                times_s.push(e.t_s);
                vertices_um.push(e.vertices);
            }
        }
    }
    Ok(StoredShapes { times_s, vertices_um, triangles })
}
