//! `results.h5`: many simulation runs in one HDF5 file (layout, writer, reader, schema_version).
//!
//! # Layout (schema_version 1)
//!
//! ```text
//! /                          attrs: schema_version (u32 = 1), created_by (string)
//! /runs/<run_id>/            attrs, written by begin_run:
//!                              start_shape (string: discocyte|croissant|slipper|...)
//!                              r_init_um, y_init_um, z_init_um (f64, um; z = 5 y / 9 in the paper)
//!                              lambda (f64, viscosity ratio mu_in / mu)
//!                              scene (string: the full scene TOML)
//!                              status (string: running, then steady|periodic|unsteady|failed;
//!                                or overlaps-wall: never run, see record_overlaps_wall)
//!                            attrs, written by finish (absent while running or after a failure):
//!                              final_shape (string: croissant|slipper|other)
//!                              tank_treading, tumbling (HDF5 enum bool; numpy bool in h5py)
//!                              mean_velocity_mm_s, min_velocity_mm_s, max_velocity_mm_s (f64, mm/s,
//!                                mean / min / max of the centroid's x-velocity over the steady window)
//!                              mean_radial_um, mean_y_um, mean_z_um (f64, um; mean of
//!                                sqrt(y^2 + z^2), y and z of the centroid over the steady window)
//!                              evidence_<name> (f64, optional: the classifier's evidence, e.g.
//!                                evidence_mirror_y, evidence_tt_frequency_hz)
//!                            attrs, written by fail: failure (string, the diagnosis)
//!                            attrs, written by record_overlaps_wall (a sweep's run whose cell
//!                              starts in or too close to the channel wall): not_run (string,
//!                              where it overlaps); such a run has no timeseries/ or snapshots/
//!                              group, and its readers return no rows and no snapshots
//!                            attrs, written by set_transit when the cell has travelled D mm
//!                              (optional, any status; D as written by [`transit_key`], e.g. 10mm):
//!                              transit_<D>_t_s (f64, s), transit_<D>_x_um, transit_<D>_y_um,
//!                              transit_<D>_z_um (f64, um: the centroid), transit_<D>_velocity_mm_s
//!                              (f64, mm/s), transit_<D>_shape (string: croissant|slipper|other),
//!                              transit_<D>_from_steady (HDF5 enum bool, optional, absent = false:
//!                              the run had ended steady or periodic before D; the record is its
//!                              steady state carried to D, see [`Transit::from_steady`])
//!                            copied_from (string, optional): where an ended run's data were
//!                              copied from (a start shape, [`crate::start_shape`])
//! /runs/<run_id>/timeseries/ one row per sample, chunked and resizable along the first axis:
//!                              t_s[n], centroid_um[n,3], velocity_mm_s[n,3], area_um2[n],
//!                              volume_um3[n], asphericity[n], extents_um[n,3] (bounding box
//!                              lengths along x, y, z)
//! /runs/<run_id>/snapshots/  times_s[k] (chunked, resizable), vertices_um[k,nv,3] (chunked
//!                              [1,nv,3], resizable along k), triangles[nt,3] (u32, vertex indices,
//!                              0-based, outward orientation); optional per-vertex fields
//!                              <name>[k,nv] (f64, chunked [1,nv], resizable along k), present
//!                              from a run's first snapshot on or never (see
//!                              [`RunWriter::append_snapshot_with`]): the solver writes
//!                              mean_curvature_per_um (1/um, cotangent formula, positive on a
//!                              sphere); runs written before it have none
//! ```
//!
//! A running run may have a checkpoint beside the file (`<file name>.<run_id>.ckpt`,
//! layout and crash-safety argument in [`crate::checkpoint`]); it is not part of
//! this layout, so `schema_version` stays 1. It is deleted when the run fails. A run that ends
//! keeps the one of its end state: `rbc-simulate` when the run reached its end time (status
//! `unsteady`), from which a later end time continues the run; a sweep's run at its verdict or
//! its largest time (since session 28), from which `rbc-sweep reopen` continues it.
//!
//! All floating-point values are `f64` (little-endian IEEE), strings are
//! variable-length UTF-8, so the file reads directly with h5py:
//! `h5py.File(p)["runs/r0/timeseries/centroid_um"][:]` is an `(n, 3)` array,
//! `f["runs/r0"].attrs["status"]` a `str` (checked by `data-schema/tests/results_h5py.rs`).
//!
//! # Writing incrementally
//!
//! A running simulation opens the file with [`ResultsFile::create_or_open`],
//! starts a run with [`ResultsFile::begin_run`] (status `running`), appends
//! samples and snapshots with [`RunWriter::append_sample`] and
//! [`RunWriter::append_snapshot`] (samples are buffered and written in blocks,
//! snapshots at once; each write resizes the datasets), calls
//! [`RunWriter::flush`] at each checkpoint, and ends with [`RunWriter::finish`]
//! or [`RunWriter::fail`]. After a kill, [`ResultsFile::resume_run`] reopens the
//! run and [`RunWriter::truncate_to`] (or [`RunWriter::truncate_after`]) drops
//! samples written after the last checkpoint. Runs from several files are combined with [`merge_files`].
//!
//! # Reading
//!
//! [`read_runs`] lists every run with its attributes; it does not fail on a run
//! that failed or is still running (its summary is `None`). [`read_timeseries`]
//! and [`read_snapshots`] read one run's arrays. Every reader checks the root
//! `schema_version` and refuses an unknown one with [`SchemaError::SchemaVersion`].
//!
//! HDF5 1.10 locks files: a reader cannot open a file a simulation holds open
//! for writing unless `HDF5_USE_FILE_LOCKING=FALSE` is set in its environment.

use crate::error::{Result, SchemaError};
use hdf5::types::VarLenUnicode;
use hdf5::{Dataset, File, Group, H5Type};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The layout version this build writes and reads.
pub const SCHEMA_VERSION: u32 = 1;

/// Rows per chunk of the timeseries datasets (a chunk of `centroid_um` is 6 KiB).
const TIMESERIES_CHUNK: usize = 256;

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

/// What is known when a run starts (written by [`ResultsFile::begin_run`]).
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

/// What is known when a run ends normally (written by [`RunWriter::finish`]).
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

/// Where a run's snapshots lie in `results.h5` (read by [`ResultsFile::snapshot_layout`]).
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

/// One run as listed by [`read_runs`].
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

fn h5err(path: &Path, context: &str, e: hdf5::Error) -> SchemaError {
    let msg = e.to_string().replace('\n', " ");
    // (HDF5 says "unable to lock file" for a lock and "truncated file" for a short one; a bare
    // "lock" would also match the "sblock" of the truncation message)
    let hint = if msg.contains("unable to lock file") || msg.contains("file locking") {
        " (another process has the file open for writing, e.g. a running simulation; set HDF5_USE_FILE_LOCKING=FALSE to read it anyway)"
    } else if msg.contains("truncated file") {
        " (the file is cut short: an interrupted copy or write; copy it again, or restore it from its backup)"
    } else {
        ""
    };
    SchemaError::Hdf5 { path: path.into(), message: format!("{context}: {msg}{hint}") }
}

pub(crate) fn invalid(path: &Path, message: impl Into<String>) -> SchemaError {
    SchemaError::Invalid { path: path.into(), message: message.into() }
}

// ---------------------------------------------------------------- attributes

