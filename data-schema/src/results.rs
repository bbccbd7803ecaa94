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
use std::path::Path;

/// The layout version this build writes and reads.
pub const SCHEMA_VERSION: u32 = 1;

/// Rows per chunk of the timeseries datasets (a chunk of `centroid_um` is 6 KiB).
const TIMESERIES_CHUNK: usize = 256;


mod file;
mod merge;
mod records;
mod writer;

pub use file::ResultsFile;
pub use merge::{copy_run, merge_files, read_runs, read_snapshots, read_timeseries};
pub use records::*;
pub use writer::{RunWriter, SAMPLE_BUFFER};

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

/// Whether a run id is usable as an HDF5 group name: not empty, no `/`, not `.` or `..`.
pub(crate) fn is_valid_run_id(run_id: &str) -> bool {
    !(run_id.is_empty() || run_id.contains('/') || run_id == "." || run_id == "..")
}

/// Check that a run id is usable as an HDF5 group name.
fn check_run_id(path: &Path, run_id: &str) -> Result<()> {
    if !is_valid_run_id(run_id) {
        return Err(invalid(path, format!("run id `{run_id}` is not a valid group name (empty, `/`, `.` or `..`)")));
    }
    Ok(())
}

// ---------------------------------------------------------------- writer

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
