//! `rbc-bench channel-profile`: where the time of one viscosity-contrast channel solve goes (each kind of Ewald sum, real and Fourier parts, real-space pair counts).
//!
//! Usage: `rbc-bench channel-profile [--level 3] [--lambda 5] [--edge 2.0] [--tol 1e-4] [--threads 1] [--repeats 2] [--cutoffs 0,4,5,6]`.
//! The last table repeats the solve with the real-space parts of the sums inside GMRES frozen
//! into block-sparse matrices at each real-space cutoff (um; 0: the cost model's choice), against
//! the plain solve, and times their parts as the solve builds them (the cell's stresslet blocks
//! with the single layer's real part fused in, the wall's Stokeslet blocks group by group). The
//! first table's sums are the plain path's (`IterationSums::Plain`), where the single layer is a
//! sum of its own.
//! Times are CPU seconds of the process (`/proc/self/task/*/schedstat`), best of the repeats.

use anyhow::{bail, Context};
use nalgebra::{Rotation3, Vector3};

use super::clock::load_average;
use rbc_solver::bim::surface::Surface;
use rbc_solver::viscosity::ViscosityContrast;
use rbc_solver::channel::cell_layer::CellNodes;
use rbc_solver::channel::wall::WallNodes;
use rbc_solver::channel::{ChannelError, ChannelGeometry, ChannelOptions, ChannelStokes, IterationSums, WallMode};
use rbc_solver::ewald::real_space::CellList;
use rbc_solver::ewald::lanes32::BlockPrecision;
use rbc_solver::ewald::PeriodicStokes;

/// Run the benchmark with the remaining command-line arguments.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let (mut level, mut lambda, mut edge, mut tol, mut threads, mut repeats) = (3usize, 5.0, 2.0, 1e-4, 1usize, 2usize);
    let mut cutoffs = vec![0.0, 4.0, 5.0, 6.0];
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("rbc-bench channel-profile: {a} needs a value"));
        match a.as_str() {
            "--level" => level = val()?.parse().context("--level")?,
            "--lambda" => lambda = val()?.parse().context("--lambda")?,
            "--edge" => edge = val()?.parse().context("--edge")?,
            "--tol" => tol = val()?.parse().context("--tol")?,
            "--threads" => threads = val()?.parse().context("--threads")?,
            "--repeats" => repeats = val()?.parse().context("--repeats")?,
            "--cutoffs" => cutoffs = val()?.split(',').map(|s| s.trim().parse()).collect::<Result<_, _>>().context("--cutoffs")?,
            other => bail!("rbc-bench channel-profile: unknown option {other:?} (expected --level, --lambda, --edge, --tol, --threads, --repeats, --cutoffs)"),
        }
    }
    if level > 6 {
        bail!("--level: {level} is above the largest mesh level 6");
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build().context("rayon pool")?;
    let p = pool.install(|| profile(level, lambda, edge, tol, repeats, &cutoffs)).context("channel profile")?;
    println!("## One channel solve (no-slip, lambda = {lambda}, wall edge {edge} um, Ewald tol {tol:e}), {threads} thread(s), load {}", load_average());
    println!("{}", profile_table(&p));
    Ok(())
}

/// CPU seconds (best of `repeats`) of `f`.
fn best_cpu(repeats: usize, f: impl FnMut()) -> f64 {
    super::clock::best_cpu(repeats, f).0
}

/// One kind of Ewald sum of the solve.
#[derive(Debug, Clone, PartialEq)]
pub struct SumCost {
    pub name: &'static str,
    pub targets: usize,
    pub sources: usize,
    /// Real-space pairs within the cutoff.
    pub pairs: usize,
    /// CPU seconds of the real and the Fourier part (best of the repeats).
    pub real_s: f64,
    pub fourier_s: f64,
    /// How many of these one solve does.
    pub per_solve: usize,
}

