//! Segmentation of real bright-field frames (RT-DC blood sample, dclab test data) against the instrument's masks.
//!
//! The 18 events share one camera region of interest, so the per-pixel median
//! over the events is the empty channel (a per-recording background, as for a
//! video). For each event the object of our segmentation that overlaps the
//! instrument's mask most is compared with it by intersection over union.

use rbc_analysis::channel::detect_walls;
use rbc_analysis::segment::{background::median_background, segment, SegmentParams};
use rbc_analysis::types::Frame;
use rbc_schema::rtdc::read_events;
use std::path::Path;

const FILE: &str = "/work/shared/data/real/rtdc-blood/blood_rbc_leukocytes.rtdc";

#[test]
fn segmentation_matches_instrument_masks() {
    let path = Path::new(FILE);
    if !path.exists() {
        eprintln!("skipped: {FILE} not present on this machine");
        return;
    }
    let ev = read_events(path).unwrap();
    assert_eq!(ev.images.len(), 18);
    let frames: Vec<Frame> = ev
        .images
        .iter()
        .map(|im| Frame { width: ev.width, height: ev.height, data: im.iter().map(|&v| v as f32 / 255.0).collect() })
        .collect();
    let bg = median_background(&frames);
    // channel: 20 um wide (`setup:channel width`)
    let walls = detect_walls(&bg, Some(20.0 / ev.pixel_size_um));
    println!("walls: {walls:?} (rows)");
    let rows = match walls {
        Some([a, b]) => (a.ceil() as usize)..(b.floor() as usize + 1),
        None => 0..ev.height,
    };
    let mut worst: f64 = 1.0;
    for (i, (f, mask)) in frames.iter().zip(&ev.masks).enumerate() {
        let seg = segment(f, &bg, rows.clone(), ev.pixel_size_um, &SegmentParams::default());
        let n_mask = mask.iter().filter(|&&m| m).count();
        let best = seg
            .blobs
            .iter()
            .map(|b| {
                let inter = b.pixels.iter().filter(|&&p| mask[p as usize]).count();
                (inter, b)
            })
            .max_by_key(|(inter, _)| *inter);
        let (iou, n_ours) = match best {
            Some((inter, b)) => (inter as f64 / (n_mask + b.pixels.len() - inter) as f64, b.pixels.len()),
            None => (0.0, 0),
        };
        println!("event {i:2}: IoU {iou:.3}  (instrument {n_mask} px, ours {n_ours} px, {} objects in frame)", seg.blobs.len());
        worst = worst.min(iou);
    }
    println!("worst IoU {worst:.3}");
    assert!(worst >= 0.8, "IoU below 0.8");
}
