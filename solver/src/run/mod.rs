//! The driver loop: step-size control, failure checks, volume correction, output and timing, once for every integrator.
//!
//! [`Runner::run`] advances the vertex positions with any [`Integrator`] and
//! hands samples at fixed output times to an [`Observer`] (the HDF5 writer,
//! a progress bar, a test). Step-size control is the standard one of embedded
//! Runge-Kutta pairs (Hairer, Norsett & Wanner, "Solving ODEs I", sec. II.4):
//! with the error norm `e = max_i |err_i| / atol` (per-vertex Euclidean error in
//! um against the absolute tolerance, as in the paper), a step is accepted when
//! `e <= 1` and the next step is `h * min(fac_max, max(fac_min, factor))` with the factor of the
//! chosen [`Controller`]: the integral (elementary) controller `safety * e_n^(-1/(q+1))`, or the
//! PI controller `safety^(0.3) * e_n^(-0.7/(q+1)) * e_(n-1)^(0.4/(q+1))` (Gustafsson 1991; see [`Controller`]),
//! which also weighs the error of the previous accepted step. After a rejection the step is
//! cut with the integral factor (never grown), and the step accepted right after a rejection
//! does not grow the step either. The first accepted step of a run may grow the step by up to
//! `fac_max_first` (1e4, as SUNDIALS CVODE's first step) instead of `fac_max`: the first trial
//! step is a guess far below the tolerance's.
//!
//! Output times: a scheme without dense output has every output time end a step (the step is
//! shortened to land on it). A scheme with dense output ([`Integrator::dense_output`], the
//! Rosenbrock schemes) steps across output times, and the samples between two step ends come
//! from the cubic Hermite interpolant [`hermite`] of the states and velocities at both ends
//! (Hairer, Norsett & Wanner I, sec. II.6; error `O(h^4)`, below the `O(h^3)` local error the
//! step control holds); the end velocity is the first stage of the next step, so a sample costs
//! no velocity evaluation. Checkpoints are then taken at the end of the step that produced the
//! sample (with the next output index and the scheme's first stage), not at the output time.

pub mod cell_output;
pub mod checkpoint;
pub mod persist;
pub mod progress;
pub mod results;
pub mod step_log;

pub use cell_output::CellOutput;

use crate::dynamics::volume::VolumeCorrection;
use crate::error::SolverError;
use crate::integrate::check::{first_non_finite, Checks};
use crate::integrate::{Dynamics, Integrator, IntegrateError, StepContext};
use crate::mesh::slices;
use crate::state::StateMap;
use checkpoint::RunState;
use nalgebra::Vector3;
use std::time::Instant;

/// How the next step follows from the error norms `e_n` (this step) and `e_(n-1)` (the
/// previous accepted one); `q` is the order of the embedded solution, `k = q + 1` the order
/// of the local error estimate (`e ~ h^k`). Both factors are dimensionless.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Controller {
    /// Elementary integral controller `h_new = h * safety * e_n^(-1/k)` (Hairer, Norsett &
    /// Wanner, "Solving ODEs I", 2nd ed., sec. II.4, eq. (4.13)).
    Integral,
    /// PI controller (Hairer & Wanner, "Solving ODEs II", 2nd ed., sec. IV.2, "PI step size
    /// control"), written with the target error `theta = safety^k` inside the ratios as in
    /// Soderlind's filters (G. Soderlind, "Digital filters in adaptive time-stepping", ACM TOMS
    /// 29, 1-26 (2003), eq. (9) with `eps = theta`):
    /// `h_new = h * (theta / e_n)^(k_beta1/k) * (e_(n-1) / theta)^(k_beta2/k)`
    /// `      = h * safety^(k_beta1 - k_beta2) * e_n^(-k_beta1/k) * e_(n-1)^(k_beta2/k)`,
    /// so that on a smooth problem it settles at the same error norm `e = safety^k` (0.73 for
    /// bs23) as the integral controller, which is the case `k_beta1 = 1`, `k_beta2 = 0`.
    /// (With the safety factor outside, `h * safety * e_n^(-beta1) * e_(n-1)^(beta2)`, PI.3.4
    /// would settle at `e = safety^(k / 0.3) = 0.35` and take ~30 % more steps than the integral
    /// controller for a smaller error: `tests/integrate_ode.rs` measured 191 against 146 steps.)
    /// `e_(n-1)` is the error norm of the previous accepted step of free (not output-shortened)
    /// size, floored at `1e-4` as in Hairer's DOPRI5 code (`facold`). `k_beta1 = 0.7`,
    /// `k_beta2 = 0.4` is Gustafsson's PI.3.4 controller for explicit Runge-Kutta pairs
    /// (K. Gustafsson, "Control theoretic techniques for stepsize selection in explicit
    /// Runge-Kutta methods", ACM TOMS 17, 533-554 (1991); PI.3.4 in Soderlind (2003), with
    /// `k beta_1 = 0.7`, `k beta_2 = -0.4` in Soderlind's sign convention). Where `e_(n-1)`
    /// is unknown the step is chosen by the integral controller: at the first step, after a
    /// checkpoint written before the PI controller existed, and after a step whose change was
    /// saturated at `fac_max` or `h_max` (anti-windup: without it, PI.3.4 reads the rising error
    /// of a start-up ramp from a tiny `h0` as a trend to brake, and took 61 instead of 50 steps
    /// for ros34pw2-local on the 128-triangle capsule of `rbc-bench controller`).
    Pi { k_beta1: f64, k_beta2: f64 },
}

