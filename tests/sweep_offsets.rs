//! Studies side by side, on synthetic studies whose every value is known. `rbc-sweep offsets`: the
//! steady radial position against r_init in one velocity column (the paper's Fig. 4), one series
//! per study: which runs each series holds (ended and still going), their values, what is left
//! out, the figure's files and colours, and a one-line error for a column without an ended run.
//! `rbc-sweep phase`: the phase diagram (the paper's Fig. 5 a), one panel per study: its ended
//! runs, r_trans per column, the runs still going at their recent velocity, what is left out.
//! `rbc-sweep steady`: the steady radial position and the slippers' extents against the cell
//! velocity (the paper's Fig. 6), each column's mean weighted by the runs' time in the steady state.

mod output_common;

use output_common::{pixels_like, pixels_like_in};
use rbc_analysis::plot::offset::{OffsetFigure, RUNNING_WINDOW_S};
use rbc_analysis::plot::phase_studies::PhaseStudiesFigure;
use rbc_analysis::plot::simulation::SteadyClass;
use rbc_analysis::plot::steady_studies::SteadyStudiesFigure;
use rbc_schema::results::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

const SCENE: &str = "[walls]\nkind = \"periodic-channel\"\nwidth_y_um = 12.0\nheight_z_um = 10.0\n";

fn attrs(start: &str, r: f64) -> RunAttrs {
    RunAttrs { start_shape: start.into(), r_init_um: r, y_init_um: r * 0.874, z_init_um: r * 0.486, lambda: 5.0, scene: SCENE.into() }
}

fn tri() -> Vec<[u32; 3]> {
    vec![[0, 1, 2]]
}

/// An ended run in its own file `dir/<id>.h5` (as a study's state holds them).
fn ended(dir: &Path, id: &str, start: &str, r: f64, u: f64, shape: FinalShape, radial: f64, status: RunStatus) {
    std::fs::create_dir_all(dir).unwrap();
    let mut f = ResultsFile::create_or_open(&dir.join(format!("{id}.h5"))).unwrap();
    let w = f.begin_run(id, &attrs(start, r), &tri()).unwrap();
    let mut ev = BTreeMap::new();
    ev.insert("radial_min_um".to_string(), radial - 0.1);
    ev.insert("radial_max_um".to_string(), radial + 0.2);
    w.finish(&RunSummary {
        status,
        final_shape: shape,
        tank_treading: false,
        tumbling: false,
        mean_velocity_mm_s: u,
        min_velocity_mm_s: u * 0.98,
        max_velocity_mm_s: u * 1.02,
        mean_radial_um: radial,
        mean_y_um: radial,
        mean_z_um: 0.0,
        evidence: ev,
    })
    .unwrap();
}

/// A run still going: samples every 10 ms to `t_end` s, moving at `u_early` mm/s until
/// `RUNNING_WINDOW_S` before its end and at `u_late` after, ending at (y, z) = (0.3, 0.4) um.
fn running(dir: &Path, id: &str, r: f64, t_end: f64, u_early: f64, u_late: f64) {
    std::fs::create_dir_all(dir).unwrap();
    let mut f = ResultsFile::create_or_open(&dir.join(format!("{id}.h5"))).unwrap();
    let mut w = f.begin_run(id, &attrs("discocyte", r), &tri()).unwrap();
    let n = (t_end / 0.01).round() as usize;
    for k in 0..=n {
        let t = k as f64 * 0.01;
        let u = if t >= t_end - RUNNING_WINDOW_S - 1e-9 { u_late } else { u_early };
        let f = k as f64 / n as f64;
        w.append_sample(&TimeSample {
            t_s: t,
            centroid_um: [t * u, r + (0.3 - r) * f, 0.4 * f],
            velocity_mm_s: [u, 0.0, 0.0],
            area_um2: 134.1,
            volume_um3: 94.1,
            asphericity: 0.1,
            extents_um: [3.0, 7.8, 7.8],
        })
        .unwrap();
    }
    w.flush().unwrap();
}