fn set_str(path: &Path, loc: &hdf5::Location, name: &str, value: &str) -> Result<()> {
    let v: VarLenUnicode = value
        .parse()
        .map_err(|e| invalid(path, format!("attribute `{name}`: {e}")))?;
    set_attr(path, loc, name, &v)
}

fn set_attr<T: H5Type>(path: &Path, loc: &hdf5::Location, name: &str, value: &T) -> Result<()> {
    if loc.attr(name).is_ok() {
        loc.delete_attr(name).map_err(|e| h5err(path, name, e))?;
    }
    loc.new_attr::<T>()
        .shape(())
        .create(name)
        .and_then(|a| a.write_scalar(value))
        .map_err(|e| h5err(path, name, e))
}

/// The attributes of a transit record (layout in the module documentation); overwrites.
fn write_transit(p: &Path, g: &hdf5::Group, t: &Transit) -> Result<()> {
    let k = transit_key(t.distance_mm);
    set_f64(p, g, &format!("transit_{k}_t_s"), t.t_s)?;
    set_f64(p, g, &format!("transit_{k}_x_um"), t.x_um)?;
    set_f64(p, g, &format!("transit_{k}_y_um"), t.y_um)?;
    set_f64(p, g, &format!("transit_{k}_z_um"), t.z_um)?;
    set_f64(p, g, &format!("transit_{k}_velocity_mm_s"), t.velocity_mm_s)?;
    let steady = format!("transit_{k}_from_steady");
    if t.from_steady {
        set_attr(p, g, &steady, &true)?;
    } else if has_attr(g, &steady) {
        g.delete_attr(&steady).map_err(|e| h5err(p, &steady, e))?;
    }
    set_str(p, g, &format!("transit_{k}_shape"), t.shape.as_str())
}

/// The start attributes of a run (see the layout).
fn set_start_attrs(path: &Path, g: &Group, attrs: &RunAttrs) -> Result<()> {
    set_str(path, g, "start_shape", &attrs.start_shape)?;
    set_f64(path, g, "r_init_um", attrs.r_init_um)?;
    set_f64(path, g, "y_init_um", attrs.y_init_um)?;
    set_f64(path, g, "z_init_um", attrs.z_init_um)?;
    set_f64(path, g, "lambda", attrs.lambda)?;
    set_str(path, g, "scene", &attrs.scene)
}

fn set_f64(path: &Path, loc: &hdf5::Location, name: &str, value: f64) -> Result<()> {
    if !value.is_finite() {
        return Err(SchemaError::field(path, name, format!("{value} is not a finite number")));
    }
    set_attr(path, loc, name, &value)
}

fn has_attr(loc: &hdf5::Location, name: &str) -> bool {
    loc.attr_names().map(|n| n.iter().any(|x| x == name)).unwrap_or(false)
}

/// The text of a string attribute, refused (naming `field`) unless it is UTF-8: HDF5 does not check
/// the encoding and hdf5-metno's `as_str` assumes it, so a damaged file must not reach a `String`
/// unchecked (a flipped byte in a run's scene made `rbc-bench fuzz` panic in the TOML parser).
pub(crate) fn utf8_text(path: &Path, field: &str, bytes: &[u8]) -> Result<String> {
    std::str::from_utf8(bytes).map(str::to_string).map_err(|e| SchemaError::field(path, field, format!("not UTF-8 text ({e})")))
}

fn get_str(path: &Path, loc: &hdf5::Location, field: &str, name: &str) -> Result<String> {
    // a variable-length string is read from a global heap collection, where libhdf5 1.10 can loop forever
    let _watch = crate::hdf5_watch::arm(path, || format!("attribute `{field}`"));
    let a = loc.attr(name).map_err(|_| SchemaError::field(path, field, "missing attribute"))?;
    if let Ok(v) = a.read_scalar::<VarLenUnicode>() {
        return utf8_text(path, field, v.as_bytes());
    }
    if let Ok(v) = a.read_scalar::<hdf5::types::VarLenAscii>() {
        return utf8_text(path, field, v.as_bytes());
    }
    Err(SchemaError::field(path, field, "not a string"))
}

fn get_f64(path: &Path, loc: &hdf5::Location, field: &str, name: &str) -> Result<f64> {
    let _watch = crate::hdf5_watch::arm(path, || format!("attribute `{field}`"));
    let a = loc.attr(name).map_err(|_| SchemaError::field(path, field, "missing attribute"))?;
    let v = a.read_scalar::<f64>().map_err(|e| SchemaError::field(path, field, format!("not a number: {e}")))?;
    if !v.is_finite() {
        return Err(SchemaError::field(path, field, format!("{v} is not a finite number")));
    }
    Ok(v)
}

fn get_bool(path: &Path, loc: &hdf5::Location, field: &str, name: &str) -> Result<bool> {
    let _watch = crate::hdf5_watch::arm(path, || format!("attribute `{field}`"));
    let a = loc.attr(name).map_err(|_| SchemaError::field(path, field, "missing attribute"))?;
    if let Ok(v) = a.read_scalar::<bool>() {
        return Ok(v);
    }
    // Files written by other tools may store flags as integers.
    a.read_scalar::<i64>()
        .map(|v| v != 0)
        .map_err(|e| SchemaError::field(path, field, format!("not a boolean: {e}")))
}

/// Check the root `schema_version` attribute (an integer, or a string holding one).
fn check_version(path: &Path, file: &File) -> Result<()> {
    let _watch = crate::hdf5_watch::arm(path, || "attribute `schema_version`".into());
    let a = file
        .attr("schema_version")
        .map_err(|_| SchemaError::SchemaVersion { path: path.into(), found: "none".into(), supported: SCHEMA_VERSION.to_string() })?;
    let found = match a.read_scalar::<i64>() {
        Ok(v) => v.to_string(),
        Err(_) => match a.read_scalar::<VarLenUnicode>() {
            Ok(s) => String::from_utf8_lossy(s.as_bytes()).into_owned(),
            Err(_) => "unreadable".into(),
        },
    };
    if found.trim() != SCHEMA_VERSION.to_string() {
        return Err(SchemaError::SchemaVersion { path: path.into(), found, supported: SCHEMA_VERSION.to_string() });
    }
    Ok(())
}

/// Check that a run id is usable as an HDF5 group name.
fn check_run_id(path: &Path, run_id: &str) -> Result<()> {
    if run_id.is_empty() || run_id.contains('/') || run_id == "." || run_id == ".." {
        return Err(invalid(path, format!("run id `{run_id}` is not a valid group name (empty, `/`, `.` or `..`)")));
    }
    Ok(())
}

// ---------------------------------------------------------------- writer

/// An open `results.h5`, for writing runs (or reading them).
pub struct ResultsFile {
    path: PathBuf,
    file: File,
}

impl ResultsFile {
    /// Open `path` for writing, creating it (with `schema_version` and
    /// `created_by`) when it does not exist; refuses a file of another schema version.
    pub fn create_or_open(path: &Path) -> Result<ResultsFile> {
        Self::create_or_open_by(path, concat!("rbc-toolkit ", env!("CARGO_PKG_VERSION")))
    }

