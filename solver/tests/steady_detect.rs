//! Steady-state detector on analytic time series: exponential convergence (detected at the
//! predicted time), periodic orbits (right period), quasi-periodic and drifting series (unsteady).

use rbc_schema::results::TimeSample;
use rbc_solver::steady::{
    detect, window_stats, SteadyCriterion, SteadyDetector, SteadyError, Verdict,
};
use std::f64::consts::PI;

/// Uniform samples `t_i = i dt`, `i = 0..n`, of the observables `f(t)`.
fn series(dt: f64, n: usize, f: impl Fn(f64) -> Vec<f64>) -> (Vec<f64>, Vec<Vec<f64>>) {
    let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
    let x = t.iter().map(|&t| f(t)).collect();
    (t, x)
}

fn criterion(window_s: f64, max_time_s: f64, tolerances: Vec<f64>) -> SteadyCriterion {
    SteadyCriterion {
        window_s,
        max_time_s,
        min_cycles: 3,
        min_samples: 20,
        tolerances,
    }
}

#[test]
fn exponential_convergence_is_detected_at_the_predicted_time() {
    // two observables, x0 = 1 + 2 exp(-t/0.3), x1 = 0.5 exp(-t/0.1); range over [t - W, t] is
    // a exp(-(t-W)/tau) (1 - exp(-W/tau)) <= tol from t* = W + tau ln(a (1 - exp(-W/tau)) / tol)
    let (w, tol, dt) = (0.5, 0.01, 1e-3);
    let (t, x) = series(dt, 4000, |t| {
        vec![1.0 + 2.0 * (-t / 0.3).exp(), 0.5 * (-t / 0.1).exp()]
    });
    let t_star = |a: f64, tau: f64| w + tau * (a * (1.0 - (-w / tau).exp()) / tol).ln();
    let predicted = t_star(2.0, 0.3).max(t_star(0.5, 0.1));
    let v = detect(&criterion(w, 3.9, vec![tol, tol]), &t, &x).unwrap();
    let Verdict::Steady {
        t_s,
        window_start_s,
    } = v
    else {
        panic!("expected steady, got {v:?}")
    };
    println!(
        "exponential: detected at {t_s:.4} s, predicted first sample at or after {predicted:.4} s"
    );
    // detection is the first sample at or after t* (sampling resolution dt)
    assert!(
        t_s >= predicted - 1e-9 && t_s < predicted + dt + 1e-9,
        "detected {t_s}, predicted {predicted}"
    );
    assert!((t_s - window_start_s - w).abs() < 1e-9);
}

#[test]
fn periodic_orbit_is_detected_with_its_period() {
    // a periodic orbit (period P, two harmonics) on top of a decaying transient; a second
    // observable oscillates at twice the frequency (a shape measure of a symmetric contraction)
    let (p, w, tol, dt, tau) = (0.0937, 0.5, 0.01, 1e-3, 0.2);
    let f = move |t: f64| {
        vec![
            1.0 + 0.3 * (2.0 * PI * t / p).sin()
                + 0.1 * (4.0 * PI * t / p + 0.7).sin()
                + 0.5 * (-t / tau).exp(),
            0.05 * (2.0 * PI * t / p).sin().powi(2),
        ]
    };
    let (t, x) = series(dt, 3000, f);
    let v = detect(&criterion(w, 2.9, vec![tol, tol]), &t, &x).unwrap();
    let Verdict::Periodic { t_s, period_s, .. } = v else {
        panic!("expected periodic, got {v:?}")
    };
    // the transient changes by 0.5 e^{-s/tau} (1 - e^{-P/tau}) over one period starting at s; the
    // oldest compared pair starts at the window start s = t - W, so the lag test passes from
    let lag_bound = w + tau * (0.5 * (1.0 - (-p / tau).exp()) / tol).ln();
    // its mean over [s, s + P] is 0.5 (tau / P) e^{-s/tau} (1 - e^{-P/tau}): the means over the
    // window's first and last period differ by at most tol from
    let drift_bound = w + tau * (0.5 * tau / p * (1.0 - (-p / tau).exp()) * (1.0 - (-(w - p) / tau).exp()) / tol).ln();
    let bound = lag_bound.max(drift_bound);
    assert!(drift_bound > lag_bound + 0.1, "the mean drift decides here: {drift_bound} vs {lag_bound}");
    println!("periodic: detected at {t_s:.4} s (transient bound {bound:.4} s), period {period_s:.6} s vs {p} s");
    assert!(
        (period_s / p - 1.0).abs() < 2e-3,
        "period {period_s} vs {p}"
    );
    // within 10 samples: the residual period error (|x'| dP ~ 1e-3 here) shifts it slightly
    assert!(
        (t_s - bound).abs() < 10.0 * dt,
        "detected at {t_s}, bound {bound}"
    );
}

