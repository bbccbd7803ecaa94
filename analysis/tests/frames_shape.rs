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
