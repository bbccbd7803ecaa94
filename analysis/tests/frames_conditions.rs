//! The pipeline under imaging conditions it was not tuned on (`rbc_analysis::simulated::synth::conditions`), against the synthesiser's truth.
//!
//! Below focus a red cell's rim is bright inside a dark halo: the segmentation reads the
//! polarity from each recording (`experiment::segment::polarity`) and the outline, centroid and
//! shape come out as above focus. The default tests run a few conditions with 2-3 recordings
//! of 3 cells each; the whole grid (one condition varied at a time, 6 recordings each, plus 24
//! recordings under random conditions) is
//! `cargo nextest run -p rbc-analysis --run-ignored only -E 'test(condition_grid_full_study)' --no-capture`
//! (or `rbc-bench robustness`).

use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::experiment::segment::polarity::Polarity;
use rbc_analysis::simulated::robustness::{run_condition, Score};
use rbc_analysis::simulated::synth::{condition_grid, condition_spec, random_conditions, write_recording, Conditions};

/// The bar of issue 15 for a condition a lab meets.
fn check(name: &str, s: &Score) {
    println!("{}", s.row(name));
    assert!(s.recall() >= 0.95, "{name}: recall {}", s.recall());
    assert_eq!(s.mixed, 0, "{name}: mixed tracks");
    assert_eq!(s.false_tracks, 0, "{name}: false tracks");
    assert!(s.accuracy() >= 0.95, "{name}: croissant/slipper accuracy {}", s.accuracy());
    assert!(s.median_y_err_um() <= 0.01, "{name}: median y error {} um", s.median_y_err_um());
}

#[test]
fn polarity_follows_the_sign_of_the_defocus() {
    let dir = tempfile::tempdir().unwrap();
    for (k, dz) in [-2.0, -1.0, 1.0, 2.0, 0.0].into_iter().enumerate() {
        let c = Conditions { defocus_um: dz, um_per_px: 0.3, ..Conditions::default() };
        let rec_dir = dir.path().join(format!("dz{k}"));
        write_recording(&rec_dir, &condition_spec(11 + k as u64, &c), 5).unwrap();
        let rec = Recording::open(&rec_dir).unwrap();
        let found = detect_recording(&rec).unwrap();
        // in focus only the interior's absorption is left: dark, like above focus
        let want = if dz < 0.0 { Polarity::Bright } else { Polarity::Dark };
        assert_eq!(found.polarity, want, "defocus {dz} um");
    }
}

#[test]
fn inverted_rim_below_focus_meets_the_bar() {
    let dir = tempfile::tempdir().unwrap();
    for (k, dz) in [-2.0, -1.0].into_iter().enumerate() {
        let c = Conditions { defocus_um: dz, ..Conditions::default() };
        let s = run_condition(dir.path(), &format!("below{k}"), &c, 1..4).unwrap();
        check(&format!("defocus {dz} um"), &s);
    }
}

#[test]
fn low_na_coarse_pixels_and_close_neighbours_meet_the_bar() {
    let dir = tempfile::tempdir().unwrap();
    let n = Conditions::default();
    for (name, c) in [
        ("NA 0.5, defocus -1.5 um", Conditions { na: 0.5, defocus_um: -1.5, ..n }),
        ("0.35 um/px, noise 2 %", Conditions { um_per_px: 0.35, noise_sigma: 0.02, ..n }),
        ("neighbours 15 um", Conditions { spacing_um: 15.0, ..n }),
    ] {
        let s = run_condition(dir.path(), &name.replace([' ', ',', '.', '%'], "_"), &c, 1..3).unwrap();
        check(name, &s);
    }
}

