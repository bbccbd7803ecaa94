//! ROS34PW2 on ODEs with exact solutions: order 3 of the solution and 2 of the embedded one for exact, wrong and local Jacobians; stiff stability.

use nalgebra::{DMatrix, DVector, Vector3};
use rbc_solver::integrate::bs23::BogackiShampine;
use rbc_solver::integrate::check::Checks;
use rbc_solver::integrate::precondition::LocalJacobian;
use rbc_solver::integrate::ros34pw2::{Ros34pw2, StageJacobian};
use rbc_solver::integrate::{Dynamics, Integrator, Linearised, StepContext};
use rbc_solver::run::{Recorder, RunConfig, RunSummary, Runner, StepControl};
use rbc_solver::SolverError;

fn flat(v: &[Vector3<f64>]) -> DVector<f64> {
    DVector::from_iterator(3 * v.len(), v.iter().flat_map(|p| [p.x, p.y, p.z]))
}

fn unflat(d: &DVector<f64>, out: &mut [Vector3<f64>]) {
    for (i, o) in out.iter_mut().enumerate() {
        *o = Vector3::new(d[3 * i], d[3 * i + 1], d[3 * i + 2]);
    }
}

/// `y' = A y` on two "vertices" (6 unknowns) with a fixed non-normal `A` whose
/// eigenvalues are `-1, -0.5, -2, -0.2 +- i, -3`; `J` is the matrix used by the
/// scheme (exact `A`, a wrong one, or the same handed over as a local Jacobian).
struct Linear {
    a: DMatrix<f64>,
    j: DMatrix<f64>,
    local: Option<LocalJacobian>,
}

fn matrix_a() -> DMatrix<f64> {
    // similarity transform S D S^-1 of a real block-diagonal D with a fixed, well-conditioned S
    let mut d = DMatrix::<f64>::zeros(6, 6);
    for (i, l) in [-1.0, -0.5, -2.0, -3.0].iter().enumerate() {
        d[(i, i)] = *l;
    }
    d[(4, 4)] = -0.2;
    d[(5, 5)] = -0.2;
    d[(4, 5)] = 1.0;
    d[(5, 4)] = -1.0;
    let s = DMatrix::<f64>::from_fn(6, 6, |i, j| if i == j { 2.0 } else { 0.3 * ((i * 7 + j * 3) % 5) as f64 / 5.0 - 0.1 });
    let si = s.clone().try_inverse().unwrap();
    &s * d * si
}

impl Linear {
    fn new(j_scale: f64, local: bool) -> Self {
        let a = matrix_a();
        let j = &a * j_scale;
        let local = local.then(|| {
            let e: Vec<(usize, usize, f64)> = (0..6).flat_map(|r| (0..6).map(move |c| (r, c))).map(|(r, c)| (r, c, j[(r, c)])).collect();
            LocalJacobian::from_entries(2, &e).unwrap()
        });
        Self { a, j, local }
    }
    fn exact(&self, t: f64, y0: &DVector<f64>) -> DVector<f64> {
        (&self.a * t).exp() * y0
    }
}

impl Dynamics for Linear {
    fn velocity(&mut self, _t: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        unflat(&(&self.a * flat(x)), u);
        Ok(())
    }
}

impl Linearised for Linear {
    fn linearise(&mut self, _t: f64, _x: &[Vector3<f64>]) -> Result<(), SolverError> {
        Ok(())
    }
    fn jacobian_apply(&mut self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        unflat(&(&self.j * flat(w)), out);
        Ok(())
    }
    fn local_jacobian(&mut self) -> Result<Option<&LocalJacobian>, SolverError> {
        Ok(self.local.as_ref())
    }
}

