//! Closed loop on a results.h5: every labelled simulated cell is rendered in bright field ([`crate::simulated::render3d`]), analysed like an experiment, and the analysis' label compared with the solver's.
//!
//! For each run of the results file that has a summary (a finished run; its
//! `final_shape` is the solver's label, [`crate::simulated::render3d::cell_from_results`]),
//! the run's last snapshot is rendered moving along +x at the run's mean
//! velocity ([`crate::simulated::render3d::write_recording_3d`], default depth of field
//! `sigma = 0.5 um`, the synthesiser's bright-field edge, background and noise)
//! into `<out>/<run_id>/`, the recording is analysed by the same stages as
//! `rbc-analyze` (detection, tracking, isolation with the cluster rule,
//! classification: [`crate::experiment::pipeline::analyse_detections`]), and the label of
//! its longest track is compared with the solver's. The shape classifier's
//! label alone (without the isolation stage's cluster check) is reported too.
//!
//! `rbc-synth --closed-loop results.h5 --out DIR` runs this and prints the
//! agreement table; `DIR/closed_loop.csv` holds one row per run.

use crate::experiment::classify::classify;
use crate::experiment::pipeline::{analyse_detections, StageConfig};
use crate::experiment::recording::{detect_recording, Recording};
use crate::simulated::render3d::{cell_from_results, cell_image, single_cell_spec, write_recording_3d, CellMotion, Render3dError, Render3dParams, SimulatedCell};
use crate::simulated::synth::OpticsSpec;
use crate::simulated::wave::{write_recording_mesh, WaveOptics};
use crate::experiment::track::link;
use serde::Serialize;
use std::path::Path;

/// Rendering and analysis settings of the loop.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopConfig {
    /// Pixel size of the rendered recording, um.
    pub um_per_px: f64,
    /// Read noise, fraction of full scale.
    pub noise: f64,
    pub render: Render3dParams,
    /// Noise seed of the first run (run `k` uses `seed + k`).
    pub seed: u64,
    pub stages: StageConfig,
    /// Draw the cells with the wave-optics renderer under these optics
    /// ([`crate::simulated::wave::write_recording_mesh`]) instead of [`crate::simulated::render3d`].
    pub wave: Option<WaveOptics>,
}

impl Default for LoopConfig {
    fn default() -> Self {
        LoopConfig { um_per_px: 0.2, noise: 0.01, render: Render3dParams::default(), seed: 100, stages: StageConfig::default(), wave: None }
    }
}

/// One simulated cell through the loop (a row of `closed_loop.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoopRow {
    pub run_id: String,
    /// The solver's label (`croissant|slipper|other`).
    pub solver: String,
    /// `tracks.csv` shape of the longest track (`none` when nothing was tracked).
    pub pipeline: String,
    /// The shape classifier alone on the same track.
    pub classifier: String,
    /// The isolation stage called the object merged touching cells.
    pub cluster: bool,
    pub velocity_mm_s: f64,
    /// Over the track: mean y (um from the axis), the classifier's mirror asymmetry (of the track's
    /// median mask, `classify::track_asymmetry`), medians of solidity, notch and waist; NaN where
    /// nothing was tracked, written as an empty cell of `closed_loop.csv` (never a NaN).
    #[serde(serialize_with = "unknown_as_empty")]
    pub y_um: f64,
    #[serde(serialize_with = "unknown_as_empty")]
    pub asymmetry: f64,
    #[serde(serialize_with = "unknown_as_empty")]
    pub solidity: f64,
    #[serde(serialize_with = "unknown_as_empty")]
    pub notch: f64,
    #[serde(serialize_with = "unknown_as_empty")]
    pub waist: f64,
}

/// A measure that is not finite (nothing tracked) as an empty CSV cell.
fn unknown_as_empty<S: serde::Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    if v.is_finite() {
        s.serialize_f64(*v)
    } else {
        s.serialize_none()
    }
}

