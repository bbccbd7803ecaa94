//! Phase diagrams of several studies side by side, one panel per study (the paper's Fig. 5 a:
//! Guckenberger et al., "Numerical-experimental observation of shape bistability of red blood
//! cells flowing in a microchannel"), e.g. the same grid with exact no-slip walls and with the
//! paper's penalty walls: each panel is [`PhaseDiagramFigure`] of the study's ended runs (steady
//! or periodic: mean cell velocity u against r_init, the final shape, r_trans(u) with its bracket)
//! and its runs still going, hollow at the mean velocity of their last
//! [`super::studies::RUNNING_WINDOW_S`]. The panels share their axes.

use super::prediction::PhaseDiagramFigure;
use super::studies::{read_studies, running_tail};
use super::{write_one, DrawResult, Figure};
use crate::error::AnalysisError;
use crate::simulated::phase::{phase_points, PhasePoint, DEFAULT_VELOCITY_REL_TOL};
use crate::simulated::threshold::{thresholds, Threshold};
use plotters::coord::Shift;
use plotters::prelude::*;
use rbc_schema::results::RunStatus;
use std::path::{Path, PathBuf};

/// Name of the figure in its output folder (`.png` and `.svg`).
pub const NAME: &str = "phase_studies";

/// A run still going, placed in the phase diagram by its start and its recent velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct RunningRun {
    pub run_id: String,
    pub start_shape: String,
    /// Initial centroid offset from the axis, um.
    pub r_init_um: f64,
    /// Its last sample's time, s.
    pub t_s: f64,
    /// Mean cell velocity over its last [`super::studies::RUNNING_WINDOW_S`], mm/s.
    pub velocity_mm_s: f64,
}

/// One study's panel.
#[derive(Debug, Clone)]
pub struct StudyPhase {
    /// The study (its folder's name, [`read_studies`]).
    pub label: String,
    /// The ended runs of the start shape (steady or periodic).
    pub points: Vec<PhasePoint>,
    /// r_trans per velocity column of those runs (columns binned at
    /// [`DEFAULT_VELOCITY_REL_TOL`]).
    pub thresholds: Vec<Threshold>,
    /// The runs of the start shape still going.
    pub running: Vec<RunningRun>,
}

/// The phase diagrams of one start shape, one panel per study.
#[derive(Debug, Clone)]
pub struct PhaseStudiesFigure {
    pub start_shape: String,
    pub studies: Vec<StudyPhase>,
    /// Runs of the start shape left out, with the reason: failed, not run, unsteady (no converged
    /// shape), or still going without a finite sample.
    pub skipped: Vec<String>,
}

impl PhaseStudiesFigure {
    /// Read the runs of start shape `start_shape` from `files`, one study per folder of files
    /// ([`read_studies`]: a file that cannot be read, or a run id two files of one folder hold, is
    /// an error naming the file). A study without any run of the start shape has no panel; no run
    /// at all, ended or going, is an error.
    pub fn read(files: &[&Path], start_shape: &str) -> Result<Self, AnalysisError> {
        let mut studies = Vec::new();
        let mut skipped = Vec::new();
        for study in read_studies(files)? {
            let mut points = Vec::new();
            let mut running = Vec::new();
            for (f, runs) in &study.files {
                let ours = |id: &str| runs.iter().any(|r| r.run_id == id && r.attrs.as_ref().is_some_and(|a| a.start_shape == start_shape));
                for r in runs.iter().filter(|r| r.status == RunStatus::Running && ours(&r.run_id)) {
                    let Some(a) = &r.attrs else { continue };
                    match running_tail(f, &r.run_id)? {
                        Some(tail) => running.push(RunningRun { run_id: r.run_id.clone(), start_shape: a.start_shape.clone(), r_init_um: a.r_init_um, t_s: tail.t_s, velocity_mm_s: tail.velocity_mm_s }),
                        None => skipped.push(format!("{}: run {} left out: still running, no finite sample yet", f.display(), r.run_id)),
                    }
                }
                let (ended, left_out) = phase_points(runs);
                points.extend(ended.into_iter().filter(|p| p.start_shape == start_shape));
                let going = |id: &str| runs.iter().any(|r| r.run_id == id && r.status == RunStatus::Running);
                skipped.extend(left_out.into_iter().filter(|s| ours(&s.run_id) && !going(&s.run_id)).map(|s| format!("{}: run {} left out: {}", f.display(), s.run_id, s.reason)));
            }
            if points.is_empty() && running.is_empty() {
                continue;
            }
            points.sort_by(|a, b| a.velocity_mm_s.total_cmp(&b.velocity_mm_s).then(a.r_init_um.total_cmp(&b.r_init_um)));
            running.sort_by(|a, b| a.velocity_mm_s.total_cmp(&b.velocity_mm_s).then(a.r_init_um.total_cmp(&b.r_init_um)));
            let thresholds = thresholds(&points, DEFAULT_VELOCITY_REL_TOL);
            studies.push(StudyPhase { label: study.label, points, thresholds, running });
        }
        if studies.is_empty() {
            return Err(AnalysisError::Input {
                path: files.first().map_or_else(PathBuf::new, |f| f.to_path_buf()),
                message: format!("no {start_shape} run, ended or still going, in {} file(s): nothing to draw", files.len()),
            });
        }
        Ok(Self { start_shape: start_shape.to_string(), studies, skipped })
    }

    /// Save as `out/phase_studies.png` and `.svg` (650 px wide a panel, 650 high), replacing both
    /// as one set ([`rbc_schema::output_set`]); returns the two paths (PNG first).
    pub fn write(&self, out: &Path) -> Result<[PathBuf; 2], AnalysisError> {
        write_one(self, out, NAME, (650 * self.studies.len() as u32, 650))
    }

    fn panel<'a>(&self, s: &'a StudyPhase) -> PhaseDiagramFigure<'a> {
        PhaseDiagramFigure::new(&s.points, &s.thresholds, &self.start_shape).with_running(&s.running).with_caption(format!("{}, start shape: {}", s.label, self.start_shape))
    }
}

impl Figure for PhaseStudiesFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        // one extent for all panels: the largest each asks for
        let extent = self.studies.iter().map(|s| self.panel(s).extent()).fold((0.0f64, 0.0f64), |(u, r), (a, b)| (u.max(a), r.max(b)));
        let areas = root.split_evenly((1, self.studies.len()));
        for (s, area) in self.studies.iter().zip(&areas) {
            self.panel(s).with_extent(extent).draw(area)?;
        }
        Ok(())
    }
}
