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

use crate::error::AnalysisError;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use rbc_schema::recording::{ChannelConfig, RecordingConfig};
use rbc_schema::SchemaError;
use serde::{Deserialize, Serialize};
use shape::{outline, OutlineParams, Polygon};
use std::path::Path;

/// File names written next to the frames.
pub const TRUTH_FILE: &str = "truth.csv";
pub const SPEC_FILE: &str = "spec.toml";

/// One row of `truth.csv`: one cell in one frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthRow {
    pub frame: u64,
    pub cell_id: u64,
    pub t_s: f64,
    /// Centroid of the outline at mid-exposure, um from the image's left edge.
    pub x_um: f64,
    /// Centroid across the channel, um from the axis.
    pub y_um: f64,
    pub shape: String,
    pub velocity_mm_s: f64,
    /// The whole cell (outline plus 0.5 um) is inside the image in this frame.
    pub visible: bool,
    /// Area of the outline, um^2; length and width along / across its principal axis, um.
    pub area_um2: f64,
    pub length_um: f64,
    pub width_um: f64,
}

/// Columns of `truth.csv`, in order.
pub const TRUTH_COLUMNS: [&str; 11] = ["frame", "cell_id", "t_s", "x_um", "y_um", "shape", "velocity_mm_s", "visible", "area_um2", "length_um", "width_um"];

/// The truth of a synthetic recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    pub rows: Vec<TruthRow>,
    /// The spec the recording was made from.
    pub spec: SynthSpec,
}

impl Truth {
    /// Read `truth.csv` and `spec.toml` from a synthetic recording folder.
    pub fn read(dir: &Path) -> Result<Truth, AnalysisError> {
        let rows = rbc_schema::tables::read_table(&dir.join(TRUTH_FILE), &TRUTH_COLUMNS)?;
        let spec = read_spec(&dir.join(SPEC_FILE))?;
        Ok(Truth { rows, spec })
    }

    /// Channel axis row (px) and wall rows (px) of the truth.
    pub fn channel_rows(&self) -> (f64, [f64; 2]) {
        let a = self.spec.channel.axis_row_px;
        let h = 0.5 * self.spec.channel.width_um / self.spec.um_per_px;
        (a, [a - h, a + h])
    }
}

/// Read and validate a [`SynthSpec`] from a TOML file; errors name the file (and field).
pub fn read_spec(path: &Path) -> Result<SynthSpec, AnalysisError> {
    let text = std::fs::read_to_string(path).map_err(|e| SchemaError::io(path, e))?;
    let spec: SynthSpec = toml::from_str(&text).map_err(|e| rbc_schema::recording::toml_error(path, &e))?;
    spec.validate(path)?;
    Ok(spec)
}

