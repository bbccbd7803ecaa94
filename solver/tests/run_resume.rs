//! The runner continued from a checkpoint (`Observer::resume`) repeats the uninterrupted run bit-for-bit: samples, counters, final state.

use nalgebra::Vector3;
use rbc_solver::integrate::bs23::BogackiShampine;
use rbc_solver::integrate::check::Checks;
use rbc_solver::integrate::Dynamics;
use rbc_solver::run::checkpoint::RunState;
use rbc_solver::run::{Controller, RunConfig, RunSummary, Runner, StepControl};
use rbc_solver::SolverError;

mod common;
use common::Tap;

/// A forced, damped rotation per point: `u = A x + (0, 0, cos(40 t))`, non-autonomous so
/// that the time of every stage matters, mildly stiff so that steps get rejected.
struct Forced;

impl Dynamics for Forced {
    fn velocity(&mut self, t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        for (ui, p) in u.iter_mut().zip(x) {
            *ui = Vector3::new(-3.0 * p.x + 20.0 * p.y, -20.0 * p.x - 3.0 * p.y, -0.5 * p.z + (40.0 * t_s).cos());
        }
        Ok(())
    }
}

fn config(controller: Controller) -> RunConfig {
    RunConfig {
        t_start_s: 0.0,
        t_end_s: 1.0,
        output_interval_s: 0.05,
        control: StepControl::new(1e-6, 0.05, 1e-12, 0.05).with_controller(controller),
        checks: Checks::default(),
        volume: None,
    }
}

fn run_with(tap: &mut Tap, integrator: &mut BogackiShampine, controller: Controller) -> (RunSummary, Vec<Vector3<f64>>) {
    let mut x = vec![Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.3, -0.7, 2.0)];
    let s = Runner::new(config(controller)).run(&mut Forced, integrator, &[], &mut x, tap).unwrap();
    (s, x)
}

fn run(tap: &mut Tap, integrator: &mut BogackiShampine) -> (RunSummary, Vec<Vector3<f64>>) {
    run_with(tap, integrator, Controller::Integral)
}

#[test]
fn resumed_run_repeats_the_uninterrupted_one_bit_for_bit() {
    for controller in [Controller::Integral, Controller::PI34] {
        resumed_run_repeats(controller);
    }
}

fn resumed_run_repeats(controller: Controller) {
    let mut full = Tap::default();
    let (s_full, x_full) = run_with(&mut full, &mut BogackiShampine::new(), controller);
    assert!(s_full.rejected > 0 && s_full.accepted > 40, "adaptive steps with rejections: {s_full:?}");
    assert_eq!(full.states.len(), 21, "a checkpoint at t = 0 and at each of the 20 outputs");
    if controller != Controller::Integral {
        assert!(full.states[7].err_prev.is_some(), "the PI memory is in the checkpoint");
    }
    for k in [0, 7, 19] {
        // the state survives the trip through named f64 arrays (the checkpoint file's content)
        let st = RunState::from_fields(&full.states[k].to_fields(), "").unwrap();
        let mut part = Tap { from: Some(st), ..Default::default() };
        let (s, x) = run_with(&mut part, &mut BogackiShampine::new(), controller);
        assert_eq!(x, x_full, "final state after resuming at output {k}");
        assert_eq!(part.rec.times_s[..], full.rec.times_s[k + 1..], "samples after the checkpoint only");
        assert_eq!(part.rec.vertices[..], full.rec.vertices[k + 1..]);
        assert_eq!(part.rec.steps[..], full.rec.steps[k + 1..]);
        let strip = |s: &RunSummary| RunSummary { wall_s: 0.0, observer_s: 0.0, ..s.clone() };
        assert_eq!(strip(&s), strip(&s_full), "counters, step extremes ({controller:?})");
    }
}

