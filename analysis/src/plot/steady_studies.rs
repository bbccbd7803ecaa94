//! The steady states of several studies against the cell velocity, side by side in three panels
//! (the paper's Fig. 6 (a, b): Guckenberger et al., "Numerical-experimental observation of shape
//! bistability of red blood cells flowing in a microchannel", and the membrane's motion it
//! describes in words):
//!
//! - (a) the steady radial position of each class (non-tank-treading croissant, tank-treading
//!   croissant, slipper) per velocity column: the mean over the steady window of each run,
//!   weighted over the column's runs by their observation time in the steady state (the paper's
//!   weighting, [`column_means`]), vertical bars the smallest and largest radial position over the
//!   windows, horizontal bars the smallest and largest velocity; one colour per study, the marker
//!   the class;
//! - (b) the slippers' bounding-box extents along x (length), y and z, weighted the same way; the
//!   colour the axis, the marker the study (triangle, square, filled and hollow circle, in the
//!   order of the folders);
//! - (c) the membrane's tank-treading frequency of each class, weighted the same way (each run's
//!   frequency over the classifier's window its label was decided on, `evidence_tt_frequency_hz`:
//!   the membrane's circulation relative to the shape), bars the smallest and largest run; colours
//!   and markers as in (a); and the shape's tumbling frequency of the slippers that tumble
//!   (`evidence_tumbling_frequency_hz`, the rotation of the shape about z, for the runs labelled
//!   tumbling), squares in the study's colour. The paper's slippers tank-tread, except below
//!   ~0.7 mm/s where they tumble ("the cell rotates around the z-axis while approximately
//!   preserving its shape"; it still counts them as slippers, and so do (a) and (b)); its
//!   croissants move as rigid bodies, except above ~7 mm/s where some tank-tread.
//!
//! A study is a folder of results files ([`read_studies`]: a study's `state/` is named by its
//! study), e.g. the same grid with exact no-slip walls and with the paper's penalty walls. Only
//! the runs of one start shape that ended steady or periodic count (the runs still going are
//! counted, not drawn: they have no steady state yet).

use super::studies::{check_velocity_tol, read_studies};
use super::simulation::{column_means, draw_panel, extent_of, radial_of, tank_treading_of, tumbling_of, ColumnMean, Marker, Series, SteadyClass};
use super::{write_one, DrawResult, Figure, SERIES_COLOURS};
use crate::error::AnalysisError;
use plotters::coord::Shift;
use plotters::prelude::*;
use rbc_schema::results::RunRecord;
use std::path::{Path, PathBuf};

/// Name of the figure in its output folder (`.png` and `.svg`).
pub const NAME: &str = "steady_studies";

/// The bounding-box axes of panel (b), in its order, with their legend names.
pub const AXES: [(&str, &str); 3] = [("x", "length (x)"), ("y", "extent y"), ("z", "extent z")];

/// One study's steady states.
#[derive(Debug, Clone)]
pub struct StudySteady {
    /// The study (its folder's name, [`read_studies`]).
    pub label: String,
    /// Panel (a): the radial position (um) per class and velocity column, by class, then velocity.
    pub radial: Vec<ColumnMean>,
    /// Panel (b): the slippers' extents (um) along x, y and z ([`AXES`]) per velocity column.
    pub extents: [Vec<ColumnMean>; 3],
    /// Panel (c): the membrane's tank-treading frequency (Hz) per class and velocity column, by
    /// class, then velocity.
    pub tank_treading: Vec<ColumnMean>,
    /// Panel (c) too: the shape's tumbling frequency (Hz) of the slippers labelled tumbling, per
    /// velocity column (class [`SteadyClass::Slipper`]), by velocity.
    pub tumbling: Vec<ColumnMean>,
    /// Its runs of the start shape still going (not drawn).
    pub running: usize,
}

/// The steady states of one start shape against the cell velocity, one colour or marker per study.
#[derive(Debug, Clone)]
pub struct SteadyStudiesFigure {
    start_shape: String,
    studies: Vec<StudySteady>,
    skipped: Vec<String>,
}

