//! `rbc-bench channel-cost`: cost of one channel Stokes solve (no-slip walls, paper geometry, lambda = 1) at 512, 2048 and 8192 cell triangles, split into Ewald real/Fourier parts, wall LU back-substitution and the rest.
//!
//! Usage: `rbc-bench channel-cost [--levels 3,4,5] [--threads 1] [--repeats 3]`.
//!
//! For each discocyte level (8 * 4^level triangles) a `ChannelStokes` is built
//! with the paper's geometry and Ewald tolerance 5e-5, its Ewald parameters tuned
//! for the actual number of cell quadrature nodes (`cell_nodes_hint = 7 * triangles`),
//! and `velocity` is timed (best of `repeats`) for a discocyte on the channel axis
//! carrying a smooth force density. The solve reports its own Ewald time, its wall
//! back-substitution time and its total; the rest (cell surface set-up, Duffy
//! corrections of the touching triangles, wall-force sums) is the difference. The
//! real-space / Fourier-space split is measured by repeating the solve's three
//! Ewald sums (cell -> cell + wall vertices, the normal-singularity sum cell -> cell,
//! wall -> cell vertices, its spreading precomputed as in the solve) with the same parameters and the two halves of
//! `PeriodicStokes` called separately. The spectral Ewald method costs
//! `O(N log N)` for `N` points when its grid grows with `N` (Lindbo & Tornberg,
//! J. Comput. Phys. 229, 8994 (2010)), so `Ewald time / (N log2 N)` should stay
//! roughly constant; here `N` is the number of targets plus sources summed over the three sums,
//! the wall's quadrature nodes counted as its vertices (their spreading to the grid is precomputed
//! once, so a solve only touches the nodal wall traction and the nodes near the cell).

use super::clock::{load_average, process_cpu_s};
use anyhow::{bail, Context};
use nalgebra::{Rotation3, Vector3};
use rbc_solver::bim::kernels::LANES;
use rbc_solver::viscosity::ViscosityContrast;
use rbc_solver::bim::surface::Surface;
use rbc_solver::channel::wall::WallNodes;
use rbc_solver::channel::{ChannelGeometry, ChannelOptions, ChannelStokes, WallMode};
use rbc_solver::ewald::PeriodicStokes;
use std::time::Instant;

/// One row of the table (times in s: CPU times of one thread, except `build_s` and `solve_wall_s`).
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelCost {
    pub cell_triangles: usize,
    /// Ewald splitting parameter (1/um), real-space cutoff (um), FFT grid.
    pub xi: f64,
    pub r_cut_um: f64,
    pub grid: [usize; 3],
    /// Building the solver (wall operator assembly and LU, calibration).
    pub build_s: f64,
    /// One `velocity` call: wall clock (as the solve reports it) and CPU time.
    pub solve_wall_s: f64,
    pub total_s: f64,
    /// Its parts: the solve's three Ewald sums repeated with the real and Fourier parts
    /// timed apart, one LU back-substitution of the wall operator, and the rest (total - parts).
    pub real_s: f64,
    pub fourier_s: f64,
    pub wall_lu_s: f64,
    pub rest_s: f64,
    /// Targets plus sources over the Ewald sums of one solve.
    pub n_points: usize,
}

impl ChannelCost {
    /// Ewald time (real + Fourier) / (N log2 N), in ns.
    pub fn ewald_per_n_log_n_ns(&self) -> f64 {
        let n = self.n_points as f64;
        (self.real_s + self.fourier_s) / (n * n.log2()) * 1e9
    }
}

/// CPU time (s) of this process so far ([`process_cpu_s`]), an error off Linux.
fn cpu_s() -> anyhow::Result<f64> {
    process_cpu_s().context("/proc/self/task/*/schedstat (CPU times need Linux)")
}

