//! Isolation (40 um criterion, border objects as neighbours, merged clusters) and the
//! croissant / slipper / other decision, on detection lists with known answers.

mod tracks_common;

use rbc_analysis::experiment::classify::{classify, classify_frames, classify_frames_with, ClassifierConfig, FrameShape, Shape};
use rbc_analysis::experiment::isolate::{cluster_flags, gaps_per_detection, isolate, IsolationConfig};
use rbc_analysis::experiment::track::{link, Track, TrackerConfig};
use tracks_common::*;

/// Two cells at constant spacing s: gap_um is exactly s, isolated iff s >= 40 um.
#[test]
fn gap_is_the_centroid_distance_along_x() {
    for (spacing, isolated) in [(39.9, false), (40.0, true), (55.0, true), (12.0, false)] {
        let cells = vec![
            Cell {
                x0_um: 20.0 + spacing,
                v_um_per_frame: 2.0,
                y_um: 0.3,
            },
            Cell {
                x0_um: 20.0,
                v_um_per_frame: 2.0,
                y_um: -0.7,
            },
        ];
        let scene = Scene {
            cells,
            n_frames: 10,
            fov_um: 200.0,
            half_length_um: 4.0,
            jitter_um: 0.0,
            p_miss: 0.0,
        };
        let g = scene.generate(0);
        let tracks = link(&g.dets, 400.0, &TrackerConfig::default());
        assert_eq!(tracks.len(), 2);
        for iso in isolate(&tracks, &g.dets, &IsolationConfig::default()) {
            assert!((iso.gap_um - spacing).abs() < 1e-9, "{iso:?}");
            assert_eq!(iso.isolated, isolated, "spacing {spacing}: {iso:?}");
        }
    }
}

/// A lone cell has gap inf and is isolated; an object touching the border 30 um away makes it
/// not isolated although that object is never tracked; the gap is the minimum over frames.
#[test]
fn border_objects_count_as_neighbours_and_gap_is_minimum_over_frames() {
    let lone: Vec<_> = (0..5).map(|f| det(f, 50.0 + 2.0 * f as f64, 0.0)).collect();
    let tracks = link(&lone, 400.0, &TrackerConfig::default());
    let iso = isolate(&tracks, &lone, &IsolationConfig::default());
    assert_eq!(iso.len(), 1);
    assert!(iso[0].gap_um.is_infinite() && iso[0].isolated);

    let mut dets = lone.clone();
    let mut edge = det(3, 50.0 + 6.0 + 30.0, 0.0);
    edge.touches_border = true;
    dets.push(edge);
    let mut far = det(1, 52.0 + 45.0, 0.0);
    far.touches_border = true;
    dets.push(far);
    let tracks = link(&dets, 400.0, &TrackerConfig::default());
    assert_eq!(tracks.len(), 1, "border objects are not tracked");
    let iso = isolate(&tracks, &dets, &IsolationConfig::default());
    assert!(
        (iso[0].gap_um - 30.0).abs() < 1e-9 && !iso[0].isolated,
        "{iso:?}"
    );
    let gaps = gaps_per_detection(&dets);
    assert!((gaps[1] - 45.0).abs() < 1e-9 && gaps[0].is_infinite());
}

/// Touching cells merged into one object (twice the area) are a cluster, never isolated.
#[test]
fn merged_touching_cells_are_not_isolated() {
    let mut dets = Vec::new();
    for f in 0..6 {
        dets.push(det(f, 10.0 + 3.0 * f as f64, 0.0));
        let mut pair = det(f, 80.0 + 3.0 * f as f64, 0.5);
        pair.area_um2 = 100.0; // two 50 um^2 cells
        dets.push(pair);
        dets.push(det(f, 150.0 + 3.0 * f as f64, 0.0));
    }
    let tracks = link(&dets, 400.0, &TrackerConfig::default());
    assert_eq!(tracks.len(), 3);
    let iso = isolate(&tracks, &dets, &IsolationConfig::default());
    let by_x: Vec<(f64, bool, bool)> = tracks
        .iter()
        .zip(&iso)
        .map(|(t, i)| (dets[t.detections[0]].x_um, i.cluster, i.isolated))
        .collect();
    for (x, cluster, isolated) in by_x {
        assert_eq!(cluster, x == 80.0, "x {x}");
        assert_eq!(
            isolated,
            x != 80.0,
            "x {x}: 70 um gaps, only the pair is excluded"
        );
    }
}

