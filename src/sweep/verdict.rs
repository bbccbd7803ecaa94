//! A sweep run's verdict, judged and summarised: the sweep's steady-state criterion and classifier
//! settings ([`criterion`], [`classify_config`]), the summary written when a run ends
//! ([`summarize`]: status, window statistics and the classification of its last frames, with the
//! evidence) and the steady state carried to the transit distances a run had not reached
//! ([`steady_transits`]). Used by the observer of [`super::solver_exec`] and by
//! `rbc-sweep relabel` ([`super::relabel`]).

use rbc_schema::results::{FinalShape, RunStatus, RunSummary, TimeSample, Transit};
use rbc_schema::sweep::{ClassifySettings, SteadySettings};
use rbc_solver::classify::{classify, ClassifyConfig, Frame};
use rbc_solver::steady::{window_stats, SteadyCriterion, Verdict};
use std::collections::BTreeMap;

/// The steady-state criterion of a sweep: the solver's defaults with the sweep file's settings;
/// the maximal time is `max_time_s` or else the scene's end time.
pub fn criterion(s: &SteadySettings, scene_end_s: f64) -> SteadyCriterion {
    let mut c = SteadyCriterion::paper_default();
    c.window_s = s.window_s.unwrap_or(c.window_s);
    c.max_time_s = s.max_time_s.unwrap_or(scene_end_s);
    c.min_cycles = s.min_cycles.unwrap_or(c.min_cycles);
    if let Some(p) = s.position_tol_um {
        for k in [0, 2, 3, 4] {
            c.tolerances[k] = p;
        }
    }
    if let Some(a) = s.asphericity_tol {
        c.tolerances[1] = a;
    }
    c
}

/// The classifier configuration of a sweep (defaults with the sweep file's settings).
pub fn classify_config(s: &ClassifySettings) -> ClassifyConfig {
    let mut c = ClassifyConfig::default();
    c.centred_um = s.centred_um.unwrap_or(c.centred_um);
    c.symmetric_rel = s.symmetric_rel.unwrap_or(c.symmetric_rel);
    c.rigid_rel = s.rigid_rel.unwrap_or(c.rigid_rel);
    c
}

/// The run summary from the verdict, the samples and the final frames.
///
/// Pending (the run ended before the maximal time undecided) counts as unsteady
/// over the last window. With fewer than 3 frames the shape is `other` with no evidence.
pub fn summarize(
    verdict: Verdict,
    window_s: f64,
    samples: &[TimeSample],
    frames: &[(f64, Vec<[f64; 3]>)],
    triangles: &[[usize; 3]],
    cfg: &ClassifyConfig,
) -> RunSummary {
    let t_end = samples.last().map(|s| s.t_s).unwrap_or(0.0);
    let (status, window, period) = match verdict {
        Verdict::Steady {
            t_s,
            window_start_s,
        } => (RunStatus::Steady, (window_start_s, t_s), None),
        Verdict::Periodic {
            t_s,
            window_start_s,
            period_s,
        } => (RunStatus::Periodic, (window_start_s, t_s), Some(period_s)),
        Verdict::Unsteady {
            t_s,
            window_start_s,
        } => (RunStatus::Unsteady, (window_start_s, t_s), None),
        Verdict::Pending => (
            RunStatus::Unsteady,
            ((t_end - window_s).max(0.0), t_end),
            None,
        ),
    };
    let mut evidence = BTreeMap::new();
    evidence.insert("steady_start_s".to_string(), window.0);
    evidence.insert("steady_end_s".to_string(), window.1);
    if let Some(p) = period {
        evidence.insert("period_s".to_string(), p);
    }
    let stats = window_stats(samples, window);
    if let Some(w) = &stats {
        evidence.insert("steady_duration_s".into(), w.duration_s);
        evidence.insert("radial_min_um".into(), w.radial_min_um);
        evidence.insert("radial_max_um".into(), w.radial_max_um);
        for (j, axis) in ["x", "y", "z"].iter().enumerate() {
            evidence.insert(format!("extent_{axis}_mean_um"), w.extents_mean_um[j]);
            evidence.insert(format!("extent_{axis}_min_um"), w.extents_min_um[j]);
            evidence.insert(format!("extent_{axis}_max_um"), w.extents_max_um[j]);
        }
    }
    let fr: Vec<Frame<'_>> = frames
        .iter()
        .map(|(t, v)| Frame {
            t_s: *t,
            vertices: v,
        })
        .collect();
    let (shape, tt, tumbling) = match classify(&fr, triangles, cfg) {
        Ok(c) => {
            evidence.extend(c.evidence.to_map());
            (c.shape, c.tank_treading, c.tumbling)
        }
        Err(_) => (FinalShape::Other, false, false),
    };
    let w = stats.unwrap_or(rbc_solver::steady::WindowStats {
        n: 0,
        duration_s: 0.0,
        velocity_mean_mm_s: 0.0,
        velocity_min_mm_s: 0.0,
        velocity_max_mm_s: 0.0,
        radial_mean_um: 0.0,
        radial_min_um: 0.0,
        radial_max_um: 0.0,
        y_mean_um: 0.0,
        z_mean_um: 0.0,
        extents_mean_um: [0.0; 3],
        extents_min_um: [0.0; 3],
        extents_max_um: [0.0; 3],
    });
    RunSummary {
        status,
        final_shape: shape,
        tank_treading: tt,
        tumbling,
        mean_velocity_mm_s: w.velocity_mean_mm_s,
        min_velocity_mm_s: w.velocity_min_mm_s,
        max_velocity_mm_s: w.velocity_max_mm_s,
        mean_radial_um: w.radial_mean_um,
        mean_y_um: w.y_mean_um,
        mean_z_um: w.z_mean_um,
        evidence: evidence
            .into_iter()
            .filter(|(_, v)| v.is_finite())
            .collect(),
    }
}

/// The transit records at the distances of `distances_mm` that a run which ended steady or
/// periodic had not reached: its steady state carried there ([`Transit::from_steady`]). `first`
/// and `last` are the run's first and last samples; nothing for an unsteady run, a non-positive
/// mean velocity, or a distance already travelled (those are recorded as the cell passes).
pub fn steady_transits(
    distances_mm: &[f64],
    first: &TimeSample,
    last: &TimeSample,
    summary: &RunSummary,
) -> Vec<Transit> {
    let steady = matches!(summary.status, RunStatus::Steady | RunStatus::Periodic);
    let u_um_s = summary.mean_velocity_mm_s * 1e3;
    if !steady || !(u_um_s > 0.0) {
        return Vec::new();
    }
    let travelled_um = last.centroid_um[0] - first.centroid_um[0];
    distances_mm
        .iter()
        .filter(|d| **d * 1e3 > travelled_um)
        .map(|&d| Transit {
            distance_mm: d,
            t_s: last.t_s + (d * 1e3 - travelled_um) / u_um_s,
            x_um: first.centroid_um[0] + d * 1e3,
            y_um: summary.mean_y_um,
            z_um: summary.mean_z_um,
            velocity_mm_s: summary.mean_velocity_mm_s,
            shape: summary.final_shape,
            from_steady: true,
        })
        .collect()
}

