//! The prediction's results (`rbc-predict`), shared by [`crate::predict`], which computes them, and
//! [`crate::plot`], which draws them.

use crate::simulated::phase::{PhasePoint, SkippedRun, DEFAULT_VELOCITY_REL_TOL};
use crate::simulated::threshold::Threshold;
use rbc_schema::tables::PredictionRow;
use serde::Serialize;

/// Position uncertainty of the experiment's y, um (paper, SI; physics.md "Prediction").
pub const POSITION_UNCERTAINTY_UM: f64 = 0.1;

/// Settings of a prediction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PredictConfig {
    /// Relative tolerance of the velocity binning ([`DEFAULT_VELOCITY_REL_TOL`]).
    pub velocity_rel_tol: f64,
    /// Position uncertainty of the experiment, um ([`POSITION_UNCERTAINTY_UM`]).
    pub position_uncertainty_um: f64,
}

impl Default for PredictConfig {
    fn default() -> Self {
        PredictConfig { velocity_rel_tol: DEFAULT_VELOCITY_REL_TOL, position_uncertainty_um: POSITION_UNCERTAINTY_UM }
    }
}

/// Observed shape fractions of one pressure group downstream.
#[derive(Debug, Clone, PartialEq)]
pub struct Observed {
    /// Position of the summary row used (the one closest to 10 mm among positions > 0), mm.
    pub position_mm: f64,
    pub n_cells: u64,
    pub frac_croissant: f64,
    /// Interval of `frac_croissant`: the summary's own (Wilson 95 %) when present,
    /// else a Wilson 95 % interval from `n_cells`.
    pub frac_croissant_lo: f64,
    pub frac_croissant_hi: f64,
    pub velocity_mean_mm_s: f64,
    pub velocity_std_mm_s: f64,
}

/// Where a group's velocity comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VelocitySource {
    /// `summary.csv` downstream (the velocity of the steady shapes, as in the paper).
    Observed,
    /// Mean and standard deviation of the entering cells' velocities in `entry.csv`
    /// (used without `--observed`; cells at the entrance have not reached their
    /// steady shape, so this is an approximation).
    Entry,
}

/// One pressure drop: the entering cells' y and the group's velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct PressureGroup {
    pub pressure_mbar: f64,
    /// Mean cell velocity, mm/s, and its standard deviation sigma_u.
    pub velocity_mm_s: f64,
    pub velocity_std_mm_s: f64,
    pub velocity_source: VelocitySource,
    /// y of every isolated cell entering the channel, um.
    pub entry_y_um: Vec<f64>,
    pub observed: Option<Observed>,
}

/// Simulated tank-treading slipper positions of one velocity column, all start shapes pooled
/// (the paper's Fig. 6a shows the positions do not depend on the start shape).
#[derive(Debug, Clone, PartialEq)]
pub struct SimulatedOffset {
    /// Mean of the runs' mean velocities, and the extreme min / max velocities, mm/s.
    pub velocity_mm_s: f64,
    pub velocity_min_mm_s: f64,
    pub velocity_max_mm_s: f64,
    /// Mean over runs of |mean y| and |mean z|, with their extremes over runs, um.
    pub abs_y_um: f64,
    pub abs_y_min_um: f64,
    pub abs_y_max_um: f64,
    pub abs_z_um: f64,
    pub abs_z_min_um: f64,
    pub abs_z_max_um: f64,
    pub n_runs: usize,
}

/// The experiment's slipper off-centre position of one pressure group.
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentOffset {
    pub pressure_mbar: f64,
    pub position_mm: f64,
    pub velocity_mm_s: f64,
    pub velocity_std_mm_s: f64,
    pub y_l_um: f64,
    pub y_r_um: f64,
    /// `(y_r - y_l) / 2`, um.
    pub offset_um: f64,
}