/// Two studies of one grid: `exact/state` and `penalty/state`, each run in its own file.
fn two_studies(root: &Path) -> Vec<PathBuf> {
    let (exact, penalty) = (root.join("exact/state"), root.join("penalty/state"));
    ended(&exact, "discocyte_u3.8_r0.4", "discocyte", 0.4, 6.3, FinalShape::Croissant, 0.31, RunStatus::Steady);
    ended(&exact, "discocyte_u3.8_r0.8", "discocyte", 0.8, 6.2, FinalShape::Slipper, 1.56, RunStatus::Periodic);
    ended(&exact, "discocyte_u1.5_r0.8", "discocyte", 0.8, 2.5, FinalShape::Slipper, 1.13, RunStatus::Periodic); // another column
    ended(&exact, "slipper_u3.8_r0.4", "slipper", 0.4, 6.3, FinalShape::Slipper, 1.55, RunStatus::Periodic); // another start shape
    ended(&penalty, "discocyte_u3.8_r1.2", "discocyte", 1.2, 6.4, FinalShape::Slipper, 1.32, RunStatus::Periodic);
    ended(&penalty, "discocyte_u3.8_r0.4", "discocyte", 0.4, 6.45, FinalShape::Croissant, 0.38, RunStatus::Periodic);
    ended(&penalty, "discocyte_u3.8_r0.5", "discocyte", 0.5, 6.4, FinalShape::Other, 0.9, RunStatus::Unsteady); // no converged shape
    // still going: in the column by its last 50 ms (6.4 mm/s), though slower before (2.0)
    running(&penalty, "discocyte_u3.8_r0.8", 0.8, 0.26, 2.0, 6.4);
    // still going, but in another column by its last 50 ms
    running(&penalty, "discocyte_u1.5_r0.6", 0.6, 0.2, 6.4, 2.5);
    let mut files: Vec<PathBuf> = [exact, penalty].iter().flat_map(|d| std::fs::read_dir(d).unwrap().map(|e| e.unwrap().path())).collect();
    files.sort();
    files
}

#[test]
fn each_study_is_a_series_of_its_ended_and_running_runs_in_the_column() {
    let dir = tempfile::tempdir().unwrap();
    let files = two_studies(dir.path());
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let fig = OffsetFigure::read(&refs, "discocyte", 6.5, 0.05, Some(0.7)).unwrap();
    let labels: Vec<&str> = fig.series.iter().map(|s| s.label.as_str()).collect();
    assert_eq!(labels, ["exact", "penalty"], "a study's state/ is named by its study");
    let ended = |k: usize| fig.series[k].points.iter().map(|p| (p.r_init_um, p.final_shape, p.mean_radial_um, p.radial_min_um, p.radial_max_um)).collect::<Vec<_>>();
    assert_eq!(ended(0), [(0.4, FinalShape::Croissant, 0.31, 0.31 - 0.1, 0.31 + 0.2), (0.8, FinalShape::Slipper, 1.56, 1.56 - 0.1, 1.56 + 0.2)]);
    assert_eq!(ended(1), [(0.4, FinalShape::Croissant, 0.38, 0.38 - 0.1, 0.38 + 0.2), (1.2, FinalShape::Slipper, 1.32, 1.32 - 0.1, 1.32 + 0.2)]);
    assert!(fig.series[0].running.is_empty());
    let going = &fig.series[1].running;
    assert_eq!(going.len(), 1, "only the running run whose last 50 ms lie in the column: {going:?}");
    let g = &going[0];
    assert_eq!((g.run_id.as_str(), g.r_init_um), ("discocyte_u3.8_r0.8", 0.8));
    assert!((g.tail.t_s - 0.26).abs() < 1e-12 && (g.tail.radial_um - 0.5).abs() < 1e-12 && (g.tail.velocity_mm_s - 6.4).abs() < 1e-12, "{g:?}");
    // its radial range over the samples of its last 50 ms (from k = 21 or 22 of 26, as the
    // window's edge rounds): the path passes its closest point to the axis at f = 0.8 / 0.82
    let radial_at = |k: usize| {
        let f = k as f64 / 26.0;
        (0.8 + (0.3 - 0.8) * f).hypot(0.4 * f)
    };
    let first = (0..=26).find(|&k| k as f64 * 0.01 >= 26.0 * 0.01 - RUNNING_WINDOW_S).unwrap();
    let (lo, hi) = (first..=26).map(radial_at).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| (a.min(r), b.max(r)));
    assert!(lo < 0.5 && (g.tail.radial_min_um - lo).abs() < 1e-12 && (g.tail.radial_max_um - hi).abs() < 1e-12, "{g:?}: {lo}-{hi} (window from k = {first})");
    assert_eq!(fig.skipped.len(), 1, "{:?}", fig.skipped);
    assert!(fig.skipped[0].contains("discocyte_u3.8_r0.5") && fig.skipped[0].contains("unsteady"), "{:?}", fig.skipped);
    // the other start shape and the other column are not in the figure
    let fig = OffsetFigure::read(&refs, "slipper", 6.5, 0.05, None).unwrap();
    assert_eq!(fig.series.len(), 1);
    assert_eq!(fig.series[0].points.iter().map(|p| p.run_id.as_str()).collect::<Vec<_>>(), ["slipper_u3.8_r0.4"]);
    let fig = OffsetFigure::read(&refs, "discocyte", 2.5, 0.05, None).unwrap();
    assert_eq!(fig.series.iter().map(|s| (s.label.as_str(), s.points.len(), s.running.len())).collect::<Vec<_>>(), [("exact", 1, 0), ("penalty", 0, 1)]);
}

