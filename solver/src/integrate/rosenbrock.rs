//! Linearly implicit Rosenbrock-W method ROS2 with an embedded first-order error estimate.
//!
//! Verwer, Spee, Blom & Hundsdorfer, SIAM J. Sci. Comput. 20, 1456 (1999), eq. (2.3):
//! ```text
//! W = I - gamma h J,                 gamma = 1 + 1/sqrt(2)
//! W k1 = f(t, y)
//! W k2 = f(t + h, y + h k1) - 2 k1
//! y1 = y + h (3/2 k1 + 1/2 k2)       (order 2 for any matrix J: a W-method)
//! err = y1 - (y + h k1) = h/2 (k1 + k2)   (against the first-order solution)
//! ```
//! With the exact Jacobian the method is L-stable, so the stiff membrane modes
//! (area dilatation, bending) no longer bound the step; with an approximate `J`
//! (membrane force linearised at `y`, Stokes mobility lagged: [`super::Linearised`])
//! the order is still 2 and stability holds as long as `J` captures the stiff
//! eigenvalues *and their coupling to the slow variables*. The Prothero-Robinson
//! test (`tests/integrate_ode.rs`) shows why: when a stiff mode relaxes to an
//! equilibrium that moves with the slow variables, a `J` that omits the
//! dependence of the stiff force on the slow variables leaves an `O(h)` lag in
//! the stiff mode, which the error estimate sees (correctly) and which forces
//! small steps; with the coupling the steps grow to the accuracy limit of the
//! slow dynamics. For the membrane, `J = M dF/dx` contains the full derivative
//! of the elastic force, so it has that coupling. (Shampine's `W^-1` filter of
//! the estimate was tried and rejected: it hides that lag and under-reports
//! the error by 100x on the same test.) The linear systems are solved matrix-free with [`crate::gmres`];
//! a solve that misses its tolerance turns the step into a rejected one (error
//! estimate `+inf`), so the controller retries with a smaller step.

use crate::gmres::{gmres, GmresOptions, Tolerance};
use super::{axpy_stages, Integrator, Linearised, StepContext, StepWork};
use crate::error::SolverError;
use nalgebra::Vector3;

/// `gamma = 1 + 1/sqrt(2)` of ROS2.
pub const GAMMA: f64 = 1.0 + std::f64::consts::FRAC_1_SQRT_2;

/// ROS2 stepper; owns its stage buffers.
#[derive(Debug, Clone)]
pub struct Ros2 {
    /// Krylov dimension of the stage solves before restart.
    pub restart: usize,
    /// Maximal Jacobian applications per stage solve.
    pub max_iterations: usize,
    /// The stage residual (um/s, 2-norm) times `h` is driven below this fraction of the
    /// absolute tolerance, so that solve errors stay well under the local error (default 0.05).
    pub linear_tol_fraction: f64,
    f0: Vec<Vector3<f64>>,
    k1: Vec<Vector3<f64>>,
    k2: Vec<Vector3<f64>>,
    rhs: Vec<Vector3<f64>>,
    tmp: Vec<Vector3<f64>>,
    /// `f0` and the linearisation are valid for the current state at this time.
    valid_at: Option<f64>,
    /// Stage solves that missed the tolerance so far.
    pub failed_solves: usize,
}

impl Default for Ros2 {
    fn default() -> Self {
        Self {
            restart: 30,
            max_iterations: 200,
            linear_tol_fraction: 0.05,
            f0: Vec::new(),
            k1: Vec::new(),
            k2: Vec::new(),
            rhs: Vec::new(),
            tmp: Vec::new(),
            valid_at: None,
            failed_solves: 0,
        }
    }
}

impl Ros2 {
    pub fn new() -> Self {
        Self::default()
    }
}

impl<D: Linearised + ?Sized> Integrator<D> for Ros2 {
    fn name(&self) -> &'static str {
        "ros2"
    }

    fn embedded_order(&self) -> u32 {
        1
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
        if self.f0.len() != n {
            for v in [&mut self.f0, &mut self.k1, &mut self.k2, &mut self.rhs, &mut self.tmp] {
                v.resize(n, Vector3::zeros());
            }
            self.valid_at = None;
        }
        let mut work = StepWork::default();
        if self.valid_at != Some(t) {
            f.velocity(t, x, &mut self.f0)?;
            f.linearise(t, x)?;
            work.velocity_evals += 1;
            self.valid_at = Some(t);
        }
        let opts = GmresOptions {
            restart: self.restart,
            max_iterations: self.max_iterations,
            tolerance: Tolerance::Absolute(self.linear_tol_fraction * ctx.atol_um / h),
        };
        let gh = GAMMA * h;
        let mut applies = 0usize;
        // W v = v - gamma h J v
        let solve = |f: &mut D, rhs: &[Vector3<f64>], k: &mut [Vector3<f64>], applies: &mut usize| {
            k.copy_from_slice(rhs); // explicit guess: exact for non-stiff components as h -> 0
            gmres::<_, SolverError>(
                |v, out| {
                    f.jacobian_apply(v, out)?;
                    *applies += 1;
                    for (o, vi) in out.iter_mut().zip(v) {
                        *o = vi - gh * *o;
                    }
                    Ok(())
                },
                rhs,
                k,
                &opts,
            )
        };
        let r1 = solve(f, &self.f0, &mut self.k1, &mut applies)?;
        axpy_stages(&mut self.tmp, x, h, &[(1.0, &self.k1)]);
        f.velocity(t + h, &self.tmp, &mut self.rhs)?;
        work.velocity_evals += 1;
        for (r, k) in self.rhs.iter_mut().zip(&self.k1) {
            *r -= 2.0 * k;
        }
        let r2 = solve(f, &self.rhs, &mut self.k2, &mut applies)?;
        work.jacobian_applies = applies;
        axpy_stages(x_new, x, h, &[(1.5, &self.k1), (0.5, &self.k2)]);
        if !(r1.converged() && r2.converged()) {
            self.failed_solves += 1;
            err.iter_mut().for_each(|e| *e = Vector3::repeat(f64::INFINITY));
            return Ok(work);
        }
        for (i, e) in err.iter_mut().enumerate().take(n) {
            *e = 0.5 * h * (self.k1[i] + self.k2[i]);
        }
        Ok(work)
    }

    fn accepted(&mut self) {
        self.valid_at = None;
    }

    fn invalidate(&mut self) {
        self.valid_at = None;
    }
}