impl SynthSpec {
    /// Check ranges; the error names `path` and the field.
    pub fn validate(&self, path: &Path) -> Result<(), AnalysisError> {
        use rbc_schema::recording::{non_negative, positive};
        let f = |field: &str, msg: &str| -> AnalysisError { SchemaError::field(path, field, msg).into() };
        if self.width_px < 16 || self.height_px < 16 || self.width_px > 8192 || self.height_px > 8192 {
            return Err(f("width_px", "width_px and height_px must be in 16..=8192"));
        }
        positive(path, "um_per_px", self.um_per_px)?;
        positive(path, "fps", self.fps)?;
        if self.n_frames == 0 || self.n_frames > 100_000 {
            return Err(f("n_frames", "must be in 1..=100000"));
        }
        non_negative(path, "pressure_mbar", self.pressure_mbar)?;
        non_negative(path, "position_mm", self.position_mm)?;
        non_negative(path, "noise.gaussian_sigma", self.noise.gaussian_sigma)?;
        non_negative(path, "noise.full_well", self.noise.full_well)?;
        positive(path, "illumination.level", self.illumination.level)?;
        if self.illumination.level > 1.0 {
            return Err(f("illumination.level", "must be <= 1 (fraction of full scale)"));
        }
        non_negative(path, "optics.exposure_s", self.optics.exposure_s)?;
        positive(path, "illumination.wall_brightness", self.illumination.wall_brightness)?;
        positive(path, "optics.edge_um", self.optics.edge_um)?;
        positive(path, "optics.rim_width_um", self.optics.rim_width_um)?;
        positive(path, "optics.halo_width_um", self.optics.halo_width_um)?;
        positive(path, "channel.width_um", self.channel.width_um)?;
        positive(path, "channel.height_um", self.channel.height_um)?;
        if !self.channel.axis_row_px.is_finite() {
            return Err(f("channel.axis_row_px", "must be a finite number"));
        }
        for (i, c) in self.cells.iter().enumerate() {
            let name = |s: &str| format!("cells[{i}].{s}");
            for (field, v) in [("x0_um", c.x0_um), ("y_um", c.y_um), ("velocity_mm_s", c.velocity_mm_s), ("orientation_deg", c.orientation_deg), ("deform", c.deform), ("asymmetry", c.asymmetry)] {
                if !v.is_finite() {
                    return Err(f(&name(field), "must be a finite number"));
                }
            }
            positive(path, &name("length_um"), c.length_um)?;
            positive(path, &name("width_um"), c.width_um)?;
        }
        for (i, d) in self.debris.iter().enumerate() {
            let name = |s: &str| format!("debris[{i}].{s}");
            for (field, v) in [("x0_um", d.x0_um), ("y_um", d.y_um), ("velocity_mm_s", d.velocity_mm_s), ("contrast", d.contrast)] {
                if !v.is_finite() {
                    return Err(f(&name(field), "must be a finite number"));
                }
            }
            positive(path, &name("radius_um"), d.radius_um)?;
        }
        if let Some(w) = &self.wave {
            w.validate(path)?;
        }
        Ok(())
    }

    /// The `recording.toml` of this spec.
    pub fn recording_config(&self) -> RecordingConfig {
        RecordingConfig {
            fps: self.fps,
            um_per_px: self.um_per_px,
            pressure_mbar: self.pressure_mbar,
            position_mm: self.position_mm,
            channel: Some(ChannelConfig {
                width_um: self.channel.width_um,
                height_um: self.channel.height_um,
                axis_row_px: self.channel.axis_in_toml.then_some(self.channel.axis_row_px),
            }),
        }
    }
}

/// The outline of cell `c` (centred polygon, um): the truth shape both renderers draw.
pub(crate) fn outline_of(c: &CellSpec) -> Polygon {
    outline(
        c.shape,
        &OutlineParams { length_um: c.length_um, width_um: c.width_um, orientation_deg: c.orientation_deg, deform: c.deform, flip: c.flip, asymmetry: c.asymmetry, seed: c.seed },
    )
}

/// Centroid x of cell `c` at time `t`, um: `x0 + v t` (v in mm/s = 1000 um/s).
fn x_at(c: &CellSpec, t: f64) -> f64 {
    c.x0_um + c.velocity_mm_s * 1000.0 * t
}