#[test]
fn a_file_given_twice_counts_once_and_a_run_in_two_files_of_one_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let files = two_studies(dir.path());
    let mut twice: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    twice.extend(files.iter().map(PathBuf::as_path));
    let fig = OffsetFigure::read(&twice, "discocyte", 6.5, 0.05, None).unwrap();
    assert_eq!(fig.series.iter().map(|s| (s.points.len(), s.running.len())).collect::<Vec<_>>(), [(2, 0), (2, 1)], "each run once");
    assert_eq!(fig.skipped.len(), 1, "{:?}", fig.skipped);
    // the same run id in a second file of the exact-wall folder: an error naming both files
    let copy = dir.path().join("exact/state/copy.h5");
    std::fs::copy(dir.path().join("exact/state/discocyte_u3.8_r0.4.h5"), &copy).unwrap();
    let mut refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    refs.push(&copy);
    let e = OffsetFigure::read(&refs, "discocyte", 6.5, 0.05, None).unwrap_err().to_string();
    assert!(e.contains("copy.h5") && e.contains("run discocyte_u3.8_r0.4 is also in") && e.contains("discocyte_u3.8_r0.4.h5") && !e.contains('\n'), "{e}");
}

#[test]
fn a_running_run_without_samples_is_listed_as_left_out_and_a_bare_file_name_labels_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    ended(dir.path(), "discocyte_u3.8_r0.4", "discocyte", 0.4, 6.3, FinalShape::Croissant, 0.31, RunStatus::Steady);
    let fresh = dir.path().join("discocyte_u3.8_r1.h5");
    ResultsFile::create_or_open(&fresh).unwrap().begin_run("discocyte_u3.8_r1", &attrs("discocyte", 1.0), &tri()).unwrap();
    // named from inside the folder, without one in the path
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
        .current_dir(dir.path())
        .args(["offsets", "discocyte_u3.8_r0.4.h5", "./discocyte_u3.8_r1.h5", "--out", "figs"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let folder = dir.path().canonicalize().unwrap();
    let name = folder.file_name().unwrap().to_string_lossy();
    assert!(err.contains("run discocyte_u3.8_r1 left out: still running, no finite sample yet"), "{err}");
    assert!(err.contains(&format!("rbc-sweep: {name}: 0.4 um -> croissant at 0.310 um\n")), "one series, named by the folder: {err}");
}

#[test]
fn folders_of_the_same_name_are_told_apart_by_where_their_paths_differ() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("x/study/state"), dir.path().join("y/study/state"));
    ended(&a, "discocyte_u3.8_r0.4", "discocyte", 0.4, 6.3, FinalShape::Croissant, 0.31, RunStatus::Steady);
    ended(&b, "discocyte_u3.8_r0.4", "discocyte", 0.4, 6.3, FinalShape::Croissant, 0.35, RunStatus::Steady);
    let files = [a.join("discocyte_u3.8_r0.4.h5"), b.join("discocyte_u3.8_r0.4.h5")];
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let fig = OffsetFigure::read(&refs, "discocyte", 6.5, 0.05, None).unwrap();
    assert_eq!(fig.series.iter().map(|s| s.label.as_str()).collect::<Vec<_>>(), ["x", "y"]);
}

#[test]
fn rbc_sweep_offsets_draws_both_studies_and_names_the_runs() {
    let dir = tempfile::tempdir().unwrap();
    let files = two_studies(dir.path());
    let out = dir.path().join("figs");
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).arg("offsets").args(&files).args(["--mark-um", "0.7", "--out"]).arg(&out).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("exact: 0.4 um -> croissant at 0.310 um, 0.8 um -> slipper at 1.560 um"), "{err}");
    assert!(err.contains("penalty: 0.4 um -> croissant at 0.380 um, 1.2 um -> slipper at 1.320 um, 0.8 um still running at 260.0 ms, 0.500 um now"), "{err}");
    let png = out.join("radial_offset.png");
    let svg = std::fs::read_to_string(out.join("radial_offset.svg")).unwrap();
    assert!(svg.contains("transition (r_init ~0.7 um)") && svg.contains("still running") && svg.contains("260 ms"), "the legend and the running run's time");
    // one colour a study: blue (exact), red (penalty)
    assert!(pixels_like(&png, [0x1f, 0x77, 0xb4]) > 100, "the first study's markers");
    assert!(pixels_like(&png, [0xd6, 0x27, 0x28]) > 100, "the second study's markers");
    // a column without any ended run: one line naming the file, nothing written
    refused_in_one_line("offsets", &files, &["--velocity-mm-s", "10.4"], &dir.path().join("empty"), "no ended discocyte run within 5 % of 10.4 mm/s");
    // a mark off the channel, or not a number (`inf` drew an endless axis): refused the same way
    for mark in ["inf", "NaN", "1.7e308", "25"] {
        refused_in_one_line("offsets", &files, &["--mark-um", mark], &dir.path().join("marked"), &format!("--mark-um {}", mark.parse::<f64>().unwrap()));
    }
}

/// `rbc-sweep COMMAND FILES... EXTRA... --out OUT` fails with one line naming the first file and
/// saying `why`, and writes nothing.
fn refused_in_one_line(command: &str, files: &[PathBuf], extra: &[&str], out: &Path, why: &str) {
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).arg(command).args(files).args(extra).arg("--out").arg(out).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains(&files[0].display().to_string()) && err.contains(why), "{err}");
    assert!(!out.exists(), "nothing written");
}

