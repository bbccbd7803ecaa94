//! The periodic-channel Stokes solve: membrane velocity of a cell (any viscosity ratio) in the paper's channel, driven by a prescribed mean flow, with exact no-slip walls (dense factorised wall operator) or penalty springs.
//!
//! ## Equations (outer viscosity `mu`, `lambda = 1`)
//! With `f_c` the force per area the membrane exerts on the fluid (Pa) and `f_w` the wall
//! traction (the single-layer density of the wall, Pa), the velocity everywhere is
//!
//! ```text
//! u(x) = U0 e_x + 1/(8 pi mu) [ Int_cell G_per(x - y) f_c(y) dS_y + Int_wall G_per(x - y) f_w(y) dS_y ]
//! ```
//!
//! `G_per` is the triply periodic Stokeslet of [`crate::ewald`] in the box
//! `L_x x (L_y + 2 gap) x (L_z + 2 gap)`, and `U0` its `k = 0` mode (the box-mean velocity).
//! - Exact no-slip ([`WallMode::NoSlip`]): `u = 0` at the wall vertices, i.e.
//!   `S f_w = -mu U0 e_x - SL_cell[f_c]|_wall` ([`super::wall::WallOperator`], factorised once).
//! - Penalty ([`WallMode::Penalty`], the paper's method, Guckenberger & Gekle 2018 and Tahiri
//!   et al. 2013): the wall vertices are material points tied by springs to their rest positions
//!   `X_0`; the traction is `f_w = -kappa_W (X - X_0)` (N/m^3 x m = Pa), and the wall vertices move
//!   with the fluid velocity. The wall displacement is then part of the state of the time
//!   integration ([`ChannelStokes::penalty_velocity`] returns both velocities); in a steady
//!   state the wall velocity vanishes and `f_w` is the no-slip traction, reached with the
//!   relaxation rate `kappa_W lambda_max(S) / mu` (which limits explicit steps).
//!
//! ## Viscosity contrast (`lambda != 1`; Pozrikidis 1992, ch. 5-6)
//! The inner fluid has viscosity `lambda mu`. The cell adds the periodic double layer with the
//! box-mean term derived in [`super::double_layer`]: at fluid points
//! `u(x) = ... (as above) + (1 - lambda)/2 E[u](x)`, and on the membrane
//!
//! ```text
//! (1 + lambda)/2 u = U0 e_x + (SL_cell[f_c] + SL_wall[f_w])/mu + (1 - lambda)/2 A[u]     (cell vertices)
//! 0 = U0 e_x + (SL_cell[f_c]|_wall + S f_w)/mu + (1 - lambda)/2 E[u]|_wall                 (no-slip, wall vertices)
//! Q = U0 A_box - K_E b,  b = -(F_c + F_w)_x / V                                             (flux)
//! ```
//!
//! The last two are linear in `u` given the factorised `S`: `f_w = f_w0 + f_w'[u]`,
//! `U0 = U0_0 + U0'[u]` (`f_w0`, `U0_0` those of the `lambda = 1` solve). GMRES solves for the
//! membrane velocity `u - kappa A[u] - 2/(1+lambda) (U0'[u] e_x + SL_wall[f_w'[u]]/mu) = 2/(1+lambda) (u of lambda = 1)`,
//! `kappa = (1 - lambda)/(1 + lambda)`: each operator application is one Ewald stresslet sum
//! (the cell's double layer at the cell and wall vertices), one LU back-substitution and one Ewald
//! Stokeslet sum (the wall's answer at the cell). Rigid-body Wielandt deflation as a right
//! preconditioner keeps the iterations flat in lambda (measured 9 at lambda = 5, 14-15 at
//! lambda = 20 for 128 to 2048 triangles, tolerance 1e-5, from a zero start). Penalty walls: `f_w` and `U0` do not
//! depend on `u`; the wall velocity gains `(1 - lambda)/2 E[u]`.
//!
//! ## Cost (what makes a lambda != 1 solve cheap)
//! The geometry is fixed during one solve while GMRES applies the operator ~5-10 times, and the
//! wall never moves. So ([`ChannelOptions::iteration_sums`], [`IterationSums::Model`] by default):
//! - the sums inside GMRES have their own splitting `xi`, chosen by the cost model
//!   [`crate::ewald::params::sums_cost`] with the real-space pairs frozen: their real-space parts
//!   are built once per solve as block-sparse matrices over the vertex values
//!   ([`crate::ewald::blocks`]: 3 x 3 blocks, the double layer at the cell and wall vertices, the
//!   wall's single layer at the cell vertices), each application is a mat-vec plus the Fourier part;
//! - the wall's quadrature nodes (28 224 for 2 um edges, refined once) are spread to the Fourier
//!   grids once ([`crate::ewald::BasisSpread`]), for every wall -> cell sum (also lambda = 1);
//! - the cell's stresslet spreading onto the Fourier grids is likewise a sparse map from the
//!   vertex values built once per solve ([`crate::ewald::StressletSpread`]), and its real-space
//!   blocks are built triangle by triangle with the 7 nodes in SIMD lanes ([`crate::ewald::lanes`]);
//!   session 6 measured one cold solve 0.47-0.50 -> 0.40-0.42 CPU s (`solver/README.md`);
//! - the cell's single layer (the right-hand side) takes GMRES's splitting, and its real-space
//!   part is summed from the same pairs while the stresslet blocks are built (the distances,
//!   `erfc` and `exp` shared: [`crate::ewald::PeriodicStokes::stresslet_real_blocks_with_single_layer`]),
//!   so only its Fourier part is a sum of its own; session 14 measured 0.92 of the core-s of a
//!   late-run window (`solver/README.md`);
//! - the wall's Stokeslet blocks at the cell are built sub-triangle by sub-triangle, the 7 nodes
//!   in SIMD lanes ([`crate::ewald::PeriodicStokes::stokeslet_real_blocks_grouped`]); with the
//!   AVX-512 kernels of [`crate::ewald::lanes`] session 15 measured 0.885 of a late window;
//! - two real grids share one complex FFT ([`crate::ewald::spectral`]);
//! - the parameters of the other sums come from the same cost model with the real-space pairs of
//!   the clustered membrane nodes (`~ r^2`, [`crate::ewald::params::PairModel::Surface`]), not
//!   those of evenly spread points: for the paper's coarse scene this picked `r_cut` 4.5 um and a
//!   75 x 27 x 24 grid instead of 2.75 um and 120 x 45 x 40 (real 4 ms / Fourier 44 ms per sum before).
//!
//! GMRES starts from the velocity predicted from the path of the last 8 solves
//! ([`super::secant_guess`], `extrapolate_guess`, on by default; the path is kept in checkpoints),
//! else from the last velocity of the time integration (stopping rule relative to the right-hand
//! side, so the answer is the same to the tolerance). In a late-run window of the paper's channel
//! (ROS34PW2 with the dense mobility Jacobian, 2048 triangles) it cuts GMRES from 223 to 189
//! iterations and the core-s to 0.94-0.95 (`solver/README.md`, session 16). The two-point
//! extrapolation along the last step it replaces saved 4 % with bs23 at 512 triangles (session 5)
//! and cost iterations with the Rosenbrock schemes.
//!
//! Measured (`rbc-bench channel --lambda 5 --walls no-slip --levels 3 --edge 2.0 --tol 1e-4
//! --sim-ms 0.2 --threads 1`, 512 triangles, process CPU time, load ~9 on 2 cores, the
//! same 9 bs23 / 11 ros34pw2-local steps of mean 22 / 18 us before and after, two runs): bs23
//! 134-145 -> 31-32.5 core-s per simulated ms (30-31 with the extrapolated guess), ros34pw2-local
//! 184-192 -> 42-44 (40-42.5); GMRES 4.6 iterations per solve warm-started (4.15 extrapolated;
//! 9 from zero), centroid velocity 7.575 -> 7.574 mm/s. One cold solve (`rbc-bench channel-profile`): 1.03-1.10 CPU s -> 0.22 s.
//! The frozen and the plain sums agree to 4e-5..9e-5 (Ewald tolerance 1e-4) and 1e-6 (1e-6),
//! test `channel_fast`.
//!
//! The flux stays exact: `U0 A_box` is the flux of the whole box through any cross-section (the
//! velocity is continuous across the membrane and divergence-free inside too), `U0` is the
//! box mean of the whole field including the cell interior (the double layer and its box-mean
//! term carry no `k = 0` mode), and the exterior fluid still only feels `b`. Tested by the
//! far-field profile (`tests/channel_lambda.rs`). `lambda = 1` builds no double layer.
//!
//! ## Driving by a prescribed mean flow
//! `G_per` leaves out `k = 0`: the net force `F = Int f_c + Int f_w` on the box is balanced by a
//! uniform body force `b = -F / V_box` (Pa/um), the mean pressure gradient `-dp/dx` of the
//! channel, and the box-mean velocity is `U0`. The box also contains fluid outside the tube
//! (between periodic images of the channel in y and z); there the flow is `b` times a fixed
//! field (u = 0 on the wall), with flux `K_E b`. Hence the flux inside the channel is
//! `Q = U0 A_box - K_E b`. `K_E` comes from one calibration solve without a cell (`U0 = 1`):
//! its body force `b_1` and the interior flux `K_I b_1` of the rounded-corner duct
//! ([`super::duct::rounded_flux`]). Each solve then picks `U0` so that `Q = U_mean A_channel`
//! (a scalar equation, solved with the precomputed `S^-1 e_x`).
//!
//! ## Quadrature on the cell
//! As [`crate::bim::single_layer`]: 7-point Gauss, normal part removed by
//! `Int_cell G_per . n dS = 0` (true for the periodic kernel as well: it is divergence-free),
//! Duffy rule for the free-space part on the triangles touching the target.
//!
//! Units: um, Pa, Pa s, um/s; mean flows in the API in mm/s (`1 mm/s = 1000 um/s`).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use faer::Mat;
use nalgebra::Vector3;

