//! The croissant fraction predicted from simulations (`rbc-predict`; paper section IV.B, Figs. 5, 7, 8).
//!
//! One module per step, after the simulated phase diagram ([`crate::simulated::phase`]: finished
//! runs as points in the (u, r_init) plane, velocity binning) and its r_trans per velocity column
//! with its bracket ([`crate::simulated::threshold`]):
//! - [`threshold`]: r_trans(u) by interpolation;
//! - [`input`]: the experiment's pressure groups (entrance y-sample, velocity, observed fraction);
//! - [`fraction`]: y_trans and phi with its uncertainty;
//! - [`offset`]: slipper off-centre positions, experiment vs simulation;
//! - [`transit`]: the runs as seen after travelling a distance (the experiment's 10 mm window),
//!   for the transit-matched prediction beside the steady-state one;
//! - [`next`]: the runs to simulate next, one per start shape and pressure group, each halving
//!   the entering cells its bracket of r_trans leaves undecided.
//!
//! [`predict`] runs them in order on data already read; [`write_outputs`] writes
//! the tables (the figures: [`crate::plot::prediction::write_figures`]). The results are
//! [`crate::types::prediction`]. Nothing is written before everything is computed.
//!
//! # Decisions (where the paper leaves room)
//!
//! - **Runs used**: status `steady` or `periodic`; `failed`, `running` and
//!   `unsteady` runs are skipped with a reason. Runs ending as `other` are drawn
//!   but do not vote on r_trans.
//! - **Velocity columns**: simulated mean velocities are grouped per start shape
//!   by single linkage with a relative tolerance of 5 % ([`DEFAULT_VELOCITY_REL_TOL`](crate::simulated::phase::DEFAULT_VELOCITY_REL_TOL),
//!   `--velocity-tol`); the column's velocity is the mean of its runs.
//! - **r_trans of a column**: midpoint between the largest croissant offset and
//!   the smallest slipper offset; `inf` without slipper, 0 without croissant; the
//!   fewest-misclassifications offset when they overlap ([`crate::simulated::threshold::column_threshold`]).
//! - **Between columns**: linear in u; next to a croissant-only column the nearer
//!   column's value, with an interval reaching to `inf` ([`ThresholdCurve::at`]).
//!   Outside the simulated range the nearest column is used and a warning given.
//! - **Status of phi** ([`Phi::status`](crate::types::prediction::Phi::status), column `status`): `bracketed`, `extrapolated`, or
//!   `unbracketed` when the runs leave r_trans anywhere in `[0, inf]` (or phi anywhere in
//!   `[0, 1]`): then phi is printed but is no result, and a warning names the group.
//! - **Uncertainty of phi**: the r_trans interval over the bracket and
//!   `u -+ sigma_u`, projected, widened by `s_P = 0.1 um`, then by the 1-sigma
//!   Wilson interval of the finite sample, end to end ([`predict_phi`]).
//! - **Velocity of a pressure group**: the 10 mm row of `--observed`; without it,
//!   the mean and standard deviation of the entering cells' velocities.
//! - **Slipper offsets**: the two highest peaks of the slipper-only density at
//!   10 mm, refined by a parabola through the log-density; simulated |y| and |z|
//!   of tank-treading slippers, all start shapes pooled, equal weight per run.

pub mod fraction;
pub mod input;
pub mod next;
pub mod offset;
pub mod threshold;
pub mod transit;

use crate::error::AnalysisError;
use crate::simulated::phase::{phase_points, start_shapes};
use crate::simulated::threshold::{thresholds, Threshold};
use crate::types::prediction::{ExperimentOffset, PredictConfig, Prediction, PressureGroup};
use rbc_schema::results::RunRecord;
use rbc_schema::tables::{self, EntryRow, KdeRow, PredictionRow, SummaryRow, ThresholdRow};
use std::path::{Path, PathBuf};

pub use fraction::{predict_phi, y_trans};
pub use input::pressure_groups;
pub use offset::{simulated_offsets, slipper_offset};
pub use threshold::ThresholdCurve;

