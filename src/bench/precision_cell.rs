//! `rbc-bench precision --paper-cell MS`: core-seconds per simulated millisecond of the paper's cell for every integrator, at equal error against a tight-tolerance reference.
//!
//! Configurations (2048-triangle discocyte, lambda = 5, Krueger Skalak
//! kappa_S = 5e-6 N/m, free space, shear flow):
//! - `plain`: kappa_A = 100 kappa_S, shear 100 1/s (Ca_S = mu rate R / kappa_S = 0.096), no bending;
//! - `bending`: the same with the paper's kappa_B = 3e-19 N m (default bending method);
//! - `stiff`: kappa_A = 1000 kappa_S, Ca_S = 0.01 (shear 10.4 1/s), no bending.
//!
//! Each configuration runs `MS` simulated milliseconds from rest (h0 = 1e-6 s) with
//! each scheme at `atol` and once with the reference scheme at `atol / reference_factor`;
//! the error is the largest vertex distance (um) between the final shapes. Core-seconds
//! are the process CPU time (user + system, /proc/self/stat) spent in the run, so
//! other jobs on a shared machine do not inflate them. Schemes: `bs23`, `ros2`,
//! `ros34pw2` (lagged-mobility J, GMRES preconditioned by the local sparse J),
//! `ros34pw2-plain` (the same without preconditioner), `ros34pw2-local` (J = J_loc, direct solves).

use super::clock::process_cpu_ticks_s;
use anyhow::{bail, Context, Result};
use rbc_schema::scene::Scene;
use rbc_solver::integrate::bs23::BogackiShampine;
use rbc_solver::dynamics::cell::CellDynamics;
use rbc_solver::integrate::ros34pw2::{Ros34pw2, StageJacobian};
use rbc_solver::integrate::rosenbrock::Ros2;
use rbc_solver::dynamics::volume::no_flux;
use rbc_solver::run::{Recorder, RunSummary, Runner};
use std::path::Path;
use std::time::Instant;

/// One configuration of the paper's cell.
#[derive(Debug, Clone, Copy)]
pub struct CellConfig {
    pub name: &'static str,
    pub kappa_a_n_m: f64,
    pub shear_rate_1_s: f64,
    pub bending_n_m: Option<f64>,
}

/// `plain`, `bending`, `stiff` (see the module docs).
pub fn config(name: &str) -> Result<CellConfig> {
    let ks = 5e-6;
    // Ca_S = mu rate R / kappa_S with mu = 1.2e-3 Pa s, R = 4 um
    let rate_for = |ca: f64| ca * ks / (1.2e-3 * 4e-6);
    Ok(match name {
        "plain" => CellConfig { name: "plain", kappa_a_n_m: 100.0 * ks, shear_rate_1_s: 100.0, bending_n_m: None },
        "bending" => CellConfig { name: "bending", kappa_a_n_m: 100.0 * ks, shear_rate_1_s: 100.0, bending_n_m: Some(3e-19) },
        "stiff" => CellConfig { name: "stiff", kappa_a_n_m: 1000.0 * ks, shear_rate_1_s: rate_for(0.01), bending_n_m: None },
        other => bail!("--paper-configs: unknown configuration {other} (plain, bending, stiff)"),
    })
}

fn scene_text(c: &CellConfig, atol_um: f64, end_s: f64) -> String {
    let bending = c.bending_n_m.map(|kb| format!("[membrane.bending]\nkappa_b_n_m = {kb:e}\n")).unwrap_or_default();
    format!(
        "name = \"paper-cell-{name}\"\n[cell]\nshape = \"discocyte\"\nlevel = 4\n[membrane.skalak]\nconvention = \"krueger\"\nkappa_s_n_m = 5e-6\nkappa_a_n_m = {ka:e}\n{bending}\
         [fluid]\nviscosity_pa_s = 1.2e-3\nlambda = 5.0\n[flow]\nkind = \"shear\"\nshear_rate_1_s = {rate:e}\n[integrator]\nscheme = \"bs23\"\natol_um = {atol_um:e}\nh0_s = 1e-6\n\
         [time]\nend_s = {end_s:e}\noutput_interval_s = {end_s:e}\n",
        name = c.name,
        ka = c.kappa_a_n_m,
        rate = c.shear_rate_1_s,
    )
}

/// Outcome of one run.
#[derive(Debug, Clone)]
pub struct CellRun {
    pub summary: RunSummary,
    pub cpu_s: f64,
    pub wall_s: f64,
    pub vertices: Vec<nalgebra::Vector3<f64>>,
    /// Stage solves and GMRES iterations (Rosenbrock schemes).
    pub stage_solves: usize,
    pub gmres_iterations: usize,
    pub stokes_solves: usize,
}

