//! Checkpoints of a run on disk: when to take them, writing them beside results.h5, and reopening a run from its checkpoint.
//!
//! The order of a checkpoint makes a `SIGKILL` at any instant harmless: first the
//! run's rows up to the checkpoint are flushed into results.h5, then the
//! checkpoint file (`rbc_schema::checkpoint`) replaces the previous one by an
//! atomic rename. A resumed run cuts the results back to the counts the
//! checkpoint recorded, so rows written after it (complete or not) are dropped
//! and written again by the resumed run.

use super::checkpoint::RunState;
use crate::error::SolverError;
use crate::state::StateMap;
use rbc_schema::checkpoint::{self, Checkpoint};
use rbc_schema::results::{ResultsFile, RunStatus, RunWriter, TimeSample};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Key prefix of an observer's own state in a checkpoint.
pub const OBSERVER_PREFIX: &str = "observer.";

/// The fields of a checkpoint: the runner's `state` ([`RunState::to_fields`]) and the
/// observer's own fields under [`OBSERVER_PREFIX`]. What [`CheckpointWriter::write`] stores, and
/// what a checkpoint made outside a run (`rbc-sweep reopen`, for a run that ended) must store.
pub fn checkpoint_fields(state: &RunState, observer_fields: &StateMap) -> StateMap {
    let mut fields = state.to_fields();
    for (k, v) in observer_fields {
        fields.insert(format!("{OBSERVER_PREFIX}{k}"), v.clone());
    }
    fields
}

/// The observer's own fields of a checkpoint's `fields` ([`OBSERVER_PREFIX`] removed): the
/// inverse of [`checkpoint_fields`] for them.
pub fn observer_fields(fields: &StateMap) -> StateMap {
    fields.iter().filter_map(|(k, v)| k.strip_prefix(OBSERVER_PREFIX).map(|s| (s.to_string(), v.clone()))).collect()
}

/// When checkpoints are taken: after every `every_outputs`-th output sample and/or when
/// `every_wall_s` seconds of wall time have passed since the last one (0 disables either),
/// and always at the initial sample, so a run has a checkpoint from its start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckpointPolicy {
    pub every_outputs: usize,
    pub every_wall_s: f64,
}

impl Default for CheckpointPolicy {
    /// Every 60 s of wall time: at most a minute of work is lost, and a checkpoint
    /// (one small HDF5 file and an `fsync`, milliseconds) costs nothing next to a minute.
    fn default() -> Self {
        CheckpointPolicy { every_outputs: 0, every_wall_s: 60.0 }
    }
}

/// The message of the error by which an observer suspends the solver after a checkpoint
/// ([`SuspendRequest`]).
pub const SUSPEND: &str = "suspend requested: the run stops at its checkpoint and resumes from it";

/// The suspend request of the runs written to `out`: the file `<out>.suspend` beside it. When it
/// exists, a run takes a checkpoint at its next output sample and stops there, unfinished
/// (status `running`), so that the results file and the checkpoint can be copied and resumed
/// elsewhere (a study committed to the repository, a job moved between machines, a machine that
/// is about to go away).
pub fn suspend_path(out: &Path) -> PathBuf {
    let mut name = out.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(".suspend");
    out.with_file_name(name)
}

/// A run's suspend request ([`suspend_path`]), as an observer serves it: asked whether a
/// checkpoint is due ([`SuspendRequest::poll`]: the file exists), it makes the runner take one;
/// after writing it, [`SuspendRequest::after_checkpoint`] stops the run with [`SUSPEND`]. The
/// file is left in place: whoever asked removes it before resuming.
#[derive(Debug)]
pub struct SuspendRequest {
    file: PathBuf,
    requested: bool,
    served: bool,
}

impl SuspendRequest {
    /// The request for runs written to the results file `out` (`<out>.suspend`).
    pub fn for_results(out: &Path) -> Self {
        SuspendRequest { file: suspend_path(out), requested: false, served: false }
    }

    /// The request file (`<out>.suspend`).
    pub fn path(&self) -> &Path {
        &self.file
    }

    /// Whether the request file exists now (asked at each output sample, where checkpoints are decided).
    pub fn poll(&mut self) -> bool {
        self.requested = self.file.exists();
        self.requested
    }

    /// Called right after a checkpoint was written: stops the run ([`SUSPEND`]) when the last
    /// [`SuspendRequest::poll`] saw the request.
    pub fn after_checkpoint(&mut self) -> Result<(), SolverError> {
        if self.requested {
            self.served = true;
            return Err(SolverError::Output(SUSPEND.into()));
        }
        Ok(())
    }

    /// True when the run stopped at a checkpoint on this request.
    pub fn served(&self) -> bool {
        self.served
    }
}

/// Writes the checkpoints of one run into `<results>.<run_id>.ckpt`.
#[derive(Debug)]
pub struct CheckpointWriter {
    path: PathBuf,
    run_id: String,
    scene: String,
    policy: CheckpointPolicy,
    outputs_since: usize,
    last: Option<Instant>,
    /// Checkpoints written.
    pub written: usize,
}

