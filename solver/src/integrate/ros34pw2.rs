//! Rosenbrock-W methods: ROS34PW2 (four stages, third order for any Jacobian approximation, embedded second-order estimate), other W-tableaux of order 3, and RosW6S4 (six stages, order 4).
//!
//! Rang & Angermann, "New Rosenbrock W-methods of order 3 for partial
//! differential algebraic equations of index 1", BIT Numer. Math. 45, 761 (2005),
//! method ROS34PW2 (stiffly accurate, L-stable with the exact Jacobian), the default; the
//! same stepper runs the other tableaux of [`Method`] (ROS3Pw and ROS34PW3 of the same paper,
//! ROS34PRw of Rang, J. Comput. Appl. Math. 286, 128 (2015)) through [`Ros34pw2::with_method`],
//! all W-methods of order 3 with an embedded solution of order 2, and RosW6S4 (Rahunanthan &
//! Stanescu 2010), a W-method of order 4 with six stages and an embedded solution of order 3
//! ([`Method::Rosw6s4`]; with penalty walls it is cheaper and closer to the paper's integrator
//! than ROS34PW2, `solver/README.md` "Session 34"). In the
//! form of Hairer & Wanner (Solving ODEs II, sec. IV.7), with `k_i` increments (um):
//! ```text
//! (I - gamma h J) k_i = h f(y + sum_{j<i} alpha_ij k_j) + h J sum_{j<i} gamma_ij k_j
//! y1 = y + sum b_i k_i            (order 3 for any J: a W-method)
//! y1^ = y + sum b^_i k_i          (order 2, embedded)
//! ```
//! with `gamma = 0.43586652150845900` and the `alpha`, `gamma_ij`, `b`, `b^` of
//! [`ALPHA`], [`GAMMA`], [`B`], [`B_HAT`] (the paper's table, 17 digits as in
//! PETSc's `TSROSWRA34PW2`). The code uses the equivalent transformed form that
//! needs no Jacobian product on the right-hand side (Hairer & Wanner eq. (7.25)):
//! with `u = Gamma k` (`Gamma` the lower triangle of `gamma_ij`, `gamma` on its diagonal),
//! ```text
//! (I - gamma h J) u_i = gamma h f(y + sum_{j<i} (alpha Gamma^-1)_ij u_j) - gamma sum_{j<i} (Gamma^-1)_ij u_j
//! y1 = y + sum (b Gamma^-1)_i u_i,     err = y1 - y1^ = sum ((b - b^) Gamma^-1)_i u_i
//! ```
//! No `h gamma_i df/dt` term: the stages are evaluated at `t + alpha_i h`, which is
//! the method applied to the autonomised system `(y, t)' = (f, 1)` with a `J` that
//! omits the column `df/dt`; as a W-method it keeps order 3 with that `J` too
//! (`tests/integrate_ros34.rs` checks it on the non-autonomous Prothero-Robinson problem).
//!
//! The stage matrix `W = I - gamma h J` is the same for all stages. `J` is
//! either the lagged-mobility Jacobian of [`super::Linearised::jacobian_apply`]
//! (every product a Stokes solve; the systems solved by GMRES, right-preconditioned
//! with the local sparse `W_loc = I - gamma h J_loc` of [`super::precondition`]),
//! or `J_loc` itself ([`StageJacobian::Local`]: each stage one sparse triangular
//! solve, no Stokes solve beyond the stages' velocity evaluations). A stage solve
//! that misses its tolerance, or a singular `W_loc`, rejects the step (error `+inf`), so the
//! controller retries with a smaller step; failure detection (NaN, inverted
//! triangles, area change, step collapse) and the volume-drift correction are
//! those of [`crate::run::Runner`], as for every scheme.

use crate::gmres::{gmres_preconditioned, GmresOptions, Tolerance};
use super::mobility_jacobian::DenseStage;
use super::wall_block::WallCoupling;
use super::precondition::StageMatrix;
use super::{flatten, Integrator, Linearised, StateMap, StepContext, StepWork};
use crate::error::SolverError;
use nalgebra::Vector3;
pub use super::w_tableaux::{Method, Tableau, Transformed, ALPHA, B, B_HAT, GAMMA, GAMMA_DIAG, MAX_STAGES};