/// One solve with the frozen sums inside GMRES at cutoff `r_cut_um` (requested, or the cost model's for 0), against the plain solve.
#[derive(Debug, Clone, PartialEq)]
pub struct FastRow {
    pub r_cut_um: f64,
    pub xi: f64,
    pub grid: [usize; 3],
    pub iterations: usize,
    pub cpu_s: f64,
    pub ewald_wall_s: f64,
    /// `|u_fast - u_plain| / |u_plain|` over the membrane velocities.
    pub relative_difference: f64,
    /// CPU s: stresslet blocks build (the single layer's real part fused in, as the solve builds
    /// them), spreading build, blocks apply, Fourier (precomputed spreading); wall Stokeslet
    /// blocks build (group by group), apply, Fourier (precomputed spreading); the stresslet blocks
    /// build again with the kernels in single precision ([`BlockPrecision::Single`]).
    pub parts: [f64; 8],
    /// The stresslet's precomputed spreading: stored entries and heap memory (bytes).
    pub stresslet_spread: (usize, usize),
}

/// The profile of one solve.
#[derive(Debug, Clone)]
pub struct SolveProfile {
    pub cell_triangles: usize,
    pub wall_vertices: usize,
    pub xi: f64,
    pub r_cut_um: f64,
    pub grid: [usize; 3],
    pub support: usize,
    pub iterations: usize,
    pub solve_cpu_s: f64,
    pub ewald_wall_s: f64,
    pub wall_lu_wall_s: f64,
    pub total_wall_s: f64,
    pub sums: Vec<SumCost>,
    pub fast: Vec<FastRow>,
}

fn count_pairs(box_len: [f64; 3], r_cut: f64, targets: &[Vector3<f64>], sources: &[Vector3<f64>]) -> usize {
    let cells = CellList::new(box_len, r_cut, sources);
    let rc2 = r_cut * r_cut;
    let mut n = 0usize;
    for x in targets {
        cells.for_each_neighbour(x, |t, range| {
            for s in range {
                let (rx, ry, rz) = (t[0] - cells.x[s], t[1] - cells.y[s], t[2] - cells.z[s]);
                if rx * rx + ry * ry + rz * rz < rc2 {
                    n += 1;
                }
            }
        });
    }
    n
}

