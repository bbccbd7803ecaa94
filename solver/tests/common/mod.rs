//! Helpers shared by the solver's integration tests.

use rbc_solver::run::checkpoint::RunState;
use rbc_solver::run::{Observer, Recorder, Sample};
use rbc_solver::SolverError;

/// An observer that records the samples, takes a checkpoint whenever the runner offers one, and
/// resumes from `from` if given: a run and its resumption from any of `states` compared sample
/// by sample.
#[derive(Default)]
pub struct Tap {
    pub rec: Recorder,
    pub states: Vec<RunState>,
    pub from: Option<RunState>,
}

impl Observer for Tap {
    fn sample(&mut self, s: &Sample<'_>) -> Result<(), SolverError> {
        self.rec.sample(s)
    }
    fn checkpoint_due(&mut self, _t_s: f64) -> bool {
        true
    }
    fn checkpoint(&mut self, state: &RunState) -> Result<(), SolverError> {
        self.states.push(state.clone());
        Ok(())
    }
    fn resume(&mut self) -> Result<Option<RunState>, SolverError> {
        Ok(self.from.take())
    }
}
