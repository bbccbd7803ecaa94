//! Shared fixtures of the sweep tests: a paper-like base scene, sweep files, and a cheap fake run executor.
#![allow(dead_code)]

use rbc::sweep::SweepError;
use rbc_schema::results::*;
use rbc_schema::sweep::{Sweep, SweepRun};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The paper's channel (schema-valid; the solver's periodic channel is not needed by the fake).
pub static BASE_SCENE: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    format!(
        r#"
name = "paper-channel"
[cell]
shape = "discocyte"
level = 2
{}[time]
end_s = 40.0
output_interval_s = 0.001
"#,
        rbc_schema::paper_scene::channel_blocks(5.0, 1000.0)
    )
});

/// 3 velocities x 4 offsets x 2 start shapes = 24 runs.
pub const SWEEP: &str = r##"
base_scene = "base.toml"
mean_velocity_mm_s = [1.0, 2.5, 6.5]
r_init_um = [0.0, 0.4, 0.8, 1.2]
start_shapes = ["discocyte", "slipper"]
threads_per_run = 2
[start_shape.slipper]
shape = "mesh-from-results"
results = "starts.h5"
run = "slipper-start"
[slurm]
partition = "compute"
time = "2-00:00:00"
max_concurrent = 4
extra = ["#SBATCH --constraint=avx2"]
"##;

/// Write base scene and sweep file into `dir`; returns the sweep path.
pub fn write_sweep(dir: &Path, sweep: &str) -> PathBuf {
    std::fs::write(dir.join("base.toml"), &*BASE_SCENE).unwrap();
    let p = dir.join("sweep.toml");
    std::fs::write(&p, sweep).unwrap();
    p
}

/// The synthetic outcome of a run: croissant below r_trans = 0.7 um (discocyte) / 0.5 um (slipper start).
pub fn fake_shape(run: &SweepRun) -> FinalShape {
    let r_trans = if run.start_shape == "slipper" {
        0.5
    } else {
        0.7
    };
    if run.r_init_um < r_trans {
        FinalShape::Croissant
    } else {
        FinalShape::Slipper
    }
}

/// A tetrahedron (4 vertices) as the "mesh" of the fake runs.
pub const TETRA: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

/// Behaviour of the fake executor for one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    Finish,
    /// Record the run as failed (a diagnosed blow-up).
    Fail,
    /// Leave the run half written (status running) and return an error, like a kill.
    Crash,
}

/// A fake executor: writes a few samples and a summary through rbc_schema::results, counts calls.
pub struct Fake {
    pub calls: Mutex<Vec<String>>,
    pub mode: fn(&SweepRun) -> Mode,
}

impl Fake {
    pub fn new(mode: fn(&SweepRun) -> Mode) -> Self {
        Fake {
            calls: Mutex::new(Vec::new()),
            mode,
        }
    }

    pub fn calls(&self) -> Vec<String> {
        let mut c = self.calls.lock().unwrap().clone();
        c.sort();
        c
    }

    pub fn execute(&self, _sweep: &Sweep, run: &SweepRun, out: &Path) -> Result<(), SweepError> {
        self.calls.lock().unwrap().push(run.run_id.clone());
        let mut f = ResultsFile::create_or_open(out)?;
        if f.has_run(&run.run_id) {
            f.remove_run(&run.run_id)?;
        }
        let attrs = rbc::sweep::run_attrs(run, 5.0);
        let mut w = f.begin_run(&run.run_id, &attrs, &TETRA)?;
        let shape = fake_shape(run);
        let y = if shape == FinalShape::Slipper {
            1.2
        } else {
            0.0
        };
        for k in 0..5 {
            let t = k as f64 * 0.01;
            w.append_sample(&TimeSample {
                t_s: t,
                centroid_um: [run.velocity_mm_s * 1000.0 * t, y, 0.0],
                velocity_mm_s: [run.velocity_mm_s, 0.0, 0.0],
                area_um2: 140.0,
                volume_um3: 100.0,
                asphericity: 0.2,
                extents_um: [8.0, 6.0, 3.0],
            })?;
        }
        w.append_snapshot(
            0.04,
            &[
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
        )?;
        match (self.mode)(run) {
            Mode::Finish => {
                let mut evidence = BTreeMap::new();
                evidence.insert("steady_duration_s".into(), 0.04);
                w.finish(&RunSummary {
                    status: if shape == FinalShape::Slipper {
                        RunStatus::Periodic
                    } else {
                        RunStatus::Steady
                    },
                    final_shape: shape,
                    tank_treading: shape == FinalShape::Slipper,
                    tumbling: false,
                    mean_velocity_mm_s: run.velocity_mm_s,
                    min_velocity_mm_s: run.velocity_mm_s * 0.98,
                    max_velocity_mm_s: run.velocity_mm_s * 1.02,
                    mean_radial_um: y,
                    mean_y_um: y,
                    mean_z_um: 0.0,
                    evidence,
                })?;
                Ok(())
            }
            Mode::Fail => {
                w.fail("fake blow-up at t = 0.04 s")?;
                Ok(())
            }
            Mode::Crash => {
                w.flush()?;
                Err(SweepError::Run {
                    run_id: run.run_id.clone(),
                    message: "killed".into(),
                })
            }
        }
    }
}

/// Statuses of every run in a results file.
pub fn statuses(path: &Path) -> BTreeMap<String, RunStatus> {
    read_runs(path)
        .unwrap()
        .into_iter()
        .map(|r| (r.run_id, r.status))
        .collect()
}