impl SteadyStudiesFigure {
    /// Read the runs of start shape `start_shape` from `files`, one study per folder of files
    /// ([`read_studies`]: a file that cannot be read, or a run id two files of one folder hold, is
    /// an error naming the file), the velocity columns binned at `rel_tol` (relative, as
    /// `rbc-predict`'s). A study without an ended run of the start shape that is a croissant or a
    /// slipper draws nothing; none at all is an error (with the number of runs left out).
    pub fn read(files: &[&Path], start_shape: &str, rel_tol: f64) -> Result<Self, AnalysisError> {
        check_velocity_tol(files, rel_tol)?;
        let classes = [SteadyClass::Croissant, SteadyClass::TankTreadingCroissant, SteadyClass::Slipper];
        let mut studies = Vec::new();
        let mut skipped = Vec::new();
        for study in read_studies(files)? {
            let runs = study.runs_of(start_shape)?;
            skipped.extend(runs.left_out.into_iter().map(|l| l.message));
            let ended: Vec<RunRecord> = runs.ended.iter().map(|(_, r)| (*r).clone()).collect();
            let radial = column_means(&ended, rel_tol, &classes, &radial_of);
            let extents = AXES.map(|(axis, _)| column_means(&ended, rel_tol, &[SteadyClass::Slipper], &move |r| extent_of(r, axis)));
            let tank_treading = column_means(&ended, rel_tol, &classes, &tank_treading_of);
            let tumbling = column_means(&ended, rel_tol, &[SteadyClass::Slipper], &tumbling_of);
            let running = runs.running.len();
            studies.push(StudySteady { label: study.label.clone(), radial, extents, tank_treading, tumbling, running });
        }
        if studies.iter().all(|s| s.radial.is_empty()) {
            return Err(AnalysisError::Input {
                path: files.first().map_or_else(PathBuf::new, |f| f.to_path_buf()),
                message: format!("no {start_shape} run that ended a croissant or a slipper in {} file(s) ({} left out): nothing to draw", files.len(), skipped.len()),
            });
        }
        Ok(Self { start_shape: start_shape.to_string(), studies, skipped })
    }

    /// The start shape drawn.
    pub fn start_shape(&self) -> &str {
        &self.start_shape
    }

    /// The studies, in the order of their folders (those without a steady state too).
    pub fn studies(&self) -> &[StudySteady] {
        &self.studies
    }

    /// Runs left out, one line each naming the file (as [`super::phase_studies::PhaseStudiesFigure::skipped`]).
    pub fn skipped(&self) -> &[String] {
        &self.skipped
    }

    /// Save as `out/steady_studies.png` and `.svg` (three panels of 650 x 650 px), replacing both
    /// as one set ([`rbc_schema::output_set`]); returns the two paths (PNG first).
    pub fn write(&self, out: &Path) -> Result<[PathBuf; 2], AnalysisError> {
        write_one(self, out, NAME, (1950, 650))
    }
}

/// The columns of `class` in `cols` (sorted by class, then velocity).
fn of_class(cols: &[ColumnMean], class: SteadyClass) -> &[ColumnMean] {
    &cols[cols.partition_point(|c| c.class < class)..cols.partition_point(|c| c.class <= class)]
}

impl Figure for SteadyStudiesFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let mut radial = Vec::new();
        let mut extents = Vec::new();
        let mut tank_treading = Vec::new();
        for (k, s) in self.studies.iter().enumerate() {
            let colour = SERIES_COLOURS[k % SERIES_COLOURS.len()];
            for class in [SteadyClass::Croissant, SteadyClass::TankTreadingCroissant, SteadyClass::Slipper] {
                radial.push(Series { label: format!("{}: {}", s.label, class.label()), colour, marker: class.marker(), points: of_class(&s.radial, class) });
                tank_treading.push(Series { label: format!("{}: {}", s.label, class.label()), colour, marker: class.marker(), points: of_class(&s.tank_treading, class) });
            }
            tank_treading.push(Series { label: format!("{}: slipper tumbling", s.label), colour, marker: Marker::Square, points: &s.tumbling });
            let marker = [Marker::Triangle, Marker::Square, Marker::Circle { filled: true }, Marker::Circle { filled: false }][k % 4];
            for (j, (_, name)) in AXES.iter().enumerate() {
                extents.push(Series { label: format!("{}: {name}", s.label), colour: SERIES_COLOURS[(j + 3) % SERIES_COLOURS.len()], marker, points: &s.extents[j] });
            }
        }
        let all = || self.studies.iter().flat_map(|s| s.radial.iter().chain(s.extents.iter().flatten()).chain(&s.tank_treading).chain(&s.tumbling));
        let u_max = all().map(|c| c.velocity_max_mm_s.max(c.velocity_mm_s)).fold(1.0, f64::max) * 1.08;
        let top = |cols: &mut dyn Iterator<Item = &ColumnMean>, least: f64| cols.map(|c| c.max.max(c.value)).fold(least, f64::max);
        let r_max = top(&mut self.studies.iter().flat_map(|s| s.radial.iter()), 0.5) * 1.45;
        let e_max = top(&mut self.studies.iter().flat_map(|s| s.extents.iter().flatten()), 1.0) * 1.45;
        let f_max = top(&mut self.studies.iter().flat_map(|s| s.tank_treading.iter().chain(&s.tumbling)), 1.0) * 1.45;
        let areas = root.split_evenly((1, 3));
        let start = &self.start_shape;
        draw_panel(&areas[0], &format!("(a) steady radial position, start: {start}"), "radial centroid position (um)", (u_max, r_max), &radial)?;
        draw_panel(&areas[1], &format!("(b) slipper extents, start: {start}"), "bounding-box extent (um)", (u_max, e_max), &extents)?;
        draw_panel(&areas[2], &format!("(c) membrane tank-treading, shape tumbling, start: {start}"), "tank-treading or tumbling frequency (Hz)", (u_max, f_max), &tank_treading)
    }
}
