//! Reopen a run that ended (steady, periodic or unsteady) so that it continues from its last
//! state: `rbc-sweep reopen`, for a run that a criterion since made stricter would not have
//! stopped (e.g. the periodic verdict before the orbit's mean drift was checked,
//! `rbc_solver::steady`), without computing its simulated time again.
//!
//! A run that ended before session 28 has no checkpoint (it was deleted at the end), but its
//! results hold what one needs: the state of a boundary integral run is the vertex positions alone (Stokes flow has
//! no inertia, the membrane's reference shape is the initial mesh), and the run's final state
//! is its last snapshot, at its last sample's time. [`reopen_ended`] writes a checkpoint at
//! that state and sets the run back to `running` (its summary and evidence removed; its
//! samples, snapshots and transit records stay), so that `rbc-sweep task`/`run` resumes it
//! like a suspended run. The runner starts from that state with a fresh integrator (its
//! private state, the last Jacobian and the step-size controller's memory, is not in the
//! results: the first step is `integrator.h0_s` and the controller grows it). The observer's
//! ring is rebuilt from the final classification frames stored at the end (the snapshots
//! within the classifier's window `evidence_classify_window_s` before the end).
//!
//! A run that ended since session 28 kept the checkpoint of its end state
//! ([`super::solver_exec`]: written at its last sample, with the integrator's state and, with
//! penalty walls, the walls' displacements): it is reopened at that checkpoint instead, and the
//! resumed run continues exactly as the runner left it. A run with penalty walls that kept no
//! end checkpoint is refused: their displacements are part of its state, and the results do not
//! hold them.

use super::observer_state::{observer_fields, RingEntry};
use super::SweepError;
use nalgebra::Vector3;
use rbc_schema::checkpoint::{self, Checkpoint};
use rbc_schema::results::{ResultsFile, RunStatus};
use rbc_schema::scene::Scene;
use rbc_solver::run::checkpoint::RunState;
use rbc_solver::run::persist::checkpoint_fields;
use rbc_solver::run::results::SampleRows;
use rbc_solver::run::RunSummary as SolverSummary;
use rbc_solver::state::StateMap;
use std::path::Path;

fn bad(path: &Path, message: impl std::fmt::Display) -> SweepError {
    SweepError::Io { path: path.into(), message: message.to_string() }
}