#[test]
fn a_checkpoint_without_the_pi_memory_resumes_with_one_integral_step() {
    // what the PI memory is for: a checkpoint without `runner.err_prev` (one written before the
    // PI controller existed) still resumes, the first step after it chosen by the integral
    // controller, so the run goes on but is no longer bit-identical to the uninterrupted one
    let mut full = Tap::default();
    let (s_full, x_full) = run_with(&mut full, &mut BogackiShampine::new(), Controller::PI34);
    let k = 7;
    let mut fields = full.states[k].to_fields();
    assert!(fields.remove("runner.err_prev").is_some());
    let st = RunState::from_fields(&fields, "").unwrap();
    assert_eq!(st.err_prev, None);
    let mut part = Tap { from: Some(st), ..Default::default() };
    let (s, x) = run_with(&mut part, &mut BogackiShampine::new(), Controller::PI34);
    assert_eq!(part.rec.times_s[..], full.rec.times_s[k + 1..], "the same output times");
    // other step sizes after the integral step (measured: the same step counts, h_max 1e-11 apart)
    assert_ne!(part.rec.vertices[0], full.rec.vertices[k + 1], "other steps after the integral one: {s:?} vs {s_full:?}");
    assert_ne!(s.h_max_s, s_full.h_max_s);
    // both solve the same problem to the tolerance 1e-6: the final states agree to a few atol
    let d = x.iter().zip(&x_full).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
    assert!(d > 0.0 && d < 2e-5, "final states {d:e} apart");
}

#[test]
fn without_the_fsal_stage_a_resumed_run_costs_an_extra_evaluation() {
    // what the integrator state is for: Bogacki-Shampine's first stage is the last stage of
    // the previous step; a checkpoint without it makes the resumed run recompute it
    let mut full = Tap::default();
    let (s_full, x_full) = run(&mut full, &mut BogackiShampine::new());
    let mut st = full.states[7].clone();
    assert!(!st.integrator.is_empty(), "bs23 saves its first-same-as-last stage");
    st.integrator.clear();
    let mut part = Tap { from: Some(st), ..Default::default() };
    let (s, x) = run(&mut part, &mut BogackiShampine::new());
    assert_eq!(x, x_full, "the recomputed stage has the same bits (the dynamics are deterministic)");
    assert_eq!(s.velocity_evals, s_full.velocity_evals + 1);
}

/// A run that starts with a small first step, whose first accepted step grows by what its error
/// allows (`StepControl::fac_max_first`), resumed from its checkpoint at t = 0 (before that step)
/// or at a later output repeats the uninterrupted run bit for bit: the rule is the run's first
/// accepted step, counted across the checkpoint, not the first step after a resume.
#[test]
fn a_run_whose_first_step_grows_past_fac_max_resumes_bit_for_bit() {
    let cfg = |fac_max_first: f64| {
        let mut c = config(Controller::PI34);
        c.control.h0_s = 1e-5;
        c.control.fac_max_first = fac_max_first;
        c
    };
    let go = |tap: &mut Tap, c: RunConfig| {
        let mut x = vec![Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.3, -0.7, 2.0)];
        let s = Runner::new(c).run(&mut Forced, &mut BogackiShampine::new(), &[], &mut x, tap).unwrap();
        (s, x)
    };
    let (s_ramp, _) = go(&mut Tap::default(), cfg(5.0));
    let mut full = Tap::default();
    let (s_full, x_full) = go(&mut full, cfg(1e4));
    assert!(s_full.accepted < s_ramp.accepted, "the first step grew past 5x: {s_full:?} against the ramp's {s_ramp:?}");
    for k in [0, 1, 7] {
        let st = RunState::from_fields(&full.states[k].to_fields(), "").unwrap();
        let mut part = Tap { from: Some(st), ..Default::default() };
        let (s, x) = go(&mut part, cfg(1e4));
        assert_eq!(x, x_full, "final state after resuming at output {k}");
        assert_eq!(part.rec.vertices[..], full.rec.vertices[k + 1..]);
        let strip = |s: &RunSummary| RunSummary { wall_s: 0.0, observer_s: 0.0, ..s.clone() };
        assert_eq!(strip(&s), strip(&s_full), "counters, step extremes after resuming at output {k}");
    }
}
