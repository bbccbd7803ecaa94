//! `rbc-bench frame-stages`: frames per second of `detect_recording` alone and the time per frame of each detection stage (load, median background, segmentation, measurement), single recording, printed.
//!
//! Usage: `rbc-bench frame-stages` (run with `RAYON_NUM_THREADS=2` to match the machine the
//! tables in the analysis README come from). Two synthetic recordings of 400 frames
//! (`rbc_analysis::simulated::synth`: 0.2 um/px at 1 mm/s, 0.3 um/px at 5 mm/s) for the
//! throughput; one of 50 frames at 0.2 um/px for the stages, timed on one thread (the stages run one after another on the
//! calling thread).
//! Moved here from the ignored test `analysis/tests/frames_speed.rs` (speed belongs to the
//! benchmarks, issue 13 item 7); `rbc-bench analyze` times the whole pipeline beside trackpy.

use rbc_analysis::experiment::measure::measure_refined;
use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::experiment::segment::{background, segment, SegmentParams};
use rbc_analysis::simulated::synth::{random_spec, write_recording};
use std::path::Path;
use std::time::Instant;

pub fn run(args: &[String]) -> anyhow::Result<()> {
    if let Some(a) = args.first() {
        anyhow::bail!("rbc-bench frame-stages takes no options, got `{a}`");
    }
    // A scratch folder removed at the end (std only: tempfile is a dev-dependency of this package).
    let tmp = std::env::temp_dir().join(format!("rbc-bench-frame-stages-{}", std::process::id()));
    let result = throughput(&tmp).and_then(|()| stage_times(&tmp.join("stages")));
    let _ = std::fs::remove_dir_all(&tmp);
    result
}

/// Frames per second of `detect_recording` on the current rayon pool.
fn throughput(tmp: &Path) -> anyhow::Result<()> {
    for (k, &(px, v)) in [(0.2, 1.0), (0.3, 5.0)].iter().enumerate() {
        let dir = tmp.join(format!("rec{k}"));
        let mut spec = random_spec(1, px, 0.01, v);
        spec.n_frames = 400;
        write_recording(&dir, &spec, 1)?;
        let rec = Recording::open(&dir)?;
        let t0 = Instant::now();
        let det = detect_recording(&rec)?;
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
    Ok(())
}

/// Per-stage time of one frame (single thread), to see where the time goes.
fn stage_times(dir: &Path) -> anyhow::Result<()> {
    let mut spec = random_spec(1, 0.2, 0.01, 1.0);
    spec.n_frames = 50;
    write_recording(dir, &spec, 1)?;
    let rec = Recording::open(dir)?;
    let t = Instant::now();
    let frames = (0..50).map(|i| rec.load_frame(i)).collect::<Result<Vec<_>, _>>()?;
    println!("load: {:.2} ms/frame", t.elapsed().as_secs_f64() * 1e3 / 50.0);
    let t = Instant::now();
    let bg = background::median_background(&frames[..41]);
    println!("median background of 41: {:.2} ms", t.elapsed().as_secs_f64() * 1e3);
    let p = SegmentParams::default();
    let t = Instant::now();
    let segs: Vec<_> = frames.iter().map(|f| segment(f, &bg, 10..100, 0.2, &p)).collect();
    println!("segment: {:.2} ms/frame", t.elapsed().as_secs_f64() * 1e3 / 50.0);
    let t = Instant::now();
    let mut n = 0;
    for s in &segs {
        for b in &s.blobs {
            std::hint::black_box(measure_refined(b, s));
            n += 1;
        }
    }
    println!("measure: {:.3} ms/frame ({n} blobs)", t.elapsed().as_secs_f64() * 1e3 / 50.0);
    Ok(())
}
