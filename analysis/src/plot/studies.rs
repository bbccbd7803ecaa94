//! The runs of several studies' results files, grouped by study, for the figures that draw
//! studies side by side (the steady radial position of [`super::offset`], the phase diagrams of
//! [`super::phase_studies`]): one group per folder of files (a study's `state/` folder is named by
//! its study), each file and each run once; per start shape, its ended runs, its runs still going
//! with where each stands at the end of its file, and the runs left out with the reason.

use super::trajectory::folder_tags;
use crate::error::AnalysisError;
use crate::simulated::phase::{phase_points, PhasePoint};
use rbc_schema::results::{read_runs, read_timeseries, RunRecord, RunStatus, TimeSample};
use std::path::{Path, PathBuf};

/// The files of one folder, in the order given, each with its runs.
#[derive(Debug, Clone)]
pub struct StudyFiles {
    /// The folder's name (a study's `state/` folder is named by its study); when two folders share
    /// that name, the innermost folder in which their paths differ ([`folder_tags`]).
    pub label: String,
    pub files: Vec<(PathBuf, Vec<RunRecord>)>,
}

/// `Ok` when `rel_tol` (relative, for binning the runs' velocities into columns) is finite and
/// `>= 0`, else the error naming the first of `files`.
pub fn check_velocity_tol(files: &[&Path], rel_tol: f64) -> Result<(), AnalysisError> {
    if rel_tol.is_finite() && rel_tol >= 0.0 {
        return Ok(());
    }
    Err(AnalysisError::Input { path: files.first().map_or_else(PathBuf::new, |f| f.to_path_buf()), message: format!("velocity tolerance {rel_tol}: need a finite tolerance >= 0") })
}

/// Read `files` grouped by folder, the folders in the order of their first file. A file that
/// cannot be read is an error naming it; so is a run id that two files of one folder hold, of any
/// start shape (a file given twice, or named by two paths, counts once).
pub fn read_studies(files: &[&Path]) -> Result<Vec<StudyFiles>, AnalysisError> {
    let mut folders: Vec<PathBuf> = Vec::new();
    let mut groups: Vec<Vec<(PathBuf, Vec<RunRecord>)>> = Vec::new();
    let mut read: Vec<PathBuf> = Vec::new(); // files read, by canonical path
    let mut ids: Vec<(usize, String, PathBuf)> = Vec::new(); // (folder, run id, its file)
    for &f in files {
        let whole = std::fs::canonicalize(f).unwrap_or_else(|_| f.to_path_buf());
        if read.contains(&whole) {
            continue; // the same file again (a repeated or overlapping glob)
        }
        read.push(whole.clone());
        let runs = read_runs(f)?;
        let folder = whole.parent().map_or_else(PathBuf::new, Path::to_path_buf);
        let at = folders.iter().position(|d| *d == folder).unwrap_or_else(|| {
            folders.push(folder.clone());
            groups.push(Vec::new());
            folders.len() - 1
        });
        for r in &runs {
            if let Some((_, _, g)) = ids.iter().find(|(k, id, _)| *k == at && *id == r.run_id) {
                return Err(AnalysisError::Input { path: f.into(), message: format!("run {} is also in {}: one folder, one file per run", r.run_id, g.display()) });
            }
            ids.push((at, r.run_id.clone(), whole.clone()));
        }
        groups[at].push((f.to_path_buf(), runs));
    }
    let labels = folder_labels(&folders);
    Ok(labels.into_iter().zip(groups).map(|(label, files)| StudyFiles { label, files }).collect())
}

/// The groups' names: each folder's name, or that of the folder above it when it is a study's
/// `state`; where two folders would share a name, [`folder_tags`] of their paths.
fn folder_labels(folders: &[PathBuf]) -> Vec<String> {
    let name = |d: &Path| -> String {
        let last = d.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| d.display().to_string());
        match (last.as_str(), d.parent().and_then(Path::file_name)) {
            ("state", Some(study)) => study.to_string_lossy().into_owned(),
            _ => last,
        }
    };
    let names: Vec<String> = folders.iter().map(|d| name(d)).collect();
    if names.iter().enumerate().all(|(k, n)| !names[..k].contains(n)) {
        return names;
    }
    // folder_tags names files: give it a file inside each folder
    let inside: Vec<PathBuf> = folders.iter().map(|d| d.join("x")).collect();
    folder_tags(&inside.iter().map(PathBuf::as_path).collect::<Vec<_>>())
}

/// The stretch at the end of a running run whose mean velocity places it in a velocity column and
/// whose radial range the figures draw, s.
pub const RUNNING_WINDOW_S: f64 = 0.05;

