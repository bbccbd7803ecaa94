//! `rbc-bench controller`: the integral and the PI step-size controller side by side on the free-space work-precision cases (steps, rejections, velocity evaluations, core-seconds, error against a tight reference).
//!
//! ```text
//! rbc-bench controller [--cases capsule,drop,paper-cell] [--levels 2,3] [--schemes bs23,ros34pw2-local]
//!                      [--controllers integral,pi] [--atol 4e-5] [--reference-factor 100]
//!                      [--paper-level 4] [--paper-ms 1]
//! ```
//!
//! Cases: the validation cases of `rbc-bench precision` (capsule Ca = 0.01, C = 1 and drop
//! Ca = 0.01, lambda = 1, 30 relaxation times from a sphere, `rbc_solver::integrate::validation`)
//! at each mesh level, and the paper's cell of `rbc-bench precision --paper-cell` (`plain`:
//! discocyte at `--paper-level`, lambda = 5, Krueger Skalak kappa_S = 5e-6, kappa_A = 100 kappa_S
//! N/m, shear 100 1/s, `--paper-ms` from rest, h0 = 1 us). Every run is built from the scene
//! text with `integrator.controller` set, so the scene wiring is what is measured. The
//! reference of each case is bs23 with the integral controller at `atol / reference_factor`;
//! the error is the largest vertex distance (um) between the final shapes. Core-s is the
//! process CPU time (/proc/self/stat) of the run, so other jobs on the machine do not count.
//! The channel scene is measured by `rbc-bench channel-tol --controllers integral,pi`
//! (`src/bench/channel_tol.rs`, where the two tables and the recommendation are).
//!
//! # Measured (`nice -n 10`, 2 cores shared with two science runs at nice 5 and two channel-tol processes; load ~5-6)
//!
//! See the table in the module doc of `src/bench/channel_tol.rs` ("Step-size controllers").

use super::precision_cell::cpu_seconds;
use anyhow::{bail, Context, Result};
use nalgebra::Vector3;
use rbc_schema::scene::Scene;
use rbc_solver::integrate::validation::Case;
use rbc_solver::run::{Recorder, RunSummary};
use std::path::Path;

struct Options {
    cases: Vec<String>,
    levels: Vec<u32>,
    schemes: Vec<String>,
    controllers: Vec<String>,
    atol_um: f64,
    reference_factor: f64,
    paper_level: u32,
    paper_ms: f64,
}

fn parse(args: &[String]) -> Result<Options> {
    let mut o = Options {
        cases: vec!["capsule".into(), "drop".into(), "paper-cell".into()],
        levels: vec![2, 3],
        schemes: vec!["bs23".into(), "ros34pw2-local".into()],
        controllers: vec!["integral".into(), "pi".into()],
        atol_um: 4e-5,
        reference_factor: 100.0,
        paper_level: 4,
        paper_ms: 1.0,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("rbc-bench controller: {a} needs a value"));
        let list = |s: &str| s.split(',').map(str::trim).filter(|s| !s.is_empty()).map(String::from).collect::<Vec<_>>();
        match a.as_str() {
            "--cases" => o.cases = list(val()?),
            "--levels" => o.levels = list(val()?).iter().map(|s| s.parse().with_context(|| format!("--levels: `{s}`"))).collect::<Result<_>>()?,
            "--schemes" => o.schemes = list(val()?),
            "--controllers" => o.controllers = list(val()?),
            "--atol" => o.atol_um = val()?.parse().context("--atol")?,
            "--reference-factor" => o.reference_factor = val()?.parse().context("--reference-factor")?,
            "--paper-level" => o.paper_level = val()?.parse().context("--paper-level")?,
            "--paper-ms" => o.paper_ms = val()?.parse().context("--paper-ms")?,
            other => bail!("rbc-bench controller: unknown option {other} (see src/bench/controller.rs)"),
        }
    }
    for c in &o.controllers {
        if c != "integral" && c != "pi" {
            bail!("--controllers: unknown controller {c:?} (integral, pi)");
        }
    }
    if let Some(l) = o.levels.iter().chain([&o.paper_level]).find(|&&l| !(1..=6).contains(&l)) {
        bail!("level {l} is outside 1..=6");
    }
    Ok(o)
}

/// `text` (a scene with an `[integrator]` table and no `controller` line) with `controller = "<controller>"`.
pub fn with_controller(text: &str, controller: &str) -> Result<String> {
    if !text.contains("[integrator]\n") || text.contains("\ncontroller =") {
        bail!("scene text without an [integrator] table or with a controller already");
    }
    Ok(text.replacen("[integrator]\n", &format!("[integrator]\ncontroller = \"{controller}\"\n"), 1))
}