#[test]
fn each_study_is_a_phase_diagram_panel_of_its_ended_runs_and_those_still_going() {
    let dir = tempfile::tempdir().unwrap();
    let files = two_studies(dir.path());
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let fig = PhaseStudiesFigure::read(&refs, "discocyte", 0.05).unwrap();
    assert_eq!(fig.studies().iter().map(|s| s.label.as_str()).collect::<Vec<_>>(), ["exact", "penalty"]);
    let ended = |k: usize| fig.studies()[k].points.iter().map(|p| (p.velocity_mm_s, p.r_init_um, p.final_shape)).collect::<Vec<_>>();
    // by velocity, then r_init; the slipper start shape's run is not in the discocyte's diagram
    assert_eq!(ended(0), [(2.5, 0.8, FinalShape::Slipper), (6.2, 0.8, FinalShape::Slipper), (6.3, 0.4, FinalShape::Croissant)]);
    assert_eq!(ended(1), [(6.4, 1.2, FinalShape::Slipper), (6.45, 0.4, FinalShape::Croissant)]);
    // r_trans per column: the bracket's midpoint, 0 without a croissant
    let columns = |k: usize| fig.studies()[k].thresholds.iter().map(|t| (t.r_trans_um, t.interval())).collect::<Vec<_>>();
    let near = |a: &[(f64, (f64, f64))], b: &[(f64, (f64, f64))]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x.0 - y.0).abs() < 1e-12 && (x.1 .0 - y.1 .0).abs() < 1e-12 && (x.1 .1 - y.1 .1).abs() < 1e-12);
    assert!(near(&columns(0), &[(0.0, (0.0, 0.8)), (0.6, (0.4, 0.8))]), "{:?}", columns(0));
    assert!(near(&columns(1), &[(0.8, (0.4, 1.2))]), "{:?}", columns(1));
    // still going: where their last 50 ms place them (one at 2.0 mm/s before, 6.4 after)
    assert!(fig.studies()[0].running.is_empty());
    let going: Vec<_> = fig.studies()[1].running.iter().map(|p| (p.run_id.as_str(), p.r_init_um, p.tail.velocity_mm_s, p.tail.t_s)).collect();
    assert_eq!(going.len(), 2, "{going:?}");
    assert_eq!((going[0].0, going[0].1), ("discocyte_u1.5_r0.6", 0.6));
    assert!((going[0].2 - 2.5).abs() < 1e-12 && (going[0].3 - 0.2).abs() < 1e-12, "{going:?}");
    assert_eq!((going[1].0, going[1].1), ("discocyte_u3.8_r0.8", 0.8));
    assert!((going[1].2 - 6.4).abs() < 1e-12 && (going[1].3 - 0.26).abs() < 1e-12, "{going:?}");
    assert_eq!(fig.skipped().len(), 1, "{:?}", fig.skipped());
    assert!(fig.skipped()[0].contains("discocyte_u3.8_r0.5") && fig.skipped()[0].contains("unsteady"), "{:?}", fig.skipped());
    // the other start shape: one panel, the exact-wall study's
    let fig = PhaseStudiesFigure::read(&refs, "slipper", 0.05).unwrap();
    assert_eq!(fig.studies().iter().map(|s| (s.label.as_str(), s.points.len(), s.running.len())).collect::<Vec<_>>(), [("exact", 1, 0)]);
    // a tolerance of 1 %: the exact walls' 6.2 and 6.3 mm/s runs are two columns, each of one shape
    let fig = PhaseStudiesFigure::read(&refs, "discocyte", 0.01).unwrap();
    assert_eq!(fig.studies()[0].thresholds.iter().map(|t| (t.n_croissant, t.n_slipper)).collect::<Vec<_>>(), [(0, 1), (0, 1), (1, 0)]);
}