/// Which `J` the stage matrix `I - gamma h J` uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StageJacobian {
    /// The lagged-mobility Jacobian of [`Linearised::jacobian_apply`], solved by GMRES
    /// (preconditioned with the local Jacobian when the dynamics provides one and `precondition` is set).
    Lagged,
    /// The local sparse Jacobian of [`Linearised::local_jacobian`] only, solved directly.
    Local,
    /// The dense mobility Jacobian of [`Linearised::mobility_jacobian`] (every vertex pair's
    /// free-space two-fluid mobility times the stiffness), factorised densely and kept for
    /// several steps ([`Ros34pw2::reuse`]).
    Mobility,
}

/// When [`StageJacobian::Mobility`] keeps its factorised `W = I - g_0 J_mob` for a step of
/// `gamma h`: a W-method with `J' = g_0/(s gamma h) s J_mob` (its W-order for any `J`); stability needs
/// `J'` to stay above ~0.7 of the true `J` on the stiff modes, accuracy that it stays close.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reuse {
    /// Keep the factor while `h / h_0` lies in `[min_ratio, max_ratio]` ...
    pub min_ratio: f64,
    pub max_ratio: f64,
    /// ... and for at most this many accepted steps (the shape, hence `J`, moves on).
    pub max_age: usize,
    /// ... or for at most `quiet_max_age` accepted steps while the cell is quiet: its own error
    /// norm at the last accepted step, the largest vertex error of the cell (not of the penalty
    /// walls' displacements after it) over the tolerance `atol_um`, at most `quiet_cell_error`.
    pub quiet_cell_error: f64,
    pub quiet_max_age: usize,
}

impl Reuse {
    /// With penalty walls: the walls set every step (their traction pattern travels with the
    /// cell past the wall vertices, `solver/README.md` "Session 25"), at 0.3-0.4 of the step the
    /// cell's error alone would allow, and a factor refactorised every step is ~15 % of a step's
    /// cost. On a settled croissant the cell's error norm stays at 0.03-0.10 and a factor kept
    /// over 3 steps cost 0.86 of the core-s at equal deviations from bs23 (u3.8 and u1.5); on a
    /// tank-treading slipper (0.11-0.16) it cost 0.95 but with 4x the rejections and dy 1.14x
    /// farther from bs23, so the cell's error decides (`solver/README.md`, "Session 33"). The
    /// threshold 0.1 sits just above the largest value measured on a settled croissant (0.099 at
    /// u1.5) and below the smallest on the slipper (0.109): a busier croissant falls back to a
    /// factor a step, which costs time, not accuracy.
    pub const PENALTY_WALLS: Reuse = Reuse { min_ratio: 0.5, max_ratio: 1.3, max_age: 1, quiet_cell_error: 0.1, quiet_max_age: 3 };
}

impl Default for Reuse {
    /// A factor serves the step it was built for and its retries only (`max_age` 1): material
    /// flows through the rear rim's fold within a few steps, and a factor kept over several
    /// accepted steps left a mode there unstable (measured mid-run at atol 1e-2 um: steps in a
    /// 250 -> 480 us limit cycle with 13 rejections in 54 attempts and an error growing 3x per
    /// step at constant `h`; rebuilt every step, 26 + 2 steps of 470-540 us and 0.63 of the
    /// core-s, `solver/README.md`).
    fn default() -> Self {
        Self { min_ratio: 0.5, max_ratio: 1.3, max_age: 1, quiet_cell_error: 0.0, quiet_max_age: 1 }
    }
}

/// The dense stage factor and where it was built (kept in checkpoints as its linearisation
/// point, `g` and age, so that a resumed run refactorises the same matrix).
#[derive(Debug)]
struct DenseFactor {
    stage: DenseStage,
    x: Vec<Vector3<f64>>,
    t: f64,
    age: usize,
}

/// Counters of the stage solves.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageStats {
    /// Linear stage solves.
    pub solves: usize,
    /// GMRES iterations (Jacobian applications) over all stage solves.
    pub iterations: usize,
    /// Sparse LU factorisations of `I - gamma h J_loc`.
    pub factorisations: usize,
    /// Stage solves that missed their tolerance (or singular `W_loc`): rejected steps.
    pub failed: usize,
}

