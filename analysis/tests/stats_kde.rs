//! Tests of `kde::ksdensity` against MATLAB R2017a `ksdensity` semantics: reference fixture (numpy + GNU Octave), exact properties, hand-computed bandwidths, errors.
//!
//! The fixture `fixtures/ksdensity_reference.txt` is written by
//! `python3 scripts/ksdensity_reference.py --octave DIR` (see that script): an
//! independent numpy implementation of MATLAB's documented algorithm, and for the
//! cases where Octave implements the same estimator, GNU Octave's statistics
//! package `ksdensity` evaluated at the same points.

use rbc_analysis::experiment::kde::{default_bandwidth, ksdensity, ksdensity_at, KdeError};

/// One case of the reference fixture.
struct Case {
    name: String,
    support: Option<(f64, f64)>,
    sample: Vec<f64>,
    bandwidth: f64,
    y: Vec<f64>,
    density: Vec<f64>,
    octave: Option<(f64, Vec<f64>)>,
}

fn numbers(rest: &str) -> Vec<f64> {
    rest.split_whitespace()
        .map(|w| w.parse::<f64>().unwrap_or_else(|e| panic!("{w}: {e}")))
        .collect()
}

fn fixture() -> Vec<Case> {
    let text = include_str!("fixtures/ksdensity_reference.txt");
    let mut cases = Vec::new();
    let mut cur: Option<Case> = None;
    let mut octave_bw = None;
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let (key, rest) = line.split_once(' ').unwrap_or((line, ""));
        match key {
            "case" => {
                cur = Some(Case {
                    name: rest.into(),
                    support: None,
                    sample: vec![],
                    bandwidth: f64::NAN,
                    y: vec![],
                    density: vec![],
                    octave: None,
                })
            }
            "end" => cases.push(cur.take().expect("end without case")),
            _ => {
                let c = cur.as_mut().expect("line outside a case");
                match key {
                    "support" if rest == "none" => c.support = None,
                    "support" => {
                        let v = numbers(rest);
                        c.support = Some((v[0], v[1]));
                    }
                    "sample" => c.sample = numbers(rest),
                    "bandwidth" => c.bandwidth = numbers(rest)[0],
                    "y" => c.y = numbers(rest),
                    "density" => c.density = numbers(rest),
                    "octave_bandwidth" => octave_bw = Some(numbers(rest)[0]),
                    "octave_density" => {
                        c.octave = Some((
                            octave_bw.take().expect("octave_bandwidth first"),
                            numbers(rest),
                        ))
                    }
                    other => panic!("unknown fixture key {other}"),
                }
            }
        }
    }
    cases
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Our estimator reproduces the reference values to 1e-10 (absolute, 1/um; densities are O(0.01-1)).
/// Measured: max deviation printed with `cargo test -p rbc-analysis --test stats_kde -- --nocapture`.
#[test]
fn matches_matlab_reference_fixture() {
    let cases = fixture();
    assert_eq!(cases.len(), 9, "fixture cases");
    let (mut worst_ref, mut worst_oct, mut n_oct) = (0.0f64, 0.0f64, 0);
    for c in &cases {
        let kde = if c.name == "given_points" {
            ksdensity_at(&c.sample, c.support, &c.y).unwrap()
        } else {
            ksdensity(&c.sample, c.support, 100).unwrap()
        };
        let dy = max_abs_diff(&kde.y, &c.y);
        let dd = max_abs_diff(&kde.density, &c.density);
        let dh = (kde.bandwidth - c.bandwidth).abs();
        println!(
            "{:15} n={:4} grid {dy:.1e} density {dd:.1e} bandwidth {dh:.1e}",
            c.name,
            c.sample.len()
        );
        assert!(
            dy < 1e-10 && dd < 1e-10 && dh < 1e-10,
            "{}: grid {dy:e}, density {dd:e}, bandwidth {dh:e}",
            c.name
        );
        worst_ref = worst_ref.max(dy).max(dd).max(dh);
        if let Some((h, f)) = &c.octave {
            let d = max_abs_diff(&kde.density, f).max((kde.bandwidth - h).abs());
            assert!(d < 1e-10, "{} vs Octave: {d:e}", c.name);
            worst_oct = worst_oct.max(d);
            n_oct += 1;
        }
    }
    assert!(n_oct >= 6, "Octave values for {n_oct} cases");
    println!(
        "max deviation: numpy reference {worst_ref:.2e}, Octave {worst_oct:.2e} ({n_oct} cases)"
    );
}

