//! The records a results file holds, as the readers return them and the writers take them: a run's status, attributes, summary, time samples, snapshots and transits.

use std::collections::BTreeMap;

/// Status of a run, the `status` attribute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RunStatus {
    /// Started, not finished (or killed before finishing).
    Running,
    /// Converged to a steady shape and position.
    Steady,
    /// Converged to a periodic motion (e.g. a tank-treading slipper with contractions).
    Periodic,
    /// Reached its end time without converging.
    Unsteady,
    /// Stopped by an error (blow-up, solver failure); see the `failure` attribute.
    Failed,
    /// Not run: the cell's start position puts it into (or closer than the solver's gap to) the
    /// channel wall (a sweep's largest offsets; the paper's dashed line). No rows, no snapshots;
    /// the `not_run` attribute says where it overlaps.
    OverlapsWall,
}

impl RunStatus {
    /// The attribute value.
    pub fn as_str(self) -> &'static str {
        match self {
            RunStatus::Running => "running",
            RunStatus::Steady => "steady",
            RunStatus::Periodic => "periodic",
            RunStatus::Unsteady => "unsteady",
            RunStatus::Failed => "failed",
            RunStatus::OverlapsWall => "overlaps-wall",
        }
    }

    /// Parse an attribute value.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "running" => RunStatus::Running,
            "steady" => RunStatus::Steady,
            "periodic" => RunStatus::Periodic,
            "unsteady" => RunStatus::Unsteady,
            "failed" => RunStatus::Failed,
            "overlaps-wall" => RunStatus::OverlapsWall,
            _ => return None,
        })
    }

    /// True for the end states that carry a [`RunSummary`] (steady, periodic, unsteady).
    pub fn is_finished(self) -> bool {
        matches!(self, RunStatus::Steady | RunStatus::Periodic | RunStatus::Unsteady)
    }
}

/// Final shape class of a finished run, the `final_shape` attribute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FinalShape {
    Croissant,
    Slipper,
    Other,
}

impl FinalShape {
    /// The attribute value.
    pub fn as_str(self) -> &'static str {
        match self {
            FinalShape::Croissant => "croissant",
            FinalShape::Slipper => "slipper",
            FinalShape::Other => "other",
        }
    }

    /// Parse an attribute value.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "croissant" => FinalShape::Croissant,
            "slipper" => FinalShape::Slipper,
            "other" => FinalShape::Other,
            _ => return None,
        })
    }
}

/// What is known when a run starts (written by [`super::ResultsFile::begin_run`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RunAttrs {
    /// `discocyte`, `croissant`, `slipper`, ...
    pub start_shape: String,
    /// Initial centroid offset from the channel axis, um.
    pub r_init_um: f64,
    /// Initial centroid y (across the width), um.
    pub y_init_um: f64,
    /// Initial centroid z (across the height), um.
    pub z_init_um: f64,
    /// Viscosity ratio inside / outside.
    pub lambda: f64,
    /// The full scene TOML this run was started from.
    pub scene: String,
}

/// What is known when a run ends normally (written by [`super::RunWriter::finish`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// Steady, periodic or unsteady (running and failed are refused by `finish`).
    pub status: RunStatus,
    pub final_shape: FinalShape,
    pub tank_treading: bool,
    pub tumbling: bool,
    /// Mean centroid velocity along x over the steady window, mm/s.
    pub mean_velocity_mm_s: f64,
    pub min_velocity_mm_s: f64,
    pub max_velocity_mm_s: f64,
    /// Mean of `sqrt(y^2 + z^2)` of the centroid over the steady window, um.
    pub mean_radial_um: f64,
    /// Mean centroid y, um (signed).
    pub mean_y_um: f64,
    /// Mean centroid z, um (signed).
    pub mean_z_um: f64,
    /// The classifier's evidence (symmetry measures, tank-treading frequency...),
    /// stored as attributes `evidence_<name>`.
    pub evidence: BTreeMap<String, f64>,
}

/// One row of `timeseries/`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeSample {
    /// Physical time, s.
    pub t_s: f64,
    /// Centroid (x, y, z), um.
    pub centroid_um: [f64; 3],
    /// Centroid velocity, mm/s.
    pub velocity_mm_s: [f64; 3],
    /// Membrane area, um^2.
    pub area_um2: f64,
    /// Enclosed volume, um^3.
    pub volume_um3: f64,
    /// Asphericity of the gyration tensor (0 for a sphere).
    pub asphericity: f64,
    /// Bounding-box lengths along x, y, z, um.
    pub extents_um: [f64; 3],
}