/// ROS34PW2 stepper; owns its stage buffers.
#[derive(Debug)]
pub struct Ros34pw2 {
    pub jacobian: StageJacobian,
    /// Right-precondition the GMRES stage solves with `I - gamma h J_loc` (Lagged only).
    pub precondition: bool,
    /// Krylov dimension before restart, maximal Jacobian applications per stage solve.
    pub restart: usize,
    pub max_iterations: usize,
    /// The stage residual (um, 2-norm) is driven below this fraction of the absolute tolerance (default 0.05, as ROS2).
    pub linear_tol_fraction: f64,
    /// The local Jacobian enters the stage matrix as `local_scale J_loc`. Preconditioner:
    /// 0.5 (the disc self-mobility over-estimates the lambda = 5 mobility of the mid-wavelength
    /// modes that dominate the iterations; measured 43 -> 14 iterations at 0.5, 29 at 1, 300 at 4 on
    /// the stiff 512-triangle cell, `tests/integrate_precondition.rs`). Local W-method: 2, a
    /// stability margin (the W-method is stable on modes where `local_scale J_loc >= 0.7 J`).
    pub local_scale: f64,
    /// Reuse of the dense factor ([`StageJacobian::Mobility`]).
    pub reuse: Reuse,
    /// Step across output times and let the runner interpolate the samples (default): the
    /// velocity at the end of a step is the first stage of the next, so the cubic Hermite
    /// interpolant costs no evaluation ([`Integrator::end_velocity`]).
    pub dense_output: bool,
    pub stats: StageStats,
    /// The walls' answer to the cell in the stage matrix ([`StageJacobian::Mobility`] with
    /// penalty walls; [`WallCoupling`], `integrator.wall_coupling`); `None`: `J` block diagonal.
    pub wall_coupling: Option<WallCoupling>,
    /// The tableau ([`Ros34pw2::with_method`]).
    method: Method,
    tab: Transformed,
    f0: Vec<Vector3<f64>>,
    u: [Vec<Vector3<f64>>; MAX_STAGES],
    y: Vec<Vector3<f64>>,
    rhs: Vec<Vector3<f64>>,
    /// `f0` and the linearisation are valid for the state at this time.
    valid_at: Option<f64>,
    /// Factorised local stage matrix for the current linearisation.
    stage: Option<StageMatrix>,
    /// Factorised dense stage matrix ([`StageJacobian::Mobility`]) and a factor to rebuild after a restore.
    dense: Option<DenseFactor>,
    /// Buffers of an invalidated dense factor, reused by the next factorisation.
    spare: Option<DenseStage>,
    restored: Option<(Vec<Vector3<f64>>, f64, f64, usize)>,
    /// `f0` was restored from a checkpoint for this time (the state is not yet linearised).
    restored_f0: Option<f64>,
    /// Time of the last attempt (a second attempt at the same time follows a rejection).
    last_attempt_t: Option<f64>,
    /// The cell's error norm of the last attempt and of the last accepted step ([`Reuse`]).
    attempt_cell_error: Option<f64>,
    cell_error: Option<f64>,
}

impl Ros34pw2 {
    /// Lagged-mobility Jacobian, preconditioned stage solves.
    pub fn new() -> Self {
        Self::with(StageJacobian::Lagged, true)
    }

    /// Choose the Jacobian and whether GMRES is preconditioned.
    pub fn with(jacobian: StageJacobian, precondition: bool) -> Self {
        Self {
            jacobian,
            precondition,
            restart: 30,
            max_iterations: 200,
            linear_tol_fraction: 0.05,
            local_scale: match jacobian {
                StageJacobian::Local => 2.0,
                StageJacobian::Mobility => 1.5,
                StageJacobian::Lagged => 0.5,
            },
            reuse: Reuse::default(),
            dense_output: true,
            stats: StageStats::default(),
            wall_coupling: None,
            method: Method::Ros34pw2,
            tab: Transformed::ros34pw2(),
            f0: Vec::new(),
            u: Default::default(),
            y: Vec::new(),
            rhs: Vec::new(),
            valid_at: None,
            stage: None,
            dense: None,
            spare: None,
            restored: None,
            restored_f0: None,
            last_attempt_t: None,
            attempt_cell_error: None,
            cell_error: None,
        }
    }