/// The density of y is a Gaussian mixture in t mapped back with dt/dy, so its integral over
/// the support is exactly 1; we integrate in t (trapezoid on a Gaussian sum is spectrally accurate).
#[test]
fn integrates_to_one_over_the_support() {
    let (lo, hi) = (-6.0, 6.0);
    let sample = [-5.2, -2.5, -2.4, -0.3, 0.0, 0.8, 2.6, 3.1, 5.7];
    let kde = ksdensity(&sample, Some((lo, hi)), 100).unwrap();
    let h = kde.bandwidth;
    let t: Vec<f64> = sample
        .iter()
        .map(|y: &f64| ((y - lo) / (hi - y)).ln())
        .collect();
    let (t0, t1) = (
        t.iter().cloned().fold(f64::INFINITY, f64::min) - 12.0 * h,
        t.iter().cloned().fold(f64::NEG_INFINITY, f64::max) + 12.0 * h,
    );
    let m = 4001;
    let dt = (t1 - t0) / (m - 1) as f64;
    let ts: Vec<f64> = (0..m).map(|i| t0 + i as f64 * dt).collect();
    let ys: Vec<f64> = ts
        .iter()
        .map(|t| lo + (hi - lo) / (1.0 + (-t).exp()))
        .collect();
    // in chunks of 1000 points: 9 x 4001 evaluations at once would take MATLAB's truncated sum,
    // which drops the kernel mass beyond 4 bandwidths (2 Phi(-4) = 6.3e-5)
    let f: Vec<f64> = ys
        .chunks(1000)
        .flat_map(|c| ksdensity_at(&sample, Some((lo, hi)), c).unwrap().density)
        .collect();
    // dy/dt = (y - L)(U - y)/(U - L)
    let integral: f64 = (0..m)
        .map(|i| {
            let w = if i == 0 || i == m - 1 { 0.5 } else { 1.0 };
            w * f[i] * (ys[i] - lo) * (hi - ys[i]) / (hi - lo) * dt
        })
        .sum();
    assert!((integral - 1.0).abs() < 1e-12, "integral {integral}");
    // on MATLAB's own 100-point grid the trapezoid misses the tails beyond 3 bandwidths and the discretisation
    let g: f64 = kde
        .y
        .windows(2)
        .zip(kde.density.windows(2))
        .map(|(y, d)| 0.5 * (d[0] + d[1]) * (y[1] - y[0]))
        .sum();
    assert!((g - 1.0).abs() < 0.02, "grid integral {g}");
}

#[test]
fn symmetric_sample_gives_symmetric_density() {
    let half = [0.3, 1.1, 2.5, 2.7, 4.8];
    let sample: Vec<f64> = half.iter().flat_map(|&v| [v, -v]).collect();
    let kde = ksdensity(&sample, Some((-6.0, 6.0)), 100).unwrap();
    let n = kde.y.len();
    for i in 0..n {
        assert!((kde.y[i] + kde.y[n - 1 - i]).abs() < 1e-13, "grid {i}");
        let (a, b) = (kde.density[i], kde.density[n - 1 - i]);
        assert!(
            (a - b).abs() <= 1e-13 * a.abs().max(1e-3),
            "density {i}: {a} vs {b}"
        );
    }
}

/// Bandwidths computed by hand (40-digit decimals): h = MAD/0.6745 (4/(3n))^(1/5) on t.
#[test]
fn bandwidth_formula_on_hand_computed_cases() {
    // unbounded t = 1, 2, 3, 4, 10: median 3, |t - 3| = 2, 1, 0, 1, 7, MAD 1
    let h = default_bandwidth(&[1.0, 2.0, 3.0, 4.0, 10.0]);
    assert!((h - 1.138_182_207_968_502_6).abs() < 1e-15, "{h}");
    // support [-6, 6], y = -3, 0, 3 -> t = -ln 3, 0, ln 3: MAD ln 3, h = ln3/0.6745 (4/9)^(1/5)
    let kde = ksdensity(&[-3.0, 0.0, 3.0], Some((-6.0, 6.0)), 100).unwrap();
    assert!(
        (kde.bandwidth - 1.384_924_170_650_734_8).abs() < 1e-14,
        "{}",
        kde.bandwidth
    );
    // MAD = 0 (three equal values): MATLAB falls back to the range, 4 (1/3)^(1/5)
    let h = default_bandwidth(&[1.0, 1.0, 1.0, 5.0]);
    assert!((h - 3.210_966_247_040_923).abs() < 1e-15, "{h}");
    // all equal: h = 1
    assert_eq!(default_bandwidth(&[2.0, 2.0, 2.0]), 1.0);
}

