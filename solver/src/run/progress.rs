//! Progress display of a run: a kdam bar (simulated time, step size, time left) on a terminal, plain log lines otherwise.

use super::checkpoint::RunState;
use super::{Observer, RunSummary, Sample};
use crate::error::SolverError;
use kdam::{Bar, BarExt};
use std::io::IsTerminal;
use std::time::Instant;

/// Wall time left (s) when simulated time advanced from `t0_s` to `t_s` in `wall_s` seconds and
/// runs to `t_end_s`, assuming the rate so far holds; `None` before any progress.
pub fn time_left_s(t0_s: f64, t_s: f64, t_end_s: f64, wall_s: f64) -> Option<f64> {
    let done = t_s - t0_s;
    (done > 0.0 && wall_s.is_finite()).then(|| (wall_s * (t_end_s - t_s) / done).max(0.0))
}

/// `1h02m`, `3m05s`, `42s`.
pub fn format_duration(s: f64) -> String {
    let s = s.round().max(0.0) as u64;
    match (s / 3600, (s / 60) % 60, s % 60) {
        (0, 0, sec) => format!("{sec}s"),
        (0, m, sec) => format!("{m}m{sec:02}s"),
        (h, m, _) => format!("{h}h{m:02}m"),
    }
}

/// Shows the progress of a run on standard error.
pub struct Progress {
    bar: Option<Bar>,
    t_end_s: f64,
    interval_s: f64,
    last_h_s: f64,
    label: String,
    /// Simulated time and wall clock at the (re)start, for the time left.
    t0_s: f64,
    started: Instant,
}

fn make_bar(label: &str, total: usize, initial: usize) -> Option<Bar> {
    if std::io::stderr().is_terminal() {
        Bar::builder().total(total).initial(initial).desc(label.to_string()).unit("out").build().ok()
    } else {
        None
    }
}

impl Progress {
    /// A bar over `t_end_s` in steps of the output interval when stderr is a
    /// terminal (kdam draws even when it is not, so it is disabled then: see
    /// dependencies.md), plain lines otherwise.
    pub fn new(label: &str, t_end_s: f64, output_interval_s: f64) -> Self {
        let total = (t_end_s / output_interval_s).round().max(1.0) as usize;
        let bar = make_bar(label, total, 0);
        Self { bar, t_end_s, interval_s: output_interval_s, last_h_s: 0.0, label: label.to_string(), t0_s: 0.0, started: Instant::now() }
    }

    fn left(&self, t_s: f64) -> String {
        match time_left_s(self.t0_s, t_s, self.t_end_s, self.started.elapsed().as_secs_f64()) {
            Some(s) => format_duration(s),
            None => "?".into(),
        }
    }
}

impl Observer for Progress {
    fn sample(&mut self, s: &Sample<'_>) -> Result<(), SolverError> {
        let left = self.left(s.t_s);
        // the sharpest fold between adjacent triangles: resolution trouble shows before the run
        // stops at integrator.max_fold_deg
        let fold = crate::integrate::check::sharpest_fold(s.vertices, s.triangles).0.to_degrees();
        match &mut self.bar {
            Some(bar) => {
                bar.set_postfix(format!("t={:.4e} s, h={:.2e} s, step {}, fold {fold:.0} deg, left {left}", s.t_s, self.last_h_s, s.step));
                let _ = bar.update_to((s.t_s / self.interval_s).round() as usize);
            }
            None => eprintln!(
                "{}: t = {:.6e} s / {:.6e} s, step {}, h = {:.3e} s, area {:.4} um^2, volume {:.4} um^3, sharpest fold {fold:.0} deg, left {left}",
                self.label, s.t_s, self.t_end_s, s.step, s.h_s, s.area_um2, s.volume_um3
            ),
        }
        Ok(())
    }

    fn progress(&mut self, _t_s: f64, h_s: f64, _step: usize) {
        self.last_h_s = h_s;
    }

    fn resumed(&mut self, state: &RunState) {
        self.t0_s = state.t_s;
        self.started = Instant::now();
        self.last_h_s = state.h_s;
        if self.bar.is_some() {
            let total = (self.t_end_s / self.interval_s).round().max(1.0) as usize;
            self.bar = make_bar(&self.label, total, (state.t_s / self.interval_s).round() as usize);
        } else {
            eprintln!("{}: resumed at t = {:.6e} s, step {}", self.label, state.t_s, state.summary.accepted);
        }
    }

    fn finish(&mut self, summary: &RunSummary, failure: Option<&SolverError>) -> Result<(), SolverError> {
        if matches!(failure, Some(SolverError::Resume(_))) {
            return Ok(()); // not run: the caller reports why
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_left_extrapolates_the_rate_since_the_restart() {
        // 2 s of wall for 0.1 -> 0.3 s simulated: 0.7 s simulated left take 7 s
        assert!((time_left_s(0.1, 0.3, 1.0, 2.0).unwrap() - 7.0).abs() < 1e-12);
        assert_eq!(time_left_s(0.1, 0.1, 1.0, 2.0), None);
        assert_eq!(format_duration(42.4), "42s");
        assert_eq!(format_duration(185.0), "3m05s");
        assert_eq!(format_duration(3720.0), "1h02m");
    }
}
