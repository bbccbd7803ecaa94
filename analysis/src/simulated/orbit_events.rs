//! The moments a cell stops lying along the flow: its length along the channel axis (the x
//! extent of its bounding box) collapses, as when a slipper turns over about z (the paper's
//! tumbling: "the cell rotates around the z-axis while approximately preserving its shape") or
//! folds (its two shortest axes nearly equal) and comes out lying flat again.
//!
//! A collapse is a stretch of samples whose x extent lies below `fraction` times the median x
//! extent over the run's samples (a robust measure of the cell's usual length along the flow:
//! a slipper or croissant spends most of its time lying along it); its time is the minimum of the
//! x extent, refined by the parabola through the lowest sample and its two neighbours. A stretch
//! that begins at the first sample is the start shape (a discocyte facing the flow), not an
//! event, and one still open at the last sample is not yet complete: both are left out.
//!
//! Measured on the two studies' runs (`science-6p5`, `science-6p5-penalty`, samples every 0.2
//! ms): after their first 0.1 s the ended runs' x extents never fall below 0.86 of their median
//! (the slippers' swings; the one deeper dip, to 0.80, is the exact-wall ~6.5 mm/s r_init 0.6 um
//! run's start transient at 0.07 s), a fold takes it to 0.74-0.78 and a turn-over to 0.55-0.60,
//! so the default `fraction` 0.82 keeps both kinds of event and no swing. The depth alone does
//! not tell the kinds apart: the slow runs' first overturn from the start reaches only 0.74-0.78,
//! as deep as a fold. How far the cell reaches across the flow meanwhile does: turning over it
//! passes broadside, its largest y extent during the event 0.94-1.0 of its usual length along the
//! flow (`across`); folding it reaches 0.79-0.83 (`tests/science_6p5.rs`).
//!
//! There is no hysteresis: noise crossing the threshold near an event's bottom would split it
//! into events a few samples apart (the studies' samples, every 0.2 ms, are smooth on that scale).
//! Samples whose x extent is not finite count as above the threshold (the results reader refuses
//! them before they get here).

use rbc_schema::results::TimeSample;

/// The default `fraction` of [`length_collapses`]: between the deepest swing of the studies'
/// steady orbits (0.86) and the shallowest fold (0.78).
pub const DEFAULT_FRACTION: f64 = 0.82;

/// One collapse of the cell's length along the flow.
#[derive(Debug, Clone, PartialEq)]
pub struct Collapse {
    /// The time of the least x extent, s: the vertex of the parabola through the lowest sample
    /// and its two neighbours, so it may lie up to one sample interval outside
    /// [`start_s`, `end_s`] when the lowest sample is the stretch's first or last.
    pub t_s: f64,
    /// The first sample below the threshold, s.
    pub start_s: f64,
    /// The last sample below the threshold, s.
    pub end_s: f64,
    /// The least x extent (the lowest sample), um.
    pub x_min_um: f64,
    /// `x_min_um` over the run's median x extent (dimensionless).
    pub x_min_rel: f64,
    /// The largest y extent during the collapse, um.
    pub y_max_um: f64,
    /// `y_max_um` over the run's median x extent (dimensionless; ~1 when the cell passes
    /// broadside to the flow).
    pub across: f64,
    /// The time since the previous collapse, s (`None` for the first).
    pub interval_s: Option<f64>,
}

