//! The synthesiser's input: image, optics, noise, channel and cells of one synthetic recording (serde, TOML).

use super::shape::{outline, CellShape, OutlineParams, Polygon};
use crate::error::AnalysisError;
use rbc_schema::recording::{ChannelConfig, RecordingConfig};
use rbc_schema::SchemaError;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// File format and bit depth of the synthetic frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameFormat {
    #[default]
    Png8,
    Png16,
    Tiff8,
    Tiff16,
}

impl FrameFormat {
    pub fn extension(self) -> &'static str {
        match self {
            FrameFormat::Png8 | FrameFormat::Png16 => "png",
            FrameFormat::Tiff8 | FrameFormat::Tiff16 => "tif",
        }
    }
    pub fn sixteen_bit(self) -> bool {
        matches!(self, FrameFormat::Png16 | FrameFormat::Tiff16)
    }
}

/// Camera noise. Intensities are in [0, 1] of full scale.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NoiseSpec {
    /// Gaussian read noise, standard deviation in units of full scale.
    pub gaussian_sigma: f64,
    /// Photo-electrons at full scale (shot noise is Poisson in these); 0 = no shot noise.
    pub full_well: f64,
}

impl Default for NoiseSpec {
    fn default() -> Self {
        NoiseSpec { gaussian_sigma: 0.01, full_well: 10000.0 }
    }
}

/// Uneven, slightly flickering illumination and static dust.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IlluminationSpec {
    /// Mean background intensity inside the channel (fraction of full scale).
    pub level: f64,
    /// Relative change of the illumination across the image width / height (linear ramps).
    pub gradient_x: f64,
    pub gradient_y: f64,
    /// Relative darkening at the image corners (quadratic vignette).
    pub vignette: f64,
    /// Relative standard deviation of the frame-to-frame brightness.
    pub flicker: f64,
    /// Number of static dark dust spots (removed by the background).
    pub dust_spots: usize,
    /// Brightness of the PDMS beyond the walls relative to the channel's inside (0.85: 15 % darker;
    /// above 1 the walls are brighter than the channel).
    pub wall_brightness: f64,
}

impl Default for IlluminationSpec {
    fn default() -> Self {
        IlluminationSpec { level: 0.55, gradient_x: 0.15, gradient_y: 0.06, vignette: 0.12, flicker: 0.01, dust_spots: 3, wall_brightness: 0.85 }
    }
}

/// Bright-field appearance of a cell edge, as a relative contrast profile in the signed distance `d` (um, < 0 inside):
/// `c(d) = interior S(-d) + inner S(-(d + inner_depth_um)) - rim g(d + rim_offset_um, rim_width_um) + halo g(d - halo_offset_um, halo_width_um)`,
/// with `S` a Gaussian-smoothed step of width `edge_um` and `g(u, w) = exp(-u^2 / (2 w^2))`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OpticsSpec {
    pub interior: f64,
    pub inner: f64,
    pub inner_depth_um: f64,
    pub rim: f64,
    pub rim_offset_um: f64,
    pub rim_width_um: f64,
    pub halo: f64,
    pub halo_offset_um: f64,
    pub halo_width_um: f64,
    pub edge_um: f64,
    /// Exposure time, s (motion blur: the cell moves `velocity * exposure` during it).
    pub exposure_s: f64,
}

impl Default for OpticsSpec {
    fn default() -> Self {
        OpticsSpec {
            interior: -0.12,
            inner: 0.07,
            inner_depth_um: 1.2,
            rim: 0.35,
            rim_offset_um: 0.4,
            rim_width_um: 0.3,
            halo: 0.25,
            halo_offset_um: 0.35,
            halo_width_um: 0.3,
            edge_um: 0.15,
            exposure_s: 20e-6,
        }
    }
}

/// Where the channel is in the image.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelSpec {
    /// Wall-to-wall distance, um.
    #[serde(default = "default_width")]
    pub width_um: f64,
    /// Channel height (z), um (only written to recording.toml).
    #[serde(default = "default_height")]
    pub height_um: f64,
    /// Image row of the axis (pixel centres at integer rows).
    pub axis_row_px: f64,
    /// Write `channel.axis_row_px` into recording.toml (else the analysis detects the walls).
    #[serde(default)]
    pub axis_in_toml: bool,
}

fn default_width() -> f64 {
    11.9
}
fn default_height() -> f64 {
    9.7
}