/// Everything [`predict`] needs, already read from disk (paths for error messages).
pub struct PredictInputs<'a> {
    pub runs: &'a [RunRecord],
    pub sims_path: &'a Path,
    pub entry: &'a [EntryRow],
    pub entry_path: &'a Path,
    pub observed: Option<(&'a [SummaryRow], &'a Path)>,
    /// The experiment's densities (`kde.csv`), for the slipper offsets.
    pub kde: Option<&'a [KdeRow]>,
}

/// Run the prediction: phase diagram, thresholds, phi per start shape and
/// pressure group, slipper offsets.
///
/// Errors: no finished croissant/slipper run in the simulations, no entering
/// cell, non-finite values in the tables (each naming the file).
pub fn predict(inputs: &PredictInputs, config: PredictConfig) -> Result<Prediction, AnalysisError> {
    if !(config.velocity_rel_tol >= 0.0 && config.velocity_rel_tol.is_finite()) {
        return Err(AnalysisError::Input { path: inputs.sims_path.into(), message: format!("velocity tolerance {} must be >= 0", config.velocity_rel_tol) });
    }
    let (points, skipped) = phase_points(inputs.runs);
    let thresholds = thresholds(&points, config.velocity_rel_tol);
    if thresholds.is_empty() {
        return Err(AnalysisError::Input {
            path: inputs.sims_path.into(),
            message: format!(
                "no finished run ended as croissant or slipper ({} runs, {} skipped as failed/running/unsteady)",
                inputs.runs.len(),
                skipped.len()
            ),
        });
    }
    let (groups, mut warnings) = pressure_groups(inputs.entry, inputs.entry_path, inputs.observed)?;
    let mut rows = Vec::new();
    let mut phis = Vec::new();
    let mut next_runs = Vec::new();
    let mut next_run_notes = Vec::new();
    for shape in start_shapes(&points) {
        let Some(curve) = ThresholdCurve::new(&thresholds, &shape) else { continue };
        let velocities: Vec<(String, f64)> = points.iter().filter(|p| p.start_shape == shape).map(|p| (p.run_id.clone(), p.velocity_mm_s)).collect();
        for g in &groups {
            match next::next_run(&curve, &shape, g, inputs.runs, &velocities, config.velocity_rel_tol) {
                Ok(Some(n)) => next_runs.push(n),
                Ok(None) => {}
                Err(why) => next_run_notes.push(why),
            }
            let phi = predict_phi(&curve, &g.entry_y_um, g.velocity_mm_s, g.velocity_std_mm_s, config.position_uncertainty_um);
            if phi.status() == "unbracketed" {
                warnings.push(format!(
                    "start shape {shape}, {} mbar: the simulated runs do not bracket the croissant-slipper switch at {:.3} +- {:.3} mm/s (r_trans in [{:.3}, {:.3}] um, phi in [{:.3}, {:.3}]): phi = {:.3} is not a result (status unbracketed); simulate runs either side of the switch at this velocity",
                    g.pressure_mbar,
                    g.velocity_mm_s,
                    g.velocity_std_mm_s,
                    phi.r_lo_um,
                    phi.r_hi_um,
                    phi.phi_lo,
                    phi.phi_hi,
                    phi.phi
                ));
            } else if phi.extrapolated {
                warnings.push(format!(
                    "start shape {shape}, {} mbar: velocity {:.3} +- {:.3} mm/s reaches outside the simulated range {:.3}..{:.3} mm/s (nearest column used)",
                    g.pressure_mbar,
                    g.velocity_mm_s,
                    g.velocity_std_mm_s,
                    curve.nodes()[0].velocity_mm_s,
                    curve.nodes()[curve.nodes().len() - 1].velocity_mm_s
                ));
            }
            rows.push(PredictionRow {
                start_shape: shape.clone(),
                pressure_mbar: g.pressure_mbar,
                velocity_mm_s: g.velocity_mm_s,
                velocity_std_mm_s: g.velocity_std_mm_s,
                r_trans_um: phi.r_trans_um,
                y_trans_um: phi.y_trans_um,
                phi: phi.phi,
                phi_lo: phi.phi_lo,
                phi_hi: phi.phi_hi,
                phi_observed: g.observed.as_ref().map(|o| o.frac_croissant),
                status: phi.status().into(),
            });
            phis.push(phi);
        }
    }
    let experiment_offsets = inputs.kde.map(|k| experiment_offsets(k, &groups)).unwrap_or_default();
    let simulated_offsets = simulated_offsets(&points, config.velocity_rel_tol);
    next_runs.sort_by_key(|r| std::cmp::Reverse(r.undecided));
    Ok(Prediction { points, skipped, thresholds, groups, rows, phis, experiment_offsets, simulated_offsets, next_runs, next_run_notes, warnings, config })
}