    /// The same stepper with another tableau (default ROS34PW2).
    pub fn with_method(mut self, method: Method) -> Self {
        self.method = method;
        self.tab = Transformed::of(&method.tableau());
        self
    }

    /// The tableau in use.
    pub fn method(&self) -> Method {
        self.method
    }

    /// Buffers sized for `n` vertices, `f0 = f(t, x)` and the linearisation at `(t, x)` (kept
    /// until the next accepted step); returns the velocity evaluations it took (0 or 1).
    fn prepare<D: Linearised + ?Sized>(&mut self, f: &mut D, t: f64, x: &[Vector3<f64>]) -> Result<usize, SolverError> {
        let n = x.len();
        if self.f0.len() != n {
            self.f0.resize(n, Vector3::zeros());
            self.valid_at = None;
            self.restored_f0 = None;
        }
        for v in [&mut self.y, &mut self.rhs] {
            v.resize(n, Vector3::zeros());
        }
        for v in &mut self.u {
            v.resize(n, Vector3::zeros());
        }
        if self.jacobian == StageJacobian::Mobility {
            self.rebuild_restored(f, n)?;
        }
        if self.valid_at == Some(t) {
            return Ok(0);
        }
        let evals = if self.restored_f0 == Some(t) {
            0
        } else {
            f.velocity(t, x, &mut self.f0)?;
            1
        };
        self.restored_f0 = None;
        f.linearise(t, x)?;
        self.valid_at = Some(t);
        self.stage = None;
        Ok(evals)
    }

    /// Make sure a dense factor usable for `g = local_scale gamma h` exists (reusing the kept one
    /// under [`Reuse`], refactorising at the current linearisation point otherwise); `false` when
    /// `I - g J_mob` is singular (the step is then rejected).
    /// The walls' part (penalty walls) is factorised at `g_wall`, the step's own `gamma h`, also
    /// when the cell's factor is kept ([`super::wall_block`]).
    fn dense_stage<D: Linearised + ?Sized>(&mut self, f: &mut D, t: f64, x: &[Vector3<f64>], g: f64, g_wall: f64, retry: bool) -> Result<bool, SolverError> {
        if let Some(d) = &mut self.dense {
            let ratio = g / d.stage.g;
            let fresh = d.t == t;
            let quiet = self.cell_error.is_some_and(|e| e <= self.reuse.quiet_cell_error);
            let max_age = if quiet { self.reuse.quiet_max_age.max(self.reuse.max_age) } else { self.reuse.max_age };
            let in_band = ratio >= self.reuse.min_ratio && ratio <= self.reuse.max_ratio && d.age < max_age;
            // after a rejection, an old factor is rebuilt at the current state
            if in_band && (fresh || !retry) {
                d.stage.set_wall_g(g_wall);
                return Ok(true);
            }
        }
        let mut stage = self.take_dense_buffers();
        let Some(j) = f.mobility_jacobian()? else {
            return Err(SolverError::Unsupported {
                field: "integrator.scheme".into(),
                message: "the mobility-Jacobian W-method needs a membrane with an assembled stiffness (Skalak or tension) and a Stokes operator with known viscosities".into(),
            });
        };
        match stage.factorise_with_wall_g(&j, g, g_wall) {
            Ok(()) => {
                self.stats.factorisations += 1;
                self.dense = Some(DenseFactor { stage, x: x.to_vec(), t, age: 0 });
                Ok(true)
            }
            Err(_) => {
                self.spare = Some(stage);
                Ok(false)
            }
        }
    }

    /// The buffers of the current dense factor (invalidated) or of a spare one, to refactorise
    /// into without allocating (76 MB each at 2048 triangles).
    fn take_dense_buffers(&mut self) -> DenseStage {
        match self.dense.take() {
            Some(d) => d.stage,
            None => self.spare.take().unwrap_or_else(DenseStage::empty),
        }
    }

