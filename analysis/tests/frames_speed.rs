//! Throughput of `detect_recording` (printed, never asserted: speed belongs to benchmarks).
//!
//! `RAYON_NUM_THREADS=2 cargo test -p rbc-analysis --test frames_speed -- --ignored --nocapture`

use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::simulated::synth::{random_spec, write_recording};

#[test]
#[ignore]
fn detect_throughput() {
    for &(px, v) in &[(0.2, 1.0), (0.3, 5.0)] {
        let dir = tempfile::tempdir().unwrap();
        let mut spec = random_spec(1, px, 0.01, v);
        spec.n_frames = 400;
        write_recording(dir.path(), &spec, 1).unwrap();
        let rec = Recording::open(dir.path()).unwrap();
        let t0 = std::time::Instant::now();
        let det = detect_recording(&rec).unwrap();
        let dt = t0.elapsed().as_secs_f64();
        println!(
            "{} x {} px, {} frames: {:.3} s, {:.0} frames/s ({} threads), {} detections",
            rec.width,
            rec.height,
            rec.n_frames(),
            dt,
            rec.n_frames() as f64 / dt,
            rayon::current_num_threads(),
            det.detections.len()
        );
    }
}

/// Per-stage time of one frame (single thread), to see where the time goes.
#[test]
#[ignore]
fn stage_times() {
    use rbc_analysis::experiment::measure::measure_refined;
    use rbc_analysis::experiment::segment::{background, segment, SegmentParams};
    let dir = tempfile::tempdir().unwrap();
    let mut spec = random_spec(1, 0.2, 0.01, 1.0);
    spec.n_frames = 50;
    write_recording(dir.path(), &spec, 1).unwrap();
    let rec = Recording::open(dir.path()).unwrap();
    let t = std::time::Instant::now();
    let frames: Vec<_> = (0..50).map(|i| rec.load_frame(i).unwrap()).collect();
    println!("load: {:.2} ms/frame", t.elapsed().as_secs_f64() * 1e3 / 50.0);
    let t = std::time::Instant::now();
    let bg = background::median_background(&frames[..41]);
    println!("median background of 41: {:.2} ms", t.elapsed().as_secs_f64() * 1e3);
    let p = SegmentParams::default();
    let t = std::time::Instant::now();
    let segs: Vec<_> = frames.iter().map(|f| segment(f, &bg, 10..100, 0.2, &p)).collect();
    println!("segment: {:.2} ms/frame", t.elapsed().as_secs_f64() * 1e3 / 50.0);
    let t = std::time::Instant::now();
    let mut n = 0;
    for s in &segs {
        for b in &s.blobs {
            std::hint::black_box(measure_refined(b, s));
            n += 1;
        }
    }
    println!("measure: {:.3} ms/frame ({n} blobs)", t.elapsed().as_secs_f64() * 1e3 / 50.0);
}