/// The result of [`crate::predict::predict`].
#[derive(Debug, Clone)]
pub struct Prediction {
    pub points: Vec<PhasePoint>,
    pub skipped: Vec<SkippedRun>,
    pub thresholds: Vec<Threshold>,
    pub groups: Vec<PressureGroup>,
    /// One row per start shape x pressure group (start shapes in [`crate::simulated::phase::start_shapes`] order).
    pub rows: Vec<PredictionRow>,
    /// The full prediction behind each row (same order as `rows`).
    pub phis: Vec<Phi>,
    pub experiment_offsets: Vec<ExperimentOffset>,
    pub simulated_offsets: Vec<SimulatedOffset>,
    /// The runs to simulate next ([`crate::predict::next`]), most undecided cells first.
    pub next_runs: Vec<NextRun>,
    /// Why a group with undecided cells got no next run (its own list: a prediction from the
    /// runs' transit records computes the runs too, but its warnings are about its thresholds).
    pub next_run_notes: Vec<String>,
    /// Things the user should know (skipped runs are in `skipped`).
    pub warnings: Vec<String>,
    pub config: PredictConfig,
}

/// The prediction for one start shape and one pressure group.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phi {
    /// r_trans at the group's mean velocity, um.
    pub r_trans_um: f64,
    pub y_trans_um: f64,
    pub phi: f64,
    pub phi_lo: f64,
    pub phi_hi: f64,
    /// r_trans interval over the bracket and `u +- sigma_u`, um.
    pub r_lo_um: f64,
    pub r_hi_um: f64,
    /// The velocity range left the simulated range.
    pub extrapolated: bool,
}

impl Phi {
    /// Whether phi is a result (`prediction.csv` column `status`):
    /// - `unbracketed`: the r_trans interval is `[0, inf]` (no run bracketed the switch at these
    ///   velocities: a croissant-only column next to a slipper-only one, or one run), or phi's
    ///   interval is all of `[0, 1]`: phi is no result;
    /// - `extrapolated`: the group's velocities `u -+ sigma_u` leave the simulated range (the
    ///   nearest column was used);
    /// - `bracketed`: otherwise.
    pub fn status(&self) -> &'static str {
        if (self.r_lo_um <= 0.0 && self.r_hi_um == f64::INFINITY) || (self.phi_lo <= 0.0 && self.phi_hi >= 1.0) {
            "unbracketed"
        } else if self.extrapolated {
            "extrapolated"
        } else {
            "bracketed"
        }
    }
}

/// One suggested run (a row of `next_runs.csv`, [`NEXT_RUN_COLUMNS`]), computed by
/// [`crate::predict::next`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NextRun {
    pub start_shape: String,
    /// The pressure group whose prediction it narrows.
    pub pressure_mbar: f64,
    /// The cell velocity the run is for (mm/s): the joined column's or the group's.
    pub velocity_mm_s: f64,
    /// The mean flow to impose for it (mm/s), `None` (an empty cell) when unknown
    /// ([`crate::predict::next`], "Mean flow").
    pub mean_flow_mm_s: Option<f64>,
    /// The start offset (um).
    pub r_init_um: f64,
    /// The bracket of r_trans it splits (um): the largest croissant start, the smallest slipper
    /// start (`inf` where none).
    pub r_lo_um: f64,
    pub r_hi_um: f64,
    /// The group's entering cells, and those of them the bracket leaves undecided.
    pub cells: usize,
    pub undecided: usize,
    /// `joins` (a simulated column within the velocity tolerance) or `new`.
    pub column: String,
    /// A run of this start shape still going that will narrow the same bracket, or empty.
    pub awaits: String,
}

/// Columns of `next_runs.csv`, in order.
pub const NEXT_RUN_COLUMNS: &[&str] = &[
    "start_shape", "pressure_mbar", "velocity_mm_s", "mean_flow_mm_s", "r_init_um", "r_lo_um", "r_hi_um", "cells", "undecided", "column",
    "awaits",
];
