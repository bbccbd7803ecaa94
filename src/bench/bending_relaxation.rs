//! `rbc-bench bending-relaxation`: the relaxation rate of a shape mode of a nearly spherical
//! bending-only membrane against linear theory, per bending method, mode, viscosity ratio and mesh
//! (`rbc_solver::validation::run_bending_relaxation`; the table of `solver/src/membrane/CONVERGENCE.md`,
//! "Bending in flow", which chose the default bending method).
//!
//! Long: at 2048 triangles one run takes 35-440 s on the 2-core machine (Method C, quartic fit,
//! fit + Galerkin; lambda = 5 is ~3x slower); the default grid (levels 3, 4 x modes 2, 3 x lambda 1, 5
//! x three methods) about an hour. `nice -n 10 rbc-bench bending-relaxation --levels 3 --modes 2`
//! gives one row group in minutes.

use std::time::Instant;

use anyhow::{bail, Context};

use rbc_solver::membrane::bending::BendingMethod;
use rbc_solver::validation::run_bending_relaxation;

/// The three bending methods in the order of the table.
const METHODS: [(BendingMethod, &str); 3] =
    [(BendingMethod::CotangentMethodC, "method-c"), (BendingMethod::QuarticFit, "quartic-fit"), (BendingMethod::QuarticFitGalerkin, "quartic-fit-galerkin")];

fn list<T: std::str::FromStr>(s: &str, name: &str) -> anyhow::Result<Vec<T>>
where
    T::Err: std::error::Error + Send + Sync + 'static,
{
    s.split(',').map(|v| v.trim().parse::<T>()).collect::<Result<_, _>>().with_context(|| format!("{name}: expected a comma-separated list, got {s:?}"))
}

/// `rbc-bench bending-relaxation [--levels 3,4] [--modes 2,3] [--lambdas 1,5] [--eps 0.01]
/// [--methods method-c,quartic-fit,quartic-fit-galerkin] [--atol 4e-5]`: one row per run (BS23 at
/// `--atol` um for one e-folding time, rate fitted to `ln eps(t)`).
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let (mut levels, mut modes, mut lambdas, mut eps, mut atol) = (vec![3usize, 4], vec![2u32, 3], vec![1.0f64, 5.0], 0.01f64, 4e-5f64);
    let mut methods: Vec<BendingMethod> = METHODS.iter().map(|m| m.0).collect();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("rbc-bench bending-relaxation: {a} needs a value"));
        match a.as_str() {
            "--levels" => levels = list(val()?, "--levels")?,
            "--modes" => modes = list(val()?, "--modes")?,
            "--lambdas" => lambdas = list(val()?, "--lambdas")?,
            "--eps" => eps = val()?.parse().context("--eps")?,
            "--atol" => atol = val()?.parse().context("--atol")?,
            "--methods" => methods = list(val()?, "--methods")?,
            other => bail!("rbc-bench bending-relaxation: unknown option {other:?} (expected --levels, --modes, --lambdas, --eps, --methods, --atol)"),
        }
    }
    if let Some(l) = levels.iter().find(|&&l| l > 6) {
        bail!("--levels: {l} is above the largest mesh level 6");
    }
    if let Some(l) = modes.iter().find(|&&l| l < 2) {
        bail!("--modes: {l} is not a shape mode (l >= 2)");
    }
    println!("## Bending-mode relaxation against linear theory (sphere of 4 um, kB = 3e-19 J, eps0 = {eps}, BS23 at {atol:e} um, one e-folding time)\n");
    println!("| mode | lambda | triangles | method | rate (1/s) | theory (1/s) | error | steps (rejected) | wall (s) |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for &level in &levels {
        for &l in &modes {
            for &lambda in &lambdas {
                for &method in &methods {
                    let name = METHODS.iter().find(|m| m.0 == method).map_or("?", |m| m.1);
                    let triangles = 8 * 4usize.pow(level as u32);
                    let t0 = Instant::now();
                    match run_bending_relaxation(l, lambda, level, method, eps, 1.0, atol) {
                        Ok(r) => println!(
                            "| {l} | {lambda} | {triangles} | {name} | {:.4} | {:.4} | {:+.2} % | {} ({}) | {:.0} |",
                            r.rate_1_s,
                            r.rate_ref_1_s,
                            100.0 * r.relative_error(),
                            r.summary.accepted,
                            r.summary.rejected,
                            t0.elapsed().as_secs_f64()
                        ),
                        Err(e) => println!("| {l} | {lambda} | {triangles} | {name} | failed: {e} | | | | |"),
                    }
                }
            }
        }
    }
    Ok(())
}
