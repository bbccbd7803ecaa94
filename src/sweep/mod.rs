//! `rbc-sweep` machinery: a grid of runs (velocity x initial offset x start shape) executed on local cores or as a Slurm array, resumable, merged into one results.h5.
//!
//! - [`RunExecutor`]: executes one [`SweepRun`] into a results file. The real
//!   one is [`solver_exec::SolverExecutor`] (solver + steady-state detection +
//!   classification); tests inject a cheap fake, so the machinery is tested
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
//! - [`study::progress`]: how far the runs of a study have come (read from their checkpoints while they run).
//!
//! Threads per run: one by default (`threads_per_run` in the sweep file). The
//! runs of a sweep are independent, so running one per core uses every core
//! with no synchronisation at all, while a single boundary-integral run of the
//! paper's size (1026 vertices, a dense 3078 x 3078 operator) gains less than
//! linearly from more threads; several threads per run only pay off when there
//! are fewer runs left than cores (the tail of a sweep) or for memory limits.

pub mod copy;
pub mod local;
pub mod relabel;
pub mod reopen;
pub mod slurm;
pub mod solver_exec;
pub mod study;
pub mod task;

use rbc_schema::sweep::{Sweep, SweepRun};
use rbc_schema::SchemaError;
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