/// The collapses of the x extent of `samples` (in time order) below `fraction` times its median
/// (see the module doc). Empty for fewer than three samples, or a `fraction` or median that is
/// not finite.
pub fn length_collapses(samples: &[TimeSample], fraction: f64) -> Vec<Collapse> {
    if samples.len() < 3 {
        return Vec::new();
    }
    let x: Vec<f64> = samples.iter().map(|s| s.extents_um[0]).collect();
    let median = crate::stats::median::median(&mut x.clone()).expect("three samples or more");
    let threshold = fraction * median;
    if !threshold.is_finite() {
        return Vec::new();
    }
    let below = |v: f64| v < threshold;
    let mut out: Vec<Collapse> = Vec::new();
    let mut i = 0;
    while i < x.len() {
        if !below(x[i]) {
            i += 1;
            continue;
        }
        let start = i;
        while i < x.len() && below(x[i]) {
            i += 1;
        }
        let end = i - 1;
        if start == 0 || i == x.len() {
            continue;
        }
        let k = (start..=end).min_by(|&a, &b| x[a].total_cmp(&x[b])).unwrap();
        let t_s = refined_minimum(samples, &x, k);
        let y_max_um = samples[start..=end].iter().map(|s| s.extents_um[1]).fold(f64::NEG_INFINITY, f64::max);
        let interval_s = out.last().map(|c| t_s - c.t_s);
        out.push(Collapse { t_s, start_s: samples[start].t_s, end_s: samples[end].t_s, x_min_um: x[k], x_min_rel: x[k] / median, y_max_um, across: y_max_um / median, interval_s });
    }
    out
}

