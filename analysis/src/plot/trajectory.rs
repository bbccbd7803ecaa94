//! Runs in progress, drawn from their time series: lateral position (y, z) and asphericity against time, one colour per run (for a study's progress; any run status).

use super::{draw_legend, write_one, DrawResult, Figure, FONT_FAMILY, SERIES_COLOURS};
use crate::error::AnalysisError;
use plotters::coord::Shift;
use plotters::prelude::*;
use rbc_schema::results::{read_runs, read_timeseries};
use std::path::{Path, PathBuf};

/// Points drawn per series at most (the figure stays small however long the run).
pub const MAX_POINTS: usize = 2000;

/// One run's series: time (ms), centroid y and z (um), asphericity.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    pub run_id: String,
    /// The legend's name: the run id, with the folder that tells its file apart when another file
    /// holds a run of the same id (two studies of the same grid: `discocyte_u1.5_r0.8
    /// (science-6p5-penalty)`; [`folder_tags`]).
    pub label: String,
    pub t_ms: Vec<f64>,
    pub y_um: Vec<f64>,
    pub z_um: Vec<f64>,
    pub asphericity: Vec<f64>,
}

/// Lateral position and asphericity against time of every run of some results files.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TrajectoryFigure {
    pub runs: Vec<Trajectory>,
}

/// Name of the figure in its output folder (`.png` and `.svg`).
pub const NAME: &str = "trajectories";

impl TrajectoryFigure {
    /// Save as `out/trajectories.png` and `.svg` (1200 x 520 px), replacing both as one set
    /// ([`rbc_schema::output_set`]); returns the two paths (PNG first).
    pub fn write(&self, out: &Path) -> Result<[PathBuf; 2], AnalysisError> {
        write_one(self, out, NAME, (1200, 520))
    }

    /// Read every run (any status) of every file, thinned to at most [`MAX_POINTS`] samples per run
    /// (evenly, the last one kept); a file without runs is an error naming it.
    pub fn read(files: &[&Path]) -> Result<Self, AnalysisError> {
        let mut runs: Vec<Trajectory> = Vec::new();
        let mut sources: Vec<&Path> = Vec::new();
        for &f in files {
            let records = read_runs(f)?;
            if records.is_empty() {
                return Err(AnalysisError::Input { path: f.into(), message: "no run".into() });
            }
            for r in records {
                if r.status == rbc_schema::results::RunStatus::OverlapsWall {
                    continue; // never run: no trajectory
                }
                let all = read_timeseries(f, &r.run_id)?;
                // at most ~MAX_POINTS points per series (a long run has a row every output interval)
                let stride = all.len().div_ceil(MAX_POINTS).max(1);
                let ts: Vec<_> = all.iter().step_by(stride).chain(all.last().filter(|_| (all.len() - 1) % stride != 0)).collect();
                runs.push(Trajectory {
                    label: r.run_id.clone(),
                    run_id: r.run_id,
                    t_ms: ts.iter().map(|s| s.t_s * 1e3).collect(),
                    y_um: ts.iter().map(|s| s.centroid_um[1]).collect(),
                    z_um: ts.iter().map(|s| s.centroid_um[2]).collect(),
                    asphericity: ts.iter().map(|s| s.asphericity).collect(),
                });
                sources.push(f);
            }
        }
        let runs_ids: Vec<String> = runs.iter().map(|r| r.run_id.clone()).collect();
        for (k, r) in runs.iter_mut().enumerate() {
            let group: Vec<usize> = (0..runs_ids.len()).filter(|&j| runs_ids[j] == r.run_id).collect();
            if group.len() > 1 {
                // whole paths, so that `state/x.h5` and `../other/state/x.h5` differ in their study's folder
                let whole: Vec<PathBuf> = group.iter().map(|&j| std::fs::canonicalize(sources[j]).unwrap_or_else(|_| sources[j].to_path_buf())).collect();
                let files: Vec<&Path> = whole.iter().map(PathBuf::as_path).collect();
                let at = group.iter().position(|&j| j == k).expect("the run is in its own group");
                r.label = format!("{} ({})", r.run_id, folder_tags(&files)[at]);
            }
        }
        Ok(Self { runs })
    }
}