#[test]
fn two_humped_orbit_reports_the_full_period_not_half() {
    // sin(u) + 0.9 sin(2u): the mean is crossed twice per period with large hysteresis margins
    let (p, dt) = (0.05, 5e-4);
    let (t, x) = series(dt, 4000, |t| {
        let u = 2.0 * PI * t / p;
        vec![u.sin() + 0.9 * (2.0 * u).sin()]
    });
    let v = detect(&criterion(0.3, 1.9, vec![0.01]), &t, &x).unwrap();
    let Verdict::Periodic { period_s, .. } = v else {
        panic!("expected periodic, got {v:?}")
    };
    println!("two humps: period {period_s:.6} s vs {p} s");
    assert!((period_s / p - 1.0).abs() < 2e-3, "period {period_s}");
}

#[test]
fn oscillation_below_tolerance_is_steady() {
    let (t, x) = series(1e-3, 2000, |t| {
        vec![1.0 + 0.004 * (2.0 * PI * t / 0.07).sin()]
    });
    let v = detect(&criterion(0.5, 1.9, vec![0.01]), &t, &x).unwrap();
    // range 0.008 <= 0.01: steady as soon as the window is full
    assert_eq!(
        v,
        Verdict::Steady {
            t_s: 0.5,
            window_start_s: 0.0
        }
    );
}

#[test]
fn series_that_never_settle_are_unsteady_at_max_time() {
    let max_t = 1.5;
    // slow drift: range over the window 0.05 > tol
    let (t, x) = series(1e-3, 3000, |t| vec![0.1 * t, 1.0]);
    let v = detect(&criterion(0.5, max_t, vec![0.01, 0.01]), &t, &x).unwrap();
    assert!(
        matches!(v, Verdict::Unsteady { t_s, .. } if (t_s - max_t).abs() < 1e-9),
        "{v:?}"
    );
    // quasi-periodic: incommensurate frequencies never repeat within tolerance
    let (t, x) = series(1e-3, 3000, |t| {
        vec![(2.0 * PI * t / 0.05).sin() + (2.0 * PI * t * 2f64.sqrt() / 0.05).sin()]
    });
    let v = detect(&criterion(0.5, max_t, vec![0.01]), &t, &x).unwrap();
    assert!(matches!(v, Verdict::Unsteady { .. }), "{v:?}");
    // a growing oscillation (period 0.05 s) is not periodic either
    let (t, x) = series(1e-3, 3000, |t| {
        vec![(1.0 + t) * (2.0 * PI * t / 0.05).sin()]
    });
    let v = detect(&criterion(0.5, max_t, vec![0.01]), &t, &x).unwrap();
    assert!(matches!(v, Verdict::Unsteady { .. }), "{v:?}");
    // an orbit that repeats within tolerance period by period (period 0.05 s, drift 0.002 per
    // period) while its mean drifts by 0.018 > tol across the window is not periodic: unsteady
    let (t, x) = series(1e-3, 3000, |t| vec![0.3 * (2.0 * PI * t / 0.05).sin() + 0.04 * t]);
    let v = detect(&criterion(0.5, max_t, vec![0.01]), &t, &x).unwrap();
    assert!(matches!(v, Verdict::Unsteady { .. }), "{v:?}");
    // ... and periodic once the drift is below tolerance across the window (0.009)
    let (t, x) = series(1e-3, 3000, |t| vec![0.3 * (2.0 * PI * t / 0.05).sin() + 0.02 * t]);
    let v = detect(&criterion(0.5, max_t, vec![0.01]), &t, &x).unwrap();
    assert!(matches!(v, Verdict::Periodic { t_s, period_s, .. } if (t_s - 0.5).abs() < 1e-9 && (period_s / 0.05 - 1.0).abs() < 2e-3), "{v:?}");
    // a series that ends before max_time undecided stays pending
    let (t, x) = series(1e-3, 1000, |t| vec![0.1 * t]);
    assert_eq!(
        detect(&criterion(0.5, max_t, vec![0.01]), &t, &x).unwrap(),
        Verdict::Pending
    );
}

