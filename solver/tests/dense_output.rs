//! Dense output of the Rosenbrock schemes: steps cross output times, the samples in between come from the cubic Hermite interpolant, exact on cubics, accurate to the tolerance against an exact solution, and a run resumed from a checkpoint taken at a step end repeats the uninterrupted one bit-for-bit.

use nalgebra::Vector3;
use rbc_solver::integrate::check::Checks;
use rbc_solver::integrate::precondition::LocalJacobian;
use rbc_solver::integrate::ros34pw2::{Ros34pw2, StageJacobian};
use rbc_solver::integrate::{Dynamics, Linearised};
use rbc_solver::run::checkpoint::RunState;
use rbc_solver::run::{hermite, Recorder, RunConfig, RunSummary, Runner, StepControl};
use rbc_solver::SolverError;

mod common;
use common::Tap;

/// `u = A x + (0, 0, cos(40 t))` per point, `A` = a damped rotation in (x, y) and decay in z:
/// non-autonomous, with an exact solution ([`exact`]) and an exact Jacobian.
struct Forced {
    j: LocalJacobian,
}

const A: [[f64; 3]; 3] = [[-3.0, 20.0, 0.0], [-20.0, -3.0, 0.0], [0.0, 0.0, -0.5]];

impl Forced {
    fn new(n: usize) -> Self {
        let mut e = Vec::new();
        for p in 0..n {
            for (r, row) in A.iter().enumerate() {
                for (c, &v) in row.iter().enumerate() {
                    if v != 0.0 {
                        e.push((3 * p + r, 3 * p + c, v));
                    }
                }
            }
        }
        Self { j: LocalJacobian::from_entries(n, &e).unwrap() }
    }
}

impl Dynamics for Forced {
    fn velocity(&mut self, t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        for (ui, p) in u.iter_mut().zip(x) {
            *ui = Vector3::new(A[0][0] * p.x + A[0][1] * p.y, A[1][0] * p.x + A[1][1] * p.y, A[2][2] * p.z + (40.0 * t_s).cos());
        }
        Ok(())
    }
}

impl Linearised for Forced {
    fn linearise(&mut self, _t_s: f64, _x: &[Vector3<f64>]) -> Result<(), SolverError> {
        Ok(())
    }
    fn jacobian_apply(&mut self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        self.j.apply(w, out);
        Ok(())
    }
    fn local_jacobian(&mut self) -> Result<Option<&LocalJacobian>, SolverError> {
        Ok(Some(&self.j))
    }
}

/// The exact solution at `t` from `p0` at 0.
fn exact(p0: &Vector3<f64>, t: f64) -> Vector3<f64> {
    let (c, s) = ((20.0 * t).cos(), (20.0 * t).sin());
    let d = (-3.0 * t).exp();
    // z' = -z/2 + cos(40 t): particular solution a cos + b sin
    let w: f64 = 40.0;
    let den = 0.25 + w * w;
    let (a, b) = (0.5 / den, w / den);
    let z = (p0.z - a) * (-0.5 * t).exp() + a * (w * t).cos() + b * (w * t).sin();
    Vector3::new(d * (c * p0.x + s * p0.y), d * (-s * p0.x + c * p0.y), z)
}

fn x0() -> Vec<Vector3<f64>> {
    vec![Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.3, -0.7, 2.0)]
}

fn config(output: f64) -> RunConfig {
    RunConfig {
        t_start_s: 0.0,
        t_end_s: 1.0,
        output_interval_s: output,
        control: StepControl::new(1e-6, 1e-3, 1e-12, 1.0),
        checks: Checks::default(),
        volume: None,
    }
}

fn scheme(dense: bool) -> Ros34pw2 {
    let mut s = Ros34pw2::with(StageJacobian::Local, false);
    s.local_scale = 1.0; // the exact J
    s.dense_output = dense;
    s
}

fn run(tap: &mut Tap, dense: bool, output: f64) -> (RunSummary, Vec<Vector3<f64>>) {
    let mut x = x0();
    let s = Runner::new(config(output)).run(&mut Forced::new(2), &mut scheme(dense), &[], &mut x, tap).unwrap();
    (s, x)
}

fn max_sample_error(rec: &Recorder) -> f64 {
    let p0 = x0();
    rec.times_s.iter().zip(&rec.vertices).map(|(&t, v)| v.iter().zip(&p0).map(|(x, p)| (x - exact(p, t)).norm()).fold(0.0, f64::max)).fold(0.0, f64::max)
}

