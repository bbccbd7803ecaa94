//! `rbc-sweep relabel`: the labels of ended runs decided again from their stored evidence.
//! The evidence of the study's r_init = 0.4 um run (ended periodic at 1303.2 ms, labelled
//! `other` when a croissant needed both mirror planes) becomes a (tank-treading) croissant; a tank-treading
//! slipper's stays; the r0.4 run, which ended before 10 mm, gets its steady state carried
//! there; a running run is not touched; incomplete evidence is refused before anything is written.

use rbc::sweep::relabel::relabel;
use rbc_schema::results::*;
use rbc_solver::classify::{ClassifyConfig, Evidence};
use std::collections::BTreeMap;
use std::path::Path;

fn attrs(r: f64) -> RunAttrs {
    RunAttrs { start_shape: "discocyte".into(), r_init_um: r, y_init_um: r, z_init_um: 0.0, lambda: 5.0, scene: "[cell]\n".into() }
}

/// The classifier's evidence of the study's r_init = 0.4 um run at its end (state/discocyte_u3.8_r0.4.h5).
fn r04_evidence() -> Evidence {
    Evidence {
        offset_y_um: 0.0153,
        offset_z_um: 0.3126,
        offset_r_um: 0.3129,
        r_eff_um: 3.354,
        mirror_y_um: 0.0474,
        mirror_z_um: 0.930,
        mirror_y_rel: 0.0141,
        mirror_z_rel: 0.2772,
        mirror_fold_um: 0.0474,
        mirror_fold_rel: 0.0141,
        fold_angle_deg: 0.0,
        tt_axis: [0.0016, -0.9994, 0.0348],
        label_rate_rad_s: 0.0,
        shape_rate_rad_s: 0.0,
        tt_frequency_hz: 2.28,
        tumbling_frequency_hz: 0.0027,
        tumbling_turns: -0.0005,
        nonrigid_speed_um_s: 39.0,
        nonrigid_ratio: 0.00605,
        window_s: 0.096,
        n_frames: 25,
    }
}

fn slipper_evidence() -> Evidence {
    Evidence { offset_y_um: 1.5, offset_z_um: 0.02, offset_r_um: 1.5, mirror_y_rel: 0.3, mirror_z_rel: 0.04, mirror_fold_rel: 0.04, fold_angle_deg: 90.0, tt_frequency_hz: 12.8, tt_axis: [0.0, 0.0, 1.0], ..r04_evidence() }
}

/// A run from x = 0 at t = 0 to `end` = (t_s, x_um), ended periodic at 6.45 mm/s (or running
/// without evidence), with a 10 mm transit recorded as it passed when `passed_10mm`.
fn write_run(f: &mut ResultsFile, id: &str, shape: FinalShape, tt: bool, evidence: Option<BTreeMap<String, f64>>, end: (f64, f64), passed_10mm: bool) {
    let mut w = f.begin_run(id, &attrs(0.4), &[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]).unwrap();
    for (t_s, x) in [(0.0, 0.0), end] {
        w.append_sample(&TimeSample { t_s, centroid_um: [x, 0.0, 0.31], velocity_mm_s: [6.45, 0.0, 0.0], area_um2: 135.0, volume_um3: 94.0, asphericity: 0.1, extents_um: [2.0, 7.8, 7.8] })
            .unwrap();
    }
    if passed_10mm {
        w.set_transit(&Transit { distance_mm: 10.0, t_s: 1.55, x_um: 1e4, y_um: 1.5, z_um: 0.0, velocity_mm_s: 6.45, shape, from_steady: false }).unwrap();
    }
    let Some(evidence) = evidence else { return w.flush().unwrap() };
    let summary = RunSummary {
        status: RunStatus::Periodic,
        final_shape: shape,
        tank_treading: tt,
        tumbling: false,
        mean_velocity_mm_s: 6.45,
        min_velocity_mm_s: 6.4,
        max_velocity_mm_s: 6.5,
        mean_radial_um: 0.31,
        mean_y_um: 0.015,
        mean_z_um: 0.31,
        evidence,
    };
    w.finish(&summary).unwrap();
}

fn label(path: &Path, id: &str) -> Option<(FinalShape, bool, bool)> {
    ResultsFile::open(path).unwrap().run(id).unwrap().summary.map(|s| (s.final_shape, s.tank_treading, s.tumbling))
}