/// Best CPU time (s) of `repeats` calls of `f` (its result from the last call).
fn best_of<T>(repeats: usize, mut f: impl FnMut() -> anyhow::Result<T>) -> anyhow::Result<(f64, T)> {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let t = cpu_s()?;
        let r = f()?;
        best = best.min(cpu_s()? - t);
        last = Some(r);
    }
    Ok((best, last.expect("at least one repeat")))
}

/// Time one channel solve for the discocyte of `level` on `threads` threads (best of `repeats`).
pub fn channel_cost(level: usize, threads: usize, repeats: usize) -> anyhow::Result<ChannelCost> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build().context("rayon thread pool")?;
    pool.install(|| {
        let cell = rbc_solver::mesh::discocyte(level);
        let n_tri = cell.triangles.len();
        let opts = ChannelOptions { ewald_tol: 5e-5, cell_nodes_hint: 7 * n_tri, ..ChannelOptions::default() };
        let t0 = Instant::now();
        let ch = ChannelStokes::new(ChannelGeometry::default(), 1.2e-3, ViscosityContrast::MATCHED, WallMode::NoSlip, opts.clone()).context("build the channel solver")?;
        let build_s = t0.elapsed().as_secs_f64();
        // discocyte axis (z) turned onto the channel axis x, in the middle of the box
        let rot = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
        let cell = cell.transformed(&rot, &Vector3::new(0.5 * ch.geometry.length_x, 0.0, 0.0));
        let f: Vec<Vector3<f64>> = cell.vertices.iter().map(|x| Vector3::new(0.05 * x.x, -0.3 * x.y, -0.3 * x.z)).collect();
        let mut solve_wall_s = f64::INFINITY;
        let (total_s, s) = best_of(repeats, || {
            let (_, s) = ch.velocity(&cell, &f, 1.0).context("channel solve")?;
            solve_wall_s = solve_wall_s.min(s.total_seconds);
            Ok(s)
        })?;
        let rhs = vec![Vector3::new(0.3, -0.1, 0.2); ch.mesh.n_vertices()];
        let (wall_lu_s, _) = best_of(repeats, || Ok(ch.wall.solve(&rhs)))?;

        // the same three Ewald sums, real and Fourier parts apart
        let ewald = PeriodicStokes::new(ch.box_len(), *ch.ewald_params()).context("Ewald set-up")?;
        let surface = Surface::new(&cell).context("cell surface")?;
        let chunks = surface.chunks_with_density(&f, true);
        let nodes: Vec<Vector3<f64>> = (0..surface.n_nodes).map(|p| {
            let c = &chunks[p / LANES];
            let l = p % LANES;
            Vector3::new(c.x[l], c.y[l], c.z[l])
        }).collect();
        let node_f: Vec<Vector3<f64>> = (0..surface.n_nodes).map(|p| {
            let c = &chunks[p / LANES];
            let l = p % LANES;
            Vector3::new(c.dx[l], c.dy[l], c.dz[l])
        }).collect();
        let wall = WallNodes::refined(&ch.mesh, opts.wall_eval_refine);
        let wall_f = wall.forces(&vec![Vector3::new(1.0, 0.2, -0.1); ch.mesh.n_vertices()]);
        let mut cell_and_wall = surface.vertices.clone();
        cell_and_wall.extend_from_slice(&ch.mesh.vertices);
        type Sum<'a> = (&'a [Vector3<f64>], &'a [Vector3<f64>], &'a [Vector3<f64>]); // targets, sources, forces
        let sums: [Sum<'_>; 3] = [
            (&cell_and_wall, &nodes, &node_f),
            (&surface.vertices, &nodes, &node_f),
            (&surface.vertices, &wall.positions, &wall_f),
        ];
        let (mut real_s, mut fourier_s, mut n_points) = (0.0, 0.0, 0);
        // the wall's spreading is precomputed (its nodes never move), as the solve does
        let spread = ewald.basis_spread(&wall.positions, &wall.weights, &wall.interp, ch.mesh.n_vertices()).context("wall spreading")?;
        let wall_nodal = vec![Vector3::new(1.0, 0.2, -0.1); ch.mesh.n_vertices()];
        for (k, (targets, sources, forces)) in sums.into_iter().enumerate() {
            let mut out = vec![Vector3::zeros(); targets.len()];
            real_s += best_of(repeats, || {
                ewald.stokeslet_real(targets, sources, forces, &mut out);
                Ok(())
            })?
            .0;
            fourier_s += best_of(repeats, || {
                if k == 2 {
                    ewald.stokeslet_fourier_basis_add(&spread, &wall_nodal, targets, &mut out)?;
                } else {
                    ewald.stokeslet_fourier_add(targets, sources, forces, &mut out);
                }
                Ok(())
            })?
            .0;
            // the wall's nodes enter through their precomputed spreading: count its nodal values
            n_points += targets.len() + if k == 2 { ch.mesh.n_vertices() } else { sources.len() };
        }
        if s.ewald_sums != 3 {
            bail!("the solve did {} Ewald sums, the split repeats 3", s.ewald_sums);
        }
        let p = ch.ewald_params();
        Ok(ChannelCost {
            cell_triangles: n_tri,
            xi: p.xi,
            r_cut_um: p.r_cut,
            grid: p.grid,
            build_s,
            solve_wall_s,
            total_s,
            real_s,
            fourier_s,
            wall_lu_s,
            rest_s: total_s - real_s - fourier_s - wall_lu_s,
            n_points,
        })
    })
}

