//! `rbc-bench channel-tol`: step sizes, rejections, error-estimate anatomy and accuracy versus cost of the time integrators in the channel, per scheme and absolute tolerance.
//!
//! Usage: `rbc-bench channel-tol --start RESULTS.h5 [--run steps-bs23] [--snapshot -1]
//! [--schemes bs23,ros34pw2-local] [--atols 4e-5,1e-4,3e-4,1e-3]
//! [--reference bs23@1e-5] [--window-ms 1] [--output-ms 0.25] [--threads 1] [--dir channel-tol]
//! [--controllers integral,pi] [--runs bs23@4e-5@pi,ros34pw2-local@1e-3] [--no-reference]`
//! (schemes: bs23, ros34pw2-local, ros34pw2-local-sS with `J = S J_loc`, ros34pw2 with the lagged `J`;
//! controllers: integral (default), pi: the step-size controller of `rbc_solver::run::Controller`;
//! `--runs` lists `scheme@atol[@controller]` runs instead of the grid schemes x atols x controllers;
//! `--no-reference` runs only those, without the reference and the tables, to split a study
//! over processes: a last call without it prints the tables from the saved runs).
//! The table below: `--atols 4e-5,1e-4,3e-4,1e-3,3e-3,1e-2`, the runs split over processes by `--schemes`.
//!
//! Scene: the coarse channel of session 3's `steps/bs23.toml` (discocyte of 512 triangles,
//! Krueger's Skalak law kappa_S = 5e-6, kappa_A = 5e-4 N/m, bending 3e-19 N m, lambda = 5,
//! 42.7 x 12 x 10 um channel, mean flow 4.3 mm/s, exact no-slip walls of edge 2 um, Ewald
//! tolerance 1e-4), started from a snapshot of an earlier run (`--start`, required; the tables below
//! started from the bs23 run at atol 4e-5 um after 8 ms, past the initial relaxation from the discocyte) at the snapshot's
//! centroid, and run for `--window-ms` with every scheme at every tolerance.
//!
//! Per run: accepted / rejected steps per simulated ms, mean and largest step, velocity
//! evaluations, core-seconds per simulated ms (CPU time of the process, one thread, minus
//! the time of the error analysis below), and errors against the reference run at the output
//! times: max over vertices and output times of `|x_i - x_i^ref|` (um), centroid `(y, z)`
//! (um), mean axial velocity over the window (relative), asphericity (absolute).
//!
//! Anatomy of the error estimate (each attempted step, medians over accepted and over
//! rejected attempts): `e = max_i |err_i| / atol` as the controller sees it; `e_filt` the
//! same for `W_loc^-1 err` with `W_loc = I - 2 gamma h J_loc` (the local W-method's stage
//! matrix, gamma = 0.4359; Shampine's filter: Shampine, ACM TOMS 8, 93 (1982); Hairer & Wanner II, sec. IV.8);
//! the share of `|err|^2` in a rigid translation, the normal share of the rest (vertex normals;
//! the tangential rest is in-plane: area dilatation and shear), the high-pass share
//! `sum |err_i - mean_{j ~ i} err_j|^2 / sum |err_i|^2` (0 for a smooth field, O(1) for
//! mesh-scale oscillations), and `h ||J_loc err|| / ||err||` (how stiff the modes carrying
//! the error are in units of the step: the explicit Bogacki-Shampine is stable up to ~2.5).
//!
//! `--probe 1e-6,2e-6,...` instead makes single attempts from the start state at those step
//! sizes (s) and prints how the error estimate scales with `h` (see [`probe`]); with
//! `--shifts 0,0.05,...` (um) it evaluates the velocity of the rigidly shifted cell instead.
//!
//! Each run is saved as `<dir>/<scheme>@<atol>.txt` (stats, attempts, samples) and skipped
//! when present, so that the study can be split over processes and resumed; the tables are
//! printed from the saved runs.
//!
//! # Measured (rbc-bench channel-tol, 1 thread per run, `nice -n 10`; 2 cores shared by 4 helpers, load 7-12)
//!
//! 1 ms from the bs23 (atol 4e-5 um) run's state at t = 8 ms (cell at r ~ 1.1 um, 7.38 mm/s,
//! still migrating at ~43 um/s towards the axis), errors against bs23 at atol 1e-5 um (bs23 at the
//! paper's 4e-5 is within 7e-7 um of it in the centroid). Core-s per simulated ms under that load
//! (one Stokes solve ~0.75 core-s). Errors are maxima over the 5 output times (every 0.25 ms).
//! ```text
//! scheme         | atol  | acc/ms | rej/ms | evals/ms | h mean/max (us) | core-s/ms | max vertex err (um) | centroid (y,z) err (um) | rel. velocity err | asphericity err
//! bs23           | 1e-5  | 92 | 15 | 329 | 10.9 / 34.8  | 267 | reference | reference | reference | reference
//! bs23           | 4e-5  | 64 | 17 | 263 | 15.6 / 33.1  | 194 | 2.6e-5 | 7.1e-7 | 3.9e-8 | 2.5e-7
//! bs23           | 1e-4  | 50 | 11 | 211 | 20.0 / 40.4  | 169 | 9.4e-5 | 1.3e-6 | 2.8e-7 | 1.7e-6
//! bs23           | 3e-4  | 40 | 13 | 194 | 25.0 / 53.7  | 162 | 2.8e-4 | 2.8e-6 | 8.5e-7 | 6.1e-6
//! bs23           | 1e-3  | 41 | 14 | 200 | 24.4 / 38.4  | 175 | 1.3e-3 | 8.6e-6 | 9.5e-9 | 2.5e-6
//! bs23           | 3e-3  | 39 | 14 | 195 | 25.6 / 46.9  | 172 | 2.1e-3 | 4.1e-5 | 2.2e-6 | 4.3e-5
//! bs23           | 1e-2  | 35 | 11 | 172 | 28.6 / 70.1  | 158 | 1.3e-2 | 1.3e-4 | 6.7e-7 | 1.3e-4
//! ros34pw2-local | 4e-5  | 78 | 11 | 345 | 12.8 / 29.5  | 269 | 2.1e-4 | 5.1e-6 | 1.8e-6 | 2.0e-6
//! ros34pw2-local | 1e-4  | 56 |  9 | 251 | 17.9 / 42.8  | 211 | 3.9e-4 | 1.3e-5 | 3.6e-6 | 2.5e-6
//! ros34pw2-local | 3e-4  | 40 |  8 | 184 | 25.0 / 65.1  | 152 | 6.8e-4 | 2.8e-5 | 8.2e-6 | 3.3e-6
//! ros34pw2-local | 1e-3  | 28 |  6 | 130 | 35.7 / 81.5  | 124 | 1.6e-3 | 6.1e-5 | 2.0e-5 | 9.1e-6
//! ros34pw2-local | 3e-3  | 21 |  3 |  93 | 47.6 / 120.5 |  89 | 3.4e-3 | 7.8e-5 | 3.8e-5 | 4.7e-5
//! ros34pw2-local | 1e-2  | 16 |  5 |  79 | 62.5 / 164.1 |  87 | 9.2e-3 | 7.6e-5 | 1.2e-6 | 1.8e-4
//! ```
//! Anatomy of the error estimates (medians over accepted attempts; rejected ones alike):
//! ```text
//! scheme         | atol      | e / e filtered | normal share | high-pass share | h |J_loc err|/|err| | worst vertices
//! bs23           | 4e-5      | 0.66 / 0.55    | 0.24         | 0.22            | 0.09               | 171, 176, 177 (rear of the cell)
//! bs23           | 1e-4      | 0.57 / 0.46    | 0.22         | 0.25            | 0.15               | 171, 176, 177
//! bs23           | 1e-3..1e-2| 0.53 / 0.13-0.18 | 0.02-0.03  | 1.34-1.37       | 3.4-4.6 (> 2.5)    | 218, 4 (the stiffest, 1.7e5 1/s)
//! ros34pw2-local | 4e-5..1e-2| 0.15-0.67 / within 10% | 0.29-0.34 | 0.27-0.60   | 0.43-0.54          | 171, 176, 177
//! ```
//! Single attempts from the same state (`--probe`), largest `|err_i|` (um) against `h`:
//! ```text
//! h (us)                 2       4       8       16      32      64      128
//! bs23                   2.8e-7  2.4e-6  2.3e-5  2.2e-4  7.1e-4  4.4e-3
//! ros34pw2-local         7.8e-7  4.9e-6  4.2e-5  3.3e-4  1.7e-3  7.6e-3
//! ros34pw2 (lagged J)                                    1.1e-3  1.0e-2  7.0e-2
//! ```
//! always at vertex 176 (max/rms 9-10; 1-3 vertices above half the max); `W_loc^-1 err` within 3-10%
//! of `err`; `J = 4 J_loc` instead of `2 J_loc`: the same steps (16 accepted in 0.5 ms at 1e-3).
//! Self rates `m_v |df_v/dx_v|`: median 6.3e4, max 1.74e5 1/s (vertex 4, of valence 4 with
//! 15-degree angles: the mesh's worst corner sets bs23's stability limit; the rear vertices 171,
//! 176, 177 have valence 6 and angles >= 39 degrees, so their fast motion is no mesh defect); `J_loc` matches the
//! finite-difference block of the whole membrane to 2% (bending alone <= 1e4 1/s). Translation
//! invariance: the velocity of the cell shifted rigidly by 0.04-4 um along the channel changes by
//! up to 2 um/s at a vertex (2.7e-4 of 7380 um/s), its mean by up to 0.13 (x), 0.08 (y), 0.19 (z)
//! um/s: spatial-discretisation noise (wall mesh of 2 um, Ewald tolerance 1e-4) that moves the
//! centroid laterally by up to ~2e-4 um per ms.
//!
//! Reading: (1) At the paper's tolerance both schemes are accuracy-limited, not stability-limited:
//! the estimate is a smooth truncation error (`~ h^3` over 2-16 us) of a few vertices at the rear
//! of the cell, in modes that `J_loc` calls slow; neither Shampine's filter, a larger `J_loc`, nor
//! the lagged full `J` shrinks it (so no integrator change was made). (2) bs23 turns
//! stability-limited from 3e-4 um on: ~25 us steps whatever the tolerance, 30% rejected, the error
//! in the stiffest in-plane mesh-scale modes with `h lambda` beyond bs23's 2.5 (physics.md), so
//! it is more accurate than its tolerance asks at more cost. (3) ros34pw2-local stays
//! accuracy-limited (`h ~ atol^0.29`) up to 1e-2 um, with larger errors than bs23 at the same atol.
//! (4) Every run keeps the centroid within 1.3e-4 um, the velocity within 4e-5 and the asphericity
//! within 2e-4 of the reference over the ms: below the lateral drift the spatial discretisation
//! itself causes (~2e-4 um per ms) and <= 0.3% of the ~0.043 um/ms lateral migration.
//! Recommendation for the science study: ros34pw2-local at atol 1e-3 um: 124 core-s per ms, 1.6x
//! cheaper than bs23 at the paper's 4e-5 and 2.2x than ros34pw2-local at 4e-5; centroid error
//! 6e-5 um per ms (0.14% of the migration, 3x under the discretisation noise), asphericity 9e-6.
//! 3e-3 um (89 core-s/ms, 2.2x cheaper than the paper's setting) keeps the centroid error (8e-5 um)
//! but the asphericity error grows 5x; 1e-2 gains nothing more. bs23 gains nothing beyond 3e-4
//! (stability), though bs23 at 3e-4..1e-3 is 10x more accurate than ros34pw2-local at 1e-3 for
//! 1.3-1.4x its cost. Weak points: one 1 ms window from one state of one cell at r ~ 1.1 um;
//! errors over seconds not measured (the lateral dynamics relaxes to a steady state, so per-ms
//! errors should not add up linearly, but near the bistability
//! threshold a scan should confirm by repeating one r_init at 3e-4 um).
//!
//! # Step-size controllers (`--controllers integral,pi`)
//!
//! The integral controller against Gustafsson's PI.3.4 (`rbc_solver::run::Controller`), same
//! binary, run as two concurrent processes (`--runs ... --no-reference`, then one call printing
//! the tables), 1 thread each, `nice -n 10`, beside a science sweep of two runs at nice 5 (load
//! average 4-10 while other helpers compiled). The same start state as above; the core-s per ms
//! are ~4.5x lower than in the tables above (reference 267 -> 59), from the solver changes since
//! (near-field quadrature, normal-part sum) and/or the lower load: compare them only within this
//! section. The reference was recomputed with this binary.
//! 2 ms (`--window-ms 2`), reference bs23/integral at atol 1e-5 um (75.5 + 14.5 steps per ms):
//! ```text
//! scheme         | atol  | controller | acc/ms | rej/ms | evals/ms | core-s/ms | max vertex err | centroid err | rel. velocity err | asphericity err
//! bs23           | 4e-5  | integral   | 54.5 | 17.0 | 232 | 44 | 3.3e-5 | 1.1e-6 | 2.3e-8 | 3.3e-7
//! bs23           | 4e-5  | pi         | 58.5 |  7.5 | 211 | 39 | 5.8e-5 | 1.1e-6 | 5.8e-8 | 4.1e-7
//! bs23           | 1e-3  | integral   | 42.5 |  9.5 | 192 | 37 | 1.3e-3 | 9.9e-6 | 4.7e-8 | 6.8e-6
//! bs23           | 1e-3  | pi         | 41.0 |  2.5 | 166 | 31 | 8.3e-4 | 1.2e-5 | 1.1e-6 | 2.3e-5
//! ros34pw2-local | 1e-3  | integral   | 22.0 |  6.0 | 106 | 21 | 5.0e-3 | 1.0e-4 | 2.2e-5 | 7.1e-5
//! ros34pw2-local | 1e-3  | pi         | 25.5 |  3.5 | 112 | 23 | 3.6e-3 | 4.3e-5 | 1.2e-5 | 6.5e-5
//! ```
//! 1 ms (the first half of the same window, a separate study; reference 92 + 15 steps per ms):
//! ```text
//! bs23           | 4e-5  | integral   | 64 | 18 | 266 | 49 | 3.3e-5 | 6.8e-7 | 3.4e-8 | 3.3e-7
//! bs23           | 4e-5  | pi         | 68 | 10 | 250 | 49 | 2.5e-5 | 7.6e-7 | 4.2e-8 | 3.8e-7
//! ros34pw2-local | 1e-3  | integral   | 28 |  6 | 130 | 26 | 1.5e-3 | 6.0e-5 | 2.0e-5 | 9.1e-6
//! ros34pw2-local | 1e-3  | pi         | 32 |  4 | 140 | 28 | 1.7e-3 | 2.5e-5 | 7.6e-6 | 3.0e-5
//! ```
//! Reading: for bs23, PI halves (4e-5: 24 % -> 11 % of the attempts) to quarters (1e-3: 18 % ->
//! 6 %) the rejections; with ~3 velocity evaluations per attempted step it needs 9 % and
//! 14 % fewer evaluations and 11 % and 16 % fewer core-s over 2 ms, at errors of the same size
//! (the largest vertex error 1.8x larger at 4e-5, 1.6x smaller at 1e-3; the centroid error the
//! same). For ros34pw2-local at 1e-3, PI rejects less (21 % -> 12 %) but accepts 16 % more
//! steps: 6 % more evaluations and 10 % more core-s, for 1.4x (vertex) to 2.3x (centroid)
//! smaller errors, i.e. about the work-precision line of a tighter tolerance (the table above:
//! ~25 % more evaluations per 3x in atol), not a saving at the chosen tolerance. The free-space
//! cases (`rbc-bench controller`, `src/bench/controller.rs`) agree. Hence the scene default
//! (`rbc_schema::scene::StepController::default_for`): PI for bs23, integral for the Rosenbrock
//! schemes (set `integrator.controller = "pi"` to trade ~10 % cost for ~2x accuracy there), except
//! with penalty walls, whose error norm swings with the wall vertices the cell passes: PI for
//! every scheme there (`solver/README.md`, "Session 33").
//! Weak points: one start state, 2 ms; 5-34 rejections per run, so the rejection ratios carry
//! ~20-40 % counting noise, the evaluation and core-s differences less (they were consistent over the
//! 1 ms and 2 ms windows and the free-space cases).

