//! The experiment pipeline of `rbc-analyze`: per recording detect -> track -> isolate -> classify,
//! then group statistics and figures, every output written atomically.
//!
//! Stages (one module each): [`crate::experiment::track::link`] and [`crate::experiment::track::motion`],
//! [`crate::experiment::isolate::isolate`], [`crate::experiment::classify::classify`], then
//! [`crate::experiment::groups::summarise`] and [`crate::plot::experiment::write_figures`].
//!
//! Outputs (`../shared/spec/interfaces.md`): `detections.csv`, `tracks.csv`,
//! `summary.csv`, `kde.csv`, `entry.csv`, `figures/`. They are replaced as one set
//! ([`rbc_schema::output_set`]): first written into a staging folder beside the output
//! folder, then renamed into place only when every file is complete, so a failed run
//! replaces none of the previous outputs and never leaves a half-written file.

use crate::experiment::classify::{classify, ClassifierConfig, Shape};
use crate::error::AnalysisError;
use crate::experiment::isolate::{isolate, IsolationConfig};
use crate::experiment::track::{link, motion, TrackerConfig};
use crate::types::Detection;
use rbc_schema::recording::RecordingConfig;
use rbc_schema::tables::{columns, write_table, DetectionRow, EntryRow, KdeRow, SummaryRow, TrackRow};
use std::path::{Path, PathBuf};

/// Parameters of every stage.
#[derive(Debug, Clone, PartialEq)]
pub struct StageConfig {
    pub tracker: TrackerConfig,
    pub isolation: IsolationConfig,
    pub classifier: ClassifierConfig,
    /// Smallest median area of a track that is a cell, um^2: a red cell projects to 25-60 um^2
    /// at any optics; smaller moving objects (debris, platelets) keep their rows in
    /// `detections.csv` but make no track and are nobody's neighbour in the isolation.
    pub min_cell_area_um2: f64,
    /// Refine each track's per-frame positions by registering its frames on the track's own
    /// image ([`crate::experiment::register`]); off: every position is its frame's centroid.
    pub register_frames: bool,
}

impl Default for StageConfig {
    fn default() -> Self {
        StageConfig { tracker: TrackerConfig::default(), isolation: IsolationConfig::default(), classifier: ClassifierConfig::default(), min_cell_area_um2: 12.0, register_frames: true }
    }
}

/// Median area of a track's detections, um^2.
fn median_area(t: &crate::experiment::track::Track, dets: &[Detection]) -> f64 {
    let mut a: Vec<f64> = t.detections.iter().map(|&i| dets[i].area_um2).collect();
    crate::stats::median::median(&mut a).unwrap_or(0.0)
}

/// The detections with the frames of each track registered on the track's own image
/// ([`crate::experiment::register`]): centroids moved by the offsets (px, and um at `um_per_px`);
/// a track the registration refuses keeps its frames' centroids.
fn registered(dets: &[Detection], tracks: &[crate::experiment::track::Track], um_per_px: f64) -> Vec<Detection> {
    let mut out = dets.to_vec();
    let mut registrar = crate::experiment::register::Registrar::default();
    for t in tracks {
        let patches: Vec<&crate::types::ContrastPatch> = t.detections.iter().map(|&i| &dets[i].contrast).collect();
        let p: Vec<(f64, f64)> = t.detections.iter().map(|&i| (dets[i].x_px, dets[i].y_px)).collect();
        let Some(shift) = registrar.register(&patches, &p) else { continue };
        for (&i, (dx, dy)) in t.detections.iter().zip(shift) {
            let d = &mut out[i];
            d.x_px += dx;
            d.y_px += dy;
            d.x_um += dx * um_per_px;
            d.y_um += dy * um_per_px;
        }
    }
    out
}

/// The analysed tables of one recording.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RecordingTables {
    pub detections: Vec<DetectionRow>,
    pub tracks: Vec<TrackRow>,
}

/// Finite or a fallback: outputs never carry NaN (a NaN is no measurement).
fn finite_or(v: f64, fallback: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        fallback
    }
}

