//! Accuracy of the experiment pipeline per imaging condition, against the synthesiser's truth: recall, false tracks, centroid and y error, croissant/slipper accuracy.
//!
//! [`run_condition`] renders recordings of [`crate::simulated::synth::condition_spec`], runs
//! `rbc-analyze`'s pipeline on them in this process (detect, track, isolate, classify: the
//! same calls as the binary) and scores the result with [`score`]: output tracks are matched
//! to truth cells by position (every detection of a track to the nearest truth centroid of
//! its frame within [`MATCH_UM`]), never by label, as in `tests/analyze_truth.rs`.
//! `rbc-bench robustness` prints the table over [`crate::simulated::synth::condition_grid`].

use crate::error::AnalysisError;
use crate::experiment::pipeline::{analyse_detections, detect_dir, StageConfig};
use crate::simulated::synth::{condition_spec, condition_spec_wave, write_recording, Conditions, Truth, TruthRow};
use crate::stats::median::upper_median;
use rbc_schema::tables::{DetectionRow, TrackRow};
use std::collections::HashMap;
use std::path::Path;

/// Distance within which a detection is attributed to a truth centroid, um (half a cell).
pub const MATCH_UM: f64 = 3.0;

/// What the pipeline got right and wrong on a set of recordings.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Score {
    /// Truth cells seen whole in at least 3 frames, and those one pure track covers in >= 80 % of them.
    pub truth_cells: usize,
    pub found: usize,
    /// Tracks whose detections are mostly (> half) near no truth cell.
    pub false_tracks: usize,
    /// Tracks that mix two truth cells.
    pub mixed: usize,
    /// Per matched detection: distance to the truth centroid, um, and |y - y_true|, um.
    pub centroid_err_um: Vec<f64>,
    pub y_err_um: Vec<f64>,
    /// Per matched track: (truth shape, label given).
    pub shapes: Vec<(String, String)>,
    /// Per matched track, in the order of `shapes`: the classifier's `shape_score`.
    pub shape_scores: Vec<f64>,
    /// Per matched track, in the order of `shapes`: a debris particle rides with the truth cell
    /// (its truth rows say `debris_on_cell` in at least half of the frames it is seen whole).
    pub debris_riding: Vec<bool>,
}

impl Score {
    /// Add another score's counts and samples.
    pub fn merge(&mut self, o: Score) {
        self.truth_cells += o.truth_cells;
        self.found += o.found;
        self.false_tracks += o.false_tracks;
        self.mixed += o.mixed;
        self.centroid_err_um.extend(o.centroid_err_um);
        self.y_err_um.extend(o.y_err_um);
        self.shapes.extend(o.shapes);
        self.shape_scores.extend(o.shape_scores);
        self.debris_riding.extend(o.debris_riding);
    }

    /// Tracked croissants and slippers (truth), and how many got their own label (`other` counts as wrong).
    pub fn shape_counts(&self) -> (usize, usize) {
        let cs: Vec<_> = self.shapes.iter().filter(|(t, _)| t == "croissant" || t == "slipper").collect();
        (cs.iter().filter(|(t, p)| t == p).count(), cs.len())
    }

    /// [`Score::shape_counts`] of the cells a debris particle rides with: their images are not
    /// their shapes alone (the synthesiser draws debris independently of the cells).
    pub fn shape_counts_debris_riding(&self) -> (usize, usize) {
        let cs: Vec<_> = self
            .shapes
            .iter()
            .zip(&self.debris_riding)
            .filter(|((t, _), &riding)| riding && (t == "croissant" || t == "slipper"))
            .collect();
        (cs.iter().filter(|((t, p), _)| t == p).count(), cs.len())
    }

    /// Croissant/slipper accuracy over the cells no debris rides with (NaN when there are none).
    pub fn accuracy_without_debris_riding(&self) -> f64 {
        let ((ok, n), (ok_d, n_d)) = (self.shape_counts(), self.shape_counts_debris_riding());
        if n == n_d { f64::NAN } else { (ok - ok_d) as f64 / (n - n_d) as f64 }
    }

    /// Croissant/slipper accuracy: correct labels over tracked croissants and slippers (`other` is wrong).
    pub fn accuracy(&self) -> f64 {
        let (ok, n) = self.shape_counts();
        if n == 0 { f64::NAN } else { ok as f64 / n as f64 }
    }

    /// Croissants and slippers labelled `other`.
    pub fn called_other(&self) -> usize {
        self.shapes.iter().filter(|(t, p)| (t == "croissant" || t == "slipper") && p == "other").count()
    }

    /// Found over truth cells.
    pub fn recall(&self) -> f64 {
        if self.truth_cells == 0 { f64::NAN } else { self.found as f64 / self.truth_cells as f64 }
    }