use super::clock::{load_average, process_cpu_ticks_s};
use anyhow::{bail, Context};
use nalgebra::Vector3;
use rbc_analysis::stats::median::upper_median;
use rbc_schema::scene::Scene;
use rbc_solver::integrate::bs23::BogackiShampine;
use rbc_solver::dynamics::cell::CellDynamics;
use rbc_solver::integrate::ros34pw2::{Ros34pw2, StageJacobian, GAMMA_DIAG};
use rbc_solver::dynamics::volume::no_flux;
use rbc_solver::integrate::{Integrator, Linearised, StepContext, StepWork};
use rbc_solver::state::StateMap;
use rbc_solver::mesh::Mesh;
use rbc_solver::run::results::asphericity;
use rbc_solver::run::{Controller, Recorder, RunSummary, Runner};
use rbc_solver::SolverError;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The scene of session 3's `steps/bs23.toml` started from `results`/`run`/`snapshot` at `position` (um).
fn scene_text(results: &Path, run: &str, snapshot: i64, position: Vector3<f64>, atol: f64, end_s: f64, output_s: f64) -> String {
    format!(
        r#"name = "channel-tol"
[cell]
shape = "mesh-from-results"
results = "{results}"
run = "{run}"
snapshot = {snapshot}
level = 3
position_um = [{px:?}, {py:?}, {pz:?}]
{blocks}wall_model = "no-slip"
wall_edge_um = 2.0
ewald_tol = 1e-4
[integrator]
scheme = "bs23"
atol_um = {atol:e}
h0_s = 1e-5
[time]
end_s = {end_s:e}
output_interval_s = {output_s:e}
"#,
        blocks = rbc_schema::paper_scene::channel_blocks(5.0, 4300.0),
        results = results.display(),
        px = position.x,
        py = position.y,
        pz = position.z,
    )
}

