//! The drift of an orbit's mean and its trend (`rbc_solver::steady::orbit_drift`) on series whose
//! period means are known in closed form.

use rbc_solver::steady::{drift_interval_s, orbit_drift, OrbitGap, OrbitPart, SteadyCriterion, SteadyDetector, ORBIT_DRIFT_PERIODS};
use std::f64::consts::PI;

/// Samples every `dt` from 0 to `t_end` of a swing of period `p` (a sine and a harmonic, whose
/// period means vanish) on top of `base(t)`.
fn swing(dt: f64, t_end: f64, p: f64, base: impl Fn(f64) -> f64) -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..=(t_end / dt).round() as usize).map(|i| i as f64 * dt).collect();
    let x = t.iter().map(|&t| base(t) + 0.2 * (2.0 * PI * t / p).sin() + 0.05 * (4.0 * PI * t / p + 0.3).sin()).collect();
    (t, x)
}

/// A mean that moves linearly at `a` um/s: both fits give `a` (the period means of a line lie on a
/// line of the same slope), over spans of four periods.
#[test]
fn a_steady_drift_is_its_own_rate_before_and_after() {
    assert_eq!(ORBIT_DRIFT_PERIODS, 4);
    for p in [0.77, 0.3, 0.217, 0.05] {
        let a = -0.02;
        let (t, x) = swing(2e-4, 6.5, p, |t| 0.8 + a * t);
        let d = orbit_drift(&t, &x, p).unwrap();
        assert!((d.span_s - 4.0 * p).abs() < 1e-12, "P {p}: span {}", d.span_s);
        assert!((d.rate - a).abs() < 1e-5, "P {p}: rate {} against {a}", d.rate);
        let e = d.earlier_rate.unwrap();
        assert!((e - a).abs() < 1e-5, "P {p}: earlier rate {e} against {a}");
    }
}

/// A cell leaving an unstable orbit, `0.8 - 0.01 exp(t / 2.9 s)`, and one settling onto a stable
/// one, `0.8 + 0.1 exp(-t / 0.5 s)`: the period means of `c exp(t / tau)` are `c exp(t_j / tau)`
/// times one factor, and so are the slopes fitted through equally spaced ones, so the rate over
/// the earlier rate is exactly `exp(D / tau)` for the span `D`: > 1 (speeding up) when leaving,
/// < 1 when settling.
#[test]
fn leaving_an_orbit_speeds_up_and_settling_slows_down() {
    let p = 0.217;
    let (t, x) = swing(2e-4, 5.5, p, |t| 0.8 - 0.01 * (t / 2.9).exp());
    let d = orbit_drift(&t, &x, p).unwrap();
    let e = d.earlier_rate.unwrap();
    let ratio = d.rate / e;
    println!("leaving: rate {:.5} um/s, earlier {e:.5}, ratio {ratio:.5} against {:.5}", d.rate, (d.span_s / 2.9).exp());
    assert!(d.rate < 0.0 && e < 0.0 && ratio > 1.0);
    assert!((ratio / (d.span_s / 2.9).exp() - 1.0).abs() < 1e-3, "ratio {ratio}");
    // the rate is the derivative at the span's centre to the exponential's curvature over it
    let centre = 5.5 - 0.5 * d.span_s;
    let derivative = -0.01 / 2.9 * (centre / 2.9).exp();
    assert!((d.rate / derivative - 1.0).abs() < 0.02, "rate {} against {derivative}", d.rate);

    let (t, x) = swing(2e-4, 5.5, p, |t| 0.8 + 0.1 * (-t / 0.5).exp());
    let d = orbit_drift(&t, &x, p).unwrap();
    let e = d.earlier_rate.unwrap();
    assert!(d.rate < 0.0 && e < d.rate, "settling: {d:?}");
    assert!((d.rate / e / (-d.span_s / 0.5).exp() - 1.0).abs() < 1e-3, "settling: {d:?}");
}