impl Controller {
    /// Gustafsson's PI.3.4: `k beta1 = 0.7`, `k beta2 = 0.4`.
    pub const PI34: Controller = Controller::Pi { k_beta1: 0.7, k_beta2: 0.4 };

    /// Step factor (before clamping) after an accepted step with error norm `e > 0`,
    /// the previous accepted error norm `e_prev` (None: unknown) and estimate order `k = q + 1`.
    pub fn factor(&self, safety: f64, e: f64, e_prev: Option<f64>, k: f64) -> f64 {
        match (*self, e_prev) {
            (Controller::Pi { k_beta1, k_beta2 }, Some(ep)) => safety.powf(k_beta1 - k_beta2) * e.powf(-k_beta1 / k) * ep.max(PI_ERROR_FLOOR).powf(k_beta2 / k),
            _ => safety * e.powf(-1.0 / k),
        }
    }
}

/// Floor of the previous error norm in the PI controller (Hairer's DOPRI5: `facold >= 1e-4`),
/// so that an exceptionally accurate step does not throttle the next one.
pub const PI_ERROR_FLOOR: f64 = 1e-4;

/// How the per-vertex local error estimates `err_i` (um) are reduced to the step's error norm `e`
/// (a step is accepted when `e <= 1`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ErrorNorm {
    /// `e = max_i |err_i| / atol`: every vertex within the tolerance (the default).
    #[default]
    Max,
    /// `e = sqrt(1/N sum_i |err_i|^2) / atol`: the root-mean-square over the `N` vertices (the
    /// norm of Hairer, Norsett & Wanner I, eq. II.4.11, and of SUNDIALS), which bounds the error
    /// of surface averages (centroid, moments, asphericity) rather than that of the single worst
    /// vertex. A few vertices may then exceed `atol` by up to `sqrt(N)`.
    Rms,
}

/// Parameters of the step-size controller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepControl {
    /// Absolute tolerance on the local error of each vertex position (um).
    /// The paper uses `1e-5 R_RBC = 4e-5 um`.
    pub atol_um: f64,
    /// First trial step (s).
    pub h0_s: f64,
    /// Smallest step (s) before the run is declared failed (step-size collapse).
    pub h_min_s: f64,
    /// Largest step (s).
    pub h_max_s: f64,
    /// Safety factor of the controller (0.9, Hairer et al.).
    pub safety: f64,
    /// Bounds of the step change per step (0.2 and 5, Hairer et al.).
    pub fac_min: f64,
    pub fac_max: f64,
    /// Bound of the step change after the first accepted step of a run: 1e4, SUNDIALS CVODE's
    /// `eta_max_fs`. The first trial step `h0_s` is a guess far below what the tolerance allows
    /// (1 us against ~80-300 us in the paper's channel), and its error says how far: growing by
    /// `fac_max` a step instead would ramp up over 3-4 steps whose errors are 1e-5..1e-2 of the
    /// tolerance (`solver/README.md`, "Session 43").
    pub fac_max_first: f64,
    /// Maximal number of accepted plus rejected steps.
    pub max_steps: usize,
    /// Integral or PI control of accepted steps.
    pub controller: Controller,
    /// Reduction of the per-vertex error estimates to one number.
    pub norm: ErrorNorm,
    /// A tolerance of its own for the state's entries from this index on (the penalty walls'
    /// displacements after the cell's vertices): `(first entry, atol in um)`
    /// ([`Self::with_tail_atol`]).
    pub tail_atol: Option<(usize, f64)>,
}