fn schema(e: rbc_schema::SchemaError) -> SolverError {
    SolverError::Schema(e)
}

impl CheckpointWriter {
    /// Checkpoints of run `run_id` (started from the scene TOML `scene`) of the results file `results`.
    pub fn new(results: &Path, run_id: &str, scene: &str, policy: CheckpointPolicy) -> Self {
        CheckpointWriter {
            path: checkpoint::checkpoint_path(results, run_id),
            run_id: run_id.into(),
            scene: scene.into(),
            policy,
            outputs_since: 0,
            last: None,
            written: 0,
        }
    }

    /// The checkpoint file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Called at every sample: is a checkpoint due?
    pub fn due(&mut self) -> bool {
        self.outputs_since += 1;
        let Some(last) = self.last else { return true };
        let by_count = self.policy.every_outputs > 0 && self.outputs_since >= self.policy.every_outputs;
        let by_time = self.policy.every_wall_s > 0.0 && last.elapsed() >= Duration::from_secs_f64(self.policy.every_wall_s);
        by_count || by_time
    }

    /// Flush `writer` and write the checkpoint of `state` with the observer's own fields
    /// (`observer_fields`, stored under `observer.`).
    pub fn write(&mut self, writer: &mut RunWriter, state: &RunState, observer_fields: &StateMap) -> Result<(), SolverError> {
        writer.flush().map_err(schema)?;
        let fields = checkpoint_fields(state, observer_fields);
        let ck = Checkpoint {
            run_id: self.run_id.clone(),
            scene: self.scene.clone(),
            t_s: state.t_s,
            n_samples: writer.n_samples(),
            n_snapshots: writer.n_snapshots(),
            fields,
        };
        checkpoint::write(&self.path, &ck).map_err(schema)?;
        self.outputs_since = 0;
        self.last = Some(Instant::now());
        self.written += 1;
        Ok(())
    }

    /// Start the clocks as if a checkpoint had just been written (after resuming from one).
    pub fn restart_clock(&mut self) {
        self.outputs_since = 0;
        self.last = Some(Instant::now());
    }

    /// Delete the checkpoint (the run ended).
    pub fn remove(&self) -> Result<(), SolverError> {
        checkpoint::remove(&self.path).map_err(schema)
    }
}

/// A run reopened at its checkpoint.
pub struct Reopened {
    /// Appends to the run, cut back to the checkpoint's rows.
    pub writer: RunWriter,
    /// The runner's state.
    pub state: RunState,
    /// The observer's own fields (prefix `observer.` removed).
    pub observer: StateMap,
    /// Timeseries rows up to the checkpoint (to rebuild derived state: velocities, statistics, detectors).
    pub rows: Vec<TimeSample>,
    /// Times of the snapshots up to the checkpoint (s).
    pub snapshot_times_s: Vec<f64>,
    /// The run's triangles (0-based vertex indices).
    pub triangles: Vec<[usize; 3]>,
    /// The scene text the checkpoint was written with (it may differ from the current one in
    /// what the caller's `same_scene` allows, e.g. the step method).
    pub scene: String,
}

/// Why a run cannot be resumed.
#[derive(Debug, Clone, PartialEq)]
pub enum NotResumable {
    /// The file has no such run.
    NoRun,
    /// The run ended (steady, periodic, unsteady, or failed).
    Ended(RunStatus),
    /// The run reached its end time (s) and kept the checkpoint of its end state, but the
    /// caller's end time does not pass it ([`reopen_to`]).
    AtEnd(f64),
    /// The run is unfinished but has no checkpoint (killed before its first one).
    NoCheckpoint,
    /// The checkpoint belongs to another run or is unreadable.
    Mismatch(String),
    /// The checkpoint was written with a scene the caller's does not continue (another model).
    OtherScene,
}

/// Reopen run `run_id` of `file` at its checkpoint, after checking that the run is
/// unfinished and the checkpoint belongs to it and to `scene` (`same_scene(stored)`
/// compares the scene TOML stored with the checkpoint to the caller's scene).
pub fn reopen(file: &mut ResultsFile, run_id: &str, same_scene: &dyn Fn(&str) -> bool) -> Result<Result<Reopened, NotResumable>, SolverError> {
    if !file.has_run(run_id) {
        return Ok(Err(NotResumable::NoRun));
    }
    let rec = file.run(run_id).map_err(schema)?;
    if rec.status != RunStatus::Running {
        return Ok(Err(NotResumable::Ended(rec.status)));
    }
    reopen_checked(file, run_id, same_scene)
}