/// One attempted step and the anatomy of its error estimate.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Attempt {
    pub t_s: f64,
    pub h_s: f64,
    pub accepted: bool,
    /// `max_i |err_i| / atol` and the same after the filter `W_loc^-1`.
    pub e: f64,
    pub e_filtered: f64,
    /// Vertex with the largest `|err_i|`.
    pub worst: usize,
    /// Shares of `|err|^2`: rigid translation; normal part of the rest; high-pass (see the module docs).
    pub translation: f64,
    pub normal: f64,
    pub high_pass: f64,
    /// `h ||J_loc err|| / ||err||`.
    pub h_lambda: f64,
}

/// Vertex neighbours (sorted, without duplicates) of the mesh `triangles` on `n` vertices.
pub fn neighbours(triangles: &[[usize; 3]], n: usize) -> Vec<Vec<usize>> {
    let mut nb = vec![Vec::new(); n];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            nb[a].push(b);
            nb[b].push(a);
        }
    }
    for v in &mut nb {
        v.sort_unstable();
        v.dedup();
    }
    nb
}

/// Shares of `sum_i |err_i|^2` (err per vertex, any unit): (rigid translation `n |mean|^2`;
/// normal part of the rest, with area-weighted vertex normals of `x`; high-pass part
/// `sum_i |err_i - mean_{j ~ i} err_j|^2`). All zero for a zero `err`.
pub fn shares(x: &[Vector3<f64>], triangles: &[[usize; 3]], neighbours: &[Vec<usize>], err: &[Vector3<f64>]) -> (f64, f64, f64) {
    let n = x.len();
    let total: f64 = err.iter().map(|e| e.norm_squared()).sum();
    if total == 0.0 || n == 0 {
        return (0.0, 0.0, 0.0);
    }
    let mean: Vector3<f64> = err.iter().sum::<Vector3<f64>>() / n as f64;
    let translation = n as f64 * mean.norm_squared() / total;
    let mut normals = vec![Vector3::zeros(); n];
    for t in triangles {
        let (p, q, r) = (x[t[0]], x[t[1]], x[t[2]]);
        let nrm = (q - p).cross(&(r - p));
        for &v in t {
            normals[v] += nrm;
        }
    }
    let (mut normal, mut rest) = (0.0, 0.0);
    for (e, nv) in err.iter().zip(&normals) {
        let d = e - mean;
        if let Some(u) = nv.try_normalize(0.0) {
            normal += d.dot(&u).powi(2);
        }
        rest += d.norm_squared();
    }
    let hp: f64 = (0..n)
        .map(|i| {
            let nb = &neighbours[i];
            let avg: Vector3<f64> = nb.iter().map(|&j| err[j]).sum::<Vector3<f64>>() / nb.len().max(1) as f64;
            (err[i] - avg).norm_squared()
        })
        .sum();
    (translation, if rest > 0.0 { normal / rest } else { 0.0 }, hp / total)
}

/// An [`Integrator`] that passes everything to `inner` and records the anatomy of each error estimate.
pub struct Probe<I> {
    pub inner: I,
    triangles: Vec<[usize; 3]>,
    neighbours: Vec<Vec<usize>>,
    atol_um: f64,
    pub attempts: Vec<Attempt>,
    /// Wall time spent in the analysis (s), to subtract from the cost.
    pub analysis_s: f64,
}

impl<I> Probe<I> {
    pub fn new(inner: I, triangles: &[[usize; 3]], n: usize, atol_um: f64) -> Self {
        Self { inner, triangles: triangles.to_vec(), neighbours: neighbours(triangles, n), atol_um, attempts: Vec::new(), analysis_s: 0.0 }
    }

    fn analyse<D: Linearised + ?Sized>(&mut self, f: &mut D, t: f64, x: &[Vector3<f64>], h: f64, err: &[Vector3<f64>]) -> Result<Attempt, SolverError> {
        let n = x.len();
        let mut a = Attempt { t_s: t, h_s: h, ..Default::default() };
        let (mut emax, mut worst) = (0.0f64, 0usize);
        for (i, e) in err.iter().enumerate() {
            if e.norm() > emax {
                (emax, worst) = (e.norm(), i);
            }
        }
        a.e = emax / self.atol_um;
        a.worst = worst;
        if !emax.is_finite() || emax == 0.0 {
            return Ok(a);
        }
        let total: f64 = err.iter().map(|e| e.norm_squared()).sum();
        (a.translation, a.normal, a.high_pass) = shares(x, &self.triangles, &self.neighbours, err);
        // stiffness of the error modes and the filtered estimate, with J_loc at (t, x)
        f.linearise(t, x)?;
        if let Some(j) = f.local_jacobian()? {
            let mut je = vec![Vector3::zeros(); n];
            j.apply(err, &mut je);
            a.h_lambda = h * (je.iter().map(|v| v.norm_squared()).sum::<f64>() / total).sqrt();
            if let Ok(w) = j.stage_matrix(2.0 * GAMMA_DIAG * h) {
                let mut ef = err.to_vec();
                w.solve_in_place(&mut ef);
                a.e_filtered = ef.iter().map(|v| v.norm()).fold(0.0, f64::max) / self.atol_um;
            }
        }
        Ok(a)
    }
}