/// What it cannot answer: a period that is not a positive number, samples shorter than one span
/// (no rate), shorter than two (no earlier rate).
#[test]
fn too_few_periods_give_no_rate_or_no_earlier_rate() {
    let p = 0.217;
    let (t, x) = swing(2e-4, 6.0, p, |t| 0.8 - 0.02 * t);
    for bad in [0.0, -0.2, f64::NAN, f64::INFINITY] {
        assert_eq!(orbit_drift(&t, &x, bad), None, "period {bad}");
    }
    let cut = |s: f64| t.partition_point(|&t| t <= s + 1e-9);
    // one span is 4 P = 0.868 s: 0.86 s of samples hold 3 periods
    let k = cut(0.86);
    assert_eq!(orbit_drift(&t[..k], &x[..k], p), None);
    let k = cut(1.7);
    let d = orbit_drift(&t[..k], &x[..k], p).unwrap();
    assert!((d.rate + 0.02).abs() < 1e-5 && d.earlier_rate.is_none(), "{d:?}");
    let k = cut(8.0 * p + 1e-3);
    assert!(orbit_drift(&t[..k], &x[..k], p).unwrap().earlier_rate.is_some());
    assert_eq!(orbit_drift(&t[..3], &x[..2], p), None, "mismatched lengths");
}

/// A running run's detector keeps the last WINDOW_STRETCH W of its samples (here 32 x 0.5 s = 16 s
/// of 20 s), more than the two spans of 4 periods the drift fits: its drift is the free function's
/// on the whole series, the earlier rate included. (The drift reads only the last two spans, so
/// this holds for any kept stretch of at least 8 periods; a detector that kept only its window,
/// 0.5 s, would have no earlier rate and another rate.)
#[test]
fn the_detector_measures_it_as_on_the_whole_series() {
    let (p, t_end) = (0.217, 20.0);
    let (t, x) = swing(1e-3, t_end, p, |t| 0.8 - 0.01 * (t / 9.0).exp());
    let c = SteadyCriterion { window_s: 0.5, max_time_s: 100.0, min_cycles: 3, min_samples: 20, tolerances: vec![1e-6, 1.0] };
    let kept_s = rbc_solver::steady::WINDOW_STRETCH * c.window_s;
    assert!(kept_s < t_end && kept_s > 8.0 * p);
    let mut d = SteadyDetector::new(c).unwrap();
    for (t, x) in t.iter().zip(&x) {
        assert!(!d.push(*t, &[*x, 0.1]).unwrap().is_decided());
    }
    let whole = orbit_drift(&t, &x, p).unwrap();
    assert_eq!(d.orbit_drift(p), Some(whole));
    assert!(whole.earlier_rate.is_some());
    let window = t.partition_point(|&s| s < t_end - 0.5);
    assert_ne!(orbit_drift(&t[window..], &x[window..], p), Some(whole), "the window alone gives another drift");
}

/// With no candidate orbit the means are taken over quarters of the window, so each fit spans one
/// window: a croissant creeping off the axis at 0.07 um/s (less than the study's 0.05 um
/// tolerance per 0.5 s window, so the steady test alone passes it) reads 0.07 um/s over the last
/// window and the one before; one settling, `0.04 + 0.05 exp(-t / 0.3 s)`, slows by `exp(-W /
/// tau)` from one window to the next. With a candidate the interval is its period.
#[test]
fn with_no_orbit_the_drift_is_over_windows() {
    let w = 0.5;
    assert_eq!(drift_interval_s(None, w), w / ORBIT_DRIFT_PERIODS as f64);
    let orbit = OrbitGap { gap: 1.3, part: OrbitPart::Drift, observable: 0, period_s: 0.217, window_start_s: 1.0 };
    assert_eq!(drift_interval_s(Some(&orbit), w), 0.217);
    let t: Vec<f64> = (0..=10_000).map(|i| i as f64 * 2e-4).collect();
    let creep: Vec<f64> = t.iter().map(|&t| 0.01 + 0.07 * t).collect();
    let d = orbit_drift(&t, &creep, drift_interval_s(None, w)).unwrap();
    assert!((d.span_s - w).abs() < 1e-12 && (d.rate - 0.07).abs() < 1e-9 && (d.earlier_rate.unwrap() - 0.07).abs() < 1e-9, "{d:?}");
    let settle: Vec<f64> = t.iter().map(|&t| 0.04 + 0.05 * (-t / 0.3).exp()).collect();
    let d = orbit_drift(&t, &settle, drift_interval_s(None, w)).unwrap();
    let e = d.earlier_rate.unwrap();
    assert!(d.rate < 0.0 && e < d.rate && (d.rate / e / (-w / 0.3f64).exp() - 1.0).abs() < 1e-6, "{d:?}");
}