#[test]
fn a_run_in_two_files_of_one_folder_is_refused_whatever_its_start_shape_and_a_run_without_a_forward_velocity_is_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let files = two_studies(dir.path());
    // a second copy of the slipper start's run in the exact-wall folder: refused also when the
    // figure draws the discocyte start
    let copy = dir.path().join("exact/state/copy.h5");
    std::fs::copy(dir.path().join("exact/state/slipper_u3.8_r0.4.h5"), &copy).unwrap();
    let mut refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    refs.push(&copy);
    for e in [PhaseStudiesFigure::read(&refs, "discocyte", 0.05).unwrap_err().to_string(), OffsetFigure::read(&refs, "discocyte", 6.5, 0.05, None).unwrap_err().to_string()] {
        assert!(e.contains("copy.h5") && e.contains("run slipper_u3.8_r0.4 is also in") && !e.contains('\n'), "{e}");
    }
    // an ended run moving backwards (the results writer refuses a NaN): left out with the reason,
    // not drawn in a column
    let nan = dir.path().join("backwards/state");
    ended(&nan, "discocyte_u3.8_r0.6", "discocyte", 0.6, -6.3, FinalShape::Slipper, 1.5, RunStatus::Periodic);
    ended(&nan, "discocyte_u3.8_r0.4", "discocyte", 0.4, 6.3, FinalShape::Croissant, 0.31, RunStatus::Steady);
    let both = [nan.join("discocyte_u3.8_r0.6.h5"), nan.join("discocyte_u3.8_r0.4.h5")];
    let refs: Vec<&Path> = both.iter().map(PathBuf::as_path).collect();
    let fig = PhaseStudiesFigure::read(&refs, "discocyte", 0.05).unwrap();
    assert_eq!(fig.studies()[0].points.len(), 1);
    assert_eq!(fig.studies()[0].thresholds.iter().map(|t| (t.velocity_mm_s, t.n_croissant, t.n_slipper)).collect::<Vec<_>>(), [(6.3, 1, 0)], "one column, the croissant's");
    assert_eq!(fig.skipped().len(), 1, "{:?}", fig.skipped());
    assert!(fig.skipped()[0].contains("discocyte_u3.8_r0.6") && fig.skipped()[0].contains("not a positive finite number"), "{:?}", fig.skipped());
}

#[test]
fn rbc_sweep_phase_draws_one_panel_a_study_and_refuses_a_start_shape_without_runs() {
    let dir = tempfile::tempdir().unwrap();
    let files = two_studies(dir.path());
    let out = dir.path().join("figs");
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).arg("phase").args(&files).arg("--out").arg(&out).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("exact: 2.50 mm/s from 0.8 um -> slipper, 6.20 mm/s from 0.8 um -> slipper, 6.30 mm/s from 0.4 um -> croissant\n"), "{err}");
    assert!(err.contains("penalty: 6.40 mm/s from 1.2 um -> slipper, 6.45 mm/s from 0.4 um -> croissant, 2.50 mm/s from 0.6 um still running at 200.0 ms, 6.40 mm/s from 0.8 um still running at 260.0 ms"), "{err}");
    assert!(err.contains("run discocyte_u3.8_r0.5 left out: unsteady"), "{err}");
    let png = out.join("phase_studies.png");
    let svg = std::fs::read_to_string(out.join("phase_studies.svg")).unwrap();
    assert!(svg.contains("exact, start shape: discocyte") && svg.contains("penalty, start shape: discocyte"), "one panel a study");
    assert!(svg.contains("still running") && svg.contains("260 ms") && svg.contains("200 ms"), "the runs still going and how far they got");
    assert_eq!(image::image_dimensions(&png).unwrap(), (1300, 650), "650 px a panel");
    // croissants (blue) and slippers (red) in both panels
    for x0 in [0, 650] {
        let panel = |c| pixels_like_in(&png, c, x0..x0 + 650);
        assert!(panel([0x1f, 0x77, 0xb4]) > 50 && panel([0xd6, 0x27, 0x28]) > 50, "panel at x = {x0}");
    }
    // the hollow markers of the two runs still going, and the legend's
    assert_eq!(svg.matches("fill=\"none\" stroke=\"#555555\"").count(), 2 + 1, "the hollow markers");
    // a start shape no file holds: one line naming the first file, nothing written
    refused_in_one_line("phase", &files, &["--start", "stomatocyte"], &dir.path().join("none"), "no stomatocyte run, ended or still going");
}

/// An ended run in its own file `dir/<id>.h5` with what the paper's Fig. 6 reads: its time in the
/// steady state `steady_s` (s, the weight), its radial position (mean, and min/max 0.1 below and
/// 0.2 above), its extents along x, y, z (um, mean; min 0.2 below, max 0.3 above) and its
/// membrane's tank-treading frequency (`1.25 u + radial` Hz when it tank-treads, 0.02 Hz when not).
#[allow(clippy::too_many_arguments)]
fn ended_steady(dir: &Path, id: &str, u: f64, shape: FinalShape, tank_treading: bool, radial: f64, steady_s: f64, extents: [f64; 3]) {
    ended_steady_tumbling(dir, id, u, shape, tank_treading, None, radial, steady_s, extents);
}