#[test]
fn hermite_interpolant_is_exact_on_cubics() {
    // x(t) = c0 + c1 t + c2 t^2 + c3 t^3 per component, on a step from 0.2 to 0.7
    let c = [Vector3::new(0.3, -1.0, 2.0), Vector3::new(1.5, 0.25, -0.5), Vector3::new(-2.0, 0.75, 1.0), Vector3::new(0.5, -1.25, 3.0)];
    let x = |t: f64| c[0] + c[1] * t + c[2] * t * t + c[3] * t * t * t;
    let f = |t: f64| c[1] + c[2] * (2.0 * t) + c[3] * (3.0 * t * t);
    let (t0, h) = (0.2, 0.5);
    let mut out = Vec::new();
    for theta in [0.0, 0.1, 0.37, 0.5, 0.9, 1.0] {
        hermite(&[x(t0)], &[x(t0 + h)], &[f(t0)], &[f(t0 + h)], h, theta, &mut out);
        assert!((out[0] - x(t0 + theta * h)).norm() < 1e-14, "theta {theta}: {:?} vs {:?}", out[0], x(t0 + theta * h));
    }
}

#[test]
fn steps_cross_output_times_and_samples_stay_accurate() {
    // output every 1 ms against free steps of ~2-3.5 ms: without dense output every step ends on
    // an output time (>= 1000 steps); with it the steps follow the error control alone and the
    // interpolated samples are as accurate as the step ends (the interpolant's O(h^4) error lies
    // below the steps' O(h^3) local error)
    let (mut clamped, mut dense) = (Tap::default(), Tap::default());
    let (s_clamped, _) = run(&mut clamped, false, 0.001);
    let (s_dense, _) = run(&mut dense, true, 0.001);
    assert_eq!(dense.rec.times_s, clamped.rec.times_s, "the same output times");
    assert_eq!(dense.rec.times_s.len(), 1001);
    assert!(s_clamped.accepted >= 1000, "{s_clamped:?}");
    assert!(s_dense.h_max_s > 0.002 && s_dense.accepted * 3 < s_clamped.accepted * 2, "dense {s_dense:?} vs clamped {s_clamped:?}");
    // with dense output the steps, and so the final state, do not depend on the output interval
    let (s_coarse, x_coarse) = run(&mut Tap::default(), true, 0.005);
    let (_, x_dense) = run(&mut Tap::default(), true, 0.001);
    assert_eq!((s_coarse.accepted, s_coarse.rejected), (s_dense.accepted, s_dense.rejected));
    assert_eq!(x_coarse, x_dense);
    let (e_clamped, e_dense) = (max_sample_error(&clamped.rec), max_sample_error(&dense.rec));
    // both are held to atol 1e-6 per step; over 1 s the global error stays within ~10 atol
    assert!(e_dense < 1e-5 && e_clamped < 1e-5, "max sample error: dense {e_dense:e}, clamped {e_clamped:e}");
    assert!(e_dense > 0.0);
    // the end velocity is the next step's first stage: three evaluations per attempt and one per
    // accepted state, as without dense output (plus one at the very end when the last step holds samples)
    let base = 4 * s_dense.accepted + 3 * s_dense.rejected;
    assert!(s_dense.velocity_evals == base || s_dense.velocity_evals == base + 1, "{s_dense:?}");
    assert_eq!(s_clamped.velocity_evals, 4 * s_clamped.accepted + 3 * s_clamped.rejected, "{s_clamped:?}");
}

#[test]
fn resumed_from_a_step_end_the_run_repeats_bit_for_bit() {
    // checkpoints are taken at the end of a step that crossed an output time (not on the output
    // time): the next output index, the next step and the scheme's first stage travel with it
    let mut full = Tap::default();
    let (s_full, x_full) = run(&mut full, true, 0.05);
    let n_ckpt = full.states.len();
    assert!(n_ckpt >= 10, "{n_ckpt} checkpoints");
    let off_output = full.states.iter().filter(|s| ((s.t_s / 0.05).round() * 0.05 - s.t_s).abs() > 1e-9).count();
    assert!(off_output > 0, "checkpoints between output times");
    for k in [1, n_ckpt / 2, n_ckpt - 2] {
        let st = RunState::from_fields(&full.states[k].to_fields(), "").unwrap();
        assert!(st.integrator.contains_key("f0_um_s"), "the first stage of the next step is saved");
        let emitted = full.rec.times_s.iter().filter(|&&t| t <= st.t_s + 1e-12).count();
        let mut part = Tap { from: Some(st), ..Default::default() };
        let (s, x) = run(&mut part, true, 0.05);
        assert_eq!(x, x_full, "final state after resuming at checkpoint {k}");
        assert_eq!(part.rec.times_s[..], full.rec.times_s[emitted..]);
        assert_eq!(part.rec.vertices[..], full.rec.vertices[emitted..]);
        let strip = |s: &RunSummary| RunSummary { wall_s: 0.0, observer_s: 0.0, ..s.clone() };
        assert_eq!(strip(&s), strip(&s_full));
    }
}