    /// Rebuild the dense factor saved in a checkpoint: linearise at its point, factorise with its `g`.
    fn rebuild_restored<D: Linearised + ?Sized>(&mut self, f: &mut D, n: usize) -> Result<(), SolverError> {
        let Some((x, t, g, age)) = self.restored.take() else { return Ok(()) };
        if x.len() != n {
            return Err(SolverError::Output(format!("checkpoint field dense_x: {} vertices, the state has {n}", x.len())));
        }
        f.linearise(t, &x)?;
        self.valid_at = None;
        let Some(j) = f.mobility_jacobian()? else { return Ok(()) };
        let mut stage = self.take_dense_buffers();
        if stage.factorise(&j, g).is_ok() {
            self.stats.factorisations += 1;
            self.dense = Some(DenseFactor { stage, x, t, age });
        } else {
            self.spare = Some(stage);
        }
        Ok(())
    }
}

impl Default for Ros34pw2 {
    fn default() -> Self {
        Self::new()
    }
}

/// Build (or reuse) the factorised `I - gamma h J_loc` for `gh`; `None` when the dynamics has no local Jacobian.
fn stage_matrix<D: Linearised + ?Sized>(f: &mut D, stage: &mut Option<StageMatrix>, gh: f64, stats: &mut StageStats) -> Result<bool, SolverError> {
    // (gh already carries local_scale: I - (s gamma h) J_loc)
    if stage.as_ref().is_some_and(|s| s.gamma_h == gh) {
        return Ok(true);
    }
    *stage = None;
    let Some(j) = f.local_jacobian()? else { return Ok(false) };
    match j.stage_matrix(gh) {
        Ok(s) => {
            stats.factorisations += 1;
            *stage = Some(s);
            Ok(true)
        }
        // a singular W_loc (a geometric-stiffness mode with gamma h lambda = 1): reject the step
        Err(_) => Ok(false),
    }
}

