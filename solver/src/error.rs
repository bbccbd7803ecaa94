//! Typed errors of the solver: each variant carries the context needed for a diagnosis.

use crate::bim::BimError;
use crate::integrate::error::IntegrateError;
use crate::membrane::MembraneError;
use crate::mesh::MeshError;

/// A failure of the solver, with the evidence for a diagnosis.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    /// Time integration stopped (blow-up, inverted triangle, area change, step collapse...).
    #[error(transparent)]
    Integrate(#[from] IntegrateError),
    /// A mesh could not be built or became unusable.
    #[error("mesh: {0}")]
    Mesh(#[from] MeshError),
    /// A boundary-integral solve failed.
    #[error("boundary integral: {0}")]
    Bim(#[from] BimError),
    /// A membrane law was given invalid parameters.
    #[error("membrane: {0}")]
    Membrane(#[from] MembraneError),
    /// A file (scene, results) failed to read, validate or write (names the file and field).
    #[error(transparent)]
    Schema(#[from] rbc_schema::SchemaError),
    /// The scene is valid but asks for something this build cannot assemble yet.
    #[error("scene field `{field}`: {message}")]
    Unsupported { field: String, message: String },
    /// A velocity evaluation failed inside a step.
    #[error("at t = {t_s:.6e} s, step {step}: {source}")]
    AtStep { t_s: f64, step: usize, source: Box<SolverError> },
    /// A periodic-channel Stokes solve failed (bad input, cell outside the channel, Ewald).
    #[error("channel: {0}")]
    Channel(#[from] crate::channel::ChannelError),
    /// Writing output failed.
    #[error("output: {0}")]
    Output(String),
    /// A run could not continue from its checkpoint after it was reopened (the checkpoint's
    /// state does not fit the run: the vertex count, the integrator's or the dynamics' stored
    /// state, the observer's own fields; or the results could not be read back). Not a failure of
    /// the run: observers keep its rows up to the checkpoint, its status `running` and its
    /// checkpoint ([`crate::run::Observer::finish`]). What a checkpoint file alone shows to be
    /// unusable is refused earlier, before anything is cut back ([`crate::run::persist::reopen`]).
    #[error("cannot continue from its checkpoint: {0}")]
    Resume(String),
}