/// Fixed-step integration to `t_end` propagating either the third-order solution or the embedded one.
fn fixed_steps<D: Linearised>(d: &mut D, scheme: &mut Ros34pw2, y0: &[Vector3<f64>], h: f64, t_end: f64, embedded: bool) -> Vec<Vector3<f64>> {
    let mut x = y0.to_vec();
    let mut x_new = x.clone();
    let mut err = x.clone();
    let steps = (t_end / h).round() as usize;
    let ctx = StepContext { step: 0, atol_um: 1e-13 };
    for k in 0..steps {
        Integrator::<D>::attempt(scheme, d, k as f64 * h, &x, h, ctx, &mut x_new, &mut err).unwrap();
        for p in 0..x.len() {
            x[p] = if embedded { x_new[p] - err[p] } else { x_new[p] };
        }
        Integrator::<D>::accepted(scheme);
    }
    x
}

fn orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

fn y0() -> Vec<Vector3<f64>> {
    vec![Vector3::new(1.0, -0.5, 0.3), Vector3::new(0.2, 0.8, -1.0)]
}

#[test]
fn order_three_and_embedded_order_two_for_exact_wrong_and_local_jacobians() {
    let t_end = 2.0;
    let hs = [0.2, 0.1, 0.05, 0.025, 0.0125];
    // (J = scale A, handed over as: lagged GMRES J or local direct J)
    for (scale, jac) in [(1.0, StageJacobian::Lagged), (0.3, StageJacobian::Lagged), (0.0, StageJacobian::Lagged), (1.0, StageJacobian::Local), (2.5, StageJacobian::Local)] {
        for embedded in [false, true] {
            let errs: Vec<f64> = hs
                .iter()
                .map(|&h| {
                    let mut d = Linear::new(scale, jac == StageJacobian::Local);
                    let exact = d.exact(t_end, &flat(&y0()));
                    let mut s = Ros34pw2::with(jac, false);
                    s.local_scale = 1.0; // J exactly as given
                    s.linear_tol_fraction = 1e-3; // GMRES to 1e-16: far below the truncation error
                    let y = fixed_steps(&mut d, &mut s, &y0(), h, t_end, embedded);
                    (flat(&y) - exact).norm()
                })
                .collect();
            let p = orders(&errs);
            let want = if embedded { 2.0 } else { 3.0 };
            // the last two halvings are in the asymptotic range on this problem (|h lambda| <= 0.15)
            for q in &p[2..] {
                assert!((q - want).abs() < 0.2, "J = {scale} A ({jac:?}), embedded {embedded}: orders {p:?}, errors {errs:?}");
            }
        }
    }
}

/// Prothero-Robinson `y' = -L (y - phi(t)) + phi'(t)` per component, non-autonomous
/// (the scheme has no df/dt term), exact `y = phi(t) + e^{-L t} (y0 - phi(0))`.
struct ProtheroRobinson {
    l: f64,
}

fn phi(t: f64) -> Vector3<f64> {
    Vector3::new(t.sin(), (2.0 * t).cos(), 1.0 / (1.0 + t))
}

fn dphi(t: f64) -> Vector3<f64> {
    Vector3::new(t.cos(), -2.0 * (2.0 * t).sin(), -1.0 / (1.0 + t).powi(2))
}

impl Dynamics for ProtheroRobinson {
    fn velocity(&mut self, t: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        u[0] = -self.l * (x[0] - phi(t)) + dphi(t);
        Ok(())
    }
}

impl Linearised for ProtheroRobinson {
    fn linearise(&mut self, _t: f64, _x: &[Vector3<f64>]) -> Result<(), SolverError> {
        Ok(())
    }
    fn jacobian_apply(&mut self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        out[0] = -self.l * w[0];
        Ok(())
    }
}

