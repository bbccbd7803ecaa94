//! Calibration data of the shape classifier: per-track features against the synthesiser's truth shape.
//!
//! Not a check (prints a table): `cargo test -p rbc-analysis --test tracks_calibrate -- --ignored --nocapture > features.csv`.
//! The thresholds in `classify.rs` were read off this table (see its documentation).

use rbc_analysis::experiment::isolate::median;
use rbc_analysis::experiment::pipeline::{analyse_detections, StageConfig};
use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::simulated::synth::{random_spec, write_recording};
use rbc_analysis::experiment::track::link;

#[test]
#[ignore]
fn dump_features_per_truth_shape() {
    println!("truth,predicted,score,asym,abs_y,skew_y,orientation_deg,solidity,aspect,px,noise,v");
    let mut seed = 90_000;
    for px in [0.15, 0.25, 0.35] {
        for noise in [0.005, 0.02] {
            for v in [0.1, 1.0, 3.0, 12.0] {
                for _ in 0..4 {
                    seed += 1;
                    let dir = tempfile::tempdir().unwrap();
                    let spec = random_spec(seed, px, noise, v);
                    let truth = write_recording(dir.path(), &spec, seed).unwrap();
                    let rec = Recording::open(dir.path()).unwrap();
                    let det = detect_recording(&rec).unwrap();
                    let stages = StageConfig::default();
                    let tables = analyse_detections("r", &rec.config, &det.detections, &stages);
                    let tracks = link(&det.detections, rec.config.fps, &stages.tracker);
                    for (t, row) in tracks.iter().zip(&tables.tracks) {
                        let d0 = &det.detections[t.detections[0]];
                        let Some(tr) = truth
                            .rows
                            .iter()
                            .filter(|r| r.frame as usize == d0.frame)
                            .min_by(|a, b| {
                                (a.x_um - d0.x_um)
                                    .abs()
                                    .total_cmp(&(b.x_um - d0.x_um).abs())
                            })
                        else {
                            continue;
                        };
                        let f = |g: &dyn Fn(&rbc_analysis::types::Detection) -> f64| {
                            let mut v: Vec<f64> = t
                                .detections
                                .iter()
                                .map(|&i| g(&det.detections[i]))
                                .collect();
                            median(&mut v).unwrap()
                        };
                        println!(
                            "{},{},{:.3},{:.4},{:.3},{:.3},{:.1},{:.3},{:.3},{px},{noise},{v}",
                            tr.shape,
                            row.shape,
                            row.shape_score,
                            f(&|d| d.features.mirror_asymmetry),
                            row.y_mean_um.abs(),
                            f(&|d| d.features.skew_y),
                            f(&|d| d.features.orientation_rad.to_degrees()),
                            f(&|d| d.features.solidity),
                            f(&|d| d.length_um / d.width_um),
                        );
                    }
                }
            }
        }
    }
}