#[test]
fn bad_samples_and_criteria_are_refused() {
    let mut d = SteadyDetector::new(criterion(0.5, 1.0, vec![0.01, 0.01])).unwrap();
    // a time that is not a number is refused as the first sample too (no previous one to compare)
    for t in [f64::NAN, f64::INFINITY] {
        assert!(matches!(d.push(t, &[1.0, 1.0]), Err(SteadyError::NonFiniteTime { .. })), "{t}");
    }
    assert!(matches!(
        d.push(0.0, &[1.0]),
        Err(SteadyError::Channels {
            expected: 2,
            found: 1,
            ..
        })
    ));
    assert!(matches!(
        d.push(0.0, &[1.0, f64::NAN]),
        Err(SteadyError::NonFinite { channel: 1, .. })
    ));
    d.push(0.0, &[1.0, 1.0]).unwrap();
    assert!(matches!(
        d.push(0.0, &[1.0, 1.0]),
        Err(SteadyError::TimeOrder { .. })
    ));
    assert!(SteadyDetector::new(criterion(0.0, 1.0, vec![0.01])).is_err());
    assert!(SteadyDetector::new(criterion(0.5, 1.0, vec![-1.0])).is_err());
    assert!(SteadyDetector::new(criterion(0.5, 1.0, vec![])).is_err());
    // a window must hold two samples to measure a change (its count includes one before it)
    let mut few = criterion(0.5, 1.0, vec![0.01]);
    few.min_samples = 2;
    assert!(matches!(SteadyDetector::new(few.clone()), Err(SteadyError::Criterion(m)) if m.contains("min_samples")));
    few.min_samples = 3;
    assert!(SteadyDetector::new(few).is_ok());
}

#[test]
fn window_statistics_of_a_uniform_translation() {
    // centroid x = u t with u = 2 mm/s = 2000 um/s, at y = 0.6, z = -0.8 (radial 1.0 um)
    let samples: Vec<TimeSample> = (0..101)
        .map(|i| {
            let t = i as f64 * 1e-3;
            TimeSample {
                t_s: t,
                centroid_um: [2000.0 * t, 0.6, -0.8],
                velocity_mm_s: [2.0 + 0.1 * (i % 2) as f64, 0.0, 0.0],
                area_um2: 140.0,
                volume_um3: 100.0,
                asphericity: 0.1,
                extents_um: [8.0, 4.0 + 0.01 * i as f64, 3.0],
            }
        })
        .collect();
    let s = window_stats(&samples, (0.05, 0.1)).unwrap();
    assert_eq!(s.n, 51);
    assert!((s.duration_s - 0.05).abs() < 1e-12);
    assert!((s.velocity_mean_mm_s - 2.0).abs() < 1e-9);
    assert_eq!((s.velocity_min_mm_s, s.velocity_max_mm_s), (2.0, 2.1));
    assert!((s.radial_mean_um - 1.0).abs() < 1e-12 && (s.radial_max_um - 1.0).abs() < 1e-12);
    assert!((s.y_mean_um - 0.6).abs() < 1e-12 && (s.z_mean_um + 0.8).abs() < 1e-12);
    assert!((s.extents_min_um[1] - 4.5).abs() < 1e-12 && (s.extents_max_um[1] - 5.0).abs() < 1e-12);
    assert!(window_stats(&samples, (1.0, 2.0)).is_none());
}

/// A periodic verdict `v` on an orbit of period `p` sampled every `dt`: the period found to
/// 0.2 %, judged over a window stretched to exactly four found periods; `(t_s, window_start_s,
/// period_s)`.
fn stretched_orbit(v: Verdict, p: f64, dt: f64) -> (f64, f64, f64) {
    let Verdict::Periodic { t_s, window_start_s, period_s } = v else {
        panic!("expected periodic, got {v:?}")
    };
    println!("orbit of {p} s: periodic at {t_s:.4} s over [{window_start_s:.4}, {t_s:.4}], period {period_s:.6} s");
    assert!((period_s / p - 1.0).abs() < 2e-3, "period {period_s} vs {p}");
    assert!(((t_s - window_start_s) / (4.0 * period_s) - 1.0).abs() < 2.0 * dt / p, "window {window_start_s}..{t_s}");
    (t_s, window_start_s, period_s)
}

