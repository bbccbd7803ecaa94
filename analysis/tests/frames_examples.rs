//! The shipped `examples/frames/` are what the synthesiser makes today, and the pipeline finds their cells.
//!
//! Regenerate after changing the synthesiser: `cargo run --bin rbc-synth -- --examples examples/frames`.

use rbc_analysis::experiment::recording::{detect_recording, discover, Recording};
use rbc_analysis::simulated::synth::{examples::examples, truth_rows, write_recording, Truth};
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/frames")
}

#[test]
fn shipped_examples_match_the_generator_and_are_found() {
    let found = discover(&root()).unwrap();
    assert_eq!(found.len(), examples().len());
    for ex in examples() {
        let dir = root().join(&ex.name);
        let truth = Truth::read(&dir).unwrap();
        assert_eq!(truth.spec, ex.spec, "{}: spec.toml differs from the generator; regenerate", ex.name);
        assert_eq!(truth.rows, truth_rows(&ex.spec), "{}: truth.csv differs from the generator; regenerate", ex.name);
        let rec = Recording::open_under(&root(), &dir).unwrap();
        assert_eq!(rec.name, ex.name);
        assert_eq!(rec.n_frames(), ex.spec.n_frames);
        let det = detect_recording(&rec).unwrap();
        let mut errs = Vec::new();
        for t in truth.rows.iter().filter(|t| t.visible) {
            let e = det
                .detections
                .iter()
                .filter(|d| d.frame as u64 == t.frame && !d.touches_border)
                .map(|d| ((d.x_um - t.x_um).powi(2) + (d.y_um - t.y_um).powi(2)).sqrt())
                .fold(f64::MAX, f64::min);
            assert!(e < 0.2, "{}: frame {} cell {} not found (nearest {e} um)", ex.name, t.frame, t.cell_id);
            errs.push(e);
        }
        errs.sort_by(|a, b| a.total_cmp(b));
        let n_vis_cells = truth.rows.iter().filter(|t| t.visible).map(|t| t.cell_id).collect::<std::collections::BTreeSet<_>>().len();
        println!("{}: {} visible cell-frames ({} cells), median error {:.4} um", ex.name, errs.len(), n_vis_cells, errs[errs.len() / 2]);
        assert!(n_vis_cells >= 4, "every recording shows at least 4 whole cells");
        assert!(errs[errs.len() / 2] <= 0.05);
    }
}

/// Every shipped frame and `recording.toml` is what the synthesiser renders now. Frames are
/// compared by their pixels (not their PNG bytes, which depend on the encoder): at most one
/// count apart in at most 0.1 % of the pixels, room for a last-bit difference of `exp`/`sin` on
/// another machine flipping a rounding; anything the renderer or the example specs change moves
/// cells or noise by many counts over many pixels.
#[test]
fn shipped_frames_are_what_the_synthesiser_renders() {
    let fresh = tempfile::tempdir().unwrap();
    let regenerate = "regenerate with `cargo run --bin rbc-synth -- --examples examples/frames`";
    for ex in examples() {
        let shipped = root().join(&ex.name);
        let made = fresh.path().join(&ex.name);
        write_recording(&made, &ex.spec, ex.seed).unwrap();
        assert_eq!(
            std::fs::read_to_string(shipped.join("recording.toml")).unwrap(),
            std::fs::read_to_string(made.join("recording.toml")).unwrap(),
            "{}/recording.toml is stale: {regenerate}",
            ex.name
        );
        for k in 0..ex.spec.n_frames {
            let name = format!("frame_{k:05}.{}", ex.spec.format.extension());
            let a = image::open(shipped.join(&name)).unwrap_or_else(|e| panic!("{}/{name}: {e}: {regenerate}", ex.name)).into_luma16();
            let b = image::open(made.join(&name)).unwrap().into_luma16();
            assert_eq!(a.dimensions(), b.dimensions(), "{}/{name} has another size: {regenerate}", ex.name);
            // 8-bit counts are scaled by 257 in 16 bits
            let step = if ex.spec.format.sixteen_bit() { 1 } else { 257 };
            let diffs: Vec<u32> = a.pixels().zip(b.pixels()).map(|(p, q)| (p.0[0] as i32 - q.0[0] as i32).unsigned_abs() / step).filter(|&d| d > 0).collect();
            let worst = diffs.iter().copied().max().unwrap_or(0);
            assert!(
                worst <= 1 && diffs.len() * 1000 <= a.len(),
                "{}/{name} is stale ({} pixels differ, by up to {worst} counts): {regenerate}",
                ex.name,
                diffs.len()
            );
        }
    }
}
