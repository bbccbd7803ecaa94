//! The pipeline on recordings drawn by the wave-optics renderer (`rbc_analysis::simulated::wave`), which shares no image formation with the synthesiser it was tuned on.
//!
//! The same cells, positions, camera and truth as `condition_spec`, imaged as thin
//! phase-and-amplitude objects through the objective's pupil. The whole table (both renderers,
//! every condition of the grid) is `rbc-bench robustness --renderer both` (analysis/README.md).

use rbc_analysis::simulated::robustness::{run_condition_with, Renderer};
use rbc_analysis::simulated::synth::{condition_spec_wave, write_recording, Conditions, Truth};
use rbc_analysis::simulated::wave::WaveOptics;

/// At the nominal conditions (1 um above focus, NA 0.8, 0.2 um/px) the pipeline finds, tracks and
/// classifies every cell of the wave-rendered recordings, with the centroid as accurate as on the
/// synthesiser's own images to within a few nm (measured 9/9 cells, 7/7 croissant/slipper,
/// median y error 0.0033 um against 0.0019 for the synthesiser, 3 recordings).
#[test]
fn wave_rendered_cells_at_nominal_conditions_are_found_and_classified() {
    let dir = tempfile::tempdir().unwrap();
    let s = run_condition_with(dir.path(), "nominal", &Conditions::default(), 1..3, Renderer::Wave).unwrap();
    println!("{}", s.row("nominal (wave)"));
    assert_eq!(s.found, s.truth_cells, "recall");
    assert!(s.truth_cells >= 5);
    assert_eq!((s.false_tracks, s.mixed), (0, 0));
    assert_eq!(s.accuracy(), 1.0, "croissant/slipper");
    assert!(s.median_y_err_um() <= 0.01, "median y error {} um", s.median_y_err_um());
    assert!(s.median_centroid_err_um() <= 0.02, "median centroid error {} um", s.median_centroid_err_um());
}

/// Run `c` on 2 wave-rendered recordings (seeds 1, 2), print the row, and hold it to the bar:
/// every cell found, no false or mixed track, every croissant and slipper right, median y error
/// at most `max_y_um`.
fn wave_condition_holds(name: &str, c: Conditions, max_y_um: f64) {
    wave_condition_holds_over(name, c, 1..3, max_y_um)
}

/// As [`wave_condition_holds`] over the recordings of `seeds`.
fn wave_condition_holds_over(name: &str, c: Conditions, seeds: std::ops::Range<u64>, max_y_um: f64) {
    let dir = tempfile::tempdir().unwrap();
    let s = run_condition_with(dir.path(), "c", &c, seeds, Renderer::Wave).unwrap();
    println!("{}", s.row(&format!("{name} (wave)")));
    assert!(s.truth_cells >= 5, "{name}: {} cells", s.truth_cells);
    assert_eq!(s.found, s.truth_cells, "{name}: recall");
    assert_eq!((s.false_tracks, s.mixed), (0, 0), "{name}: false / mixed tracks");
    assert_eq!(s.accuracy(), 1.0, "{name}: croissant/slipper");
    assert!(s.median_y_err_um() <= max_y_um, "{name}: median y error {} um", s.median_y_err_um());
}

// Away from the nominal focus the y error of the wave rows was 0.02-0.04 um in session 12 (the
// README's table); it was the channel's axis, not the cells: the renderer drew the walls up to
// half a fine sample (0.05 um) off the spec's rows (`wave::tests::the_walls_image_is_mirror_symmetric_about_the_axis`),
// and the pipeline, which reads the axis from the walls, measured every y from there. Measured
// after the fix (seeds 1, 2): median y error 0.0034 (+0.5), 0.0036 (NA 0.6), 0.0052 (focus),
// 0.0064 um (+2); the bar is the 0.01 um.

/// In focus (only absorption and the walls' amplitude step): session 12 0.035 um.
#[test]
fn wave_rendered_cells_in_focus_hold_y_to_10_nm() {
    wave_condition_holds("defocus 0", Conditions { defocus_um: 0.0, ..Conditions::default() }, 0.01);
}

/// Half a micrometre above focus: session 12 0.021 um.
#[test]
fn wave_rendered_cells_half_a_micrometre_above_focus_hold_y_to_10_nm() {
    wave_condition_holds("defocus +0.5", Conditions { defocus_um: 0.5, ..Conditions::default() }, 0.01);
}

/// Two micrometres above focus (wide halo, walls' fringes): session 12 0.039 um.
#[test]
fn wave_rendered_cells_two_micrometres_above_focus_hold_y_to_10_nm() {
    wave_condition_holds("defocus +2", Conditions { defocus_um: 2.0, ..Conditions::default() }, 0.01);
}

/// A dry objective of NA 0.6 (wider edges and wall fringes): session 12 0.034 um.
#[test]
fn wave_rendered_cells_at_na_0_6_hold_y_to_10_nm() {
    wave_condition_holds("NA 0.6", Conditions { na: 0.6, ..Conditions::default() }, 0.01);
}

