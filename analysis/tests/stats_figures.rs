//! Tests of `plot::experiment::write_figures` on a seeded synthetic experiment: every figure is written as PNG and SVG, at its size, with content.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rbc_analysis::experiment::groups::summarise;
use rbc_analysis::plot::experiment::write_figures;
use rbc_schema::tables::TrackRow;
use std::path::PathBuf;

/// A synthetic experiment shaped like the paper's: 6 pressure drops at 0 and 10 mm; croissants
/// centred, slippers off-centre at +-2.5 um, slipper fraction growing with pressure.
fn synthetic_tracks(seed: u64) -> Vec<TrackRow> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    let mut id = 0;
    for (k, p) in [20.0, 50.0, 100.0, 200.0, 500.0, 1000.0]
        .into_iter()
        .enumerate()
    {
        for pos in [0.0, 10.0] {
            let v_mean = 0.0106 * p;
            let v = Normal::new(v_mean, 0.15 * v_mean).unwrap();
            let p_slipper = 0.1 + 0.15 * k as f64;
            for _ in 0..(40 + 10 * k) {
                id += 1;
                let u: f64 = rng.random();
                let (shape, y): (&str, f64) = if u < p_slipper {
                    let side = if rng.random::<bool>() { 1.0 } else { -1.0 };
                    (
                        "slipper",
                        side * 2.5 + Normal::new(0.0, 0.6).unwrap().sample(&mut rng),
                    )
                } else if u < p_slipper + 0.6 {
                    ("croissant", Normal::new(0.0, 0.5).unwrap().sample(&mut rng))
                } else {
                    ("other", Normal::new(0.0, 1.2).unwrap().sample(&mut rng))
                };
                out.push(TrackRow {
                    recording: format!("p{p}_x{pos}"),
                    pressure_mbar: p,
                    position_mm: pos,
                    track_id: id,
                    n_frames: 30,
                    x_first_um: 0.0,
                    y_mean_um: y.clamp(-5.5, 5.5),
                    y_std_um: 0.1,
                    velocity_mm_s: v.sample(&mut rng).abs(),
                    velocity_se_mm_s: 0.01,
                    isolated: rng.random::<f64>() < 0.85,
                    gap_um: 50.0,
                    shape: shape.into(),
                    shape_score: 0.0,
                    p_croissant: None,
                });
            }
        }
    }
    out
}

#[test]
fn all_figures_written_as_png_and_svg_with_content() {
    let tracks = synthetic_tracks(7);
    let g = summarise(&tracks);
    // keep the figures for inspection when RBC_FIGURE_DIR is set
    let tmp = tempfile::tempdir().unwrap();
    let dir: PathBuf = std::env::var_os("RBC_FIGURE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| tmp.path().to_path_buf());
    let files = write_figures(&dir, &g.summary, &g.kde, &tracks).unwrap();
    let names: Vec<String> = files
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for stem in [
        "fractions_vs_velocity_10mm",
        "fractions_vs_velocity_0mm",
        "y_density_10mm",
        "y_density_0mm",
        "y_density_by_shape_10mm",
        "y_density_by_shape_0mm",
    ] {
        for ext in ["png", "svg"] {
            let name = format!("{stem}.{ext}");
            assert!(names.contains(&name), "{name} missing from {names:?}");
        }
    }
    for f in &files {
        let meta = std::fs::metadata(f).unwrap();
        assert!(
            meta.len() > 1000,
            "{} has {} bytes",
            f.display(),
            meta.len()
        );
        if f.extension().unwrap() == "png" {
            let img = image::open(f).unwrap().to_rgb8();
            let (w, h) = img.dimensions();
            assert!(w >= 700 && h >= 480, "{}: {w}x{h}", f.display());
            let non_white = img
                .pixels()
                .filter(|p| p.0.iter().any(|&c| c < 200))
                .count();
            // axes, text and curves: well over 1 % of the pixels
            assert!(
                non_white > (w * h / 100) as usize,
                "{}: {non_white} non-white pixels",
                f.display()
            );
            // coloured pixels (shape colours) are present, not only gray text
            let coloured = img
                .pixels()
                .filter(|p| p.0.iter().max().unwrap() - p.0.iter().min().unwrap() > 80)
                .count();
            let name = f.file_name().unwrap().to_string_lossy();
            if name.starts_with("fractions") || name.contains("by_shape") {
                assert!(coloured > 50, "{}: {coloured} coloured pixels", f.display());
            }
        } else {
            let text = std::fs::read_to_string(f).unwrap();
            assert!(
                text.contains("<svg") && text.contains("mbar"),
                "{}",
                f.display()
            );
        }
    }
}

#[test]
fn fraction_figure_for_rows_without_interval_columns() {
    // summary read back from a CSV written by another tool: CI columns empty
    let tracks = synthetic_tracks(3);
    let mut g = summarise(&tracks);
    for r in &mut g.summary {
        r.frac_croissant_lo = None;
        r.frac_croissant_hi = None;
    }
    let dir = tempfile::tempdir().unwrap();
    let files = write_figures(dir.path(), &g.summary, &[], &[]).unwrap();
    // no densities: only the fraction figures
    assert_eq!(files.len(), 4, "{files:?}");
}

#[test]
fn empty_summary_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    assert!(write_figures(dir.path(), &[], &[], &[]).unwrap().is_empty());
}

#[test]
fn single_group_uses_a_linear_axis_and_odd_positions_are_named() {
    // one pressure at 2.5 mm: velocities within a decade -> linear velocity axis
    let tracks: Vec<TrackRow> = synthetic_tracks(11)
        .into_iter()
        .filter(|t| t.pressure_mbar == 100.0 && t.position_mm == 10.0)
        .map(|mut t| {
            t.position_mm = 2.5;
            t
        })
        .collect();
    let g = summarise(&tracks);
    assert_eq!(g.summary.len(), 1);
    let tmp = tempfile::tempdir().unwrap();
    let dir: PathBuf = std::env::var_os("RBC_FIGURE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| tmp.path().to_path_buf());
    let files = write_figures(&dir, &g.summary, &g.kde, &tracks).unwrap();
    let names: Vec<String> = files
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 6, "{names:?}");
    assert!(
        names.contains(&"fractions_vs_velocity_2.5mm.png".to_string()),
        "{names:?}"
    );
    let svg = std::fs::read_to_string(dir.join("fractions_vs_velocity_2.5mm.svg")).unwrap();
    // linear axis: plotters' own tick labels and axis title
    assert!(svg.contains("mean cell velocity (mm/s)") && svg.contains("pressure drop (mbar)"));
}
