//! What the fuzzer feeds, per format: the seeds, how a case's input is written, and the library calls that read it
//! (the same calls the binaries make, so a panic found is one a user can hit).

mod checkpoint;
mod frames;
mod recording;
mod results;
mod scene;
mod sweep;
mod tables;

use super::Format;
use anyhow::{Context, Result};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};

/// One input format under test.
pub trait Target {
    /// Write the input of one case (files) into the empty folder `case`.
    fn write_case(&self, rng: &mut ChaCha8Rng, case: &Path) -> Result<(), String>;
    /// Read the case's input the way the binaries do; `Err` is the one-line message a user would see.
    fn exercise(&self, case: &Path) -> Result<(), String>;
}

/// The shipped examples (seeds of every format).
pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples")
}

/// Read a seed file; the error names it.
pub fn read(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("reading seed {}", path.display()))
}

/// Write one file of a case.
pub fn put(path: &Path, bytes: &[u8]) -> Result<(), String> {
    std::fs::write(path, bytes).map_err(|e| format!("harness: writing {}: {e}", path.display()))
}

/// Prepare the seeds of `format` in `seeds` (a scratch folder of the worker).
pub fn prepare(format: Format, seeds: &Path) -> Result<Box<dyn Target>> {
    std::fs::create_dir_all(seeds).with_context(|| format!("creating {}", seeds.display()))?;
    Ok(match format {
        Format::Recording => Box::new(recording::RecordingToml::prepare()?),
        Format::Frames => Box::new(frames::Frames::prepare()?),
        Format::Scene => Box::new(scene::SceneToml::prepare()?),
        Format::Sweep => Box::new(sweep::SweepToml::prepare()?),
        Format::Csv => Box::new(tables::Tables::prepare(seeds)?),
        Format::Results => Box::new(results::ResultsH5::prepare(seeds)?),
        Format::Checkpoint => Box::new(checkpoint::CheckpointFile::prepare(seeds)?),
    })
}

/// Text mutation half the time, structured TOML mutation otherwise (text when the seed is not TOML).
pub fn mutate_toml_text(seed: &str, rng: &mut ChaCha8Rng) -> Vec<u8> {
    use rand::Rng;
    if rng.random() {
        if let Some(t) = super::toml_mutate::mutate_toml(seed, rng) {
            return t.into_bytes();
        }
    }
    super::mutate::mutate_text(seed, rng)
}

/// Byte positions where HDF5 keeps its metadata (superblock, object headers, B-trees, heaps):
/// mutations aimed there reach the library's parsers instead of raw data.
pub fn hdf5_metadata_offsets(bytes: &[u8]) -> Vec<usize> {
    const SIGNATURES: [&[u8]; 12] = [b"\x89HDF", b"OHDR", b"OCHK", b"TREE", b"HEAP", b"SNOD", b"BTHD", b"BTLF", b"FRHP", b"FHDB", b"FHIB", b"GCOL"];
    let mut out = Vec::new();
    for sig in SIGNATURES {
        out.extend(bytes.windows(sig.len()).enumerate().filter(|(_, w)| *w == sig).map(|(i, _)| i));
    }
    out.sort_unstable();
    out
}

/// 1 to 4 byte mutations of an HDF5 file, most of them within 96 bytes after a metadata signature.
pub fn mutate_hdf5(bytes: &[u8], offsets: &[usize], rng: &mut ChaCha8Rng) -> Vec<u8> {
    use rand::Rng;
    let mut d = bytes.to_vec();
    for _ in 0..rng.random_range(1..=4) {
        let pos = match rng.random_range(0..10) {
            0..=5 if !offsets.is_empty() => offsets[rng.random_range(0..offsets.len())] + rng.random_range(0..96),
            6 => rng.random_range(0..512.min(d.len().max(1))),
            _ => rng.random_range(0..d.len().max(1)),
        };
        if rng.random_range(0..40) == 0 {
            d.truncate(pos);
        } else {
            super::mutate::mutate_at(&mut d, pos, rng);
        }
    }
    d
}

/// `e` with its context chain on one line (what the binaries print).
pub fn line(e: impl std::fmt::Display) -> String {
    format!("{e:#}").replace('\n', " ")
}
