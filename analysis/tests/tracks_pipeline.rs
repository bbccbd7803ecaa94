//! The pipeline on detection lists with known truth: tables, isolation, grouping, atomic outputs.

mod tracks_common;

use rbc_analysis::experiment::pipeline::{
    analyse_all, write_outputs, DetectedRecording, StageConfig, TABLE_FILES,
};
use rbc_analysis::AnalysisError;
use rbc_schema::recording::RecordingConfig;
use rbc_schema::tables::{columns, read_table, DetectionRow, TrackRow};
use std::path::{Path, PathBuf};
use tracks_common::*;

fn config(pressure: f64, position: f64) -> RecordingConfig {
    RecordingConfig {
        fps: 400.0,
        um_per_px: 0.2,
        pressure_mbar: pressure,
        position_mm: position,
        channel: None,
    }
}

/// A recording of a train of cells: `spacing` um apart at `v` um/frame, croissant-like
/// (symmetric, centred) or slipper-like (asymmetric, 1.2 um off-centre) alternately.
fn recording(
    name: &str,
    pressure: f64,
    position: f64,
    v: f64,
    spacing: f64,
    seed: u64,
) -> DetectedRecording {
    let mut cells = train(seed, 6, v, 0.0, spacing, 0.0, 0.0, 60, 10.0);
    for (k, c) in cells.iter_mut().enumerate() {
        c.x0_um += 200.0;
        c.y_um = if k % 2 == 0 { 0.05 } else { -1.2 };
    }
    let scene = Scene {
        cells,
        n_frames: 60,
        fov_um: 300.0,
        half_length_um: 4.0,
        jitter_um: 0.05,
        p_miss: 0.0,
    };
    let mut g = scene.generate(seed);
    for (d, &c) in g.dets.iter_mut().zip(&g.truth) {
        d.features.mirror_asymmetry = if c % 2 == 0 { 0.03 } else { 0.3 };
    }
    DetectedRecording {
        name: name.into(),
        config: config(pressure, position),
        n_frames: 60,
        detections: g.dets,
    }
}

fn detector(dir: &Path) -> Result<DetectedRecording, AnalysisError> {
    let name = dir.file_name().unwrap().to_string_lossy().to_string();
    match name.as_str() {
        "p100_10mm" => Ok(recording(&name, 100.0, 10.0, 2.5, 50.0, 1)),
        "p100_0mm" => Ok(recording(&name, 100.0, 0.0, 2.5, 50.0, 2)),
        "p500_10mm_dense" => Ok(recording(&name, 500.0, 10.0, 12.0, 30.0, 3)),
        "empty" => Ok(DetectedRecording {
            name,
            config: config(50.0, 10.0),
            n_frames: 20,
            detections: vec![],
        }),
        _ => Err(AnalysisError::Input {
            path: dir.join("frame_0003.png"),
            message: "truncated image".into(),
        }),
    }
}