/// The two conditions whose median y error stayed above the bar until the track's frames were
/// registered on the track's own image (`experiment::register`, session 26): a weak bright rim
/// just below focus (-0.5 um) and defocus -1.5 um with NA 0.5, 0.35 um/px and 2 % noise, where
/// pixel noise moves each frame's outline (measured, 6 recordings each: 0.0108 and 0.0120 um with
/// each frame's centroid, 0.0082 and 0.0093 registered). Both renderers, the same cells; the
/// centroids alone must still miss the bar on the synthesiser's rows (what the registration
/// fixes), and the registration must not move the track means.
#[test]
fn frames_registered_on_their_track_hold_y_below_focus_and_at_coarse_noisy_pixels() {
    use rbc_analysis::experiment::pipeline::StageConfig;
    use rbc_analysis::simulated::robustness::{score_recording_with, Renderer};
    use rbc_analysis::simulated::synth::condition_spec_wave;
    let dir = tempfile::tempdir().unwrap();
    let grid = condition_grid();
    let centroids = StageConfig { register_frames: false, ..StageConfig::default() };
    for name in ["defocus -0.5 um", "defocus -1.5, NA 0.5, 0.35 um/px, noise 2 %"] {
        let c = &grid.iter().find(|(n, _)| n == name).expect("a grid row").1;
        for renderer in [Renderer::Synth, Renderer::Wave] {
            let (mut registered, mut alone) = (Score::default(), Score::default());
            for seed in 1..7 {
                let rec = dir.path().join(format!("{}_{}_{seed}", name.replace([' ', ',', '.', '%'], "_"), renderer.as_str()));
                let spec = match renderer {
                    Renderer::Synth => condition_spec(seed, c),
                    Renderer::Wave => condition_spec_wave(seed, c),
                };
                write_recording(&rec, &spec, seed).unwrap();
                registered.merge(score_recording_with(&rec, dir.path(), &StageConfig::default()).unwrap());
                alone.merge(score_recording_with(&rec, dir.path(), &centroids).unwrap());
            }
            let label = format!("{name} ({})", renderer.as_str());
            println!("{} centroids alone: median y error {:.4} um", registered.row(&label), alone.median_y_err_um());
            check(&label, &registered);
            assert_eq!(registered.shapes, alone.shapes, "{label}: the labels do not depend on the registration");
            if renderer == Renderer::Synth {
                assert!(alone.median_y_err_um() > 0.0105, "{label}: the centroids alone {} um", alone.median_y_err_um());
            }
        }
    }
}

/// The full grid: every condition of `condition_grid` with 6 recordings of 3 cells, and 24
/// recordings each under its own random conditions. Asserts the bar on every condition a lab
/// meets (the last two below 0.01 um in y since session 26: -0.5 um and the combined row, 0.0082
/// and 0.0093 um; the longest exposure, 2.5 um of motion blur at 10 mm/s, since session 17). The random conditions
/// are held to the bar's croissant/slipper accuracy (0.95) and to a recall of 0.9.
#[test]
#[ignore]
fn condition_grid_full_study() {
    let dir = tempfile::tempdir().unwrap();
    println!("{}", Score::header());
    for (k, (name, c)) in condition_grid().into_iter().enumerate() {
        let s = run_condition(dir.path(), &format!("c{k:02}"), &c, 1..7).unwrap();
        check(&name, &s);
    }
    let mut r = Score::default();
    for seed in 0..24 {
        r.merge(run_condition(dir.path(), &format!("random{seed:02}"), &random_conditions(seed), seed..seed + 1).unwrap());
    }
    println!("{}", r.row("random conditions (24 recordings)"));
    // croissant/slipper 50/52 since the symmetry is judged on the track's median mask (48/52
    // before: two near-focus croissants ragged by noise); the two misses left carry debris, and
    // the recall (67/72) loses the cells of two recordings just below focus at a low NA
    // (`analysis/README.md`, "What still fails")
    assert!(r.accuracy() >= 0.95, "random conditions: croissant/slipper accuracy {}", r.accuracy());
    assert!(r.recall() >= 0.9, "random conditions: recall {}", r.recall());
}
