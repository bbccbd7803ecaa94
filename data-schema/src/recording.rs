//! `recording.toml`: the metadata of one recording (a folder of frames).
//!
//! ```toml
//! fps = 400.0            # frames per second, in (0, 1e7]
//! um_per_px = 0.2        # pixel size in the object plane, um, in [1e-3, 100]
//! pressure_mbar = 100.0  # applied pressure drop, mbar, in [0, 1e5]
//! position_mm = 10.0     # 0 = channel entrance, 10 = downstream; in [0, 1e4]
//! [channel]              # optional
//! width_um = 11.9        # channel width (y), um, in [1, 1e4]
//! height_um = 9.7        # channel height (z), um, in [1, 1e4]
//! axis_row_px = 120.0    # optional: image row of the channel axis; detected when absent
//! ```

use crate::error::{Result, SchemaError};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// File name of the metadata file inside a recording folder.
pub const FILE_NAME: &str = "recording.toml";

/// Optional channel geometry of a recording.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelConfig {
    /// Channel width along y, um.
    pub width_um: f64,
    /// Channel height along z, um.
    pub height_um: f64,
    /// Image row (pixels, may be fractional) of the channel centre line; detected when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis_row_px: Option<f64>,
}

/// Validated contents of `recording.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordingConfig {
    /// Frames per second.
    pub fps: f64,
    /// Pixel size in the object plane, um per pixel.
    pub um_per_px: f64,
    /// Applied pressure drop, mbar.
    pub pressure_mbar: f64,
    /// Distance from the channel entrance, mm (0 = entrance).
    pub position_mm: f64,
    /// Channel geometry, when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub channel: Option<ChannelConfig>,
}

impl RecordingConfig {
    /// Parse and validate `recording.toml` text; `path` is used in error messages.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let cfg: RecordingConfig = toml::from_str(text).map_err(|e| toml_error(path, &e))?;
        cfg.validate(path)?;
        Ok(cfg)
    }

    /// Read and validate the `recording.toml` inside the recording folder `dir`.
    pub fn read_dir(dir: &Path) -> Result<Self> {
        let path = dir.join(FILE_NAME);
        let text = std::fs::read_to_string(&path).map_err(|e| SchemaError::io(&path, e))?;
        Self::parse(&text, &path)
    }

    /// Write this configuration as `recording.toml` into `dir` (atomically).
    pub fn write_dir(&self, dir: &Path) -> Result<()> {
        let path = dir.join(FILE_NAME);
        let text = toml::to_string(self).map_err(|e| SchemaError::Invalid { path: path.clone(), message: e.to_string() })?;
        crate::atomic::write_atomic(&path, |w| {
            use std::io::Write;
            w.write_all(text.as_bytes()).map_err(|e| SchemaError::io(&path, e))
        })
    }

    /// Check ranges; the error names the field.
    pub fn validate(&self, path: &Path) -> Result<()> {
        // physical ranges: a camera, an objective, a pump and a microchannel that exist
        positive(path, "fps", self.fps)?;
        within(path, "fps", self.fps, 0.0, 1e7, "frames per second")?;
        within(path, "um_per_px", self.um_per_px, 1e-3, 100.0, "um")?;
        within(path, "pressure_mbar", self.pressure_mbar, 0.0, 1e5, "mbar")?;
        within(path, "position_mm", self.position_mm, 0.0, 1e4, "mm")?;
        if let Some(ch) = &self.channel {
            within(path, "channel.width_um", ch.width_um, 1.0, 1e4, "um")?;
            within(path, "channel.height_um", ch.height_um, 1.0, 1e4, "um")?;
            if let Some(r) = ch.axis_row_px {
                if !r.is_finite() {
                    return Err(SchemaError::field(path, "channel.axis_row_px", "must be a finite number"));
                }
            }
        }
        Ok(())
    }
}