#[test]
fn the_r04_run_becomes_a_croissant_and_the_others_stay() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("results.h5");
    {
        let mut f = ResultsFile::create_or_open(&path).unwrap();
        // r0.4 ended periodic at 1.3032 s after 8.4 mm; r1.2 passed 10 mm and ended at 12 mm
        write_run(&mut f, "r0.4", FinalShape::Other, false, Some(r04_evidence().to_map()), (1.3032, 8400.0), false);
        write_run(&mut f, "r1.2", FinalShape::Slipper, true, Some(slipper_evidence().to_map()), (1.9, 12_000.0), true);
        write_run(&mut f, "running", FinalShape::Other, false, None, (0.5, 3000.0), false);
    }
    let before = ResultsFile::open(&path).unwrap().run("r0.4").unwrap();
    let out = relabel(&path, &ClassifyConfig::default()).unwrap();
    assert_eq!(out.len(), 2, "the ended runs: {out:?}");
    assert_eq!(out[0].run_id, "r0.4");
    // its membrane circulates at 2.28 Hz, 0.22 turn over its window: a tank-treading croissant
    assert_eq!((out[0].before, out[0].after), ((FinalShape::Other, false, false), (FinalShape::Croissant, true, false)));
    assert!(!out[1].changed() && out[1].transits_mm.is_empty(), "{:?}", out[1]);
    assert_eq!(out[0].transits_mm, [10.0], "r0.4 ended before 10 mm");
    assert_eq!(label(&path, "r0.4"), Some((FinalShape::Croissant, true, false)));
    // its steady state carried to 10 mm: the new label, the window's mean position and velocity,
    // reached 1.6 mm after its end at 6.45 mm/s
    let t = ResultsFile::open(&path).unwrap().run("r0.4").unwrap().transits;
    assert_eq!(t.len(), 1, "{t:?}");
    assert!(t[0].from_steady && t[0].shape == FinalShape::Croissant && t[0].distance_mm == 10.0, "{t:?}");
    assert_eq!([t[0].x_um, t[0].y_um, t[0].z_um, t[0].velocity_mm_s], [1e4, 0.015, 0.31, 6.45]);
    assert!((t[0].t_s - (1.3032 + 1600.0 / 6450.0)).abs() < 1e-12, "{}", t[0].t_s);
    let passed = ResultsFile::open(&path).unwrap().run("r1.2").unwrap().transits;
    assert_eq!((passed.len(), passed[0].from_steady, passed[0].t_s), (1, false, 1.55), "the record made as it passed stays");
    assert_eq!(label(&path, "r1.2"), Some((FinalShape::Slipper, true, false)));
    let after = ResultsFile::open(&path).unwrap().run("r0.4").unwrap();
    let (b, a) = (before.summary.unwrap(), after.summary.unwrap());
    assert_eq!((b.evidence, b.mean_radial_um, b.status), (a.evidence, a.mean_radial_um, a.status), "only the label changes");
    let running = ResultsFile::open(&path).unwrap().run("running").unwrap();
    assert_eq!((running.status, running.summary.is_none()), (RunStatus::Running, true));
    // again: nothing changes
    assert!(relabel(&path, &ClassifyConfig::default()).unwrap().iter().all(|r| !r.changed()));
    // stricter thresholds than the run's asymmetry about y: other again
    let strict = ClassifyConfig { symmetric_rel: 0.01, ..ClassifyConfig::default() };
    let out = relabel(&path, &strict).unwrap();
    assert_eq!((out[0].after.0, &out[0].transits_mm[..]), (FinalShape::Other, &[10.0][..]), "the carried record follows the label");
    let t = ResultsFile::open(&path).unwrap().run("r0.4").unwrap().transits;
    assert_eq!((t.len(), t[0].shape), (1, FinalShape::Other));
}

#[test]
fn incomplete_evidence_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("results.h5");
    {
        let mut f = ResultsFile::create_or_open(&path).unwrap();
        write_run(&mut f, "a", FinalShape::Other, false, Some(r04_evidence().to_map()), (1.3, 8400.0), false);
        let mut partial = r04_evidence().to_map();
        partial.remove("mirror_z_rel");
        write_run(&mut f, "b", FinalShape::Other, false, Some(partial), (1.3, 8400.0), false);
    }
    let e = relabel(&path, &ClassifyConfig::default()).unwrap_err().to_string();
    assert!(e.contains("results.h5") && e.contains("run `b`") && e.contains("evidence_mirror_z_rel"), "{e}");
    assert_eq!(label(&path, "a"), Some((FinalShape::Other, false, false)), "nothing written");
    assert!(ResultsFile::open(&path).unwrap().run("a").unwrap().transits.is_empty(), "nothing written");
    assert!(relabel(&dir.path().join("missing.h5"), &ClassifyConfig::default()).is_err());
    assert!(!dir.path().join("missing.h5").exists(), "a missing file is not created");
}

/// A run that ended with no classifier evidence (fewer than 3 shapes when it ended: `other`, as
/// `summarize` records it) keeps its label and does not stop the other runs of the file from
/// being decided again; a run whose evidence lacks one attribute is still refused (above).
#[test]
fn a_run_without_classifier_evidence_keeps_its_label_and_the_others_are_decided() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("results.h5");
    {
        let mut f = ResultsFile::create_or_open(&path).unwrap();
        write_run(&mut f, "r0.4", FinalShape::Other, false, Some(r04_evidence().to_map()), (1.3032, 8400.0), false);
        let window: BTreeMap<String, f64> = [("steady_start_s".to_string(), 0.0), ("steady_end_s".to_string(), 0.05)].into();
        write_run(&mut f, "short", FinalShape::Other, false, Some(window), (0.05, 320.0), false);
    }
    let out = relabel(&path, &ClassifyConfig::default()).unwrap();
    assert_eq!(out.iter().map(|r| (r.run_id.as_str(), r.changed())).collect::<Vec<_>>(), [("r0.4", true), ("short", false)]);
    assert_eq!(label(&path, "r0.4"), Some((FinalShape::Croissant, true, false)));
    assert_eq!(label(&path, "short"), Some((FinalShape::Other, false, false)));
    assert!(ResultsFile::open(&path).unwrap().run("short").unwrap().transits.is_empty(), "nothing carried for it");
}
