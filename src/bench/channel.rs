//! `rbc-bench channel`: cost of the paper's channel scene per simulated millisecond, exact no-slip and penalty walls side by side, with the step sizes each allows.
//!
//! Usage: `rbc-bench channel [--levels 3,4] [--sim-ms 0.05] [--edge 1.38] [--tol 5e-5] [--scheme ros2] [--threads 2] [--lambda 5] [--walls no-slip,penalty] [--iteration-sums plain,model,5] [--guess last,extrapolated]`.
//! `--iteration-sums` repeats each row with `ChannelOptions::iteration_sums` set to each value
//! (plain: the sums inside GMRES evaluated in full every time, model: frozen real-space blocks at
//! the cost model's cutoff, a number: at that cutoff in um; default: the scene's setting), `--guess`
//! with GMRES started from the last velocity or the extrapolated one (`ChannelOptions::extrapolate_guess`).
//!
//! Each row builds the paper's scene (examples/sweeps/paper-channel.toml: discocyte with its
//! axis along the channel, Krueger's Skalak law kappa_S = 5e-6 N/m, kappa_A = 100 kappa_S,
//! bending 3e-19 N m, 12 x 10 x 42.7 um channel, mean flow 5 mm/s, centred) at the viscosity
//! ratio `--lambda` (default 5, the paper's; 1 leaves the double layer out), with exact no-slip walls or the
//! paper's penalty springs kappa_W = 1.9e7 N/m^3, runs it for `--sim-ms` of physical time and
//! reports the CPU time of the process (core-seconds: user + system time from
//! `/proc/self/stat`, so other load on the machine does not inflate it), the accepted steps and
//! their sizes, and core-seconds per simulated millisecond. The last table extrapolates the rate
//! of each row to the 2 to 30 s of physical time the paper's runs need to reach a steady state
//! (a measured rate times the time; not a measured time to steady state). The first steps of a
//! run start at h0 = 1e-6 s and follow the fast initial relaxation of the shape, so a short window
//! gives an upper bound of the rate.

use super::clock::{load_average, process_cpu_ticks_s};
use anyhow::{bail, Context};
use rbc_schema::scene::Scene;
use rbc_solver::run::Recorder;
use std::path::Path;
use std::time::Instant;

/// The paper's scene with `level`, `wall_model` lines, wall edge, Ewald tolerance, scheme and end time.
fn scene_text(level: u32, walls: &str, edge_um: f64, tol: f64, scheme: &str, end_s: f64, lambda: f64) -> String {
    format!(
        r#"name = "bench-channel"
[cell]
shape = "discocyte"
level = {level}
position_um = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
{blocks}wall_edge_um = {edge_um}
ewald_tol = {tol:e}
{walls}
[integrator]
scheme = "{scheme}"
atol_um = 4e-5
[time]
end_s = {end_s:e}
output_interval_s = {end_s:e}
"#,
        blocks = rbc_schema::paper_scene::channel_blocks(lambda, 5000.0)
    )
}

/// One measured configuration.
#[derive(Debug, Clone)]
pub struct ChannelRunCost {
    pub triangles: usize,
    pub walls: &'static str,
    pub wall_triangles: usize,
    /// Setup (mesh, wall operator, LU, calibration) and run: wall clock and CPU seconds.
    pub setup_wall_s: f64,
    pub setup_cpu_s: f64,
    pub run_wall_s: f64,
    pub run_cpu_s: f64,
    pub sim_ms: f64,
    pub accepted: usize,
    pub rejected: usize,
    pub velocity_evals: usize,
    pub jacobian_applies: usize,
    pub h_min_s: f64,
    pub h_max_s: f64,
    pub h_mean_s: f64,
    /// Centroid velocity over the run (mm/s).
    pub velocity_mm_s: f64,
    /// Penalty walls: the explicit stability limit `2.5 / (kappa_W lambda_max(S) / mu)` (s)
    /// of Bogacki-Shampine set by the springs (Ros2 treats them implicitly); NaN for no-slip.
    pub penalty_explicit_h_s: f64,
    /// Viscosity contrast: Stokes solves, GMRES iterations, solves started from a guess.
    pub gmres: (usize, usize, usize),
}

