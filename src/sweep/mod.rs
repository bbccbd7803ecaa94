//! `rbc-sweep` machinery: a grid of runs (velocity x initial offset x start shape) executed on local cores or as a Slurm array, resumable, merged into one results.h5.
//!
//! - [`RunExecutor`]: executes one [`SweepRun`] into a results file. The real
//!   one is [`solver_exec::SolverExecutor`] (solver + steady-state detection +
//!   classification: the verdict and summary in [`verdict`], the observer's checkpoint fields in
//!   [`observer_state`]); tests inject a cheap fake, so the machinery is tested
//!   without the solver.
//! - [`local::run_local`]: a pool of worker threads on this machine, one run per
//!   worker. Each run writes its own part file (`.<out>.parts/<run_id>.h5`); the
//!   coordinating thread copies every finished run into the output file, so the
//!   output only ever grows by complete runs. A backup of the output taken when
//!   the call starts and the part files of the call (removed when it ends) make
//!   an output damaged by a kill recoverable without rerunning anything.
//!   Resuming skips every run the output already holds as finished (and failed,
//!   unless `retry_failed`), copies finished part files left by a kill, and
//!   restarts the others from their beginning.
//! - [`task::run_task`]: one run by index (a Slurm array task) into its own file.
//! - [`slurm::write_slurm`]: the array job, the merge job and a submit script.
//! - merging uses `rbc_schema::results::merge_files`.
//! - [`stored_shapes::stored_shapes`]: the shapes a run has stored (snapshots, then its open
//!   checkpoint's ring).
//! - [`study::progress`]: how far the runs of a study have come (read from their checkpoints while they run).
//! - [`events::events`]: the turn-overs and folds of each run (`rbc-sweep events`).
//!
//! Threads per run: one by default (`threads_per_run` in the sweep file). The
//! runs of a sweep are independent, so running one per core uses every core
//! with no synchronisation at all, while a single boundary-integral run of the
//! paper's size (1026 vertices, a dense 3078 x 3078 operator) gains less than
//! linearly from more threads; several threads per run only pay off when there
//! are fewer runs left than cores (the tail of a sweep) or for memory limits.

pub mod copy;
pub mod events;
pub mod local;
pub mod observer_state;
pub mod relabel;
pub mod reopen;
pub mod slurm;
pub mod solver_exec;
pub mod stored_shapes;
pub mod study;
pub mod task;
pub mod verdict;

use nalgebra::Vector3;
use rbc_schema::results::ResultsFile;
use rbc_schema::scene::{Scene, WallsSpec};
use rbc_schema::sweep::{Sweep, SweepRun};
use rbc_schema::unstage::Unstage;
use rbc_schema::SchemaError;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Errors of the sweep machinery (each names the file or the run).
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error(transparent)]
    Schema(#[from] SchemaError),
    /// A run could not be executed (bad scene, solver refused it, I/O...).
    #[error("run {run_id}: {message}")]
    Run { run_id: String, message: String },
    #[error("{path}: {message}")]
    Io { path: PathBuf, message: String },
    #[error("task index {index} is out of range: the sweep has {len} runs (0..{len})")]
    TaskIndex { index: usize, len: usize },
}

impl Unstage for SweepError {
    fn unstaged(self, from: &Path, to: &Path) -> Self {
        use rbc_schema::unstage::{rebased, renamed_in};
        match self {
            SweepError::Schema(e) => SweepError::Schema(e.unstaged(from, to)),
            SweepError::Run { run_id, message } => SweepError::Run { run_id, message: renamed_in(&message, from, to) },
            SweepError::Io { path, message } => SweepError::Io { path: rebased(&path, from, to), message: renamed_in(&message, from, to) },
            e @ SweepError::TaskIndex { .. } => e,
        }
    }
}