impl<D: Linearised + ?Sized, I: Integrator<D>> Integrator<D> for Probe<I> {
    fn name(&self) -> &'static str {
        self.inner.name()
    }
    fn embedded_order(&self) -> u32 {
        self.inner.embedded_order()
    }
    fn attempt(&mut self, f: &mut D, t: f64, x: &[Vector3<f64>], h: f64, ctx: StepContext, x_new: &mut [Vector3<f64>], err: &mut [Vector3<f64>]) -> Result<StepWork, SolverError> {
        let w = self.inner.attempt(f, t, x, h, ctx, x_new, err)?;
        let t0 = Instant::now();
        let a = self.analyse(f, t, x, h, err)?;
        self.attempts.push(a);
        self.analysis_s += t0.elapsed().as_secs_f64();
        Ok(w)
    }
    fn accepted(&mut self) {
        if let Some(a) = self.attempts.last_mut() {
            a.accepted = true;
        }
        self.inner.accepted()
    }
    fn invalidate(&mut self) {
        self.inner.invalidate()
    }
    fn save_state(&self, prefix: &str, out: &mut StateMap) {
        self.inner.save_state(prefix, out)
    }
    fn restore_state(&mut self, prefix: &str, state: &StateMap) -> Result<(), SolverError> {
        self.inner.restore_state(prefix, state)
    }
}

/// One run of the study as saved on disk.
#[derive(Debug, Clone, Default)]
pub struct TolRun {
    pub scheme: String,
    pub atol_um: f64,
    /// Step-size controller: `integral` or `pi` (see [`controller_of`]).
    pub controller: String,
    pub accepted: usize,
    pub rejected: usize,
    pub velocity_evals: usize,
    /// CPU seconds of the run without the analysis, wall seconds of the analysis, simulated ms.
    pub cpu_s: f64,
    pub analysis_s: f64,
    pub sim_ms: f64,
    pub h_max_s: f64,
    pub attempts: Vec<Attempt>,
    /// Output times (s) and vertices (um).
    pub times_s: Vec<f64>,
    pub vertices: Vec<Vec<Vector3<f64>>>,
}

impl TolRun {
    /// `<scheme>@<atol>.txt` for the integral controller (the name of the runs saved before
    /// there was a choice), `<scheme>@<atol>@<controller>.txt` otherwise.
    fn file_name(scheme: &str, atol: f64, controller: &str) -> String {
        if controller == "integral" {
            format!("{scheme}@{atol:e}.txt")
        } else {
            format!("{scheme}@{atol:e}@{controller}.txt")
        }
    }

    fn save(&self, path: &Path) -> anyhow::Result<()> {
        let mut s = String::new();
        writeln!(
            s,
            "run {} {:e} {} {} {} {:e} {:e} {:e} {:e} {}",
            self.scheme, self.atol_um, self.accepted, self.rejected, self.velocity_evals, self.cpu_s, self.analysis_s, self.sim_ms, self.h_max_s, self.controller
        )?;
        for a in &self.attempts {
            writeln!(s, "a {:e} {:e} {} {:e} {:e} {} {:e} {:e} {:e} {:e}", a.t_s, a.h_s, a.accepted as u8, a.e, a.e_filtered, a.worst, a.translation, a.normal, a.high_pass, a.h_lambda)?;
        }
        for (t, v) in self.times_s.iter().zip(&self.vertices) {
            write!(s, "s {t:e}")?;
            for p in v {
                write!(s, " {:e} {:e} {:e}", p.x, p.y, p.z)?;
            }
            writeln!(s)?;
        }
        rbc_schema::atomic::write_atomic(path, |w| {
            use std::io::Write;
            w.write_all(s.as_bytes()).map_err(|e| rbc_schema::SchemaError::io(path, e))
        })
        .with_context(|| path.display().to_string())?;
        Ok(())
    }

    fn load(path: &Path) -> anyhow::Result<Self> {
        let text = std::fs::read_to_string(path).with_context(|| path.display().to_string())?;
        let mut r = TolRun::default();
        for (k, line) in text.lines().enumerate() {
            let w: Vec<&str> = line.split_whitespace().collect();
            let ctx = || format!("{} line {}", path.display(), k + 1);
            let num = |i: usize| -> anyhow::Result<f64> { w.get(i).with_context(ctx)?.parse::<f64>().with_context(ctx) };
            match w.first().copied() {
                Some("run") => {
                    r.scheme = w.get(1).with_context(ctx)?.to_string();
                    (r.atol_um, r.accepted, r.rejected, r.velocity_evals) = (num(2)?, num(3)? as usize, num(4)? as usize, num(5)? as usize);
                    (r.cpu_s, r.analysis_s, r.sim_ms, r.h_max_s) = (num(6)?, num(7)?, num(8)?, num(9)?);
                    // runs saved before the controller was a choice had the integral one
                    r.controller = w.get(10).unwrap_or(&"integral").to_string();
                }
                Some("a") => r.attempts.push(Attempt {
                    t_s: num(1)?,
                    h_s: num(2)?,
                    accepted: num(3)? != 0.0,
                    e: num(4)?,
                    e_filtered: num(5)?,
                    worst: num(6)? as usize,
                    translation: num(7)?,
                    normal: num(8)?,
                    high_pass: num(9)?,
                    h_lambda: num(10)?,
                }),
                Some("s") => {
                    r.times_s.push(num(1)?);
                    let v: Vec<f64> = w[2..].iter().map(|x| x.parse::<f64>()).collect::<Result<_, _>>().with_context(ctx)?;
                    r.vertices.push(v.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])).collect());
                }
                _ => bail!("{}: unexpected line", ctx()),
            }
        }
        Ok(r)
    }
}

/// The integrator of `scheme` (bs23, ros34pw2-local, ros34pw2-local-sS: `J = S J_loc`).
enum Scheme {
    Bs23(BogackiShampine),
    Ros(Box<Ros34pw2>),
}

fn scheme_of(name: &str) -> anyhow::Result<Scheme> {
    Ok(match name {
        "bs23" => Scheme::Bs23(BogackiShampine::new()),
        "ros34pw2-local" => Scheme::Ros(Box::new(Ros34pw2::with(StageJacobian::Local, false))),
        // the lagged-mobility J (every product a Stokes solve), GMRES preconditioned with J_loc
        "ros34pw2" => Scheme::Ros(Box::new(Ros34pw2::new())),
        // the local W-method with J = s J_loc instead of the default 2 J_loc
        other if other.starts_with("ros34pw2-local-s") => {
            let scale: f64 = other["ros34pw2-local-s".len()..].parse().with_context(|| format!("scheme {other:?}: scale after -s"))?;
            let mut r = Ros34pw2::with(StageJacobian::Local, false);
            r.local_scale = scale;
            Scheme::Ros(Box::new(r))
        }
        other => bail!("rbc-bench channel-tol: unknown scheme {other:?} (bs23, ros34pw2-local, ros34pw2-local-sS for J = S J_loc)"),
    })
}

