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

/// Conditions where the median y error is still above 0.01 um (measured with 6 recordings each:
/// 0.0108 and 0.0120 um, session 18): a weak bright rim just below focus (-0.5 um), too faint to
/// be read as the rim (its dark halo is peeled back to its darkest ring, `segment::ring`, and read
/// on the ring's ridge, `measure::ridge_weights`: 0.0171 before session 15, 0.0126 before
/// session 18), and the combination of defocus -1.5 um, NA 0.5, 0.35 um/px and 2 % noise. They
/// are held to what was found (accuracy and recall at the bar, y error <= 0.02 um).
const KNOWN_GAPS: [&str; 2] = ["defocus -0.5 um", "defocus -1.5, NA 0.5"];

/// The full grid: every condition of `condition_grid` with 6 recordings of 3 cells, and 24
/// recordings each under its own random conditions. Asserts the bar on every condition a lab
/// meets but the [`KNOWN_GAPS`], which are held to what they reached (the longest exposure, 2.5 um
/// of motion blur at 10 mm/s, meets the bar since session 17: 0.0072 um). The random conditions
/// are held to the bar's croissant/slipper accuracy (0.95) and to a recall of 0.9.
#[test]
#[ignore]
fn condition_grid_full_study() {
    let dir = tempfile::tempdir().unwrap();
    println!("{}", Score::header());
    for (k, (name, c)) in condition_grid().into_iter().enumerate() {
        let s = run_condition(dir.path(), &format!("c{k:02}"), &c, 1..7).unwrap();
        if KNOWN_GAPS.iter().any(|g| name.starts_with(g)) {
            println!("{} (known gap)", s.row(&name));
            assert!(s.accuracy() >= 0.95 && s.recall() >= 0.95 && s.median_y_err_um() <= 0.02, "{name}");
        } else {
            check(&name, &s);
        }
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
