//! Recordings on disk: find recording folders, list their PNG/TIFF frames in file-name order, check and load them.
//!
//! A recording is a folder holding `recording.toml` and grayscale frames
//! (`*.png`, `*.tif`, `*.tiff`; 8 or 16 bit) sorted by file name
//! (`../shared/spec/interfaces.md`). Every frame must have the size and bit
//! depth of the first one; [`Recording::open`] checks this from the image
//! headers (cheap: no pixel data is decoded) so a bad recording fails before
//! any work, with the offending file named.

pub mod detect;

pub use detect::{detect_recording, RecordingDetections};

use crate::error::AnalysisError;
use crate::types::Frame;
use rayon::prelude::*;
use rbc_schema::recording::{RecordingConfig, FILE_NAME};
use std::path::{Path, PathBuf};

/// Pixel depth of the frames of a recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BitDepth {
    Eight,
    Sixteen,
}

impl BitDepth {
    /// Largest raw value (255 or 65535), used to scale intensities to [0, 1].
    pub fn max_value(self) -> f32 {
        match self {
            BitDepth::Eight => 255.0,
            BitDepth::Sixteen => 65535.0,
        }
    }
}

/// One recording folder: validated metadata and the ordered list of its frames.
#[derive(Debug, Clone)]
pub struct Recording {
    /// The recording folder.
    pub dir: PathBuf,
    /// Name used in output tables: the path relative to the searched root (or the folder name).
    pub name: String,
    /// Validated `recording.toml`.
    pub config: RecordingConfig,
    /// Frame files in file-name order.
    pub frames: Vec<PathBuf>,
    /// Frame size, pixels.
    pub width: usize,
    pub height: usize,
    pub bit_depth: BitDepth,
}

fn input_err(path: &Path, message: impl Into<String>) -> AnalysisError {
    AnalysisError::Input { path: path.to_path_buf(), message: message.into() }
}

/// True when `path` names a frame file we read (by extension, case-insensitive).
pub fn is_frame_file(path: &Path) -> bool {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) => matches!(e.to_ascii_lowercase().as_str(), "png" | "tif" | "tiff"),
        None => false,
    }
}

/// Recording folders under `root`, sorted by path.
///
/// `root` itself is a recording when it holds `recording.toml` or frame files;
/// otherwise its sub-folders are searched recursively and every folder holding
/// `recording.toml` or frames is returned (a folder with frames but no
/// `recording.toml` is returned too, so that [`Recording::open`] can name the
/// missing file). Hidden folders (`.name`) are skipped.
pub fn discover(root: &Path) -> Result<Vec<PathBuf>, AnalysisError> {
    let meta = std::fs::metadata(root).map_err(|e| input_err(root, e.to_string()))?;
    if !meta.is_dir() {
        return Err(input_err(root, "not a folder (expected a recording folder or a folder of recordings)"));
    }
    let mut found = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let mut has_frames = false;
        let mut has_toml = false;
        let entries = std::fs::read_dir(&dir).map_err(|e| input_err(&dir, e.to_string()))?;
        for entry in entries {
            let entry = entry.map_err(|e| input_err(&dir, e.to_string()))?;
            let path = entry.path();
            let hidden = entry.file_name().to_string_lossy().starts_with('.');
            let ft = entry.file_type().map_err(|e| input_err(&path, e.to_string()))?;
            if ft.is_dir() || (ft.is_symlink() && path.is_dir()) {
                if !hidden {
                    stack.push(path);
                }
            } else if entry.file_name() == FILE_NAME {
                has_toml = true;
            } else if !hidden && is_frame_file(&path) {
                has_frames = true;
            }
        }
        if has_toml || has_frames {
            found.push(dir);
        }
    }
    if found.is_empty() {
        return Err(input_err(root, "no recording found (no folder with recording.toml and PNG/TIFF frames)"));
    }
    found.sort();
    Ok(found)
}

/// Size and bit depth from an image file's header, without decoding pixels.
fn probe(path: &Path) -> Result<(usize, usize, BitDepth), AnalysisError> {
    use image::ImageDecoder;
    let reader = image::ImageReader::open(path)
        .map_err(|e| input_err(path, format!("cannot open image: {e}")))?
        .with_guessed_format()
        .map_err(|e| input_err(path, format!("cannot read image: {e}")))?;
    let decoder = reader.into_decoder().map_err(|e| input_err(path, format!("not a readable PNG/TIFF image: {e}")))?;
    let (w, h) = decoder.dimensions();
    let depth = depth_of(path, decoder.color_type())?;
    Ok((w as usize, h as usize, depth))
}

