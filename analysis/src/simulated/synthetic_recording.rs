//! The files of a synthetic recording, whichever renderer drew it: the frames, `truth.csv` (the ground truth), `spec.toml` (the spec it was made from) and `recording.toml`; written atomically, read back as a [`Truth`].

use crate::error::AnalysisError;
use crate::simulated::synth::spec::{FrameFormat, SynthSpec};
use rayon::prelude::*;
use rbc_schema::SchemaError;
use serde::{Deserialize, Serialize};
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
    /// A debris particle of the spec lies on the cell in this frame ([`debris_on_cell`]): the
    /// cell's image is not its shape alone. Absent in recordings written before it (read as false).
    #[serde(default)]
    pub debris_on_cell: bool,
}

/// Columns of `truth.csv`, in order.
pub const TRUTH_COLUMNS: [&str; 12] = ["frame", "cell_id", "t_s", "x_um", "y_um", "shape", "velocity_mm_s", "visible", "area_um2", "length_um", "width_um", "debris_on_cell"];

/// The columns a `truth.csv` must have (`debris_on_cell` came later and may be absent).
pub const TRUTH_REQUIRED: [&str; 11] = ["frame", "cell_id", "t_s", "x_um", "y_um", "shape", "velocity_mm_s", "visible", "area_um2", "length_um", "width_um"];

/// How close to a cell's outline a debris particle's centre lies when it is on the cell, in
/// particle radii (the standard deviation of its Gaussian spot): three, the spot's thresholded
/// image measured 1.1-1.9 um in equivalent radius for particles of 0.3-0.6 um (analysis/README).
pub const DEBRIS_ON_CELL_RADII: f64 = 3.0;

/// Signed distance of `(x, y)` to the axis-aligned box `[-half[0], half[0]] x [-half[1], half[1]]`
/// (negative inside), in the units of its arguments.
pub fn box_distance(x: f64, y: f64, half: [f64; 2]) -> f64 {
    let (qx, qy) = (x.abs() - half[0], y.abs() - half[1]);
    qx.max(0.0).hypot(qy.max(0.0)) + qx.max(qy).min(0.0)
}

/// Whether a debris particle of `spec` lies on a cell at time `t` (s): the particle's centre at
/// mid-exposure inside the cell's outline or within [`DEBRIS_ON_CELL_RADII`] of its radii of it.
/// `distance(x_um, y_um)` is the signed distance to the cell's outline (negative inside), `x_um`
/// from the image's left edge and `y_um` from the channel axis, as the spec's positions.
pub fn debris_on_cell(spec: &SynthSpec, t: f64, distance: impl Fn(f64, f64) -> f64) -> bool {
    spec.debris.iter().any(|d| distance(d.x_um_at(t), d.y_um) <= DEBRIS_ON_CELL_RADII * d.radius_um)
}

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
        let rows = rbc_schema::tables::read_table(&dir.join(TRUTH_FILE), &TRUTH_REQUIRED)?;
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

/// The files of a synthetic recording written into `staging` (errors about `spec.toml`'s text name
/// it in `dir`).
fn write_into(staging: &Path, dir: &Path, spec: &SynthSpec, rows: &[TruthRow], frame: &(impl Fn(usize) -> Vec<u16> + Sync)) -> Result<(), AnalysisError> {
    (0..spec.n_frames).into_par_iter().try_for_each(|k| write_frame(&staging.join(format!("frame_{k:05}.{}", spec.format.extension())), frame(k), spec))?;
    rbc_schema::tables::write_table(&staging.join(TRUTH_FILE), rows, &TRUTH_COLUMNS)?;
    let spec_text = toml::to_string(spec).map_err(|e| AnalysisError::Input { path: dir.join(SPEC_FILE), message: e.to_string() })?;
    let spec_path = staging.join(SPEC_FILE);
    rbc_schema::atomic::write_atomic(&spec_path, |w| {
        use std::io::Write;
        w.write_all(spec_text.as_bytes()).map_err(|e| SchemaError::io(&spec_path, e))
    })?;
    spec.recording_config().write_dir(staging)?;
    Ok(())
}

/// Write a synthetic recording into `dir` (created if needed; refused if it already holds frames):
/// frame `k` as `frame(k)` for every frame of `spec`, then `truth.csv` (`rows`), `spec.toml` and
/// `recording.toml`.
pub fn write_frames_and_truth(dir: &Path, spec: &SynthSpec, rows: &[TruthRow], frame: impl Fn(usize) -> Vec<u16> + Sync) -> Result<Truth, AnalysisError> {
    let existing = std::fs::read_dir(dir).into_iter().flatten().filter_map(|e| e.ok()).any(|e| crate::experiment::recording::is_frame_file(&e.path()));
    if existing {
        return Err(AnalysisError::Input { path: dir.to_path_buf(), message: "output folder already holds frames; choose an empty folder".into() });
    }
    // written as a set (`rbc_schema::output_set`): a recording cut short (an error, a kill) leaves
    // no frames behind in `dir`, so the same command can run again
    let owns = |name: &str| crate::experiment::recording::is_frame_file(Path::new(name)) || [TRUTH_FILE, SPEC_FILE, rbc_schema::recording::FILE_NAME].contains(&name);
    // an error names the file in `dir`, not in the hidden staging folder (write_set's Unstage)
    rbc_schema::output_set::write_set(dir, owns, |staging| write_into(staging, dir, spec, rows, &frame))?;
    Ok(Truth { rows: rows.to_vec(), spec: spec.clone() })
}
