//! Explicit adaptive Bogacki-Shampine 3(2) with first-same-as-last stage reuse.
//!
//! Tableau (Bogacki & Shampine, Appl. Math. Lett. 2, 321 (1989); the scheme of
//! MATLAB's `ode23` and of the paper):
//! ```text
//! k1 = f(t, y)
//! k2 = f(t + h/2,  y + h/2 k1)
//! k3 = f(t + 3h/4, y + 3h/4 k2)
//! y1 = y + h (2/9 k1 + 1/3 k2 + 4/9 k3)              (order 3, propagated)
//! k4 = f(t + h, y1)                                   (= k1 of the next step)
//! z1 = y + h (7/24 k1 + 1/4 k2 + 1/3 k3 + 1/8 k4)    (order 2, embedded)
//! err = y1 - z1 = h (-5/72 k1 + 1/12 k2 + 1/9 k3 - 1/8 k4)
//! ```
//! Stability: the real stability interval is about [-2.51, 0], so the step is
//! bounded by `2.5 / |lambda_max|` of the stiffest membrane mode.

use super::{axpy_stages, flatten, Dynamics, Integrator, StateMap, StepContext, StepWork};
use crate::error::SolverError;
use nalgebra::Vector3;

/// Bogacki-Shampine 3(2) stepper; owns its stage buffers.
#[derive(Debug, Default, Clone)]
pub struct BogackiShampine {
    k1: Vec<Vector3<f64>>,
    k2: Vec<Vector3<f64>>,
    k3: Vec<Vector3<f64>>,
    k4: Vec<Vector3<f64>>,
    tmp: Vec<Vector3<f64>>,
    /// `k1` is valid for the current state at this time.
    k1_valid_at: Option<f64>,
    /// Time at which `k4` was evaluated (end of the last attempt).
    t_new: f64,
}

impl BogackiShampine {
    pub fn new() -> Self {
        Self::default()
    }

    fn resize(&mut self, n: usize) {
        for v in [&mut self.k1, &mut self.k2, &mut self.k3, &mut self.k4, &mut self.tmp] {
            v.resize(n, Vector3::zeros());
        }
    }
}

impl<D: Dynamics + ?Sized> Integrator<D> for BogackiShampine {
    fn name(&self) -> &'static str {
        "bs23"
    }

    fn embedded_order(&self) -> u32 {
        2
    }

    fn attempt(
        &mut self,
        f: &mut D,
        t: f64,
        x: &[Vector3<f64>],
        h: f64,
        _ctx: StepContext,
        x_new: &mut [Vector3<f64>],
        err: &mut [Vector3<f64>],
    ) -> Result<StepWork, SolverError> {
        let n = x.len();
        if self.k1.len() != n {
            self.resize(n);
            self.k1_valid_at = None;
        }
        let mut work = StepWork::default();
        if self.k1_valid_at != Some(t) {
            f.velocity(t, x, &mut self.k1)?;
            work.velocity_evals += 1;
            self.k1_valid_at = Some(t);
        }
        axpy_stages(&mut self.tmp, x, h, &[(0.5, &self.k1)]);
        f.velocity(t + 0.5 * h, &self.tmp, &mut self.k2)?;
        axpy_stages(&mut self.tmp, x, h, &[(0.75, &self.k2)]);
        f.velocity(t + 0.75 * h, &self.tmp, &mut self.k3)?;
        axpy_stages(x_new, x, h, &[(2.0 / 9.0, &self.k1), (1.0 / 3.0, &self.k2), (4.0 / 9.0, &self.k3)]);
        f.velocity(t + h, x_new, &mut self.k4)?;
        work.velocity_evals += 3;
        for (i, e) in err.iter_mut().enumerate().take(n) {
            *e = h * (-5.0 / 72.0 * self.k1[i] + 1.0 / 12.0 * self.k2[i] + 1.0 / 9.0 * self.k3[i] - 0.125 * self.k4[i]);
        }
        // remember where k4 was evaluated so that `accepted` can promote it
        self.t_new = t + h;
        Ok(work)
    }

    fn accepted(&mut self) {
        std::mem::swap(&mut self.k1, &mut self.k4);
        self.k1_valid_at = Some(self.t_new);
    }

    fn invalidate(&mut self) {
        self.k1_valid_at = None;
    }

    /// `k1` (um/s, the first-same-as-last stage) and the time it is valid at (empty when invalid).
    fn save_state(&self, prefix: &str, out: &mut StateMap) {
        if let Some(t) = self.k1_valid_at {
            out.insert(format!("{prefix}k1_um_s"), flatten(&self.k1));
            out.insert(format!("{prefix}k1_valid_at_s"), vec![t]);
        }
    }

    fn restore_state(&mut self, prefix: &str, state: &StateMap) -> Result<(), SolverError> {
        self.k1_valid_at = None;
        if let (Some(k1), Some(t)) = (super::state_vectors(state, &format!("{prefix}k1_um_s"))?, state.get(&format!("{prefix}k1_valid_at_s"))) {
            let n = k1.len();
            self.resize(n);
            self.k1 = k1;
            self.k1_valid_at = t.first().copied();
        }
        Ok(())
    }
}