/// Snapshots of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshots {
    /// Time of each snapshot, s.
    pub times_s: Vec<f64>,
    /// Vertex positions of each snapshot, um.
    pub vertices_um: Vec<Vec<[f64; 3]>>,
    /// Triangles (0-based vertex indices), the same for every snapshot.
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex scalar fields by name, one row of `nv` values per snapshot (empty for runs
    /// written without them).
    pub fields: BTreeMap<String, Vec<Vec<f64>>>,
}

/// Where a run's snapshots lie in `results.h5` (read by [`super::ResultsFile::snapshot_layout`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SnapshotLayout {
    /// Time of each complete snapshot, s (snapshots whose time was not written are left out).
    pub times_s: Vec<f64>,
    /// Rows of `vertices_um` (the first dimension; at least `times_s.len()`).
    pub rows: usize,
    /// Vertices per snapshot.
    pub n_vertices: usize,
    /// Rows of `triangles`.
    pub n_triangles: usize,
    /// Per-vertex fields stored beside the positions (`snapshots/<name>`, f64, `[k, nv]` or
    /// `[k, nv, 3]`) with a row for every snapshot, in name order.
    pub fields: Vec<VertexField>,
}

/// A per-vertex dataset of `snapshots/`.
#[derive(Debug, Clone, PartialEq)]
pub struct VertexField {
    /// Dataset name (the attribute name in XDMF).
    pub name: String,
    /// 1 (`[k, nv]`, a scalar) or 3 (`[k, nv, 3]`, a vector).
    pub components: usize,
    /// Rows of the dataset (the first dimension).
    pub rows: usize,
}

/// The cell as an experiment downstream would see it: when its centroid has travelled
/// `distance_mm` along the channel from its start (the paper's experiments film 0 mm and 10 mm
/// after the entrance, i.e. after `t = 10 mm / u`, not at the steady state).
#[derive(Debug, Clone, PartialEq)]
pub struct Transit {
    /// Distance travelled along x (mm).
    pub distance_mm: f64,
    /// Time at which it was reached (s).
    pub t_s: f64,
    /// Centroid then (um).
    pub x_um: f64,
    pub y_um: f64,
    pub z_um: f64,
    /// Centroid velocity along x then (mm/s).
    pub velocity_mm_s: f64,
    /// The shape label then.
    pub shape: FinalShape,
    /// The run had ended steady or periodic before it travelled `distance_mm`, and this record is
    /// its steady state carried to that distance: the final label, the steady window's mean y, z
    /// and velocity, `x_um` = first sample's x + `distance_mm`, `t_s` = the end + the rest of the
    /// distance at the mean velocity. A steady state does not change downstream by definition
    /// (`rbc_solver::steady`: within the sweep's tolerances over its window), so this is what the
    /// cell shows there without simulating the way. `false`: recorded as the cell passed.
    pub from_steady: bool,
}

/// The attribute infix of a transit distance: `10mm`, `0mm`, `2.5mm` -> `2p5mm`.
pub fn transit_key(distance_mm: f64) -> String {
    format!("{distance_mm}mm").replace('.', "p")
}

/// One run as listed by [`super::read_runs`].
#[derive(Debug, Clone, PartialEq)]
pub struct RunRecord {
    pub run_id: String,
    pub status: RunStatus,
    /// `None` only for a run that crashed while it was being created (status running or failed).
    pub attrs: Option<RunAttrs>,
    /// `Some` exactly when `status.is_finished()`.
    pub summary: Option<RunSummary>,
    /// Diagnosis of a failed run.
    pub failure: Option<String>,
    /// Why a run was not run (status `overlaps-wall`: where the cell meets the wall).
    pub not_run: Option<String>,
    /// Where an ended run's data were copied from (a start shape, [`crate::start_shape`]).
    pub copied_from: Option<String>,
    /// Transit records, by increasing distance (any status: a running run has those it passed).
    pub transits: Vec<Transit>,
    pub n_samples: usize,
    pub n_snapshots: usize,
}
