//! The simulated phase diagram: one point per finished run in the (mean velocity u, r_init) plane, and the velocity bins.
//!
//! Runs at "the same" imposed flow end with slightly different mean cell
//! velocities (a slipper moves at another speed than a croissant, and the speed
//! oscillates), so runs are grouped into velocity bins before a threshold is
//! read off each column (paper Fig. 5 is drawn the same way: one column of
//! symbols per imposed flow).

use rbc_schema::results::{FinalShape, RunRecord, RunStatus};

/// Default relative tolerance of the velocity binning: two mean velocities
/// belong to one column when they differ by at most 5 %.
///
/// Why 5 %: in the paper's Fig. 5 the min-max velocity bars of one column (the
/// slippers' periodic oscillation, and the spread of mean velocities with r_init)
/// are a few percent wide, while neighbouring columns differ by 15 % or more
/// (0.13 to 10.4 mm/s in about 20-30 columns, roughly geometric steps).
pub const DEFAULT_VELOCITY_REL_TOL: f64 = 0.05;

/// One finished simulation in the phase diagram.
#[derive(Debug, Clone, PartialEq)]
pub struct PhasePoint {
    pub run_id: String,
    /// Start shape (`discocyte`, `croissant`, `slipper`, ...).
    pub start_shape: String,
    /// Mean cell velocity in the steady state, mm/s.
    pub velocity_mm_s: f64,
    /// Minimum and maximum velocity in one period, mm/s.
    pub min_velocity_mm_s: f64,
    pub max_velocity_mm_s: f64,
    /// Initial centroid offset from the axis, um.
    pub r_init_um: f64,
    pub final_shape: FinalShape,
    pub tank_treading: bool,
    /// Mean steady centroid y and z, um (signed).
    pub mean_y_um: f64,
    pub mean_z_um: f64,
}

/// A run left out of the phase diagram, with the reason (for a warning).
#[derive(Debug, Clone, PartialEq)]
pub struct SkippedRun {
    pub run_id: String,
    pub reason: String,
}

/// Phase points of every steady or periodic run; failed, running and unsteady
/// runs (and runs without start attributes) are returned as skipped with a reason.
pub fn phase_points(records: &[RunRecord]) -> (Vec<PhasePoint>, Vec<SkippedRun>) {
    let mut points = Vec::new();
    let mut skipped = Vec::new();
    for r in records {
        let skip = |reason: String| SkippedRun { run_id: r.run_id.clone(), reason };
        let (attrs, summary) = match (&r.attrs, &r.summary) {
            (Some(a), Some(s)) => (a, s),
            _ => {
                let why = match r.status {
                    RunStatus::Failed => format!("failed ({})", r.failure.as_deref().unwrap_or("no diagnosis")),
                    RunStatus::Running => "still running (or killed before it finished)".to_string(),
                    RunStatus::OverlapsWall => format!("not run: overlaps the wall ({})", r.not_run.as_deref().unwrap_or("no detail")),
                    other => format!("status {} without attributes", other.as_str()),
                };
                skipped.push(skip(why));
                continue;
            }
        };
        if summary.status == RunStatus::Unsteady {
            skipped.push(skip("unsteady (no converged shape)".into()));
            continue;
        }
        if !(summary.mean_velocity_mm_s.is_finite() && summary.mean_velocity_mm_s > 0.0) {
            skipped.push(skip(format!("mean velocity {} mm/s is not a positive finite number", summary.mean_velocity_mm_s)));
            continue;
        }
        points.push(PhasePoint {
            run_id: r.run_id.clone(),
            start_shape: attrs.start_shape.clone(),
            velocity_mm_s: summary.mean_velocity_mm_s,
            min_velocity_mm_s: summary.min_velocity_mm_s,
            max_velocity_mm_s: summary.max_velocity_mm_s,
            r_init_um: attrs.r_init_um,
            final_shape: summary.final_shape,
            tank_treading: summary.tank_treading,
            mean_y_um: summary.mean_y_um,
            mean_z_um: summary.mean_z_um,
        });
    }
    (points, skipped)
}

/// Bin velocities by single linkage in relative distance: sorted velocities
/// `u_k < u_{k+1}` share a bin when `u_{k+1} / u_k - 1 <= rel_tol`.
///
/// Returns, for each input velocity, the index of its bin; bins are numbered in
/// increasing velocity. Single linkage can chain a slow drift into one bin; that
/// only happens if the simulated columns are closer than `rel_tol`, which the
/// caller controls (`--velocity-tol`).
pub fn bin_velocities(velocities_mm_s: &[f64], rel_tol: f64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..velocities_mm_s.len()).collect();
    order.sort_by(|&a, &b| velocities_mm_s[a].total_cmp(&velocities_mm_s[b]));
    let mut bin = vec![0; velocities_mm_s.len()];
    let mut current = 0;
    for w in 0..order.len() {
        if w > 0 {
            let (prev, this) = (velocities_mm_s[order[w - 1]], velocities_mm_s[order[w]]);
            if this > prev * (1.0 + rel_tol) {
                current += 1;
            }
        }
        bin[order[w]] = current;
    }
    bin
}

/// The start shapes present, in a fixed order: discocyte, croissant, slipper, then others alphabetically.
pub fn start_shapes(points: &[PhasePoint]) -> Vec<String> {
    let rank = |s: &str| match s {
        "discocyte" => 0,
        "croissant" => 1,
        "slipper" => 2,
        _ => 3,
    };
    let mut shapes: Vec<String> = points.iter().map(|p| p.start_shape.clone()).collect();
    shapes.sort_by(|a, b| rank(a).cmp(&rank(b)).then(a.cmp(b)));
    shapes.dedup();
    shapes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binning_groups_close_velocities_and_separates_columns() {
        // two columns: around 1.0 (spread 3 %) and around 1.2 (spread 2 %)
        let u = [1.0, 1.21, 1.03, 1.2, 1.015, 1.22];
        let b = bin_velocities(&u, 0.05);
        assert_eq!(b, vec![0, 1, 0, 1, 0, 1]);
        // a tolerance below the within-column spread splits a column
        let b = bin_velocities(&u, 0.01);
        assert_eq!(b, vec![0, 3, 2, 3, 1, 3]);
        assert!(bin_velocities(&[], 0.05).is_empty());
    }
}