/// [`reopen`], and also a run that ended at its end time (status `unsteady`) when `end_s` (s,
/// the caller's scene's end time) is later than the run's end: from the checkpoint of its end
/// state, which [`super::results::ResultsObserver`] keeps, the run continues to `end_s` (status
/// `running` again, its summary removed, the final snapshot cut back to the checkpoint's). A run
/// that ended at or after `end_s` is [`NotResumable::AtEnd`], one that kept no end checkpoint
/// (written before they were kept) stays [`NotResumable::Ended`]. The continuation's first step is the one the controller
/// proposed at the end; the last step before it was shortened to land on the old end time, so
/// the continuation equals an uninterrupted run to `end_s` only up to the step control's error.
pub fn reopen_to(file: &mut ResultsFile, run_id: &str, same_scene: &dyn Fn(&str) -> bool, end_s: f64) -> Result<Result<Reopened, NotResumable>, SolverError> {
    if !file.has_run(run_id) {
        return Ok(Err(NotResumable::NoRun));
    }
    let rec = file.run(run_id).map_err(schema)?;
    if rec.status != RunStatus::Unsteady {
        return reopen(file, run_id, same_scene);
    }
    let path = checkpoint::checkpoint_path(file.path(), run_id);
    let ended = Ok(Err(NotResumable::Ended(rec.status)));
    if !path.exists() {
        return ended;
    }
    let ck = match checkpoint::read(&path) {
        Ok(ck) => ck,
        Err(e) => return Ok(Err(NotResumable::Mismatch(e.to_string()))),
    };
    // the end checkpoint is at the last sample (an older one would cut the run back)
    if file.timeseries(run_id).map_err(schema)?.last().map(|r| r.t_s) != Some(ck.t_s) {
        return ended;
    }
    if end_s <= ck.t_s * (1.0 + 1e-12) {
        return Ok(Err(NotResumable::AtEnd(ck.t_s)));
    }
    reopen_at(file, run_id, same_scene, &path, ck)
}

/// [`reopen`] after the status check: the checkpoint read, then [`reopen_at`].
fn reopen_checked(file: &mut ResultsFile, run_id: &str, same_scene: &dyn Fn(&str) -> bool) -> Result<Result<Reopened, NotResumable>, SolverError> {
    let path = checkpoint::checkpoint_path(file.path(), run_id);
    if !path.exists() {
        return Ok(Err(NotResumable::NoCheckpoint));
    }
    match checkpoint::read(&path) {
        Ok(ck) => reopen_at(file, run_id, same_scene, &path, ck),
        Err(e) => Ok(Err(NotResumable::Mismatch(e.to_string()))),
    }
}

/// The checkpoint `ck` (read from `path`) checked against run `run_id`, `same_scene` and its own
/// state ([`RunState::unusable`]), then the run reopened at it, its rows and snapshots cut back
/// to it.
fn reopen_at(file: &mut ResultsFile, run_id: &str, same_scene: &dyn Fn(&str) -> bool, path: &Path, ck: Checkpoint) -> Result<Result<Reopened, NotResumable>, SolverError> {
    if ck.run_id != run_id {
        return Ok(Err(NotResumable::Mismatch(format!("{} is the checkpoint of run `{}`", path.display(), ck.run_id))));
    }
    if !same_scene(&ck.scene) {
        return Ok(Err(NotResumable::OtherScene));
    }
    let state = match RunState::from_fields(&ck.fields, "") {
        Ok(s) => s,
        Err(e) => return Ok(Err(NotResumable::Mismatch(e.to_string()))),
    };
    if state.t_s != ck.t_s {
        return Ok(Err(NotResumable::Mismatch(format!("{}: t_s {} differs from runner.t_s {}", path.display(), ck.t_s, state.t_s))));
    }
    // a state no run could continue from is refused here, before the run is cut back to it (the
    // snapshots hold the cell's vertices: their count, not their data)
    let n_cell = file.snapshot_layout(run_id).map_err(schema)?.n_vertices;
    if let Some(why) = state.unusable(n_cell) {
        return Ok(Err(NotResumable::Mismatch(format!("{}: {why}", path.display()))));
    }
    let mut writer = file.resume_run(run_id).map_err(schema)?;
    writer.truncate_to(ck.n_samples, ck.n_snapshots).map_err(schema)?;
    writer.flush().map_err(schema)?;
    let rows = file.timeseries(run_id).map_err(schema)?;
    let snaps = file.snapshots(run_id).map_err(schema)?;
    let (snapshot_times_s, triangles) = (snaps.times_s, snaps.triangles.iter().map(|t| t.map(|i| i as usize)).collect());
    // the checkpoint holds the state at the end of the step that produced the last sample: at
    // that sample's time, or after it with dense output (steps across output times)
    if rows.len() != ck.n_samples || !rows.last().is_some_and(|r| r.t_s <= ck.t_s) {
        return Err(SolverError::Output(format!(
            "{}: run `{run_id}` holds {} samples ending at {:?} s after truncation, the checkpoint expects {} ending at or before {} s",
            file.path().display(),
            rows.len(),
            rows.last().map(|r| r.t_s),
            ck.n_samples,
            ck.t_s
        )));
    }
    let observer = observer_fields(&ck.fields);
    Ok(Ok(Reopened { writer, state, observer, rows, snapshot_times_s, triangles, scene: ck.scene }))
}