#[test]
fn order_three_on_a_non_autonomous_problem_without_a_time_derivative_term() {
    let t_end = 1.0;
    let x0 = [phi(0.0) + Vector3::new(0.3, -0.2, 0.1)];
    let l = 2.0;
    let exact = phi(t_end) + (-l * t_end).exp() * (x0[0] - phi(0.0));
    let errs: Vec<f64> = [0.1, 0.05, 0.025, 0.0125]
        .iter()
        .map(|&h| {
            let mut s = Ros34pw2::with(StageJacobian::Lagged, false);
            s.linear_tol_fraction = 1e-3;
            (fixed_steps(&mut ProtheroRobinson { l }, &mut s, &x0, h, t_end, false)[0] - exact).norm()
        })
        .collect();
    let p = orders(&errs);
    for q in &p {
        assert!((q - 3.0).abs() < 0.25, "orders {p:?}, errors {errs:?}");
    }
}

fn run<D: Linearised, I: Integrator<D>>(d: &mut D, i: &mut I, t_end: f64, atol: f64, x0: &[Vector3<f64>]) -> (Vec<Vector3<f64>>, RunSummary) {
    let cfg = RunConfig {
        t_start_s: 0.0,
        t_end_s: t_end,
        output_interval_s: t_end,
        control: StepControl::new(atol, 1e-4, 1e-14, t_end),
        checks: Checks::default(),
        volume: None,
    };
    let mut x = x0.to_vec();
    let s = Runner::new(cfg).run(d, i, &[], &mut x, &mut Recorder::default()).expect("run");
    (x, s)
}

fn diag_in_rotated_basis(l: [f64; 3]) -> nalgebra::Matrix3<f64> {
    let q = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1).into_inner();
    q * nalgebra::Matrix3::from_diagonal(&Vector3::from(l)) * q.transpose()
}

fn local_of(m: &nalgebra::Matrix3<f64>) -> LocalJacobian {
    let e: Vec<(usize, usize, f64)> = (0..3).flat_map(|r| (0..3).map(move |c| (r, c, m[(r, c)]))).collect();
    LocalJacobian::from_entries(1, &e).unwrap()
}

/// `y' = A y` with a fixed 3x3 `A`; the local Jacobian is a separate matrix.
struct Stiff3 {
    a: nalgebra::Matrix3<f64>,
    local: LocalJacobian,
}

impl Dynamics for Stiff3 {
    fn velocity(&mut self, _t: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        u[0] = self.a * x[0];
        Ok(())
    }
}

impl Linearised for Stiff3 {
    fn linearise(&mut self, _t: f64, _x: &[Vector3<f64>]) -> Result<(), SolverError> {
        Ok(())
    }
    fn jacobian_apply(&mut self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        self.local.apply(w, out);
        Ok(())
    }
    fn local_jacobian(&mut self) -> Result<Option<&LocalJacobian>, SolverError> {
        Ok(Some(&self.local))
    }
}

#[test]
fn over_estimating_local_jacobian_is_stable_and_steps_are_set_by_the_slow_mode() {
    // eigenvalues -1e5 (stiff), -1, -0.5; the local J over-estimates the stiff one 4x (as the
    // self-mobility does at the mesh scale): BS23 is bounded by h < 2.5e-5, ROS34PW2 only by accuracy
    let lam = [-1e5, -1.0, -0.5];
    let a = diag_in_rotated_basis(lam);
    let t_end = 2.0;
    let x0 = [Vector3::new(1.0, 0.5, -0.3)];
    let exact = (a * t_end).exp() * x0[0];
    let mut d = Stiff3 { a, local: local_of(&diag_in_rotated_basis([4.0 * lam[0], lam[1], lam[2]])) };
    let mut scheme = Ros34pw2::with(StageJacobian::Local, false);
    scheme.local_scale = 1.0;
    let (y, s_ros) = run(&mut d, &mut scheme, t_end, 1e-6, &x0);
    let (yb, s_bs) = run(&mut Stiff3 { a, local: local_of(&a) }, &mut BogackiShampine::new(), t_end, 1e-6, &x0);
    let (e_ros, e_bs) = ((y[0] - exact).norm(), (yb[0] - exact).norm());
    assert!(e_ros < 1e-5 && e_bs < 1e-5, "errors ros34 {e_ros:e}, bs23 {e_bs:e}");
    // BS23: >= |lambda| t_end / 2.5 = 8e4 steps; the W-method: the slow mode at atol 1e-6 (~ hundred)
    assert!(s_bs.accepted > 60_000, "{s_bs:?}");
    assert!(s_ros.accepted * 100 < s_bs.accepted, "ros34pw2-local {s_ros:?} vs bs23 {s_bs:?}");
}