/// The paper's channel scene (default geometry, mu = 1.2 mPa s, mean flow 5 mm/s) at `lambda`
/// with no-slip walls of edge `edge_um` and Ewald tolerance `tol`, a discocyte of `level` on the
/// axis with a smooth force density; one solve (from rest) timed and its sums profiled.
pub fn profile(level: usize, lambda: f64, edge_um: f64, tol: f64, repeats: usize, cutoffs: &[f64]) -> Result<SolveProfile, ChannelError> {
    let cell = rbc_solver::mesh::discocyte(level);
    let n_tri = cell.triangles.len();
    let opts = ChannelOptions { ewald_tol: tol, wall_edge_um: edge_um, cell_nodes_hint: 7 * n_tri, ..ChannelOptions::default() };
    let opts = ChannelOptions { iteration_sums: IterationSums::Plain, ..opts };
    let mut ch = ChannelStokes::new(ChannelGeometry::default(), 1.2e-3, ViscosityContrast::new(lambda).unwrap(), WallMode::NoSlip, opts.clone())?;
    let rot = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
    let cell = cell.transformed(&rot, &Vector3::new(0.5 * ch.geometry.length_x, 0.0, 0.0));
    let c = cell.centroid();
    let f: Vec<Vector3<f64>> = cell.vertices.iter().map(|x| Vector3::new(4.0, x.y - c.y, -0.5 * (x.z - c.z))).collect();
    let surface = Surface::new(&cell)?;
    let nodes = CellNodes::new(&surface);
    let wall = WallNodes::refined(&ch.mesh, opts.wall_eval_refine);
    let mut cell_and_wall = surface.vertices.clone();
    cell_and_wall.extend_from_slice(&ch.mesh.vertices);
    let b = ch.box_len();
    let mut sol = None;
    let solve_cpu_s = best_cpu(repeats, || sol = Some(ch.velocity_with_guess(&cell, &f, 5.0, None)));
    let reference = sol.take().expect("one repeat")?;
    let st = reference.stats.clone();
    let norm = |v: &[Vector3<f64>]| v.iter().map(|x| x.norm_squared()).sum::<f64>().sqrt();
    let mut fast = Vec::new();
    for &r_cut in cutoffs {
        // 0: the cost model's choice
        ch = ch.with_iteration_sums(if r_cut > 0.0 { IterationSums::Cutoff(r_cut) } else { IterationSums::Model })?;
        let cpu_s = best_cpu(repeats, || sol = Some(ch.velocity_with_guess(&cell, &f, 5.0, None)));
        let s = sol.take().expect("one repeat")?;
        let diff: Vec<Vector3<f64>> = s.cell_velocity.iter().zip(&reference.cell_velocity).map(|(a, b)| a - b).collect();
        let p = ch.iteration_ewald_params().copied();
        // The parts of the frozen sums at this cutoff.
        let mut parts = [0.0; 8];
        let mut stresslet_spread = (0, 0);
        if let Some(pe) = p {
            let e = PeriodicStokes::new(b, pe)?;
            let bary = rbc_solver::channel::double_layer::rule_bary(&surface);
            let groups = rbc_solver::ewald::NodeGroups { sources: &nodes.positions, normals: &nodes.weighted_normals, groups: &surface.triangles, bary: &bary };
            let nc = surface.n_vertices();
            // the solve's build: the stresslet blocks with the single layer's real part fused in
            let (_, node_forces) = rbc_solver::channel::cell_layer::weighted_node_forces(&surface, &f);
            let mut blocks = None;
            parts[0] = best_cpu(repeats, || blocks = Some(e.stresslet_real_blocks_with_single_layer(&cell_and_wall, groups, Some(&node_forces), nc, BlockPrecision::Double)));
            parts[7] = best_cpu(repeats, || drop(e.stresslet_real_blocks_with_single_layer(&cell_and_wall, groups, Some(&node_forces), nc, BlockPrecision::Single)));
            let (blocks, _) = blocks.expect("one repeat")?;
            let mut cs = None;
            parts[1] = best_cpu(repeats, || cs = Some(e.stresslet_basis_spread(&nodes.positions, &nodes.weighted_normals, &rbc_solver::channel::double_layer::node_interp(&surface), nc)));
            let cs = cs.expect("one repeat")?;
            stresslet_spread = (cs.n_entries(), cs.bytes());
            let u = vec![Vector3::new(1.0, 0.2, -0.1); nc];
            let mut out = vec![Vector3::zeros(); cell_and_wall.len()];
            parts[2] = best_cpu(repeats, || blocks.apply(&u, &mut out));
            parts[3] = best_cpu(repeats, || e.stresslet_fourier_basis_add(&cs, &u, &cell_and_wall, &mut out).expect("finite"));
            let nw = ch.mesh.n_vertices();
            let mut wb = None;
            parts[4] = best_cpu(repeats, || wb = Some(e.stokeslet_real_blocks_grouped(&surface.vertices, &wall.positions, &wall.weights, &wall.interp, WallNodes::PER_SUB_TRIANGLE, nw)));
            let wb = wb.expect("one repeat")?;
            let fw = vec![Vector3::new(1.0, 0.2, -0.1); nw];
            let mut out = vec![Vector3::zeros(); nc];
            parts[5] = best_cpu(repeats, || wb.apply(&fw, &mut out));
            let spread = e.basis_spread(&wall.positions, &wall.weights, &wall.interp, nw)?;
            parts[6] = best_cpu(repeats, || e.stokeslet_fourier_basis_add(&spread, &fw, &surface.vertices, &mut out).expect("finite"));
        }
        fast.push(FastRow {
            r_cut_um: p.map_or(f64::NAN, |p| p.r_cut),
            xi: p.map_or(f64::NAN, |p| p.xi),
            grid: p.map_or([0; 3], |p| p.grid),
            iterations: s.stats.gmres_iterations,
            cpu_s,
            ewald_wall_s: s.stats.ewald_seconds,
            relative_difference: norm(&diff) / norm(&reference.cell_velocity),
            parts,
            stresslet_spread,
        });
    }

    let p = *ch.ewald_params();
    let ewald = PeriodicStokes::new(b, p)?;

    let unit = vec![Vector3::new(1.0, 0.2, -0.1); nodes.positions.len().max(wall.positions.len())];
    let mut sums = Vec::new();
    let it = st.gmres_iterations;
    // (name, targets, sources, stresslet?, per solve)
    type Kind<'a> = (&'static str, &'a [Vector3<f64>], &'a [Vector3<f64>], bool, usize);
    let kinds: [Kind<'_>; 3] = [
        ("stresslet cell -> cell+wall", &cell_and_wall, &nodes.positions, true, it + 1),
        ("Stokeslet wall -> cell", &surface.vertices, &wall.positions, false, it + 1),
        ("Stokeslet cell -> cell+wall", &cell_and_wall, &nodes.positions, false, 1),
    ];
    for (name, targets, sources, stresslet, per_solve) in kinds {
        let mut out = vec![Vector3::zeros(); targets.len()];
        let w = &unit[..sources.len()];
        let (real_s, fourier_s) = if stresslet {
            (
                best_cpu(repeats, || ewald.stresslet_real(targets, sources, w, &nodes.weighted_normals, &mut out)),
                best_cpu(repeats, || ewald.stresslet_fourier_add(targets, sources, w, &nodes.weighted_normals, &mut out)),
            )
        } else {
            (
                best_cpu(repeats, || ewald.stokeslet_real(targets, sources, w, &mut out)),
                best_cpu(repeats, || ewald.stokeslet_fourier_add(targets, sources, w, &mut out)),
            )
        };
        sums.push(SumCost { name, targets: targets.len(), sources: sources.len(), pairs: count_pairs(b, p.r_cut, targets, sources), real_s, fourier_s, per_solve });
    }
    Ok(SolveProfile {
        cell_triangles: n_tri,
        wall_vertices: ch.mesh.n_vertices(),
        xi: p.xi,
        r_cut_um: p.r_cut,
        grid: p.grid,
        support: p.support,
        iterations: it,
        solve_cpu_s,
        ewald_wall_s: st.ewald_seconds,
        wall_lu_wall_s: st.wall_solve_seconds,
        total_wall_s: st.total_seconds,
        sums,
        fast,
    })
}