    /// As [`create_or_open`](Self::create_or_open), recording `created_by` (e.g. the command line) in a new file.
    pub fn create_or_open_by(path: &Path, created_by: &str) -> Result<ResultsFile> {
        if path.exists() {
            let file = {
                let _watch = crate::hdf5_watch::arm(path, || "open for writing".into());
                File::open_rw(path).map_err(|e| h5err(path, "open for writing", e))?
            };
            check_version(path, &file)?;
            if !file.link_exists("runs") {
                file.create_group("runs").map_err(|e| h5err(path, "create /runs", e))?;
            }
            return Ok(ResultsFile { path: path.into(), file });
        }
        if let Some(parent) = path.parent() {
            if !parent.as_os_str().is_empty() {
                std::fs::create_dir_all(parent).map_err(|e| SchemaError::io(parent, e))?;
            }
        }
        let file = File::create_excl(path).map_err(|e| h5err(path, "create", e))?;
        set_attr(path, &file, "schema_version", &SCHEMA_VERSION)?;
        set_str(path, &file, "created_by", created_by)?;
        file.create_group("runs").map_err(|e| h5err(path, "create /runs", e))?;
        file.flush().map_err(|e| h5err(path, "flush", e))?;
        Ok(ResultsFile { path: path.into(), file })
    }