/// The truth rows of `spec` (no rendering).
pub fn truth_rows(spec: &SynthSpec) -> Vec<TruthRow> {
    let polys: Vec<Polygon> = spec.cells.iter().map(outline_of).collect();
    let um = spec.um_per_px;
    let (wu, hu) = (spec.width_px as f64 * um, spec.height_px as f64 * um);
    let mut rows = Vec::new();
    for k in 0..spec.n_frames {
        let t = k as f64 / spec.fps;
        for (id, (c, p)) in spec.cells.iter().zip(&polys).enumerate() {
            let x = x_at(c, t);
            let bb = p.bbox();
            let blur = 0.5 * c.velocity_mm_s.abs() * 1000.0 * spec.optics.exposure_s;
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
        let travel = c.velocity_mm_s * 1000.0 * spec.optics.exposure_s; // um during the exposure
        let n_sub = ((travel.abs() / (0.2 * um)).ceil() as usize).clamp(1, 64);
        let xs_um: Vec<f64> = (0..n_sub).map(|j| x_at(c, t) + travel * ((j as f64 + 0.5) / n_sub as f64 - 0.5)).collect();
        let cell = render::CellInFrame { poly: p, xs_um, y_um: spec.channel.axis_row_px * um + c.y_um };
        render::add_cell(&mut contrast, w, h, um, &spec.optics, &cell);
    }
    for d in &spec.debris {
        let travel = d.velocity_mm_s * 1000.0 * spec.optics.exposure_s;
        let n_sub = ((travel.abs() / (0.2 * um)).ceil() as usize).clamp(1, 64);
        let x = d.x0_um + d.velocity_mm_s * 1000.0 * t;
        let xs_um: Vec<f64> = (0..n_sub).map(|j| x + travel * ((j as f64 + 0.5) / n_sub as f64 - 0.5)).collect();
        render::add_debris(&mut contrast, w, h, um, &xs_um, spec.channel.axis_row_px * um + d.y_um, d.radius_um, d.contrast);
    }
    let gain = 1.0 + spec.illumination.flicker * Normal::new(0.0, 1.0).expect("unit normal").sample(&mut rng);
    let intensity: Vec<f64> = background.iter().zip(&contrast).map(|(b, c)| b * gain * (1.0 + c)).collect();
    let max = if spec.format.sixteen_bit() { 65535.0 } else { 255.0 };
    render::add_noise_and_quantise(&intensity, spec, &mut rng, max)
}

/// Write one frame file (atomically: temporary file, then rename).
pub fn write_frame(path: &Path, counts: Vec<u16>, spec: &SynthSpec) -> Result<(), AnalysisError> {
    let (w, h) = (spec.width_px as u32, spec.height_px as u32);
    let tmp = rbc_schema::atomic::temp_path(path);
    let fmt = match spec.format {
        FrameFormat::Png8 | FrameFormat::Png16 => image::ImageFormat::Png,
        FrameFormat::Tiff8 | FrameFormat::Tiff16 => image::ImageFormat::Tiff,
    };
    let res = if spec.format.sixteen_bit() {
        image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(w, h, counts).expect("size").save_with_format(&tmp, fmt)
    } else {
        let bytes: Vec<u8> = counts.into_iter().map(|v| v as u8).collect();
        image::GrayImage::from_raw(w, h, bytes).expect("size").save_with_format(&tmp, fmt)
    };
    if let Err(e) = res {
        let _ = std::fs::remove_file(&tmp);
        return Err(AnalysisError::Input { path: path.to_path_buf(), message: format!("cannot write frame: {e}") });
    }
    rbc_schema::atomic::commit(&tmp, path)?;
    Ok(())
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
        let polys: Vec<Polygon> = spec.cells.iter().map(outline_of).collect();
        let background = render::static_background(spec, seed);
        write_frames_and_truth(dir, spec, &rows, |k| render_frame(spec, &polys, &background, seed, k))
    }
}

/// Write a synthetic recording into `dir` (created if needed; refused if it already holds frames):
/// frame `k` as `frame(k)` for every frame of `spec`, then `truth.csv` (`rows`), `spec.toml` and
/// `recording.toml`.
pub fn write_frames_and_truth(dir: &Path, spec: &SynthSpec, rows: &[TruthRow], frame: impl Fn(usize) -> Vec<u16> + Sync) -> Result<Truth, AnalysisError> {
    std::fs::create_dir_all(dir).map_err(|e| SchemaError::io(dir, e))?;
    let existing = std::fs::read_dir(dir).map_err(|e| SchemaError::io(dir, e))?.filter_map(|e| e.ok()).any(|e| crate::experiment::recording::is_frame_file(&e.path()));
    if existing {
        return Err(AnalysisError::Input { path: dir.to_path_buf(), message: "output folder already holds frames; choose an empty folder".into() });
    }
    (0..spec.n_frames).into_par_iter().try_for_each(|k| write_frame(&dir.join(format!("frame_{k:05}.{}", spec.format.extension())), frame(k), spec))?;
    rbc_schema::tables::write_table(&dir.join(TRUTH_FILE), rows, &TRUTH_COLUMNS)?;
    let spec_text = toml::to_string(spec).map_err(|e| AnalysisError::Input { path: dir.join(SPEC_FILE), message: e.to_string() })?;
    let spec_path = dir.join(SPEC_FILE);
    rbc_schema::atomic::write_atomic(&spec_path, |w| {
        use std::io::Write;
        w.write_all(spec_text.as_bytes()).map_err(|e| SchemaError::io(&spec_path, e))
    })?;
    spec.recording_config().write_dir(dir)?;
    Ok(Truth { rows: rows.to_vec(), spec: spec.clone() })
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
