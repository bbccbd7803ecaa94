//! `rbc-bench near-field`: the cost of the near-singular quadrature ([`rbc_solver::bim::near_field`]) against one channel solve, with the correction on and off side by side.
//!
//! Usage: `rbc-bench near-field [--levels 3,4] [--lambda 5] [--edge 2.0] [--tol 1e-4] [--threads 1] [--repeats 2] [--reach R] [--eta E] [--skip-rings K]`
//! (`--reach`, `--eta`: the correction measured, default [`NearFieldOptions::default`]).
//! For each mesh level of the discocyte: the corrected pairs and 7-point pieces, the CPU time of
//! building the correction, and the CPU time of one cold channel solve (no-slip walls, the paper's
//! geometry, mean flow 5 mm/s, cell on the axis with a smooth force density) with the default
//! correction and without it, and how much the velocity changes. CPU seconds of the process
//! (`/proc/self/task/*/schedstat`), best of the repeats, both variants in the same run.

use anyhow::{bail, Context};
use nalgebra::{Rotation3, Vector3};
use super::clock::{best_cpu, load_average};
use rbc_solver::bim::near_field::{NearField, NearFieldOptions};
use rbc_solver::viscosity::ViscosityContrast;
use rbc_solver::bim::surface::Surface;
use rbc_solver::channel::{ChannelGeometry, ChannelOptions, ChannelStokes, WallMode};

/// Run the benchmark with the remaining command-line arguments.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let (mut levels, mut lambda, mut edge, mut tol, mut threads, mut repeats) = (vec![3usize, 4], 5.0, 2.0, 1e-4, 1usize, 2usize);
    let mut near = NearFieldOptions::default();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("rbc-bench near-field: {a} needs a value"));
        match a.as_str() {
            "--levels" => levels = val()?.split(',').map(|s| s.trim().parse()).collect::<Result<_, _>>().context("--levels")?,
            "--lambda" => lambda = val()?.parse().context("--lambda")?,
            "--edge" => edge = val()?.parse().context("--edge")?,
            "--tol" => tol = val()?.parse().context("--tol")?,
            "--threads" => threads = val()?.parse().context("--threads")?,
            "--repeats" => repeats = val()?.parse().context("--repeats")?,
            "--reach" => near.reach = val()?.parse().context("--reach")?,
            "--eta" => near.eta = val()?.parse().context("--eta")?,
            "--skip-rings" => near.skip_rings = val()?.parse().context("--skip-rings")?,
            other => bail!("rbc-bench near-field: unknown option {other:?} (expected --levels, --lambda, --edge, --tol, --threads, --repeats, --reach, --eta, --skip-rings)"),
        }
    }
    if let Some(l) = levels.iter().find(|&&l| l > 6) {
        bail!("--levels: {l} is above the largest mesh level 6");
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build().context("rayon pool")?;
    println!(
        "## Near-singular quadrature (reach {}, eta {}) against one channel solve (no-slip, lambda = {lambda}, wall edge {edge} um, Ewald tol {tol:e}), {threads} thread(s), load {}\n",
        near.reach,
        near.eta,
        load_average()
    );
    println!("cell triangles | pairs per vertex | pieces per pair | build (CPU s) | solve with (CPU s) | solve without (CPU s) | ratio | max |u_with - u_without| / max |u|");
    println!("---|---|---|---|---|---|---|---");
    pool.install(|| -> anyhow::Result<()> {
        for &level in &levels {
            let cell = rbc_solver::mesh::discocyte(level);
            let n_tri = cell.triangles.len();
            let base = ChannelOptions { ewald_tol: tol, wall_edge_um: edge, cell_nodes_hint: 7 * n_tri, near_field: near, ..ChannelOptions::default() };
            let with = ChannelStokes::new(ChannelGeometry::default(), 1.2e-3, ViscosityContrast::new(lambda).unwrap(), WallMode::NoSlip, base.clone())?;
            let without = ChannelStokes::new(
                ChannelGeometry::default(),
                1.2e-3,
                ViscosityContrast::new(lambda).unwrap(),
                WallMode::NoSlip,
                ChannelOptions { near_field: NearFieldOptions::off(), ..base },
            )?;
            let rot = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
            let cell = cell.transformed(&rot, &Vector3::new(0.5 * with.geometry.length_x, 0.0, 0.0));
            let c = cell.centroid();
            let f: Vec<Vector3<f64>> = cell.vertices.iter().map(|x| Vector3::new(4.0, x.y - c.y, -0.5 * (x.z - c.z))).collect();
            let surface = Surface::new(&cell)?;
            let (build_s, nf) = best_cpu(repeats, || NearField::new(&surface, &near));
            let (with_s, a) = best_cpu(repeats, || with.velocity_with_guess(&cell, &f, 5.0, None));
            let (without_s, b) = best_cpu(repeats, || without.velocity_with_guess(&cell, &f, 5.0, None));
            let (a, b) = (a?.cell_velocity, b?.cell_velocity);
            let umax = a.iter().map(|v| v.norm()).fold(0.0, f64::max);
            let diff = a.iter().zip(&b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max);
            println!(
                "{n_tri} | {:.1} | {:.1} | {build_s:.4} | {with_s:.3} | {without_s:.3} | {:.3} | {:.1e}",
                nf.pairs() as f64 / surface.n_vertices() as f64,
                nf.pieces() as f64 / nf.pairs().max(1) as f64,
                with_s / without_s,
                diff / umax
            );
        }
        Ok(())
    })
}