/// Run configuration `c` with `scheme` at `atol_um` for `end_s` seconds.
pub fn run_cell(c: &CellConfig, scheme: &str, atol_um: f64, end_s: f64) -> Result<CellRun> {
    let text = scene_text(c, atol_um, end_s);
    let scene = Scene::parse(&text, Path::new("paper-cell.toml"))?;
    let built = rbc_solver::scene::build(&scene)?;
    let tris = built.mesh.triangles.clone();
    let mut x = built.mesh.vertices.clone();
    let cell = CellDynamics::new(tris.clone(), &built.membrane, &built.stokes);
    let mut dynamics = no_flux(cell, &tris);
    let runner = Runner::new(built.run.clone());
    let cpu0 = process_cpu_ticks_s();
    let t0 = Instant::now();
    let (summary, stats) = match scheme {
        // the Rosenbrock-W variants report their stage statistics
        s if s.starts_with("ros34pw2") => {
            let mut r = match s {
                "ros34pw2" => Ros34pw2::with(StageJacobian::Lagged, true),
                "ros34pw2-plain" => Ros34pw2::with(StageJacobian::Lagged, false),
                "ros34pw2-local" => Ros34pw2::with(StageJacobian::Local, false),
                other => bail!("unknown scheme {other}"),
            };
            let sm = runner.run(&mut dynamics, &mut r, &tris, &mut x, &mut Recorder::default()).with_context(|| format!("{} {scheme}", c.name))?;
            (sm, (r.stats.solves, r.stats.iterations))
        }
        "bs23" => (runner.run(&mut dynamics, &mut BogackiShampine::new(), &tris, &mut x, &mut Recorder::default()).with_context(|| format!("{} {scheme}", c.name))?, (0, 0)),
        "ros2" => (runner.run(&mut dynamics, &mut Ros2::new(), &tris, &mut x, &mut Recorder::default()).with_context(|| format!("{} {scheme}", c.name))?, (0, 0)),
        other => bail!("unknown scheme {other} (bs23, ros2, ros34pw2, ros34pw2-plain, ros34pw2-local)"),
    };
    let wall_s = t0.elapsed().as_secs_f64();
    let cpu_s = match (cpu0, process_cpu_ticks_s()) {
        (Some(a), Some(b)) => b - a,
        _ => wall_s * rayon::current_num_threads() as f64,
    };
    let stokes_solves = dynamics.inner.work.stokes_solves;
    Ok(CellRun { summary, cpu_s, wall_s, vertices: x, stage_solves: stats.0, gmres_iterations: stats.1, stokes_solves })
}

/// Largest vertex distance (um).
pub fn max_distance(a: &[nalgebra::Vector3<f64>], b: &[nalgebra::Vector3<f64>]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max)
}

/// Print the table for `configs` x `schemes`.
/// Every scheme runs at every tolerance of `atols_um`; the reference at `atol_um / reference_factor`.
pub fn run(configs: &[String], schemes: &[String], sim_ms: f64, atol_um: f64, atols_um: &[f64], reference: &str, reference_factor: f64) -> Result<()> {
    let end_s = sim_ms * 1e-3;
    println!("\n## Paper's cell: {sim_ms} ms from rest, atol {atol_um:e} um, reference {reference} at atol / {reference_factor}");
    println!("| config | integrator | atol (um) | steps (rejected) | mean h (s) | Stokes solves | GMRES its / stage | max error (um) | wall (s) | core-s | core-s per simulated ms |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for name in configs {
        let c = config(name)?;
        let r = run_cell(&c, reference, atol_um / reference_factor, end_s)?;
        println!(
            "| {} | {reference} (reference) | {:.1e} | {} ({}) | {:.2e} | {} | - | - | {:.1} | {:.1} | {:.0} |",
            c.name,
            atol_um / reference_factor,
            r.summary.accepted,
            r.summary.rejected,
            r.summary.h_mean_s(0.0),
            r.stokes_solves,
            r.wall_s,
            r.cpu_s,
            r.cpu_s / sim_ms
        );
        for (scheme, &atol) in schemes.iter().flat_map(|s| atols_um.iter().map(move |a| (s, a))) {
            match run_cell(&c, scheme, atol, end_s) {
                Ok(s) => {
                    let its = if s.stage_solves > 0 { format!("{:.1}", s.gmres_iterations as f64 / s.stage_solves as f64) } else { "-".into() };
                    println!(
                        "| {} | {scheme} | {atol:.1e} | {} ({}) | {:.2e} | {} | {its} | {:.2e} | {:.1} | {:.1} | {:.0} |",
                        c.name,
                        s.summary.accepted,
                        s.summary.rejected,
                        s.summary.h_mean_s(0.0),
                        s.stokes_solves,
                        max_distance(&s.vertices, &r.vertices),
                        s.wall_s,
                        s.cpu_s,
                        s.cpu_s / sim_ms
                    );
                }
                Err(e) => println!("| {} | {scheme} | {atol:.1e} | failed: {e:#} | | | | | | | |", c.name),
            }
        }
    }
    Ok(())
}