/// Track, isolate and classify the detections of one recording.
///
/// `dets` are all objects of all frames (border objects included); `name` is the
/// recording's name in the tables.
pub fn analyse_detections(
    name: &str,
    config: &RecordingConfig,
    dets: &[Detection],
    stages: &StageConfig,
) -> RecordingTables {
    let mut tracks = link(dets, config.fps, &stages.tracker);
    tracks.retain(|t| median_area(t, dets) >= stages.min_cell_area_um2);
    let own;
    let dets = if stages.register_frames {
        own = registered(dets, &tracks, config.um_per_px);
        &own[..]
    } else {
        dets
    };
    let isolation = isolate(&tracks, dets, &stages.isolation);
    let mut track_of: Vec<Option<u64>> = vec![None; dets.len()];
    let mut rows = Vec::with_capacity(tracks.len());
    for (t, iso) in tracks.iter().zip(&isolation) {
        let Some(m) = motion(t, dets) else { continue };
        for &i in &t.detections {
            track_of[i] = Some(t.id);
        }
        let k = classify(t, dets, &stages.classifier);
        let (shape, score) = if iso.cluster {
            (Shape::Other, 0.0)
        } else {
            (k.shape, k.score)
        };
        let score = finite_or(score, 0.0);
        rows.push(TrackRow {
            recording: name.to_string(),
            pressure_mbar: config.pressure_mbar,
            position_mm: config.position_mm,
            track_id: t.id,
            n_frames: m.n_frames as u64,
            x_first_um: m.x_first_um,
            y_mean_um: m.y_mean_um,
            y_std_um: m.y_std_um,
            velocity_mm_s: m.velocity_um_s / 1000.0,
            velocity_se_mm_s: m.velocity_se_um_s / 1000.0,
            isolated: iso.isolated,
            gap_um: iso.gap_um,
            shape: shape.as_str().to_string(),
            shape_score: score,
            p_croissant: Some(stages.classifier.calibration.probability(score)),
        });
    }
    let detections = dets
        .iter()
        .zip(&track_of)
        .map(|(d, &track_id)| DetectionRow {
            recording: name.to_string(),
            frame: d.frame as u64,
            t_s: d.t_s,
            x_um: d.x_um,
            y_um: d.y_um,
            area_um2: d.area_um2,
            length_um: d.length_um,
            width_um: d.width_um,
            touches_border: d.touches_border,
            track_id,
            mirror_asymmetry: finite_or(d.features.mirror_asymmetry, 1.0),
        })
        .collect();
    RecordingTables {
        detections,
        tracks: rows,
    }
}

/// Every table of one run, ready to be written.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Outputs {
    pub detections: Vec<DetectionRow>,
    pub tracks: Vec<TrackRow>,
    pub summary: Vec<SummaryRow>,
    pub kde: Vec<KdeRow>,
    pub entry: Vec<EntryRow>,
    /// Notes from the statistics (cells left out), one line each.
    pub notes: Vec<String>,
}

impl Outputs {
    /// Collect the tables of all recordings and compute the group statistics.
    pub fn from_recordings(recordings: Vec<RecordingTables>) -> Outputs {
        let mut out = Outputs::default();
        for r in recordings {
            out.detections.extend(r.detections);
            out.tracks.extend(r.tracks);
        }
        let groups = crate::experiment::groups::summarise(&out.tracks);
        out.summary = groups.summary;
        out.kde = groups.kde;
        out.entry = groups.entry;
        out.notes = groups.notes;
        out
    }
}

/// Names of the table files inside the output folder.
pub const TABLE_FILES: [&str; 5] = [
    "detections.csv",
    "tracks.csv",
    "summary.csv",
    "kde.csv",
    "entry.csv",
];
/// Name of the figure folder inside the output folder.
pub const FIGURES_DIR: &str = "figures";

const DETECTION_HEADER: &[&str] = &[
    "recording",
    "frame",
    "t_s",
    "x_um",
    "y_um",
    "area_um2",
    "length_um",
    "width_um",
    "touches_border",
    "track_id",
    "mirror_asymmetry",
];
const TRACK_HEADER: &[&str] = &[
    "recording",
    "pressure_mbar",
    "position_mm",
    "track_id",
    "n_frames",
    "x_first_um",
    "y_mean_um",
    "y_std_um",
    "velocity_mm_s",
    "velocity_se_mm_s",
    "isolated",
    "gap_um",
    "shape",
    "shape_score",
    "p_croissant",
];
const SUMMARY_HEADER: &[&str] = &[
    "pressure_mbar",
    "position_mm",
    "n_cells",
    "velocity_mean_mm_s",
    "velocity_std_mm_s",
    "frac_croissant",
    "frac_slipper",
    "frac_other",
    "frac_croissant_lo",
    "frac_croissant_hi",
    "frac_slipper_lo",
    "frac_slipper_hi",
    "frac_croissant_expected",
    "frac_croissant_expected_sd",
];

/// Write all outputs into `out` (created if needed) as one set ([`rbc_schema::output_set`]):
/// staged in a folder beside `out`, then moved into place; on any error the previous outputs
/// in `out` stay as they were, byte for byte. The figure folder is replaced as a whole; with
/// `figures == false` it is neither written nor touched. Returns the final paths written.
pub fn write_outputs(
    out: &Path,
    outputs: &Outputs,
    figures: bool,
) -> Result<Vec<PathBuf>, AnalysisError> {
    let owns = |name: &str| TABLE_FILES.contains(&name) || (figures && name == FIGURES_DIR);
    let ((), written) = rbc_schema::output_set::write_set(out, owns, |dir| stage(dir, outputs, figures))?;
    Ok(written)
}

