//! The periodic test's candidate orbits (the module documentation of [`super`], point 2): the
//! period from the lead observable's crossings of its mean, refined as the minimiser of the lag
//! differences' variance, and scored by the repetition and the drift of the orbit's mean over
//! `min_cycles + 1` periods ([`OrbitGap`]); over the window `W`, and over longer spans of the
//! kept samples for the orbits too slow for it.

use super::{ranges, SteadyCriterion, Verdict, SLOW_ORBIT_SPANS};

/// The periodic test's candidates over one full window (module documentation, point 2), in
/// the order it tries them: the lead observable's crossing period times 1, 2, 3, refined, as
/// long as `min_cycles + 1` of them fit in the window (none when the lead observable does not
/// cross its mean `min_cycles` times), each scored by [`orbit_gap`].
pub(super) fn window_orbits(times: &[f64], rows: &[&[f64]], c: &SteadyCriterion) -> Vec<OrbitGap> {
    let (t0, t1) = (times[0], times[times.len() - 1]);
    let mut out = Vec::new();
    let Some((cols, p0)) = lead_period(times, rows, c) else { return out };
    for m in 1..=3 {
        let guess = m as f64 * p0;
        if (c.min_cycles + 1) as f64 * guess * 0.9 > t1 - t0 {
            break;
        }
        let Some(p) = refine_period(times, &cols, &c.tolerances, guess) else { break };
        if (c.min_cycles + 1) as f64 * p > t1 - t0 + 1e-9 * c.window_s {
            continue;
        }
        out.push(orbit_gap(times, &cols, &c.tolerances, p));
    }
    out
}

/// The samples as columns (`cols[k]` observable `k`) and the crossing period of the lead
/// observable, the one whose range over the samples is the largest over its tolerance; `None`
/// when it does not cross its mean `min_cycles` times.
fn lead_period(times: &[f64], rows: &[&[f64]], c: &SteadyCriterion) -> Option<(Vec<Vec<f64>>, f64)> {
    let nk = c.tolerances.len();
    let ranges = ranges(rows, nk);
    let lead = (0..nk).max_by(|&a, &b| (ranges[a] / c.tolerances[a]).total_cmp(&(ranges[b] / c.tolerances[b])))?;
    let cols: Vec<Vec<f64>> = (0..nk).map(|k| rows.iter().map(|r| r[k]).collect()).collect();
    let p0 = crossing_period(times, &cols[lead], c.min_cycles)?;
    Some((cols, p0))
}

/// Periodic verdict on an orbit whose `min_cycles + 1` periods do not fit in the window `W`
/// (see [`slow_orbits`]), or `None`.
/// Only the spans of [`SLOW_ORBIT_SPANS`] whose `due` is true are tried (the detector tests a
/// span's periods at its own cadence, [`super::slow_test_interval_s`]).
pub(super) fn slow_orbit(times: &[f64], rows: &[&[f64]], c: &SteadyCriterion, due: &[bool; SLOW_ORBIT_SPANS.len()]) -> Option<Verdict> {
    let g = slow_orbits_of(times, rows, c, due).into_iter().find(|g| g.gap <= 1.0)?;
    Some(Verdict::Periodic {
        t_s: times[times.len() - 1],
        window_start_s: g.window_start_s,
        period_s: g.period_s,
    })
}

/// The candidates for a periodic orbit whose `min_cycles + 1` periods do not fit in the window
/// `W` but do in the samples given (the detector's last [`WINDOW_STRETCH`](super::WINDOW_STRETCH)` W`): the period
/// estimated from the crossings over the last `4 W` of them and, for the periods those cannot
/// hold, over the longer spans of [`SLOW_ORBIT_SPANS`] in turn, refined and scored
/// like [`window_orbits`]'s over the window `[t - (min_cycles + 1) P, t]`. Periods that `W` holds are left to
/// [`window_orbits`].
pub(super) fn slow_orbits(times: &[f64], rows: &[&[f64]], c: &SteadyCriterion) -> Vec<OrbitGap> {
    slow_orbits_of(times, rows, c, &[true; SLOW_ORBIT_SPANS.len()])
}

/// [`slow_orbits`] of the spans whose `due` is true.
fn slow_orbits_of(times: &[f64], rows: &[&[f64]], c: &SteadyCriterion, due: &[bool; SLOW_ORBIT_SPANS.len()]) -> Vec<OrbitGap> {
    let t1 = times[times.len() - 1];
    let eps = 1e-9 * c.window_s;
    let mut out = Vec::new();
    // the periods the window W holds are window_orbits'; each stage adds the ones the samples
    // of the stages before could not hold
    let mut held = c.window_s;
    for (stretch, &due) in SLOW_ORBIT_SPANS.into_iter().zip(due) {
        if due {
            // as `record` keeps them: from the last sample at or before t1 - stretch W
            let from = times.partition_point(|&t| t <= t1 - stretch * c.window_s + eps).saturating_sub(1);
            out.extend(slow_orbits_over(&times[from..], &rows[from..], c, held));
        }
        held = stretch * c.window_s;
    }
    out
}