#[test]
fn an_orbit_too_slow_for_the_window_is_judged_over_four_of_its_periods() {
    // The study's case: a cell swinging with a period of 135 ms under a 0.5 s window, which
    // holds only 3.7 of the min_cycles + 1 = 4 periods the repetition test needs. Until the
    // window stretched, this orbit stayed undecided until max_time.
    let (p, w, tol, dt, tau) = (0.135, 0.5, 0.05, 1e-3, 0.3);
    let f = move |t: f64| {
        let u = 2.0 * PI * t / p;
        vec![
            1.1 + 0.2 * u.sin() + 0.05 * (2.0 * u + 0.4).sin() + 0.3 * (-t / tau).exp(),
            0.11 + 0.07 * (u + 1.0).sin(),
        ]
    };
    let (t, x) = series(dt, 3000, f);
    let v = detect(&criterion(w, 2.9, vec![tol, 0.005]), &t, &x).unwrap();
    let (t_s, window_start_s, _) = stretched_orbit(v, p, dt);
    assert!(t_s - window_start_s > w);
    // the transient (0.3 e^{-t/tau}) must have faded below the tolerances first: over one period
    // it changes by 0.3 e^{-s/tau} (1 - e^{-P/tau}) <= tol from s = tau ln(0.3 (1 - e^{-P/tau}) / tol),
    // and the window's oldest pair starts at t - 4P
    let lag_bound = 4.0 * p + tau * (0.3 * (1.0 - (-p / tau).exp()) / tol).ln();
    assert!(t_s >= lag_bound - 1e-9, "detected at {t_s} before the transient bound {lag_bound}");
    assert!(t_s < lag_bound + 1.0, "detected at {t_s}, long after the transient bound {lag_bound}");

    // the same orbit still migrating at 0.2 um/s is judged like a fast one: it repeats within
    // tol period by period (0.027 per period) but its mean moves by 0.081 > tol between the
    // stretched window's first and last periods (3 P apart), so it is not periodic
    let g = move |t: f64| {
        let u = 2.0 * PI * t / p;
        vec![1.1 + 0.2 * u.sin() + 0.2 * t, 0.11 + 0.07 * (u + 1.0).sin()]
    };
    let (t, x) = series(dt, 3000, g);
    let v = detect(&criterion(w, 2.9, vec![tol, 0.005]), &t, &x).unwrap();
    assert!(matches!(v, Verdict::Unsteady { .. }), "{v:?}");

    // a period beyond what the kept samples can hold (4 P > WINDOW_STRETCH W = 16 s) stays
    // undecided, one just inside is judged (samples every 10 ms, 300-420 a period; an amplitude
    // whose range over W at a peak, 2 (1 - cos(pi W / P)) >= 0.14, exceeds the tolerance)
    let stretch = rbc_solver::steady::WINDOW_STRETCH * w;
    for (q, judged) in [(1.05 * stretch / 4.0, false), (0.75 * stretch / 4.0, true)] {
        let (t, x) = series(1e-2, 2500, |t| vec![1.0 + 2.0 * (2.0 * PI * t / q).sin()]);
        let v = detect(&criterion(w, 24.9, vec![tol]), &t, &x).unwrap();
        assert_eq!(matches!(v, Verdict::Periodic { period_s, .. } if (period_s / q - 1.0).abs() < 2e-3), judged, "P {q} s: {v:?}");
        assert!(judged || matches!(v, Verdict::Unsteady { .. }), "{v:?}");
    }
}

/// The study's slipper at ~0.26 mm/s (science-6p5-penalty, r_init 1.2 um, session 52) tumbles: it
/// turned over at ~0.75 s and again at ~1.9 s, a flip of ~0.3 s after ~0.9 s lying flat. An orbit
/// of that kind, a flip every 1.2 s whose two halves of a turn differ (so the period is a whole
/// turn, 2.4 s), sampled every 0.2 ms as the study outputs, after a transient: four of its periods
/// (9.6 s) need more than the 4 s the detector kept until session 52 (WINDOW_STRETCH 8, periods
/// up to 1 s at the study's W = 0.5 s), so it would have run to max_time_s undecided. Judged
/// periodic over four periods of the whole turn, with the period to 0.2 %, once the transient
/// fades below the tolerance over a period.
#[test]
fn a_tumbling_orbit_of_2p4_s_at_the_studys_window_is_judged_periodic() {
    let (p, w, tol, tau, dt) = (2.4, 0.5, 0.05, 0.5, 2e-4);
    // the x extent (um): a dip to ~4.9 um at each flip, long plateaus at ~8 um between, the second
    // flip's dip 0.3 um shallower; y (um) sways by 0.4 um and drifts out, then settles
    let flip = |t: f64, at: f64| (-((t - at).rem_euclid(p) - p / 2.0).powi(2) / (2.0 * 0.08f64.powi(2))).exp();
    let f = move |t: f64| {
        vec![
            8.0 - 3.1 * flip(t, 0.3) - 2.8 * flip(t, 0.3 + p / 2.0),
            1.5 + 0.4 * (2.0 * PI * t / p).sin() - 0.6 * (-t / tau).exp(),
        ]
    };
    let n = 70_000; // 14 s
    let (t, x) = series(dt, n, f);
    let v = detect(&criterion(w, 13.9, vec![tol, tol]), &t, &x).unwrap();
    let (t_s, _, period_s) = stretched_orbit(v, p, dt);
    let lag_bound = 4.0 * period_s + tau * (0.6 * (1.0 - (-p / tau).exp()) / tol).ln();
    assert!(t_s >= lag_bound - 1e-9 && t_s < lag_bound + 1.0, "detected at {t_s}, the transient bound {lag_bound}");
}