impl StepControl {
    /// Integral controller with the usual safety factors for tolerance `atol_um` and steps in `[h_min_s, h_max_s]`.
    pub fn new(atol_um: f64, h0_s: f64, h_min_s: f64, h_max_s: f64) -> Self {
        Self { atol_um, h0_s, h_min_s, h_max_s, safety: 0.9, fac_min: 0.2, fac_max: 5.0, fac_max_first: 1e4, max_steps: 10_000_000, controller: Controller::Integral, norm: ErrorNorm::Max, tail_atol: None }
    }

    /// The same with the error norm `norm`.
    pub fn with_norm(self, norm: ErrorNorm) -> Self {
        Self { norm, ..self }
    }

    /// The same with `controller`.
    pub fn with_controller(self, controller: Controller) -> Self {
        Self { controller, ..self }
    }

    /// The same with the entries from `first` on held to `atol_um` (um) instead of
    /// [`Self::atol_um`]: their local errors are scaled by `self.atol_um / atol_um` before the
    /// norm, i.e. a vector tolerance (Hairer, Norsett & Wanner I, eq. II.4.10). The penalty walls'
    /// displacements take one of their own because an error in them is a traction error
    /// `kappa_W d` that the whole channel feels (`solver/README.md`, "Session 23").
    pub fn with_tail_atol(self, first: usize, atol_um: f64) -> Self {
        Self { tail_atol: Some((first, atol_um)), ..self }
    }
}

/// What to run and what to check.
#[derive(Debug, Clone, PartialEq)]
pub struct RunConfig {
    /// Start time (s).
    pub t_start_s: f64,
    /// End time (s).
    pub t_end_s: f64,
    /// Interval between samples handed to the observer (s); steps are shortened to land on them.
    pub output_interval_s: f64,
    pub control: StepControl,
    pub checks: Checks,
    /// Rescale to the target volume after accepted steps (None: no rescaling).
    pub volume: Option<VolumeCorrection>,
}

/// The state handed to an [`Observer`] at an output time.
#[derive(Debug, Clone, Copy)]
pub struct Sample<'a> {
    pub t_s: f64,
    /// Accepted steps so far.
    pub step: usize,
    /// Last accepted step size (s); 0 at the initial sample.
    pub h_s: f64,
    /// Vertex positions (um).
    pub vertices: &'a [Vector3<f64>],
    pub triangles: &'a [[usize; 3]],
    pub area_um2: f64,
    pub volume_um3: f64,
    /// Volume centroid (um).
    pub centroid_um: Vector3<f64>,
}

/// Statistics of a run (also of a failed one, up to the failure).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunSummary {
    pub integrator: &'static str,
    /// Time reached (s).
    pub t_s: f64,
    pub accepted: usize,
    pub rejected: usize,
    pub velocity_evals: usize,
    pub jacobian_applies: usize,
    /// Number of volume rescalings.
    pub rescalings: usize,
    /// Smallest and largest accepted step, excluding steps shortened to hit an output time (s).
    pub h_min_s: f64,
    pub h_max_s: f64,
    /// Wall-clock time of the whole run and of the observer calls (s).
    pub wall_s: f64,
    pub observer_s: f64,
}

impl RunSummary {
    /// Mean accepted step (s).
    pub fn h_mean_s(&self, t_start_s: f64) -> f64 {
        if self.accepted == 0 {
            0.0
        } else {
            (self.t_s - t_start_s) / self.accepted as f64
        }
    }
}