/// For files that hold runs of the same id, the name that tells each apart: the innermost
/// folder of their paths in which they differ (`a/state/x.h5`, `b/state/x.h5` -> `a`, `b`; a
/// path that has no folder there is named by its whole folder), else the file name, else the
/// file's place in the list (`#1`, ...).
pub fn folder_tags(files: &[&Path]) -> Vec<String> {
    let parts: Vec<Vec<String>> = files
        .iter()
        .map(|f| f.parent().map_or_else(Vec::new, |d| d.components().rev().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect()))
        .collect();
    let depth = parts.iter().map(Vec::len).max().unwrap_or(0);
    let at = |p: &Vec<String>, k: usize| p.get(k).cloned().unwrap_or_default();
    if let Some(k) = (0..depth).find(|&k| parts.iter().any(|p| at(p, k) != at(&parts[0], k))) {
        // a path that ends above that folder is named by its whole folder
        let whole = |f: &Path| f.parent().map_or_else(|| ".".into(), |d| d.display().to_string());
        return parts.iter().zip(files).map(|(p, f)| Some(at(p, k)).filter(|t| !t.is_empty()).unwrap_or_else(|| whole(f))).collect();
    }
    let names: Vec<String> = files.iter().map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()).collect();
    if names.iter().any(|n| *n != names[0]) {
        return names;
    }
    (1..=files.len()).map(|k| format!("#{k}")).collect()
}


/// The range of `v` with a 5 % margin (a flat or empty series gets a unit range).
fn range(v: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = v.filter(|x| x.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    if hi <= lo {
        let c = if lo.is_finite() { lo } else { 0.0 };
        return c - 0.5..c + 0.5;
    }
    let m = 0.05 * (hi - lo);
    lo - m..hi + m
}

impl Figure for TrajectoryFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let panels = root.split_evenly((1, 2));
        let t = range(self.runs.iter().flat_map(|r| r.t_ms.iter().copied()));
        // left: y solid, z dashed; right: asphericity
        let lateral = range(self.runs.iter().flat_map(|r| r.y_um.iter().chain(&r.z_um).copied()));
        let mut chart = ChartBuilder::on(&panels[0])
            .caption("Lateral position (y solid, z dashed)", (FONT_FAMILY, 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(t.clone(), lateral)?;
        chart.configure_mesh().x_desc("t (ms)").y_desc("centroid (um)").label_style((FONT_FAMILY, 14)).draw()?;
        for (k, r) in self.runs.iter().enumerate() {
            let c = SERIES_COLOURS[k % SERIES_COLOURS.len()];
            chart
                .draw_series(LineSeries::new(r.t_ms.iter().zip(&r.y_um).map(|(&t, &y)| (t, y)), c.stroke_width(2)))?
                .label(format!("{} (y)", r.label))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
            chart.draw_series(DashedLineSeries::new(r.t_ms.iter().zip(&r.z_um).map(|(&t, &z)| (t, z)), 6, 4, c.stroke_width(2)))?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        let a = range(self.runs.iter().flat_map(|r| r.asphericity.iter().copied()));
        let mut chart = ChartBuilder::on(&panels[1])
            .caption("Asphericity", (FONT_FAMILY, 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(t, a)?;
        chart.configure_mesh().x_desc("t (ms)").y_desc("asphericity").label_style((FONT_FAMILY, 14)).draw()?;
        for (k, r) in self.runs.iter().enumerate() {
            let c = SERIES_COLOURS[k % SERIES_COLOURS.len()];
            chart.draw_series(LineSeries::new(r.t_ms.iter().zip(&r.asphericity).map(|(&t, &a)| (t, a)), c.stroke_width(2)))?;
        }
        Ok(())
    }
}
