//! The steady radial position against the initial offset `r_init` in one velocity column: the
//! paper's Fig. 4 (Guckenberger et al., "Numerical-experimental observation of shape bistability
//! of red blood cells flowing in a microchannel", at ~6.5 mm/s: croissants near the axis from
//! starts below ~0.7 um, slippers off it from starts above). One series per source folder, so
//! that two studies of the same grid (e.g. exact and penalty walls) are drawn side by side.

use super::studies::{read_studies, RunningRun};
pub use super::studies::RUNNING_WINDOW_S;
use super::{chart_xy, draw_legend, draw_y_error_bar, write_one, DrawResult, Figure, FONT_FAMILY, SERIES_COLOURS};
use crate::error::AnalysisError;
use plotters::coord::Shift;
use plotters::prelude::*;
use super::simulation::radial_of;
use rbc_schema::results::FinalShape;
use std::path::{Path, PathBuf};

/// Name of the figure in its output folder (`.png` and `.svg`).
pub const NAME: &str = "radial_offset";

/// One ended run of the column.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetPoint {
    pub run_id: String,
    /// Initial centroid offset from the axis, um.
    pub r_init_um: f64,
    /// Mean cell velocity over the steady window, mm/s.
    pub velocity_mm_s: f64,
    /// Mean of `sqrt(y^2 + z^2)` of the centroid over the steady window, um.
    pub mean_radial_um: f64,
    /// Smallest and largest radial position over the steady window, um (the run's evidence
    /// `radial_min_um`, `radial_max_um`; the mean when a run has none).
    pub radial_min_um: f64,
    pub radial_max_um: f64,
    pub final_shape: FinalShape,
}

/// The runs of one source folder, by increasing `r_init`.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetSeries {
    /// The folder's name (a study's `state/` folder is named by its study); when two sources share
    /// that name, the innermost folder in which their paths differ ([`read_studies`]).
    pub label: String,
    /// The ended runs (steady or periodic).
    pub points: Vec<OffsetPoint>,
    /// The runs still going whose last [`RUNNING_WINDOW_S`] lie in the column, drawn hollow at
    /// their last saved radial position.
    pub running: Vec<RunningRun>,
}

/// Steady radial position against `r_init` for one start shape in one velocity column.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetFigure {
    pub start_shape: String,
    /// The column's velocity, mm/s: runs whose mean velocity lies within `rel_tol` of it.
    pub velocity_mm_s: f64,
    pub rel_tol: f64,
    /// A vertical line at this `r_init` (um), e.g. the paper's transition at ~0.7 um.
    pub mark_um: Option<f64>,
    pub series: Vec<OffsetSeries>,
    /// Runs of the start shape left out, with the reason: unsteady (no converged shape) in the
    /// column, failed, not run, or still going without a finite sample; and runs without start
    /// attributes. Runs still going are drawn ([`OffsetSeries::running`]); ended runs of other
    /// columns and runs of other start shapes are not listed.
    pub skipped: Vec<String>,
}