impl ChannelRunCost {
    /// Core-seconds per simulated millisecond of the run (setup excluded).
    pub fn core_s_per_ms(&self) -> f64 {
        self.run_cpu_s / self.sim_ms
    }
}

/// Build and run the scene of one row on `threads` threads.
#[allow(clippy::too_many_arguments)]
pub fn measure(level: u32, penalty: bool, edge_um: f64, tol: f64, scheme: &str, sim_ms: f64, threads: usize, lambda: f64, iteration_cutoff: Option<rbc_solver::channel::IterationSums>, extrapolate: Option<bool>) -> anyhow::Result<ChannelRunCost> {
    let walls = if penalty { "wall_model = \"penalty\"\nkappa_w_n_m3 = 1.9e7" } else { "wall_model = \"no-slip\"" };
    let text = scene_text(level, walls, edge_um, tol, scheme, sim_ms * 1e-3, lambda);
    let scene = Scene::parse(&text, Path::new("bench-channel.toml"))?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build().context("rayon pool")?;
    pool.install(|| {
        let (c0, t0) = (process_cpu_ticks_s().unwrap_or(f64::NAN), Instant::now());
        let mut built = rbc_solver::scene::build(&scene)?;
        if let (Some(r), rbc_solver::scene::Operator::Channel(ch)) = (iteration_cutoff, &mut built.stokes) {
            ch.set_iteration_sums(r)?;
        }
        if let (Some(e), rbc_solver::scene::Operator::Channel(ch)) = (extrapolate, &mut built.stokes) {
            ch.set_extrapolate_guess(e);
        }
        let (c1, t1) = (process_cpu_ticks_s().unwrap_or(f64::NAN), Instant::now());
        let mut rec = Recorder::default();
        let (s, _) = built.run(&mut rec)?;
        let c2 = process_cpu_ticks_s().unwrap_or(f64::NAN);
        let run_wall_s = t1.elapsed().as_secs_f64();
        let penalty_explicit_h_s = match built.channel() {
            Some(ch) if penalty => 2.5 / ch.penalty_rate(1.9e7),
            _ => f64::NAN,
        };
        let n = rec.times_s.len();
        let v = (rec.centroid_um[n - 1].x - rec.centroid_um[0].x) / (rec.times_s[n - 1] - rec.times_s[0]) * 1e-3;
        Ok(ChannelRunCost {
            triangles: built.mesh.triangles.len(),
            walls: if penalty { "penalty 1.9e7" } else { "no-slip" },
            wall_triangles: built.channel().map_or(0, |c| c.mesh.triangles.len()),
            setup_wall_s: (t1 - t0).as_secs_f64(),
            setup_cpu_s: c1 - c0,
            run_wall_s,
            run_cpu_s: c2 - c1,
            sim_ms,
            accepted: s.accepted,
            rejected: s.rejected,
            velocity_evals: s.velocity_evals,
            jacobian_applies: s.jacobian_applies,
            h_min_s: s.h_min_s,
            h_max_s: s.h_max_s,
            h_mean_s: s.h_mean_s(0.0),
            velocity_mm_s: v,
            penalty_explicit_h_s,
            gmres: built.channel().map_or((0, 0, 0), |c| c.gmres_totals()),
        })
    })
}