use super::cell_layer::{cell_single_layer, StokesletSum};
use super::double_layer::PeriodicDoubleLayer;
use super::duct::RoundedDuct;
use super::mesh::{ChannelGeometry, ChannelMesh};
use super::wall::{WallNodes, WallOperator};
use super::ChannelError;
use crate::bim::surface::Surface;
use crate::ewald::lanes32::BlockPrecision;
use crate::ewald::{BasisSpread, BlockRows, EwaldParams, PeriodicStokes};
use crate::gmres::{GmresOptions, Tolerance};
use crate::mesh::Mesh;
use crate::viscosity::ViscosityContrast;

use super::secant_guess::{self, PathPoint};
pub use super::options::{ChannelOptions, IterationSums, WallMode};
pub use super::stats::{ChannelSolution, ChannelStats, SolveTimes};
use sums::{iteration_sums, solve_sums};

mod solve;
mod sums;

/// Stokes solver of the periodic channel (see the module docs).
pub struct ChannelStokes {
    pub geometry: ChannelGeometry,
    /// The rounded-corner duct flow (reference profile and the flux of the calibration).
    pub duct: RoundedDuct,
    pub mesh: ChannelMesh,
    mu: f64,
    lambda: ViscosityContrast,
    pub wall_mode: WallMode,
    pub opts: ChannelOptions,
    ewald: PeriodicStokes,
    pub wall: WallOperator,
    /// Wall quadrature for off-wall evaluation ([`ChannelOptions::wall_eval_refine`]).
    eval_nodes: WallNodes,
    /// The sums inside GMRES ([`ChannelOptions::iteration_sums`]) and the spreading of the
    /// wall's quadrature nodes to their grid.
    iteration: Option<(PeriodicStokes, BasisSpread)>,
    /// The spreading of the wall's quadrature nodes to the grid of `ewald` (their positions never change).
    wall_spread: BasisSpread,
    box_len: [f64; 3],
    /// `f_e = -mu S^-1 e_x` (Pa per um/s of U0).
    f_e: Vec<Vector3<f64>>,
    /// Body force per unit U0 without a cell (Pa/um per um/s), interior flux per unit U0 (um^2), `K_E` (um^4 / (Pa s)... um^3/s per Pa/um).
    b_e: f64,
    q_interior_e: f64,
    k_exterior: f64,
    /// Mean flow used by the [`crate::bim::Stokes`] implementation (mm/s).
    pub mean_flow_mm_s: f64,
    /// Viscosity-contrast solves so far, their GMRES iterations (Arnoldi steps) and those that
    /// started from a guess ([`Self::gmres_totals`]).
    gmres_counts: [AtomicUsize; 3],
    /// Wall time summed over the trait's solves ([`Self::solve_times`]).
    times: Mutex<SolveTimes>,
    /// The last [`secant_guess::HISTORY`] `(vertices, velocity)` of the trait's solves with the mean flow, oldest first ([`ChannelOptions::extrapolate_guess`]).
    history: Mutex<Vec<PathPoint>>,
}