    /// Open an existing file read-only (schema_version checked).
    pub fn open(path: &Path) -> Result<ResultsFile> {
        if !path.exists() {
            return Err(SchemaError::io(path, std::io::Error::new(std::io::ErrorKind::NotFound, "no such file")));
        }
        let file = {
            let _watch = crate::hdf5_watch::arm(path, || "open".into());
            File::open(path).map_err(|e| h5err(path, "open", e))?
        };
        check_version(path, &file)?;
        Ok(ResultsFile { path: path.into(), file })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn runs_group(&self) -> Result<Group> {
        self.file.group("runs").map_err(|_| invalid(&self.path, "no /runs group"))
    }

    fn run_group(&self, run_id: &str) -> Result<Group> {
        self.runs_group()?
            .group(run_id)
            .map_err(|_| invalid(&self.path, format!("no run `{run_id}` in /runs")))
    }

    /// Ids of every run, in name order.
    pub fn run_ids(&self) -> Result<Vec<String>> {
        let _reading = crate::hdf5_watch::reading(&self.path, || "listing /runs".into());
        let mut ids = self.runs_group()?.member_names().map_err(|e| h5err(&self.path, "list /runs", e))?;
        ids.sort();
        Ok(ids)
    }

    /// True when `/runs/<run_id>` exists.
    pub fn has_run(&self, run_id: &str) -> bool {
        self.runs_group().map(|g| g.link_exists(run_id)).unwrap_or(false)
    }

    /// Delete a run (e.g. to restart it from scratch). The file does not shrink.
    pub fn remove_run(&mut self, run_id: &str) -> Result<()> {
        self.runs_group()?.unlink(run_id).map_err(|e| h5err(&self.path, &format!("remove run {run_id}"), e))
    }

    /// Start a run: create `/runs/<run_id>` with its start attributes, status `running`,
    /// empty resizable timeseries and snapshot datasets, and the mesh `triangles`.
    /// The vertex count of every snapshot is `max index + 1`. Refuses an existing `run_id`.
    pub fn begin_run(&mut self, run_id: &str, attrs: &RunAttrs, triangles: &[[u32; 3]]) -> Result<RunWriter> {
        let path = self.path.clone();
        check_run_id(&path, run_id)?;
        if self.has_run(run_id) {
            return Err(invalid(&path, format!("run `{run_id}` already exists (resume it or remove it)")));
        }
        if triangles.is_empty() {
            return Err(invalid(&path, format!("run `{run_id}`: empty triangle list")));
        }
        let nv = triangles.iter().flat_map(|t| t.iter()).copied().max().unwrap_or(0) as usize + 1;
        let g = self.runs_group()?.create_group(run_id).map_err(|e| h5err(&path, run_id, e))?;
        set_start_attrs(&path, &g, attrs)?;

        let ts = g.create_group("timeseries").map_err(|e| h5err(&path, "timeseries", e))?;
        for name in ["t_s", "area_um2", "volume_um3", "asphericity"] {
            ts.new_dataset::<f64>()
                .chunk(TIMESERIES_CHUNK)
                .shape(0..)
                .create(name)
                .map_err(|e| h5err(&path, name, e))?;
        }
        for name in ["centroid_um", "velocity_mm_s", "extents_um"] {
            ts.new_dataset::<f64>()
                .chunk((TIMESERIES_CHUNK, 3))
                .shape((0.., 3))
                .create(name)
                .map_err(|e| h5err(&path, name, e))?;
        }
        let sn = g.create_group("snapshots").map_err(|e| h5err(&path, "snapshots", e))?;
        sn.new_dataset::<f64>().chunk(64).shape(0..).create("times_s").map_err(|e| h5err(&path, "times_s", e))?;
        sn.new_dataset::<f64>()
            .chunk((1, nv, 3))
            .shape((0.., nv, 3))
            .create("vertices_um")
            .map_err(|e| h5err(&path, "vertices_um", e))?;
        let tri = ndarray::Array2::from_shape_fn((triangles.len(), 3), |(i, j)| triangles[i][j]);
        sn.new_dataset_builder().with_data(&tri).create("triangles").map_err(|e| h5err(&path, "triangles", e))?;
        // status last: a group without it was interrupted while being created
        set_str(&path, &g, "status", RunStatus::Running.as_str())?;
        self.file.flush().map_err(|e| h5err(&path, "flush", e))?;
        RunWriter::open(path, run_id, g)
    }

    /// True for a run recorded as not run (status `overlaps-wall`, no timeseries or snapshot groups).
    fn not_run(&self, g: &Group) -> bool {
        has_attr(g, "status") && get_str(&self.path, g, "status", "status").is_ok_and(|s| s == RunStatus::OverlapsWall.as_str())
    }

    /// Record run `run_id` as not run because its cell overlaps the channel wall (status
    /// `overlaps-wall`, `reason` in the `not_run` attribute, the start attributes, no rows and no
    /// snapshots), replacing a run of that id (e.g. one an earlier build ran and recorded as failed).
    pub fn record_overlaps_wall(&mut self, run_id: &str, attrs: &RunAttrs, reason: &str) -> Result<()> {
        let path = self.path.clone();
        check_run_id(&path, run_id)?;
        if self.has_run(run_id) {
            self.remove_run(run_id)?;
        }
        let g = self.runs_group()?.create_group(run_id).map_err(|e| h5err(&path, run_id, e))?;
        set_start_attrs(&path, &g, attrs)?;
        set_str(&path, &g, "not_run", reason)?;
        // status last, as in begin_run
        set_str(&path, &g, "status", RunStatus::OverlapsWall.as_str())?;
        self.file.flush().map_err(|e| h5err(&path, "flush", e))
    }

    /// Reopen a run (normally one with status `running`) to append to it after a restart.
    /// Its status is set back to `running` and summary attributes of an earlier finish are removed.
    pub fn resume_run(&mut self, run_id: &str) -> Result<RunWriter> {
        let g = self.run_group(run_id)?;
        for name in SUMMARY_ATTRS.iter().copied().chain(["failure"]) {
            if has_attr(&g, name) {
                g.delete_attr(name).map_err(|e| h5err(&self.path, name, e))?;
            }
        }
        // a steady state carried to a distance is no record of a run that continues: it will pass it
        let names = g.attr_names().map_err(|e| h5err(&self.path, run_id, e))?;
        let carried: Vec<String> = names
            .iter()
            .filter_map(|n| n.strip_prefix("transit_").and_then(|r| r.strip_suffix("_from_steady")))
            .map(|k| format!("transit_{k}_"))
            .collect();
        for name in names {
            if name.starts_with("evidence_") || carried.iter().any(|c| name.starts_with(c.as_str())) {
                g.delete_attr(&name).map_err(|e| h5err(&self.path, &name, e))?;
            }
        }
        set_str(&self.path, &g, "status", RunStatus::Running.as_str())?;
        RunWriter::open(self.path.clone(), run_id, g)
    }

    /// Overwrite the label of a run that ended (`final_shape`, `tank_treading`, `tumbling`), e.g.
    /// decided again from its stored evidence under another classification rule; everything else
    /// of the run stays. A run that has not ended (running, failed) is refused.
    pub fn set_label(&mut self, run_id: &str, shape: FinalShape, tank_treading: bool, tumbling: bool) -> Result<()> {
        self.write_ended(run_id, "a label", |p, g| {
            set_str(p, g, "final_shape", shape.as_str())?;
            set_attr(p, g, "tank_treading", &tank_treading)?;
            set_attr(p, g, "tumbling", &tumbling)
        })
    }

    /// Say where an ended run's data were copied from (attribute `copied_from`, free text, e.g.
    /// `state/a.h5: run r1, snapshot at t = 3.16 s`; see [`crate::start_shape`]).
    pub fn set_copied_from(&mut self, run_id: &str, source: &str) -> Result<()> {
        self.write_ended(run_id, "a copy's source", |p, g| set_str(p, g, "copied_from", source))
    }

    /// Record a transit of a run that ended (a steady state carried to a distance it had not
    /// reached, [`Transit::from_steady`]); a run that has not ended is refused (its transits are
    /// written by its [`RunWriter`] as it passes them).
    pub fn set_transit_of_ended(&mut self, run_id: &str, t: &Transit) -> Result<()> {
        self.write_ended(run_id, "a transit after the end", |p, g| write_transit(p, g, t))
    }

    /// Write attributes of a run that ended (`what` names them in the refusal of one that has not).
    fn write_ended(&mut self, run_id: &str, what: &str, write: impl FnOnce(&Path, &hdf5::Group) -> Result<()>) -> Result<()> {
        let status = self.run(run_id)?.status;
        if !status.is_finished() {
            return Err(SchemaError::field(
                &self.path,
                format!("runs/{run_id}.status"),
                format!("{what} belongs to a run that ended, this one is {}", status.as_str()),
            ));
        }
        let g = self.run_group(run_id)?;
        write(&self.path, &g)?;
        self.file.flush().map_err(|e| h5err(&self.path, "flush", e))
    }

    /// Every run with its attributes (see [`read_runs`]).
    pub fn runs(&self) -> Result<Vec<RunRecord>> {
        self.run_ids()?.iter().map(|id| self.run(id)).collect()
    }

    /// One run's attributes. Tolerates failed and running runs (their summary is `None`);
    /// a finished run must carry every summary attribute.
    pub fn run(&self, run_id: &str) -> Result<RunRecord> {
        let p = &self.path;
        let _reading = crate::hdf5_watch::reading(p, || format!("run `{run_id}`: attributes"));
        let g = self.run_group(run_id)?;
        let field = |name: &str| format!("runs/{run_id}.{name}");
        let status = if has_attr(&g, "status") {
            let s = get_str(p, &g, &field("status"), "status")?;
            RunStatus::parse(&s).ok_or_else(|| {
                SchemaError::field(p, field("status"), format!("`{s}` is not one of steady, periodic, unsteady, failed, running, overlaps-wall"))
            })?
        } else {
            RunStatus::Running
        };
        let read_attrs = || -> Result<RunAttrs> {
            Ok(RunAttrs {
                start_shape: get_str(p, &g, &field("start_shape"), "start_shape")?,
                r_init_um: get_f64(p, &g, &field("r_init_um"), "r_init_um")?,
                y_init_um: get_f64(p, &g, &field("y_init_um"), "y_init_um")?,
                z_init_um: get_f64(p, &g, &field("z_init_um"), "z_init_um")?,
                lambda: get_f64(p, &g, &field("lambda"), "lambda")?,
                scene: get_str(p, &g, &field("scene"), "scene").unwrap_or_default(),
            })
        };
        let attrs = match read_attrs() {
            Ok(a) => Some(a),
            Err(_) if !status.is_finished() => None,
            Err(e) => return Err(e),
        };
        let summary = if status.is_finished() {
            let shape = get_str(p, &g, &field("final_shape"), "final_shape")?;
            let final_shape = FinalShape::parse(&shape).ok_or_else(|| {
                SchemaError::field(p, field("final_shape"), format!("`{shape}` is not one of croissant, slipper, other"))
            })?;
            let mut evidence = BTreeMap::new();
            for name in g.attr_names().map_err(|e| h5err(p, run_id, e))? {
                if let Some(key) = name.strip_prefix("evidence_") {
                    evidence.insert(key.to_string(), get_f64(p, &g, &field(&name), &name)?);
                }
            }
            Some(RunSummary {
                status,
                final_shape,
                tank_treading: get_bool(p, &g, &field("tank_treading"), "tank_treading")?,
                tumbling: get_bool(p, &g, &field("tumbling"), "tumbling")?,
                mean_velocity_mm_s: get_f64(p, &g, &field("mean_velocity_mm_s"), "mean_velocity_mm_s")?,
                min_velocity_mm_s: get_f64(p, &g, &field("min_velocity_mm_s"), "min_velocity_mm_s")?,
                max_velocity_mm_s: get_f64(p, &g, &field("max_velocity_mm_s"), "max_velocity_mm_s")?,
                mean_radial_um: get_f64(p, &g, &field("mean_radial_um"), "mean_radial_um")?,
                mean_y_um: get_f64(p, &g, &field("mean_y_um"), "mean_y_um")?,
                mean_z_um: get_f64(p, &g, &field("mean_z_um"), "mean_z_um")?,
                evidence,
            })
        } else {
            None
        };
        let failure = if has_attr(&g, "failure") { get_str(p, &g, &field("failure"), "failure").ok() } else { None };
        let not_run = if has_attr(&g, "not_run") { get_str(p, &g, &field("not_run"), "not_run").ok() } else { None };
        let copied_from = if has_attr(&g, "copied_from") { get_str(p, &g, &field("copied_from"), "copied_from").ok() } else { None };
        let mut transits = Vec::new();
        for name in g.attr_names().map_err(|e| h5err(p, run_id, e))? {
            let Some(key) = name.strip_prefix("transit_").and_then(|r| r.strip_suffix("_t_s")) else { continue };
            let Some(distance_mm) = key.strip_suffix("mm").and_then(|d| d.replace('p', ".").parse::<f64>().ok()) else { continue };
            let get = |q: &str| {
                let n = format!("transit_{key}_{q}");
                get_f64(p, &g, &field(&n), &n)
            };
            let n = format!("transit_{key}_shape");
            let s = get_str(p, &g, &field(&n), &n)?;
            let shape = FinalShape::parse(&s).ok_or_else(|| SchemaError::field(p, field(&n), format!("`{s}` is not one of croissant, slipper, other")))?;
            let n = format!("transit_{key}_from_steady");
            let from_steady = has_attr(&g, &n) && get_bool(p, &g, &field(&n), &n)?;
            transits.push(Transit { distance_mm, t_s: get("t_s")?, x_um: get("x_um")?, y_um: get("y_um")?, z_um: get("z_um")?, velocity_mm_s: get("velocity_mm_s")?, shape, from_steady });
        }
        transits.sort_by(|a, b| a.distance_mm.total_cmp(&b.distance_mm));
        let len = |grp: &str, ds: &str| -> usize {
            g.group(grp).and_then(|x| x.dataset(ds)).map(|d| d.shape().first().copied().unwrap_or(0)).unwrap_or(0)
        };
        Ok(RunRecord {
            run_id: run_id.to_string(),
            status,
            attrs,
            summary,
            failure,
            not_run,
            copied_from,
            transits,
            n_samples: len("timeseries", "t_s"),
            n_snapshots: len("snapshots", "times_s"),
        })
    }

    /// One run's timeseries (rows that were fully written: the shortest dataset decides).
    pub fn timeseries(&self, run_id: &str) -> Result<Vec<TimeSample>> {
        let p = &self.path;
        let _reading = crate::hdf5_watch::reading(p, || format!("runs/{run_id}/timeseries"));
        let g = self.run_group(run_id)?;
        if self.not_run(&g) {
            return Ok(Vec::new());
        }
        let ts = g.group("timeseries").map_err(|_| invalid(p, format!("run `{run_id}`: no timeseries")))?;
        let d1 = |name: &str| -> Result<Vec<f64>> {
            let ctx = format!("runs/{run_id}/timeseries/{name}");
            let d = ts.dataset(name).map_err(|e| h5err(p, &ctx, e))?;
            read_all(p, &d, &ctx)
        };
        let d3 = |name: &str| -> Result<Vec<[f64; 3]>> {
            let d = ts.dataset(name).map_err(|e| h5err(p, &format!("runs/{run_id}/timeseries/{name}"), e))?;
            read_rows3(p, &d, &format!("runs/{run_id}/timeseries/{name}"))
        };
        let (t, area, vol, asph) = (d1("t_s")?, d1("area_um2")?, d1("volume_um3")?, d1("asphericity")?);
        let (c, v, ext) = (d3("centroid_um")?, d3("velocity_mm_s")?, d3("extents_um")?);
        let n = [t.len(), area.len(), vol.len(), asph.len(), c.len(), v.len(), ext.len()].into_iter().min().unwrap_or(0);
        Ok((0..n)
            .map(|i| TimeSample {
                t_s: t[i],
                centroid_um: c[i],
                velocity_mm_s: v[i],
                area_um2: area[i],
                volume_um3: vol[i],
                asphericity: asph[i],
                extents_um: ext[i],
            })
            .collect())
    }

    /// One run's snapshots and triangles.
    pub fn snapshots(&self, run_id: &str) -> Result<Snapshots> {
        let p = &self.path;
        let _reading = crate::hdf5_watch::reading(p, || format!("runs/{run_id}/snapshots"));
        let ctx = |name: &str| format!("runs/{run_id}/snapshots/{name}");
        let g = self.run_group(run_id)?;
        if self.not_run(&g) {
            return Ok(Snapshots { times_s: Vec::new(), vertices_um: Vec::new(), triangles: Vec::new(), fields: BTreeMap::new() });
        }
        let sn = g.group("snapshots").map_err(|_| invalid(p, format!("run `{run_id}`: no snapshots")))?;
        let times_s = read_all::<f64>(p, &sn.dataset("times_s").map_err(|e| h5err(p, &ctx("times_s"), e))?, &ctx("times_s"))?;
        let vd = sn.dataset("vertices_um").map_err(|e| h5err(p, &ctx("vertices_um"), e))?;
        let shape = vd.shape();
        if shape.len() != 3 || shape[2] != 3 {
            return Err(invalid(p, format!("{}: shape {shape:?}, expected [k, nv, 3]", ctx("vertices_um"))));
        }
        let (k, nv) = (shape[0].min(times_s.len()), shape[1]);
        let flat = read_all::<f64>(p, &vd, &ctx("vertices_um"))?;
        let vertices_um = (0..k)
            .map(|s| (0..nv).map(|i| { let o = (s * nv + i) * 3; [flat[o], flat[o + 1], flat[o + 2]] }).collect())
            .collect();
        let td = sn.dataset("triangles").map_err(|e| h5err(p, &ctx("triangles"), e))?;
        let tflat = read_all::<u32>(p, &td, &ctx("triangles"))?;
        if tflat.len() % 3 != 0 {
            return Err(invalid(p, format!("{}: not an [nt, 3] array", ctx("triangles"))));
        }
        let triangles: Vec<[u32; 3]> = tflat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        if let Some((i, t)) = triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= nv)) {
            return Err(invalid(p, format!("{}: triangle {i} {t:?} refers to a vertex beyond the {nv} of vertices_um", ctx("triangles"))));
        }
        let mut fields = BTreeMap::new();
        for f in self.snapshot_layout(run_id)?.fields.iter().filter(|f| f.components == 1) {
            let flat = sn.dataset(&f.name).and_then(|d| d.read_raw::<f64>()).map_err(|e| h5err(p, &ctx(&f.name), e))?;
            fields.insert(f.name.clone(), flat.chunks_exact(nv.max(1)).take(k).map(<[f64]>::to_vec).collect());
        }
        Ok(Snapshots { times_s: times_s[..k].to_vec(), vertices_um, triangles, fields })
    }

    /// Where one run's snapshots lie in the file, without reading the vertex data: dataset shapes,
    /// the snapshot times, and the per-vertex fields stored beside the positions (for
    /// [`crate::xdmf`], which points at these datasets instead of copying them).
    pub fn snapshot_layout(&self, run_id: &str) -> Result<SnapshotLayout> {
        let p = &self.path;
        let _reading = crate::hdf5_watch::reading(p, || format!("runs/{run_id}/snapshots"));
        let ctx = |name: &str| format!("runs/{run_id}/snapshots/{name}");
        let sn = self.run_group(run_id)?.group("snapshots").map_err(|_| invalid(p, format!("run `{run_id}`: no snapshots")))?;
        let times_s = sn.dataset("times_s").and_then(|d| d.read_raw::<f64>()).map_err(|e| h5err(p, &ctx("times_s"), e))?;
        let vd = sn.dataset("vertices_um").map_err(|e| h5err(p, &ctx("vertices_um"), e))?;
        let shape = vd.shape();
        if shape.len() != 3 || shape[2] != 3 {
            return Err(invalid(p, format!("{}: shape {shape:?}, expected [k, nv, 3]", ctx("vertices_um"))));
        }
        let (rows, nv) = (shape[0], shape[1]);
        let td = sn.dataset("triangles").map_err(|e| h5err(p, &ctx("triangles"), e))?;
        let tshape = td.shape();
        if tshape.len() != 2 || tshape[1] != 3 {
            return Err(invalid(p, format!("{}: shape {tshape:?}, expected [nt, 3]", ctx("triangles"))));
        }
        let is = |d: &Dataset, want: hdf5::types::TypeDescriptor| d.dtype().and_then(|t| t.to_descriptor()).map(|t| t == want).unwrap_or(false);
        if !is(&td, hdf5::types::TypeDescriptor::Unsigned(hdf5::types::IntSize::U4)) {
            return Err(invalid(p, format!("{}: not unsigned 32-bit integers", ctx("triangles"))));
        }
        let f64_type = hdf5::types::TypeDescriptor::Float(hdf5::types::FloatSize::U8);
        let mut fields = Vec::new();
        let mut names = sn.member_names().map_err(|e| h5err(p, &ctx(""), e))?;
        names.sort();
        for name in names {
            if ["times_s", "vertices_um", "triangles"].contains(&name.as_str()) {
                continue;
            }
            let Ok(d) = sn.dataset(&name) else { continue };
            let s = d.shape();
            let components = match s.as_slice() {
                [_, n] if *n == nv => 1,
                [_, n, 3] if *n == nv => 3,
                _ => continue,
            };
            if is(&d, f64_type.clone()) {
                fields.push(VertexField { name, components, rows: s[0] });
            }
        }
        let n = times_s.len().min(rows);
        fields.retain(|f| f.rows >= n);
        Ok(SnapshotLayout { times_s: times_s[..n].to_vec(), rows, n_vertices: nv, n_triangles: tshape[0], fields })
    }

    /// Flush buffered data to disk.
    pub fn flush(&self) -> Result<()> {
        self.file.flush().map_err(|e| h5err(&self.path, "flush", e))
    }
}

