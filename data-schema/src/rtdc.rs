//! Reader for real-time deformability cytometry (`.rtdc`, HDF5) files: images, masks and features of events.
//!
//! Layout (dclab's HDF5 format): `events/image` and `events/mask` are
//! `u8[n, height, width]` (mask 0/255: the one object the instrument measured),
//! per-event features such as `events/pos_x`, `events/pos_y` (um) and
//! `events/area_um` (um^2), and root attributes `imaging:pixel size` (um) and
//! `imaging:frame rate` (1/s).

use crate::error::{Result, SchemaError};
use std::path::{Path, PathBuf};

/// The events of an `.rtdc` file that carry images.
#[derive(Debug, Clone, PartialEq)]
pub struct RtdcEvents {
    pub path: PathBuf,
    /// Image size, pixels.
    pub width: usize,
    pub height: usize,
    /// One 8-bit image per event, row-major.
    pub images: Vec<Vec<u8>>,
    /// The instrument's mask of the measured object per event (`true` = object).
    pub masks: Vec<Vec<bool>>,
    /// Pixel size, um.
    pub pixel_size_um: f64,
    /// Frame rate, 1/s.
    pub frame_rate: f64,
    /// Per-event features (um, um^2) when present in the file.
    pub pos_x_um: Option<Vec<f64>>,
    pub pos_y_um: Option<Vec<f64>>,
    pub area_um2: Option<Vec<f64>>,
}

fn h5err(path: &Path, what: &str, e: impl std::fmt::Display) -> SchemaError {
    SchemaError::Hdf5 { path: path.to_path_buf(), message: format!("{what}: {e}") }
}

/// Read a `u8[n, h, w]` dataset; returns (n, h, w, data).
fn read_stack(file: &hdf5::File, path: &Path, name: &str) -> Result<(usize, usize, usize, Vec<u8>)> {
    let ds = file.dataset(name).map_err(|e| h5err(path, name, e))?;
    let shape = ds.shape();
    if shape.len() != 3 {
        return Err(SchemaError::Invalid { path: path.to_path_buf(), message: format!("{name}: expected 3 dimensions (event, row, column), found {shape:?}") });
    }
    let data: Vec<u8> = ds.read_raw::<u8>().map_err(|e| h5err(path, name, e))?;
    Ok((shape[0], shape[1], shape[2], data))
}

fn read_feature(file: &hdf5::File, path: &Path, name: &str, n: usize) -> Result<Option<Vec<f64>>> {
    let Ok(ds) = file.dataset(name) else { return Ok(None) };
    let v: Vec<f64> = ds.read_raw::<f64>().map_err(|e| h5err(path, name, e))?;
    if v.len() != n {
        return Err(SchemaError::Invalid { path: path.to_path_buf(), message: format!("{name}: {} values for {n} events", v.len()) });
    }
    Ok(Some(v))
}

fn read_attr_f64(file: &hdf5::File, path: &Path, name: &str) -> Result<f64> {
    let a = file.attr(name).map_err(|e| h5err(path, &format!("attribute `{name}`"), e))?;
    let v: f64 = a.read_scalar::<f64>().map_err(|e| h5err(path, &format!("attribute `{name}`"), e))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(SchemaError::field(path, name, format!("must be a finite number > 0, got {v}")));
    }
    Ok(v)
}

/// Read the images, masks and main features of all events of an `.rtdc` file.
pub fn read_events(path: &Path) -> Result<RtdcEvents> {
    if !path.exists() {
        return Err(SchemaError::io(path, std::io::Error::new(std::io::ErrorKind::NotFound, "file not found")));
    }
    let file = hdf5::File::open(path).map_err(|e| h5err(path, "cannot open", e))?;
    let (n, height, width, image) = read_stack(&file, path, "events/image")?;
    let (nm, hm, wm, mask) = read_stack(&file, path, "events/mask")?;
    if (nm, hm, wm) != (n, height, width) {
        return Err(SchemaError::Invalid { path: path.to_path_buf(), message: format!("events/mask is {nm} x {hm} x {wm}, events/image is {n} x {height} x {width}") });
    }
    let px = width * height;
    let images = image.chunks(px).map(|c| c.to_vec()).collect();
    let masks = mask.chunks(px).map(|c| c.iter().map(|&v| v > 0).collect()).collect();
    Ok(RtdcEvents {
        path: path.to_path_buf(),
        width,
        height,
        images,
        masks,
        pixel_size_um: read_attr_f64(&file, path, "imaging:pixel size")?,
        frame_rate: read_attr_f64(&file, path, "imaging:frame rate")?,
        pos_x_um: read_feature(&file, path, "events/pos_x", n)?,
        pos_y_um: read_feature(&file, path, "events/pos_y", n)?,
        area_um2: read_feature(&file, path, "events/area_um", n)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_file_is_named() {
        let err = read_events(Path::new("/nonexistent/x.rtdc")).unwrap_err().to_string();
        assert!(err.contains("/nonexistent/x.rtdc"), "{err}");
    }

    #[test]
    fn non_hdf5_file_is_an_error_not_a_panic() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.rtdc");
        std::fs::write(&p, b"not hdf5").unwrap();
        let err = read_events(&p).unwrap_err().to_string();
        assert!(err.contains("bad.rtdc") && !err.contains('\n'), "{err}");
    }
}