fn depth_of(path: &Path, ct: image::ColorType) -> Result<BitDepth, AnalysisError> {
    match ct {
        image::ColorType::L8 => Ok(BitDepth::Eight),
        image::ColorType::L16 => Ok(BitDepth::Sixteen),
        other => Err(input_err(path, format!("expected an 8- or 16-bit grayscale image, found {other:?}"))),
    }
}

impl Recording {
    /// Open the recording in `dir`: read and validate `recording.toml`, list
    /// the frames in file-name order and check that all have one size and bit depth.
    pub fn open(dir: &Path) -> Result<Recording, AnalysisError> {
        Self::open_named(dir, None)
    }

    /// Like [`Recording::open`], naming the recording by its path relative to `root`.
    pub fn open_under(root: &Path, dir: &Path) -> Result<Recording, AnalysisError> {
        Self::open_named(dir, Some(root))
    }

    fn open_named(dir: &Path, root: Option<&Path>) -> Result<Recording, AnalysisError> {
        let config = RecordingConfig::read_dir(dir)?;
        let mut frames = Vec::new();
        let entries = std::fs::read_dir(dir).map_err(|e| input_err(dir, e.to_string()))?;
        for entry in entries {
            let entry = entry.map_err(|e| input_err(dir, e.to_string()))?;
            let path = entry.path();
            if entry.file_name().to_string_lossy().starts_with('.') || !is_frame_file(&path) {
                continue;
            }
            // a frame's time is its place in the sorted list: one left out would shift every later
            // frame's time, so a frame-named entry that is not a readable file is an error
            if !path.is_file() {
                let what = if path.is_dir() { "a directory" } else { "not a readable file (a broken link?)" };
                return Err(input_err(&path, format!("named as a frame but {what}")));
            }
            frames.push(path);
        }
        if frames.is_empty() {
            return Err(input_err(dir, "recording has no frames (no *.png, *.tif or *.tiff file)"));
        }
        frames.sort_by(|a, b| a.file_name().cmp(&b.file_name()));
        let (width, height, bit_depth) = probe(&frames[0])?;
        if width < 8 || height < 8 {
            return Err(input_err(&frames[0], format!("frame of {width} x {height} px is too small (need at least 8 x 8)")));
        }
        // Headers of all other frames, in parallel: same size and depth as the first.
        frames[1..].par_iter().try_for_each(|p| {
            let (w, h, d) = probe(p)?;
            if (w, h) != (width, height) {
                return Err(input_err(p, format!("frame is {w} x {h} px but {} is {width} x {height} px", frames[0].display())));
            }
            if d != bit_depth {
                return Err(input_err(p, format!("frame is {d:?}-bit but {} is {bit_depth:?}-bit", frames[0].display())));
            }
            Ok(())
        })?;
        let name = match root.and_then(|r| dir.strip_prefix(r).ok()) {
            Some(rel) if !rel.as_os_str().is_empty() => rel.to_string_lossy().into_owned(),
            _ => dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| dir.display().to_string()),
        };
        Ok(Recording { dir: dir.to_path_buf(), name, config, frames, width, height, bit_depth })
    }

    /// Number of frames.
    pub fn n_frames(&self) -> usize {
        self.frames.len()
    }

    /// Time of frame `i`, s (`i / fps`).
    pub fn time_s(&self, i: usize) -> f64 {
        i as f64 / self.config.fps
    }

    /// Decode frame `i` into intensities in [0, 1]; the error names the file.
    pub fn load_frame(&self, i: usize) -> Result<Frame, AnalysisError> {
        let path = self.frames.get(i).ok_or_else(|| input_err(&self.dir, format!("frame {i} does not exist ({} frames)", self.frames.len())))?;
        let frame = load_frame_file(path)?;
        if (frame.width, frame.height) != (self.width, self.height) {
            return Err(input_err(path, format!("frame is {} x {} px, recording is {} x {} px", frame.width, frame.height, self.width, self.height)));
        }
        Ok(frame)
    }

    /// All frames, decoded in parallel (rayon), in file-name order.
    pub fn load_frames(&self) -> Result<Vec<Frame>, AnalysisError> {
        (0..self.frames.len()).into_par_iter().map(|i| self.load_frame(i)).collect()
    }
}