/// Receives the samples of a run (HDF5 writer, progress display, tests).
pub trait Observer {
    /// A sample at an output time (also at the start).
    fn sample(&mut self, s: &Sample<'_>) -> Result<(), SolverError>;
    /// Called after every accepted step, for progress displays.
    fn progress(&mut self, _t_s: f64, _h_s: f64, _step: usize) {}
    /// Called after every step attempt, accepted or rejected, before the state moves
    /// (diagnosis of the step-size control: [`step_log::StepLog`]).
    fn attempt(&mut self, _a: &Attempt<'_>) {}
    /// Called once at the end, with the failure if the run stopped early. A
    /// [`SolverError::Resume`] failure is the resumed state refused before any step: the run did
    /// not fail, and a recording observer keeps its rows, its status and its checkpoint.
    fn finish(&mut self, _summary: &RunSummary, _failure: Option<&SolverError>) -> Result<(), SolverError> {
        Ok(())
    }
    /// Called after every sample (the initial one included): true when the runner should
    /// take a checkpoint of the state of this sample now (and hand it to [`Observer::checkpoint`]).
    fn checkpoint_due(&mut self, _t_s: f64) -> bool {
        false
    }
    /// Store a checkpoint (the state right after the last sample).
    fn checkpoint(&mut self, _state: &RunState) -> Result<(), SolverError> {
        Ok(())
    }
    /// Asked once when the run reached its end time: true when the runner should hand the end
    /// state to [`Observer::checkpoint`], so that a later end time can continue the run from it.
    fn checkpoint_at_end(&mut self) -> bool {
        false
    }
    /// Asked when [`Observer::sample`] returned an error: true when that error stops the run on
    /// purpose (e.g. a steady-state verdict, not a failure) and the runner should hand the state
    /// of that sample to [`Observer::checkpoint`] before it stops, so that the run can be
    /// continued from its end later (`rbc-sweep reopen`).
    fn checkpoint_at_stop(&mut self) -> bool {
        false
    }
    /// Asked once before the run: a state to continue from (a resumed run) instead of the
    /// start; the runner then emits no initial sample and goes on with the next output time.
    fn resume(&mut self) -> Result<Option<RunState>, SolverError> {
        Ok(None)
    }
    /// The run continues from `state` (another observer supplied it): e.g. restart a clock there.
    fn resumed(&mut self, _state: &RunState) {}
}

/// An observer that keeps every sample in memory (tests, validation studies).
#[derive(Debug, Default, Clone)]
pub struct Recorder {
    pub times_s: Vec<f64>,
    pub vertices: Vec<Vec<Vector3<f64>>>,
    pub area_um2: Vec<f64>,
    pub volume_um3: Vec<f64>,
    pub centroid_um: Vec<Vector3<f64>>,
    pub steps: Vec<usize>,
}

impl Observer for Recorder {
    fn sample(&mut self, s: &Sample<'_>) -> Result<(), SolverError> {
        self.times_s.push(s.t_s);
        self.vertices.push(s.vertices.to_vec());
        self.area_um2.push(s.area_um2);
        self.volume_um3.push(s.volume_um3);
        self.centroid_um.push(s.centroid_um);
        self.steps.push(s.step);
        Ok(())
    }
}

/// One step attempt as the step-size control saw it.
#[derive(Debug, Clone, Copy)]
pub struct Attempt<'a> {
    /// Time at the start of the step (s) and the step tried (s).
    pub t_s: f64,
    pub h_s: f64,
    /// The error norm `e` (accepted when `e <= 1` and the new state is finite).
    pub error_norm: f64,
    /// The vertex with the largest local error estimate and that error (um).
    pub worst_vertex: usize,
    pub worst_error_um: f64,
    pub accepted: bool,
    /// Accepted steps before this attempt, and velocity evaluations so far (this attempt's included).
    pub step: usize,
    pub velocity_evals: usize,
    /// The state at the start of the step (um) and the per-vertex error estimates (um). With the
    /// penalty walls' own tolerance ([`StepControl::with_tail_atol`]) the entries past the cell
    /// are the wall displacements' errors scaled by `atol_um / tail_atol`, i.e. measured against
    /// `atol_um` like the cell's.
    pub x: &'a [Vector3<f64>],
    pub err: &'a [Vector3<f64>],
    /// The tolerance the error norm measures against (um).
    pub atol_um: f64,
}

/// Fans samples out to several observers.
pub struct Fanout<'a>(pub Vec<&'a mut dyn Observer>);

impl Observer for Fanout<'_> {
    fn sample(&mut self, s: &Sample<'_>) -> Result<(), SolverError> {
        self.0.iter_mut().try_for_each(|o| o.sample(s))
    }
    fn progress(&mut self, t_s: f64, h_s: f64, step: usize) {
        self.0.iter_mut().for_each(|o| o.progress(t_s, h_s, step))
    }
    fn attempt(&mut self, a: &Attempt<'_>) {
        self.0.iter_mut().for_each(|o| o.attempt(a))
    }
    /// Every observer finishes even when an earlier one fails (the first error is returned).
    fn finish(&mut self, summary: &RunSummary, failure: Option<&SolverError>) -> Result<(), SolverError> {
        let mut first = Ok(());
        for o in self.0.iter_mut() {
            let r = o.finish(summary, failure);
            if first.is_ok() {
                first = r;
            }
        }
        first
    }
    /// Every observer is asked (not short-circuiting: each counts outputs and keeps its clock).
    #[allow(clippy::unnecessary_fold)]
    fn checkpoint_at_end(&mut self) -> bool {
        self.0.iter_mut().fold(false, |due, o| o.checkpoint_at_end() || due)
    }
    /// Every observer is asked (as at the end).
    #[allow(clippy::unnecessary_fold)]
    fn checkpoint_at_stop(&mut self) -> bool {
        self.0.iter_mut().fold(false, |due, o| o.checkpoint_at_stop() || due)
    }
    // every observer is asked (each keeps its own schedule), so no short-circuiting `any`
    #[allow(clippy::unnecessary_fold)]
    fn checkpoint_due(&mut self, t_s: f64) -> bool {
        self.0.iter_mut().fold(false, |due, o| o.checkpoint_due(t_s) || due)
    }
    fn checkpoint(&mut self, state: &RunState) -> Result<(), SolverError> {
        self.0.iter_mut().try_for_each(|o| o.checkpoint(state))
    }
    /// The first observer that has a state to continue from supplies it.
    fn resume(&mut self) -> Result<Option<RunState>, SolverError> {
        for o in self.0.iter_mut() {
            if let Some(s) = o.resume()? {
                return Ok(Some(s));
            }
        }
        Ok(None)
    }
    fn resumed(&mut self, state: &RunState) {
        self.0.iter_mut().for_each(|o| o.resumed(state))
    }
}

