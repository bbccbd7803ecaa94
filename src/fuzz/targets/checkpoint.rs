//! Checkpoints (`<results>.<run>.ckpt`): a small run's real checkpoint with its fields or bytes mutated, resumed as
//! `rbc-simulate --resume` does (reopen, restore the observer, continue the run to its end) and read by
//! `rbc-sweep --study-status`.

use super::{hdf5_metadata_offsets, line, mutate_hdf5, put, Target};
use crate::fuzz::mutate::mutate_text;
use anyhow::{bail, Context, Result};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rbc_schema::checkpoint::{self, Checkpoint};
use rbc_schema::results::{ResultsFile, RunAttrs};
use rbc_schema::scene::Scene;
use rbc_solver::run::checkpoint::RunState;
use rbc_solver::run::persist::{self, CheckpointPolicy, CheckpointWriter};
use rbc_solver::run::results::ResultsObserver;
use rbc_solver::run::{Fanout, Observer, Sample};
use rbc_solver::SolverError;
use std::path::{Path, PathBuf};

/// A capsule of 32 triangles in shear, 8 output samples: milliseconds per run.
const SCENE: &str = r#"name = "cap"
[cell]
shape = "sphere"
level = 1
radius_um = 3.0
[membrane.skalak]
convention = "barthes-biesel"
shear_modulus_n_m = 5e-6
c = 1.0
[fluid]
viscosity_pa_s = 1.2e-3
lambda = 1.0
[flow]
kind = "shear"
shear_rate_1_s = 100.0
[time]
end_s = 0.004
output_interval_s = 0.0005
"#;

const RUN: &str = "cap";
const RESULTS: &str = "r.h5";

/// Seeds: results.h5 of the capsule run left `running` at its fourth checkpoint, and that checkpoint.
pub struct CheckpointFile {
    results: Vec<u8>,
    ckpt: Vec<u8>,
    offsets: Vec<usize>,
    decoded: Checkpoint,
}

/// Copies the results file and the checkpoint when the `at`-th checkpoint has been written:
/// the state a `SIGKILL` right after that checkpoint leaves behind.
struct Grab {
    at: usize,
    seen: usize,
    from: [PathBuf; 2],
    to: [PathBuf; 2],
}

impl Observer for Grab {
    fn sample(&mut self, _s: &Sample<'_>) -> Result<(), SolverError> {
        Ok(())
    }
    fn checkpoint(&mut self, _state: &RunState) -> Result<(), SolverError> {
        self.seen += 1;
        if self.seen == self.at {
            for (a, b) in self.from.iter().zip(&self.to) {
                std::fs::copy(a, b).map_err(|e| SolverError::Output(format!("{}: {e}", a.display())))?;
            }
        }
        Ok(())
    }
}

impl CheckpointFile {
    pub fn prepare(scratch: &Path) -> Result<Self> {
        let dir = scratch.join("run");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir)?;
        let out = dir.join(RESULTS);
        let scene = Scene::parse(SCENE, &dir.join("scene.toml"))?;
        let built = rbc_solver::scene::build(&scene)?;
        let mut file = ResultsFile::create_or_open(&out)?;
        let attrs = RunAttrs { start_shape: "sphere".into(), r_init_um: 0.0, y_init_um: 0.0, z_init_um: 0.0, lambda: 1.0, scene: SCENE.into() };
        let tris: Vec<[u32; 3]> = built.mesh.triangles.iter().map(|t| [t[0] as u32, t[1] as u32, t[2] as u32]).collect();
        let writer = file.begin_run(RUN, &attrs, &tris)?;
        let policy = CheckpointPolicy { every_outputs: 1, every_wall_s: 0.0 };
        let ck_path = checkpoint::checkpoint_path(&out, RUN);
        let mut results = ResultsObserver::new(writer, 2).with_checkpoints(CheckpointWriter::new(&out, RUN, SCENE, policy));
        let seed = [scratch.join(RESULTS), scratch.join("seed.ckpt")];
        let mut grab = Grab { at: 4, seen: 0, from: [out.clone(), ck_path], to: seed.clone() };
        built.run(&mut Fanout(vec![&mut results, &mut grab]))?;
        if grab.seen < grab.at {
            bail!("the seed run took {} checkpoints, fewer than {}", grab.seen, grab.at);
        }
        let ckpt = std::fs::read(&seed[1]).context("seed checkpoint")?;
        let decoded = checkpoint::read(&seed[1])?;
        Ok(CheckpointFile { results: std::fs::read(&seed[0])?, offsets: hdf5_metadata_offsets(&ckpt), ckpt, decoded })
    }

    /// The decoded checkpoint with one to three fields changed: removed, emptied, shortened, lengthened,
    /// an element made NaN / infinite / huge / negative, the counts, time, run id or scene text changed.
    fn mutate_fields(&self, rng: &mut ChaCha8Rng) -> Checkpoint {
        const NASTY: [f64; 9] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e308, -1.0, 0.0, 1e20, 0.5, 4294967296.0];
        let mut ck = self.decoded.clone();
        for _ in 0..rng.random_range(1..=3) {
            let names: Vec<String> = ck.fields.keys().cloned().collect();
            match rng.random_range(0..12) {
                0 => ck.t_s = NASTY[rng.random_range(0..NASTY.len())],
                1 => ck.n_samples = [0, 1, 3, 100, usize::MAX, 1 << 40][rng.random_range(0..6)],
                2 => ck.n_snapshots = [0, 1, 3, 100, usize::MAX][rng.random_range(0..5)],
                3 => ck.run_id = ["", "other", "cap-2"][rng.random_range(0..3)].into(),
                4 => ck.scene = String::from_utf8_lossy(&mutate_text(&ck.scene, rng)).into_owned(),
                _ => {
                    let name = &names[rng.random_range(0..names.len())];
                    match rng.random_range(0..5) {
                        0 => {
                            ck.fields.remove(name);
                        }
                        1 => ck.fields.get_mut(name).expect("listed").clear(),
                        2 => {
                            let v = ck.fields.get_mut(name).expect("listed");
                            let keep = rng.random_range(0..=v.len());
                            v.truncate(keep);
                        }
                        3 => {
                            let v = ck.fields.get_mut(name).expect("listed");
                            let extra = rng.random_range(1..=4);
                            v.extend(std::iter::repeat_n(1.0, extra));
                        }
                        _ => {
                            let v = ck.fields.get_mut(name).expect("listed");
                            if !v.is_empty() {
                                let i = rng.random_range(0..v.len());
                                v[i] = NASTY[rng.random_range(0..NASTY.len())];
                            }
                        }
                    }
                }
            }
        }
        ck
    }
}