/// Write the tables (and the figures) into the staging folder `dir`.
fn stage(dir: &Path, o: &Outputs, figures: bool) -> Result<(), AnalysisError> {
    write_table(&dir.join("detections.csv"), &o.detections, DETECTION_HEADER)?;
    write_table(&dir.join("tracks.csv"), &o.tracks, TRACK_HEADER)?;
    write_table(&dir.join("summary.csv"), &o.summary, SUMMARY_HEADER)?;
    write_table(&dir.join("kde.csv"), &o.kde, columns::KDE)?;
    write_table(&dir.join("entry.csv"), &o.entry, columns::ENTRY)?;
    if figures {
        let staged_figures = dir.join(FIGURES_DIR);
        std::fs::create_dir_all(&staged_figures)
            .map_err(|e| AnalysisError::Schema(rbc_schema::SchemaError::io(&staged_figures, e)))?;
        crate::plot::experiment::write_figures(&staged_figures, &o.summary, &o.kde, &o.tracks)?;
    }
    Ok(())
}

/// One recording's detections, as produced by the detection stage.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectedRecording {
    /// Name used in the tables (the folder relative to the analysed root).
    pub name: String,
    pub config: RecordingConfig,
    /// Number of frames read.
    pub n_frames: usize,
    pub detections: Vec<Detection>,
}

/// What one recording produced, for progress display and warnings.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingReport {
    pub name: String,
    pub n_frames: usize,
    pub n_detections: usize,
    pub n_tracks: usize,
    pub n_isolated: usize,
    /// Wall time of detection + tracking, s.
    pub seconds: f64,
    /// Human-readable warnings (e.g. no cell tracked), one line each.
    pub warnings: Vec<String>,
}

/// Analyse every recording with `detect` (in parallel on the current rayon pool), calling
/// `on_done` after each one, and compute the group statistics. The first failing
/// recording's error is returned (the error names its file); nothing is written here.
pub fn analyse_all<D, P>(
    recordings: &[PathBuf],
    detect: D,
    stages: &StageConfig,
    on_done: P,
) -> Result<(Outputs, Vec<RecordingReport>), AnalysisError>
where
    D: Fn(&Path) -> Result<DetectedRecording, AnalysisError> + Sync,
    P: Fn(&RecordingReport) + Sync,
{
    use rayon::prelude::*;
    let results: Vec<Result<(RecordingTables, RecordingReport), AnalysisError>> = recordings
        .par_iter()
        .map(|dir| {
            let start = std::time::Instant::now();
            let rec = detect(dir)?;
            let tables = analyse_detections(&rec.name, &rec.config, &rec.detections, stages);
            let n_isolated = tables.tracks.iter().filter(|t| t.isolated).count();
            let mut warnings = Vec::new();
            if tables.tracks.is_empty() {
                warnings.push(format!(
                    "{}: no cell tracked in {} frames ({} objects detected); the recording adds nothing to its group",
                    dir.display(),
                    rec.n_frames,
                    rec.detections.len()
                ));
            } else if n_isolated == 0 {
                warnings.push(format!("{}: {} cells tracked, none isolated (40 um criterion)", dir.display(), tables.tracks.len()));
            }
            let report = RecordingReport {
                name: rec.name.clone(),
                n_frames: rec.n_frames,
                n_detections: rec.detections.len(),
                n_tracks: tables.tracks.len(),
                n_isolated,
                seconds: start.elapsed().as_secs_f64(),
                warnings,
            };
            on_done(&report);
            Ok((tables, report))
        })
        .collect();
    let mut tables = Vec::with_capacity(results.len());
    let mut reports = Vec::with_capacity(results.len());
    for r in results {
        let (t, rep) = r?;
        tables.push(t);
        reports.push(rep);
    }
    Ok((Outputs::from_recordings(tables), reports))
}

/// Recording folders under `root` ([`crate::experiment::recording::discover`]); the error names `root` when none is found.
pub fn find_recordings(root: &Path) -> Result<Vec<PathBuf>, AnalysisError> {
    crate::experiment::recording::discover(root)
}

/// Open the recording in `dir` (named relative to `root`) and detect its objects
/// ([`crate::experiment::recording::detect_recording`]).
pub fn detect_dir(dir: &Path, root: &Path) -> Result<DetectedRecording, AnalysisError> {
    let rec = crate::experiment::recording::Recording::open_under(root, dir)?;
    let found = crate::experiment::recording::detect_recording(&rec)?;
    Ok(DetectedRecording {
        name: rec.name.clone(),
        config: rec.config.clone(),
        n_frames: found.n_frames,
        detections: found.detections,
    })
}
