//! The shape descriptors separate the synthesiser's croissants (mirror-symmetric about their centre line) from slippers (tilted, asymmetric).

mod frames_common;

use frames_common::{matches, quantile};
use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::simulated::synth::{random_spec, write_recording};

#[test]
fn mirror_asymmetry_separates_croissants_from_slippers() {
    let (mut cro, mut sli) = (Vec::new(), Vec::new());
    let (mut cro_o, mut sli_o) = (Vec::new(), Vec::new());
    for seed in 0..12u64 {
        let px = 0.15 + 0.02 * seed as f64;
        let dir = tempfile::tempdir().unwrap();
        let spec = random_spec(300 + seed, px, 0.01, 3.0);
        let truth = write_recording(dir.path(), &spec, seed).unwrap();
        let det = detect_recording(&Recording::open(dir.path()).unwrap()).unwrap();
        for (t, d) in matches(&truth, &det, 2.0) {
            match t.shape.as_str() {
                "croissant" => {
                    cro.push(d.features.mirror_asymmetry);
                    cro_o.push(d.features.skew_y.abs());
                }
                "slipper" => {
                    sli.push(d.features.mirror_asymmetry);
                    sli_o.push(d.features.skew_y.abs());
                }
                _ => {}
            }
        }
    }
    println!("mirror asymmetry: croissants n {} median {:.3} p90 {:.3}; slippers n {} p10 {:.3} median {:.3}", cro.len(), quantile(&cro, 0.5), quantile(&cro, 0.9), sli.len(), quantile(&sli, 0.1), quantile(&sli, 0.5));
    println!("|skew_y|: croissants median {:.3}; slippers median {:.3}", quantile(&cro_o, 0.5), quantile(&sli_o, 0.5));
    assert!(cro.len() >= 10 && sli.len() >= 10);
    // a croissant's mask equals its mirror image up to pixel noise on the outline
    assert!(quantile(&cro, 0.9) < 0.1);
    assert!(quantile(&cro, 0.9) < quantile(&sli, 0.1), "the two classes overlap");
}

/// Issue 15, random conditions, seed 0 (`rbc-bench robustness --seeds 0 --random 24`): near focus
/// (defocus -0.12 um, NA 0.52, 0.228 um/px, 1.8 % read noise) the synthesiser's rim contrast
/// vanishes and the interior's absorption is only 2.6 x the noise, so the two croissants'
/// outlines are ragged frame by frame: the median of their frames' mirror asymmetries is above the
/// classifier's 0.11 (measured 0.118 and 0.127), and classified on it they were `other`. Their
/// median mask (`experiment::median_mask`: the frames' masks aligned at their centroids, the
/// per-pixel median) is symmetric (0.057 and 0.055), and `classify` calls them croissants; the
/// slipper of the recording stays a slipper with its asymmetry (0.388 per frame, 0.358).
#[test]
fn noisy_croissants_near_focus_are_judged_on_their_median_mask() {
    use rbc_analysis::experiment::classify::{classify, classify_frames, track_asymmetry, ClassifierConfig, FrameShape, Shape};
    use rbc_analysis::experiment::track::{link, TrackerConfig};
    use rbc_analysis::stats::median::upper_median;
    use rbc_analysis::simulated::synth::{condition_spec, random_conditions};

    let dir = tempfile::tempdir().unwrap();
    let c = random_conditions(0);
    assert!(c.defocus_um.abs() < 0.2 && c.noise_sigma > 0.015, "the conditions of the case: {c:?}");
    let truth = write_recording(dir.path(), &condition_spec(0, &c), 0).unwrap();
    let rec = Recording::open(dir.path()).unwrap();
    let det = detect_recording(&rec).unwrap();
    let dets = &det.detections;
    let cfg = ClassifierConfig::default();
    let (mut croissants, mut slippers) = (0, 0);
    for t in link(dets, rec.config.fps, &TrackerConfig::default()) {
        // the truth cell of the track: the nearest truth centroid of every detection's frame
        let cells: Vec<(u64, &str)> = t
            .detections
            .iter()
            .filter_map(|&i| {
                let d = &dets[i];
                truth
                    .rows
                    .iter()
                    .filter(|r| r.frame == d.frame as u64 && ((r.x_um - d.x_um).powi(2) + (r.y_um - d.y_um).powi(2)).sqrt() <= 1.0)
                    .map(|r| (r.cell_id, r.shape.as_str()))
                    .next()
            })
            .collect();
        if cells.len() < 3 || cells.iter().any(|c| c.0 != cells[0].0) {
            continue;
        }
        let per_frame = upper_median(&mut t.detections.iter().map(|&i| dets[i].features.mirror_asymmetry).collect::<Vec<_>>()).unwrap_or(f64::NAN);
        let whole = track_asymmetry(&t, dets).expect("segmented detections carry their masks");
        let frames: Vec<FrameShape> = t.detections.iter().map(|&i| FrameShape::of(&dets[i])).collect();
        let y_mean = t.detections.iter().map(|&i| dets[i].y_um).sum::<f64>() / t.detections.len() as f64;
        let on_frames = classify_frames(&frames, y_mean, &cfg);
        let k = classify(&t, dets, &cfg);
        println!("{}: per-frame median asymmetry {per_frame:.3}, median mask {whole:.3}; label {} (on the frames' median: {})", cells[0].1, k.shape, on_frames.shape);
        match cells[0].1 {
            "croissant" => {
                croissants += 1;
                assert!(per_frame > cfg.asymmetry_threshold, "the case: a croissant ragged by noise, {per_frame}");
                assert_eq!(on_frames.shape, Shape::Other, "judged on its frames it was unsure");
                assert!(whole < 0.08, "median mask {whole}");
                assert_eq!(k.shape, Shape::Croissant, "{k:?}");
            }
            "slipper" => {
                slippers += 1;
                assert!(whole > 0.25, "a slipper keeps its asymmetry: {whole}");
                assert_eq!(k.shape, Shape::Slipper, "{k:?}");
            }
            _ => {}
        }
    }
    assert_eq!((croissants, slippers), (2, 1), "tracked cells of the recording");
}