/// Where a run still going stands at the end of its file.
#[derive(Debug, Clone, PartialEq)]
pub struct Tail {
    /// Its last sample's time, s.
    pub t_s: f64,
    /// Its last sample's radial position `sqrt(y^2 + z^2)`, um.
    pub radial_um: f64,
    /// Smallest and largest radial position over its last [`RUNNING_WINDOW_S`], um (a slipper's
    /// swing: one sample alone may sit anywhere in it).
    pub radial_min_um: f64,
    pub radial_max_um: f64,
    /// Mean x-velocity of the cell over its last [`RUNNING_WINDOW_S`] (all of it when shorter),
    /// mm/s: what places it in a velocity column.
    pub velocity_mm_s: f64,
}

/// The [`Tail`] of run `run_id` of `file` from its finite samples; `None` when it has none yet.
pub fn running_tail(file: &Path, run_id: &str) -> Result<Option<Tail>, AnalysisError> {
    let rows: Vec<TimeSample> = read_timeseries(file, run_id)?.into_iter().filter(|s| s.t_s.is_finite() && s.centroid_um.iter().chain(&s.velocity_mm_s).all(|v| v.is_finite())).collect();
    let Some(last) = rows.last() else { return Ok(None) };
    let tail: Vec<&TimeSample> = rows.iter().filter(|s| s.t_s >= last.t_s - RUNNING_WINDOW_S).collect();
    let radial = |s: &TimeSample| s.centroid_um[1].hypot(s.centroid_um[2]);
    Ok(Some(Tail {
        t_s: last.t_s,
        radial_um: radial(last),
        radial_min_um: tail.iter().map(|s| radial(s)).fold(f64::INFINITY, f64::min),
        radial_max_um: tail.iter().map(|s| radial(s)).fold(f64::NEG_INFINITY, f64::max),
        velocity_mm_s: tail.iter().map(|s| s.velocity_mm_s[0]).sum::<f64>() / tail.len() as f64,
    }))
}

/// A run still going: its start, and where it stands at the end of its file.
#[derive(Debug, Clone, PartialEq)]
pub struct RunningRun {
    pub run_id: String,
    pub start_shape: String,
    /// Initial centroid offset from the axis, um.
    pub r_init_um: f64,
    pub tail: Tail,
}

/// A run that is neither an ended run nor a run still going with a sample, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct LeftOut {
    /// One line naming the file and the run: `FILE: run ID left out: REASON`.
    pub message: String,
    /// Its mean velocity when it ended with one (e.g. unsteady), mm/s: which velocity column it
    /// belongs to.
    pub velocity_mm_s: Option<f64>,
}

/// The runs of one start shape in a study's files.
#[derive(Debug, Clone)]
pub struct StartRuns<'a> {
    /// The runs that ended steady or periodic ([`phase_points`]), each with its record.
    pub ended: Vec<(PhasePoint, &'a RunRecord)>,
    /// The runs still going that have a finite sample.
    pub running: Vec<RunningRun>,
    /// The start shape's runs that ended without a phase point (failed, not run, unsteady, no
    /// positive finite velocity) or are still going without a finite sample yet, and the runs
    /// of no start shape (without attributes), whatever the start shape asked for.
    pub left_out: Vec<LeftOut>,
}

impl StudyFiles {
    /// The runs of start shape `start_shape` in this study's files, in the files' order.
    pub fn runs_of(&self, start_shape: &str) -> Result<StartRuns<'_>, AnalysisError> {
        let mut out = StartRuns { ended: Vec::new(), running: Vec::new(), left_out: Vec::new() };
        for (f, runs) in &self.files {
            let (points, skipped) = phase_points(runs);
            let left = |id: &str, reason: &str, velocity_mm_s| LeftOut { message: format!("{}: run {id} left out: {reason}", f.display()), velocity_mm_s };
            for r in runs {
                let Some(a) = &r.attrs else {
                    out.left_out.push(left(&r.run_id, &format!("no start attributes (status {})", r.status.as_str()), None));
                    continue;
                };
                if a.start_shape != start_shape {
                    continue;
                }
                if r.status == RunStatus::Running {
                    match running_tail(f, &r.run_id)? {
                        Some(tail) => out.running.push(RunningRun { run_id: r.run_id.clone(), start_shape: a.start_shape.clone(), r_init_um: a.r_init_um, tail }),
                        None => out.left_out.push(left(&r.run_id, "still running, no finite sample yet", None)),
                    }
                } else if let Some(p) = points.iter().find(|p| p.run_id == r.run_id) {
                    out.ended.push((p.clone(), r));
                } else if let Some(s) = skipped.iter().find(|s| s.run_id == r.run_id) {
                    out.left_out.push(left(&r.run_id, &s.reason, r.summary.as_ref().map(|m| m.mean_velocity_mm_s)));
                }
            }
        }
        Ok(out)
    }
}