/// The runner's step-size controller named `name` (`integral`, `pi`: Gustafsson's PI.3.4).
pub fn controller_of(name: &str) -> anyhow::Result<Controller> {
    Ok(match name {
        "integral" => Controller::Integral,
        "pi" => Controller::PI34,
        other => bail!("rbc-bench channel-tol: unknown controller {other:?} (integral, pi)"),
    })
}

/// One run of the study: scheme, absolute tolerance (um), controller.
type TolConfig = (String, f64, String);

/// `scheme@atol[@controller]` (controller default `integral`).
fn parse_config(v: &str) -> anyhow::Result<TolConfig> {
    let mut parts = v.split('@');
    let (Some(s), Some(a)) = (parts.next(), parts.next()) else { bail!("{v:?}: expected scheme@atol[@controller]") };
    let c = parts.next().unwrap_or("integral");
    controller_of(c)?;
    Ok((s.trim().to_string(), a.trim().parse().with_context(|| format!("{v:?}: atol"))?, c.trim().to_string()))
}

/// Where the study starts from.
#[derive(Debug, Clone)]
pub struct Start {
    pub results: PathBuf,
    pub run: String,
    pub snapshot: i64,
}

/// Run `scheme` at `atol` with `controller` for `window_ms` from `start` on `threads` threads.
pub fn measure(start: &Start, scheme: &str, atol: f64, controller: &str, window_ms: f64, output_ms: f64, threads: usize) -> anyhow::Result<TolRun> {
    let snaps = rbc_schema::results::read_snapshots(&start.results, &start.run)?;
    let k = snaps.times_s.len() as i64;
    let idx = if start.snapshot < 0 { k + start.snapshot } else { start.snapshot };
    if idx < 0 || idx >= k {
        bail!("snapshot {} out of range ({k} snapshots)", start.snapshot);
    }
    let verts: Vec<Vector3<f64>> = snaps.vertices_um[idx as usize].iter().map(|v| Vector3::from(*v)).collect();
    let tris: Vec<[usize; 3]> = snaps.triangles.iter().map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
    let centre = Mesh::from_arrays(verts, tris)?.centroid();
    let text = scene_text(&start.results, &start.run, start.snapshot, centre, atol, window_ms * 1e-3, output_ms * 1e-3);
    let scene = Scene::parse(&text, Path::new("channel-tol.toml"))?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build().context("rayon pool")?;
    pool.install(|| -> anyhow::Result<TolRun> {
        let built = rbc_solver::scene::build(&scene)?;
        let tris = built.mesh.triangles.clone();
        let mut x = built.mesh.vertices.clone();
        let cell = CellDynamics::new(tris.clone(), &built.membrane, &built.stokes);
        let mut dynamics = no_flux(cell, &tris);
        let mut config = built.run.clone();
        config.control.controller = controller_of(controller)?;
        let runner = Runner::new(config);
        let mut rec = Recorder::default();
        let c0 = process_cpu_ticks_s().unwrap_or(f64::NAN);
        let (summary, attempts, analysis_s): (RunSummary, Vec<Attempt>, f64) = match scheme_of(scheme)? {
            Scheme::Bs23(s) => {
                let mut p = Probe::new(s, &tris, x.len(), atol);
                let sm = runner.run(&mut dynamics, &mut p, &tris, &mut x, &mut rec)?;
                (sm, p.attempts, p.analysis_s)
            }
            Scheme::Ros(s) => {
                let mut p = Probe::new(*s, &tris, x.len(), atol);
                let sm = runner.run(&mut dynamics, &mut p, &tris, &mut x, &mut rec)?;
                (sm, p.attempts, p.analysis_s)
            }
        };
        let cpu_s = process_cpu_ticks_s().unwrap_or(f64::NAN) - c0 - analysis_s;
        Ok(TolRun {
            scheme: scheme.to_string(),
            atol_um: atol,
            controller: controller.to_string(),
            accepted: summary.accepted,
            rejected: summary.rejected,
            velocity_evals: summary.velocity_evals,
            cpu_s,
            analysis_s,
            sim_ms: window_ms,
            h_max_s: summary.h_max_s,
            attempts,
            times_s: rec.times_s,
            vertices: rec.vertices,
        })
    })
}

/// Single attempts from the start state at several step sizes (`rbc-bench channel-tol --probe`):
/// velocity repeatability (the same `x` evaluated twice, the second time with the first as the
/// iterative solve's initial guess), then for each scheme and `h` the largest `|err_i|` (um), its
/// vertex and `|err_v|` at vertex `watch`: `|err| ~ h^(q+1)` for truncation error, `~ h` for noise.
pub fn probe(start: &Start, schemes: &[String], hs: &[f64], shifts: &[f64], watch: usize, threads: usize) -> anyhow::Result<()> {
    let snaps = rbc_schema::results::read_snapshots(&start.results, &start.run)?;
    let k = snaps.times_s.len() as i64;
    let idx = if start.snapshot < 0 { k + start.snapshot } else { start.snapshot };
    let verts: Vec<Vector3<f64>> = snaps.vertices_um[idx as usize].iter().map(|v| Vector3::from(*v)).collect();
    let tris: Vec<[usize; 3]> = snaps.triangles.iter().map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
    let centre = Mesh::from_arrays(verts, tris)?.centroid();
    let text = scene_text(&start.results, &start.run, start.snapshot, centre, 4e-5, 1e-3, 1e-3);
    let scene = Scene::parse(&text, Path::new("channel-tol.toml"))?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build().context("rayon pool")?;
    pool.install(|| -> anyhow::Result<()> {
        let built = rbc_solver::scene::build(&scene)?;
        let tris = built.mesh.triangles.clone();
        let x = built.mesh.vertices.clone();
        let n = x.len();
        let cell = CellDynamics::new(tris.clone(), &built.membrane, &built.stokes);
        let mut f = no_flux(cell, &tris);
        let (mut ua, mut ub) = (vec![Vector3::zeros(); n], vec![Vector3::zeros(); n]);
        use rbc_solver::integrate::Dynamics;
        f.velocity(0.0, &x, &mut ua)?;
        f.velocity(0.0, &x, &mut ub)?;
        let d = ua.iter().zip(&ub).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        let umax = ua.iter().map(|u| u.norm()).fold(0.0, f64::max);
        println!("velocity repeatability: max |u_a - u_b| = {d:.3e} um/s (max |u| {umax:.3e} um/s); at vertex {watch}: {:.3e}", (ua[watch] - ub[watch]).norm());
        let mean: Vector3<f64> = ua.iter().sum::<Vector3<f64>>() / n as f64;
        println!("vertex {watch}: position - centroid {:?} um, velocity - mean {:?} um/s", x[watch] - centre, ua[watch] - mean);
        if shifts.is_empty() {
            self_rates(&built.membrane, &x, &tris, &mut f, watch)?;
        }
        // the channel is invariant under translations along x: any change of the velocity of
        // the rigidly shifted cell is discretisation error fixed in the laboratory frame
        if !shifts.is_empty() {
            println!("shift along x (um) | mean velocity (um/s) | max_i |u_i(s) - u_i(0)| (um/s) | at vertex | |u_{watch}(s) - u_{watch}(0)| (um/s)");
            println!("---|---|---|---|---");
        }
        for &sx in shifts {
            let xs: Vec<Vector3<f64>> = x.iter().map(|p| p + Vector3::new(sx, 0.0, 0.0)).collect();
            f.velocity(0.0, &xs, &mut ub)?;
            let (mut dmax, mut dv) = (0.0f64, 0usize);
            for (i, (a, b)) in ua.iter().zip(&ub).enumerate() {
                if (a - b).norm() > dmax {
                    (dmax, dv) = ((a - b).norm(), i);
                }
            }
            let mean: Vector3<f64> = ub.iter().sum::<Vector3<f64>>() / n as f64;
            println!("{sx:.3} | {:.3} {:.3} {:.3} | {dmax:.3e} | {dv} | {:.3e}", mean.x, mean.y, mean.z, (ua[watch] - ub[watch]).norm());
        }
        if !shifts.is_empty() {
            return Ok(());
        }
        println!("scheme | h (us) | max |err| (um) | vertex | |err_{watch}| (um) | max |W_loc^-1 err| (um) | rms |err| (um) | vertices above max/2");
        println!("---|---|---|---|---|---");
        for name in schemes {
            for &h in hs {
                let (mut xn, mut err) = (vec![Vector3::zeros(); n], vec![Vector3::zeros(); n]);
                // (the tolerance only sets the GMRES target of the lagged scheme: 5e-5 um, far below the errors probed)
                let ctx = StepContext { step: 0, atol_um: 1e-3 };
                match scheme_of(name)? {
                    Scheme::Bs23(mut s) => s.attempt(&mut f, 0.0, &x, h, ctx, &mut xn, &mut err)?,
                    Scheme::Ros(mut s) => s.attempt(&mut f, 0.0, &x, h, ctx, &mut xn, &mut err)?,
                };
                let (mut emax, mut worst) = (0.0f64, 0usize);
                for (i, e) in err.iter().enumerate() {
                    if e.norm() > emax {
                        (emax, worst) = (e.norm(), i);
                    }
                }
                f.linearise(0.0, &x)?;
                let mut ef = err.clone();
                if let Some(j) = f.local_jacobian()? {
                    if let Ok(w) = j.stage_matrix(2.0 * GAMMA_DIAG * h) {
                        w.solve_in_place(&mut ef);
                    }
                }
                let efmax = ef.iter().map(|v| v.norm()).fold(0.0, f64::max);
                let rms = (err.iter().map(|v| v.norm_squared()).sum::<f64>() / n as f64).sqrt();
                let above = err.iter().filter(|v| v.norm() > 0.5 * emax).count();
                println!("{name} | {:.1} | {emax:.3e} | {worst} | {:.3e} | {efmax:.3e} | {rms:.3e} | {above}", h * 1e6, err[watch].norm());
            }
        }
        Ok(())
    })
}