/// The study's slipper at ~0.5 mm/s (science-6p5-penalty, r_init 1.2 um, session 45) swings with
/// a period of ~0.77 s at y 0.55-1.67 um under the study's window W = 0.5 s: four of its periods
/// (3.1 s) need more than the 2 s the detector kept until session 46 (WINDOW_STRETCH 4), so it
/// would have run to max_time_s undecided. A swing of that period and amplitude, two harmonics
/// (a slipper's swing is not a sine) and an asphericity that beats twice a period, sampled every
/// 0.2 ms as the study outputs, after a transient 0.4 e^{-t/0.3 s}: judged periodic over exactly
/// four periods, with the period to 0.2 % (the transient biases it slightly), once the transient fades below the tolerance over a
/// period (the bound of `an_orbit_too_slow_for_the_window_is_judged_over_four_of_its_periods`). The same swing whose
/// mean still migrates inwards at 0.02 um/s (0.046 um over the three periods between the
/// window's first and last, under 0.05 um) is periodic too, and at 0.04 um/s (0.092 um) it is not.
/// Slow orbits are judged once per W / 50 = 10 ms, so the verdict falls on the first sample of such
/// an interval.
#[test]
fn an_orbit_of_0p77_s_at_the_studys_window_is_judged_periodic() {
    let (p, w, tol, tau, dt) = (0.77, 0.5, 0.05, 0.3, 2e-4);
    let swing = move |drift: f64| {
        move |t: f64| {
            let u = 2.0 * PI * t / p;
            vec![
                1.11 + 0.5 * u.sin() + 0.08 * (2.0 * u + 0.7).sin() + 0.4 * (-t / tau).exp() - drift * t,
                0.12 + 0.02 * (2.0 * u).cos(),
            ]
        }
    };
    let n = 40_000; // 8 s
    let (t, x) = series(dt, n, swing(0.0));
    let v = detect(&criterion(w, 7.9, vec![tol, 0.005]), &t, &x).unwrap();
    let (t_s, _, period_s) = stretched_orbit(v, p, dt);
    // judged at the first sample of a W / SLOW_ORBITS_PER_WINDOW interval (10 ms here)
    let every = w / rbc_solver::steady::SLOW_ORBITS_PER_WINDOW;
    assert!(t_s - (t_s / every + 1e-9).floor() * every < dt, "decided at {t_s} s, inside a {every} s interval");
    // the window's oldest pair starts four found periods back
    let lag_bound = 4.0 * period_s + tau * (0.4 * (1.0 - (-p / tau).exp()) / tol).ln();
    assert!(t_s >= lag_bound - 1e-9, "detected at {t_s} before the transient bound {lag_bound}");
    assert!(t_s < lag_bound + 1.0, "detected at {t_s}, long after the transient bound {lag_bound}");

    let (t, x) = series(dt, n, swing(0.02));
    let v = detect(&criterion(w, 7.9, vec![tol, 0.005]), &t, &x).unwrap();
    assert!(matches!(v, Verdict::Periodic { period_s, .. } if (period_s / p - 1.0).abs() < 2e-3), "{v:?}");
    let (t, x) = series(dt, n, swing(0.04));
    let v = detect(&criterion(w, 7.9, vec![tol, 0.005]), &t, &x).unwrap();
    assert!(matches!(v, Verdict::Unsteady { .. }), "{v:?}");
}