/// [`slow_orbits`] over the samples `times` (the last `stretch W` of them, one older sample) for
/// the periods whose `min_cycles + 1` do not fit in `held` (s): the period estimated from the
/// crossings over these samples, refined and scored over `[t - (min_cycles + 1) P, t]`.
fn slow_orbits_over(times: &[f64], rows: &[&[f64]], c: &SteadyCriterion, held: f64) -> Vec<OrbitGap> {
    let t1 = times[times.len() - 1];
    let span = t1 - times[0];
    let mut out = Vec::new();
    if span <= held {
        return out;
    }
    let Some((cols, p0)) = lead_period(times, rows, c) else { return out };
    let cycles = (c.min_cycles + 1) as f64;
    let eps = 1e-9 * c.window_s;
    // the samples of [t1 - len, t1]
    let tail = |len: f64| times.partition_point(|&t| t < t1 - len - eps);
    for m in 1..=3 {
        let guess = m as f64 * p0;
        if cycles * guess * 1.1 <= held {
            continue; // W holds it (window_orbits'), or a shorter stage's samples
        }
        if cycles * guess * 0.9 > span {
            break;
        }
        let from = tail(cycles * guess * 1.1);
        let sub: Vec<Vec<f64>> = cols.iter().map(|x| x[from..].to_vec()).collect();
        let Some(p) = refine_period(&times[from..], &sub, &c.tolerances, guess) else { break };
        let len = cycles * p;
        if len <= held || len > span + eps {
            continue;
        }
        let from = tail(len);
        let (ts, sub): (&[f64], Vec<Vec<f64>>) = (&times[from..], cols.iter().map(|x| x[from..].to_vec()).collect());
        if ts.len() >= c.min_samples {
            out.push(orbit_gap(ts, &sub, &c.tolerances, p));
        }
    }
    out
}

/// What sets a candidate orbit's [`OrbitGap`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OrbitPart {
    /// The repetition: `|x_k(t_i) - x_k(t_i - P)| / tol_k`, largest over the window.
    Repeat,
    /// The drift of the orbit's mean between the window's first and last period, over `tol_k`.
    Drift,
}

impl OrbitPart {
    /// `repeat` or `drift`.
    pub fn name(&self) -> &'static str {
        match self {
            OrbitPart::Repeat => "repeat",
            OrbitPart::Drift => "drift",
        }
    }
}

/// How far a candidate orbit of period `period_s` is from the periodic test (module
/// documentation, point 2): the larger of its repetition and its mean drift over the window,
/// each over its observable's tolerance. The test accepts the orbit when `gap <= 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitGap {
    /// `max(repetition, drift)` in units of the tolerances (dimensionless).
    pub gap: f64,
    /// Which of the two sets `gap`.
    pub part: OrbitPart,
    /// The observable that sets it (its index in the criterion's tolerances, [`OBSERVABLE_NAMES`](super::OBSERVABLE_NAMES)
    /// for the default observables).
    pub observable: usize,
    /// The candidate's period (s).
    pub period_s: f64,
    /// The start of the window it was judged over (s).
    pub window_start_s: f64,
}

/// The periodic test's score of period `p` over the samples `times` (`cols[k]` observable `k`).
fn orbit_gap(times: &[f64], cols: &[Vec<f64>], tol: &[f64], p: f64) -> OrbitGap {
    let (repeat, kr) = max_lag_difference(times, cols, tol, p);
    let (drift, kd) = max_mean_drift(times, cols, tol, p);
    let (gap, part, observable) = if repeat >= drift { (repeat, OrbitPart::Repeat, kr) } else { (drift, OrbitPart::Drift, kd) };
    OrbitGap { gap, part, observable, period_s: p, window_start_s: times[0] }
}

/// Period from the upward crossings of the mean (hysteresis 10 % of the range):
/// the median spacing of the crossings, if at least `min_cycles` full cycles are seen.
fn crossing_period(times: &[f64], x: &[f64], min_cycles: usize) -> Option<f64> {
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let lo = x.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let h = 0.1 * (hi - lo);
    if h <= 0.0 {
        return None;
    }
    let mut crossings = Vec::new();
    let mut below = x[0] < mean - h;
    let mut last_under = if x[0] < mean { Some(0) } else { None };
    for j in 1..x.len() {
        if x[j] < mean {
            last_under = Some(j);
        }
        if x[j] < mean - h {
            below = true;
        } else if below && x[j] > mean + h {
            below = false;
            // the crossing of the mean between the last sample under it and the next one
            if let Some(i) = last_under {
                let (xa, xb) = (x[i], x[i + 1]);
                let f = if xb != xa {
                    (mean - xa) / (xb - xa)
                } else {
                    0.0
                };
                crossings.push(times[i] + f * (times[i + 1] - times[i]));
            }
        }
    }
    if crossings.len() < min_cycles + 1 {
        return None;
    }
    let mut gaps: Vec<f64> = crossings.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_by(f64::total_cmp);
    Some(gaps[gaps.len() / 2])
}