    /// Median distance of the matched detections to the truth centroid, um: the upper middle
    /// value ([`upper_median`]), NaN when nothing matched.
    pub fn median_centroid_err_um(&self) -> f64 {
        upper_median(&mut self.centroid_err_um.clone()).unwrap_or(f64::NAN)
    }

    /// Median |y - y_true| of the matched detections, um: the upper middle value
    /// ([`upper_median`]), NaN when nothing matched.
    pub fn median_y_err_um(&self) -> f64 {
        upper_median(&mut self.y_err_um.clone()).unwrap_or(f64::NAN)
    }

    /// Header of [`Score::row`], Markdown.
    pub fn header() -> String {
        "| condition | croissant/slipper correct | accuracy | C/S called other | debris riding: correct / cells | accuracy without them | median centroid error (um) | median y error (um) | recall | false tracks | mixed |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |".into()
    }

    /// One Markdown row named `name`.
    pub fn row(&self, name: &str) -> String {
        let (ok, n) = self.shape_counts();
        let (ok_d, n_d) = self.shape_counts_debris_riding();
        format!(
            "| {name} | {ok}/{n} | {:.3} | {} | {ok_d}/{n_d} | {:.3} | {:.4} | {:.4} | {}/{} = {:.3} | {} | {} |",
            self.accuracy(),
            self.called_other(),
            self.accuracy_without_debris_riding(),
            self.median_centroid_err_um(),
            self.median_y_err_um(),
            self.found,
            self.truth_cells,
            self.recall(),
            self.false_tracks,
            self.mixed
        )
    }
}

/// Score one recording's detections and tracks (as `rbc-analyze` writes them) against its truth rows.
pub fn score(truth: &[TruthRow], dets: &[DetectionRow], tracks: &[TrackRow]) -> Score {
    let mut m = Score::default();
    let mut truth_at: HashMap<u64, Vec<&TruthRow>> = HashMap::new();
    for r in truth {
        truth_at.entry(r.frame).or_default().push(r);
    }
    let mut points: HashMap<u64, Vec<&DetectionRow>> = HashMap::new();
    for d in dets {
        if let Some(id) = d.track_id {
            points.entry(id).or_default().push(d);
        }
    }
    // per truth cell: frames seen whole, and of them those with debris on the cell
    let mut seen: HashMap<u64, (usize, usize)> = HashMap::new();
    for r in truth.iter().filter(|r| r.visible) {
        let e = seen.entry(r.cell_id).or_default();
        e.0 += 1;
        e.1 += r.debris_on_cell as usize;
    }
    let mut covered: HashMap<u64, usize> = HashMap::new();
    for t in tracks {
        let Some(pts) = points.get(&t.track_id) else { continue };
        let cells: Vec<Option<&TruthRow>> = pts
            .iter()
            .map(|d| {
                truth_at.get(&d.frame).and_then(|rows| {
                    rows.iter()
                        .map(|r| (*r, ((r.x_um - d.x_um).powi(2) + (r.y_um - d.y_um).powi(2)).sqrt()))
                        .filter(|(_, e)| *e <= MATCH_UM)
                        .min_by(|a, b| a.1.total_cmp(&b.1))
                        .map(|(r, _)| r)
                })
            })
            .collect();
        let ids: Vec<u64> = cells.iter().flatten().map(|r| r.cell_id).collect();
        if ids.len() * 2 < cells.len() || ids.is_empty() {
            m.false_tracks += 1;
            continue;
        }
        if ids.iter().any(|&c| c != ids[0]) {
            m.mixed += 1;
            continue;
        }
        let e = covered.entry(ids[0]).or_default();
        *e = (*e).max(ids.len());
        for (d, r) in pts.iter().zip(&cells) {
            if let Some(r) = r {
                m.centroid_err_um.push(((r.x_um - d.x_um).powi(2) + (r.y_um - d.y_um).powi(2)).sqrt());
                m.y_err_um.push((r.y_um - d.y_um).abs());
            }
        }
        let truth_row = cells.iter().flatten().next().expect("ids is not empty");
        m.shapes.push((truth_row.shape.clone(), t.shape.clone()));
        m.shape_scores.push(t.shape_score);
        m.debris_riding.push(seen.get(&truth_row.cell_id).is_some_and(|&(n, d)| n > 0 && 2 * d >= n));
    }
    for (&cell, &(n, _)) in &seen {
        if n < 3 {
            continue;
        }
        m.truth_cells += 1;
        if covered.get(&cell).is_some_and(|&c| c * 5 >= n * 4) {
            m.found += 1;
        }
    }
    m
}

/// Which renderer draws the recordings of a condition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Renderer {
    /// The synthesiser's edge profiles ([`condition_spec`]), the images `rbc-analyze` was tuned on.
    Synth,
    /// The wave-optics renderer ([`condition_spec_wave`], [`crate::simulated::wave`]).
    Wave,
}