/// `rbc-simulate SCENE --out RESULTS --resume` (the run `cap`) in-process: reopen the run at its checkpoint,
/// restore the observer and continue the run to its end.
fn resume(scene_path: &Path, out: &Path) -> Result<(), String> {
    let scene = Scene::read(scene_path).map_err(line)?;
    let built = rbc_solver::scene::build(&scene).map_err(line)?;
    let mut file = ResultsFile::create_or_open(out).map_err(line)?;
    let same = |stored: &str| Scene::parse(stored, scene_path).is_ok_and(|old| Scene { source: String::new(), ..old } == Scene { source: String::new(), ..scene.clone() });
    let where_ = format!("run `{RUN}` in {}", out.display());
    let reopened = match persist::reopen(&mut file, RUN, &same).map_err(|e| format!("{where_}: {e}"))? {
        Ok(r) => r,
        Err(why) => return Err(format!("{where_}: not resumable: {why:?}")),
    };
    let checkpoints = CheckpointWriter::new(out, RUN, &scene.source, CheckpointPolicy::default());
    let mut results = ResultsObserver::resumed(reopened, checkpoints).map_err(|e| format!("{where_}: {e}"))?;
    built.run(&mut Fanout(vec![&mut results])).map_err(|e| format!("{}, {where_}: {e}", scene_path.display()))?;
    Ok(())
}

impl Target for CheckpointFile {
    fn write_case(&self, rng: &mut ChaCha8Rng, case: &Path) -> Result<(), String> {
        put(&case.join("scene.toml"), SCENE.as_bytes())?;
        let out = case.join(RESULTS);
        put(&out, &self.results)?;
        let ck_path = checkpoint::checkpoint_path(&out, RUN);
        if rng.random() {
            checkpoint::write(&ck_path, &self.mutate_fields(rng)).map_err(|e| format!("harness: {e}"))
        } else {
            put(&ck_path, &mutate_hdf5(&self.ckpt, &self.offsets, rng))
        }
    }

    fn exercise(&self, case: &Path) -> Result<(), String> {
        let out = case.join(RESULTS);
        // both readers see the case (the status table does not change the files; the resume does)
        let status = crate::sweep::study::run_progress(&out, RUN, &Default::default(), None).map(|_| ()).map_err(line);
        let resumed = resume(&case.join("scene.toml"), &out);
        status.and(resumed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A checkpoint with one vertex fewer than its scene's mesh (`rbc-bench fuzz --format checkpoint --seed 2
    /// --case 139`) made `rbc-sweep --study-status` index out of bounds in the shape classifier; it is now
    /// refused naming the checkpoint and the field, and the resume refuses it too.
    #[test]
    fn a_checkpoint_with_a_vertex_missing_is_refused_by_the_status_table_and_the_resume() {
        let dir = std::env::temp_dir().join(format!("rbc-fuzz-ck-test-{}", std::process::id()));
        let seeds = CheckpointFile::prepare(&dir.join("seeds")).unwrap();
        let case = dir.join("case");
        std::fs::create_dir_all(&case).unwrap();
        put(&case.join("scene.toml"), SCENE.as_bytes()).unwrap();
        let out = case.join(RESULTS);
        put(&out, &seeds.results).unwrap();
        put(&checkpoint::checkpoint_path(&out, RUN), &seeds.ckpt).unwrap();
        assert_eq!(seeds.exercise(&case), Ok(()), "the seed checkpoint resumes");
        put(&out, &seeds.results).unwrap();
        let mut ck = seeds.decoded.clone();
        let v = ck.fields.get_mut("runner.vertices_um").unwrap();
        assert_eq!(v.len(), 18 * 3, "level 1: 18 vertices");
        v.truncate(17 * 3);
        checkpoint::write(&checkpoint::checkpoint_path(&out, RUN), &ck).unwrap();
        let e = crate::sweep::study::run_progress(&out, RUN, &Default::default(), None).unwrap_err().to_string();
        assert!(e.contains("r.h5.cap.ckpt") && e.contains("runner.vertices_um") && e.contains("17 vertices"), "{e}");
        let e = resume(&case.join("scene.toml"), &out).unwrap_err();
        assert!(e.contains("r.h5") && e.contains("17"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