/// Slipper offsets of every pressure group whose slipper-only density (the
/// position closest to 10 mm among positions > 0) has a peak on each side.
/// The velocity is the group's (see [`VelocitySource`](crate::types::prediction::VelocitySource)).
pub fn experiment_offsets(kde: &[KdeRow], groups: &[PressureGroup]) -> Vec<ExperimentOffset> {
    let mut out = Vec::new();
    for g in groups {
        let slip: Vec<&KdeRow> = kde
            .iter()
            .filter(|r| r.shape == "slipper" && r.position_mm > 0.0 && (r.pressure_mbar - g.pressure_mbar).abs() <= 1e-6 * g.pressure_mbar.abs().max(1.0))
            .collect();
        let Some(pos) = slip
            .iter()
            .map(|r| r.position_mm)
            .min_by(|a, b| (a - input::OBSERVED_POSITION_MM).abs().total_cmp(&(b - input::OBSERVED_POSITION_MM).abs()))
        else {
            continue;
        };
        let mut pts: Vec<(f64, f64)> = slip.iter().filter(|r| r.position_mm == pos).map(|r| (r.y_um, r.density)).collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (y, d): (Vec<f64>, Vec<f64>) = pts.into_iter().unzip();
        if let Some((l, r)) = offset::density_peaks(&y, &d) {
            out.push(ExperimentOffset {
                pressure_mbar: g.pressure_mbar,
                position_mm: pos,
                velocity_mm_s: g.velocity_mm_s,
                velocity_std_mm_s: g.velocity_std_mm_s,
                y_l_um: l,
                y_r_um: r,
                offset_um: 0.5 * (r - l),
            });
        }
    }
    out
}

/// Write the transit-matched prediction (`rbc-predict --transit-mm D`, [`transit`]) beside the
/// others: `thresholds_transit_<D>mm.csv` and `prediction_transit_<D>mm.csv`, the columns of
/// `thresholds.csv` and `prediction.csv`; each file atomically. Returns the paths written.
pub fn write_transit_outputs(pred: &Prediction, distance_mm: f64, out: &Path) -> Result<Vec<PathBuf>, AnalysisError> {
    let key = rbc_schema::results::transit_key(distance_mm);
    let th = out.join(format!("thresholds_transit_{key}.csv"));
    tables::write_table(&th, &threshold_rows(&pred.thresholds), tables::columns::THRESHOLDS)?;
    let pr = out.join(format!("prediction_transit_{key}.csv"));
    tables::write_table(&pr, &pred.rows, tables::columns::PREDICTION)?;
    Ok(vec![th, pr])
}

/// `thresholds.csv` rows.
pub fn threshold_rows(thresholds: &[Threshold]) -> Vec<ThresholdRow> {
    thresholds
        .iter()
        .map(|t| ThresholdRow {
            start_shape: t.start_shape.clone(),
            velocity_mm_s: t.velocity_mm_s,
            r_trans_um: t.r_trans_um,
            r_lo_um: t.r_lo_um,
            r_hi_um: t.r_hi_um,
        })
        .collect()
}

/// One row of `slipper_offsets.csv` (an extra output): a simulated velocity
/// column or a measured pressure group. Empty cells where a value does not apply.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OffsetRow {
    /// `simulation` (mean |y| of tank-treading slippers) or `experiment` ((y_r - y_l) / 2).
    pub source: String,
    /// Pressure group (experiment only).
    pub pressure_mbar: Option<f64>,
    pub velocity_mm_s: f64,
    /// Simulation: min / max velocity over the runs; experiment: u -+ sigma_u.
    pub velocity_lo_mm_s: f64,
    pub velocity_hi_mm_s: f64,
    /// Off-centre position along y, um, and its bar (simulation: extremes over runs; experiment: -+ s_P).
    pub offset_um: f64,
    pub offset_lo_um: f64,
    pub offset_hi_um: f64,
    /// Simulation: mean |z| of the slippers, um.
    pub abs_z_um: Option<f64>,
    /// Experiment: the two peaks of the slipper-only density, um.
    pub y_l_um: Option<f64>,
    pub y_r_um: Option<f64>,
    /// Simulation: number of runs in the column.
    pub n_runs: Option<usize>,
}

