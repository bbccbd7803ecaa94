//! `recording.toml`: mutated metadata beside three valid example frames, analysed as `rbc-analyze` does.

use super::{examples, line, mutate_toml_text, put, read, Target};
use anyhow::Result;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rbc_analysis::experiment::pipeline::{self, StageConfig};
use std::path::Path;

/// Seeds: the example recordings' `recording.toml` (with and without `[channel]`, one with `axis_row_px`).
pub struct RecordingToml {
    seeds: Vec<String>,
    /// Valid frames written beside the mutated metadata: (file name, bytes).
    frames: Vec<(String, Vec<u8>)>,
}

/// The example recording whose frames the recording and frame cases use.
pub fn example_recording() -> std::path::PathBuf {
    examples().join("frames/p100mbar_x00mm")
}

/// The first `n` frames of the example recording.
pub fn example_frames(n: usize) -> Result<Vec<(String, Vec<u8>)>> {
    (0..n).map(|i| {
        let name = format!("frame_{i:05}.png");
        Ok((name.clone(), read(&example_recording().join(&name))?))
    })
    .collect()
}

impl RecordingToml {
    pub fn prepare() -> Result<Self> {
        let mut seeds = Vec::new();
        for e in std::fs::read_dir(examples().join("frames"))?.flatten() {
            let p = e.path().join("recording.toml");
            if p.exists() {
                seeds.push(String::from_utf8(read(&p)?)?);
            }
        }
        seeds.sort();
        let with_axis = seeds[0].clone() + "axis_row_px = 37.0\n";
        seeds.push(with_axis);
        seeds.push("fps = 400.0\num_per_px = 0.3\npressure_mbar = 100.0\nposition_mm = 10.0\n".to_string());
        Ok(RecordingToml { seeds, frames: example_frames(3)? })
    }
}

/// Analyse the recording in `dir` as `rbc-analyze` does: open and detect (`pipeline::detect_dir`), then tracks,
/// isolation, classification and groups.
pub fn analyse_recording(dir: &Path) -> Result<(), String> {
    let root = dir.parent().unwrap_or(dir);
    let found = pipeline::find_recordings(dir).map_err(line)?;
    let (outputs, _) = pipeline::analyse_all(&found, |d| pipeline::detect_dir(d, root), &StageConfig::default(), |_| {}).map_err(line)?;
    std::hint::black_box(outputs);
    Ok(())
}

impl Target for RecordingToml {
    fn write_case(&self, rng: &mut ChaCha8Rng, case: &Path) -> Result<(), String> {
        let seed = &self.seeds[rng.random_range(0..self.seeds.len())];
        put(&case.join("recording.toml"), &mutate_toml_text(seed, rng))?;
        for (name, bytes) in &self.frames {
            put(&case.join(name), bytes)?;
        }
        Ok(())
    }

    fn exercise(&self, case: &Path) -> Result<(), String> {
        analyse_recording(case)
    }
}