/// Reopen run `run_id` of the results file `path`, which ended steady, periodic or unsteady,
/// at its last state (see the module documentation); `snapshot_every` is the sweep's snapshot
/// cadence (output samples). Returns the time (s) the run continues from. A running run, a
/// failed one (its end is a diagnosis) and one whose last snapshot is not its final state are
/// refused and nothing is changed.
pub fn reopen_ended(path: &Path, run_id: &str, snapshot_every: usize) -> Result<f64, SweepError> {
    let mut file = ResultsFile::create_or_open(path)?;
    let rec = file.run(run_id)?;
    if !rec.status.is_finished() {
        let why = match rec.status {
            RunStatus::Failed => "failed (its end is a diagnosis, not a verdict): start it again instead",
            RunStatus::OverlapsWall => "was never run: its cell overlaps the channel wall",
            _ => "has not ended: resume it instead",
        };
        return Err(bad(path, format!("run `{run_id}` {why}")));
    }
    let (Some(attrs), Some(summary)) = (rec.attrs.as_ref(), rec.summary.as_ref()) else {
        return Err(bad(path, format!("run `{run_id}`: no attributes or summary")));
    };
    let scene = Scene::parse(&attrs.scene, path).map_err(|e| bad(path, format!("run `{run_id}`: field `scene`: {e}")))?;
    let rows = file.timeseries(run_id)?;
    // the checkpoint of its end state, kept at its last sample: the run continues from it
    let ck_path = checkpoint::checkpoint_path(path, run_id);
    if ck_path.exists() {
        let ck = checkpoint::read(&ck_path).map_err(|e| bad(&ck_path, e))?;
        if ck.run_id != run_id {
            return Err(bad(&ck_path, format!("not the end checkpoint of run `{run_id}` (it is run `{}`'s)", ck.run_id)));
        }
        let Some(last) = rows.last() else {
            return Err(bad(path, format!("run `{run_id}` has no samples")));
        };
        if ck.t_s != last.t_s || ck.n_samples != rows.len() {
            return Err(bad(&ck_path, format!("not the end checkpoint of run `{run_id}`: it is at {} s after {} samples, the run ends at {} s after {}", ck.t_s, ck.n_samples, last.t_s, rows.len())));
        }
        file.resume_run(run_id)?.flush()?;
        return Ok(ck.t_s);
    }
    if scene.walls.has_penalty_walls() {
        // the walls' displacements are part of the state (after the cell's vertices) but not of
        // the results: a checkpoint of the cell alone would not fit the run
        return Err(bad(path, format!("run `{run_id}` has penalty walls, whose displacements the results do not hold, and kept no checkpoint of its end (it ended before session 28): it cannot be reopened from its last snapshot (start it again with a longer end)")));
    }
    let snaps = file.snapshots(run_id)?;
    let (Some(last_row), Some(&t_last)) = (rows.last(), snaps.times_s.last()) else {
        return Err(bad(path, format!("run `{run_id}` has no samples or no snapshots")));
    };
    if t_last != last_row.t_s || snaps.times_s[0] != rows[0].t_s {
        return Err(bad(path, format!("run `{run_id}`: the snapshots end at {t_last} s, the samples at {} s: the final state is not stored", last_row.t_s)));
    }
    // the output times are t_0 + k dt: the next one is k = rows
    let dt = scene.time.output_interval_s;
    let index = |t: f64| ((t - rows[0].t_s) / dt).round() as usize;
    if rows.iter().enumerate().any(|(k, r)| (r.t_s - rows[0].t_s - k as f64 * dt).abs() > 1e-6 * dt) {
        return Err(bad(path, format!("run `{run_id}`: the samples are not every output interval ({dt} s)")));
    }
    // the final ring: the snapshots within the classifier's window before the end
    let window_s = summary.evidence.get("classify_window_s").copied().unwrap_or(0.0);
    let keep = snaps.times_s.iter().position(|t| *t >= t_last - window_s - 1e-9 * dt).unwrap_or(snaps.times_s.len() - 1);
    let triangles: Vec<[usize; 3]> = snaps.triangles.iter().map(|t| t.map(|i| i as usize)).collect();
    let vertices: Vec<Vector3<f64>> = snaps.vertices_um[snaps.vertices_um.len() - 1].iter().map(|p| Vector3::from(*p)).collect();
    let area0_um2 = rbc_solver::classify::surface_area(&snaps.vertices_um[0], &triangles);
    let evidence = |k: &str| summary.evidence.get(k).copied().unwrap_or(0.0);
    let state = RunState {
        t_s: t_last,
        h_s: scene.integrator.h0_s,
        next_output: rows.len(),
        area0_um2,
        err_prev: None,
        summary: SolverSummary {
            accepted: evidence("steps_accepted") as usize,
            rejected: evidence("steps_rejected") as usize,
            wall_s: evidence("wall_s"),
            ..SolverSummary::default()
        },
        vertices,
        integrator: StateMap::new(),
        dynamics: StateMap::new(),
    };
    // the observer's ring at the end: every kept snapshot is a classification frame
    let ring: Vec<RingEntry> = (keep..snaps.times_s.len())
        .map(|j| RingEntry {
            t_s: snaps.times_s[j],
            vertices: snaps.vertices_um[j].clone(),
            regular: index(snaps.times_s[j]) % snapshot_every.max(1) == 0,
            frame: true,
        })
        .collect();
    let own = observer_fields(&SampleRows::new(snapshot_every), &ring.iter().collect::<Vec<_>>(), None, None, None);
    let fields = checkpoint_fields(&state, &own);
    let ck = Checkpoint { run_id: run_id.into(), scene: attrs.scene.clone(), t_s: t_last, n_samples: rows.len(), n_snapshots: keep, fields };
    checkpoint::write(&checkpoint::checkpoint_path(path, run_id), &ck)?;
    file.resume_run(run_id)?.flush()?;
    Ok(t_last)
}