/// Convert a TOML parse error into a one-line [`SchemaError`] naming the file (and field when toml reports one).
pub fn toml_error(path: &Path, e: &toml::de::Error) -> SchemaError {
    let msg = e.message().replace('\n', " ");
    SchemaError::Toml { path: path.to_path_buf(), message: msg.trim().to_string() }
}

/// The 1-based line of byte offset `at` of `text` (for TOML errors; counts bytes, so any offset is safe).
pub fn line_at(text: &str, at: usize) -> usize {
    text.as_bytes()[..at.min(text.len())].iter().filter(|&&b| b == b'\n').count() + 1
}

/// Require a finite value > 0.
pub fn positive(path: &Path, field: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SchemaError::field(path, field, format!("must be a finite number > 0, got {}", short(v))))
    }
}

/// Require a finite value in `[lo, hi]` (`unit` for the message).
pub fn within(path: &Path, field: &str, v: f64, lo: f64, hi: f64, unit: &str) -> Result<()> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(SchemaError::field(path, field, format!("must lie in [{}, {}] {unit}, got {}", short(lo), short(hi), short(v))))
    }
}

/// `v` for a message: in scientific notation when very large or small (1e300 is not 301 digits).
pub fn short(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Require a finite value >= 0.
pub fn non_negative(path: &Path, field: &str, v: f64) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(SchemaError::field(path, field, format!("must be a finite number >= 0, got {}", short(v))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "fps = 400.0\num_per_px = 0.2\npressure_mbar = 100.0\nposition_mm = 10.0\n[channel]\nwidth_um = 11.9\nheight_um = 9.7\n";

    #[test]
    fn parses_and_round_trips() {
        let p = Path::new("rec/recording.toml");
        let cfg = RecordingConfig::parse(GOOD, p).unwrap();
        assert_eq!(cfg.fps, 400.0);
        assert_eq!(cfg.channel.as_ref().unwrap().axis_row_px, None);
        let dir = tempfile::tempdir().unwrap();
        cfg.write_dir(dir.path()).unwrap();
        assert_eq!(RecordingConfig::read_dir(dir.path()).unwrap(), cfg);
    }

    #[test]
    fn missing_field_is_named() {
        let text = GOOD.replace("fps = 400.0\n", "");
        let err = RecordingConfig::parse(&text, Path::new("rec/recording.toml")).unwrap_err().to_string();
        assert!(err.contains("rec/recording.toml") && err.contains("fps"), "{err}");
        assert!(!err.contains('\n'));
    }

    #[test]
    fn out_of_range_field_is_named() {
        let text = GOOD.replace("um_per_px = 0.2", "um_per_px = -1");
        let err = RecordingConfig::parse(&text, Path::new("r.toml")).unwrap_err().to_string();
        assert!(err.contains("um_per_px"), "{err}");
    }

    /// Values no camera, objective or channel has (found by mutating the file) are refused by name.
    #[test]
    fn implausible_values_are_named() {
        for (from, to, field) in [
            ("height_um = 9.7", "height_um = 1e-320", "channel.height_um"),
            ("width_um = 11.9", "width_um = 1e308", "channel.width_um"),
            ("fps = 400.0", "fps = 4294967297", "fps"),
            ("um_per_px = 0.2", "um_per_px = 1e-9", "um_per_px"),
        ] {
            let err = RecordingConfig::parse(&GOOD.replace(from, to), Path::new("r.toml")).unwrap_err().to_string();
            assert!(err.contains("r.toml") && err.contains(field) && err.contains("must lie in"), "{err}");
        }
    }

    #[test]
    fn unknown_field_is_refused() {
        let text = format!("{GOOD}\n");
        let text = text.replace("fps = 400.0", "fps = 400.0\nfsp = 3");
        let err = RecordingConfig::parse(&text, Path::new("r.toml")).unwrap_err().to_string();
        assert!(err.contains("fsp"), "{err}");
    }
}