/// A run that continues (resumed or reopened) is judged where it is. The series: a plateau at 0
/// until 1 s, a ramp of 0.2 per s until 2 s, a plateau at 0.2 from 2 s on (window 0.5 s, samples
/// every ms). Under a tolerance of 0.0455, sample-by-sample pushes decide `steady` at 0.5 s, on
/// the first plateau. Handed the samples up to 1.8 s at once (`resume_with`), the detector judges
/// the window ending at 1.8 s only: on the ramp (range 0.1), so pending; pushed on, it decides
/// `steady` at the first window whose ramp part spans at most 0.0455 (from 2.2725 s: the sample at
/// 2.273 s), where the run then is. A run from the ramp's start on under a tolerance of 0.0099 is
/// undecided at 1.8 s; `resume_with` then pushing the rest gives exactly the verdict of pushing
/// everything sample by sample (steady at 2.451 s).
#[test]
fn a_continued_run_is_judged_at_its_end_not_at_an_earlier_window() {
    let ramp = |t: f64| vec![if t < 1.0 { 0.0 } else if t < 2.0 { 0.2 * (t - 1.0) } else { 0.2 }];
    let (t, x) = series(1e-3, 3001, ramp);
    let split = t.iter().position(|&t| t > 1.8 - 1e-9).unwrap();
    let loose = criterion(0.5, 10.0, vec![0.0455]);
    let early = detect(&loose, &t, &x).unwrap();
    assert!(matches!(early, Verdict::Steady { t_s, .. } if (t_s - 0.5).abs() < 1e-9), "{early:?}");
    let mut d = SteadyDetector::new(loose.clone()).unwrap();
    let at_resume = d.resume_with(t[..split].iter().zip(&x[..split]).map(|(t, x)| (*t, x.as_slice()))).unwrap();
    assert_eq!(at_resume, Verdict::Pending, "judged on the ramp where the run is");
    let mut v = Verdict::Pending;
    for (t, x) in t[split..].iter().zip(&x[split..]) {
        v = d.push(*t, x).unwrap();
        if v.is_decided() {
            break;
        }
    }
    assert!(matches!(v, Verdict::Steady { t_s, window_start_s } if (t_s - 2.273).abs() < 1e-9 && (window_start_s - 1.773).abs() < 1e-9), "{v:?}");

    // a run undecided until it resumes (the series from the ramp's start on), the same criterion
    // throughout: resuming changes nothing
    let (t, x) = (&t[1000..], &x[1000..]);
    let split = split - 1000;
    let strict = criterion(0.5, 2.9, vec![0.0099]);
    let all = detect(&strict, t, x).unwrap();
    let mut d = SteadyDetector::new(strict).unwrap();
    assert_eq!(d.resume_with(t[..split].iter().zip(&x[..split]).map(|(t, x)| (*t, x.as_slice()))).unwrap(), Verdict::Pending);
    let mut resumed = Verdict::Pending;
    for (t, x) in t[split..].iter().zip(&x[split..]) {
        resumed = d.push(*t, x).unwrap();
        if resumed.is_decided() {
            break;
        }
    }
    assert_eq!(resumed, all);
    assert!(matches!(all, Verdict::Steady { t_s, .. } if (t_s - 2.451).abs() < 1e-9), "{all:?}");
}

/// A run resumed under the same criterion is judged as if it had never stopped, also where only
/// the slow-orbit test (once per W / 50 = 10 ms, and over longer spans every 40, 80 and 160 ms)
/// can decide: the 0.77 s orbit of the test above, resumed at any sample before its verdict and
/// pushed on, ends at the same sample with the same period as pushed sample by sample.
#[test]
fn a_slow_orbit_resumed_anywhere_is_judged_as_if_it_never_stopped() {
    let (p, w, tau, dt) = (0.77, 0.5, 0.3, 2e-4);
    let swing = move |t: f64| {
        let u = 2.0 * PI * t / p;
        vec![1.11 + 0.5 * u.sin() + 0.08 * (2.0 * u + 0.7).sin() + 0.4 * (-t / tau).exp(), 0.12 + 0.02 * (2.0 * u).cos()]
    };
    let (t, x) = series(dt, 40_000, swing);
    let c = criterion(w, 7.9, vec![0.05, 0.005]);
    let all = detect(&c, &t, &x).unwrap();
    let Verdict::Periodic { t_s: decided, .. } = all else { panic!("{all:?}") };
    // resume points over the last 0.2 s before the verdict, 2.6 ms apart (not a multiple of the
    // slow tests' intervals), the last one sample before it
    let last = t.iter().position(|&s| s >= decided - 1e-9).unwrap();
    let mut splits: Vec<usize> = (1..=76).map(|k| last - k * 13).collect();
    splits.push(last - 1);
    let mut differ = Vec::new();
    for split in splits {
        let mut d = SteadyDetector::new(c.clone()).unwrap();
        let mut v = d.resume_with(t[..split].iter().zip(&x[..split]).map(|(t, x)| (*t, x.as_slice()))).unwrap();
        for (t, x) in t[split..].iter().zip(&x[split..]) {
            if v.is_decided() {
                break;
            }
            v = d.push(*t, x).unwrap();
        }
        if v != all {
            differ.push((t[split - 1], v));
        }
    }
    assert!(differ.is_empty(), "{} of the resumes end otherwise than {all:?}, e.g. {:?}", differ.len(), &differ[..differ.len().min(3)]);
}