/// Run the benchmark with the remaining command-line arguments.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let (mut levels, mut sim_ms, mut edge, mut tol, mut scheme, mut threads) = (vec![3u32, 4], 0.05, 1.38, 5e-5, "ros2".to_string(), 2usize);
    let (mut lambda, mut walls) = (5.0, vec![false, true]);
    let mut cutoffs: Vec<Option<rbc_solver::channel::IterationSums>> = vec![None];
    let mut guesses: Vec<Option<bool>> = vec![None];
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("rbc-bench channel: {a} needs a value"));
        match a.as_str() {
            "--levels" => levels = val()?.split(',').map(|s| s.trim().parse()).collect::<Result<_, _>>().context("--levels")?,
            "--sim-ms" => sim_ms = val()?.parse().context("--sim-ms")?,
            "--edge" => edge = val()?.parse().context("--edge")?,
            "--tol" => tol = val()?.parse().context("--tol")?,
            "--scheme" => scheme = val()?.clone(),
            "--threads" => threads = val()?.parse().context("--threads")?,
            "--lambda" => lambda = val()?.parse().context("--lambda")?,
            "--guess" => {
                guesses = val()?
                    .split(',')
                    .map(|w| match w.trim() {
                        "last" => Ok(Some(false)),
                        "extrapolated" => Ok(Some(true)),
                        other => bail!("rbc-bench channel: --guess takes last and/or extrapolated, not {other:?}"),
                    })
                    .collect::<anyhow::Result<_>>()?
            }
            "--iteration-sums" => {
                cutoffs = val()?
                    .split(',')
                    .map(|w| {
                        use rbc_solver::channel::IterationSums;
                        Ok(Some(match w.trim() {
                            "plain" => IterationSums::Plain,
                            "model" => IterationSums::Model,
                            r => IterationSums::Cutoff(r.parse().with_context(|| format!("--iteration-sums: {r:?} is not plain, model or a cutoff in um"))?),
                        }))
                    })
                    .collect::<anyhow::Result<_>>()?
            }
            "--walls" => {
                walls = val()?
                    .split(',')
                    .map(|w| match w.trim() {
                        "no-slip" => Ok(false),
                        "penalty" => Ok(true),
                        other => bail!("rbc-bench channel: --walls takes no-slip and/or penalty, not {other:?}"),
                    })
                    .collect::<anyhow::Result<_>>()?
            }
            other => bail!("rbc-bench channel: unknown option {other:?} (expected --levels, --sim-ms, --edge, --tol, --scheme, --threads, --lambda, --walls, --iteration-sums, --guess)"),
        }
    }
    println!("## The paper's channel scene (lambda = {lambda}, 5 mm/s, centred discocyte), {scheme}, atol 4e-5 um, wall edge {edge} um, Ewald tolerance {tol:e}, {threads} thread(s), {sim_ms} ms simulated");
    println!("load average at start: {}", load_average());
    println!("cell tri | walls | GMRES sums | GMRES guess | wall tri | setup (s wall / core-s) | run (s wall / core-s) | steps acc/rej | velocity evals | J applies | h min / mean / max (s) | u (mm/s) | core-s per sim ms | explicit h limit of the springs (s) | GMRES solves / iterations per solve / warm-started");
    println!("---|---|---|---|---|---|---|---|---|---|---|---|---|---|---");
    let mut rows = Vec::new();
    for &level in &levels {
        for &penalty in &walls {
          for &cut in &cutoffs {
           for &guess in &guesses {
            let r = measure(level, penalty, edge, tol, &scheme, sim_ms, threads, lambda, cut, guess)?;
            println!(
                "{} | {} | {} | {} | {} | {:.1} / {:.1} | {:.1} / {:.1} | {}/{} | {} | {} | {:.2e} / {:.2e} / {:.2e} | {:.3} | {:.1} | {:.2e} | {} / {:.2} / {}",
                r.triangles, r.walls, cut.map_or("default".to_string(), |c| format!("{c:?}")), guess.map_or("default", |e| if e { "extrapolated" } else { "last velocity" }), r.wall_triangles, r.setup_wall_s, r.setup_cpu_s, r.run_wall_s, r.run_cpu_s, r.accepted, r.rejected, r.velocity_evals, r.jacobian_applies, r.h_min_s, r.h_mean_s, r.h_max_s, r.velocity_mm_s, r.core_s_per_ms(), r.penalty_explicit_h_s, r.gmres.0, r.gmres.1 as f64 / r.gmres.0.max(1) as f64, r.gmres.2
            );
            rows.push(r);
           }
          }
        }
    }
    println!();
    println!("## Extrapolated time to a steady state (rate above x physical time; the paper: 2 to 30 s)");
    println!("cell tri | walls | core-days for 2 s | core-days for 30 s | days on 2 cores for 2 s");
    println!("---|---|---|---|---");
    for r in &rows {
        let per_s = r.core_s_per_ms() * 1e3; // core-s per simulated second
        println!("{} | {} | {:.1} | {:.0} | {:.1}", r.triangles, r.walls, 2.0 * per_s / 86400.0, 30.0 * per_s / 86400.0, 2.0 * per_s / 86400.0 / 2.0);
    }
    Ok(())
}