/// The time of the minimum of the parabola through samples `k - 1`, `k`, `k + 1` (uniform or
/// not), clamped to their span; the sample's own time at either end of the series or where the
/// three times are not increasing.
fn refined_minimum(samples: &[TimeSample], x: &[f64], k: usize) -> f64 {
    if k == 0 || k + 1 >= x.len() {
        return samples[k].t_s;
    }
    let (t0, t1, t2) = (samples[k - 1].t_s, samples[k].t_s, samples[k + 1].t_s);
    if !(t0 < t1 && t1 < t2) {
        return t1;
    }
    let (x0, x1, x2) = (x[k - 1], x[k], x[k + 1]);
    // vertex of the interpolating parabola (divided differences)
    let d01 = (x1 - x0) / (t1 - t0);
    let d12 = (x2 - x1) / (t2 - t1);
    let curvature = (d12 - d01) / (t2 - t0);
    if curvature <= 0.0 || !curvature.is_finite() {
        return t1;
    }
    let t = 0.5 * (t0 + t1) - d01 / (2.0 * curvature);
    t.clamp(t0, t2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t_s: f64, extents_um: [f64; 3]) -> TimeSample {
        TimeSample { t_s, centroid_um: [0.0; 3], velocity_mm_s: [0.0; 3], area_um2: 135.0, volume_um3: 94.0, asphericity: 0.1, extents_um }
    }

    /// A rigid disc (radius `a`, half-thickness `c`) turning about z at `omega` (rad/s) from
    /// lying along the flow (its normal along y): its extents along x and y.
    fn tumbling_disc(t: f64, omega: f64) -> [f64; 3] {
        let (a, c) = (4.0, 1.3);
        let th = omega * t;
        [2.0 * (a * a * th.cos().powi(2) + c * c * th.sin().powi(2)).sqrt(), 2.0 * (a * a * th.sin().powi(2) + c * c * th.cos().powi(2)).sqrt(), 2.0 * a]
    }

    #[test]
    fn a_tumbling_disc_collapses_at_each_half_turn() {
        // a half turn every 1.0503 s (between the samples), sampled every 0.2 ms from a start
        // facing the flow
        let period = 1.0503;
        let omega = std::f64::consts::PI / period;
        let samples: Vec<TimeSample> = (0..=32_000).map(|i| 0.2e-3 * i as f64).map(|t| sample(t, tumbling_disc(t - 0.5 * period, omega))).collect();
        let c = length_collapses(&samples, DEFAULT_FRACTION);
        // the start (facing the flow) is left out; the disc faces the flow again every period,
        // and the sixth time (6.30 s, below the threshold from 6.11 s) is cut by the end of the
        // series (6.4 s)
        let expected: Vec<f64> = (1..=5).map(|k| period * k as f64).collect();
        assert_eq!(c.len(), expected.len(), "{c:?}");
        for (e, t) in c.iter().zip(&expected) {
            assert!((e.t_s - t).abs() < 1e-6, "at {} s, expected {t}", e.t_s);
            assert!((e.x_min_um - 2.6).abs() < 1e-4, "{}", e.x_min_um);
            // the disc passes broadside: its diameter across the flow, 8 um, over the median
            // length along it (5.95 um)
            assert!(e.across > 1.3, "{}", e.across);
        }
        for e in &c[1..] {
            assert!((e.interval_s.unwrap() - period).abs() < 2e-6);
        }
        assert_eq!(c[0].interval_s, None);
    }

    #[test]
    fn a_swing_shallower_than_the_fraction_is_no_event() {
        // a slipper's swing: x extent 7.2 um +- 0.5 um (0.93 of the median at its lowest)
        let samples: Vec<TimeSample> = (0..10_000).map(|i| 0.2e-3 * i as f64).map(|t| sample(t, [7.2 + 0.5 * (2.0 * std::f64::consts::PI * t / 0.33).sin(), 6.0, 7.0])).collect();
        assert!(length_collapses(&samples, DEFAULT_FRACTION).is_empty());
        // the same with a fraction above the swing's depth: one collapse per period
        let c = length_collapses(&samples, 0.95);
        assert!(c.len() >= 5, "{c:?}");
        for e in &c {
            let phase = (e.t_s / 0.33).fract();
            assert!((phase - 0.75).abs() < 1e-4, "the minimum at 3/4 period: {phase}");
        }
    }

    #[test]
    fn the_minimum_is_refined_between_unevenly_spaced_samples() {
        // x = 5 + (t - 0.37)^2 sampled at uneven times: the parabola through three samples is exact
        // (the median, 10 um, is the cell lying along the flow before and after)
        let dip = [0.1, 0.25, 0.33, 0.41, 0.6];
        let flat = [0.0, 0.02, 0.05, 0.07, 0.7, 0.8, 0.85, 0.9];
        let mut samples: Vec<TimeSample> = dip.iter().map(|&t| sample(t, [5.0 + (t - 0.37f64).powi(2), 6.0, 7.0])).chain(flat.iter().map(|&t| sample(t, [10.0, 6.0, 7.0]))).collect();
        samples.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        let c = length_collapses(&samples, 0.9);
        assert_eq!(c.len(), 1, "{c:?}");
        assert!((c[0].t_s - 0.37).abs() < 1e-12, "{}", c[0].t_s);
        assert_eq!((c[0].start_s, c[0].end_s), (0.1, 0.6));
    }

    #[test]
    fn a_nan_or_a_time_running_back_gives_an_answer_not_a_panic() {
        let xs = [8.0, 8.0, 5.0, 4.0, 5.0, 8.0, 8.0, 8.0];
        let series = |x: &[f64], t: &dyn Fn(usize) -> f64| -> Vec<TimeSample> { x.iter().enumerate().map(|(i, &x)| sample(t(i), [x, 6.0, 7.0])).collect() };
        let even = |i: usize| i as f64;
        // a NaN at the start, inside the collapse, or as the fraction
        let mut x = xs.to_vec();
        x[0] = f64::NAN;
        assert_eq!(length_collapses(&series(&x, &even), DEFAULT_FRACTION).len(), 1);
        x[3] = f64::NAN;
        let c = length_collapses(&series(&x, &even), DEFAULT_FRACTION);
        assert_eq!(c.iter().map(|e| (e.start_s, e.end_s)).collect::<Vec<_>>(), [(2.0, 2.0), (4.0, 4.0)]);
        assert!(length_collapses(&series(&xs, &even), f64::NAN).is_empty());
        // times running back around the lowest sample: its own time
        let back = |i: usize| if i == 4 { 2.5 } else { i as f64 };
        let c = length_collapses(&series(&xs, &back), DEFAULT_FRACTION);
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].t_s, 3.0);
    }

    #[test]
    fn a_series_too_short_or_open_at_an_end_has_no_event() {
        assert!(length_collapses(&[], DEFAULT_FRACTION).is_empty());
        assert!(length_collapses(&[sample(0.0, [2.0, 8.0, 8.0]), sample(0.1, [8.0, 2.0, 8.0])], DEFAULT_FRACTION).is_empty());
        // a collapse still going at the last sample is not complete
        let samples: Vec<TimeSample> = [8.0, 8.0, 8.0, 8.0, 5.0, 4.0].iter().enumerate().map(|(i, &x)| sample(i as f64, [x, 6.0, 7.0])).collect();
        assert!(length_collapses(&samples, DEFAULT_FRACTION).is_empty());
    }
}