/// Run the benchmark with the remaining command-line arguments.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let (mut levels, mut threads, mut repeats) = (vec![3usize, 4, 5], 1usize, 3usize);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().cloned().with_context(|| format!("rbc-bench channel-cost: {name} needs a value"));
        match a.as_str() {
            "--levels" => {
                levels = value("--levels")?
                    .split(',')
                    .map(|s| s.trim().parse::<usize>().with_context(|| format!("--levels: {s:?} is not a mesh level")))
                    .collect::<anyhow::Result<_>>()?
            }
            "--threads" => threads = value("--threads")?.parse().context("--threads: not a number")?,
            "--repeats" => repeats = value("--repeats")?.parse().context("--repeats: not a number")?,
            other => bail!("rbc-bench channel-cost: unknown option {other:?} (expected --levels, --threads, --repeats)"),
        }
    }
    if let Some(l) = levels.iter().find(|l| **l > 6) {
        bail!("--levels: {l} is above the largest mesh level 6");
    }
    println!("## One channel Stokes solve (no-slip walls, lambda = 1, Ewald tol 5e-5, wall edge 1.38 um), {threads} thread(s), best of {repeats}");
    println!("(CPU seconds of one thread, best of the repeats; build and solve wall-clock for reference; machine load {})", load_average());
    println!("cell tri | xi (1/um) | r_cut (um) | grid | build wall (s) | solve wall (s) | solve CPU (s) | Ewald real (s) | Ewald Fourier (s) | wall LU (s) | rest (s) | N | Ewald/(N log2 N) (ns)");
    println!("---|---|---|---|---|---|---|---|---|---|---|---|---");
    for level in levels {
        let c = channel_cost(level, threads, repeats)?;
        println!(
            "{} | {:.3} | {:.2} | {}x{}x{} | {:.2} | {:.3} | {:.3} | {:.3} | {:.3} | {:.4} | {:.3} | {} | {:.2}",
            c.cell_triangles,
            c.xi,
            c.r_cut_um,
            c.grid[0],
            c.grid[1],
            c.grid[2],
            c.build_s,
            c.solve_wall_s,
            c.total_s,
            c.real_s,
            c.fourier_s,
            c.wall_lu_s,
            c.rest_s,
            c.n_points,
            c.ewald_per_n_log_n_ns()
        );
    }
    Ok(())
}