impl<D: Linearised + ?Sized> Integrator<D> for Ros34pw2 {
    fn name(&self) -> &'static str {
        // [tableau][ros34pw2-local, -mobility, (lagged, preconditioned), -plain]
        const NAMES: [[&str; 4]; 5] = [
            ["ros34pw2-local", "ros34pw2-mobility", "ros34pw2", "ros34pw2-plain"],
            ["ros3pw-local", "ros3pw-mobility", "ros3pw", "ros3pw-plain"],
            ["ros34pw3-local", "ros34pw3-mobility", "ros34pw3", "ros34pw3-plain"],
            ["ros34prw-local", "ros34prw-mobility", "ros34prw", "ros34prw-plain"],
            ["rosw6s4-local", "rosw6s4-mobility", "rosw6s4", "rosw6s4-plain"],
        ];
        let row = Method::ALL.iter().position(|m| *m == self.method).expect("every method is listed");
        let col = match (self.jacobian, self.precondition) {
            (StageJacobian::Local, _) => 0,
            (StageJacobian::Mobility, _) => 1,
            (StageJacobian::Lagged, true) => 2,
            (StageJacobian::Lagged, false) => 3,
        };
        NAMES[row][col]
    }

    fn embedded_order(&self) -> u32 {
        // the classical order of the embedded solution (the step controller's exponent); ROS34PRw's
        // W-order-1 embedded one is still run as order 2 (session 25's measurements)
        self.method.embedded_order()
    }

    fn attempt(
        &mut self,
        f: &mut D,
        t: f64,
        x: &[Vector3<f64>],
        h: f64,
        ctx: StepContext,
        x_new: &mut [Vector3<f64>],
        err: &mut [Vector3<f64>],
    ) -> Result<StepWork, SolverError> {
        let n = x.len();
        let mut work = StepWork::default();
        let retry = self.last_attempt_t == Some(t);
        self.last_attempt_t = Some(t);
        // (set at the end of an attempt that ran its stages: an early return leaves none)
        self.attempt_cell_error = None;
        work.velocity_evals += self.prepare(f, t, x)?;
        let gh = self.tab.gamma * h;
        if self.jacobian == StageJacobian::Mobility && !self.dense_stage(f, t, x, self.local_scale * gh, gh, retry)? {
            self.stats.failed += 1;
            err.iter_mut().for_each(|e| *e = Vector3::repeat(f64::INFINITY));
            x_new.copy_from_slice(x);
            return Ok(work);
        }
        let want_local = self.jacobian == StageJacobian::Local || (self.jacobian == StageJacobian::Lagged && self.precondition);
        let have_local = want_local && stage_matrix(f, &mut self.stage, self.local_scale * gh, &mut self.stats)?;
        if self.jacobian == StageJacobian::Local && !have_local {
            if f.local_jacobian()?.is_none() {
                return Err(SolverError::Unsupported {
                    field: "integrator.scheme".into(),
                    message: "the local-Jacobian W-method needs a membrane with an assembled stiffness (Skalak or tension) and a Stokes operator with known viscosities".into(),
                });
            }
            self.stats.failed += 1;
            err.iter_mut().for_each(|e| *e = Vector3::repeat(f64::INFINITY));
            x_new.copy_from_slice(x);
            return Ok(work);
        }
        let opts = GmresOptions { restart: self.restart, max_iterations: self.max_iterations, tolerance: Tolerance::Absolute(self.linear_tol_fraction * ctx.atol_um) };
        let tab = self.tab;
        let mut converged = true;
        for i in 0..tab.stages {
            // stage value and its velocity
            let fi: &[Vector3<f64>] = if i == 0 {
                &self.f0
            } else {
                for (p, (yi, xi)) in self.y.iter_mut().zip(x).enumerate() {
                    let mut s = *xi;
                    for j in 0..i {
                        s += tab.a[(i, j)] * self.u[j][p];
                    }
                    *yi = s;
                }
                f.velocity(t + tab.c[i] * h, &self.y, &mut self.rhs)?;
                work.velocity_evals += 1;
                &self.rhs
            };
            // right-hand side gamma h f_i - gamma sum_j (Gamma^-1)_ij u_j, written into y (free now)
            for (p, (yp, fp)) in self.y.iter_mut().zip(fi).enumerate() {
                let mut s = gh * fp;
                for j in 0..i {
                    s -= tab.gamma * tab.gamma_inv[(i, j)] * self.u[j][p];
                }
                *yp = s;
            }
            let (done, rest) = self.u.split_at_mut(i);
            let _ = done;
            let ui = &mut rest[0];
            ui.copy_from_slice(&self.y);
            self.stats.solves += 1;
            match (self.jacobian, self.stage.as_ref().filter(|_| have_local)) {
                (StageJacobian::Mobility, _) => {
                    let stage = &self.dense.as_ref().expect("factorised above").stage;
                    match self.wall_coupling.as_mut().filter(|_| stage.wall_vertices() > 0) {
                        None => stage.solve_in_place(ui),
                        Some(coupling) => {
                            // block lower triangular: the cell first, then the walls with gamma h J_wc u_c
                            let nc = stage.cell_vertices();
                            stage.solve_cell_in_place(&mut ui[..nc]);
                            work.velocity_evals += coupling.add(f, t, x, &self.f0, ui, nc, gh)?;
                            stage.solve_wall_in_place(&mut ui[nc..]);
                        }
                    }
                }
                (StageJacobian::Local, Some(s)) => s.solve_in_place(ui),
                (StageJacobian::Local, None) => unreachable!("checked above"),
                (StageJacobian::Lagged, pre) => {
                    // initial guess: W_loc^-1 r when preconditioned, else r (exact for non-stiff components as h -> 0)
                    if let Some(s) = pre {
                        s.solve_in_place(ui);
                    }
                    let mut applies = 0usize;
                    let rep = gmres_preconditioned::<_, _, SolverError>(
                        |v, out| {
                            f.jacobian_apply(v, out)?;
                            applies += 1;
                            for (o, vi) in out.iter_mut().zip(v) {
                                *o = vi - gh * *o;
                            }
                            Ok(())
                        },
                        |v| {
                            if let Some(s) = pre {
                                s.solve_in_place(v)
                            }
                        },
                        &self.y,
                        ui,
                        &opts,
                    )?;
                    work.jacobian_applies += applies;
                    self.stats.iterations += rep.iterations;
                    converged &= rep.converged();
                }
            }
        }
        for p in 0..n {
            let (mut s, mut e) = (x[p], Vector3::zeros());
            for j in 0..tab.stages {
                s += tab.m[j] * self.u[j][p];
                e += tab.e[j] * self.u[j][p];
            }
            x_new[p] = s;
            err[p] = e;
        }
        if !converged {
            self.stats.failed += 1;
            err.iter_mut().for_each(|e| *e = Vector3::repeat(f64::INFINITY));
        }
        if self.reuse.quiet_max_age > self.reuse.max_age {
            if let Some(d) = self.dense.as_ref().filter(|_| self.jacobian == StageJacobian::Mobility) {
                let cell = d.stage.cell_vertices();
                self.attempt_cell_error = Some(err[..cell].iter().map(|e| e.norm()).fold(0.0, f64::max) / ctx.atol_um);
            }
        }
        Ok(work)
    }

    fn accepted(&mut self) {
        self.valid_at = None;
        self.last_attempt_t = None;
        self.cell_error = self.attempt_cell_error.take();
        if let Some(d) = &mut self.dense {
            d.age += 1;
        }
    }

    fn dense_output(&self) -> bool {
        self.dense_output
    }

    fn end_velocity(&mut self, f: &mut D, t: f64, x: &[Vector3<f64>]) -> Result<Option<(Vec<Vector3<f64>>, usize)>, SolverError> {
        if !self.dense_output {
            return Ok(None);
        }
        let evals = self.prepare(f, t, x)?;
        Ok(Some((self.f0.clone(), evals)))
    }

    /// The first stage of the next step when it is already evaluated (dense output), the
    /// dense factor's linearisation point, time, `g` and age ([`StageJacobian::Mobility`]), and
    /// the cell's error norm of the last accepted step when [`Reuse`] reads it (`cell_error`).
    fn save_state(&self, prefix: &str, out: &mut StateMap) {
        if let Some(t) = self.valid_at {
            out.insert(format!("{prefix}f0_um_s"), flatten(&self.f0));
            out.insert(format!("{prefix}f0_t_s"), vec![t]);
        }
        if let Some(d) = &self.dense {
            out.insert(format!("{prefix}dense_x"), flatten(&d.x));
            out.insert(format!("{prefix}dense_t_g_age"), vec![d.t, d.stage.g, d.age as f64]);
        }
        if let Some(e) = self.cell_error {
            out.insert(format!("{prefix}cell_error"), vec![e]);
        }
    }

    fn restore_state(&mut self, prefix: &str, state: &StateMap) -> Result<(), SolverError> {
        self.valid_at = None;
        self.restored_f0 = None;
        if let (Some(f0), Some(t)) = (super::state_vectors(state, &format!("{prefix}f0_um_s"))?, state.get(&format!("{prefix}f0_t_s"))) {
            let [t] = t[..] else {
                return Err(SolverError::Output(format!("checkpoint field {prefix}f0_t_s: {} values, expected 1", t.len())));
            };
            self.f0 = f0;
            self.restored_f0 = Some(t);
        }
        self.dense = None;
        self.restored = None;
        if let (Some(x), Some(tga)) = (super::state_vectors(state, &format!("{prefix}dense_x"))?, state.get(&format!("{prefix}dense_t_g_age"))) {
            let [t, g, age] = tga[..] else {
                return Err(SolverError::Output(format!("checkpoint field {prefix}dense_t_g_age: {} values, expected 3", tga.len())));
            };
            self.restored = Some((x, t, g, age as usize));
        }
        // (a checkpoint from before session 33 has none: the first step then keeps `max_age`)
        self.cell_error = match state.get(&format!("{prefix}cell_error")).map(|v| &v[..]) {
            None => None,
            Some([e]) => Some(*e),
            Some(v) => return Err(SolverError::Output(format!("checkpoint field {prefix}cell_error: {} values, expected 1", v.len()))),
        };
        Ok(())
    }

    fn invalidate(&mut self) {
        self.valid_at = None;
    }
}
