//! The runs as an experiment downstream sees them: each run's transit record at a distance (`rbc-predict --transit-mm D`) in place of its steady state.
//!
//! The paper's experiments film the cells 10 mm after the entrance, i.e. after `t = 10 mm / u`
//! (1.5 s at 6.5 mm/s), while the simulated phase diagram is drawn from steady states reached
//! after 2-30 s. A run's transit record at `D` mm (written by `rbc-sweep` when its centroid has
//! travelled `D` mm; `rbc_schema::results::Transit`) gives the label, centroid and velocity it
//! had there. [`at_transit`] turns each run that has one into a record that the phase diagram,
//! the thresholds and phi ([`super::predict`]) read exactly as a finished run: status `steady`,
//! the transit's label as final shape, its velocity as the mean (and min, max) velocity, its
//! centroid as the mean position. A run that ended steady or periodic before `D` has its steady
//! state carried there (`Transit::from_steady`, written by `rbc-sweep` at the run's end or by
//! `rbc-sweep relabel`) and counts the same: past its steady state the cell does not change.
//! Runs that have not travelled `D` mm yet (or ended unsteady or failed before) are left out
//! and named.

use rbc_schema::results::{RunRecord, RunStatus, RunSummary};

/// The runs seen at `distance_mm`, and the ids of those without a record there.
pub fn at_transit(runs: &[RunRecord], distance_mm: f64) -> (Vec<RunRecord>, Vec<String>) {
    let mut seen = Vec::new();
    let mut missing = Vec::new();
    for r in runs {
        let Some(t) = r.transits.iter().find(|t| t.distance_mm == distance_mm) else {
            missing.push(r.run_id.clone());
            continue;
        };
        let summary = RunSummary {
            status: RunStatus::Steady,
            final_shape: t.shape,
            tank_treading: false,
            tumbling: false,
            mean_velocity_mm_s: t.velocity_mm_s,
            min_velocity_mm_s: t.velocity_mm_s,
            max_velocity_mm_s: t.velocity_mm_s,
            mean_radial_um: t.y_um.hypot(t.z_um),
            mean_y_um: t.y_um,
            mean_z_um: t.z_um,
            evidence: Default::default(),
        };
        seen.push(RunRecord { status: RunStatus::Steady, summary: Some(summary), failure: None, ..r.clone() });
    }
    (seen, missing)
}