/// The driver loop.
#[derive(Debug, Clone)]
pub struct Runner {
    pub config: RunConfig,
}

/// The error norm of the per-vertex errors `err` (um) over the tolerance ([`ErrorNorm`]), with the
/// worst vertex and its error (um); NaN (and the vertex) at the first non-finite error.
pub fn error_norm(err: &[Vector3<f64>], atol: f64, norm: ErrorNorm) -> (f64, usize, f64) {
    let mut worst = (0usize, 0.0);
    let mut sum2 = 0.0;
    for (i, e) in err.iter().enumerate() {
        let n = e.norm();
        if n.is_nan() {
            return (f64::NAN, i, n);
        }
        sum2 += n * n;
        if n > worst.1 {
            worst = (i, n);
        }
    }
    let e = match norm {
        ErrorNorm::Max => worst.1 / atol,
        ErrorNorm::Rms => (sum2 / err.len().max(1) as f64).sqrt() / atol,
    };
    (e, worst.0, worst.1)
}

impl Runner {
    pub fn new(config: RunConfig) -> Self {
        Self { config }
    }

    /// Integrate `x` (um, modified in place; on failure it holds the last accepted state)
    /// from `t_start_s` to `t_end_s`. Samples go to `observer` at the start and every output interval.
    pub fn run<D: Dynamics + ?Sized, I: Integrator<D> + ?Sized>(
        &self,
        dynamics: &mut D,
        integrator: &mut I,
        triangles: &[[usize; 3]],
        x: &mut Vec<Vector3<f64>>,
        observer: &mut dyn Observer,
    ) -> Result<RunSummary, SolverError> {
        let start = Instant::now();
        let mut summary = RunSummary { integrator: integrator.name(), t_s: self.config.t_start_s, h_min_s: f64::INFINITY, ..Default::default() };
        let mut wall_before = 0.0;
        let result = self.drive(dynamics, integrator, triangles, x, observer, &mut summary, start, &mut wall_before);
        summary.wall_s = wall_before + start.elapsed().as_secs_f64();
        if summary.h_min_s == f64::INFINITY {
            summary.h_min_s = 0.0;
        }
        let finish = observer.finish(&summary, result.as_ref().err());
        result?;
        finish?;
        Ok(summary)
    }

    fn emit(
        &self,
        observer: &mut dyn Observer,
        summary: &mut RunSummary,
        t_s: f64,
        h_s: f64,
        x: &[Vector3<f64>],
        triangles: &[[usize; 3]],
    ) -> Result<(), SolverError> {
        let t0 = Instant::now();
        let s = Sample {
            t_s,
            step: summary.accepted,
            h_s,
            vertices: x,
            triangles,
            area_um2: slices::area(x, triangles),
            volume_um3: slices::volume(x, triangles),
            centroid_um: slices::centroid(x, triangles),
        };
        let r = observer.sample(&s);
        summary.observer_s += t0.elapsed().as_secs_f64();
        r
    }