/// [`ended_steady`], labelled tumbling at `tumbling_hz` (the classifier's signed rate about z)
/// when given.
#[allow(clippy::too_many_arguments)]
fn ended_steady_tumbling(dir: &Path, id: &str, u: f64, shape: FinalShape, tank_treading: bool, tumbling_hz: Option<f64>, radial: f64, steady_s: f64, extents: [f64; 3]) {
    std::fs::create_dir_all(dir).unwrap();
    let mut f = ResultsFile::create_or_open(&dir.join(format!("{id}.h5"))).unwrap();
    let w = f.begin_run(id, &attrs("discocyte", 0.4), &tri()).unwrap();
    let mut ev = BTreeMap::new();
    ev.insert("radial_min_um".to_string(), radial - 0.1);
    ev.insert("radial_max_um".to_string(), radial + 0.2);
    ev.insert("steady_duration_s".to_string(), steady_s);
    ev.insert("tt_frequency_hz".to_string(), if tank_treading { 1.25 * u + radial } else { 0.02 });
    ev.insert("tumbling_frequency_hz".to_string(), tumbling_hz.unwrap_or(0.01));
    for (axis, e) in ["x", "y", "z"].iter().zip(extents) {
        ev.insert(format!("extent_{axis}_mean_um"), e);
        ev.insert(format!("extent_{axis}_min_um"), e - 0.2);
        ev.insert(format!("extent_{axis}_max_um"), e + 0.3);
    }
    let status = if shape == FinalShape::Other { RunStatus::Unsteady } else { RunStatus::Periodic };
    w.finish(&RunSummary { status, final_shape: shape, tank_treading, tumbling: tumbling_hz.is_some(), mean_velocity_mm_s: u, min_velocity_mm_s: u * 0.98, max_velocity_mm_s: u * 1.02, mean_radial_um: radial, mean_y_um: radial, mean_z_um: 0.0, evidence: ev }).unwrap();
}

/// Two studies of steady states whose column means are known by hand (`exact/state`,
/// `penalty/state`), each run in its own file, sorted.
fn two_steady_studies(root: &Path) -> Vec<PathBuf> {
    let (exact, penalty) = (root.join("exact/state"), root.join("penalty/state"));
    // one column of two croissants: weights 0.5 and 1.5 s
    ended_steady(&exact, "discocyte_u1.5_r0.4", 2.5, FinalShape::Croissant, false, 0.10, 0.5, [6.6, 6.8, 6.3]);
    ended_steady(&exact, "discocyte_u1.5_r0.6", 2.55, FinalShape::Croissant, false, 0.20, 1.5, [6.6, 6.8, 6.3]);
    ended_steady(&exact, "discocyte_u3.8_r0.4", 6.4, FinalShape::Croissant, true, 0.30, 0.5, [7.0, 6.5, 6.0]);
    ended_steady(&exact, "discocyte_u0.63_r1.2", 1.0, FinalShape::Slipper, true, 1.20, 1.0, [7.7, 4.8, 6.9]);
    ended_steady(&exact, "discocyte_u3.8_r1.2", 6.3, FinalShape::Slipper, true, 1.50, 0.5, [9.5, 4.4, 6.2]);
    // the same column: weights 0.5 and 1.5 s for the extents too
    ended_steady(&exact, "discocyte_u3.8_r0.8", 6.3, FinalShape::Slipper, true, 1.30, 1.5, [9.1, 4.6, 6.4]);
    ended_steady(&penalty, "discocyte_u3.8_r1.2", 6.4, FinalShape::Slipper, true, 1.30, 2.0, [8.9, 4.5, 6.3]);
    ended_steady(&penalty, "discocyte_u3.8_r0.5", 6.4, FinalShape::Other, false, 0.9, 0.5, [8.0, 5.0, 6.0]); // unsteady
    running(&penalty, "discocyte_u3.8_r0.8", 0.8, 0.26, 2.0, 6.4);
    ended(&exact, "slipper_u3.8_r0.4", "slipper", 0.4, 6.3, FinalShape::Slipper, 1.55, RunStatus::Periodic); // another start shape
    let mut files: Vec<PathBuf> = [exact, penalty].iter().flat_map(|d| std::fs::read_dir(d).unwrap().map(|e| e.unwrap().path())).collect();
    files.sort();
    files
}