/// The shape rule: concave, asymmetric and notched like two bodies = a cell with something
/// stuck to it; concave but symmetric (croissant), asymmetric but convex (slipper), or
/// asymmetric and concave with only the shallow one-sided notch of a bend (bent slipper) is a
/// single cell; two cells in a row (twice the median length) are a cluster too.
#[test]
fn cluster_flags_follow_the_shape_rule() {
    let mut dets: Vec<_> = (0..8).map(|k| det(0, 20.0 * k as f64, 0.0)).collect();
    dets[1].features.solidity = 0.8; // croissant: concave,
    dets[1].features.mirror_asymmetry = 0.05; // symmetric
    dets[1].features.notch = 0.25;
    dets[2].features.solidity = 0.95; // slipper: convex,
    dets[2].features.mirror_asymmetry = 0.35; // asymmetric
    dets[3].features.solidity = 0.83; // doublet: concave, asymmetric, deep notch
    dets[3].features.mirror_asymmetry = 0.36;
    dets[3].features.notch = 0.42;
    dets[4].length_um = 17.0; // two 8 um cells in a row
    dets[5].features.solidity = 0.87; // bent slipper: concave, asymmetric, shallow one-sided notch
    dets[5].features.mirror_asymmetry = 0.5;
    dets[5].features.notch = 0.28;
    dets[5].features.waist = 0.06;
    dets[6].features.solidity = 0.877; // two round cells side by side: a waist on both sides
    dets[6].features.mirror_asymmetry = 0.25;
    dets[6].features.notch = 0.26;
    dets[6].features.waist = 0.26;
    let cfg = IsolationConfig::default();
    let flags = cluster_flags(&dets, &cfg);
    assert_eq!(flags, vec![false, false, false, true, true, false, true, false]);
    // each condition is needed: the doublet is no cluster when it is convex enough or
    // symmetric, nor with a notch just below the threshold
    for (field, value) in [("solidity", 0.881), ("asymmetry", 0.19), ("notch", 0.32)] {
        let mut d = dets.clone();
        match field {
            "solidity" => d[3].features.solidity = value,
            "asymmetry" => d[3].features.mirror_asymmetry = value,
            _ => d[3].features.notch = value,
        }
        assert!(!cluster_flags(&d, &cfg)[3], "{field} = {value}");
    }
}

fn cfg() -> ClassifierConfig {
    ClassifierConfig::default()
}

/// Frames with the given asymmetries, elongated along x (aspect 1.8, tilted 10 deg) like a slipper.
fn elongated(asym: &[f64]) -> Vec<FrameShape> {
    asym.iter()
        .map(|&a| FrameShape {
            asymmetry: a,
            orientation_rad: 10f64.to_radians(),
            aspect: 1.8,
        })
        .collect()
}

fn classify_features(
    asym: &[f64],
    y_mean_um: f64,
    c: &ClassifierConfig,
) -> rbc_analysis::experiment::classify::Classification {
    classify_frames(&elongated(asym), y_mean_um, c)
}

/// The decision table of the module documentation.
#[test]
fn symmetric_centred_is_croissant_asymmetric_offcentre_is_slipper() {
    let c = cfg();
    let sym = vec![0.02; 9];
    let asym = vec![0.3; 9];
    let k = classify_features(&sym, 0.05, &c);
    assert_eq!(k.shape, Shape::Croissant);
    assert!((k.score - 1.0).abs() < 1e-12, "fully confident: {k:?}");
    let k = classify_features(&asym, -1.2, &c);
    assert_eq!(k.shape, Shape::Slipper);
    assert!((k.score + 1.0).abs() < 1e-12);
    // Cues disagree: other, whatever the sign of the score.
    assert_eq!(classify_features(&sym, 1.3, &c).shape, Shape::Other);
    assert_eq!(classify_features(&asym, 0.0, &c).shape, Shape::Other);
    // Near both thresholds: low confidence, other.
    let k = classify_features(
        &[c.asymmetry_threshold - 0.005; 5],
        c.offset_threshold_um - 0.02,
        &c,
    );
    assert!(
        k.score > 0.0 && k.p_croissant < c.p_croissant_min && k.shape == Shape::Other,
        "{k:?}"
    );
    // No features at all: other with score 0.
    let k = classify_features(&[], 0.0, &c);
    assert_eq!((k.shape, k.score), (Shape::Other, 0.0));
    // Mirror image of a slipper (y -> -y) is still a slipper: only |y| matters.
    assert_eq!(classify_features(&asym, 1.2, &c).shape, Shape::Slipper);
}