/// Two micrometres below focus the bright rim is an open arc (the dark interior runs into the dark
/// halo on a croissant's concave side and a slipper's lower edge) and the segmentation found only
/// the arc: session 13 0/9 cells. The halo closes it (`experiment::segment::halo`). Its outline,
/// the halo's darkest ring, was a whole-pixel one refined as if it were the rim's iso-contour
/// (below the bar with the old axis, whose errors partly cancelled it; 0.0106 um with the
/// session-16 axis); read on the ring's ridge to sub-pixel precision (`measure::ridge_weights`):
/// 0.0099 um on seeds 1-2, 0.0090 on the six recordings of seeds 1-6, which the test takes (a
/// median over more cells, not at the bar's edge).
#[test]
fn wave_rendered_cells_two_micrometres_below_focus_hold_y_to_10_nm() {
    wave_condition_holds_over("defocus -2", Conditions { defocus_um: -2.0, ..Conditions::default() }, 1..7, 0.01);
}

/// Half a micrometre below focus the wave optics' bright rim is weak (the dark ring inside the
/// outline rises back by 0.69-0.76 of its depth, not 0.9): until `segment::ring::RECOVERY` was
/// lowered to 0.6 the outline stayed the dark halo's, 0.5-0.8 um outside the cell (0.0086 um on
/// seeds 1-6); peeled to the ring and read on its ridge, 0.0040 um (session 19).
#[test]
fn wave_rendered_cells_half_a_micrometre_below_focus_hold_y_to_10_nm() {
    wave_condition_holds_over("defocus -0.5", Conditions { defocus_um: -0.5, ..Conditions::default() }, 1..7, 0.01);
}

/// The combined row (defocus -1.5 um, NA 0.5, 0.35 um/px, 2 % noise): the same weak rim (rise
/// 0.70-0.81), the halo's outline 0.0173 um on seeds 1-6, peeled and read on the ridge 0.0077.
#[test]
fn wave_rendered_cells_below_focus_at_low_na_and_coarse_pixels_hold_y_to_10_nm() {
    let c = Conditions { defocus_um: -1.5, na: 0.5, um_per_px: 0.35, noise_sigma: 0.02, ..Conditions::default() };
    wave_condition_holds_over("defocus -1.5, NA 0.5, 0.35 um/px, noise 2 %", c, 1..7, 0.01);
}

/// Neighbours 10 um apart (centre to centre): in seed 2 a croissant and a faster slipper 8 um
/// apart along the flow merged into one object for the last 3 of the slipper's 8 frames (session
/// 13: recall 7/9 and a false track), because the 3 x 3 closing bridged the two-pixel bright halo
/// between their rims. The closing no longer reaches into a halo (`experiment::segment`).
#[test]
fn wave_rendered_neighbours_10_um_apart_stay_apart() {
    wave_condition_holds("neighbours 10", Conditions { spacing_um: 10.0, ..Conditions::default() }, 0.01);
}

/// The `[wave]` table is written to spec.toml and read back: a wave recording says how it was drawn.
#[test]
fn a_wave_recording_keeps_its_optics_in_its_spec() {
    let dir = tempfile::tempdir().unwrap();
    let c = Conditions { defocus_um: -1.0, na: 0.6, ..Conditions::default() };
    let spec = condition_spec_wave(4, &c);
    let truth = write_recording(&dir.path().join("rec"), &spec, 4).unwrap();
    let back = Truth::read(&dir.path().join("rec")).unwrap();
    assert_eq!(back.spec, truth.spec);
    let o: WaveOptics = back.spec.wave.expect("a [wave] table");
    assert_eq!((o.defocus_um, o.na, o.condenser_na), (-1.0, 0.6, 0.3));
}

/// One micrometre below focus the bright rim is too weak to vote (+0.02), so the recording
/// votes dark and the object segmented was the dark halo with the interior, 0.5 um outside the
/// cell (session 14: median y error 0.0113 um on seeds 1-3, 0.0081 on seeds 1-2, so all three are
/// held). The recording's profile tells a halo from a rim (`experiment::segment::ring`) and the
/// halo is peeled back to its darkest ring: 0.0089 um.
#[test]
fn wave_rendered_cells_one_micrometre_below_focus_hold_y_to_10_nm() {
    let dir = tempfile::tempdir().unwrap();
    let c = Conditions { defocus_um: -1.0, ..Conditions::default() };
    let s = run_condition_with(dir.path(), "c", &c, 1..4, Renderer::Wave).unwrap();
    println!("{}", s.row("defocus -1 (wave)"));
    assert_eq!(s.truth_cells, 9);
    assert_eq!(s.found, s.truth_cells, "recall");
    assert_eq!((s.false_tracks, s.mixed), (0, 0), "false / mixed tracks");
    assert_eq!(s.accuracy(), 1.0, "croissant/slipper");
    assert!(s.median_y_err_um() <= 0.01, "median y error {} um", s.median_y_err_um());
}

/// 250 us at 10 mm/s: the cells move 2.5 um (12.5 px) during the exposure. The thresholded
/// outline of the blurred image widened the rows of a slipper's wide, dark side more than those
/// of its narrow side and lost its pointed tip, moving y towards that side (session 17, seeds 1-2:
/// median y error 0.0108 um). The pipeline now reads the blur length from the recording and
/// undoes it before measuring y (`experiment::deblur`): measured 0.0079 um.
#[test]
fn wave_rendered_cells_blurred_by_2_5_um_hold_y_to_10_nm() {
    wave_condition_holds("10 mm/s, 250 us", Conditions { velocity_mm_s: 10.0, exposure_s: 250e-6, ..Conditions::default() }, 0.01);
}