impl Renderer {
    pub fn as_str(self) -> &'static str {
        match self {
            Renderer::Synth => "synth",
            Renderer::Wave => "wave",
        }
    }
}

/// Render `seeds` recordings of [`condition_spec`] under `c` into `dir/<tag>_<seed>/` (created),
/// analyse each with the pipeline's default stages and return the summed score.
pub fn run_condition(dir: &Path, tag: &str, c: &Conditions, seeds: std::ops::Range<u64>) -> Result<Score, AnalysisError> {
    run_condition_with(dir, tag, c, seeds, Renderer::Synth)
}

/// [`run_condition`] with the recordings drawn by `renderer` (the same cells, positions and camera).
pub fn run_condition_with(dir: &Path, tag: &str, c: &Conditions, seeds: std::ops::Range<u64>, renderer: Renderer) -> Result<Score, AnalysisError> {
    let mut total = Score::default();
    for seed in seeds {
        let rec = dir.join(format!("{tag}_{}_{seed}", renderer.as_str()));
        let spec = match renderer {
            Renderer::Synth => condition_spec(seed, c),
            Renderer::Wave => condition_spec_wave(seed, c),
        };
        write_recording(&rec, &spec, seed)?;
        total.merge(score_recording(&rec, dir)?);
    }
    Ok(total)
}

/// Analyse the synthetic recording in `rec` (named relative to `root`) and score it against its `truth.csv`.
pub fn score_recording(rec: &Path, root: &Path) -> Result<Score, AnalysisError> {
    score_recording_with(rec, root, &StageConfig::default())
}

/// [`score_recording`] with the stages after detection configured by `stages`.
pub fn score_recording_with(rec: &Path, root: &Path, stages: &StageConfig) -> Result<Score, AnalysisError> {
    let truth = Truth::read(rec)?;
    let detected = detect_dir(rec, root)?;
    let tables = analyse_detections(&detected.name, &detected.config, &detected.detections, stages);
    Ok(score(&truth.rows, &tables.detections, &tables.tracks))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth(cell_id: u64, frame: u64, shape: &str, debris_on_cell: bool) -> TruthRow {
        TruthRow { frame, cell_id, t_s: frame as f64 / 400.0, x_um: 10.0 + 30.0 * cell_id as f64, y_um: 0.0, shape: shape.into(), velocity_mm_s: 1.0, visible: true, area_um2: 25.0, length_um: 7.0, width_um: 4.0, debris_on_cell }
    }

    /// Three croissants seen in 4 frames each, all tracked and labelled croissant, other and
    /// other: a particle rides with the second (on it in 2 of its 4 frames: half) and crosses the
    /// third in 1 frame only. The accuracy is 1/3 over all cells; the second is the one cell with
    /// debris riding, and without it 1/2.
    #[test]
    fn cells_debris_rides_with_are_counted_apart() {
        let mut rows = Vec::new();
        for f in 0..4 {
            rows.push(truth(0, f, "croissant", false));
            rows.push(truth(1, f, "croissant", f < 2));
            rows.push(truth(2, f, "croissant", f == 3));
        }
        let mut dets = Vec::new();
        let mut tracks = Vec::new();
        for (cell, label) in [(0u64, "croissant"), (1, "other"), (2, "other")] {
            for f in 0..4u64 {
                let r = rows.iter().find(|r| r.cell_id == cell && r.frame == f).unwrap();
                dets.push(DetectionRow { recording: "r".into(), frame: f, t_s: r.t_s, x_um: r.x_um + 0.01, y_um: 0.01, area_um2: 25.0, length_um: 7.0, width_um: 4.0, touches_border: false, track_id: Some(cell + 1), mirror_asymmetry: 0.0 });
            }
            let track_id = cell + 1;
            tracks.push(TrackRow { recording: "r".into(), pressure_mbar: 100.0, position_mm: 10.0, track_id, n_frames: 4, x_first_um: 10.0, y_mean_um: 0.0, y_std_um: 0.0, velocity_mm_s: 1.0, velocity_se_mm_s: 0.0, isolated: true, gap_um: f64::INFINITY, shape: label.into(), shape_score: 0.0, p_croissant: None });
        }
        let s = score(&rows, &dets, &tracks);
        assert_eq!((s.found, s.truth_cells, s.false_tracks, s.mixed), (3, 3, 0, 0));
        assert_eq!(s.debris_riding, vec![false, true, false]);
        assert_eq!((s.shape_counts(), s.shape_counts_debris_riding()), ((1, 3), (0, 1)));
        assert!((s.accuracy() - 1.0 / 3.0).abs() < 1e-15 && (s.accuracy_without_debris_riding() - 0.5).abs() < 1e-15);
        assert!(s.row("x").contains("| 0/1 | 0.500 |"), "{}", s.row("x"));
    }
}
