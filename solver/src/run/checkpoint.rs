//! The state of a run at an output time that lets it continue bit-for-bit after a kill, as named `f64` arrays.
//!
//! [`crate::run::Runner`] takes a checkpoint right after an output sample when
//! its observer asks for one ([`crate::run::Observer::checkpoint_due`]) and hands
//! the [`RunState`] to [`crate::run::Observer::checkpoint`]; a resumed run gets
//! it back from [`crate::run::Observer::resume`] and continues as if it had
//! never stopped: the same time, vertices, next trial step, output clock,
//! counters, reference area of the failure checks, the scheme's reused stages
//! (Bogacki-Shampine's first-same-as-last derivative) and the dynamics' state
//! (the initial guess of an iterative Stokes solve). The step-size controller's
//! state at an output time is the next trial step `h` and, for the PI controller,
//! the error norm of the last accepted free step (`runner.err_prev`; the
//! "just rejected" flag is always false after an accepted step). `runner.err_prev`
//! is absent when unknown (and in checkpoints written before the PI controller
//! existed): the resumed run then takes the integral controller's step once. Everything is stored as `f64` (counters below 2^53 are exact),
//! so the state maps onto the HDF5 checkpoint of `rbc_schema::checkpoint`.

use super::RunSummary;
use crate::error::SolverError;
use crate::state::{flatten, unflatten, StateMap};
use nalgebra::Vector3;

/// Key prefix of the scheme's private state in [`RunState::to_fields`].
pub const INTEGRATOR_PREFIX: &str = "integrator.";
/// Key prefix of the dynamics' private state.
pub const DYNAMICS_PREFIX: &str = "dynamics.";
/// Key prefix of the runner's own state.
pub const RUNNER_PREFIX: &str = "runner.";

/// Everything the runner needs to continue a run from an output time.
#[derive(Debug, Clone, PartialEq)]
pub struct RunState {
    /// Time of the checkpoint (s), an output time.
    pub t_s: f64,
    /// Next trial step (s): the step-size controller's state.
    pub h_s: f64,
    /// Index `k` of the next output time `t_start + k * output_interval`.
    pub next_output: usize,
    /// Area of the initial shape (um^2), the reference of the area-change check.
    pub area0_um2: f64,
    /// Error norm (dimensionless, `max_i |err_i| / atol`) of the last accepted step of free size:
    /// the PI controller's memory ([`crate::run::Controller::Pi`]); None when unknown.
    pub err_prev: Option<f64>,
    /// Counters and step statistics so far (`wall_s`, `observer_s`: time spent before the checkpoint).
    pub summary: RunSummary,
    /// Vertex positions (um).
    pub vertices: Vec<Vector3<f64>>,
    /// The scheme's private state ([`crate::integrate::Integrator::save_state`]).
    pub integrator: StateMap,
    /// The dynamics' private state ([`crate::integrate::Dynamics::save_state`]).
    pub dynamics: StateMap,
}

fn missing(key: &str) -> SolverError {
    SolverError::Output(format!("checkpoint: field `{key}` is missing or malformed"))
}

impl RunState {
    /// All of the state as named arrays (runner fields under `runner.`, the scheme's under
    /// `integrator.`, the dynamics' under `dynamics.`).
    pub fn to_fields(&self) -> StateMap {
        let s = &self.summary;
        let mut f = StateMap::new();
        let mut put = |k: &str, v: f64| {
            f.insert(format!("{RUNNER_PREFIX}{k}"), vec![v]);
        };
        put("t_s", self.t_s);
        put("h_s", self.h_s);
        put("next_output", self.next_output as f64);
        put("area0_um2", self.area0_um2);
        if let Some(e) = self.err_prev {
            put("err_prev", e);
        }
        put("accepted", s.accepted as f64);
        put("rejected", s.rejected as f64);
        put("velocity_evals", s.velocity_evals as f64);
        put("jacobian_applies", s.jacobian_applies as f64);
        put("rescalings", s.rescalings as f64);
        put("h_min_s", s.h_min_s);
        put("h_max_s", s.h_max_s);
        put("wall_s", s.wall_s);
        put("observer_s", s.observer_s);
        f.insert(format!("{RUNNER_PREFIX}vertices_um"), flatten(&self.vertices));
        for (k, v) in &self.integrator {
            f.insert(format!("{INTEGRATOR_PREFIX}{k}"), v.clone());
        }
        for (k, v) in &self.dynamics {
            f.insert(format!("{DYNAMICS_PREFIX}{k}"), v.clone());
        }
        f
    }