/// Local relaxation rates (1/s) per vertex: the largest eigenvalue magnitude of the 3x3 diagonal
/// block `m_v d f_v / d x_v` (`f_v` the force density (Pa) of the whole membrane or of the bending
/// law alone, by central differences of 1e-4 um; `m_v` the self-mobility of
/// [`rbc_solver::integrate::precondition::self_mobility`], lambda = 5) against the same block of `J_loc`
/// (elastic laws only). Prints the five stiffest vertices of each and vertex `watch`.
fn self_rates<D: Linearised>(membrane: &rbc_solver::membrane::Membrane, x: &[Vector3<f64>], tris: &[[usize; 3]], f: &mut D, watch: usize) -> anyhow::Result<()> {
    use rbc_solver::membrane::bending::Helfrich;
    use rbc_solver::membrane::MembraneLaw;
    let n = x.len();
    let mesh = Mesh { vertices: x.to_vec(), triangles: tris.to_vec() };
    let areas = mesh.vertex_areas();
    let lambda = rbc_solver::viscosity::ViscosityContrast::new(5.0)?;
    let mob: Vec<f64> = areas.iter().map(|&a| rbc_solver::integrate::precondition::self_mobility(a, 1.2e-3, lambda)).collect();
    let bending = Helfrich::new(3e-19)?;
    let eps = 1e-4;
    let block_rate = |law: &dyn MembraneLaw, v: usize| -> f64 {
        let mut b = nalgebra::Matrix3::zeros();
        for k in 0..3 {
            let mut m = mesh.clone();
            m.vertices[v][k] += eps;
            let fp = law.force_density(&m)[v];
            m.vertices[v][k] -= 2.0 * eps;
            let fm = law.force_density(&m)[v];
            b.set_column(k, &(mob[v] * (fp - fm) / (2.0 * eps)));
        }
        b.eigenvalues().map_or_else(|| b.norm(), |e| e.iter().map(|l| l.abs()).fold(0.0, f64::max))
    };
    f.linearise(0.0, x)?;
    let mut jloc = vec![0.0; n];
    if let Some(j) = f.local_jacobian()? {
        for (v, jl) in jloc.iter_mut().enumerate() {
            let mut b = nalgebra::Matrix3::zeros();
            for k in 0..3 {
                let mut w = vec![Vector3::zeros(); n];
                w[v][k] = 1.0;
                let mut out = vec![Vector3::zeros(); n];
                j.apply(&w, &mut out);
                b.set_column(k, &out[v]);
            }
            *jl = b.eigenvalues().map_or_else(|| b.norm(), |e| e.iter().map(|l| l.abs()).fold(0.0, f64::max));
        }
    }
    let full: Vec<f64> = (0..n).map(|v| block_rate(membrane, v)).collect();
    let bend: Vec<f64> = (0..n).map(|v| block_rate(&bending, v)).collect();
    for (name, r) in [("whole membrane (FD)", &full), ("bending alone (FD)", &bend), ("J_loc (elastic)", &jloc)] {
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| r[b].total_cmp(&r[a]));
        let top: Vec<String> = order.iter().take(5).map(|&v| format!("{v}: {:.2e}", r[v])).collect();
        let mut sorted = r.clone();
        sorted.sort_by(|a, b| a.total_cmp(b));
        println!("self rate (1/s), {name}: median {:.2e}; stiffest {}; vertex {watch}: {:.2e}", sorted[n / 2], top.join(", "), r[watch]);
    }
    Ok(())
}

/// Volume centroid (um) of a vertex set on `tris`.
fn centroid(x: &[Vector3<f64>], tris: &[[usize; 3]]) -> Vector3<f64> {
    rbc_solver::mesh::slices::centroid(x, tris)
}

/// Errors of `run` against `reference` at their common output times: max vertex distance (um),
/// max centroid (y, z) distance (um), relative error of the mean axial velocity, max asphericity difference.
pub fn errors(run: &TolRun, reference: &TolRun, tris: &[[usize; 3]]) -> [f64; 4] {
    let (mut dv, mut dc, mut da) = (0.0f64, 0.0f64, 0.0f64);
    let mut common = 0;
    for (t, v) in run.times_s.iter().zip(&run.vertices) {
        let Some(k) = reference.times_s.iter().position(|r| (r - t).abs() < 1e-12) else { continue };
        let vr = &reference.vertices[k];
        common += 1;
        dv = dv.max(v.iter().zip(vr).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max));
        let (c, cr) = (centroid(v, tris), centroid(vr, tris));
        dc = dc.max(((c.y - cr.y).powi(2) + (c.z - cr.z).powi(2)).sqrt());
        da = da.max((asphericity(v) - asphericity(vr)).abs());
    }
    let vel = |r: &TolRun| {
        let n = r.times_s.len();
        (centroid(&r.vertices[n - 1], tris).x - centroid(&r.vertices[0], tris).x) / (r.times_s[n - 1] - r.times_s[0])
    };
    let du = (vel(run) / vel(reference) - 1.0).abs();
    if common < 2 {
        return [f64::NAN; 4];
    }
    [dv, dc, du, da]
}