#[test]
fn tables_group_and_isolation_follow_the_truth() {
    let dirs: Vec<PathBuf> = ["p100_10mm", "p100_0mm", "p500_10mm_dense", "empty"]
        .iter()
        .map(PathBuf::from)
        .collect();
    let seen = std::sync::Mutex::new(Vec::new());
    let (out, reports) = analyse_all(&dirs, detector, &StageConfig::default(), |r| {
        seen.lock().unwrap().push(r.name.clone())
    })
    .unwrap();
    assert_eq!(
        seen.lock().unwrap().len(),
        4,
        "progress callback once per recording"
    );
    // Empty recording: a warning, no rows.
    let empty = reports.iter().find(|r| r.name == "empty").unwrap();
    assert_eq!(empty.n_tracks, 0);
    assert!(
        empty.warnings[0].contains("no cell tracked"),
        "{:?}",
        empty.warnings
    );
    // 6 cells per recording, all tracked; velocity 2.5 um/frame = 1 mm/s and 12 um/frame = 4.8 mm/s.
    for (name, v, isolated) in [
        ("p100_10mm", 1.0, true),
        ("p100_0mm", 1.0, true),
        ("p500_10mm_dense", 4.8, false),
    ] {
        let t: Vec<&TrackRow> = out.tracks.iter().filter(|t| t.recording == name).collect();
        assert_eq!(t.len(), 6, "{name}");
        for r in &t {
            // 0.05 um jitter over >= 10 frames: slope error ~ 0.05 / (sqrt(sum (f - fbar)^2)) um/frame, < 0.5 %.
            assert!((r.velocity_mm_s / v - 1.0).abs() < 0.005, "{name}: {r:?}");
            assert!(r.velocity_se_mm_s > 0.0 && r.velocity_se_mm_s < 0.01 * v);
            // The first and last cell of a train see a neighbour on one side only; spacing is exact.
            assert_eq!(r.isolated, isolated, "{name}: {r:?}");
            let want = if r.y_mean_um.abs() < 0.5 {
                "croissant"
            } else {
                "slipper"
            };
            assert_eq!(r.shape, want, "{r:?}");
        }
    }
    // Summary: the two isolated groups (100 mbar at 10 and 0 mm); the dense group has no isolated cell.
    assert_eq!(out.summary.len(), 2, "{:?}", out.summary);
    for s in &out.summary {
        assert_eq!(s.n_cells, 6);
        assert!((s.frac_croissant - 0.5).abs() < 1e-12 && (s.frac_slipper - 0.5).abs() < 1e-12);
    }
    assert_eq!(out.entry.len(), 6, "entry rows: isolated cells at 0 mm");
    // Every detection of a reported track carries its id.
    let linked = out
        .detections
        .iter()
        .filter(|d| d.track_id.is_some())
        .count();
    let in_tracks: u64 = out.tracks.iter().map(|t| t.n_frames).sum();
    assert_eq!(linked as u64, in_tracks);
}

#[test]
fn outputs_are_written_and_read_back_and_failures_replace_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let outdir = dir.path().join("rbc-analysis");
    let dirs: Vec<PathBuf> = ["p100_10mm", "p100_0mm"]
        .iter()
        .map(PathBuf::from)
        .collect();
    let (out, _) = analyse_all(&dirs, detector, &StageConfig::default(), |_| {}).unwrap();
    let written = write_outputs(&outdir, &out, true).unwrap();
    for f in TABLE_FILES {
        assert!(outdir.join(f).is_file(), "{f}");
    }
    let pngs = written
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .count();
    assert!(pngs >= 2, "figures: {written:?}");
    let tracks: Vec<TrackRow> = read_table(&outdir.join("tracks.csv"), columns::TRACKS).unwrap();
    assert_eq!(tracks, out.tracks);
    let dets: Vec<DetectionRow> =
        read_table(&outdir.join("detections.csv"), columns::DETECTIONS).unwrap();
    assert_eq!(dets.len(), out.detections.len());
    // No staging folder left behind.
    let hidden: Vec<_> = std::fs::read_dir(&outdir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(hidden.is_empty());

    // A run that fails in detection returns the error naming the file and writes nothing.
    let before: Vec<(PathBuf, Vec<u8>)> = TABLE_FILES
        .iter()
        .map(|f| (outdir.join(f), std::fs::read(outdir.join(f)).unwrap()))
        .collect();
    let bad: Vec<PathBuf> = ["p100_10mm", "broken"].iter().map(PathBuf::from).collect();
    let err = analyse_all(&bad, detector, &StageConfig::default(), |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("frame_0003.png"), "{err}");
    for (p, bytes) in &before {
        assert_eq!(&std::fs::read(p).unwrap(), bytes);
    }
    // A run whose figures cannot be written (the staging figure path is blocked) replaces nothing either:
    // an output folder that is a file is refused before anything is written.
    let file_out = dir.path().join("not-a-folder");
    std::fs::write(&file_out, "x").unwrap();
    assert!(write_outputs(&file_out, &out, false).is_err());
    assert_eq!(std::fs::read_to_string(&file_out).unwrap(), "x");

    // Empty run: headers only, no figures, still valid tables.
    let empty_out = dir.path().join("empty");
    let (out, _) = analyse_all(
        &[PathBuf::from("empty")],
        detector,
        &StageConfig::default(),
        |_| {},
    )
    .unwrap();
    write_outputs(&empty_out, &out, true).unwrap();
    let t: Vec<TrackRow> = read_table(&empty_out.join("tracks.csv"), columns::TRACKS).unwrap();
    assert!(t.is_empty());
    assert!(std::fs::read_to_string(empty_out.join("summary.csv"))
        .unwrap()
        .starts_with("pressure_mbar,position_mm,n_cells"));
}