    /// Why this state cannot be continued from, if it cannot: a time, step or area that is not
    /// finite and positive (the step and area) or finite (the time, the PI memory), a position or
    /// a value of the scheme's or the dynamics' state that is not finite, or fewer vertices than
    /// `n_cell` (the cell's, from the run's triangles; penalty walls add theirs after them; 0: no
    /// cell surface, whose reference area is 0).
    /// Every state a run writes passes (test `checkpoint::tests`).
    pub fn unusable(&self, n_cell: usize) -> Option<String> {
        let bad = |k: &str, v: f64| Some(format!("field `{RUNNER_PREFIX}{k}` is {v}"));
        if !self.t_s.is_finite() {
            return bad("t_s", self.t_s);
        }
        if !(self.h_s.is_finite() && self.h_s > 0.0) {
            return bad("h_s", self.h_s);
        }
        // (a state without a cell surface, n_cell 0, has a reference area of 0)
        if !(self.area0_um2.is_finite() && (self.area0_um2 > 0.0 || n_cell == 0 && self.area0_um2 == 0.0)) {
            return bad("area0_um2", self.area0_um2);
        }
        if let Some(e) = self.err_prev.filter(|e| !e.is_finite()) {
            return bad("err_prev", e);
        }
        if self.vertices.len() < n_cell {
            return Some(format!("field `{RUNNER_PREFIX}vertices_um` holds {} vertices, fewer than the run's {n_cell}", self.vertices.len()));
        }
        if let Some((i, p)) = self.vertices.iter().enumerate().find(|(_, p)| !p.iter().all(|c| c.is_finite())) {
            return Some(format!("field `{RUNNER_PREFIX}vertices_um`: vertex {i} is {p:?}"));
        }
        for (prefix, map) in [(INTEGRATOR_PREFIX, &self.integrator), (DYNAMICS_PREFIX, &self.dynamics)] {
            if let Some((k, v)) = map.iter().find_map(|(k, v)| v.iter().find(|x| !x.is_finite()).map(|x| (k, *x))) {
                return Some(format!("field `{prefix}{k}` holds {v}"));
            }
        }
        None
    }