/// Column order of `closed_loop.csv`.
pub const LOOP_COLUMNS: [&str; 11] = ["run_id", "solver", "pipeline", "classifier", "cluster", "velocity_mm_s", "y_um", "asymmetry", "solidity", "notch", "waist"];

fn median(mut v: Vec<f64>) -> f64 {
    crate::stats::median::median(&mut v).unwrap_or(f64::NAN)
}

/// Render `cell` into the recording folder `dir` (created, must hold no frames) and analyse it.
pub fn analyse_cell(cell: &SimulatedCell, run_id: &str, dir: &Path, seed: u64, cfg: &LoopConfig) -> Result<LoopRow, Render3dError> {
    if let Some(o) = &cfg.wave {
        let xs = cell.mesh.vertices.iter().map(|v| v[0]);
        let length = xs.clone().fold(f64::MIN, f64::max) - xs.fold(f64::MAX, f64::min);
        let (mut spec, x0) = single_cell_spec(cfg.um_per_px, cfg.noise, cell.velocity_mm_s, length);
        spec.wave = Some(*o);
        write_recording_mesh(dir, &spec, &cell.mesh, x0, cell.velocity_mm_s, &cell.label, seed)?;
    } else {
        let img = cell_image(&cell.mesh, &OpticsSpec::default(), &cfg.render)?;
        let (spec, x0) = single_cell_spec(cfg.um_per_px, cfg.noise, cell.velocity_mm_s, img.bbox_um[1] - img.bbox_um[0]);
        write_recording_3d(dir, &spec, &img, &CellMotion { x0_um: x0, velocity_mm_s: cell.velocity_mm_s }, &cell.label, seed)?;
    }
    let rec = Recording::open(dir)?;
    let det = detect_recording(&rec)?;
    let tables = analyse_detections(run_id, &rec.config, &det.detections, &cfg.stages);
    let mut row = LoopRow {
        run_id: run_id.to_string(),
        solver: cell.label.clone(),
        pipeline: "none".into(),
        classifier: "none".into(),
        cluster: false,
        velocity_mm_s: cell.velocity_mm_s,
        y_um: f64::NAN,
        asymmetry: f64::NAN,
        solidity: f64::NAN,
        notch: f64::NAN,
        waist: f64::NAN,
    };
    let Some(best) = tables.tracks.iter().max_by_key(|t| t.n_frames) else { return Ok(row) };
    // the same linking as inside analyse_detections, for the track's detections
    let tracks = link(&det.detections, rec.config.fps, &cfg.stages.tracker);
    let Some(ti) = tracks.iter().position(|t| t.id == best.track_id) else { return Ok(row) };
    let track = &tracks[ti];
    let iso = crate::experiment::isolate::isolate(&tracks, &det.detections, &cfg.stages.isolation);
    let k = classify(track, &det.detections, &cfg.stages.classifier);
    let med = |f: &dyn Fn(&crate::types::Detection) -> f64| median(track.detections.iter().map(|&i| f(&det.detections[i])).collect());
    row.pipeline = best.shape.clone();
    row.classifier = k.shape.as_str().to_string();
    row.cluster = iso[ti].cluster;
    row.y_um = best.y_mean_um;
    row.asymmetry = k.asymmetry;
    row.solidity = med(&|d| d.features.solidity);
    row.notch = med(&|d| d.features.notch);
    row.waist = med(&|d| d.features.waist);
    Ok(row)
}

