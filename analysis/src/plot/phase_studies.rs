//! Phase diagrams of several studies side by side, one panel per study (the paper's Fig. 5 a:
//! Guckenberger et al., "Numerical-experimental observation of shape bistability of red blood
//! cells flowing in a microchannel"), e.g. the same grid with exact no-slip walls and with the
//! paper's penalty walls: each panel is [`PhaseDiagramFigure`] of the study's ended runs (steady
//! or periodic: mean cell velocity u against r_init, the final shape, r_trans(u) with its bracket)
//! and its runs still going, hollow at the mean velocity of their last
//! [`super::studies::RUNNING_WINDOW_S`]. The panels share their axes. [`PhaseStudiesFigure::read`]
//! never returns a figure without a panel.

use super::prediction::PhaseDiagramFigure;
use super::studies::{check_velocity_tol, read_studies, RunningRun};
use super::{write_one, DrawResult, Figure};
use crate::error::AnalysisError;
use crate::simulated::phase::PhasePoint;
use crate::simulated::threshold::{thresholds, Threshold};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Name of the figure in its output folder (`.png` and `.svg`).
pub const NAME: &str = "phase_studies";

/// One study's panel.
#[derive(Debug, Clone)]
pub struct StudyPhase {
    /// The study (its folder's name, [`read_studies`]).
    pub label: String,
    /// The ended runs of the start shape (steady or periodic), by velocity, then r_init.
    pub points: Vec<PhasePoint>,
    /// r_trans per velocity column of those runs (columns binned at the figure's `rel_tol`).
    pub thresholds: Vec<Threshold>,
    /// The runs of the start shape still going, by their recent velocity, then r_init.
    pub running: Vec<RunningRun>,
}

/// The phase diagrams of one start shape, one panel per study.
#[derive(Debug, Clone)]
pub struct PhaseStudiesFigure {
    start_shape: String,
    studies: Vec<StudyPhase>,
    skipped: Vec<String>,
}

impl PhaseStudiesFigure {
    /// Read the runs of start shape `start_shape` from `files`, one study per folder of files
    /// ([`read_studies`]: a file that cannot be read, or a run id two files of one folder hold, is
    /// an error naming the file), the velocity columns binned at `rel_tol` (relative; the
    /// default of `rbc-predict` and `rbc-sweep figures` is
    /// [`crate::simulated::phase::DEFAULT_VELOCITY_REL_TOL`]). A study with neither an ended run
    /// nor a run still going of the start shape (none, or all left out) has no panel; no panel
    /// at all is an error (with the number of runs left out).
    pub fn read(files: &[&Path], start_shape: &str, rel_tol: f64) -> Result<Self, AnalysisError> {
        check_velocity_tol(files, rel_tol)?;
        let mut studies = Vec::new();
        let mut skipped = Vec::new();
        for study in read_studies(files)? {
            let runs = study.runs_of(start_shape)?;
            skipped.extend(runs.left_out.into_iter().map(|l| l.message));
            let mut points: Vec<PhasePoint> = runs.ended.into_iter().map(|(p, _)| p).collect();
            let mut running = runs.running;
            if points.is_empty() && running.is_empty() {
                continue;
            }
            points.sort_by(|a, b| a.velocity_mm_s.total_cmp(&b.velocity_mm_s).then(a.r_init_um.total_cmp(&b.r_init_um)));
            running.sort_by(|a, b| a.tail.velocity_mm_s.total_cmp(&b.tail.velocity_mm_s).then(a.r_init_um.total_cmp(&b.r_init_um)));
            let thresholds = thresholds(&points, rel_tol);
            studies.push(StudyPhase { label: study.label, points, thresholds, running });
        }
        if studies.is_empty() {
            return Err(AnalysisError::Input {
                path: files.first().map_or_else(PathBuf::new, |f| f.to_path_buf()),
                message: format!("no {start_shape} run, ended or still going, in {} file(s) ({} left out): nothing to draw", files.len(), skipped.len()),
            });
        }
        Ok(Self { start_shape: start_shape.to_string(), studies, skipped })
    }

    /// The start shape drawn.
    pub fn start_shape(&self) -> &str {
        &self.start_shape
    }

    /// The panels, one per study with runs of the start shape, in the order of the folders.
    pub fn studies(&self) -> &[StudyPhase] {
        &self.studies
    }

    /// Runs left out, one line each naming the file: of the start shape, failed, not run,
    /// unsteady (no converged shape), without a positive finite velocity, or still going without
    /// a finite sample; and runs without start attributes.
    pub fn skipped(&self) -> &[String] {
        &self.skipped
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