    #[allow(clippy::too_many_arguments)]
    fn drive<D: Dynamics + ?Sized, I: Integrator<D> + ?Sized>(
        &self,
        dynamics: &mut D,
        integrator: &mut I,
        triangles: &[[usize; 3]],
        x: &mut Vec<Vector3<f64>>,
        observer: &mut dyn Observer,
        summary: &mut RunSummary,
        start: Instant,
        wall_before: &mut f64,
    ) -> Result<(), SolverError> {
        let cfg = &self.config;
        let ctl = &cfg.control;
        let n = x.len();
        if let Some(&m) = triangles.iter().flatten().max() {
            if m >= n {
                return Err(IntegrateError::Shape { expected: m + 1, found: n }.into());
            }
        }
        if let Some((vertex, value)) = first_non_finite(x) {
            return Err(IntegrateError::NonFinite { quantity: "initial position", t_s: cfg.t_start_s, step: 0, vertex, value }.into());
        }
        let mut area0 = slices::area(x, triangles);
        let k_est = integrator.embedded_order() as f64 + 1.0;
        // error norm of the last accepted free step: the PI controller's memory (None: unknown)
        let mut e_prev: Option<f64> = None;
        let mut t = cfg.t_start_s;
        let mut h = ctl.h0_s.min(ctl.h_max_s);
        let mut x_new = vec![Vector3::zeros(); n];
        let mut err = vec![Vector3::zeros(); n];
        let mut k_out = 1usize;
        let mut just_rejected = false;
        if let Some(st) = observer.resume()? {
            // (persist::reopen refuses an unusable state before cutting the run back to it; here
            // again for any observer's state, with what only the run knows: its exact vertex count)
            let fits = (|| -> Result<(), String> {
                if st.vertices.len() != n {
                    return Err(IntegrateError::Shape { expected: n, found: st.vertices.len() }.to_string());
                }
                if let Some(why) = st.unusable(slices::cell_len(triangles)) {
                    return Err(why);
                }
                integrator.restore_state("", &st.integrator).map_err(|e| e.to_string())?;
                dynamics.restore_state("", &st.dynamics).map_err(|e| e.to_string())
            })();
            fits.map_err(SolverError::Resume)?;
            x.copy_from_slice(&st.vertices);
            (t, h, k_out, area0, e_prev) = (st.t_s, st.h_s, st.next_output, st.area0_um2, st.err_prev);
            *summary = RunSummary { integrator: integrator.name(), ..st.summary.clone() };
            *wall_before = st.summary.wall_s;
            observer.resumed(&st);
        } else {
            self.emit(observer, summary, t, 0.0, x, triangles)?;
            if observer.checkpoint_due(t) {
                self.checkpoint(dynamics, integrator, observer, summary, (t, h, k_out, area0, e_prev), x, start, *wall_before)?;
            }
        }
        // the k-th output time (the last one is the end time)
        let output_time = |k: usize| (cfg.t_start_s + k as f64 * cfg.output_interval_s).min(cfg.t_end_s);
        let mut next_out = output_time(k_out);
        let t_tol = 1e-12 * (cfg.t_end_s - cfg.t_start_s).abs().max(f64::MIN_POSITIVE);
        // dense output: steps cross output times; the samples between two step ends come from the
        // cubic Hermite interpolant of the states and velocities at both ends (error O(h^4), below
        // the O(h^3) local error the step control holds), the end velocity being the next step's
        // first stage; `f_start` is the velocity at the start of the step
        let dense = integrator.dense_output();
        let mut f_start: Vec<Vector3<f64>> = Vec::new();
        let mut x_prev: Vec<Vector3<f64>> = Vec::new();
        let mut x_out: Vec<Vector3<f64>> = Vec::new();
        if dense && t < cfg.t_end_s - t_tol {
            f_start = end_velocity(integrator, dynamics, t, x, summary)?;
        }
        while t < cfg.t_end_s - t_tol {
            if summary.accepted + summary.rejected >= ctl.max_steps {
                return Err(IntegrateError::TooManySteps { t_s: t, max_steps: ctl.max_steps, t_end_s: cfg.t_end_s }.into());
            }
            // land exactly on the next output time (dense output: on the end time only)
            let h_free = h;
            let stop = if dense { cfg.t_end_s } else { next_out };
            let clamped = t + h >= stop - t_tol;
            let h_try = if clamped { stop - t } else { h };
            let ctx = StepContext { step: summary.accepted, atol_um: ctl.atol_um };
            let work = integrator
                .attempt(dynamics, t, x, h_try, ctx, &mut x_new, &mut err)
                .map_err(|e| SolverError::AtStep { t_s: t, step: summary.accepted, cause: Box::new(e) })?;
            summary.velocity_evals += work.velocity_evals;
            summary.jacobian_applies += work.jacobian_applies;
            if let Some((first, tail_atol)) = ctl.tail_atol {
                let scale = ctl.atol_um / tail_atol;
                err.iter_mut().skip(first).for_each(|e| *e *= scale);
            }
            let (e, worst, worst_um) = error_norm(&err, ctl.atol_um, ctl.norm);
            if e.is_nan() {
                let value = err[worst].iter().copied().find(|c| c.is_nan()).unwrap_or(f64::NAN);
                return Err(IntegrateError::NonFinite { quantity: "velocity", t_s: t, step: summary.accepted, vertex: worst, value }.into());
            }
            let accept = e <= 1.0 && first_non_finite(&x_new).is_none();
            observer.attempt(&Attempt {
                t_s: t,
                h_s: h_try,
                error_norm: e,
                worst_vertex: worst,
                worst_error_um: worst_um,
                accepted: accept,
                step: summary.accepted,
                velocity_evals: summary.velocity_evals,
                x,
                err: &err,
                atol_um: ctl.atol_um,
            });
            if !accept {
                // cut with the integral factor, whatever the controller (Hairer & Wanner II, sec. IV.2)
                let cut = Controller::Integral.factor(ctl.safety, e, None, k_est).clamp(ctl.fac_min, 1.0);
                summary.rejected += 1;
                h = h_try * cut;
                just_rejected = true;
                if h < ctl.h_min_s {
                    return Err(IntegrateError::StepSizeCollapse {
                        t_s: t,
                        step: summary.accepted,
                        h_s: h,
                        h_min_s: ctl.h_min_s,
                        vertex: worst,
                        error_um: worst_um,
                        atol_um: ctl.atol_um,
                    }
                    .into());
                }
                continue;
            }
            cfg.checks.state(&x_new, x, triangles, area0, t + h_try, summary.accepted + 1)?;
            let t_prev = t;
            if dense {
                x_prev.clear();
                x_prev.extend_from_slice(x);
            }
            std::mem::swap(x, &mut x_new);
            integrator.accepted();
            t = if clamped { stop } else { t + h_try };
            summary.accepted += 1;
            summary.t_s = t;
            if !clamped || h_try >= h_free {
                summary.h_min_s = summary.h_min_s.min(h_try);
                summary.h_max_s = summary.h_max_s.max(h_try);
            }
            if let Some(vc) = &cfg.volume {
                if vc.apply(x, triangles) {
                    summary.rescalings += 1;
                    integrator.invalidate();
                }
            }
            let raw = if e == 0.0 { f64::INFINITY } else { ctl.controller.factor(ctl.safety, e, e_prev, k_est) };
            // the run's first accepted step (also after a resume from a checkpoint taken before it)
            let fac_max = if summary.accepted == 1 { ctl.fac_max_first.max(ctl.fac_max) } else { ctl.fac_max };
            let factor = raw.clamp(ctl.fac_min, fac_max);
            let grow = if just_rejected { factor.min(1.0) } else { factor };
            just_rejected = false;
            if !clamped || h_try >= h_free {
                // the PI memory: the error of this step, unless the step change is saturated (at
                // fac_max or h_max), where the error does not control the step (anti-windup: the next
                // step is again the integral controller's, so that h ramps up by fac_max per step);
                // an output-shortened step's error says little about the free step and is not kept
                e_prev = (raw < ctl.fac_max && h_try * grow < ctl.h_max_s).then_some(e);
            }
            h = (h_try * grow).min(ctl.h_max_s);
            if clamped {
                h = h.max(h_free.min(ctl.h_max_s));
            }
            if h < ctl.h_min_s || t + h == t {
                return Err(IntegrateError::StepSizeCollapse {
                    t_s: t,
                    step: summary.accepted,
                    h_s: h,
                    h_min_s: ctl.h_min_s,
                    vertex: worst,
                    error_um: worst_um,
                    atol_um: ctl.atol_um,
                }
                .into());
            }
            observer.progress(t, h_try, summary.accepted);
            if dense {
                let at_end = t >= cfg.t_end_s - t_tol;
                // the end velocity is needed by the next step, or by samples inside this one
                let f_end = if !at_end || next_out < t - t_tol { end_velocity(integrator, dynamics, t, x, summary)? } else { Vec::new() };
                let mut due = false;
                while next_out <= t + t_tol {
                    let sample: &[Vector3<f64>] = if next_out >= t - t_tol {
                        x
                    } else {
                        hermite(&x_prev, x, &f_start, &f_end, h_try, (next_out - t_prev) / h_try, &mut x_out);
                        &x_out
                    };
                    let t_out = next_out.min(t);
                    let r = self.emit(observer, summary, t_out, h_try, sample, triangles);
                    // a stop on purpose (a verdict): the sample's state is the run's end checkpoint
                    // (inside the step: its interpolant, the state a run reopened from its last
                    // snapshot starts from as well)
                    if r.is_err() && observer.checkpoint_at_stop() {
                        self.checkpoint(dynamics, integrator, observer, summary, (t_out, h, k_out + 1, area0, e_prev), sample, start, *wall_before)?;
                    }
                    r?;
                    k_out += 1;
                    let last = next_out >= cfg.t_end_s - t_tol;
                    next_out = output_time(k_out);
                    due |= observer.checkpoint_due(t_out);
                    if last {
                        break;
                    }
                }
                f_start = f_end;
                // a checkpoint holds the state at the step's end (its clock: the next output index)
                if due && !at_end {
                    self.checkpoint(dynamics, integrator, observer, summary, (t, h, k_out, area0, e_prev), x, start, *wall_before)?;
                }
            } else if clamped {
                let r = self.emit(observer, summary, t, h_try, x, triangles);
                if r.is_err() && observer.checkpoint_at_stop() {
                    self.checkpoint(dynamics, integrator, observer, summary, (t, h, k_out + 1, area0, e_prev), x, start, *wall_before)?;
                }
                r?;
                k_out += 1;
                next_out = output_time(k_out);
                if observer.checkpoint_due(t) {
                    self.checkpoint(dynamics, integrator, observer, summary, (t, h, k_out, area0, e_prev), x, start, *wall_before)?;
                }
            }
        }
        if observer.checkpoint_at_end() {
            self.checkpoint(dynamics, integrator, observer, summary, (t, h, k_out, area0, e_prev), x, start, *wall_before)?;
        }
        Ok(())
    }