impl OffsetFigure {
    /// Read the runs of start shape `start_shape` whose mean velocity lies within `rel_tol`
    /// (relative) of `velocity_mm_s` from `files`, one series per folder of files: the ended ones
    /// (their steady mean) and those still going (their last [`RUNNING_WINDOW_S`]). A file that
    /// cannot be read is an error naming it; so is a column without any ended run (with the number
    /// of runs left out), and a run id that two files of one folder hold ([`read_studies`]).
    pub fn read(files: &[&Path], start_shape: &str, velocity_mm_s: f64, rel_tol: f64, mark_um: Option<f64>) -> Result<Self, AnalysisError> {
        if !(velocity_mm_s.is_finite() && velocity_mm_s > 0.0 && rel_tol.is_finite() && rel_tol >= 0.0) {
            return Err(AnalysisError::Input {
                path: files.first().map_or_else(PathBuf::new, |f| f.to_path_buf()),
                message: format!("velocity {velocity_mm_s} mm/s and tolerance {rel_tol}: need a positive velocity and a tolerance >= 0"),
            });
        }
        // a mark is an r_init on the figure's axis: inside the channel (~12 x 10 um), so at most 20 um
        if let Some(m) = mark_um.filter(|m| !(m.is_finite() && (0.0..=20.0).contains(m))) {
            return Err(AnalysisError::Input {
                path: files.first().map_or_else(PathBuf::new, |f| f.to_path_buf()),
                message: format!("--mark-um {m}: need an r_init between 0 and 20 um"),
            });
        }
        let mut series: Vec<OffsetSeries> = Vec::new();
        let mut skipped = Vec::new();
        let in_column = |v: f64| (v - velocity_mm_s).abs() <= rel_tol * velocity_mm_s;
        for study in read_studies(files)? {
            let runs = study.runs_of(start_shape)?;
            let mut s = OffsetSeries { label: study.label.clone(), points: Vec::new(), running: Vec::new() };
            s.running = runs.running.into_iter().filter(|r| in_column(r.tail.velocity_mm_s)).collect();
            // left out: unsteady only in this column; failed, not run, or no sample in any
            skipped.extend(runs.left_out.into_iter().filter(|l| l.velocity_mm_s.is_none_or(in_column)).map(|l| l.message));
            for (p, record) in runs.ended.into_iter().filter(|(p, _)| in_column(p.velocity_mm_s)) {
                let Some((mean, lo, hi)) = radial_of(record) else { continue };
                s.points.push(OffsetPoint {
                    run_id: p.run_id,
                    r_init_um: p.r_init_um,
                    velocity_mm_s: p.velocity_mm_s,
                    mean_radial_um: mean,
                    radial_min_um: lo,
                    radial_max_um: hi,
                    final_shape: p.final_shape,
                });
            }
            s.points.sort_by(|a, b| a.r_init_um.total_cmp(&b.r_init_um));
            s.running.sort_by(|a, b| a.r_init_um.total_cmp(&b.r_init_um));
            if !s.points.is_empty() || !s.running.is_empty() {
                series.push(s);
            }
        }
        if series.iter().all(|s| s.points.is_empty()) {
            return Err(AnalysisError::Input {
                path: files.first().map_or_else(PathBuf::new, |f| f.to_path_buf()),
                message: format!(
                    "no ended {start_shape} run within {:.0} % of {velocity_mm_s} mm/s in {} file(s) ({} left out): nothing to draw",
                    rel_tol * 100.0,
                    files.len(),
                    skipped.len()
                ),
            });
        }
        Ok(Self { start_shape: start_shape.to_string(), velocity_mm_s, rel_tol, mark_um, series, skipped })
    }

    /// Save as `out/radial_offset.png` and `.svg` (900 x 650 px), replacing both as one set
    /// ([`rbc_schema::output_set`]); returns the two paths (PNG first).
    pub fn write(&self, out: &Path) -> Result<[PathBuf; 2], AnalysisError> {
        write_one(self, out, NAME, (900, 650))
    }
}