    /// Inverse of [`RunState::to_fields`] (other keys, e.g. an observer's, are ignored).
    /// `integrator` names the scheme in the summary.
    pub fn from_fields(f: &StateMap, integrator: &'static str) -> Result<Self, SolverError> {
        let get = |k: &str| -> Result<f64, SolverError> {
            let key = format!("{RUNNER_PREFIX}{k}");
            match f.get(&key).map(|v| v.as_slice()) {
                Some([x]) if !x.is_nan() => Ok(*x),
                _ => Err(missing(&key)),
            }
        };
        let count = |k: &str| -> Result<usize, SolverError> {
            let x = get(k)?;
            if x >= 0.0 && x.fract() == 0.0 && x < 9.0e15 {
                Ok(x as usize)
            } else {
                Err(missing(&format!("{RUNNER_PREFIX}{k}")))
            }
        };
        let vkey = format!("{RUNNER_PREFIX}vertices_um");
        let vertices = f.get(&vkey).and_then(|v| unflatten(v)).ok_or_else(|| missing(&vkey))?;
        let sub = |prefix: &str| -> StateMap { f.iter().filter_map(|(k, v)| k.strip_prefix(prefix).map(|s| (s.to_string(), v.clone()))).collect() };
        Ok(RunState {
            t_s: get("t_s")?,
            h_s: get("h_s")?,
            next_output: count("next_output")?,
            area0_um2: get("area0_um2")?,
            // optional: absent in checkpoints without a PI memory (older ones among them)
            err_prev: if f.contains_key(&format!("{RUNNER_PREFIX}err_prev")) { Some(get("err_prev")?) } else { None },
            summary: RunSummary {
                integrator,
                t_s: get("t_s")?,
                accepted: count("accepted")?,
                rejected: count("rejected")?,
                velocity_evals: count("velocity_evals")?,
                jacobian_applies: count("jacobian_applies")?,
                rescalings: count("rescalings")?,
                h_min_s: get("h_min_s")?,
                h_max_s: get("h_max_s")?,
                wall_s: get("wall_s")?,
                observer_s: get("observer_s")?,
            },
            vertices,
            integrator: sub(INTEGRATOR_PREFIX),
            dynamics: sub(DYNAMICS_PREFIX),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_round_trip_exactly() {
        let mut integrator = StateMap::new();
        integrator.insert("k1_um_s".into(), vec![0.1, -2.0 / 3.0, 1e-300]);
        let st = RunState {
            t_s: 0.1 + 0.2,
            h_s: 1.0 / 3.0,
            next_output: 7,
            area0_um2: 133.7,
            err_prev: Some(0.1 + 0.7),
            summary: RunSummary { integrator: "bs23", t_s: 0.1 + 0.2, accepted: 12, rejected: 3, velocity_evals: 40, h_min_s: f64::INFINITY, h_max_s: 0.5, ..Default::default() },
            vertices: vec![Vector3::new(1.0, 2.0, std::f64::consts::PI)],
            integrator,
            dynamics: StateMap::new(),
        };
        let back = RunState::from_fields(&st.to_fields(), "bs23").unwrap();
        assert_eq!(back, st);
        let mut broken = st.to_fields();
        broken.remove("runner.h_s");
        assert!(RunState::from_fields(&broken, "bs23").unwrap_err().to_string().contains("runner.h_s"));
        // a checkpoint without the PI memory (written before it existed) still reads, as unknown
        let mut old = st.to_fields();
        assert_eq!(old.remove("runner.err_prev"), Some(vec![0.1 + 0.7]));
        assert_eq!(RunState::from_fields(&old, "bs23").unwrap(), RunState { err_prev: None, ..st.clone() });
        // present but malformed is an error naming it
        old.insert("runner.err_prev".into(), vec![]);
        assert!(RunState::from_fields(&old, "bs23").unwrap_err().to_string().contains("runner.err_prev"));
    }

    /// A state a run writes is usable (an infinite `h_min_s` before the first step included);
    /// each value no run could continue from is named, and so is a state with fewer vertices than
    /// the cell's.
    #[test]
    fn an_unusable_state_is_named() {
        let mut integrator = StateMap::new();
        integrator.insert("f0_um_s".into(), vec![0.1, -2.0, 3.0]);
        let st = RunState {
            t_s: 0.0,
            h_s: 1e-6,
            next_output: 1,
            area0_um2: 133.7,
            err_prev: None,
            summary: RunSummary { integrator: "bs23", h_min_s: f64::INFINITY, ..Default::default() },
            vertices: vec![Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.0, 1.0, 0.0)],
            integrator,
            dynamics: StateMap::new(),
        };
        assert_eq!(st.unusable(2), None);
        assert_eq!(st.unusable(3).unwrap(), "field `runner.vertices_um` holds 2 vertices, fewer than the run's 3");
        let named = |f: fn(&mut RunState)| {
            let mut s = st.clone();
            f(&mut s);
            s.unusable(2).unwrap()
        };
        assert_eq!(named(|s| s.t_s = f64::INFINITY), "field `runner.t_s` is inf");
        assert_eq!(named(|s| s.h_s = 0.0), "field `runner.h_s` is 0");
        assert_eq!(named(|s| s.h_s = -1e-6), "field `runner.h_s` is -0.000001");
        assert_eq!(named(|s| s.area0_um2 = f64::NAN), "field `runner.area0_um2` is NaN");
        assert_eq!(named(|s| s.err_prev = Some(f64::INFINITY)), "field `runner.err_prev` is inf");
        assert!(named(|s| s.vertices[1].y = f64::NAN).starts_with("field `runner.vertices_um`: vertex 1 is"));
        assert_eq!(named(|s| s.integrator.get_mut("f0_um_s").unwrap()[1] = f64::NEG_INFINITY), "field `integrator.f0_um_s` holds -inf");
        assert_eq!(named(|s| drop(s.dynamics.insert("last_velocity_um_s".into(), vec![f64::NAN]))), "field `dynamics.last_velocity_um_s` holds NaN");
    }
}