/// Header of `slipper_offsets.csv`.
pub const OFFSET_COLUMNS: &[&str] = &[
    "source", "pressure_mbar", "velocity_mm_s", "velocity_lo_mm_s", "velocity_hi_mm_s", "offset_um", "offset_lo_um",
    "offset_hi_um", "abs_z_um", "y_l_um", "y_r_um", "n_runs",
];

/// `slipper_offsets.csv` rows: simulated columns, then measured groups.
pub fn offset_rows(pred: &Prediction) -> Vec<OffsetRow> {
    let s_p = pred.config.position_uncertainty_um;
    let sim = pred.simulated_offsets.iter().map(|s| OffsetRow {
        source: "simulation".into(),
        pressure_mbar: None,
        velocity_mm_s: s.velocity_mm_s,
        velocity_lo_mm_s: s.velocity_min_mm_s,
        velocity_hi_mm_s: s.velocity_max_mm_s,
        offset_um: s.abs_y_um,
        offset_lo_um: s.abs_y_min_um,
        offset_hi_um: s.abs_y_max_um,
        abs_z_um: Some(s.abs_z_um),
        y_l_um: None,
        y_r_um: None,
        n_runs: Some(s.n_runs),
    });
    let exp = pred.experiment_offsets.iter().map(|e| OffsetRow {
        source: "experiment".into(),
        pressure_mbar: Some(e.pressure_mbar),
        velocity_mm_s: e.velocity_mm_s,
        velocity_lo_mm_s: e.velocity_mm_s - e.velocity_std_mm_s,
        velocity_hi_mm_s: e.velocity_mm_s + e.velocity_std_mm_s,
        offset_um: e.offset_um,
        offset_lo_um: e.offset_um - s_p,
        offset_hi_um: e.offset_um + s_p,
        abs_z_um: None,
        y_l_um: Some(e.y_l_um),
        y_r_um: Some(e.y_r_um),
        n_runs: None,
    });
    sim.chain(exp).collect()
}

/// Whether `name` (an entry of the output folder) is one of `rbc-predict`'s outputs: its tables
/// (also those of any `--transit-mm` distance) and its `figures/` folder. The command replaces
/// these as one set ([`rbc_schema::output_set`]).
pub fn is_output_name(name: &str) -> bool {
    let transit = |prefix: &str| name.strip_prefix(prefix).is_some_and(|rest| rest.ends_with("mm.csv"));
    matches!(name, "thresholds.csv" | "prediction.csv" | "slipper_offsets.csv" | "next_runs.csv" | "figures")
        || transit("thresholds_transit_")
        || transit("prediction_transit_")
}

/// Write `thresholds.csv`, `prediction.csv`, `slipper_offsets.csv` and `next_runs.csv` into `out`, each file
/// atomically (the figures: [`crate::plot::prediction::write_figures`]). Returns the paths written.
pub fn write_outputs(pred: &Prediction, out: &Path) -> Result<Vec<PathBuf>, AnalysisError> {
    let mut written = Vec::new();
    let th = out.join("thresholds.csv");
    tables::write_table(&th, &threshold_rows(&pred.thresholds), tables::columns::THRESHOLDS)?;
    written.push(th);
    let pr = out.join("prediction.csv");
    tables::write_table(&pr, &pred.rows, tables::columns::PREDICTION)?;
    written.push(pr);
    let of = out.join("slipper_offsets.csv");
    tables::write_table(&of, &offset_rows(pred), OFFSET_COLUMNS)?;
    written.push(of);
    let nx = out.join("next_runs.csv");
    tables::write_table(&nx, &pred.next_runs, crate::types::prediction::NEXT_RUN_COLUMNS)?;
    written.push(nx);
    Ok(written)
}
