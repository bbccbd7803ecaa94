//! Typed errors of the solver: each variant carries the context needed for a diagnosis.
//!
//! A variant that shows its inner error in its own line (`mesh: {0}`, `at t = ...: {cause}`) does
//! not also hand it on as its `source`: the binaries print an error with its chain on one line
//! (anyhow's `{:#}`), which would repeat it. Transparent variants hand both on.

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
    Mesh(MeshError),
    /// A boundary-integral solve failed.
    #[error("boundary integral: {0}")]
    Bim(BimError),
    /// A membrane law was given invalid parameters.
    #[error("membrane: {0}")]
    Membrane(MembraneError),
    /// A file (scene, results) failed to read, validate or write (names the file and field).
    #[error(transparent)]
    Schema(#[from] rbc_schema::SchemaError),
    /// The scene is valid but asks for something this build cannot assemble yet.
    #[error("scene field `{field}`: {message}")]
    Unsupported { field: String, message: String },
    /// A velocity evaluation failed inside a step.
    #[error("at t = {t_s:.6e} s, step {step}: {cause}")]
    AtStep { t_s: f64, step: usize, cause: Box<SolverError> },
    /// A periodic-channel Stokes solve failed (bad input, cell outside the channel, Ewald).
    #[error("channel: {0}")]
    Channel(crate::channel::ChannelError),
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

/// The inner error's line is part of the variant's own (see the module doc).
macro_rules! shown_inside {
    ($($inner:ty => $variant:ident),*) => {
        $(impl From<$inner> for SolverError {
            fn from(e: $inner) -> Self {
                SolverError::$variant(e)
            }
        })*
    };
}
shown_inside!(MeshError => Mesh, BimError => Bim, MembraneError => Membrane, crate::channel::ChannelError => Channel);

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error as _;

    /// Each level of a nested failure appears once in its one line, and no variant that shows
    /// its inner error hands it on again as a source.
    #[test]
    fn a_nested_failure_names_each_level_once() {
        let inner = crate::channel::ChannelError::Ewald(crate::ewald::EwaldError::NonFinite { what: "density", index: 7 });
        let e = SolverError::AtStep { t_s: 1e-3, step: 4, cause: Box::new(SolverError::from(inner)) };
        let line = e.to_string();
        assert_eq!(line, "at t = 1.000000e-3 s, step 4: channel: Ewald sum: non-finite density at index 7");
        assert!(e.source().is_none(), "{line}");
        let mesh = SolverError::from(MeshError::Empty { vertices: 0, triangles: 0 });
        assert!(mesh.source().is_none() && mesh.to_string() == "mesh: mesh is empty (0 vertices, 0 triangles)");
    }
}
