//! `rbc-analyze` against the synthesiser's truth, end to end through the binary.
//!
//! Random recordings (`rbc_analysis::simulated::synth::random_spec`: two cells ~50 um apart, random
//! croissant / slipper / other shapes, sizes, tilts and offsets) across seeds, pixel sizes
//! 0.15-0.35 um/px, read-noise levels and velocities 0.1-12 mm/s are analysed in one run.
//! Output tracks are matched to truth cells by position (every detection of a track to the
//! nearest truth centroid of its frame), never by label. Printed: track recall, false
//! tracks, swapped (mixed) tracks, median and 95th-percentile centroid error, velocity
//! error, croissant-vs-slipper accuracy.
//!
//! A second test runs dense trains of cells (42 um apart at 12 mm/s and at 0.1 mm/s).
//! The default tests run a small grid (~30 s); the full study is
//! `cargo test -p rbc --test analyze_truth -- --ignored --nocapture`.

use rbc_analysis::simulated::synth::{random_spec, write_recording, SynthSpec, Truth, TruthRow};
use rbc_schema::tables::{columns, read_table, DetectionRow, TrackRow};
use std::collections::HashMap;
use std::process::Command;

/// One study case: seed, pixel size (um/px), read noise (fraction of full scale), velocity (mm/s).
type Case = (u64, f64, f64, f64);

#[derive(Debug, Default)]
struct Metrics {
    truth_cells: usize,
    found: usize,
    false_tracks: usize,
    mixed: usize,
    centroid_err: Vec<f64>,
    velocity_rel_err: Vec<f64>,
    /// (relative velocity error, recording, track id, frames) of the worst tracks.
    worst_velocity: Vec<(f64, String, u64, u64)>,
    /// (truth shape, predicted shape, isolated) of matched tracks.
    shapes: Vec<(String, String, bool)>,
}

fn quantile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[((s.len() - 1) as f64 * q).round() as usize]
}

/// Distance within which a detection is attributed to a truth centroid, um (half a cell).
const MATCH_UM: f64 = 3.0;

fn study(cases: &[Case]) -> Metrics {
    study_specs(
        cases
            .iter()
            .enumerate()
            .map(|(k, &(seed, px, noise, v))| {
                (
                    format!("case{k:03}_px{px:.2}_n{noise:.3}_v{v}"),
                    random_spec(seed, px, noise, v),
                    seed,
                )
            })
            .collect(),
    )
}

/// A train of cells `spacing_um` apart (centroid to centroid) entering from the left through
/// the whole recording: the tracker's hard case when fast and dense.
fn train_spec(
    seed: u64,
    px: f64,
    noise: f64,
    v: f64,
    spacing_um: f64,
    n_frames: usize,
) -> SynthSpec {
    let mut spec = random_spec(seed, px, noise, v);
    spec.n_frames = n_frames;
    let travel = v * 1000.0 / spec.fps * n_frames as f64;
    let n_cells = (travel / spacing_um).ceil() as usize + 2;
    let base = spec.cells.clone();
    spec.cells = (0..n_cells)
        .map(|k| {
            let mut c = base[k % base.len()];
            c.x0_um = base[0].x0_um + spacing_um - spacing_um * k as f64;
            c.velocity_mm_s = v * (1.0 + 0.01 * ((k % 3) as f64 - 1.0));
            c.seed = c.seed.wrapping_add(k as u64);
            c
        })
        .collect();
    spec
}