/// The gap to the steady test on a series whose ranges are known: the extent along y grows by
/// 0.01 um a ms and the asphericity relaxes as 0.1 + 0.02 exp(-t / 20 ms). Over the last 50 ms
/// window of 100 ms the extent's range is 0.5 um (10x its 0.05 um tolerance), the asphericity's
/// 0.02 (e^-2.5 - e^-5) = 1.51e-3 (0.30x its 0.005); the series shorter than one window has none.
#[test]
fn the_steady_gap_is_the_largest_range_over_its_tolerance_in_the_last_window() {
    use rbc_solver::steady::{steady_gap, OBSERVABLE_NAMES};
    let sample = |i: usize| {
        let t = i as f64 * 1e-3;
        TimeSample {
            t_s: t,
            centroid_um: [2000.0 * t, 0.6, -0.8],
            velocity_mm_s: [2.0, 0.0, 0.0],
            area_um2: 140.0,
            volume_um3: 100.0,
            asphericity: 0.1 + 0.02 * (-t / 0.02).exp(),
            extents_um: [8.0, 4.0 + 0.01 * i as f64, 3.0],
        }
    };
    let samples: Vec<TimeSample> = (0..=100).map(sample).collect();
    let c = criterion(0.05, 1.0, vec![0.05, 0.005, 0.05, 0.05, 0.05]);
    let (gap, name) = steady_gap(&samples, &c).unwrap();
    assert_eq!(name, "extent_y_um");
    assert!((gap - 10.0).abs() < 1e-9, "{gap}");
    // with the extents held, the asphericity leads
    let held: Vec<TimeSample> = samples.iter().map(|s| TimeSample { extents_um: [8.0, 4.0, 3.0], ..*s }).collect();
    let (gap, name) = steady_gap(&held, &c).unwrap();
    assert_eq!(name, OBSERVABLE_NAMES[1]);
    let expected = 0.02 * ((-2.5f64).exp() - (-5.0f64).exp()) / 0.005;
    assert!((gap - expected).abs() < 1e-12, "{gap} against {expected}");
    // the detector calls the run steady at the first sample whose gap is <= 1 (t* = W + tau
    // ln(0.02 (1 - e^-2.5) / 0.005) = 76.0 ms: the sample at 77 ms)
    let (times, rows): (Vec<f64>, Vec<Vec<f64>>) = held.iter().map(|s| (s.t_s, rbc_solver::steady::observables(s).to_vec())).unzip();
    let Verdict::Steady { t_s, .. } = detect(&c, &times, &rows).unwrap() else { panic!("steady") };
    let first = (1..=held.len()).find(|&n| steady_gap(&held[..n], &c).is_some_and(|(g, _)| g <= 1.0)).unwrap();
    assert_eq!(held[first - 1].t_s, t_s);
    assert!((t_s - 0.077).abs() < 1e-12, "{t_s}");
    assert!(steady_gap(&samples[..50], &c).is_none(), "49 ms: less than one window");
    // the detector's own gap (what a running run's checkpoint stores) is the same, sample by
    // sample, until it decides: none before one window, then the relaxing asphericity's
    let mut d = SteadyDetector::new(c.clone()).unwrap();
    for (n, (t, r)) in times.iter().zip(&rows).enumerate() {
        if d.push(*t, r).unwrap().is_decided() {
            assert_eq!(n + 1, first, "decided at the first gap <= 1");
            break;
        }
        assert_eq!(d.gap(), steady_gap(&held[..=n], &c), "after {} samples", n + 1);
        assert_eq!(d.gap().is_some(), n >= 50, "after {} samples", n + 1);
    }
}

