//! Frame synthesiser: renders recordings of croissants, slippers and irregular cells in bright field, with the truth written beside the frames.
//!
//! [`write_recording`] renders `spec.n_frames` frames of a [`SynthSpec`]
//! (uneven illumination, flicker, static dust, dark wall lines, cells with a
//! dark rim, bright halo and lighter centre, motion blur, Poisson shot noise
//! and Gaussian read noise, 8/16-bit PNG or TIFF) into a recording folder with
//! `recording.toml`, `spec.toml` (the spec itself) and `truth.csv`: one row per
//! frame and cell with the exact centroid of the cell's outline at
//! mid-exposure (`x_um` from the image's left edge, `y_um` from the axis), its
//! area, length and width, whether the cell lies entirely inside the image, and whether a
//! debris particle lies on it (`debris_on_cell`).
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

pub use crate::simulated::synthetic_recording::{debris_on_cell, read_spec, write_frame, write_frames_and_truth, Truth, TruthRow, DEBRIS_ON_CELL_RADII, SPEC_FILE, TRUTH_COLUMNS, TRUTH_FILE, TRUTH_REQUIRED};

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
                debris_on_cell: debris_on_cell(spec, t, |dx, dy| p.signed_distance(dx - x, dy - c.y_um)),
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
        let xs_um = camera::exposure_positions(d.x_um_at(t), d.velocity_mm_s, spec.optics.exposure_s, um);
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
        // each field named for itself; an exposure longer than a frame interval (render time grows
        // with it) and more dust than an image holds are refused
        let bad = |change: &dyn Fn(&mut SynthSpec), field: &str| {
            let mut s = spec.clone();
            change(&mut s);
            let e = s.validate(&p).unwrap_err().to_string();
            assert!(e.contains(&format!("`{field}`")) && e.contains("s.toml"), "{field}: {e}");
        };
        bad(&|s| s.height_px = 8, "height_px");
        bad(&|s| s.width_px = 9000, "width_px");
        bad(&|s| s.optics.exposure_s = 1.0 / s.fps * 1.01, "optics.exposure_s");
        bad(&|s| s.optics.exposure_s = 1e6, "optics.exposure_s");
        bad(&|s| s.illumination.dust_spots = 100_000, "illumination.dust_spots");
        let mut s = spec.clone();
        s.optics.exposure_s = 1.0 / s.fps;
        s.validate(&p).unwrap();
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

    /// A particle travelling with a cell, 0.5 um from its centroid, is on it in every frame; one
    /// travelling with it 8 um across the channel from its centroid never is; one crossing the
    /// cell at half its speed is on it in the frames where their paths overlap only. A
    /// `truth.csv` written before the column reads it as false.
    #[test]
    fn debris_on_a_cell_is_flagged_in_the_frames_it_lies_on_the_cell() {
        let mut spec = random_spec(9, 0.25, 0.01, 4.0);
        spec.cells.truncate(1);
        let c = spec.cells[0];
        let riding = DebrisSpec { x0_um: c.x0_um + 0.5, y_um: c.y_um, velocity_mm_s: c.velocity_mm_s, radius_um: 0.4, contrast: -0.3 };
        let far = DebrisSpec { y_um: c.y_um + 8.0, ..riding };
        for (d, want) in [(riding, true), (far, false)] {
            spec.debris = vec![d];
            assert!(truth_rows(&spec).iter().all(|r| r.debris_on_cell == want), "{d:?}");
        }
        // a slower particle starting 30 um ahead: the cell catches it up and passes it
        spec.debris = vec![DebrisSpec { x0_um: c.x0_um + 30.0, velocity_mm_s: 0.5 * c.velocity_mm_s, ..riding }];
        spec.n_frames = 200;
        let rows = truth_rows(&spec);
        let p = c.outline();
        let reach = DEBRIS_ON_CELL_RADII * 0.4;
        for r in &rows {
            let dx = c.x0_um + 30.0 + 0.5 * c.velocity_mm_s * 1000.0 * r.t_s - r.x_um;
            assert_eq!(r.debris_on_cell, p.signed_distance(dx, 0.0) <= reach, "t {}", r.t_s);
        }
        let on = rows.iter().filter(|r| r.debris_on_cell).count();
        assert!(on > 0 && on < rows.len(), "{on} of {}", rows.len());
        // the column is optional on reading
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(TRUTH_FILE);
        rbc_schema::tables::write_table(&path, &rows, &TRUTH_COLUMNS).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let old: String = text.lines().map(|l| l.rsplit_once(',').unwrap().0.to_string() + "\n").collect();
        assert!(old.starts_with("frame,cell_id,t_s,x_um,y_um,shape,velocity_mm_s,visible,area_um2,length_um,width_um\n"));
        std::fs::write(&path, old).unwrap();
        let back: Vec<TruthRow> = rbc_schema::tables::read_table(&path, &TRUTH_REQUIRED).unwrap();
        assert_eq!(back.len(), rows.len());
        assert!(back.iter().all(|r| !r.debris_on_cell));
    }
}
