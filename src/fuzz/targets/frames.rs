//! PNG/TIFF frames: mutated bytes, PNG chunks with valid checksums and valid images of odd sizes and depths,
//! one to three per recording, analysed as `rbc-analyze` does.

use super::recording::{analyse_recording, example_frames, example_recording};
use super::{put, read, Target};
use crate::fuzz::images::{encode, mutate_png_chunk, odd_image};
use crate::fuzz::mutate::mutate_bytes;
use anyhow::Result;
use image::ImageFormat;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::path::Path;

/// Seeds: example PNG frames, the same frames as 8- and 16-bit TIFF and 16-bit PNG.
pub struct Frames {
    recording_toml: Vec<u8>,
    /// (extension, bytes) of valid frames.
    seeds: Vec<(&'static str, Vec<u8>)>,
}

impl Frames {
    pub fn prepare() -> Result<Self> {
        let mut seeds: Vec<(&'static str, Vec<u8>)> = example_frames(3)?.into_iter().map(|(_, b)| ("png", b)).collect();
        let img = image::load_from_memory(&seeds[0].1)?;
        let wide = image::DynamicImage::ImageLuma16(img.to_luma16());
        seeds.push(("tif", encode(&img, ImageFormat::Tiff)));
        seeds.push(("tif", encode(&wide, ImageFormat::Tiff)));
        seeds.push(("png", encode(&wide, ImageFormat::Png)));
        Ok(Frames { recording_toml: read(&example_recording().join("recording.toml"))?, seeds })
    }

    /// One damaged or odd frame: (extension, bytes).
    fn bad_frame(&self, rng: &mut ChaCha8Rng) -> (&'static str, Vec<u8>) {
        let (seed_ext, seed) = &self.seeds[rng.random_range(0..self.seeds.len())];
        let seed_ext: &'static str = seed_ext;
        let (mut ext, bytes): (&'static str, Vec<u8>) = match rng.random_range(0..10) {
            0..=3 if seed_ext == "png" => (seed_ext, mutate_png_chunk(seed, rng)),
            0..=5 => (seed_ext, mutate_bytes(seed, rng, 4)),
            _ => {
                let (bytes, ext) = odd_image(rng);
                (ext, bytes)
            }
        };
        if rng.random_range(0..20) == 0 {
            ext = if ext == "png" { "tiff" } else { "PNG" };
        }
        (ext, bytes)
    }
}

impl Target for Frames {
    fn write_case(&self, rng: &mut ChaCha8Rng, case: &Path) -> Result<(), String> {
        put(&case.join("recording.toml"), &self.recording_toml)?;
        let n = rng.random_range(1..=3);
        let bad = rng.random_range(0..n);
        for i in 0..n {
            let (ext, bytes) = if i == bad { self.bad_frame(rng) } else { ("png", self.seeds[i % 3].1.clone()) };
            put(&case.join(format!("frame_{i:05}.{ext}")), &bytes)?;
        }
        Ok(())
    }

    fn exercise(&self, case: &Path) -> Result<(), String> {
        analyse_recording(case)
    }
}