/// Every element of dataset `d` (`ctx` in messages), after checking that its shape fits the file: a damaged
/// dataspace can claim more elements than memory holds, and the allocation would abort the process
/// (`rbc-bench fuzz --format results --seed 3 --case 64`: 3.8e17 bytes). Our files are not compressed, so a
/// dataset holds at most the file's bytes; the bound leaves a factor 64 and 1 MiB for other writers' files.
pub(crate) fn read_all<T: hdf5::H5Type>(path: &Path, d: &Dataset, ctx: &str) -> Result<Vec<T>> {
    let elements = d.shape().iter().try_fold(1u128, |n, &k| n.checked_mul(k as u128)).unwrap_or(u128::MAX);
    let bytes = elements.saturating_mul(std::mem::size_of::<T>() as u128);
    let file_len = std::fs::metadata(path).map(|m| m.len() as u128).unwrap_or(u128::MAX / 128);
    if bytes > 64 * file_len + (1 << 20) {
        return Err(invalid(path, format!("{ctx}: shape {:?} claims {bytes} bytes in a file of {file_len} (damaged file?)", d.shape())));
    }
    d.read_raw::<T>().map_err(|e| h5err(path, ctx, e))
}

fn read_rows3(path: &Path, d: &Dataset, ctx: &str) -> Result<Vec<[f64; 3]>> {
    let shape = d.shape();
    if shape.len() != 2 || shape[1] != 3 {
        return Err(invalid(path, format!("{ctx}: shape {shape:?}, expected [n, 3]")));
    }
    let flat = read_all::<f64>(path, d, ctx)?;
    Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

const SUMMARY_ATTRS: [&str; 9] = [
    "final_shape",
    "tank_treading",
    "tumbling",
    "mean_velocity_mm_s",
    "min_velocity_mm_s",
    "max_velocity_mm_s",
    "mean_radial_um",
    "mean_y_um",
    "mean_z_um",
];

/// Appends samples and snapshots to one run, then finishes or fails it.
///
/// Holds its own HDF5 handles, so it stays valid independently of the
/// [`ResultsFile`] borrow that created it (the file closes when both are dropped).
pub struct RunWriter {
    path: PathBuf,
    run_id: String,
    group: Group,
    /// Samples already in the datasets.
    n_written: usize,
    /// Samples appended but not yet written.
    pending: Vec<TimeSample>,
    n_snapshots: usize,
    nv: usize,
    /// Names of the run's per-vertex scalar fields (`snapshots/<name>`, `[k, nv]`).
    fields: Vec<String>,
}

/// Accessor of a scalar timeseries column.
type Column1 = fn(&TimeSample) -> f64;
/// Accessor of an `[n, 3]` timeseries column.
type Column3 = fn(&TimeSample) -> [f64; 3];

/// Rows of the timeseries buffered by [`RunWriter::append_sample`] before they are written.
pub const SAMPLE_BUFFER: usize = 256;

impl RunWriter {
    fn open(path: PathBuf, run_id: &str, group: Group) -> Result<RunWriter> {
        let ctx = |n: &str| format!("runs/{run_id}/{n}");
        let t = group.dataset("timeseries/t_s").map_err(|e| h5err(&path, &ctx("timeseries/t_s"), e))?;
        let sn = group.dataset("snapshots/times_s").map_err(|e| h5err(&path, &ctx("snapshots/times_s"), e))?;
        let vd = group.dataset("snapshots/vertices_um").map_err(|e| h5err(&path, &ctx("snapshots/vertices_um"), e))?;
        let n_written = t.shape()[0];
        let n_snapshots = sn.shape()[0].min(vd.shape()[0]);
        let nv = vd.shape().get(1).copied().unwrap_or(0);
        let sg = group.group("snapshots").map_err(|e| h5err(&path, &ctx("snapshots"), e))?;
        let mut fields: Vec<String> = sg
            .member_names()
            .map_err(|e| h5err(&path, &ctx("snapshots"), e))?
            .into_iter()
            .filter(|n| !["times_s", "vertices_um", "triangles"].contains(&n.as_str()))
            .filter(|n| sg.dataset(n).map(|d| d.shape() == [d.shape()[0], nv]).unwrap_or(false))
            .collect();
        fields.sort();
        Ok(RunWriter { path, run_id: run_id.to_string(), group, n_written, pending: Vec::new(), n_snapshots, nv, fields })
    }

    /// Names of the run's per-vertex scalar fields, in name order.
    pub fn fields(&self) -> &[String] {
        &self.fields
    }

    /// The run's id.
    pub fn run_id(&self) -> &str {
        &self.run_id
    }

    /// Samples appended so far (written or buffered).
    pub fn n_samples(&self) -> usize {
        self.n_written + self.pending.len()
    }

    /// Snapshots written so far.
    pub fn n_snapshots(&self) -> usize {
        self.n_snapshots
    }

    fn ds(&self, name: &str) -> Result<Dataset> {
        self.group.dataset(name).map_err(|e| h5err(&self.path, &format!("runs/{}/{name}", self.run_id), e))
    }

    fn err(&self, name: &str, e: hdf5::Error) -> SchemaError {
        h5err(&self.path, &format!("runs/{}/{name}", self.run_id), e)
    }

    /// Append one timeseries row (refuses non-finite values: a blow-up must be diagnosed, not stored).
    ///
    /// Rows are buffered and written in blocks of [`SAMPLE_BUFFER`] rows (one
    /// resize and one write per dataset per block: about 200 us per row unbuffered,
    /// measured), and at every [`flush`](Self::flush), snapshot, `finish`, `fail` and drop.
    pub fn append_sample(&mut self, s: &TimeSample) -> Result<()> {
        let all = [s.t_s, s.area_um2, s.volume_um3, s.asphericity]
            .into_iter()
            .chain(s.centroid_um)
            .chain(s.velocity_mm_s)
            .chain(s.extents_um);
        if all.into_iter().any(|v| !v.is_finite()) {
            return Err(SchemaError::field(
                &self.path,
                format!("runs/{}/timeseries", self.run_id),
                format!("sample at t = {} s has a non-finite value", s.t_s),
            ));
        }
        self.pending.push(*s);
        if self.pending.len() >= SAMPLE_BUFFER {
            self.write_pending()?;
        }
        Ok(())
    }

    /// Write the buffered samples to the datasets.
    fn write_pending(&mut self) -> Result<()> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let n = self.n_written;
        let m = self.pending.len();
        let cols1: [(&str, Column1); 4] = [
            ("timeseries/t_s", |s| s.t_s),
            ("timeseries/area_um2", |s| s.area_um2),
            ("timeseries/volume_um3", |s| s.volume_um3),
            ("timeseries/asphericity", |s| s.asphericity),
        ];
        for (name, get) in cols1 {
            let d = self.ds(name)?;
            let v: Vec<f64> = self.pending.iter().map(get).collect();
            d.resize(n + m).map_err(|e| self.err(name, e))?;
            d.write_slice(&v[..], n..n + m).map_err(|e| self.err(name, e))?;
        }
        let cols3: [(&str, Column3); 3] = [
            ("timeseries/centroid_um", |s| s.centroid_um),
            ("timeseries/velocity_mm_s", |s| s.velocity_mm_s),
            ("timeseries/extents_um", |s| s.extents_um),
        ];
        for (name, get) in cols3 {
            let d = self.ds(name)?;
            let rows = ndarray::Array2::from_shape_fn((m, 3), |(i, j)| get(&self.pending[i])[j]);
            d.resize((n + m, 3)).map_err(|e| self.err(name, e))?;
            d.write_slice(&rows, (n..n + m, 0..3)).map_err(|e| self.err(name, e))?;
        }
        self.n_written = n + m;
        self.pending.clear();
        Ok(())
    }

    /// Append one snapshot of all vertex positions (um) at time `t_s` (s), for a run without
    /// per-vertex fields (see [`append_snapshot_with`](Self::append_snapshot_with)).
    pub fn append_snapshot(&mut self, t_s: f64, vertices_um: &[[f64; 3]]) -> Result<()> {
        self.append_snapshot_with(t_s, vertices_um, &[])
    }

    /// Append one snapshot: vertex positions (um) at time `t_s` (s) and per-vertex scalar fields
    /// `(name, one value per vertex)`. A field's dataset `snapshots/<name>` is created with the
    /// run's first snapshot; later, a field the run does not have is left out (a run begun by an
    /// older build, resumed, stays without it), and a field the run has must be given (its rows
    /// stay aligned with the snapshots).
    pub fn append_snapshot_with(&mut self, t_s: f64, vertices_um: &[[f64; 3]], fields: &[(&str, &[f64])]) -> Result<()> {
        let ctx = |name: &str| format!("runs/{}/snapshots/{name}", self.run_id);
        for (name, v) in fields {
            if v.len() != self.nv || v.iter().any(|x| !x.is_finite()) || name.is_empty() || name.contains('/') {
                return Err(SchemaError::field(&self.path, ctx(name), format!("snapshot at t = {t_s} s: {} values (the mesh has {} vertices) or a non-finite value", v.len(), self.nv)));
            }
        }
        if let Some(missing) = self.fields.iter().find(|f| !fields.iter().any(|(n, _)| n == f)) {
            return Err(SchemaError::field(&self.path, ctx(missing), format!("snapshot at t = {t_s} s does not give this field, which the run has")));
        }
        if vertices_um.len() != self.nv {
            return Err(SchemaError::field(
                &self.path,
                format!("runs/{}/snapshots/vertices_um", self.run_id),
                format!("{} vertices, the mesh has {}", vertices_um.len(), self.nv),
            ));
        }
        if !t_s.is_finite() || vertices_um.iter().flatten().any(|v| !v.is_finite()) {
            return Err(SchemaError::field(
                &self.path,
                format!("runs/{}/snapshots/vertices_um", self.run_id),
                format!("snapshot at t = {t_s} s has a non-finite value"),
            ));
        }
        self.write_pending()?;
        let k = self.n_snapshots;
        let vd = self.ds("snapshots/vertices_um")?;
        vd.resize((k + 1, self.nv, 3)).map_err(|e| self.err("snapshots/vertices_um", e))?;
        let arr = ndarray::Array3::from_shape_fn((1, self.nv, 3), |(_, i, j)| vertices_um[i][j]);
        vd.write_slice(&arr, (k..k + 1, 0..self.nv, 0..3)).map_err(|e| self.err("snapshots/vertices_um", e))?;
        for (name, v) in fields {
            let full = format!("snapshots/{name}");
            if !self.fields.iter().any(|f| f == name) {
                if k > 0 {
                    continue; // the run began without this field
                }
                let sg = self.group.group("snapshots").map_err(|e| self.err("snapshots", e))?;
                sg.new_dataset::<f64>().chunk((1, self.nv)).shape((0.., self.nv)).create(*name).map_err(|e| self.err(&full, e))?;
                self.fields.push(name.to_string());
                self.fields.sort();
            }
            let d = self.ds(&full)?;
            d.resize((k + 1, self.nv)).map_err(|e| self.err(&full, e))?;
            let row = ndarray::Array2::from_shape_fn((1, self.nv), |(_, i)| v[i]);
            d.write_slice(&row, (k..k + 1, 0..self.nv)).map_err(|e| self.err(&full, e))?;
        }
        // times_s last: a snapshot counts only once its time is written
        let td = self.ds("snapshots/times_s")?;
        td.resize(k + 1).map_err(|e| self.err("snapshots/times_s", e))?;
        td.write_slice(&[t_s][..], k..k + 1).map_err(|e| self.err("snapshots/times_s", e))?;
        self.n_snapshots = k + 1;
        Ok(())
    }

    /// Drop samples and snapshots later than `t_s` (used when resuming from a checkpoint at `t_s`).
    pub fn truncate_after(&mut self, t_s: f64) -> Result<()> {
        self.write_pending()?;
        let t = self.ds("timeseries/t_s")?.read_raw::<f64>().map_err(|e| self.err("timeseries/t_s", e))?;
        let n = t.iter().take(self.n_written).take_while(|&&x| x <= t_s).count();
        for name in ["timeseries/t_s", "timeseries/area_um2", "timeseries/volume_um3", "timeseries/asphericity"] {
            self.ds(name)?.resize(n).map_err(|e| self.err(name, e))?;
        }
        for name in ["timeseries/centroid_um", "timeseries/velocity_mm_s", "timeseries/extents_um"] {
            self.ds(name)?.resize((n, 3)).map_err(|e| self.err(name, e))?;
        }
        self.n_written = n;
        let ts = self.ds("snapshots/times_s")?.read_raw::<f64>().map_err(|e| self.err("snapshots/times_s", e))?;
        let k = ts.iter().take(self.n_snapshots).take_while(|&&x| x <= t_s).count();
        self.resize_snapshots(k)?;
        Ok(())
    }

    /// Keep the first `n_samples` timeseries rows and the first `n_snapshots` snapshots, dropping
    /// the rest (used when resuming from a checkpoint that recorded these counts: rows written
    /// after it, possibly half-written by a killed process, go). Refuses counts larger than what
    /// the file holds (the checkpoint does not belong to this run).
    pub fn truncate_to(&mut self, n_samples: usize, n_snapshots: usize) -> Result<()> {
        self.write_pending()?;
        let rows = ["timeseries/t_s", "timeseries/area_um2", "timeseries/volume_um3", "timeseries/asphericity", "timeseries/centroid_um", "timeseries/velocity_mm_s", "timeseries/extents_um"]
            .iter()
            .map(|n| self.ds(n).map(|d| d.shape()[0]))
            .collect::<Result<Vec<_>>>()?;
        let have_rows = rows.into_iter().min().unwrap_or(0);
        let have_snaps = self.ds("snapshots/times_s")?.shape()[0].min(self.ds("snapshots/vertices_um")?.shape()[0]);
        if n_samples > have_rows || n_snapshots > have_snaps {
            return Err(invalid(
                &self.path,
                format!(
                    "run `{}`: the checkpoint needs {n_samples} samples and {n_snapshots} snapshots, the file holds {have_rows} and {have_snaps}",
                    self.run_id
                ),
            ));
        }
        for name in ["timeseries/t_s", "timeseries/area_um2", "timeseries/volume_um3", "timeseries/asphericity"] {
            self.ds(name)?.resize(n_samples).map_err(|e| self.err(name, e))?;
        }
        for name in ["timeseries/centroid_um", "timeseries/velocity_mm_s", "timeseries/extents_um"] {
            self.ds(name)?.resize((n_samples, 3)).map_err(|e| self.err(name, e))?;
        }
        self.resize_snapshots(n_snapshots)?;
        self.n_written = n_samples;
        Ok(())
    }

    /// Cut the snapshot datasets (times, positions, fields) to `k` rows.
    fn resize_snapshots(&mut self, k: usize) -> Result<()> {
        self.ds("snapshots/times_s")?.resize(k).map_err(|e| self.err("snapshots/times_s", e))?;
        self.ds("snapshots/vertices_um")?.resize((k, self.nv, 3)).map_err(|e| self.err("snapshots/vertices_um", e))?;
        for f in &self.fields {
            let name = format!("snapshots/{f}");
            self.ds(&name)?.resize((k, self.nv)).map_err(|e| self.err(&name, e))?;
        }
        self.n_snapshots = k;
        Ok(())
    }

    /// Write the buffered samples and flush everything to disk (call at each checkpoint).
    pub fn flush(&mut self) -> Result<()> {
        self.write_pending()?;
        self.group.file().and_then(|f| f.flush()).map_err(|e| self.err("", e))
    }

    /// Write the summary attributes and the final status (steady, periodic or unsteady).
    pub fn finish(mut self, summary: &RunSummary) -> Result<()> {
        if !summary.status.is_finished() {
            return Err(SchemaError::field(
                &self.path,
                format!("runs/{}.status", self.run_id),
                format!("finish needs steady, periodic or unsteady, not {}", summary.status.as_str()),
            ));
        }
        self.write_pending()?;
        let (p, g) = (&self.path, &self.group);
        set_str(p, g, "final_shape", summary.final_shape.as_str())?;
        set_attr(p, g, "tank_treading", &summary.tank_treading)?;
        set_attr(p, g, "tumbling", &summary.tumbling)?;
        set_f64(p, g, "mean_velocity_mm_s", summary.mean_velocity_mm_s)?;
        set_f64(p, g, "min_velocity_mm_s", summary.min_velocity_mm_s)?;
        set_f64(p, g, "max_velocity_mm_s", summary.max_velocity_mm_s)?;
        set_f64(p, g, "mean_radial_um", summary.mean_radial_um)?;
        set_f64(p, g, "mean_y_um", summary.mean_y_um)?;
        set_f64(p, g, "mean_z_um", summary.mean_z_um)?;
        for (k, v) in &summary.evidence {
            set_f64(p, g, &format!("evidence_{k}"), *v)?;
        }
        set_str(p, g, "status", summary.status.as_str())?;
        self.flush()
    }

    /// Record (or record again: the attributes are overwritten) where and what the cell was when
    /// it had travelled `t.distance_mm` (layout in the module documentation).
    pub fn set_transit(&mut self, t: &Transit) -> Result<()> {
        write_transit(&self.path, &self.group, t)
    }

    /// Mark the run failed with a one-line diagnosis (the data written so far are kept).
    pub fn fail(mut self, message: &str) -> Result<()> {
        self.write_pending()?;
        set_str(&self.path, &self.group, "failure", message)?;
        set_str(&self.path, &self.group, "status", RunStatus::Failed.as_str())?;
        self.flush()
    }
}