/// An asymmetric, off-centre object that is round, or whose long axis lies across the flow,
/// is not a slipper (tumbling or irregular cell): other, with the same score.
#[test]
fn round_or_transverse_asymmetric_objects_are_other() {
    let c = cfg();
    let slipper = classify_frames(&elongated(&[0.3; 6]), 1.2, &c);
    assert_eq!(slipper.shape, Shape::Slipper);
    let round: Vec<FrameShape> = (0..6)
        .map(|_| FrameShape {
            asymmetry: 0.3,
            orientation_rad: 0.1,
            aspect: 1.1,
        })
        .collect();
    let k = classify_frames(&round, 1.2, &c);
    assert_eq!(k.shape, Shape::Other);
    assert_eq!(k.score, slipper.score);
    let across: Vec<FrameShape> = (0..6)
        .map(|_| FrameShape {
            asymmetry: 0.3,
            orientation_rad: 1.2,
            aspect: 1.8,
        })
        .collect();
    assert_eq!(classify_frames(&across, 1.2, &c).shape, Shape::Other);
    // Long axis at -89 deg and +89 deg is the same direction: |angle| is used, no wrap-around.
    let wrap: Vec<FrameShape> = (0..6)
        .map(|i| FrameShape {
            asymmetry: 0.3,
            orientation_rad: if i % 2 == 0 { 1.55 } else { -1.55 },
            aspect: 1.8,
        })
        .collect();
    assert_eq!(classify_frames(&wrap, 1.2, &c).shape, Shape::Other);
    // A croissant needs no elongation.
    let wide: Vec<FrameShape> = (0..6)
        .map(|_| FrameShape {
            asymmetry: 0.02,
            orientation_rad: std::f64::consts::FRAC_PI_2,
            aspect: 1.2,
        })
        .collect();
    assert_eq!(classify_frames(&wide, 0.1, &c).shape, Shape::Croissant);
}

/// The median makes single bad frames harmless; a shape that flips between symmetric and
/// asymmetric (tumbling) has low frame agreement and is other.
#[test]
fn single_bad_frames_do_not_flip_the_label_but_flipping_shapes_are_other() {
    let c = cfg();
    let mut a = vec![0.03; 10];
    a[4] = 0.6;
    a[7] = f64::NAN;
    assert_eq!(classify_features(&a, 0.1, &c).shape, Shape::Croissant);
    let flipping: Vec<f64> = (0..10)
        .map(|i| if i % 2 == 0 { 0.02 } else { 0.3 })
        .collect();
    let k = classify_features(&flipping, 1.0, &c);
    assert_eq!(k.shape, Shape::Other, "{k:?}");
    assert!((k.agreement - 0.5).abs() < 1e-12);
}

/// classify() reads the features and mean y of the track's own detections.
#[test]
fn classify_uses_the_track_detections() {
    let mut dets: Vec<_> = (0..6).map(|f| det(f, 20.0 + f as f64, 1.1)).collect();
    for d in &mut dets {
        d.features.mirror_asymmetry = 0.25;
        d.length_um = 8.0;
        d.width_um = 4.0;
        d.features.orientation_rad = 0.2;
    }
    let t = Track {
        id: 1,
        detections: (0..6).collect(),
    };
    let k = classify(&t, &dets, &cfg());
    assert_eq!(k.shape, Shape::Slipper);
    assert!((k.offset_um - 1.1).abs() < 1e-12 && (k.asymmetry - 0.25).abs() < 1e-12);
}

/// The track's asymmetry, when given (the median mask's, `classify::track_asymmetry`), replaces
/// the median of the frames' in the score; the frames still vote on whether the shape is steady.
#[test]
fn the_track_asymmetry_replaces_the_frames_median() {
    let c = cfg();
    // frames ragged by noise just above the threshold, a symmetric median mask: a croissant
    let ragged = elongated(&[0.118, 0.125, 0.112, 0.13, 0.121]);
    assert_eq!(classify_frames(&ragged, 0.1, &c).shape, Shape::Other);
    let k = classify_frames_with(&ragged, Some(0.05), 0.1, &c);
    assert_eq!(k.shape, Shape::Croissant, "{k:?}");
    assert_eq!(k.asymmetry, 0.05);
    // frames that contradict the track's symmetry (a shape that changes): other all the same
    let changing = elongated(&[0.02, 0.3, 0.35, 0.32, 0.04]);
    assert_eq!(classify_frames_with(&changing, Some(0.05), 0.1, &c).shape, Shape::Other);
    // no finite track asymmetry: the frames' median, as `classify_frames`
    assert_eq!(classify_frames_with(&ragged, Some(f64::NAN), 0.1, &c), classify_frames(&ragged, 0.1, &c));
}