fn study_specs(specs: Vec<(String, SynthSpec, u64)>) -> Metrics {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("recordings");
    let mut truths = HashMap::new();
    for (name, spec, seed) in specs {
        let rec = root.join(&name);
        write_recording(&rec, &spec, seed).unwrap();
        truths.insert(name.clone(), Truth::read(&rec).unwrap());
    }
    let out = dir.path().join("out");
    let o = Command::new(bin())
        .arg(&root)
        .arg("--out")
        .arg(&out)
        .arg("--no-figures")
        .output()
        .expect("run rbc-analyze");
    assert!(
        o.status.success(),
        "rbc-analyze failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let dets: Vec<DetectionRow> =
        read_table(&out.join("detections.csv"), columns::DETECTIONS).unwrap();
    let tracks: Vec<TrackRow> = read_table(&out.join("tracks.csv"), columns::TRACKS).unwrap();
    evaluate(&truths, &dets, &tracks)
}

fn evaluate(
    truths: &HashMap<String, Truth>,
    dets: &[DetectionRow],
    tracks: &[TrackRow],
) -> Metrics {
    let mut m = Metrics::default();
    // Truth rows by (recording, frame).
    let mut truth_at: HashMap<(&str, u64), Vec<&TruthRow>> = HashMap::new();
    for (name, t) in truths {
        for r in &t.rows {
            truth_at
                .entry((name.as_str(), r.frame))
                .or_default()
                .push(r);
        }
    }
    // Detections of each track.
    let mut points: HashMap<(&str, u64), Vec<&DetectionRow>> = HashMap::new();
    for d in dets {
        if let Some(id) = d.track_id {
            points
                .entry((d.recording.as_str(), id))
                .or_default()
                .push(d);
        }
    }
    // cell -> number of frames covered by its best pure track
    let mut covered: HashMap<(&str, u64), usize> = HashMap::new();
    for t in tracks {
        let pts = &points[&(t.recording.as_str(), t.track_id)];
        let mut cells: Vec<Option<&TruthRow>> = Vec::new();
        for d in pts {
            let near = truth_at
                .get(&(d.recording.as_str(), d.frame))
                .and_then(|rows| {
                    rows.iter()
                        .map(|r| {
                            (
                                r,
                                ((r.x_um - d.x_um).powi(2) + (r.y_um - d.y_um).powi(2)).sqrt(),
                            )
                        })
                        .filter(|(_, e)| *e <= MATCH_UM)
                        .min_by(|a, b| a.1.total_cmp(&b.1))
                        .map(|(r, _)| *r)
                });
            cells.push(near);
        }
        let ids: Vec<u64> = cells.iter().flatten().map(|r| r.cell_id).collect();
        if ids.len() * 2 < cells.len() {
            m.false_tracks += 1;
            continue;
        }
        if ids.iter().any(|&c| c != ids[0]) {
            m.mixed += 1;
            continue;
        }
        let cell = ids[0];
        let e = covered.entry((t.recording.as_str(), cell)).or_default();
        *e = (*e).max(ids.len());
        for (d, r) in pts.iter().zip(&cells) {
            if let Some(r) = r {
                m.centroid_err
                    .push(((r.x_um - d.x_um).powi(2) + (r.y_um - d.y_um).powi(2)).sqrt());
            }
        }
        let truth_row = cells.iter().flatten().next().unwrap();
        let ve = (t.velocity_mm_s - truth_row.velocity_mm_s).abs() / truth_row.velocity_mm_s;
        m.velocity_rel_err.push(ve);
        m.worst_velocity
            .push((ve, t.recording.clone(), t.track_id, t.n_frames));
        m.shapes
            .push((truth_row.shape.clone(), t.shape.clone(), t.isolated));
    }
    // Recall over truth cells seen whole in at least 3 frames.
    for (name, t) in truths {
        let mut visible: HashMap<u64, usize> = HashMap::new();
        for r in t.rows.iter().filter(|r| r.visible) {
            *visible.entry(r.cell_id).or_default() += 1;
        }
        for (cell, n) in visible {
            if n < 3 {
                continue;
            }
            m.truth_cells += 1;
            // Found: one pure track covers >= 80 % of the frames in which the cell is whole.
            if covered
                .get(&(name.as_str(), cell))
                .is_some_and(|&c| c * 5 >= n * 4)
            {
                m.found += 1;
            }
        }
    }
    m
}

fn report(label: &str, m: &Metrics) -> (f64, f64) {
    let recall = m.found as f64 / m.truth_cells.max(1) as f64;
    let cs: Vec<&(String, String, bool)> = m
        .shapes
        .iter()
        .filter(|(t, p, _)| {
            (t == "croissant" || t == "slipper") && (p == "croissant" || p == "slipper")
        })
        .collect();
    let correct = cs.iter().filter(|(t, p, _)| t == p).count();
    let acc = correct as f64 / cs.len().max(1) as f64;
    let cs_truth = m
        .shapes
        .iter()
        .filter(|(t, _, _)| t == "croissant" || t == "slipper")
        .count();
    let other_truth: Vec<_> = m.shapes.iter().filter(|(t, _, _)| t == "other").collect();
    println!(
        "{label}: recall {}/{} = {:.1} %, false tracks {}, mixed {}, centroid error median {:.4} um p95 {:.4} um, \
         velocity error median {:.3} % max {:.3} %, croissant-vs-slipper accuracy {correct}/{} = {:.1} % \
         ({} of {} croissants+slippers called other), truth 'other' called other {}/{}",
        m.found,
        m.truth_cells,
        100.0 * recall,
        m.false_tracks,
        m.mixed,
        quantile(&m.centroid_err, 0.5),
        quantile(&m.centroid_err, 0.95),
        100.0 * quantile(&m.velocity_rel_err, 0.5),
        100.0 * m.velocity_rel_err.iter().cloned().fold(0.0, f64::max),
        cs.len(),
        100.0 * acc,
        cs_truth - cs.len(),
        cs_truth,
        other_truth.iter().filter(|(_, p, _)| p == "other").count(),
        other_truth.len(),
    );
    let mut worst = m.worst_velocity.clone();
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (e, rec, id, n) in worst.iter().take(5) {
        println!(
            "  velocity error {:.3} %: {rec} track {id} ({n} frames)",
            100.0 * e
        );
    }
    (recall, acc)
}

/// Asserts the bars every study meets; returns the recall and the croissant-vs-slipper accuracy.
fn check(label: &str, m: &Metrics) -> (f64, f64) {
    let (recall, acc) = report(label, m);
    assert!(recall >= 0.98, "recall {recall}");
    assert_eq!(m.mixed, 0, "swapped tracks");
    assert!(
        quantile(&m.centroid_err, 0.5) <= 0.05,
        "median centroid error"
    );
    // Velocity: the bar is 0.5 %; every matched track is held to it.
    let vmax = m.velocity_rel_err.iter().cloned().fold(0.0, f64::max);
    assert!(vmax <= 0.005, "velocity error {vmax}");
    assert!(acc >= 0.95, "croissant-vs-slipper accuracy {acc}");
    (recall, acc)
}

/// The grid of the default test: every pixel size, noise level and velocity end appears.
fn small_grid() -> Vec<Case> {
    let px = [0.15, 0.2, 0.25, 0.3, 0.35];
    let noise = [0.005, 0.01, 0.02];
    let v = [0.1, 0.5, 1.0, 3.0, 6.0, 12.0];
    (0..12u64)
        .map(|k| {
            (
                1000 + k,
                px[k as usize % 5],
                noise[k as usize % 3],
                v[k as usize % 6],
            )
        })
        .collect()
}

#[test]
fn analyze_matches_synthetic_truth() {
    let m = study(&small_grid());
    check("small grid (12 recordings)", &m);
}

/// Trains of cells 42 um apart (just isolated) at 12 mm/s (30 um per frame, so every cell
/// sits 12 um from where its follower will be next frame), and at 0.1 mm/s (0.25 um per
/// frame), through the binary: no swap, every cell found, velocities within 0.5 %.
#[test]
fn dense_trains_fast_and_slow() {
    let specs = vec![
        (
            "train_fast".to_string(),
            train_spec(77, 0.35, 0.01, 12.0, 42.0, 30),
            77,
        ),
        (
            "train_slow".to_string(),
            train_spec(78, 0.3, 0.01, 0.1, 42.0, 150),
            78,
        ),
    ];
    let m = study_specs(specs);
    let (recall, acc) = report("dense trains", &m);
    assert!(recall >= 0.98, "recall {recall}");
    assert_eq!(m.mixed, 0, "swapped tracks");
    assert_eq!(m.false_tracks, 0);
    assert!(m.velocity_rel_err.iter().all(|&e| e <= 0.005));
    assert!(acc >= 0.95 || m.shapes.is_empty());
}

/// Full study: 5 pixel sizes x 3 noise levels x 6 velocities x 2 seeds = 180 recordings, 360 cells.
/// Measured (the README's "Measured"): recall 360/360, no false or swapped tracks, centroid error
/// median 0.0049 um (95th percentile 0.0196 um), velocity error worst 0.21 %, croissant vs
/// slipper 242/242; asserted (the errors to 20 %) on top of the bars of [`check`].
/// `cargo nextest run -p rbc --run-ignored only --no-capture -E 'test(analyze_matches_synthetic_truth_full_study)'`
#[test]
#[ignore = "study: 180 recordings through rbc-analyze, asserted"]
fn analyze_matches_synthetic_truth_full_study() {
    let mut cases = Vec::new();
    let mut seed = 5000;
    for px in [0.15, 0.2, 0.25, 0.3, 0.35] {
        for noise in [0.005, 0.01, 0.02] {
            for v in [0.1, 0.5, 1.0, 3.0, 6.0, 12.0] {
                for _ in 0..2 {
                    seed += 1;
                    cases.push((seed, px, noise, v));
                }
            }
        }
    }
    let m = study(&cases);
    let (recall, acc) = check("full study (180 recordings)", &m);
    assert_eq!((m.found, m.truth_cells, m.false_tracks, m.mixed), (360, 360, 0, 0), "recall, false and swapped tracks");
    let (median, p95) = (quantile(&m.centroid_err, 0.5), quantile(&m.centroid_err, 0.95));
    assert!(median <= 1.2 * 0.0049 && p95 <= 1.2 * 0.0196, "centroid error median {median:.4} um, p95 {p95:.4} um; measured 0.0049, 0.0196");
    let vmax = m.velocity_rel_err.iter().cloned().fold(0.0, f64::max);
    assert!(vmax <= 1.2 * 0.0021, "worst velocity error {vmax:.4}, measured 0.0021");
    assert!(recall == 1.0 && acc == 1.0, "croissant vs slipper accuracy {acc}, measured 242/242");
}

/// The binary under test: `RBC_ANALYZE_BIN` when set (a private copy, when several worktrees
/// share one `CARGO_TARGET_DIR` and may relink `target/debug/rbc-analyze` meanwhile), else cargo's.
fn bin() -> std::path::PathBuf {
    std::env::var_os("RBC_ANALYZE_BIN")
        .map(Into::into)
        .unwrap_or_else(|| env!("CARGO_BIN_EXE_rbc-analyze").into())
}