/// Linear interpolation of `x` at time `t` (clamped to the ends); `hint` is a
/// running index for monotone queries.
fn interp(times: &[f64], x: &[f64], t: f64, hint: &mut usize) -> f64 {
    let n = times.len();
    while *hint + 1 < n && times[*hint + 1] < t {
        *hint += 1;
    }
    while *hint > 0 && times[*hint] > t {
        *hint -= 1;
    }
    let i = *hint;
    if i + 1 >= n {
        return x[n - 1];
    }
    let (ta, tb) = (times[i], times[i + 1]);
    let f = ((t - ta) / (tb - ta)).clamp(0.0, 1.0);
    x[i] + f * (x[i + 1] - x[i])
}

/// Mean of the piecewise linear interpolant of `x` over `[a, b]` (inside the sampled range).
pub(super) fn interval_mean(times: &[f64], x: &[f64], a: f64, b: f64) -> f64 {
    let mut hint = 0;
    let mut total = 0.0;
    let mut t_prev = a;
    let mut x_prev = interp(times, x, a, &mut hint);
    for (i, &t) in times.iter().enumerate() {
        if t <= a || t >= b {
            continue;
        }
        total += 0.5 * (x_prev + x[i]) * (t - t_prev);
        (t_prev, x_prev) = (t, x[i]);
    }
    let x_b = interp(times, x, b, &mut hint);
    total += 0.5 * (x_prev + x_b) * (b - t_prev);
    total / (b - a)
}

/// Largest normalised drift of the orbit's mean across the window,
/// `max_k |mean_{[t_n - P, t_n]} x_k - mean_{[t_0, t_0 + P]} x_k| / tol_k`, and its `k`.
fn max_mean_drift(times: &[f64], cols: &[Vec<f64>], tol: &[f64], period: f64) -> (f64, usize) {
    let (t0, t1) = (times[0], times[times.len() - 1]);
    cols.iter()
        .zip(tol)
        .map(|(x, tol)| (interval_mean(times, x, t1 - period, t1) - interval_mean(times, x, t0, t0 + period)).abs() / tol)
        .enumerate()
        .fold((0.0, 0), |best, (k, d)| if d > best.0 { (d, k) } else { best })
}

/// Lag energy `E(tau) = sum_k var_i((x_k(t_i) - x_k(t_i - tau)) / tol_k)` over samples with
/// `t_i - tau >= t_0`. The variance (not the mean square) of the lag differences is used so
/// that a slow drift (a constant lag difference) does not bias the period; the drift itself
/// is judged afterwards by [`max_lag_difference`].
fn lag_energy(times: &[f64], cols: &[Vec<f64>], tol: &[f64], tau: f64) -> f64 {
    let t0 = times[0];
    let mut total = 0.0;
    for (k, x) in cols.iter().enumerate() {
        let mut hint = 0;
        let (mut sum, mut sum2, mut count) = (0.0, 0.0, 0usize);
        for (i, &t) in times.iter().enumerate() {
            if t - tau < t0 {
                continue;
            }
            let d = (x[i] - interp(times, x, t - tau, &mut hint)) / tol[k];
            sum += d;
            sum2 += d * d;
            count += 1;
        }
        if count < 2 {
            return f64::INFINITY;
        }
        let m = sum / count as f64;
        total += sum2 / count as f64 - m * m;
    }
    total
}

/// Largest normalised lag difference `max_{i,k} |x_k(t_i) - x_k(t_i - tau)| / tol_k`, and its `k`.
fn max_lag_difference(times: &[f64], cols: &[Vec<f64>], tol: &[f64], tau: f64) -> (f64, usize) {
    let t0 = times[0];
    let mut worst = (0.0, 0);
    for (k, x) in cols.iter().enumerate() {
        let mut hint = 0;
        for (i, &t) in times.iter().enumerate() {
            if t - tau < t0 - 1e-12 * tau {
                continue;
            }
            let d = (x[i] - interp(times, x, (t - tau).max(t0), &mut hint)).abs() / tol[k];
            if d > worst.0 {
                worst = (d, k);
            }
        }
    }
    worst
}

/// Minimise `E(tau)` on 41 lags over `guess +- 10 %`, then a parabola through the best three.
fn refine_period(times: &[f64], cols: &[Vec<f64>], tol: &[f64], guess: f64) -> Option<f64> {
    const N: usize = 41;
    let (a, b) = (0.9 * guess, 1.1 * guess);
    let step = (b - a) / (N - 1) as f64;
    let e: Vec<f64> = (0..N)
        .map(|j| lag_energy(times, cols, tol, a + j as f64 * step))
        .collect();
    let j = (0..N).min_by(|&p, &q| e[p].total_cmp(&e[q]))?;
    if !e[j].is_finite() {
        return None;
    }
    let tau = a + j as f64 * step;
    if j == 0 || j == N - 1 {
        return Some(tau);
    }
    let (em, e0, ep) = (e[j - 1], e[j], e[j + 1]);
    let denom = em - 2.0 * e0 + ep;
    let shift = if denom > 0.0 {
        0.5 * (em - ep) / denom
    } else {
        0.0
    };
    Some(tau + shift.clamp(-1.0, 1.0) * step)
}