/// Run the loop on every finished run of `results` (runs without a summary are skipped and
/// listed in the second return value); recordings are written to `out/<run_id>/`.
pub fn closed_loop(results: &Path, out: &Path, cfg: &LoopConfig) -> Result<(Vec<LoopRow>, Vec<String>), Render3dError> {
    let runs = rbc_schema::results::read_runs(results)?;
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for (k, run) in runs.iter().enumerate() {
        if run.summary.is_none() || run.n_snapshots == 0 {
            skipped.push(run.run_id.clone());
            continue;
        }
        let cell = cell_from_results(results, &run.run_id, None)?;
        // the recording moves the cell along the flow at its run's mean velocity
        if !(cell.velocity_mm_s.is_finite() && cell.velocity_mm_s > 0.0) {
            return Err(Render3dError::Results { path: results.to_path_buf(), run_id: run.run_id.clone(), message: format!("mean velocity {} mm/s is not > 0: no recording to film", cell.velocity_mm_s) });
        }
        rows.push(analyse_cell(&cell, &run.run_id, &out.join(&run.run_id), cfg.seed + k as u64, cfg)?);
    }
    Ok((rows, skipped))
}

/// Confusion table: rows = solver label (croissant, slipper, other), columns = analysis
/// label (croissant, slipper, other, none).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Agreement {
    pub table: [[usize; 4]; 3],
}

/// Class names of the rows (and first three columns) of [`Agreement`].
pub const CLASSES: [&str; 3] = ["croissant", "slipper", "other"];

impl Agreement {
    /// Tally `(solver, analysis)` label pairs; solver labels outside [`CLASSES`] (`unlabelled`) are left out.
    pub fn tally<'a>(pairs: impl IntoIterator<Item = (&'a str, &'a str)>) -> Agreement {
        let mut a = Agreement::default();
        for (s, x) in pairs {
            if let Some(r) = CLASSES.iter().position(|c| *c == s) {
                a.table[r][CLASSES.iter().position(|c| *c == x).unwrap_or(3)] += 1;
            }
        }
        a
    }

    /// Pipeline labels against the solver's.
    pub fn pipeline(rows: &[LoopRow]) -> Agreement {
        Agreement::tally(rows.iter().map(|r| (r.solver.as_str(), r.pipeline.as_str())))
    }

    /// Classifier-alone labels against the solver's.
    pub fn classifier(rows: &[LoopRow]) -> Agreement {
        Agreement::tally(rows.iter().map(|r| (r.solver.as_str(), r.classifier.as_str())))
    }

    /// Number of cells whose labels agree, and the total.
    pub fn agreeing(&self) -> (usize, usize) {
        ((0..3).map(|r| self.table[r][r]).sum(), self.table.iter().flatten().sum())
    }

    /// Agreeing / total of one solver class (`(0, 0)` when the class is absent).
    pub fn class(&self, r: usize) -> (usize, usize) {
        (self.table[r][r], self.table[r].iter().sum())
    }

    /// The table as text, with the per-class and overall agreement.
    pub fn render(&self, title: &str) -> String {
        let mut s = format!("{title}\nsolver \\ analysis   croissant  slipper  other  none\n");
        for (r, n) in CLASSES.iter().enumerate() {
            let t = self.table[r];
            s += &format!("{n:>17}   {:9}  {:7}  {:5}  {:4}\n", t[0], t[1], t[2], t[3]);
        }
        let (a, n) = self.agreeing();
        let per: Vec<String> = (0..3).map(|r| self.class(r)).map(|(a, n)| format!("{a}/{n}")).collect();
        s += &format!("agreement {a}/{n} (croissant {}, slipper {}, other {})\n", per[0], per[1], per[2]);
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tally_counts_agreement_per_class() {
        let a = Agreement::tally([("croissant", "croissant"), ("croissant", "other"), ("slipper", "slipper"), ("other", "none"), ("unlabelled", "slipper")]);
        assert_eq!(a.table, [[1, 0, 1, 0], [0, 1, 0, 0], [0, 0, 0, 1]]);
        assert_eq!(a.agreeing(), (2, 4));
        assert_eq!((a.class(0), a.class(1), a.class(2)), ((1, 2), (1, 1), (0, 1)));
        assert!(a.render("t").contains("agreement 2/4 (croissant 1/2, slipper 1/1, other 0/1)"));
    }
}
