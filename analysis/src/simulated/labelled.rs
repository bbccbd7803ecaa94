//! Labelled synthetic tracks for the shape classifier: the synthesiser's random recordings over
//! pixel sizes, noise and velocities, analysed by `rbc-analyze`'s pipeline, each track with the
//! truth shape of the cell it follows.
//!
//! A [`SeedSet`] is the grid [`PIXEL_SIZES_UM`] x [`NOISE_SIGMAS`] x [`VELOCITIES_MM_S`] with
//! `per_condition` seeds each, numbered from `first` in that loop order; every recording is
//! [`random_spec`] (two cells, each a croissant, slipper or irregular cell with probability
//! 1/3). The classifier's thresholds were read off [`FIT_SEEDS`] (`rbc-bench
//! classifier-features`) and its probability calibration fitted on them; [`HELD_OUT_SEEDS`]
//! shares no seed with it and checks the calibration (`rbc-bench shape-calibration`,
//! `analysis/tests/tracks_calibration.rs`). Tracks are matched to truth cells by position, never
//! by label ([`crate::simulated::robustness::score`]); false and mixed tracks are left out.

use crate::error::AnalysisError;
use crate::simulated::robustness::score_recording;
use crate::simulated::synth::{condition_spec, random_conditions, random_spec, write_recording, SynthSpec};
use rayon::prelude::*;
use std::path::Path;

/// Pixel sizes of the grid, um per pixel in the object plane.
pub const PIXEL_SIZES_UM: [f64; 3] = [0.15, 0.25, 0.35];
/// Read noise of the grid, fraction of full scale.
pub const NOISE_SIGMAS: [f64; 2] = [0.005, 0.02];
/// Cell velocities of the grid, mm/s.
pub const VELOCITIES_MM_S: [f64; 4] = [0.1, 1.0, 3.0, 12.0];

/// One synthetic recording of a seed set: its seed and imaging condition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordingCase {
    pub seed: u64,
    pub um_per_px: f64,
    pub noise_sigma: f64,
    pub velocity_mm_s: f64,
}

/// Seeds `first`, `first + 1`, ... over the grid, `per_condition` recordings per condition; and
/// `random` recordings of three cells under a lab's conditions drawn at random
/// ([`random_conditions`]: defocus, NA, blur, noise, 0.1-0.4 um/px, walls, debris, neighbours;
/// [`condition_spec`]), seeds `first + RANDOM_OFFSET`, ...
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeedSet {
    pub first: u64,
    pub per_condition: usize,
    pub random: usize,
}

/// Seed of a set's first random-conditions recording, relative to `first`.
pub const RANDOM_OFFSET: u64 = 5_000;

/// The set the classifier was tuned and calibrated on: seeds 90001-90096, 4 per condition, and
/// 48 random-conditions recordings, seeds 95001-95048.
pub const FIT_SEEDS: SeedSet = SeedSet { first: 90_001, per_condition: 4, random: 48 };
/// The held-out set: seeds 190001-190096, 4 per condition, and 195001-195048 (disjoint from [`FIT_SEEDS`]).
pub const HELD_OUT_SEEDS: SeedSet = SeedSet { first: 190_001, per_condition: 4, random: 48 };

impl SeedSet {
    /// The recordings of the set, in seed order (pixel size, then noise, then velocity outermost first).
    pub fn recordings(&self) -> Vec<RecordingCase> {
        let mut out = Vec::new();
        let mut seed = self.first;
        for um_per_px in PIXEL_SIZES_UM {
            for noise_sigma in NOISE_SIGMAS {
                for velocity_mm_s in VELOCITIES_MM_S {
                    for _ in 0..self.per_condition {
                        out.push(RecordingCase { seed, um_per_px, noise_sigma, velocity_mm_s });
                        seed += 1;
                    }
                }
            }
        }
        out
    }

    /// Seeds of the random-conditions recordings.
    pub fn random_seeds(&self) -> std::ops::Range<u64> {
        let start = self.first + RANDOM_OFFSET;
        start..start + self.random as u64
    }
}

/// A track of a synthetic recording with the truth shape of its cell.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledTrack {
    /// Seed of the recording.
    pub seed: u64,
    /// Truth shape: `croissant`, `slipper` or `other` (an irregular cell).
    pub truth: String,
    /// Label the classifier gave.
    pub label: String,
    /// The classifier's `shape_score`.
    pub score: f64,
}

impl LabelledTrack {
    /// The cell is a croissant (the positive class of the calibration).
    pub fn is_croissant(&self) -> bool {
        self.truth == "croissant"
    }
}

/// Render every recording of `seeds` under `dir` (one folder each, removed after its analysis),
/// analyse it with the pipeline's default stages and return its matched tracks, in seed order.
/// Recordings run in parallel on the current rayon pool.
pub fn labelled_tracks(dir: &Path, seeds: &SeedSet) -> Result<Vec<LabelledTrack>, AnalysisError> {
    let grid = seeds
        .recordings()
        .into_iter()
        .map(|c| (c.seed, random_spec(c.seed, c.um_per_px, c.noise_sigma, c.velocity_mm_s)));
    let random = seeds.random_seeds().map(|seed| (seed, condition_spec(seed, &random_conditions(seed))));
    let specs: Vec<(u64, SynthSpec)> = grid.chain(random).collect();
    let per_recording: Vec<Result<Vec<LabelledTrack>, AnalysisError>> = specs
        .par_iter()
        .map(|(seed, spec)| {
            let rec = dir.join(format!("rec{seed}"));
            write_recording(&rec, spec, *seed)?;
            let score = score_recording(&rec, dir)?;
            let _ = std::fs::remove_dir_all(&rec);
            Ok(score
                .shapes
                .into_iter()
                .zip(score.shape_scores)
                .map(|((truth, label), score)| LabelledTrack { seed: *seed, truth, label, score })
                .collect())
        })
        .collect();
    let mut out = Vec::new();
    for r in per_recording {
        out.extend(r?);
    }
    Ok(out)
}