impl Figure for OffsetFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let r_inits = self.series.iter().flat_map(|s| s.points.iter().map(|p| p.r_init_um).chain(s.running.iter().map(|p| p.r_init_um)));
        let x_max = r_inits.chain(self.mark_um).fold(0.5, f64::max) * 1.15;
        let radial = self.series.iter().flat_map(|s| s.points.iter().map(|p| p.radial_max_um.max(p.mean_radial_um)).chain(s.running.iter().map(|p| p.tail.radial_max_um)));
        let y_max = radial.fold(0.5, f64::max) * 1.3;
        let caption = format!("Steady radial position, start: {}, ~{:.1} mm/s (+-{:.0} %)", self.start_shape, self.velocity_mm_s, self.rel_tol * 100.0);
        let mut chart = chart_xy(root, &caption, (0f64..x_max, "initial offset r_init (um)"), (0f64..y_max, "steady radial position (um)"))?;
        let grey = RGBColor(0x55, 0x55, 0x55);
        if let Some(m) = self.mark_um {
            chart
                .draw_series(DashedLineSeries::new([(m, 0.0), (m, y_max)], 6, 5, grey.stroke_width(1)))?
                .label(format!("the paper's transition (r_init ~{m} um)"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], grey.stroke_width(1)));
        }
        for (k, s) in self.series.iter().enumerate() {
            let c = SERIES_COLOURS[k % SERIES_COLOURS.len()];
            for p in &s.points {
                draw_y_error_bar(&mut chart, p.r_init_um, (p.radial_min_um, p.radial_max_um), c.stroke_width(1), 4)?;
            }
            // a dotted guide to the eye between neighbouring starts that ended the same shape (as
            // in the paper); none across a switch, whose place between two starts the runs do not
            // tell, nor through shapes of neither kind
            for w in s.points.windows(2).filter(|w| w[0].final_shape == w[1].final_shape && w[0].final_shape != FinalShape::Other) {
                chart.draw_series(DashedLineSeries::new(w.iter().map(|p| (p.r_init_um, p.mean_radial_um)), 2, 4, c.stroke_width(1)))?;
            }
            let at = |p: &OffsetPoint| (p.r_init_um, p.mean_radial_um);
            chart.draw_series(s.points.iter().filter(|p| p.final_shape == FinalShape::Croissant).map(|p| Circle::new(at(p), 5, c.filled())))?;
            chart.draw_series(s.points.iter().filter(|p| p.final_shape == FinalShape::Slipper).map(|p| TriangleMarker::new(at(p), 6, c.filled())))?;
            chart.draw_series(s.points.iter().filter(|p| p.final_shape == FinalShape::Other).map(|p| Cross::new(at(p), 5, c.stroke_width(2))))?;
            for p in &s.running {
                draw_y_error_bar(&mut chart, p.r_init_um, (p.tail.radial_min_um, p.tail.radial_max_um), c.stroke_width(1), 4)?;
            }
            chart
                .draw_series(s.running.iter().map(|p| Circle::new((p.r_init_um, p.tail.radial_um), 6, c.stroke_width(2))))?
                .label(s.label.clone())
                .legend(move |(x, y)| Rectangle::new([(x, y - 4), (x + 16, y + 4)], c.filled()));
            // how far each has got
            chart.draw_series(s.running.iter().map(|p| {
                EmptyElement::at((p.r_init_um, p.tail.radial_um)) + Text::new(format!("{:.0} ms", p.tail.t_s * 1e3), (9, -6), (FONT_FAMILY, 13).into_font().color(&c))
            }))?;
        }
        // what the markers mean, in grey
        let key: [(&str, u8); 4] = [("croissant (steady mean, bar: min-max)", 0), ("slipper", 1), ("other", 2), ("still running: last saved position, bar: its last 50 ms", 3)];
        for (label, m) in key {
            let shown = match m {
                0 => self.series.iter().any(|s| s.points.iter().any(|p| p.final_shape == FinalShape::Croissant)),
                1 => self.series.iter().any(|s| s.points.iter().any(|p| p.final_shape == FinalShape::Slipper)),
                2 => self.series.iter().any(|s| s.points.iter().any(|p| p.final_shape == FinalShape::Other)),
                _ => self.series.iter().any(|s| !s.running.is_empty()),
            };
            if !shown {
                continue;
            }
            chart.draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?.label(label).legend(move |(x, y)| match m {
                0 => Circle::new((x + 8, y), 4, grey.filled()).into_dyn(),
                1 => TriangleMarker::new((x + 8, y), 5, grey.filled()).into_dyn(),
                2 => Cross::new((x + 8, y), 4, grey.stroke_width(2)).into_dyn(),
                _ => Circle::new((x + 8, y), 5, grey.stroke_width(2)).into_dyn(),
            });
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
    }
}