impl Drop for RunWriter {
    /// Buffered samples are written when a writer is dropped without `flush`,
    /// `finish` or `fail` (best effort: an error here cannot be reported).
    fn drop(&mut self) {
        let _ = self.write_pending();
    }
}

// ---------------------------------------------------------------- free functions

/// Every run of `path` with its attributes; failed and running runs are listed with `summary: None`.
pub fn read_runs(path: &Path) -> Result<Vec<RunRecord>> {
    ResultsFile::open(path)?.runs()
}

/// One run's timeseries.
pub fn read_timeseries(path: &Path, run_id: &str) -> Result<Vec<TimeSample>> {
    ResultsFile::open(path)?.timeseries(run_id)
}

/// One run's snapshots.
pub fn read_snapshots(path: &Path, run_id: &str) -> Result<Snapshots> {
    ResultsFile::open(path)?.snapshots(run_id)
}

/// Merge the runs of `inputs` into a new file `out`, written atomically (a
/// temporary file renamed into place). Refuses a run id that occurs twice,
/// naming both files. Returns the number of runs written.
pub fn merge_files(inputs: &[PathBuf], out: &Path) -> Result<usize> {
    let mut seen: BTreeMap<String, PathBuf> = BTreeMap::new();
    let mut sources = Vec::new();
    for p in inputs {
        if p.as_path() == out {
            return Err(invalid(out, "merge output is also one of its inputs"));
        }
        let f = ResultsFile::open(p)?;
        for id in f.run_ids()? {
            if let Some(first) = seen.insert(id.clone(), p.clone()) {
                return Err(invalid(p, format!("run `{id}` is also in {}", first.display())));
            }
        }
        sources.push(f);
    }
    crate::atomic::write_via(out, |tmp| {
        let mut dst = ResultsFile::create_or_open_by(tmp, concat!("rbc-toolkit ", env!("CARGO_PKG_VERSION"), " merge"))?;
        let mut n = 0;
        for src in &sources {
            for rec in src.runs()? {
                copy_run(src, &rec.run_id, &mut dst)?;
                n += 1;
            }
        }
        dst.flush()?;
        Ok(n)
    })
}

