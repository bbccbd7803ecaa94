//! Progress display of a run: a kdam bar (simulated time, step size) on a terminal, plain log lines otherwise.

use super::{Observer, RunSummary, Sample};
use crate::error::SolverError;
use kdam::{Bar, BarExt};
use std::io::IsTerminal;

/// Shows the progress of a run on standard error.
pub struct Progress {
    bar: Option<Bar>,
    t_end_s: f64,
    interval_s: f64,
    last_h_s: f64,
    label: String,
}

impl Progress {
    /// A bar over `t_end_s` in steps of the output interval when stderr is a
    /// terminal (kdam draws even when it is not, so it is disabled then: see
    /// dependencies.md), plain lines otherwise.
    pub fn new(label: &str, t_end_s: f64, output_interval_s: f64) -> Self {
        let total = (t_end_s / output_interval_s).round().max(1.0) as usize;
        let bar = if std::io::stderr().is_terminal() {
            Bar::builder().total(total).desc(label.to_string()).unit("out").build().ok()
        } else {
            None
        };
        Self { bar, t_end_s, interval_s: output_interval_s, last_h_s: 0.0, label: label.to_string() }
    }
}

impl Observer for Progress {
    fn sample(&mut self, s: &Sample<'_>) -> Result<(), SolverError> {
        match &mut self.bar {
            Some(bar) => {
                bar.set_postfix(format!("t={:.4e} s, h={:.2e} s, step {}", s.t_s, self.last_h_s, s.step));
                let _ = bar.update_to((s.t_s / self.interval_s).round() as usize);
            }
            None => eprintln!(
                "{}: t = {:.6e} s / {:.6e} s, step {}, h = {:.3e} s, area {:.4} um^2, volume {:.4} um^3",
                self.label, s.t_s, self.t_end_s, s.step, s.h_s, s.area_um2, s.volume_um3
            ),
        }
        Ok(())
    }

    fn progress(&mut self, _t_s: f64, h_s: f64, _step: usize) {
        self.last_h_s = h_s;
    }

    fn finish(&mut self, summary: &RunSummary, failure: Option<&SolverError>) -> Result<(), SolverError> {
        if let Some(bar) = &mut self.bar {
            let _ = bar.refresh();
            eprintln!();
        }
        eprintln!(
            "{}: {} at t = {:.6e} s: {} steps accepted, {} rejected, h in [{:.3e}, {:.3e}] s, {} velocity evaluations, {:.2} s wall",
            self.label,
            if failure.is_some() { "stopped" } else { "finished" },
            summary.t_s,
            summary.accepted,
            summary.rejected,
            summary.h_min_s,
            summary.h_max_s,
            summary.velocity_evals,
            summary.wall_s
        );
        Ok(())
    }
}