/// Markdown report of [`profile`].
pub fn profile_table(p: &SolveProfile) -> String {
    let mut s = format!(
        "cell triangles {}, wall vertices {}, xi {:.3} 1/um, r_cut {:.2} um, grid {:?}, P {}\n\
         one solve: {} GMRES iterations, {:.3} CPU s (wall: total {:.3} s, Ewald {:.3} s, wall LU {:.3} s)\n\n\
         sum | targets | sources | pairs in r_cut | real (CPU s) | Fourier (CPU s) | per solve | share of the solve\n---|---|---|---|---|---|---|---\n",
        p.cell_triangles, p.wall_vertices, p.xi, p.r_cut_um, p.grid, p.support, p.iterations, p.solve_cpu_s, p.total_wall_s, p.ewald_wall_s, p.wall_lu_wall_s
    );
    for c in &p.sums {
        s += &format!(
            "{} | {} | {} | {} | {:.4} | {:.4} | {} | {:.0} %\n",
            c.name,
            c.targets,
            c.sources,
            c.pairs,
            c.real_s,
            c.fourier_s,
            c.per_solve,
            100.0 * (c.real_s + c.fourier_s) * c.per_solve as f64 / p.solve_cpu_s
        );
    }
    s += "\nfrozen sums in GMRES: r_cut (um) | xi (1/um) | grid | iterations | solve CPU (s) | Ewald wall (s) | speed-up | |u - u_plain| / |u_plain| | stresslet blocks build with the single layer / spreading build / blocks apply / Fourier (CPU s) | stresslet spreading entries (MB) | wall blocks build / apply / Fourier (CPU s) | stresslet blocks build, single-precision kernels (CPU s)\n---|---|---|---|---|---|---|---|---|---|---|---\n";
    for f in &p.fast {
        s += &format!(
            "{} | {:.3} | {:?} | {} | {:.3} | {:.3} | {:.2} | {:.1e} | {:.4} / {:.4} / {:.4} / {:.4} | {} ({:.1}) | {:.4} / {:.4} / {:.4} | {:.4}\n",
            f.r_cut_um, f.xi, f.grid, f.iterations, f.cpu_s, f.ewald_wall_s, p.solve_cpu_s / f.cpu_s, f.relative_difference,
            f.parts[0], f.parts[1], f.parts[2], f.parts[3], f.stresslet_spread.0, f.stresslet_spread.1 as f64 * 1e-6,
            f.parts[4], f.parts[5], f.parts[6], f.parts[7]
        );
    }
    s
}