/// Decode one 8- or 16-bit grayscale PNG/TIFF into a [`Frame`] scaled to [0, 1].
pub fn load_frame_file(path: &Path) -> Result<Frame, AnalysisError> {
    let img = image::ImageReader::open(path)
        .map_err(|e| input_err(path, format!("cannot open image: {e}")))?
        .with_guessed_format()
        .map_err(|e| input_err(path, format!("cannot read image: {e}")))?
        .decode()
        .map_err(|e| input_err(path, format!("cannot decode image (truncated or corrupt?): {e}")))?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    let data: Vec<f32> = match img {
        image::DynamicImage::ImageLuma8(b) => b.into_raw().into_iter().map(|v| v as f32 / 255.0).collect(),
        image::DynamicImage::ImageLuma16(b) => b.into_raw().into_iter().map(|v| v as f32 / 65535.0).collect(),
        other => return Err(input_err(path, format!("expected an 8- or 16-bit grayscale image, found {:?}", other.color()))),
    };
    Ok(Frame { width, height, data })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_extensions() {
        assert!(is_frame_file(Path::new("a/f001.PNG")));
        assert!(is_frame_file(Path::new("f.tif")));
        assert!(is_frame_file(Path::new("f.tiff")));
        assert!(!is_frame_file(Path::new("recording.toml")));
        assert!(!is_frame_file(Path::new("truth.csv")));
    }

    /// An uncompressed 8-bit grayscale little-endian TIFF, its directory first and one strip
    /// after it, whose StripByteCounts is `count` (the pixels' length when honest).
    fn tiff_bytes(w: u16, h: u16, pixels: &[u8], count: u32) -> Vec<u8> {
        const DATA: u32 = 8 + 2 + 9 * 12 + 4;
        let mut out = b"II*\0".to_vec();
        out.extend(8u32.to_le_bytes());
        let short = |tag: u16, v: u16| [tag.to_le_bytes(), 3u16.to_le_bytes(), 1u32.to_le_bytes()[..2].try_into().unwrap(), 0u16.to_le_bytes(), v.to_le_bytes(), 0u16.to_le_bytes()].concat();
        let long = |tag: u16, v: u32| [&tag.to_le_bytes()[..], &4u16.to_le_bytes(), &1u32.to_le_bytes(), &v.to_le_bytes()].concat();
        let entries = [short(256, w), short(257, h), short(258, 8), short(259, 1), short(262, 1), long(273, DATA), short(277, 1), short(278, h), long(279, count)];
        out.extend((entries.len() as u16).to_le_bytes());
        for e in entries {
            out.extend(e);
        }
        out.extend(0u32.to_le_bytes());
        assert_eq!(out.len() as u32, DATA);
        out.extend(pixels);
        out
    }

    /// A TIFF frame cut short (an acquisition that wrote the header and lost data) is refused,
    /// naming the file, whether its StripByteCounts tells the truth or not; one whose
    /// StripByteCounts is too small while its pixels are all there decodes to those pixels (the
    /// decoder reads the strip the image's size needs), as the honest file does.
    #[test]
    fn a_cut_tiff_is_refused_and_a_short_strip_count_reads_the_true_pixels() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (16u16, 8u16);
        let pixels: Vec<u8> = (0..w as usize * h as usize).map(|i| (i % 251) as u8).collect();
        let n = pixels.len() as u32;
        for (name, count) in [("good.tif", n), ("short_count.tif", n / 2)] {
            let path = dir.path().join(name);
            std::fs::write(&path, tiff_bytes(w, h, &pixels, count)).unwrap();
            let f = load_frame_file(&path).unwrap();
            assert_eq!((f.width, f.height, f.data.len()), (16, 8, pixels.len()), "{name}");
            assert!(f.data.iter().zip(&pixels).all(|(a, &b)| *a == b as f32 / 255.0), "{name}");
        }
        for (name, count) in [("cut.tif", n), ("cut_short_count.tif", n / 2)] {
            let path = dir.path().join(name);
            let mut bytes = tiff_bytes(w, h, &pixels, count);
            bytes.truncate(bytes.len() - pixels.len() / 2);
            std::fs::write(&path, bytes).unwrap();
            let err = load_frame_file(&path).map(|_| ()).unwrap_err().to_string();
            assert!(err.contains(name) && err.contains("truncated or corrupt"), "{err}");
        }
    }
}