/// Run the study with the remaining command-line arguments.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let mut start = Start { results: PathBuf::new(), run: "steps-bs23".into(), snapshot: -1 };
    let mut schemes: Vec<String> = vec!["bs23".into(), "ros34pw2-local".into()];
    let mut atols = vec![4e-5, 1e-4, 3e-4, 1e-3];
    let mut reference = ("bs23".to_string(), 1e-5, "integral".to_string());
    let mut controllers = vec!["integral".to_string()];
    let (mut explicit, mut with_reference): (Option<Vec<TolConfig>>, bool) = (None, true);
    let (mut window_ms, mut output_ms, mut threads, mut dir) = (1.0, 0.25, 1usize, PathBuf::from("channel-tol"));
    let (mut probe_hs, mut watch, mut shifts): (Option<Vec<f64>>, usize, Vec<f64>) = (None, 176, Vec::new());
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("rbc-bench channel-tol: {a} needs a value"));
        match a.as_str() {
            "--start" => start.results = PathBuf::from(val()?),
            "--run" => start.run = val()?.clone(),
            "--snapshot" => start.snapshot = val()?.parse().context("--snapshot")?,
            "--schemes" => schemes = val()?.split(',').map(|s| s.trim().to_string()).collect(),
            "--atols" => atols = val()?.split(',').map(|s| s.trim().parse()).collect::<Result<_, _>>().context("--atols")?,
            "--reference" => reference = parse_config(val()?).context("--reference")?,
            "--controllers" => {
                controllers = val()?.split(',').map(|s| s.trim().to_string()).collect();
                for c in &controllers {
                    controller_of(c).context("--controllers")?;
                }
            }
            "--runs" => explicit = Some(val()?.split(',').map(parse_config).collect::<anyhow::Result<_>>().context("--runs")?),
            "--no-reference" => with_reference = false,
            "--window-ms" => window_ms = val()?.parse().context("--window-ms")?,
            "--output-ms" => output_ms = val()?.parse().context("--output-ms")?,
            "--threads" => threads = val()?.parse().context("--threads")?,
            "--dir" => dir = PathBuf::from(val()?),
            "--probe" => probe_hs = Some(val()?.split(',').map(|s| s.trim().parse()).collect::<Result<_, _>>().context("--probe")?),
            "--watch" => watch = val()?.parse().context("--watch")?,
            "--shifts" => shifts = val()?.split(',').map(|s| s.trim().parse()).collect::<Result<_, _>>().context("--shifts")?,
            other => bail!("rbc-bench channel-tol: unknown option {other:?}"),
        }
    }
    if start.results.as_os_str().is_empty() {
        anyhow::bail!("rbc-bench channel-tol: --start RESULTS.h5 is required (a channel run's results with snapshots; --run names the run)");
    }
    if let Some(hs) = probe_hs {
        return probe(&start, &schemes, &hs, &shifts, watch, threads);
    }
    std::fs::create_dir_all(&dir).with_context(|| dir.display().to_string())?;
    println!("## Channel tolerance study: {window_ms} ms from snapshot {} of {} in {}, outputs every {output_ms} ms, {threads} thread(s)", start.snapshot, start.run, start.results.display());
    println!("load average at start: {}", load_average());
    let grid = || {
        let mut g = Vec::new();
        for s in &schemes {
            for &a in &atols {
                for c in &controllers {
                    g.push((s.clone(), a, c.clone()));
                }
            }
        }
        g
    };
    let mut configs: Vec<TolConfig> = if with_reference { vec![reference.clone()] } else { Vec::new() };
    for c in explicit.unwrap_or_else(grid) {
        if !configs.contains(&c) {
            configs.push(c);
        }
    }
    let mut runs = Vec::new();
    for (s, a, c) in &configs {
        let path = dir.join(TolRun::file_name(s, *a, c));
        let r = if path.exists() {
            TolRun::load(&path)?
        } else {
            eprintln!("channel-tol: running {s} at atol {a:e} um, {c} controller ...");
            let r = measure(&start, s, *a, c, window_ms, output_ms, threads).with_context(|| format!("{s} at atol {a:e}, {c} controller"))?;
            r.save(&path)?;
            r
        };
        eprintln!("channel-tol: {s} @ {a:e} ({c}): {} accepted, {} rejected, {:.0} core-s", r.accepted, r.rejected, r.cpu_s);
        runs.push(r);
    }
    if !with_reference {
        return Ok(());
    }
    let snaps = rbc_schema::results::read_snapshots(&start.results, &start.run)?;
    let tris: Vec<[usize; 3]> = snaps.triangles.iter().map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
    print_tables(&runs, &runs[0], &tris);
    Ok(())
}