#[test]
fn each_studys_steady_columns_are_weighted_by_the_runs_time_in_the_steady_state() {
    let dir = tempfile::tempdir().unwrap();
    let files = two_steady_studies(dir.path());
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let fig = SteadyStudiesFigure::read(&refs, "discocyte", 0.05).unwrap();
    assert_eq!(fig.studies().iter().map(|s| (s.label.as_str(), s.running)).collect::<Vec<_>>(), [("exact", 0), ("penalty", 1)]);
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    // (class, velocity, value, min, max, velocity min, velocity max, runs) by class, then velocity
    let columns = |cols: &[rbc_analysis::plot::simulation::ColumnMean]| cols.iter().map(|c| (c.class, c.velocity_mm_s, c.value, c.min, c.max, c.velocity_min_mm_s, c.velocity_max_mm_s, c.n_runs)).collect::<Vec<_>>();
    let want_exact = [
        // (0.5 x 2.5 + 1.5 x 2.55) / 2 mm/s; (0.5 x 0.10 + 1.5 x 0.20) / 2 um; radial 0.0-0.4; u 2.45-2.601
        (SteadyClass::Croissant, 2.5375, 0.175, 0.0, 0.4, 2.45, 2.601, 2),
        (SteadyClass::TankTreadingCroissant, 6.4, 0.3, 0.2, 0.5, 6.272, 6.528, 1),
        (SteadyClass::Slipper, 1.0, 1.2, 1.1, 1.4, 0.98, 1.02, 1),
        // (0.5 x 1.5 + 1.5 x 1.3) / 2 um; radial 1.2-1.7
        (SteadyClass::Slipper, 6.3, 1.35, 1.2, 1.7, 6.174, 6.426, 2),
    ];
    let got = columns(&fig.studies()[0].radial);
    assert_eq!(got.len(), want_exact.len(), "{got:?}");
    for (g, w) in got.iter().zip(&want_exact) {
        assert!(g.0 == w.0 && g.7 == w.7 && [(g.1, w.1), (g.2, w.2), (g.3, w.3), (g.4, w.4), (g.5, w.5), (g.6, w.6)].iter().all(|&(a, b)| close(a, b)), "{g:?} against {w:?}");
    }
    let got = columns(&fig.studies()[1].radial);
    assert!(got.len() == 1 && got[0].0 == SteadyClass::Slipper && close(got[0].1, 6.4) && close(got[0].2, 1.3), "the penalty study's slipper alone: {got:?}");
    // (b): the slippers' extents, per axis, by velocity (mean, min 0.2 below, max 0.3 above)
    let extents = |k: usize, axis: usize| fig.studies()[k].extents[axis].iter().map(|c| (c.velocity_mm_s, c.value, c.min, c.max)).collect::<Vec<_>>();
    let near = |a: &[(f64, f64, f64, f64)], b: &[(f64, f64, f64, f64)]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| close(x.0, y.0) && close(x.1, y.1) && close(x.2, y.2) && close(x.3, y.3));
    // at 6.3 mm/s weighted 0.5 and 1.5 s: x (0.5 x 9.5 + 1.5 x 9.1) / 2 = 9.2, z (0.5 x 6.2 + 1.5 x 6.4) / 2 = 6.35
    assert!(near(&extents(0, 0), &[(1.0, 7.7, 7.5, 8.0), (6.3, 9.2, 8.9, 9.8)]), "{:?}", extents(0, 0));
    assert!(near(&extents(0, 2), &[(1.0, 6.9, 6.7, 7.2), (6.3, 6.35, 6.0, 6.7)]), "{:?}", extents(0, 2));
    assert!(near(&extents(1, 1), &[(6.4, 4.5, 4.3, 4.8)]), "{:?}", extents(1, 1));
    // (c): the membrane's tank-treading frequency per class, weighted as (a); bars over the runs
    let tt = |k: usize| fig.studies()[k].tank_treading.iter().map(|c| (c.velocity_mm_s, c.value, c.min, c.max)).collect::<Vec<_>>();
    // 6.3 mm/s: 1.25 x 6.3 + 1.5 = 9.375 (0.5 s) and + 1.3 = 9.175 (1.5 s): 9.225
    let want = [(2.5375, 0.02, 0.02, 0.02), (6.4, 8.3, 8.3, 8.3), (1.0, 2.45, 2.45, 2.45), (6.3, 9.225, 9.175, 9.375)];
    assert!(near(&tt(0), &want), "{:?}", tt(0));
    assert_eq!(fig.studies()[0].tank_treading.iter().map(|c| c.class).collect::<Vec<_>>(), [SteadyClass::Croissant, SteadyClass::TankTreadingCroissant, SteadyClass::Slipper, SteadyClass::Slipper]);
    assert!(near(&tt(1), &[(6.4, 9.3, 9.3, 9.3)]), "{:?}", tt(1));
    assert_eq!(fig.skipped().len(), 1, "{:?}", fig.skipped());
    assert!(fig.skipped()[0].contains("discocyte_u3.8_r0.5") && fig.skipped()[0].contains("unsteady"), "{:?}", fig.skipped());
}

