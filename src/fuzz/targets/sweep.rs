//! Sweep TOML: mutated example sweeps beside their base scenes, validated and expanded as `rbc-sweep --list` does.

use super::scene::scene_files;
use super::{examples, line, mutate_toml_text, put, read, Target};
use anyhow::Result;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rbc_schema::scene::Scene;
use rbc_schema::sweep::Sweep;
use std::path::Path;

/// Seeds: the example sweeps; every base scene is written beside the mutated sweep.
pub struct SweepToml {
    seeds: Vec<String>,
    /// (file name, bytes) of the base scenes.
    scenes: Vec<(String, Vec<u8>)>,
}

impl SweepToml {
    pub fn prepare() -> Result<Self> {
        let mut seeds = Vec::new();
        for name in ["demo-channel.toml", "demo-poiseuille.toml", "paper-phase-diagram.toml", "science-6p5.toml"] {
            seeds.push(String::from_utf8(read(&examples().join("sweeps").join(name))?)?);
        }
        let scenes = scene_files()?
            .into_iter()
            .filter(|p| p.parent().is_some_and(|d| d.ends_with("sweeps")))
            .map(|p| Ok((p.file_name().unwrap_or_default().to_string_lossy().into_owned(), read(&p)?)))
            .collect::<Result<_>>()?;
        Ok(SweepToml { seeds, scenes })
    }
}

impl Target for SweepToml {
    fn write_case(&self, rng: &mut ChaCha8Rng, case: &Path) -> Result<(), String> {
        for (name, bytes) in &self.scenes {
            put(&case.join(name), bytes)?;
        }
        let seed = &self.seeds[rng.random_range(0..self.seeds.len())];
        put(&case.join("sweep.toml"), &mutate_toml_text(seed, rng))
    }

    fn exercise(&self, case: &Path) -> Result<(), String> {
        let path = case.join("sweep.toml");
        let sweep = Sweep::read(&path).map_err(line)?;
        let runs = sweep.runs().map_err(line)?;
        for r in &runs {
            Scene::parse(&r.scene_text, &sweep.base_scene).map_err(|e| line(anyhow::Error::new(e).context(format!("{}: run {}", path.display(), r.run_id))))?;
        }
        Ok(())
    }
}