#[test]
fn stiff_mode_tracking_a_moving_equilibrium_needs_the_right_stiff_eigenvalue() {
    // Prothero-Robinson with L = 1e5: the stiff mode relaxes to phi(t), which moves at O(1).
    // With J exact in the stiff mode ROS34PW2 is stiffly accurate and takes accuracy-limited
    // steps of the smooth phi; with J = 4 L it stays stable and accurate but lags phi by O(h)
    // per step, which its error estimate sees, so the steps shrink to ~1e-5 s (measured:
    // 1.6e5 steps at atol 1e-6). The membrane analogue: stiff area modes driven by the slow flow.
    let l = 1e5;
    let t_end = 1.0;
    let x0 = [phi(0.0)];
    let exact = phi(t_end);
    let mut steps = Vec::new();
    for c in [1.0, 4.0] {
        let local = LocalJacobian::from_entries(1, &[(0, 0, -c * l), (1, 1, -c * l), (2, 2, -c * l)]).unwrap();
        let mut d = LinearLocal { inner: ProtheroRobinson { l }, j: local };
        let mut scheme = Ros34pw2::with(StageJacobian::Local, false);
        scheme.local_scale = 1.0;
        let (y, s) = run(&mut d, &mut scheme, t_end, 1e-6, &x0);
        let e = (y[0] - exact).norm();
        assert!(e < 1e-5, "J = {c} L: error {e:e}");
        steps.push(s.accepted);
    }
    let (_, s_bs) = run(&mut ProtheroRobinson { l }, &mut BogackiShampine::new(), t_end, 1e-6, &x0);
    assert!(steps[0] * 100 < s_bs.accepted, "exact stiff J: {} steps, bs23 {}", steps[0], s_bs.accepted);
    assert!(steps[1] > 20 * steps[0], "J = 4 L: {} steps vs {} with the exact J", steps[1], steps[0]);
}

/// A dynamics with a fixed local Jacobian.
struct LinearLocal {
    inner: ProtheroRobinson,
    j: LocalJacobian,
}

impl Dynamics for LinearLocal {
    fn velocity(&mut self, t: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        self.inner.velocity(t, x, u)
    }
}

impl Linearised for LinearLocal {
    fn linearise(&mut self, _t: f64, _x: &[Vector3<f64>]) -> Result<(), SolverError> {
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

#[test]
fn scene_schemes_reach_the_capsule_deformation_of_bs23() {
    // capsule in shear (Ca = 0.01, C = 1, lambda = 1, 128 triangles), 30 relaxation times, built from a
    // scene like a user's run: the Rosenbrock-W variants must land on the same steady Taylor
    // deformation as BS23 (the time-integration error at atol = 4e-5 um is ~1e-4 of D, README)
    use rbc_solver::validation::{run_case, Case};
    let case = Case::Capsule { ca: 0.01, c: 1.0, lambda: 1.0 };
    let d_bs = run_case(case, 2, "bs23", 4e-5, 30.0).unwrap().d;
    for scheme in ["ros34pw2", "ros34pw2-local", "ros34pw2-mobility"] {
        let r = run_case(case, 2, scheme, 4e-5, 30.0).unwrap();
        assert!((r.d / d_bs - 1.0).abs() < 1e-3, "{scheme}: D = {} vs bs23 {d_bs} ({:?})", r.d, r.summary);
    }
}
