//! Frame synthesiser: renders recordings of croissants, slippers and irregular cells in bright field, with the truth written beside the frames.
//!
//! [`write_recording`] renders `spec.n_frames` frames of a [`SynthSpec`]
//! (uneven illumination, flicker, static dust, dark wall lines, cells with a
//! dark rim, bright halo and lighter centre, motion blur, Poisson shot noise
//! and Gaussian read noise, 8/16-bit PNG or TIFF) into a recording folder with
//! `recording.toml`, `spec.toml` (the spec itself) and `truth.csv`: one row per
//! frame and cell with the exact centroid of the cell's outline at
//! mid-exposure (`x_um` from the image's left edge, `y_um` from the axis), its
//! area, length and width, and whether the cell lies entirely inside the image.
//!
//! Pixel convention (shared with [`crate::experiment::measure`]): pixel `(col, row)` has
//! its centre at `x_um = (col + 0.5) um_per_px` and `y_um = (row - axis_row_px) um_per_px`.

pub mod conditions;
pub mod examples;
pub mod random;
pub mod render;
pub mod shape;
pub mod spec;

pub use conditions::{condition_grid, condition_spec, condition_spec_wave, microscope_optics, random_conditions, Conditions};
pub use random::{random_cell, random_spec};
pub use shape::CellShape;
pub use spec::{CellSpec, ChannelSpec, DebrisSpec, FrameFormat, IlluminationSpec, NoiseSpec, OpticsSpec, SynthSpec};

pub use crate::simulated::synthetic_recording::{read_spec, write_frame, write_frames_and_truth, Truth, TruthRow, SPEC_FILE, TRUTH_COLUMNS, TRUTH_FILE};

use crate::error::AnalysisError;
use crate::simulated::camera;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use shape::Polygon;
use std::path::Path;

/// Centroid x of cell `c` at time `t`, um: `x0 + v t` (v in mm/s = 1000 um/s).
fn x_at(c: &CellSpec, t: f64) -> f64 {
    c.x0_um + c.velocity_mm_s * 1000.0 * t
}

/// The truth rows of `spec` (no rendering).
pub fn truth_rows(spec: &SynthSpec) -> Vec<TruthRow> {
    let polys: Vec<Polygon> = spec.cells.iter().map(CellSpec::outline).collect();
    let um = spec.um_per_px;
    let (wu, hu) = (spec.width_px as f64 * um, spec.height_px as f64 * um);
    let mut rows = Vec::new();
    for k in 0..spec.n_frames {
        let t = k as f64 / spec.fps;
        for (id, (c, p)) in spec.cells.iter().zip(&polys).enumerate() {
            let x = x_at(c, t);
            let bb = p.bbox();
            let blur = camera::half_blur_um(c.velocity_mm_s, spec.optics.exposure_s);
            let y_img = spec.channel.axis_row_px * um + c.y_um + 0.5 * um; // um from the image's top edge
            let visible = x + bb[0] - blur >= 0.5 && x + bb[1] + blur <= wu - 0.5 && y_img + bb[2] >= 0.5 && y_img + bb[3] <= hu - 0.5;
            let (l, w) = p.extents();
            rows.push(TruthRow {
                frame: k as u64,
                cell_id: id as u64,
                t_s: t,
                x_um: x,
                y_um: c.y_um,
                shape: c.shape.as_str().to_string(),
                velocity_mm_s: c.velocity_mm_s,
                visible,
                area_um2: p.area(),
                length_um: l,
                width_um: w,
            });
        }
    }
    rows
}

