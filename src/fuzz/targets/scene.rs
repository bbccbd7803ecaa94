//! Scene TOML: mutated example scenes, validated as `rbc-simulate` does and, when cheap (free space, mesh level <= 3),
//! assembled by the solver (`rbc_solver::scene::build`).

use super::{examples, line, mutate_toml_text, put, read, Target};
use anyhow::Result;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rbc_schema::scene::{Scene, WallsSpec};
use std::path::Path;

/// Seeds: `examples/scenes/*.toml` and the base scenes of the example sweeps.
pub struct SceneToml {
    seeds: Vec<String>,
}

/// Example scene files: `examples/scenes/*.toml` and the sweeps' base scenes.
pub fn scene_files() -> Result<Vec<std::path::PathBuf>> {
    let mut files: Vec<_> = std::fs::read_dir(examples().join("scenes"))?.flatten().map(|e| e.path()).collect();
    for name in ["demo-capsule.toml", "demo-channel-scene.toml", "paper-channel.toml", "science-6p5-scene.toml"] {
        files.push(examples().join("sweeps").join(name));
    }
    files.retain(|p| p.extension().is_some_and(|e| e == "toml"));
    files.sort();
    Ok(files)
}

impl SceneToml {
    pub fn prepare() -> Result<Self> {
        let seeds = scene_files()?.iter().map(|p| Ok(String::from_utf8(read(p)?)?)).collect::<Result<_>>()?;
        Ok(SceneToml { seeds })
    }
}

/// Largest mesh level the fuzzer assembles (level 3: 512 triangles, milliseconds).
const MAX_BUILD_LEVEL: u32 = 3;

impl Target for SceneToml {
    fn write_case(&self, rng: &mut ChaCha8Rng, case: &Path) -> Result<(), String> {
        let seed = &self.seeds[rng.random_range(0..self.seeds.len())];
        put(&case.join("scene.toml"), &mutate_toml_text(seed, rng))
    }

    fn exercise(&self, case: &Path) -> Result<(), String> {
        let path = case.join("scene.toml");
        let scene = Scene::read(&path).map_err(line)?;
        // the periodic channel assembles a dense wall operator (seconds): validated only
        if scene.walls == WallsSpec::None && scene.cell.level <= MAX_BUILD_LEVEL {
            let built = rbc_solver::scene::build(&scene).map_err(|e| line(anyhow::Error::new(e).context(path.display().to_string())))?;
            std::hint::black_box(built);
        }
        Ok(())
    }
}