/// Executes one run of a sweep.
pub trait RunExecutor: Sync {
    /// Run `run` and write it as run `run.run_id` into the results file `out`
    /// (created when absent). `out` may already hold an unfinished attempt of the
    /// same run (a killed sweep): resume or replace it. On return the run must be
    /// finished (steady, periodic, unsteady) or failed (a diagnosed blow-up);
    /// an `Err` means it could not be executed at all.
    fn execute(&self, sweep: &Sweep, run: &SweepRun, out: &Path) -> Result<(), SweepError>;
}

impl<F> RunExecutor for F
where
    F: Fn(&Sweep, &SweepRun, &Path) -> Result<(), SweepError> + Sync,
{
    fn execute(&self, sweep: &Sweep, run: &SweepRun, out: &Path) -> Result<(), SweepError> {
        self(sweep, run, out)
    }
}

/// The start attributes of a run (results.h5 `RunAttrs`).
pub fn run_attrs(run: &SweepRun, lambda: f64) -> rbc_schema::results::RunAttrs {
    rbc_schema::results::RunAttrs {
        start_shape: run.start_shape.clone(),
        r_init_um: run.r_init_um,
        y_init_um: run.y_init_um,
        z_init_um: run.z_init_um,
        lambda,
        scene: run.scene_text.clone(),
    }
}

/// Expand `sweep` into its runs, validating every run's scene (the first invalid one is the error),
/// and mark each run whose cell starts in, or closer than the channel solve allows to, the channel
/// wall ([`SweepRun::overlaps_wall`]: the paper's largest offsets, its dashed line): such a run is
/// recorded with status `overlaps-wall` and never executed. The check is the solver's own (its
/// initial mesh of each start shape, built once, moved to each offset; `rbc_solver::scene::wall_overlap`).
/// Also returns one note per start shape whose mesh cannot be built yet (e.g. a `mesh-from-results`
/// file not made yet): its runs are not checked here, and the solver names the cause when they run.
pub fn expand(sweep: &Sweep) -> Result<(Vec<SweepRun>, Vec<String>), SweepError> {
    let mut runs = sweep.runs()?;
    let mut meshes: BTreeMap<String, Result<Vec<Vector3<f64>>, String>> = BTreeMap::new();
    let mut notes = Vec::new();
    for r in &mut runs {
        let scene = Scene::parse(&r.scene_text, &sweep.base_scene)
            .map_err(|e| SweepError::Io { path: sweep.path.clone(), message: format!("run {}: {e}", r.run_id) })?;
        if matches!(scene.walls, WallsSpec::None) {
            continue;
        }
        let start = meshes.entry(r.start_shape.clone()).or_insert_with(|| {
            let mut at_origin = scene.clone();
            at_origin.cell.position_um = [0.0; 3];
            let mesh = rbc_solver::scene::initial_mesh(&at_origin).map(|m| m.vertices).map_err(|e| e.to_string());
            if let Err(e) = &mesh {
                notes.push(format!("start shape {}: its runs are not checked against the channel wall (its mesh: {e})", r.start_shape));
            }
            mesh
        });
        if let Ok(start) = start {
            let at = Vector3::from(scene.cell.position_um);
            let moved: Vec<Vector3<f64>> = start.iter().map(|v| v + at).collect();
            if let Some(o) = rbc_solver::scene::wall_overlap_of(&scene.walls, &moved) {
                r.overlaps_wall = Some(format!("r_init_um = {}: {o}", r.r_init_um));
            }
        }
    }
    Ok((runs, notes))
}

/// Record `run` (one whose cell overlaps the wall) in `file` with status `overlaps-wall`, its start
/// attributes and the reason, replacing an earlier record of that id.
pub fn record_overlap(sweep: &Sweep, run: &SweepRun, file: &mut ResultsFile) -> Result<(), SweepError> {
    let scene = Scene::parse(&run.scene_text, &sweep.base_scene)
        .map_err(|e| SweepError::Run { run_id: run.run_id.clone(), message: e.to_string() })?;
    let reason = run.overlaps_wall.as_deref().unwrap_or("the cell overlaps the channel wall");
    file.record_overlaps_wall(&run.run_id, &run_attrs(run, scene.fluid.lambda), reason)?;
    Ok(file.flush()?)
}