/// Render frame `k` of `spec` as raw counts (0..=255 or 0..=65535), row-major.
pub fn render_frame(spec: &SynthSpec, polys: &[Polygon], background: &[f64], seed: u64, k: usize) -> Vec<u16> {
    let (w, h, um) = (spec.width_px, spec.height_px, spec.um_per_px);
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(k as u64 + 1));
    let t = k as f64 / spec.fps;
    let mut contrast = vec![0.0; w * h];
    for (c, p) in spec.cells.iter().zip(polys) {
        let xs_um = camera::exposure_positions(x_at(c, t), c.velocity_mm_s, spec.optics.exposure_s, um);
        let cell = render::CellInFrame { poly: p, xs_um, y_um: spec.channel.axis_row_px * um + c.y_um };
        render::add_cell(&mut contrast, w, h, um, &spec.optics, &cell);
    }
    for d in &spec.debris {
        let xs_um = camera::exposure_positions(d.x0_um + d.velocity_mm_s * 1000.0 * t, d.velocity_mm_s, spec.optics.exposure_s, um);
        render::add_debris(&mut contrast, w, h, um, &xs_um, spec.channel.axis_row_px * um + d.y_um, d.radius_um, d.contrast);
    }
    let gain = camera::flicker_gain(spec, &mut rng);
    let intensity: Vec<f64> = background.iter().zip(&contrast).map(|(b, c)| b * gain * (1.0 + c)).collect();
    camera::expose(&intensity, spec, &mut rng)
}

/// Render `spec` with noise seed `seed` into the recording folder `dir` (with the wave-optics
/// renderer when the spec has a `[wave]` table, [`crate::simulated::wave`])
/// (created if needed; refused if it already holds frames): frames
/// `frame_00000.<ext>`..., `recording.toml`, `spec.toml`, `truth.csv`.
pub fn write_recording(dir: &Path, spec: &SynthSpec, seed: u64) -> Result<Truth, AnalysisError> {
    spec.validate(&dir.join(SPEC_FILE))?;
    let rows = truth_rows(spec);
    if let Some(o) = &spec.wave {
        let scene = crate::simulated::wave::scene(spec, o, seed);
        write_frames_and_truth(dir, spec, &rows, |k| crate::simulated::wave::render_frame(spec, &scene, seed, k))
    } else {
        let polys: Vec<Polygon> = spec.cells.iter().map(CellSpec::outline).collect();
        let background = render::static_background(spec, seed);
        write_frames_and_truth(dir, spec, &rows, |k| render_frame(spec, &polys, &background, seed, k))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_round_trips_through_toml_and_bad_fields_are_named() {
        let spec = random_spec(4, 0.2, 0.01, 1.0);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.toml");
        std::fs::write(&p, toml::to_string(&spec).unwrap()).unwrap();
        assert_eq!(read_spec(&p).unwrap(), spec);
        let text = toml::to_string(&spec).unwrap().replacen("um_per_px = 0.2", "um_per_px = 0.0", 1);
        std::fs::write(&p, text).unwrap();
        let e = read_spec(&p).unwrap_err().to_string();
        assert!(e.contains("s.toml") && e.contains("um_per_px") && !e.contains('\n'), "{e}");
        let text = toml::to_string(&spec).unwrap().replacen("fps = 400.0", "fps = 400.0\nfsp = 1", 1);
        std::fs::write(&p, text).unwrap();
        let e = read_spec(&p).unwrap_err().to_string();
        assert!(e.contains("fsp"), "{e}");
    }

    #[test]
    fn truth_moves_at_the_cell_velocity_and_marks_visibility() {
        let spec = random_spec(9, 0.25, 0.01, 4.0);
        let rows = truth_rows(&spec);
        assert_eq!(rows.len(), spec.n_frames * spec.cells.len());
        for r in &rows {
            let c = &spec.cells[r.cell_id as usize];
            // x = x0 + v t, v in mm/s = 1000 um/s
            assert!((r.x_um - (c.x0_um + c.velocity_mm_s * 1000.0 * r.frame as f64 / spec.fps)).abs() < 1e-9);
            let w_um = spec.width_px as f64 * spec.um_per_px;
            if r.visible {
                assert!(r.x_um > 0.0 && r.x_um < w_um);
            }
        }
        assert!(rows.iter().any(|r| r.visible));
    }
}