/// The gap to the periodic test on an orbit whose drift is known: the radial position swings
/// as `1 + 0.2 sin(2 pi t / P)` (P = 0.2 s) while drifting at `d` = 0.125 um/s, sampled every
/// ms. Over the 1 s window the orbit repeats within `d P` = 0.025 um (0.5x the 0.05 um
/// tolerance), but its mean over the last period lies `d (W - P)` = 0.1 um (2.0x) above its
/// mean over the first: the gap is the drift's, 2.0, at the period P. The slower candidates
/// (2P and 3P, over 4 of their periods) drift more (3.0 and 4.5x) and are not the closest.
/// Free of a detector (`periodic_gap`, what `rbc-sweep status` computes from a results file)
/// and from the detector (what a checkpoint stores) it is the same.
#[test]
fn the_periodic_gap_is_the_closest_candidates_repetition_or_drift_over_its_tolerance() {
    use rbc_solver::steady::{periodic_gap, OrbitPart};
    let (p, d) = (0.2, 0.125);
    let sample = |i: usize| {
        let t = i as f64 * 1e-3;
        TimeSample {
            t_s: t,
            centroid_um: [2000.0 * t, 1.0 + 0.2 * (2.0 * PI * t / p).sin() + d * t, 0.0],
            velocity_mm_s: [2.0, 0.0, 0.0],
            area_um2: 140.0,
            volume_um3: 100.0,
            asphericity: 0.1,
            extents_um: [8.0, 4.0, 3.0],
        }
    };
    let samples: Vec<TimeSample> = (0..=3000).map(sample).collect();
    let c = criterion(1.0, 40.0, vec![0.05, 0.005, 0.05, 0.05, 0.05]);
    let g = periodic_gap(&samples, &c).unwrap();
    assert_eq!((g.part, g.observable), (OrbitPart::Drift, 0), "{g:?}");
    assert!((g.gap - 2.0).abs() < 2e-3, "{g:?}");
    assert!((g.period_s - p).abs() < 1e-5, "{g:?}");
    assert!((g.window_start_s - 2.0).abs() < 1e-9, "{g:?}");
    let mut det = SteadyDetector::new(c.clone()).unwrap();
    for s in &samples {
        assert_eq!(det.push(s.t_s, &rbc_solver::steady::observables(s)).unwrap(), Verdict::Pending);
    }
    assert_eq!(det.periodic_gap(), Some(g));
    // with the drift 3x slower the repetition (0.5 / 3) and the drift (2 / 3) are both within
    // tolerance: the gap is the drift's 0.67 and the run is periodic
    let slower: Vec<TimeSample> = samples.iter().map(|s| TimeSample { centroid_um: [s.centroid_um[0], s.centroid_um[1] - 2.0 / 3.0 * d * s.t_s, 0.0], ..*s }).collect();
    let g = periodic_gap(&slower, &c).unwrap();
    assert_eq!(g.part, OrbitPart::Drift);
    assert!((g.gap - 2.0 / 3.0).abs() < 2e-3, "{g:?}");
    let (times, rows): (Vec<f64>, Vec<Vec<f64>>) = slower.iter().map(|s| (s.t_s, rbc_solver::steady::observables(s).to_vec())).unzip();
    assert!(matches!(detect(&c, &times, &rows).unwrap(), Verdict::Periodic { period_s, .. } if (period_s - p).abs() < 1e-4));
    // less than one window: no gap
    assert_eq!(periodic_gap(&samples[..900], &c), None);
}

/// The verdict turns periodic at the first sample whose periodic gap is `<= 1`: an orbit whose
/// mean relaxes as `0.3 exp(-t / 0.4 s)` while it swings with a 0.15 s period. Before the
/// decision the detector's gap stays above 1 (checked every 5 ms) and equals the free
/// function's over the same samples; at it the gap is `<= 1` at the verdict's period. The drift
/// sets the time: the means of `0.3 exp(-t / tau)` over the window's first and last periods,
/// `0.3 (tau / P) (exp(-a / tau) - exp(-(a + P) / tau))` at `a = t - W` and `t - P`, differ by
/// the 0.05 um tolerance at t = 1.594 s (the repetition is within it from 1.10 s).
#[test]
fn the_verdict_turns_periodic_where_the_periodic_gap_reaches_one() {
    use rbc_solver::steady::periodic_gap;
    let p = 0.15;
    let sample = |i: usize| {
        let t = i as f64 * 1e-3;
        TimeSample {
            t_s: t,
            centroid_um: [2000.0 * t, 1.0 + 0.2 * (2.0 * PI * t / p).sin() + 0.3 * (-t / 0.4).exp(), 0.0],
            velocity_mm_s: [2.0, 0.0, 0.0],
            area_um2: 140.0,
            volume_um3: 100.0,
            asphericity: 0.1 + 0.01 * (2.0 * PI * t / p).cos(),
            extents_um: [8.0, 4.0, 3.0],
        }
    };
    let samples: Vec<TimeSample> = (0..=4000).map(sample).collect();
    let c = criterion(1.0, 40.0, vec![0.05, 0.005, 0.05, 0.05, 0.05]);
    let mut det = SteadyDetector::new(c.clone()).unwrap();
    let mut checked = 0;
    for (n, s) in samples.iter().enumerate() {
        let v = det.push(s.t_s, &rbc_solver::steady::observables(s)).unwrap();
        let g = det.periodic_gap();
        if let Verdict::Periodic { period_s, .. } = v {
            let g = g.unwrap();
            assert!(g.gap <= 1.0 && g.period_s == period_s, "{g:?} at {v:?}");
            assert!(checked > 10 && (s.t_s - 1.594).abs() < 0.005, "decided at {} s after {checked} checks", s.t_s);
            return;
        }
        assert_eq!(v, Verdict::Pending);
        if let Some(gap) = g.filter(|_| n % 5 == 0) {
            assert!(gap.gap > 1.0, "{g:?} at {} s, still pending", s.t_s);
            if n % 100 == 0 {
                assert_eq!(periodic_gap(&samples[..=n], &c), g, "at {} s", s.t_s);
            }
            checked += 1;
        }
    }
    panic!("never periodic");
}
