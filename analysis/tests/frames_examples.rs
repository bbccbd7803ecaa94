//! The shipped `examples/frames/` are what the synthesiser makes today, and the pipeline finds their cells.
//!
//! Regenerate after changing the synthesiser: `cargo run --bin rbc-synth -- --examples examples/frames`.

use rbc_analysis::experiment::recording::{detect_recording, discover, Recording};
use rbc_analysis::simulated::synth::{examples::examples, truth_rows, Truth};
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