/// Print the work-precision table and the anatomy of the error estimates.
pub fn print_tables(runs: &[TolRun], reference: &TolRun, tris: &[[usize; 3]]) {
    println!("reference: {} at atol {:e} um ({} controller)", reference.scheme, reference.atol_um, reference.controller);
    println!();
    println!("scheme | atol (um) | controller | acc/ms | rej/ms | evals/ms | h mean / max (us) | core-s per ms | max vertex err (um) | centroid (y,z) err (um) | rel. velocity err | asphericity err");
    println!("---|---|---|---|---|---|---|---|---|---|---|---");
    for r in runs {
        let [dv, dc, du, da] = errors(r, reference, tris);
        println!(
            "{} | {:.0e} | {} | {:.1} | {:.1} | {:.0} | {:.1} / {:.1} | {:.0} | {:.1e} | {:.1e} | {:.1e} | {:.1e}",
            r.scheme,
            r.atol_um,
            r.controller,
            r.accepted as f64 / r.sim_ms,
            r.rejected as f64 / r.sim_ms,
            r.velocity_evals as f64 / r.sim_ms,
            r.sim_ms * 1e3 / r.accepted.max(1) as f64,
            r.h_max_s * 1e6,
            r.cpu_s / r.sim_ms,
            dv,
            dc,
            du,
            da
        );
    }
    println!();
    println!("Anatomy of the error estimates (medians over accepted | rejected attempts)");
    println!("scheme | atol (um) | controller | e | e filtered | translation share | normal share | high-pass share | h ||J_loc err||/||err|| | worst vertices (most frequent)");
    println!("---|---|---|---|---|---|---|---|---|---");
    for r in runs {
        let pick = |acc: bool, f: &dyn Fn(&Attempt) -> f64| upper_median(&mut r.attempts.iter().filter(|a| a.accepted == acc && a.e.is_finite()).map(f).collect::<Vec<_>>()).unwrap_or(f64::NAN);
        let both = |f: &dyn Fn(&Attempt) -> f64| format!("{:.2} \\| {:.2}", pick(true, f), pick(false, f));
        let mut counts = std::collections::BTreeMap::<usize, usize>::new();
        for a in &r.attempts {
            *counts.entry(a.worst).or_default() += 1;
        }
        let mut top: Vec<(usize, usize)> = counts.into_iter().collect();
        top.sort_by_key(|t| std::cmp::Reverse(t.1));
        let top: Vec<String> = top.iter().take(3).map(|(v, c)| format!("{v} ({c})")).collect();
        println!(
            "{} | {:.0e} | {} | {} | {} | {} | {} | {} | {} | {}",
            r.scheme,
            r.atol_um,
            r.controller,
            both(&|a| a.e),
            both(&|a| a.e_filtered),
            both(&|a| a.translation),
            both(&|a| a.normal),
            both(&|a| a.high_pass),
            both(&|a| a.h_lambda),
            top.join(", ")
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere() -> Mesh {
        rbc_solver::mesh::sphere(2, 3.0)
    }

    #[test]
    fn shares_of_a_translation_a_radial_field_and_a_single_vertex_spike() {
        let m = sphere();
        let n = m.vertices.len();
        let nb = neighbours(&m.triangles, n);
        // a rigid translation: all of it translation, nothing high-pass
        let (t, _, hp) = shares(&m.vertices, &m.triangles, &nb, &vec![Vector3::new(1e-5, -2e-5, 3e-5); n]);
        assert!((t - 1.0).abs() < 1e-12 && hp < 1e-20, "translation {t}, high-pass {hp}");
        // radial displacement of a centred sphere: normal (area-weighted vertex normals of a level-2 icosphere are a few degrees off radial: measured share 0.9956)
        let radial: Vec<Vector3<f64>> = m.vertices.iter().map(|p| 1e-5 * p.normalize()).collect();
        let (t, nrm, _) = shares(&m.vertices, &m.triangles, &nb, &radial);
        assert!(t < 1e-20 && nrm > 0.99, "translation {t}, normal {nrm}");
        // one vertex displaced alone: high-pass share 1 + 1/valence (its own term plus one per neighbour of 1/valence^2 each)
        let mut spike = vec![Vector3::zeros(); n];
        spike[7] = Vector3::new(0.0, 0.0, 1e-5);
        let (_, _, hp) = shares(&m.vertices, &m.triangles, &nb, &spike);
        let k = nb[7].len() as f64;
        let want = 1.0 + nb[7].iter().map(|&j| 1.0 / (nb[j].len() as f64).powi(2)).sum::<f64>();
        assert!((hp - want).abs() < 1e-12 && k >= 5.0, "high-pass {hp} vs {want}");
        assert_eq!(shares(&m.vertices, &m.triangles, &nb, &vec![Vector3::zeros(); n]), (0.0, 0.0, 0.0));
    }

    /// `y' = A y` on one vertex, `A = diag(-1e5, -1, -2)` 1/s, handed over as its own local Jacobian.
    struct Diagonal(rbc_solver::integrate::precondition::LocalJacobian);

    impl rbc_solver::integrate::Dynamics for Diagonal {
        fn velocity(&mut self, _t: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
            self.0.apply(x, u);
            Ok(())
        }
    }

    impl Linearised for Diagonal {
        fn linearise(&mut self, _t: f64, _x: &[Vector3<f64>]) -> Result<(), SolverError> {
            Ok(())
        }
        fn jacobian_apply(&mut self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), SolverError> {
            self.0.apply(w, out);
            Ok(())
        }
        fn local_jacobian(&mut self) -> Result<Option<&rbc_solver::integrate::precondition::LocalJacobian>, SolverError> {
            Ok(Some(&self.0))
        }
    }

    #[test]
    fn probe_tells_a_stiff_error_from_a_smooth_one() {
        let j = rbc_solver::integrate::precondition::LocalJacobian::from_entries(1, &[(0, 0, -1e5), (1, 1, -1.0), (2, 2, -2.0)]).unwrap();
        let mut f = Diagonal(j);
        let mut p = Probe::new(BogackiShampine::new(), &[], 1, 1e-5);
        let (h, x) = (1e-4, [Vector3::new(1.0, 1.0, 1.0)]);
        // error along the stiff axis: h |lambda| = 10, the filter divides it by 1 + 2 gamma h 1e5
        let a = p.analyse(&mut f, 0.0, &x, h, &[Vector3::new(2e-5, 0.0, 0.0)]).unwrap();
        assert!((a.e - 2.0).abs() < 1e-12 && (a.h_lambda - 10.0).abs() < 1e-9, "{a:?}");
        assert!((a.e_filtered - 2.0 / (1.0 + 2.0 * GAMMA_DIAG * 10.0)).abs() < 1e-12, "{a:?}");
        // along a slow axis: h |lambda| = 2e-4 and the filter leaves it (to 1 + 2 gamma h 2)
        let a = p.analyse(&mut f, 0.0, &x, h, &[Vector3::new(0.0, 0.0, 2e-5)]).unwrap();
        assert!((a.h_lambda - 2e-4).abs() < 1e-12 && (a.e_filtered - 2.0 / (1.0 + 2.0 * GAMMA_DIAG * 2e-4)).abs() < 1e-12, "{a:?}");
    }

    #[test]
    fn saved_runs_read_back_exactly_and_errors_measure_a_known_offset() {
        let m = sphere();
        let mut r = TolRun { scheme: "bs23".into(), atol_um: 4e-5, controller: "pi".into(), accepted: 12, rejected: 3, velocity_evals: 40, cpu_s: 1.0 / 3.0, analysis_s: 0.1, sim_ms: 1.0, h_max_s: 2.5e-5, ..Default::default() };
        r.attempts.push(Attempt { t_s: 1e-4, h_s: 1.0 / 7.0 * 1e-5, accepted: true, e: 0.7, e_filtered: 0.69, worst: 176, translation: 0.01, normal: 0.3, high_pass: 0.2, h_lambda: 0.04 });
        for k in 0..3 {
            r.times_s.push(k as f64 * 2.5e-4);
            r.vertices.push(m.vertices.iter().map(|p| p + Vector3::new(7.4 * k as f64, 0.0, 0.0)).collect());
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(TolRun::file_name(&r.scheme, r.atol_um, &r.controller));
        assert_eq!(path.file_name().unwrap(), "bs23@4e-5@pi.txt");
        r.save(&path).unwrap();
        let back = TolRun::load(&path).unwrap();
        assert_eq!(back.controller, "pi");
        // a run saved before the controller column existed reads as the integral controller
        let old = dir.path().join(TolRun::file_name("bs23", 4e-5, "integral"));
        assert_eq!(old.file_name().unwrap(), "bs23@4e-5.txt");
        std::fs::write(&old, "run bs23 4e-5 12 3 40 1e0 1e-1 1e0 2.5e-5\n").unwrap();
        assert_eq!(TolRun::load(&old).unwrap().controller, "integral");
        assert_eq!(parse_config("ros34pw2-local@1e-3@pi").unwrap(), ("ros34pw2-local".to_string(), 1e-3, "pi".to_string()));
        assert_eq!(parse_config("bs23@4e-5").unwrap().2, "integral");
        assert!(parse_config("bs23@4e-5@pid").is_err() && parse_config("bs23").is_err());
        assert_eq!((back.accepted, back.rejected, back.velocity_evals, back.cpu_s, back.h_max_s), (12, 3, 40, 1.0 / 3.0, 2.5e-5));
        assert_eq!(back.attempts, r.attempts);
        assert_eq!((back.times_s.clone(), back.vertices.clone()), (r.times_s.clone(), r.vertices.clone()));
        assert_eq!(errors(&back, &r, &m.triangles), [0.0; 4]);
        // the same run offset by 0.1 um in y and 0.2 um more along x at the last sample
        let mut off = r.clone();
        for v in &mut off.vertices {
            v.iter_mut().for_each(|p| p.y += 0.1);
        }
        off.vertices[2].iter_mut().for_each(|p| p.x += 0.2);
        let [dv, dc, du, da] = errors(&off, &r, &m.triangles);
        let want_v = (0.1f64.powi(2) + 0.2f64.powi(2)).sqrt();
        assert!((dv - want_v).abs() < 1e-12 && (dc - 0.1).abs() < 1e-12 && da < 1e-12, "{dv} {dc} {da}");
        // mean velocity (14.8 + 0.2) um / 5e-4 s against 14.8 um / 5e-4 s
        assert!((du - 0.2 / 14.8).abs() < 1e-9, "{du}");
    }
}
