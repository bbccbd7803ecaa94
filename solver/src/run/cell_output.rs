//! An observer wrapper for runs whose state carries more than the cell: it hands the inner observer the cell part of each sample.
//!
//! The penalty-wall channel ([`crate::dynamics::penalty`]) integrates the cell's vertices followed
//! by the wall displacements; samples (snapshots, results, progress) are about the cell only.
//! Step attempts and checkpoints pass the whole state through: the step log splits each
//! attempt's error into the cell's and the walls' parts ([`super::step_log`]).

use super::checkpoint::RunState;
use super::{Observer, RunSummary, Sample};
use crate::error::SolverError;

/// Hands `inner` the cell part (the first `n_cell` entries) of each sample's state.
pub struct CellOutput<'o> {
    pub inner: &'o mut dyn Observer,
    pub n_cell: usize,
}

impl Observer for CellOutput<'_> {
    fn sample(&mut self, s: &Sample<'_>) -> Result<(), SolverError> {
        let n = self.n_cell.min(s.vertices.len());
        self.inner.sample(&Sample { vertices: &s.vertices[..n], ..*s })
    }
    fn progress(&mut self, t_s: f64, h_s: f64, step: usize) {
        self.inner.progress(t_s, h_s, step)
    }
    // The whole state and error: the step log splits them into the cell's and the walls' parts.
    fn attempt(&mut self, a: &super::Attempt<'_>) {
        self.inner.attempt(a)
    }
    fn finish(&mut self, summary: &RunSummary, failure: Option<&SolverError>) -> Result<(), SolverError> {
        self.inner.finish(summary, failure)
    }
    // Checkpoints carry the runner's whole state (cell vertices and wall displacements), so they
    // pass through unchanged: a resumed penalty run continues with its walls where they were.
    fn checkpoint_due(&mut self, t_s: f64) -> bool {
        self.inner.checkpoint_due(t_s)
    }
    fn checkpoint(&mut self, state: &RunState) -> Result<(), SolverError> {
        self.inner.checkpoint(state)
    }
    fn checkpoint_at_end(&mut self) -> bool {
        self.inner.checkpoint_at_end()
    }
    fn checkpoint_at_stop(&mut self) -> bool {
        self.inner.checkpoint_at_stop()
    }
    fn resume(&mut self) -> Result<Option<RunState>, SolverError> {
        self.inner.resume()
    }
    fn resumed(&mut self, state: &RunState) {
        self.inner.resumed(state)
    }
}