    /// Hand the state after the sample at `t` to the observer (`clock` = t, next trial step, next output index, reference area, PI memory).
    #[allow(clippy::too_many_arguments)]
    fn checkpoint<D: Dynamics + ?Sized, I: Integrator<D> + ?Sized>(
        &self,
        dynamics: &D,
        integrator: &I,
        observer: &mut dyn Observer,
        summary: &RunSummary,
        clock: (f64, f64, usize, f64, Option<f64>),
        x: &[Vector3<f64>],
        start: Instant,
        wall_before: f64,
    ) -> Result<(), SolverError> {
        let (t_s, h_s, next_output, area0_um2, err_prev) = clock;
        let mut istate = StateMap::new();
        integrator.save_state("", &mut istate);
        let mut dstate = StateMap::new();
        dynamics.save_state("", &mut dstate);
        let state = RunState {
            t_s,
            h_s,
            next_output,
            area0_um2,
            err_prev,
            summary: RunSummary { wall_s: wall_before + start.elapsed().as_secs_f64(), ..summary.clone() },
            vertices: x.to_vec(),
            integrator: istate,
            dynamics: dstate,
        };
        observer.checkpoint(&state)
    }
}

/// The velocity at `(t, x)` from a dense-output scheme (counted in `summary`).
fn end_velocity<D: Dynamics + ?Sized, I: Integrator<D> + ?Sized>(integrator: &mut I, dynamics: &mut D, t: f64, x: &[Vector3<f64>], summary: &mut RunSummary) -> Result<Vec<Vector3<f64>>, SolverError> {
    match integrator.end_velocity(dynamics, t, x)? {
        Some((f, evals)) => {
            summary.velocity_evals += evals;
            Ok(f)
        }
        None => Err(SolverError::Unsupported { field: "integrator.scheme".into(), message: format!("{} claims dense output but gives no end velocity", integrator.name()) }),
    }
}

/// Cubic Hermite interpolant at `theta` in [0, 1] of a step of `h` (s) from `x0` (um, velocity
/// `f0`, um/s) to `x1` (velocity `f1`): `x(theta) = h00 x0 + h10 h f0 + h01 x1 + h11 h f1`
/// (Hairer, Norsett & Wanner I, sec. II.6), third order like the schemes that use it.
pub fn hermite(x0: &[Vector3<f64>], x1: &[Vector3<f64>], f0: &[Vector3<f64>], f1: &[Vector3<f64>], h: f64, theta: f64, out: &mut Vec<Vector3<f64>>) {
    let (t2, t3) = (theta * theta, theta * theta * theta);
    let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
    let h10 = (t3 - 2.0 * t2 + theta) * h;
    let h01 = -2.0 * t3 + 3.0 * t2;
    let h11 = (t3 - t2) * h;
    out.clear();
    out.extend((0..x0.len()).map(|i| h00 * x0[i] + h10 * f0[i] + h01 * x1[i] + h11 * f1[i]));
}