/// Copy run `run_id` of `src` into `dst` (rows, snapshots, transits, and the summary or the
/// failure), replacing a run of that id in `dst`; returns the run's status.
pub fn copy_run(src: &ResultsFile, run_id: &str, dst: &mut ResultsFile) -> Result<RunStatus> {
    let rec = src.run(run_id)?;
    let attrs = rec
        .attrs
        .clone()
        .ok_or_else(|| invalid(&src.path, format!("run `{}` has no start attributes (interrupted while created)", rec.run_id)))?;
    if rec.status == RunStatus::OverlapsWall {
        dst.record_overlaps_wall(run_id, &attrs, rec.not_run.as_deref().unwrap_or("overlaps the wall"))?;
        return Ok(rec.status);
    }
    let snaps = src.snapshots(&rec.run_id)?;
    if dst.has_run(run_id) {
        dst.remove_run(run_id)?;
    }
    let mut w = dst.begin_run(&rec.run_id, &attrs, &snaps.triangles)?;
    for s in src.timeseries(&rec.run_id)? {
        w.append_sample(&s)?;
    }
    for (k, (t, v)) in snaps.times_s.iter().zip(&snaps.vertices_um).enumerate() {
        let fields: Vec<(&str, &[f64])> = snaps.fields.iter().map(|(n, rows)| (n.as_str(), rows[k].as_slice())).collect();
        w.append_snapshot_with(*t, v, &fields)?;
    }
    for t in &rec.transits {
        w.set_transit(t)?;
    }
    match (&rec.summary, rec.status) {
        (Some(s), _) => w.finish(s)?,
        (None, RunStatus::Failed) => w.fail(rec.failure.as_deref().unwrap_or("failed"))?,
        _ => w.flush()?,
    }
    if let Some(c) = &rec.copied_from {
        dst.set_copied_from(run_id, c)?;
    }
    Ok(rec.status)
}