impl std::fmt::Debug for ChannelStokes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ChannelStokes")
            .field("geometry", &self.geometry)
            .field("mu", &self.mu)
            .field("wall_mode", &self.wall_mode)
            .finish()
    }
}

fn check_finite(what: &'static str, v: &[Vector3<f64>]) -> Result<(), ChannelError> {
    match v.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        Some(index) => Err(ChannelError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// One value per vertex: `v` holds `expected` values (else [`ChannelError::LengthMismatch`]), all finite.
fn check_per_vertex(what: &'static str, v: &[Vector3<f64>], expected: usize) -> Result<(), ChannelError> {
    if v.len() != expected {
        return Err(ChannelError::LengthMismatch { what, expected, got: v.len() });
    }
    check_finite(what, v)
}

impl ChannelStokes {
    /// Build the wall mesh, the Ewald sums, the dense wall operator (assembled and factorised
    /// once) and the flux calibration. `mu_pa_s` outer viscosity (Pa s), `lambda` viscosity
    /// contrast `mu_in / mu` (matched: no double layer).
    pub fn new(
        geometry: ChannelGeometry,
        mu_pa_s: f64,
        lambda: ViscosityContrast,
        wall_mode: WallMode,
        opts: ChannelOptions,
    ) -> Result<Self, ChannelError> {
        geometry.validate()?;
        let bad = |name, value, reason| {
            Err(ChannelError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        if !(mu_pa_s > 0.0 && mu_pa_s.is_finite()) {
            return bad("mu_pa_s", mu_pa_s, "must be positive and finite");
        }
        if !(opts.gmres_tolerance > 0.0 && opts.gmres_tolerance < 1.0) {
            return bad(
                "gmres_tolerance",
                opts.gmres_tolerance,
                "must lie in (0, 1)",
            );
        }
        if opts.gmres_restart == 0 || opts.gmres_max_iterations == 0 {
            return bad(
                "gmres_restart/gmres_max_iterations",
                0.0,
                "must be positive",
            );
        }
        if let WallMode::Penalty {
            kappa_w_n_per_m3: k,
        } = wall_mode
        {
            if !(k > 0.0 && k.is_finite()) {
                return bad("kappa_w_n_per_m3", k, "must be positive and finite");
            }
        }
        if !(opts.cell_area_hint_um2 > 0.0 && opts.cell_area_hint_um2.is_finite()) {
            return bad(
                "cell_area_hint_um2",
                opts.cell_area_hint_um2,
                "must be positive",
            );
        }
        if !(opts.box_gap_um > 0.0 && opts.box_gap_um.is_finite()) {
            return bad("box_gap_um", opts.box_gap_um, "must be positive");
        }
        let mesh = ChannelMesh::with_edge(geometry, opts.wall_edge_um)?;
        let box_len = [
            geometry.length_x,
            geometry.width_y + 2.0 * opts.box_gap_um,
            geometry.height_z + 2.0 * opts.box_gap_um,
        ];
        let params =
            EwaldParams::for_sums(box_len, &solve_sums(&opts, &mesh, false), opts.ewald_tol)?;
        let ewald = PeriodicStokes::new(box_len, params)?;
        // The assembly sums have 42 sources and N_w targets each: a larger real-space cutoff and
        // a coarser grid than for a full solve (the cost model with ~sqrt(42 N_w) points).
        let n_assembly = ((42 * 4usize.pow(opts.wall_matrix_refine as u32) * mesh.n_vertices())
            as f64)
            .sqrt() as usize;
        let assembly_ewald = PeriodicStokes::new(
            box_len,
            EwaldParams::for_tolerance(box_len, n_assembly, opts.ewald_tol)?,
        )?;
        let wall = WallOperator::new(
            &mesh,
            &assembly_ewald,
            opts.duffy_nodes,
            opts.wall_matrix_refine,
        )?;
        let nv = mesh.n_vertices();
        let f_e: Vec<Vector3<f64>> = wall.solve(&vec![Vector3::x() * (-mu_pa_s); nv]);
        let volume = box_len[0] * box_len[1] * box_len[2];
        let b_e = -wall_force(&mesh, &f_e).x / volume;
        let duct = RoundedDuct::new(&geometry, opts.flux_grid_um);
        let q_interior_e = duct.flux(mu_pa_s, b_e);
        let a_box = box_len[1] * box_len[2];
        let k_exterior = (a_box - q_interior_e) / b_e;
        let eval_nodes = WallNodes::refined(&mesh, opts.wall_eval_refine);
        let iteration = iteration_sums(&opts, lambda, box_len, &mesh, &eval_nodes)?;
        let wall_spread = ewald.basis_spread(
            &eval_nodes.positions,
            &eval_nodes.weights,
            &eval_nodes.interp,
            nv,
        )?;
        Ok(Self {
            geometry,
            duct,
            mesh,
            mu: mu_pa_s,
            lambda,
            wall_mode,
            opts,
            ewald,
            wall,
            eval_nodes,
            iteration,
            wall_spread,
            box_len,
            f_e,
            b_e,
            q_interior_e,
            k_exterior,
            mean_flow_mm_s: 0.0,
            gmres_counts: Default::default(),
            history: Mutex::new(Vec::new()),
            times: Mutex::new(SolveTimes::default()),
        })
    }

    /// The same channel with other [`ChannelOptions::iteration_sums`]; only those sums are
    /// rebuilt. For tests and benchmarks.
    pub fn with_iteration_sums(mut self, sums: IterationSums) -> Result<Self, ChannelError> {
        self.set_iteration_sums(sums)?;
        Ok(self)
    }

    /// Set [`ChannelOptions::block_precision`] (for benchmarks and tests).
    pub fn set_block_precision(&mut self, precision: BlockPrecision) {
        self.opts.block_precision = precision;
    }

    /// Switch [`ChannelOptions::extrapolate_guess`] (for benchmarks); clears the history.
    pub fn set_extrapolate_guess(&mut self, on: bool) {
        self.opts.extrapolate_guess = on;
        self.history
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
    }

    /// Set [`ChannelOptions::two_grid_level`] (for benchmarks and tests).
    pub fn set_two_grid_level(&mut self, level: Option<usize>) {
        self.opts.two_grid_level = level;
    }

    /// In-place [`Self::with_iteration_sums`].
    pub fn set_iteration_sums(&mut self, sums: IterationSums) -> Result<(), ChannelError> {
        let opts = ChannelOptions {
            iteration_sums: sums,
            ..self.opts.clone()
        };
        self.iteration = iteration_sums(
            &opts,
            self.lambda,
            self.box_len,
            &self.mesh,
            &self.eval_nodes,
        )?;
        self.opts = opts;
        Ok(())
    }

    /// Where the solves of the [`crate::bim::Stokes`] interface spent their wall time so far.
    pub fn solve_times(&self) -> SolveTimes {
        *self.times.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// `(solves, GMRES iterations, solves started from a guess)` of the viscosity-contrast
    /// solves so far (e.g. over a time integration).
    pub fn gmres_totals(&self) -> (usize, usize, usize) {
        let [a, b, c] = &self.gmres_counts;
        (
            a.load(Ordering::Relaxed),
            b.load(Ordering::Relaxed),
            c.load(Ordering::Relaxed),
        )
    }

    /// Ewald parameters of the sums inside GMRES, if they differ from [`Self::ewald_params`].
    pub fn iteration_ewald_params(&self) -> Option<&EwaldParams> {
        self.iteration.as_ref().map(|(e, _)| e.params())
    }

    pub fn viscosity(&self) -> f64 {
        self.mu
    }
    pub fn viscosity_ratio(&self) -> ViscosityContrast {
        self.lambda
    }
    pub fn ewald_params(&self) -> &EwaldParams {
        self.ewald.params()
    }
    pub fn box_len(&self) -> [f64; 3] {
        self.box_len
    }

    /// Volume of the periodic box (um^3).
    fn box_volume(&self) -> f64 {
        self.box_len.iter().product::<f64>()
    }

    /// Fraction of the box-mean flow `U0` that passes inside the channel without a cell:
    /// `K_I b_1 / (U0 A_channel)` for `U0 = 1`, and the exterior conductance `K_E` (um^4/(Pa s)).
    pub fn calibration(&self) -> (f64, f64, f64) {
        (
            self.q_interior_e / self.geometry.cross_section_area(),
            self.b_e,
            self.k_exterior,
        )
    }

    /// The same solver with a mean flow (mm/s) for the [`crate::bim::Stokes`] trait.
    pub fn with_mean_flow(mut self, mean_flow_mm_s: f64) -> Self {
        self.mean_flow_mm_s = mean_flow_mm_s;
        self
    }

    /// The Poiseuille flow of the channel without a cell at points `x` (um/s), for the mean flow
    /// (mm/s), evaluated from the computed wall traction (the smooth-quadrature field: accurate a
    /// few wall-mesh edges away from the wall), with the pressure gradient (Pa/um).
    pub fn empty_channel_flow(
        &self,
        points: &[Vector3<f64>],
        mean_flow_mm_s: f64,
    ) -> Result<(Vec<Vector3<f64>>, f64), ChannelError> {
        check_finite("sample point", points)?;
        let u_t = mean_flow_mm_s * 1e3;
        let u0 = u_t * self.geometry.cross_section_area() / self.q_interior_e;
        let f_w: Vec<Vector3<f64>> = self.f_e.iter().map(|f| f * u0).collect();
        let mut out = vec![Vector3::zeros(); points.len()];
        self.ewald.stokeslet(
            points,
            &self.eval_nodes.positions,
            &self.eval_nodes.forces(&f_w),
            &mut out,
        )?;
        let s = 1.0 / (8.0 * std::f64::consts::PI * self.mu);
        Ok((
            out.iter().map(|v| v * s + Vector3::x() * u0).collect(),
            u0 * self.b_e,
        ))
    }

    /// The velocity (um/s) at fluid points outside the cell for a solved cell state:
    /// `u(x) = U0 e_x + (SL_cell[f] + SL_wall[f_w])(x)/mu + (1 - lambda)/2 E[u](x)` (see
    /// [`super::double_layer`]), from the solution `sol` of [`Self::velocity_with_guess`] or
    /// [`Self::penalty_velocity`] for the same `cell` and `traction`. Smooth quadrature: accurate a
    /// few mesh edges away from the cell and the wall. Points inside the cell get no meaning.
    pub fn flow_at(
        &self,
        points: &[Vector3<f64>],
        cell: &Mesh,
        traction: &[Vector3<f64>],
        sol: &ChannelSolution,
    ) -> Result<Vec<Vector3<f64>>, ChannelError> {
        check_finite("sample point", points)?;
        let n = cell.vertices.len();
        for (what, got) in [
            ("traction", traction.len()),
            ("cell velocity", sol.cell_velocity.len()),
        ] {
            if got != n {
                return Err(ChannelError::LengthMismatch {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        let surface = Surface::new(cell)?;
        let sl = cell_single_layer(
            StokesletSum::Full(&self.ewald),
            &surface,
            traction,
            points,
            self.opts.duffy_nodes,
            self.opts.subtract_normal_singularity,
            None,
        )?;
        let w = self.wall_single_layer(points, &sol.wall_traction)?;
        let mut out: Vec<Vector3<f64>> = sl
            .at_extra
            .iter()
            .zip(&w)
            .map(|(c, w)| Vector3::x() * sol.stats.u0_um_s + (c + w) / self.mu)
            .collect();
        let lambda = sol.stats.viscosity_ratio;
        if !lambda.is_matched() {
            let dl = PeriodicDoubleLayer::new(&surface, cell.volume(), &self.ewald, points)?;
            let (_, e) = dl.apply(&sol.cell_velocity)?;
            let half = lambda.half_one_minus();
            out.iter_mut().zip(&e).for_each(|(o, e)| *o += e * half);
        }
        Ok(out)
    }

    /// Membrane velocity (um/s) of `cell` with the force density `traction` (Pa, what the
    /// membrane exerts on the fluid, as for [`crate::bim::FreeSpaceStokes::velocity`]) in the
    /// channel carrying the mean flow `mean_flow_mm_s` (flux / cross-section, mm/s).
    /// Exact no-slip walls; for [`WallMode::Penalty`] use [`Self::penalty_velocity`].
    pub fn velocity(
        &self,
        cell: &Mesh,
        traction: &[Vector3<f64>],
        mean_flow_mm_s: f64,
    ) -> Result<(Vec<Vector3<f64>>, ChannelStats), ChannelError> {
        let s = self.solve(Some((cell, traction)), mean_flow_mm_s, None, None, false)?;
        Ok((s.cell_velocity, s.stats))
    }

    /// As [`Self::velocity`], starting GMRES (lambda != 1) from `guess` (um/s at the cell
    /// vertices, e.g. the previous velocity); the wall traction and stats come with it.
    pub fn velocity_with_guess(
        &self,
        cell: &Mesh,
        traction: &[Vector3<f64>],
        mean_flow_mm_s: f64,
        guess: Option<&[Vector3<f64>]>,
    ) -> Result<ChannelSolution, ChannelError> {
        self.solve(Some((cell, traction)), mean_flow_mm_s, None, guess, false)
    }

    /// The no-slip solve at another viscosity ratio `lambda` (the factorised wall operator does
    /// not depend on it); `force_double_layer` takes the viscosity-contrast path (double layer,
    /// deflated GMRES) also at lambda = 1, where it must equal the single-layer path (a test of
    /// the general path).
    #[doc(hidden)]
    pub fn velocity_at_ratio(
        &self,
        cell: &Mesh,
        traction: &[Vector3<f64>],
        mean_flow_mm_s: f64,
        lambda: ViscosityContrast,
        force_double_layer: bool,
    ) -> Result<ChannelSolution, ChannelError> {
        self.solve_at(
            Some((cell, traction)),
            mean_flow_mm_s,
            None,
            None,
            force_double_layer,
            lambda,
            true,
        )
    }

    /// Penalty walls: velocities of the cell and of the wall vertices for the wall displacement
    /// `displacement_um` (from the rest positions, um); the wall traction is `-kappa_W d`.
    pub fn penalty_velocity(
        &self,
        cell: Option<(&Mesh, &[Vector3<f64>])>,
        displacement_um: &[Vector3<f64>],
        mean_flow_mm_s: f64,
    ) -> Result<ChannelSolution, ChannelError> {
        self.solve(cell, mean_flow_mm_s, Some(displacement_um), None, false)
    }

    /// As [`Self::penalty_velocity`], starting GMRES (lambda != 1) from `guess` (um/s at the
    /// cell vertices, e.g. the previous velocity).
    pub fn penalty_velocity_with_guess(
        &self,
        cell: Option<(&Mesh, &[Vector3<f64>])>,
        displacement_um: &[Vector3<f64>],
        mean_flow_mm_s: f64,
        guess: Option<&[Vector3<f64>]>,
    ) -> Result<ChannelSolution, ChannelError> {
        self.solve(cell, mean_flow_mm_s, Some(displacement_um), guess, false)
    }

    /// Largest relaxation rate (1/s) of the penalty walls, `kappa_W lambda_max(S) / mu` (power
    /// iteration on the dense `S`): explicit steps must stay below ~`2 / rate` (Euler) or
    /// ~`2.5 / rate` (Bogacki-Shampine 3(2)).
    pub fn penalty_rate(&self, kappa_w_n_per_m3: f64) -> f64 {
        let nv = self.mesh.n_vertices();
        let mut v: Vec<Vector3<f64>> = (0..nv)
            .map(|i| Vector3::new(1.0, (i as f64).sin(), (i as f64 * 0.7).cos()))
            .collect();
        let mut lam = 0.0;
        for _ in 0..200 {
            let w = self.wall.apply(&v);
            let norm = w.iter().map(|x| x.norm_squared()).sum::<f64>().sqrt();
            let vn = v.iter().map(|x| x.norm_squared()).sum::<f64>().sqrt();
            lam = norm / vn;
            v = w.iter().map(|x| x / norm).collect();
        }
        // kappa_W (N/m^3) = 1e-6 Pa/um; S (Pa um / Pa) / mu: um/s per Pa.
        kappa_w_n_per_m3 * 1e-6 * lam / self.mu
    }

    /// The Jacobian of the penalty walls' velocity with respect to their displacement at a fixed
    /// cell (1/s, `3 Nw x 3 Nw`, row and column `3 i + c`):
    ///
    /// ```text
    /// J_ww = -(kappa_W / mu) S + e_x (x) (K_E kappa_W / (V A_box)) a_x
    /// ```
    ///
    /// from `u_wall = U0 e_x + (S f_w + SL_cell|_wall) / mu + (1 - lambda)/2 E[u]|_wall` with
    /// `f_w = -kappa_W d` ([`Self::penalty_velocity`]): `S` the wall's dense single layer
    /// ([`super::wall::WallOperator`]), and the flux's answer to the walls' net force,
    /// `U0 = (u_t A + K_E b) / A_box` with `b = -(F_w + F_c)_x / V` and
    /// `F_w,x = -kappa_W sum_j A_j d_j,x` (`A_j` the wall vertex areas, `a_x` their row on the x
    /// components). Exact at `lambda = 1`; otherwise the double layer's answer (through the
    /// cell velocity, which the wall traction moves) is left out. Its largest rate is
    /// [`Self::penalty_rate`]; the time integration's stiff part ([`crate::dynamics::penalty`]).
    pub fn penalty_wall_jacobian(&self, kappa_w_n_per_m3: f64) -> Mat<f64> {
        // kappa_W (N/m^3) = 1e-6 Pa/um; S (Pa um per Pa) / mu: um/s per Pa
        let k = kappa_w_n_per_m3 * 1e-6;
        let s = &self.wall.matrix;
        let volume = self.box_volume();
        let a_box = self.box_len[1] * self.box_len[2];
        let flux = self.k_exterior * k / (volume * a_box);
        let areas = &self.mesh.vertex_areas;
        Mat::from_fn(s.nrows(), s.ncols(), |r, c| {
            let rank_one = if r % 3 == 0 && c % 3 == 0 { flux * areas[c / 3] } else { 0.0 };
            -k / self.mu * s[(r, c)] + rank_one
        })
    }

    /// No-slip wall traction and `U0` for the velocity sources `v` at the wall vertices
    /// (Pa um, i.e. `mu` times a velocity: the cell's single layer, or its double layer times
    /// `mu (1 - lambda)/2`), the cell's net x-force (pN) and the target mean velocity `u_t`
    /// (um/s): `S f_r = -v`, `b_r = -(F_r,x + F_c,x)/V`, `U0 = (u_t A_channel + K_E b_r) / Q_I`,
    /// `f_w = f_r + U0 f_e` (module docs). Linear in `(v, F_c,x, u_t)`.
    fn no_slip_response(
        &self,
        v: &[Vector3<f64>],
        cell_force_x: f64,
        u_t: f64,
    ) -> (Vec<Vector3<f64>>, f64) {
        let volume = self.box_volume();
        let f_r: Vec<Vector3<f64>> = self.wall.solve(v).iter().map(|v| -v).collect();
        let b_r = -(wall_force(&self.mesh, &f_r).x + cell_force_x) / volume;
        let u0 =
            (u_t * self.geometry.cross_section_area() + self.k_exterior * b_r) / self.q_interior_e;
        (
            f_r.iter()
                .zip(&self.f_e)
                .map(|(r, e)| r + e * u0)
                .collect::<Vec<_>>(),
            u0,
        )
    }

    /// The wall single layer `1/(8 pi) Int_W G_per f_w dS` at `targets` (Pa um).
    fn wall_single_layer(
        &self,
        targets: &[Vector3<f64>],
        f_w: &[Vector3<f64>],
    ) -> Result<Vec<Vector3<f64>>, ChannelError> {
        let scale = 1.0 / (8.0 * std::f64::consts::PI);
        let wall_forces = self.eval_nodes.forces(f_w);
        let mut out = vec![Vector3::zeros(); targets.len()];
        // real space from the node forces, Fourier space from the precomputed spreading
        self.ewald
            .stokeslet_real(targets, &self.eval_nodes.positions, &wall_forces, &mut out);
        self.ewald
            .stokeslet_fourier_basis_add(&self.wall_spread, f_w, targets, &mut out)?;
        out.iter_mut().for_each(|v| *v *= scale);
        Ok(out)
    }

    /// [`Self::wall_single_layer`] at the cell vertices with the sums of GMRES: the real-space part
    /// from the blocks built for this cell (`blocks`), the Fourier part from the precomputed spreading.
    fn wall_single_layer_fast(
        &self,
        ewald: &PeriodicStokes,
        spread: &BasisSpread,
        blocks: &BlockRows,
        targets: &[Vector3<f64>],
        f_w: &[Vector3<f64>],
    ) -> Result<Vec<Vector3<f64>>, ChannelError> {
        let scale = 1.0 / (8.0 * std::f64::consts::PI);
        let mut out = vec![Vector3::zeros(); targets.len()];
        blocks.apply(f_w, &mut out);
        ewald.stokeslet_fourier_basis_add(spread, f_w, targets, &mut out)?;
        out.iter_mut().for_each(|v| *v *= scale);
        Ok(out)
    }

    /// Whether the sums inside GMRES use the frozen real-space blocks ([`ChannelOptions::iteration_sums`]).
    pub fn fast_iterations(&self) -> bool {
        self.iteration.is_some()
    }

    fn gmres_options(&self) -> GmresOptions {
        GmresOptions {
            tolerance: Tolerance::Relative(self.opts.gmres_tolerance),
            restart: self.opts.gmres_restart,
            max_iterations: self.opts.gmres_max_iterations,
        }
    }

    /// The solve: `double_layer` forces the viscosity-contrast path (also at lambda = 1, for
    /// tests); otherwise it is taken for lambda != 1 only.
    fn solve(
        &self,
        cell: Option<(&Mesh, &[Vector3<f64>])>,
        mean_flow_mm_s: f64,
        penalty: Option<&[Vector3<f64>]>,
        guess: Option<&[Vector3<f64>]>,
        double_layer: bool,
    ) -> Result<ChannelSolution, ChannelError> {
        self.solve_at(
            cell,
            mean_flow_mm_s,
            penalty,
            guess,
            double_layer,
            self.lambda,
            true,
        )
    }
}

/// `Int_W f dS = sum_i A_i f_i` (Pa um^2 = pN) for the linear interpolation of the nodal `f`.
fn wall_force(mesh: &ChannelMesh, f: &[Vector3<f64>]) -> Vector3<f64> {
    f.iter().zip(&mesh.vertex_areas).map(|(f, a)| f * *a).sum()
}

/// Volume-centroid velocity (um/s) of a closed cell with membrane velocity `u`:
/// `dX/dt = [Int x (u . n) dS - X Int u . n dS] / V` (divergence theorem), from flat triangles
/// with `u` linear (7-point rule).
pub fn centroid_velocity(cell: &Mesh, u: &[Vector3<f64>]) -> Vector3<f64> {
    let rule = crate::bim::quadrature::gauss7();
    let (vol, x_c) = (cell.volume(), cell.centroid());
    let mut acc = Vector3::zeros();
    for tri in &cell.triangles {
        let [a, b, c] = tri.map(|i| cell.vertices[i]);
        let n2 = (b - a).cross(&(c - a)); // 2 A n
        for node in &rule {
            let [l0, l1, l2] = node.bary;
            let y = a * l0 + b * l1 + c * l2;
            let uy = u[tri[0]] * l0 + u[tri[1]] * l1 + u[tri[2]] * l2;
            acc += (y - x_c) * (uy.dot(&n2) * 0.5 * node.weight);
        }
    }
    acc / vol
}

/// The runner's interface: `with_background` adds the mean flow [`ChannelStokes::mean_flow_mm_s`]
/// (set by [`ChannelStokes::with_mean_flow`]); without it the channel carries no net flux
/// (the solve is linear: `u(f, U) = u(f, 0) + u(0, U)`). No-slip walls only: penalty walls carry a
/// state (the wall displacement) that this interface has no place for. For lambda != 1 `guess`
/// (the last velocity) warm-starts GMRES, and the double-layer sum that only the wall traction
/// needs after GMRES is skipped (one of ~6 per evaluation mid-run; the velocity is the same bit
/// for bit, test `channel_fast`).
impl crate::bim::Stokes for ChannelStokes {
    fn velocity(
        &self,
        mesh: &Mesh,
        f: &[Vector3<f64>],
        with_background: bool,
        guess: Option<&[Vector3<f64>]>,
    ) -> Result<Vec<Vector3<f64>>, crate::SolverError> {
        if self.wall_mode != WallMode::NoSlip {
            return Err(ChannelError::InvalidParameter {
                name: "wall_mode",
                value: 0.0,
                reason: "the Stokes trait needs WallMode::NoSlip",
            }
            .into());
        }
        let mean = if with_background {
            self.mean_flow_mm_s
        } else {
            0.0
        };
        let extrapolate = self.opts.extrapolate_guess && with_background && !self.lambda.is_matched();
        let extrapolated = match (extrapolate, guess) {
            (true, Some(g)) => self.extrapolated_guess(&mesh.vertices, g),
            _ => None,
        };
        // the cell velocity alone: no double-layer sum for the wall traction after GMRES
        let solution = self.solve_at(Some((mesh, f)), mean, None, extrapolated.as_deref().or(guess), false, self.lambda, false)?;
        self.times.lock().unwrap_or_else(|e| e.into_inner()).add(&solution.stats);
        let u = solution.cell_velocity;
        if extrapolate {
            let mut h = self.history.lock().unwrap_or_else(|e| e.into_inner());
            if h.len() == secant_guess::HISTORY {
                h.remove(0);
            }
            h.push((mesh.vertices.clone(), u.clone()));
        }
        Ok(u)
    }
    /// The local self-mobility of the stiff-mode preconditioner only needs the viscosities:
    /// at the mesh scale the walls are far away.
    fn viscosities(&self) -> Option<(f64, ViscosityContrast)> {
        Some((self.mu, self.lambda))
    }

    /// The path of the last solves ([`ChannelOptions::extrapolate_guess`]) as
    /// `{prefix}path_{k}_vertices_um` and `{prefix}path_{k}_velocity_um_s`, k = 0, 1, ... (oldest first).
    fn save_state(&self, prefix: &str, out: &mut crate::state::StateMap) {
        let h = self.history.lock().unwrap_or_else(|e| e.into_inner());
        for (k, (x, u)) in h.iter().enumerate() {
            out.insert(format!("{prefix}path_{k}_vertices_um"), crate::state::flatten(x));
            out.insert(format!("{prefix}path_{k}_velocity_um_s"), crate::state::flatten(u));
        }
    }

    fn restore_state(&self, prefix: &str, state: &crate::state::StateMap) -> Result<(), crate::SolverError> {
        let mut h = self.history.lock().unwrap_or_else(|e| e.into_inner());
        h.clear();
        for k in 0..secant_guess::HISTORY {
            let (kx, ku) = (format!("{prefix}path_{k}_vertices_um"), format!("{prefix}path_{k}_velocity_um_s"));
            let (Some(x), Some(u)) = (crate::state::state_vectors(state, &kx)?, crate::state::state_vectors(state, &ku)?) else {
                break;
            };
            h.push((x, u));
        }
        Ok(())
    }
}

impl ChannelStokes {
    /// The velocity predicted at `x` from the path of the last solves ([`secant_guess::predict`]),
    /// if `guess` is the last of them (the time integration's last velocity) and the shapes match.
    fn extrapolated_guess(
        &self,
        x: &[Vector3<f64>],
        guess: &[Vector3<f64>],
    ) -> Option<Vec<Vector3<f64>>> {
        let h = self.history.lock().unwrap_or_else(|e| e.into_inner());
        match h.last() {
            Some((_, last)) if last.as_slice() == guess => secant_guess::predict(&h, x),
            _ => None,
        }
    }
}

/// The cell's mean velocity along the channel (mm/s): the x component of [`centroid_velocity`]
/// (um/s) / 1000, the quantity the paper reports as `u`.
pub fn cell_mean_velocity_mm_s(cell: &Mesh, u: &[Vector3<f64>]) -> f64 {
    centroid_velocity(cell, u).x * 1e-3
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rigid motion `u = U + omega x (x - c)`: the volume centroid moves with `U + omega x (X - c)`
    /// exactly (the divergence-theorem formula is exact for linear fields on flat triangles).
    #[test]
    fn centroid_velocity_of_rigid_motion() {
        let mut cell = crate::mesh::discocyte(2);
        cell.vertices
            .iter_mut()
            .for_each(|v| *v += Vector3::new(3.0, -1.0, 0.5));
        let (u0, om, c) = (
            Vector3::new(1.0, -2.0, 0.5),
            Vector3::new(0.3, 0.1, -0.7),
            Vector3::new(0.2, 0.4, -1.0),
        );
        let u: Vec<Vector3<f64>> = cell
            .vertices
            .iter()
            .map(|x| u0 + om.cross(&(x - c)))
            .collect();
        let v = centroid_velocity(&cell, &u);
        let expected = u0 + om.cross(&(cell.centroid() - c));
        assert!(
            (v - expected).norm() < 1e-12 * expected.norm(),
            "{v} vs {expected}"
        );
        assert!((cell_mean_velocity_mm_s(&cell, &u) - expected.x * 1e-3).abs() < 1e-15);
    }
}