/// The paper's cell, `plain` configuration of `rbc-bench precision --paper-cell`, at mesh `level`.
fn paper_cell_scene(level: u32, scheme: &str, atol_um: f64, end_s: f64) -> String {
    format!(
        "name = \"paper-cell-plain\"\n[cell]\nshape = \"discocyte\"\nlevel = {level}\n[membrane.skalak]\nconvention = \"krueger\"\nkappa_s_n_m = 5e-6\nkappa_a_n_m = 5e-4\n\
         [fluid]\nviscosity_pa_s = 1.2e-3\nlambda = 5.0\n[flow]\nkind = \"shear\"\nshear_rate_1_s = 100.0\n[integrator]\nscheme = \"{scheme}\"\natol_um = {atol_um:e}\nh0_s = 1e-6\n\
         [time]\nend_s = {end_s:e}\noutput_interval_s = {end_s:e}\n"
    )
}

/// One run: summary, core-s, final vertices (um).
fn run_scene(text: &str) -> Result<(RunSummary, f64, Vec<Vector3<f64>>)> {
    let scene = Scene::parse(text, Path::new("controller.toml"))?;
    let built = rbc_solver::scene::build(&scene)?;
    let c0 = cpu_seconds();
    let (summary, x) = built.run(&mut Recorder::default())?;
    let cpu = match (c0, cpu_seconds()) {
        (Some(a), Some(b)) => b - a,
        _ => f64::NAN,
    };
    Ok((summary, cpu, x))
}

/// Largest vertex distance (um).
fn max_distance(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max)
}

/// Run the comparison with the remaining command-line arguments.
pub fn run(args: &[String]) -> Result<()> {
    let o = parse(args)?;
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("## Step-size controllers side by side (atol {:e} um, reference bs23/integral at atol / {})", o.atol_um, o.reference_factor);
    println!("load average at start: {}", load.split_whitespace().take(3).collect::<Vec<_>>().join(" "));
    println!();
    println!("| case | triangles | scheme | controller | accepted | rejected | rejected % | velocity evals | core-s | max vertex error (um) |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    // (case label, triangles, scene text for (scheme, atol))
    let mut jobs: Vec<(String, usize, Box<dyn Fn(&str, f64) -> String>)> = Vec::new();
    for name in &o.cases {
        match name.as_str() {
            "capsule" | "drop" => {
                let case = if name == "capsule" { Case::Capsule { ca: 0.01, c: 1.0, lambda: 1.0 } } else { Case::Drop { ca: 0.01, lambda: 1.0 } };
                for &level in &o.levels {
                    let t_end = 30.0 * case.relaxation_s();
                    jobs.push((name.clone(), 8 * 4usize.pow(level), Box::new(move |s: &str, a: f64| case.scene_toml(level, s, a, t_end))));
                }
            }
            "paper-cell" => {
                let (level, end_s) = (o.paper_level, o.paper_ms * 1e-3);
                jobs.push((format!("paper cell ({} ms)", o.paper_ms), 8 * 4usize.pow(level), Box::new(move |s: &str, a: f64| paper_cell_scene(level, s, a, end_s))));
            }
            other => bail!("--cases: unknown case {other} (capsule, drop, paper-cell)"),
        }
    }
    for (label, triangles, scene) in &jobs {
        let reference = with_controller(&scene("bs23", o.atol_um / o.reference_factor), "integral")?;
        let (rs, rcpu, rx) = run_scene(&reference).with_context(|| format!("{label}: reference"))?;
        println!(
            "| {label} | {triangles} | bs23 (reference, atol {:.0e}) | integral | {} | {} | {:.1} | {} | {:.1} | - |",
            o.atol_um / o.reference_factor,
            rs.accepted,
            rs.rejected,
            100.0 * rs.rejected as f64 / (rs.accepted + rs.rejected).max(1) as f64,
            rs.velocity_evals,
            rcpu
        );
        for scheme in &o.schemes {
            for controller in &o.controllers {
                let text = with_controller(&scene(scheme, o.atol_um), controller)?;
                let (s, cpu, x) = run_scene(&text).with_context(|| format!("{label}: {scheme} with the {controller} controller"))?;
                println!(
                    "| {label} | {triangles} | {scheme} | {controller} | {} | {} | {:.1} | {} | {:.1} | {:.2e} |",
                    s.accepted,
                    s.rejected,
                    100.0 * s.rejected as f64 / (s.accepted + s.rejected).max(1) as f64,
                    s.velocity_evals,
                    cpu,
                    max_distance(&x, &rx)
                );
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_controller_line_lands_in_the_integrator_table_and_parses() {
        let case = Case::Drop { ca: 0.01, lambda: 1.0 };
        for (name, want) in [("pi", rbc_schema::scene::StepController::Pi), ("integral", rbc_schema::scene::StepController::Integral)] {
            for text in [case.scene_toml(2, "bs23", 4e-5, 1.0), paper_cell_scene(3, "ros34pw2-local", 4e-5, 1e-3)] {
                let t = with_controller(&text, name).unwrap();
                let s = Scene::parse(&t, Path::new("c.toml")).unwrap();
                assert_eq!(s.integrator.controller, want);
                assert!(with_controller(&t, name).is_err(), "a second controller line is refused");
            }
        }
        assert!(with_controller("name = \"x\"\n", "pi").is_err());
    }
}