/// Panel (c)'s tumbling slippers (the paper's below ~0.7 mm/s): weighted as every column, the
/// magnitude of the shape's rate about z, only for the runs labelled tumbling, and still
/// slippers in (a) and (b).
#[test]
fn tumbling_slippers_get_their_own_columns_in_panel_c_and_stay_slippers_in_a() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("penalty/state");
    // one column of two tumbling slippers (weights 0.5 and 1.5 s, rates -0.6 and +0.64 Hz about z)
    ended_steady_tumbling(&study, "discocyte_u0.16_r1.2", 0.25, FinalShape::Slipper, false, Some(-0.6), 1.6, 0.5, [8.0, 3.5, 7.8]);
    ended_steady_tumbling(&study, "discocyte_u0.16_r0.8", 0.26, FinalShape::Slipper, false, Some(0.64), 1.4, 1.5, [8.0, 3.6, 7.9]);
    // a tank-treading slipper at ~1 mm/s: no tumbling column
    ended_steady(&study, "discocyte_u0.63_r1.2", 1.0, FinalShape::Slipper, true, 1.2, 1.0, [7.7, 4.8, 6.9]);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&study).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let fig = SteadyStudiesFigure::read(&refs, "discocyte", 0.1).unwrap();
    let s = &fig.studies()[0];
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    // (0.5 x 0.25 + 1.5 x 0.26) / 2 = 0.2575 mm/s; (0.5 x 0.6 + 1.5 x 0.64) / 2 = 0.63 Hz
    assert_eq!(s.tumbling.len(), 1, "{:?}", s.tumbling);
    let c = &s.tumbling[0];
    assert!(c.class == SteadyClass::Slipper && c.n_runs == 2 && close(c.velocity_mm_s, 0.2575) && close(c.value, 0.63) && close(c.min, 0.6) && close(c.max, 0.64), "{c:?}");
    // (a): both columns slippers; (1.6 x 0.5 + 1.4 x 1.5) / 2 = 1.45 um
    let radial: Vec<(SteadyClass, f64, usize)> = s.radial.iter().map(|c| (c.class, c.value, c.n_runs)).collect();
    assert!(radial.len() == 2 && radial[0].0 == SteadyClass::Slipper && close(radial[0].1, 1.45) && radial[0].2 == 2 && close(radial[1].1, 1.2), "{radial:?}");
    // (c) tank-treading: the tumbling column's membrane at 0.02 Hz, the ~1 mm/s slipper's 2.45
    let tt: Vec<f64> = s.tank_treading.iter().map(|c| c.value).collect();
    assert!(tt.len() == 2 && close(tt[0], 0.02) && close(tt[1], 2.45), "{tt:?}");
    let out = dir.path().join("figs");
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).arg("steady").args(&files).args(["--velocity-tol", "0.1", "--out"]).arg(&out).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("penalty: tumbling: slipper at 0.26 mm/s: 0.63 Hz (0.60-0.64, 2 run(s))"), "{err}");
    let svg = std::fs::read_to_string(out.join("steady_studies.svg")).unwrap();
    assert!(svg.contains("penalty: slipper tumbling") && svg.contains("(c) membrane tank-treading, shape tumbling"), "panel (c)'s legend and caption");
}

#[test]
fn rbc_sweep_steady_draws_its_three_panels_and_refuses_files_without_a_steady_state() {
    let dir = tempfile::tempdir().unwrap();
    let files = two_steady_studies(dir.path());
    let out = dir.path().join("figs");
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).arg("steady").args(&files).arg("--out").arg(&out).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("exact: croissant at 2.54 mm/s: 0.175 um (0.000-0.400, 2 run(s)), TT croissant at 6.40 mm/s: 0.300 um (0.200-0.500, 1 run(s)), slipper at 1.00 mm/s"), "{err}");
    assert!(err.contains("penalty: slipper at 6.40 mm/s: 1.300 um (1.200-1.500, 1 run(s)); 1 still running"), "{err}");
    assert!(err.contains("run discocyte_u3.8_r0.5 left out: unsteady"), "{err}");
    assert!(err.contains("penalty: tank-treading: slipper at 6.40 mm/s: 9.30 Hz (9.30-9.30)"), "panel (c)'s column means: {err}");
    let png = out.join("steady_studies.png");
    let svg = std::fs::read_to_string(out.join("steady_studies.svg")).unwrap();
    for legend in ["exact: croissant", "exact: TT croissant", "exact: slipper", "penalty: slipper", "exact: length (x)", "penalty: extent z"] {
        assert!(svg.contains(legend), "legend {legend}");
    }
    assert!(!svg.contains("penalty: croissant"), "a class a study lacks has no legend");
    assert_eq!(image::image_dimensions(&png).unwrap(), (1950, 650), "three panels of 650 px");
    // (a) and (c): the studies' colours, blue (exact) and red (penalty); (b): the axes' (purple, orange, brown)
    let left = |c| pixels_like_in(&png, c, 0..650);
    let middle = |c| pixels_like_in(&png, c, 650..1300);
    let right = |c| pixels_like_in(&png, c, 1300..1950);
    assert!(left([0x1f, 0x77, 0xb4]) > 50 && left([0xd6, 0x27, 0x28]) > 50, "both studies in (a)");
    assert!(middle([0x94, 0x67, 0xbd]) > 50 && middle([0xff, 0x7f, 0x0e]) > 50 && middle([0x8c, 0x56, 0x4b]) > 50, "the three axes in (b)");
    assert!(right([0x1f, 0x77, 0xb4]) > 50 && right([0xd6, 0x27, 0x28]) > 50, "both studies in (c)");
    assert!(svg.contains("(c) membrane tank-treading, shape tumbling, start: discocyte"), "panel (c)'s caption");
    assert!(!svg.contains("slipper tumbling") && !err.contains("tumbling:"), "no study has a tumbling slipper");
    // only a run still going and an unsteady one: one line naming the first file, nothing written
    let neither = [dir.path().join("penalty/state/discocyte_u3.8_r0.5.h5"), dir.path().join("penalty/state/discocyte_u3.8_r0.8.h5")];
    refused_in_one_line("steady", &neither, &[], &dir.path().join("none"), "no discocyte run that ended a croissant or a slipper");
}