/// One synthetic cell moving along +x at constant velocity.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CellSpec {
    pub shape: CellShape,
    /// Centroid at t = 0, um from the image's left edge (may be outside the image).
    pub x0_um: f64,
    /// Centroid across the channel, um from the axis (signed, + towards increasing rows).
    pub y_um: f64,
    pub velocity_mm_s: f64,
    /// Outline length (along its own axis) and width, um.
    #[serde(default = "default_len")]
    pub length_um: f64,
    #[serde(default = "default_wid")]
    pub width_um: f64,
    /// Tilt of a slipper or irregular cell, degrees from +x.
    #[serde(default)]
    pub orientation_deg: f64,
    /// Croissant notch depth / slipper bend / irregular roughness (see [`super::shape::OutlineParams`]).
    #[serde(default = "default_deform")]
    pub deform: f64,
    /// Croissant opening downstream instead of upstream; slipper thick end upstream.
    #[serde(default)]
    pub flip: bool,
    /// Slipper teardrop asymmetry.
    #[serde(default = "default_asym")]
    pub asymmetry: f64,
    /// Seed of an irregular outline.
    #[serde(default)]
    pub seed: u64,
}

fn default_len() -> f64 {
    7.0
}
fn default_wid() -> f64 {
    5.5
}
fn default_deform() -> f64 {
    0.2
}
fn default_asym() -> f64 {
    0.3
}

/// A small particle (debris, platelet, bead) carried along +x with the flow: a Gaussian spot of
/// relative contrast `contrast` (< 0 dark) and standard deviation `radius_um`. It is no cell:
/// it has no row in `truth.csv`, and a track of it is a false track.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DebrisSpec {
    /// Position at t = 0, um from the image's left edge, and across the channel from the axis.
    pub x0_um: f64,
    pub y_um: f64,
    pub velocity_mm_s: f64,
    pub radius_um: f64,
    pub contrast: f64,
}

/// A synthetic recording.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SynthSpec {
    pub width_px: usize,
    pub height_px: usize,
    pub um_per_px: f64,
    pub fps: f64,
    pub n_frames: usize,
    pub pressure_mbar: f64,
    pub position_mm: f64,
    #[serde(default)]
    pub format: FrameFormat,
    #[serde(default)]
    pub noise: NoiseSpec,
    #[serde(default)]
    pub illumination: IlluminationSpec,
    #[serde(default)]
    pub optics: OpticsSpec,
    pub channel: ChannelSpec,
    #[serde(default)]
    pub cells: Vec<CellSpec>,
    /// Moving particles that are not cells (none by default).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub debris: Vec<DebrisSpec>,
    /// Render with the wave-optics renderer ([`crate::simulated::wave`]) under these optics instead
    /// of the edge profiles of `optics` (of which only the exposure time is then used).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wave: Option<crate::simulated::wave::optics::WaveOptics>,
}

impl SynthSpec {
    /// Check ranges; the error names `path` and the field.
    pub fn validate(&self, path: &Path) -> Result<(), AnalysisError> {
        use rbc_schema::recording::{non_negative, positive};
        let f = |field: &str, msg: &str| -> AnalysisError { SchemaError::field(path, field, msg).into() };
        for (field, v) in [("width_px", self.width_px), ("height_px", self.height_px)] {
            if !(16..=8192).contains(&v) {
                return Err(f(field, "must be in 16..=8192"));
            }
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
        // a camera exposes each frame within its frame interval (the render time grows with it)
        if self.optics.exposure_s > 1.0 / self.fps {
            return Err(f("optics.exposure_s", &format!("{} s is longer than the frame interval 1/fps = {} s", self.optics.exposure_s, 1.0 / self.fps)));
        }
        if self.illumination.dust_spots > 1000 {
            return Err(f("illumination.dust_spots", "must be at most 1000"));
        }
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

impl DebrisSpec {
    /// Position along the flow at time `t` (s), um from the image's left edge: `x0 + v t` (v in
    /// mm/s = 1000 um/s).
    pub fn x_um_at(&self, t: f64) -> f64 {
        self.x0_um + self.velocity_mm_s * 1000.0 * t
    }
}

impl CellSpec {
    /// The cell's outline (centred polygon, um): the truth shape every renderer draws.
    pub fn outline(&self) -> Polygon {
        outline(
            self.shape,
            &OutlineParams { length_um: self.length_um, width_um: self.width_um, orientation_deg: self.orientation_deg, deform: self.deform, flip: self.flip, asymmetry: self.asymmetry, seed: self.seed },
        )
    }
}
