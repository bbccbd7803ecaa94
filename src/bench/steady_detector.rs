//! `rbc-bench steady-detector`: what the steady-state detector (`rbc_solver::steady`) costs a run
//! as its samples pile up: the CPU time of pushing the samples of each stretch of sample time, per
//! 10 ms of sample time (`W / SLOW_ORBITS_PER_WINDOW` at the study's `W` = 0.5 s: the 50 window
//! tests in it and the slow-orbit tests of the spans due, each span at its own cadence,
//! `rbc_solver::steady::slow_test_interval_s`), as the detector comes to keep 4, 8 and then its
//! full 16 s of samples.
//!
//! Usage: `rbc-bench steady-detector [--dt 2e-4] [--window 0.5] [--until 4,8,16,24]`. The series
//! is the worst case, an orbit the detector never decides on: a tumbling cell's x extent and y
//! position (a flip every 1.2 s, a whole turn 2.4 s, the two halves of a turn differing) under
//! tolerances too tight for it to repeat within and a mean that drifts (0.01 um/s), so every candidate period of a span is
//! refined and scored whenever that span is due. A study run takes 10-120 core-s per 10 ms of sample time
//! (1-12 core-s per simulated ms, `examples/studies/*/ledger.csv`); the detector's share is the
//! last column's figure over that.

use anyhow::{bail, Context};
use rbc_solver::steady::{SteadyCriterion, SteadyDetector, SLOW_ORBITS_PER_WINDOW, WINDOW_STRETCH};
use std::f64::consts::PI;

use super::clock::process_cpu_s;

pub fn run(args: &[String]) -> anyhow::Result<()> {
    let (mut dt, mut window_s, mut until) = (2e-4, 0.5, vec![4.0, 8.0, 16.0, 24.0]);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("rbc-bench steady-detector: {a} needs a value"));
        match a.as_str() {
            "--dt" => dt = val()?.parse().context("--dt")?,
            "--window" => window_s = val()?.parse().context("--window")?,
            "--until" => until = val()?.split(',').map(|s| s.trim().parse()).collect::<Result<_, _>>().context("--until")?,
            other => bail!("rbc-bench steady-detector: unknown option {other:?} (expected --dt, --window, --until)"),
        }
    }
    if !(dt > 0.0 && window_s > 0.0 && until.windows(2).all(|w| w[0] < w[1]) && until.first().is_some_and(|&u| u > 0.0)) {
        bail!("rbc-bench steady-detector: --dt and --window must be positive and --until increasing from above 0");
    }
    let p = 2.4;
    let flip = |t: f64, at: f64| (-((t - at).rem_euclid(p) - p / 2.0).powi(2) / (2.0 * 0.08f64.powi(2))).exp();
    let sample = |t: f64| [8.0 - 3.1 * flip(t, 0.3) - 2.8 * flip(t, 0.3 + p / 2.0), 1.5 + 0.4 * (2.0 * PI * t / p).sin() + 0.01 * t];
    let c = SteadyCriterion { window_s, max_time_s: 1e6, min_cycles: 3, min_samples: 20, tolerances: vec![1e-4, 1e-4] };
    let mut d = SteadyDetector::new(c)?;
    let slow_every_s = window_s / SLOW_ORBITS_PER_WINDOW;
    println!("## The steady-state detector's CPU time as its samples pile up (an output every {dt} s, W = {window_s} s, samples kept: the last {} s)\n", WINDOW_STRETCH * window_s);
    println!("| sample time (s) | samples kept at the end | CPU s over the stretch | per sample (us) | per {:.0} ms of sample time (ms) |", slow_every_s * 1e3);
    println!("| --- | --- | --- | --- | --- |");
    let (mut i, mut from) = (0usize, 0.0);
    for &end in &until {
        let cpu0 = process_cpu_s().context("rbc-bench steady-detector: no process CPU clock (Linux /proc)")?;
        let first = i;
        while (i as f64) * dt <= end {
            let t = i as f64 * dt;
            if d.push(t, &sample(t))?.is_decided() {
                bail!("rbc-bench steady-detector: the series was decided at {t} s (it should not be)");
            }
            i += 1;
        }
        let cpu = process_cpu_s().context("rbc-bench steady-detector: no process CPU clock")? - cpu0;
        let kept = ((end.min(WINDOW_STRETCH * window_s)) / dt).round() as usize;
        let n = i - first;
        println!("| {from:.0}-{end:.0} | {kept} | {cpu:.2} | {:.1} | {:.1} |", cpu / n as f64 * 1e6, cpu / ((end - from) / slow_every_s) * 1e3);
        from = end;
    }
    Ok(())
}