/// One value: h = 1 and the estimate is one Gaussian in t times the Jacobian, on the grid t1 -+ 3.
#[test]
fn single_value_is_one_mapped_gaussian() {
    let (lo, hi) = (-6.0, 6.0);
    let y1: f64 = 1.5;
    let kde = ksdensity(&[y1], Some((lo, hi)), 7).unwrap();
    assert_eq!(kde.bandwidth, 1.0);
    let t1 = ((y1 - lo) / (hi - y1)).ln();
    let back = |t: f64| lo + (hi - lo) / (1.0 + (-t).exp());
    assert!((kde.y[0] - back(t1 - 3.0)).abs() < 1e-14 && (kde.y[6] - back(t1 + 3.0)).abs() < 1e-14);
    for (&y, &f) in kde.y.iter().zip(&kde.density) {
        let t = ((y - lo) / (hi - y)).ln();
        let expect = (-(t - t1).powi(2) / 2.0).exp() / (2.0 * std::f64::consts::PI).sqrt()
            * (hi - lo)
            / ((y - lo) * (hi - y));
        assert!(
            (f - expect).abs() < 1e-14 * expect.max(1.0),
            "{y}: {f} vs {expect}"
        );
    }
}

#[test]
fn points_outside_the_support_have_zero_density() {
    let f = ksdensity_at(
        &[-1.0, 0.0, 2.0],
        Some((-6.0, 6.0)),
        &[-7.0, -6.0, 0.0, 6.0, 9.0],
    )
    .unwrap()
    .density;
    assert_eq!((f[0], f[1], f[3], f[4]), (0.0, 0.0, 0.0, 0.0));
    assert!(f[2] > 0.0);
}

#[test]
fn bad_input_is_an_error() {
    let s = Some((-6.0, 6.0));
    assert_eq!(ksdensity(&[], s, 100), Err(KdeError::Empty));
    assert!(matches!(
        ksdensity(&[0.0, f64::NAN], s, 100),
        Err(KdeError::NotFinite { index: 1, .. })
    ));
    assert!(matches!(
        ksdensity(&[0.0, f64::INFINITY], None, 100),
        Err(KdeError::NotFinite { index: 1, .. })
    ));
    // the support is open: a value on the wall is outside, as in MATLAB
    assert!(matches!(
        ksdensity(&[0.0, 6.0], s, 100),
        Err(KdeError::OutsideSupport { index: 1, .. })
    ));
    assert!(matches!(
        ksdensity(&[-6.5], s, 100),
        Err(KdeError::OutsideSupport { index: 0, .. })
    ));
    assert!(matches!(
        ksdensity(&[0.0], Some((1.0, 1.0)), 100),
        Err(KdeError::BadSupport { .. })
    ));
    assert!(matches!(
        ksdensity(&[0.0], Some((f64::NEG_INFINITY, 1.0)), 100),
        Err(KdeError::BadSupport { .. })
    ));
    assert_eq!(ksdensity(&[0.0], s, 0), Err(KdeError::NoPoints));
    assert!(matches!(
        ksdensity_at(&[0.0], s, &[f64::NAN]),
        Err(KdeError::BadPoint { index: 0, .. })
    ));
    let msg = ksdensity(&[0.0, 7.0], s, 100).unwrap_err().to_string();
    assert!(msg.contains("7") && msg.contains("support"), "{msg}");
}

/// Above 30000 kernel evaluations MATLAB truncates the sum at 4 bandwidths; the truncated
/// estimate differs from the full sum by at most the mass beyond 4 h: 2 phi(4)... relative to the peak, < 1e-3.
#[test]
fn truncated_sum_is_close_to_the_full_sum() {
    let sample: Vec<f64> = (0..400)
        .map(|i| -5.0 + 10.0 * ((i as f64 * 0.618_033_988_749_895) % 1.0))
        .collect();
    let big = ksdensity(&sample, Some((-6.0, 6.0)), 100).unwrap(); // 40000 > 30000: truncated
                                                                   // the same points, evaluated 10 at a time (4000 evaluations each): full sums
    let mut full = Vec::new();
    for chunk in big.y.chunks(10) {
        full.extend(
            ksdensity_at(&sample, Some((-6.0, 6.0)), chunk)
                .unwrap()
                .density,
        );
    }
    let peak = full.iter().cloned().fold(0.0, f64::max);
    let d = max_abs_diff(&big.density, &full);
    assert!(
        d > 0.0 && d < 1e-3 * peak,
        "truncation changed the density by {d} (peak {peak})"
    );
}
