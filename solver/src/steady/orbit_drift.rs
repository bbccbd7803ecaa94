//! How fast a run's orbit mean still moves, and whether it slows down or speeds up.
//!
//! The periodic test ([`super`], point 2) bounds the drift of an orbit's mean across its window by
//! the tolerance: at the study's 0.05 um over four periods of ~0.2 s, a slipper whose mean moves
//! by up to ~0.08 um/s can pass it. A cell that settles onto a stable orbit and one that slowly
//! leaves an unstable one (the paper's "intermediate slipper state that can last several seconds"
//! before a croissant) look alike there; they differ in the sign of the drift's trend. This
//! module measures it: the means of an observable over whole periods `P` ending at the last
//! sample, `m_j = (1/P) int_{t_j - P}^{t_j} x dt` at `t_j = t_end - j P` (of the piecewise linear
//! interpolant, as the drift test's means, so that the oscillation averages out), and the slope of
//! a least-squares line through the [`ORBIT_DRIFT_PERIODS`] = 4 latest of them (the rate, unit of
//! `x` per s; over the span `4 P`, as long as the window of the periodic test at its default three
//! cycles) and through the 4 before those (the earlier rate). Settling: `|rate| < |earlier
//! rate|` with the same sign; leaving: `|rate| > |earlier rate|`. The means of a resolved orbit
//! are smooth, so four of them give its rate; a span of a fixed time instead (say 1 s) would mix
//! a fast slipper's approach into its rate at the end of a short run.
//!
//! A run with no candidate orbit (a cell heading for `steady`, or a swing the periodic test gives
//! no period for yet) drifts too: a croissant can creep off the axis by less than the position
//! tolerance per window and still be judged steady. [`drift_interval_s`] then takes the means over
//! quarters of the window `W`, so that each fit spans one window: the rate is the radial
//! position's drift over the last window, the earlier rate over the window before (a swing with
//! no period is not averaged out there: its rate swings with it).

use super::orbit::{interval_mean, OrbitGap};

/// The periods of each of [`orbit_drift()`]'s two fits.
pub const ORBIT_DRIFT_PERIODS: usize = 4;

/// The interval (s) whose means [`orbit_drift()`] fits: the period of the run's candidate orbit
/// when it has one (`orbit`, the periodic gap's), else `window_s / ORBIT_DRIFT_PERIODS`, so that
/// each of the two fits spans one steady-state window (see the module documentation).
pub fn drift_interval_s(orbit: Option<&OrbitGap>, window_s: f64) -> f64 {
    orbit.map_or(window_s / ORBIT_DRIFT_PERIODS as f64, |o| o.period_s)
}

/// The drift of an orbit's mean (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitDrift {
    /// The period the means are taken over (s).
    pub period_s: f64,
    /// The span `ORBIT_DRIFT_PERIODS P` of each fit (s).
    pub span_s: f64,
    /// Slope of the means over the last span (unit of the observable per s).
    pub rate: f64,
    /// Slope over the span before it; `None` where the samples do not reach back two spans.
    pub earlier_rate: Option<f64>,
}

/// The drift of the orbit mean of `x` (sampled at `times`, increasing) over periods of
/// `period_s` (see the module documentation); `None` for a period that is not a positive finite
/// number or samples that do not hold one span of whole periods.
pub fn orbit_drift(times: &[f64], x: &[f64], period_s: f64) -> Option<OrbitDrift> {
    if !(period_s.is_finite() && period_s > 0.0) || times.len() < 2 || times.len() != x.len() {
        return None;
    }
    let (t0, t_end) = (times[0], times[times.len() - 1]);
    let n = ORBIT_DRIFT_PERIODS;
    let held = ((t_end - t0) / period_s + 1e-9).floor() as usize;
    // (centre, mean) of period j, j = 0 the latest
    let mean = |j: usize| {
        let b = t_end - j as f64 * period_s;
        (b - 0.5 * period_s, interval_mean(times, x, b - period_s, b))
    };
    let fit = |from: usize| slope(&(from..from + n).map(mean).collect::<Vec<_>>());
    if held < n {
        return None;
    }
    Some(OrbitDrift {
        period_s,
        span_s: n as f64 * period_s,
        rate: fit(0),
        earlier_rate: (held >= 2 * n).then(|| fit(n)),
    })
}

/// Least-squares slope of the points `(t, m)` (at least two distinct `t`).
fn slope(points: &[(f64, f64)]) -> f64 {
    let k = points.len() as f64;
    let (ts, ms) = points.iter().fold((0.0, 0.0), |(a, b), (t, m)| (a + t, b + m));
    let (tm, mm) = (ts / k, ms / k);
    let (num, den) = points.iter().fold((0.0, 0.0), |(a, b), (t, m)| (a + (t - tm) * (m - mm), b + (t - tm) * (t - tm)));
    num / den
}
