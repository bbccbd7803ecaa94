//! Sweep TOML files (`rbc-sweep`): a base scene plus a grid of velocity x initial offset x start shape, expanded into one scene per run.
//!
//! ```toml
//! base_scene = "paper-channel.toml"       # relative to this file
//! mean_velocity_mm_s = [0.5, 1.0, 2.5]    # imposed mean flow (mm/s), or { from = 0.5, to = 10.0, n = 12, spacing = "log" }
//! r_init_um = { from = 0.0, to = 2.0, n = 9 }   # initial centroid offset (um), or a list
//! start_shapes = ["discocyte", "croissant"]
//! # velocity_key = "walls.mean_velocity_um_s"   # scene field set to 1000 x the velocity (um/s);
//! #                                             # e.g. "flow.max_velocity_um_s" for an unbounded Poiseuille scene
//! threads_per_run = 1                     # threads given to one run (local jobs = cores / this; Slurm cpus-per-task)
//! snapshot_every = 50                     # store all vertices every N-th output sample
//! checkpoint_interval_s = 60.0            # wall-clock seconds between a run's checkpoints (what a kill loses)
//!
//! [start_shape.croissant]                 # the scene's [cell] table for this start shape; replaces the
//! shape = "mesh-from-results"             # base scene's cell except `level` and `position_um`
//! results = "starts.h5"                   # relative to this file
//! run = "croissant"                       # (`rbc-sweep start-shape` copies an ended run's last shape there)
//! # [start_shape.discocyte] defaults to { shape = "discocyte", axis = [1, 0, 0] } (axis along the flow)
//!
//! [[also]]                                # optional further grids, numbered after the main one
//! mean_velocity_mm_s = [1.5]              # (e.g. two offsets at a second velocity only); each
//! r_init_um = [0.4, 1.2]                  # with its own velocities and offsets, and start
//! # start_shapes = ["discocyte"]          # shapes (default: the main grid's list); a shape the
//!                                         # main list does not name needs its [start_shape.X] table
//! # overrides = { "integrator.scheme" = "ros34prw-mobility" }   # scene fields set in this grid's
//!                                         # runs only, after [overrides] (e.g. a step method for a
//!                                         # velocity whose steps need another)
//!
//! [overrides]                             # optional scene fields set in every run (dotted keys)
//! "integrator.scheme" = "ros2"
//!
//! [steady]                                # optional, see rbc_solver::steady (defaults there)
//! window_s = 1.0                          # the shortest window; an orbit whose min_cycles + 1
//!                                         # periods exceed it is judged over them (up to 4 windows)
//! max_time_s = 40.0                       # also written to the scene's time.end_s
//! position_tol_um = 0.05
//! asphericity_tol = 0.005
//! min_cycles = 3
//!
//! [classify]                              # optional, see rbc_solver::classify
//! centred_um = 0.6
//! symmetric_rel = 0.05
//! rigid_rel = 0.001
//! frames = 25                             # classification frames: the last ones, ...
//! frame_interval_s = 0.004                # ... this far apart (rounded to whole output intervals; default 2 ms)
//! # frame_travel_um = 10.0                # or: as far apart as the mean flow travels 10 um (per run)
//!
//! [slurm]                                 # optional, for `rbc-sweep SWEEP --slurm DIR`
//! partition = "compute"
//! time = "7-00:00:00"
//! mem = "4G"
//! account = "mylab"
//! max_concurrent = 64
//! stop_before_limit_s = 600               # signal a task this long before its time limit: it stops at a
//!                                         # checkpoint and requeues itself (default: 600 s, at most time / 4)
//! extra = ["#SBATCH --constraint=avx2"]
//! ```
//!
//! Every run is a scene: the base scene with `cell.position_um = [x0, y, z]`,
//! `y = r 9 / sqrt(106)`, `z = r 5 / sqrt(106)` (the paper's offset line
//! `z = 5 y / 9`, `r = sqrt(y^2 + z^2)`; `x0` from the base scene), the start
//! shape's cell table, the velocity written to `velocity_key`, then
//! `[overrides]`, then its `[[also]]` grid's `overrides`. Runs are numbered start shape major, then velocity, then
//! offset, the main grid first and each `[[also]]` grid after it in file order (so
//! appending a grid keeps the numbers of the runs before it); a run id may occur only once.
//! Run ids (`<shape>_u<velocity>_r<offset>`, numbers in Rust's
//! shortest round-trip form) do not depend on the grid, so a sweep extended
//! later resumes without renaming finished runs.
//!
//! Parsing is in two stages (raw serde structs with unknown fields refused, `sweep/raw.rs`, then
//! validation, `sweep/validate.rs`); every error is one line naming the file and the field.

use crate::error::{Result, SchemaError};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

mod raw;
mod validate;

pub use validate::slurm_time_s;

/// Steady-state criterion settings (`None`: the solver's default).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SteadySettings {
    pub window_s: Option<f64>,
    pub max_time_s: Option<f64>,
    pub position_tol_um: Option<f64>,
    pub asphericity_tol: Option<f64>,
    pub min_cycles: Option<usize>,
}

/// Classifier settings (`None`: the solver's default).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClassifySettings {
    pub centred_um: Option<f64>,
    pub symmetric_rel: Option<f64>,
    /// Non-rigid vertex speed over centroid speed below which a cell moves as a rigid body.
    pub rigid_rel: Option<f64>,
    /// Number of classification frames (the last ones of the run).
    pub frames: Option<usize>,
    /// Time between two classification frames (s), rounded to a whole number of output
    /// intervals (at least one): the frames span `(frames - 1) * frame_interval_s`, which must
    /// hold the classifier's `min_tt_turns` (0.1 turn; a quarter turn until session 51) of the
    /// slowest tank-treading to be detected.
    pub frame_interval_s: Option<f64>,
    /// Instead of `frame_interval_s`: the distance (um) the imposed mean flow travels between two
    /// classification frames, so that each run's interval is `frame_travel_um / u_mean`. A cell's
    /// tank-treading frequency grows in proportion to the flow (the study's slippers: 1.2 Hz at
    /// ~1 mm/s, 3.7 at 2.5, 5.7 at 4, 8.5 at 6.3 mm/s cell velocity), so the frames then span
    /// about the same fraction of a turn at every velocity of a sweep.
    pub frame_travel_um: Option<f64>,
}

impl ClassifySettings {
    /// Time between two classification frames (s) of a run at imposed mean flow velocity
    /// `mean_velocity_mm_s`: `frame_travel_um / u_mean` when set, else `frame_interval_s`.
    pub fn frame_interval_s_at(&self, mean_velocity_mm_s: f64) -> Option<f64> {
        match self.frame_travel_um {
            Some(d) => Some(d / (mean_velocity_mm_s.abs() * 1e3)),
            None => self.frame_interval_s,
        }
    }
}

/// Slurm settings for the array job.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SlurmSettings {
    pub partition: Option<String>,
    /// Wall-clock limit per task (`D-HH:MM:SS`); default 7 days (the paper's runs took 1 to 29 days on 28 cores).
    pub time: Option<String>,
    pub mem: Option<String>,
    pub account: Option<String>,
    /// At most this many tasks at once (`--array=0-N%max`).
    pub max_concurrent: Option<usize>,
    /// Seconds before the time limit at which a task is signalled to stop at a checkpoint and
    /// requeue itself (`None`: the writer's default); less than half of `time` when both are given.
    pub stop_before_limit_s: Option<u64>,
    /// Extra lines copied into the script header (each must start with `#SBATCH`).
    pub extra: Vec<String>,
}

/// A further grid of a sweep (`[[also]]`): its own velocities, offsets and start shapes, and
/// scene fields of its own.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    /// Imposed mean velocities (mm/s), initial offsets (um), start shape names, in file order.
    pub velocities_mm_s: Vec<f64>,
    pub r_init_um: Vec<f64>,
    pub start_shapes: Vec<String>,
    /// Dotted-key scene overrides of this grid's runs, set after the sweep's `[overrides]`.
    pub overrides: Vec<(String, toml::Value)>,
}

impl Grid {
    fn len(&self) -> usize {
        self.start_shapes.len() * self.velocities_mm_s.len() * self.r_init_um.len()
    }
}

/// A validated sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// The sweep file (for messages and relative paths).
    pub path: PathBuf,
    /// The base scene file (resolved) and its text.
    pub base_scene: PathBuf,
    pub base_text: String,
    /// Imposed mean velocities (mm/s), initial offsets (um), start shape names, in file order.
    pub velocities_mm_s: Vec<f64>,
    pub r_init_um: Vec<f64>,
    pub start_shapes: Vec<String>,
    /// Further grids (`[[also]]`), expanded after the main one in this order.
    pub also: Vec<Grid>,
    /// The `[cell]` table of each start shape (paths resolved against the sweep file).
    pub cells: BTreeMap<String, toml::Table>,
    /// Scene field receiving `1000 x velocity` (um/s).
    pub velocity_key: String,
    /// Extra dotted-key scene overrides.
    pub overrides: Vec<(String, toml::Value)>,
    pub threads_per_run: usize,
    pub snapshot_every: usize,
    /// Wall-clock seconds between the checkpoints of a run (default 60): at most this much
    /// computation is lost when a run is killed.
    pub checkpoint_interval_s: f64,
    pub steady: SteadySettings,
    pub classify: ClassifySettings,
    pub slurm: SlurmSettings,
}

/// One expanded run.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRun {
    /// Position in the expansion (start shape major, then velocity, then offset).
    pub index: usize,
    pub run_id: String,
    pub start_shape: String,
    /// Imposed mean flow velocity (mm/s).
    pub velocity_mm_s: f64,
    /// Initial offset (um) and its components along the paper's line z = 5 y / 9.
    pub r_init_um: f64,
    pub y_init_um: f64,
    pub z_init_um: f64,
    /// The run's scene file text.
    pub scene_text: String,
    /// Why the run is not to be run, when its cell starts in (or closer than the solver allows to)
    /// the channel wall: one line naming `r_init_um` and the overlap. Set by the expansion that
    /// checks each cell against its channel (`rbc::sweep::expand`); `None` from [`Sweep::runs`].
    pub overlaps_wall: Option<String>,
}

/// `y = r 9 / sqrt(106)`, `z = r 5 / sqrt(106)`: the point at distance `r` on the line `z = 5 y / 9` (um).
pub fn offset_yz(r_um: f64) -> (f64, f64) {
    let s = 106f64.sqrt();
    (r_um * 9.0 / s, r_um * 5.0 / s)
}

/// Most runs a sweep may expand to: 30 times the paper's phase diagram (330 runs), each a core-day
/// simulation. Larger grids took `rbc-sweep --list` minutes to expand (`rbc-bench fuzz --format sweep
/// --seed 1 --case 4149`: 3 x 10000 x 10 runs).
pub const MAX_RUNS: usize = 10_000;

fn field(p: &Path, f: &str, m: impl Into<String>) -> SchemaError {
    SchemaError::field(p, f, m)
}

/// Set a dotted key (`a.b.c`) in a TOML table, creating intermediate tables.
fn set_dotted(
    table: &mut toml::Table,
    key: &str,
    value: toml::Value,
) -> std::result::Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|s| s.is_empty()) {
        return Err(format!("`{key}` is not a dotted key"));
    }
    let mut t = table;
    for part in &parts[..parts.len() - 1] {
        let entry = t
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        t = entry
            .as_table_mut()
            .ok_or_else(|| format!("`{part}` in `{key}` is not a table in the base scene"))?;
    }
    t.insert(parts[parts.len() - 1].to_string(), value);
    Ok(())
}

impl Sweep {
    /// Number of runs of the grids.
    pub fn len(&self) -> usize {
        self.grids().map(|g| g.len()).sum()
    }

    /// The main grid, then the `[[also]]` grids, in expansion order.
    fn grids(&self) -> impl Iterator<Item = std::borrow::Cow<'_, Grid>> {
        let main = Grid {
            velocities_mm_s: self.velocities_mm_s.clone(),
            r_init_um: self.r_init_um.clone(),
            start_shapes: self.start_shapes.clone(),
            overrides: Vec::new(),
        };
        std::iter::once(std::borrow::Cow::Owned(main)).chain(self.also.iter().map(std::borrow::Cow::Borrowed))
    }

    /// True for an empty grid (never for a validated sweep).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The run id of a grid point: `<shape>_u<velocity>_r<offset>`.
    pub fn run_id(start_shape: &str, velocity_mm_s: f64, r_init_um: f64) -> String {
        format!("{start_shape}_u{velocity_mm_s}_r{r_init_um}")
    }

    /// Expand the grid into runs with their scene text. The scene text is TOML;
    /// the caller validates it as a scene (the schema of `scene.rs`).
    pub fn runs(&self) -> Result<Vec<SweepRun>> {
        let p = &self.path;
        let base: toml::Table = self
            .base_text
            .parse()
            .map_err(|e: toml::de::Error| field(p, "base_scene", e.message().replace('\n', " ")))?;
        let base_cell = base
            .get("cell")
            .and_then(|c| c.as_table())
            .cloned()
            .unwrap_or_default();
        let x0 = base_cell
            .get("position_um")
            .and_then(|v| v.as_array())
            .and_then(|a| a.first())
            .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
            .unwrap_or(0.0);
        let mut out: Vec<SweepRun> = Vec::with_capacity(self.len());
        for grid in self.grids() {
            for shape in &grid.start_shapes {
                for &u in &grid.velocities_mm_s {
                    for &r in &grid.r_init_um {
                        let (y, z) = offset_yz(r);
                        let mut scene = base.clone();
                        let mut cell = self.cells[shape].clone();
                        if let Some(level) = base_cell.get("level") {
                            cell.insert("level".into(), level.clone());
                        }
                        cell.insert(
                            "position_um".into(),
                            toml::Value::Array(vec![x0.into(), y.into(), z.into()]),
                        );
                        scene.insert("cell".into(), toml::Value::Table(cell));
                        let run_id = Self::run_id(shape, u, r);
                        let ctx = |m: String| field(p, &format!("run {run_id}"), m);
                        set_dotted(
                            &mut scene,
                            &self.velocity_key,
                            toml::Value::Float(u * 1000.0),
                        )
                        .map_err(ctx)?;
                        if let Some(t) = self.steady.max_time_s {
                            set_dotted(&mut scene, "time.end_s", toml::Value::Float(t)).map_err(ctx)?;
                        }
                        for (k, v) in self.overrides.iter().chain(&grid.overrides) {
                            set_dotted(&mut scene, k, v.clone()).map_err(ctx)?;
                        }
                        scene.insert("name".into(), toml::Value::String(run_id.clone()));
                        let scene_text = toml::to_string(&scene)
                            .map_err(|e| ctx(format!("cannot write the scene: {e}")))?;
                        out.push(SweepRun {
                            index: out.len(),
                            run_id,
                            start_shape: shape.clone(),
                            velocity_mm_s: u,
                            r_init_um: r,
                            y_init_um: y,
                            z_init_um: z,
                            scene_text,
                            overlaps_wall: None,
                        });
                    }
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = r#"
name = "paper"
[cell]
shape = "discocyte"
level = 2
position_um = [1.5, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
[membrane.skalak]
convention = "krueger"
kappa_s_n_m = 5e-6
kappa_a_n_m = 5e-4
[fluid]
viscosity_pa_s = 1.2e-3
lambda = 5.0
[walls]
kind = "periodic-channel"
length_x_um = 42.7
width_y_um = 12.0
height_z_um = 10.0
mean_velocity_um_s = 1000.0
[time]
end_s = 1.0
output_interval_s = 0.01
"#;

    fn setup(sweep: &str) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("base.toml"), SCENE).unwrap();
        let p = dir.path().join("sweep.toml");
        std::fs::write(&p, sweep).unwrap();
        (dir, p)
    }

    const SWEEP: &str = r#"
base_scene = "base.toml"
mean_velocity_mm_s = [1.0, 6.5]
r_init_um = { from = 0.0, to = 1.0, n = 3 }
start_shapes = ["discocyte", "croissant"]
[start_shape.croissant]
shape = "mesh-from-results"
results = "starts.h5"
run = "c1"
[overrides]
"integrator.scheme" = "ros2"
[steady]
max_time_s = 30.0
"#;

    fn err(text: &str) -> String {
        let (_d, p) = setup(text);
        let e = Sweep::read(&p).unwrap_err().to_string();
        assert!(
            e.contains("sweep.toml"),
            "error does not name the file: {e}"
        );
        assert!(!e.contains('\n'));
        e
    }

    /// `frame_travel_um` gives each run the interval in which the mean flow travels that far:
    /// 10 um at 1 and 6.5 mm/s are 10 ms and 1.538 ms; without it, `frame_interval_s` for all.
    #[test]
    fn classification_frames_follow_the_flow_when_given_as_a_travel() {
        let (_d, p) = setup(&format!("{SWEEP}\n[classify]\nframe_travel_um = 10.0\n"));
        let s = Sweep::read(&p).unwrap();
        let at: Vec<f64> = s.velocities_mm_s.iter().map(|&u| s.classify.frame_interval_s_at(u).unwrap()).collect();
        assert!((at[0] - 0.01).abs() < 1e-15 && (at[1] - 0.01 / 6.5).abs() < 1e-15, "{at:?}");
        let (_d, p) = setup(&format!("{SWEEP}\n[classify]\nframe_interval_s = 0.004\n"));
        let s = Sweep::read(&p).unwrap();
        assert_eq!((s.classify.frame_interval_s_at(1.0), s.classify.frame_interval_s_at(6.5)), (Some(0.004), Some(0.004)));
        let (_d, p) = setup(SWEEP);
        assert_eq!(Sweep::read(&p).unwrap().classify.frame_interval_s_at(1.0), None, "the solver's default");
    }

    #[test]
    fn expands_the_grid_into_scenes() {
        let (dir, p) = setup(SWEEP);
        let s = Sweep::read(&p).unwrap();
        assert_eq!(s.len(), 12);
        assert_eq!(s.r_init_um, vec![0.0, 0.5, 1.0]);
        let runs = s.runs().unwrap();
        assert_eq!(runs.len(), 12);
        // start shape major, then velocity, then offset
        let ids: Vec<&str> = runs.iter().map(|r| r.run_id.as_str()).collect();
        assert_eq!(
            &ids[..4],
            [
                "discocyte_u1_r0",
                "discocyte_u1_r0.5",
                "discocyte_u1_r1",
                "discocyte_u6.5_r0"
            ]
        );
        assert_eq!(ids[11], "croissant_u6.5_r1");
        assert!(runs.iter().enumerate().all(|(i, r)| r.index == i));
        let r = &runs[5]; // discocyte, 6.5 mm/s, r = 1
        assert_eq!((r.velocity_mm_s, r.r_init_um), (6.5, 1.0));
        // on the line z = 5 y / 9 at distance r
        assert!((r.z_init_um - 5.0 * r.y_init_um / 9.0).abs() < 1e-15);
        assert!((r.y_init_um.hypot(r.z_init_um) - 1.0).abs() < 1e-15);
        let scene: toml::Table = r.scene_text.parse().unwrap();
        assert_eq!(
            scene["walls"]["mean_velocity_um_s"].as_float(),
            Some(6500.0)
        );
        assert_eq!(scene["time"]["end_s"].as_float(), Some(30.0));
        assert_eq!(scene["integrator"]["scheme"].as_str(), Some("ros2"));
        assert_eq!(scene["name"].as_str(), Some("discocyte_u6.5_r1"));
        let cell = scene["cell"].as_table().unwrap();
        assert_eq!(cell["level"].as_integer(), Some(2));
        // the discocyte default axis is the flow direction x, replacing the base's
        assert_eq!(cell["axis"].as_array().unwrap()[0].as_float(), Some(1.0));
        let pos: Vec<f64> = cell["position_um"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_float().unwrap())
            .collect();
        assert_eq!(pos, vec![1.5, r.y_init_um, r.z_init_um]);
        // the croissant start reads a mesh; its path is resolved against the sweep file
        let c: toml::Table = runs[6].scene_text.parse().unwrap();
        assert_eq!(c["cell"]["shape"].as_str(), Some("mesh-from-results"));
        assert_eq!(
            c["cell"]["results"].as_str().map(PathBuf::from),
            Some(dir.path().join("starts.h5"))
        );
        assert!(c["cell"].get("axis").is_none());
        // every run is a valid scene
        for r in &runs {
            crate::scene::Scene::parse(&r.scene_text, &s.base_scene).unwrap();
        }
    }

    /// `[[also]]` grids expand after the main grid (whose numbers they keep), with the main list of
    /// start shapes unless they name their own; a repeated run or an unknown shape is refused.
    #[test]
    fn also_grids_follow_the_main_grid() {
        let main = Sweep::read(&setup(SWEEP).1).unwrap().runs().unwrap();
        let more = format!("{SWEEP}\n[[also]]\nmean_velocity_mm_s = [2.5]\nr_init_um = [0.4, 1.2]\nstart_shapes = [\"discocyte\"]\n\n[[also]]\nmean_velocity_mm_s = [10.0]\nr_init_um = [0.0]\n");
        let (_d, p) = setup(&more);
        let s = Sweep::read(&p).unwrap();
        assert_eq!(s.len(), 12 + 2 + 2);
        let runs = s.runs().unwrap();
        assert_eq!(runs.len(), 16);
        let key = |r: &SweepRun| (r.index, r.run_id.clone(), r.velocity_mm_s, r.r_init_um);
        assert_eq!(runs[..12].iter().map(key).collect::<Vec<_>>(), main.iter().map(key).collect::<Vec<_>>());
        let ids: Vec<&str> = runs[12..].iter().map(|r| r.run_id.as_str()).collect();
        assert_eq!(ids, ["discocyte_u2.5_r0.4", "discocyte_u2.5_r1.2", "discocyte_u10_r0", "croissant_u10_r0"]);
        assert!(runs.iter().enumerate().all(|(i, r)| r.index == i));
        let scene: toml::Table = runs[13].scene_text.parse().unwrap();
        assert_eq!(scene["walls"]["mean_velocity_um_s"].as_float(), Some(2500.0));
        assert_eq!(scene["integrator"]["scheme"].as_str(), Some("ros2"));
        let repeated = format!("{SWEEP}\n[[also]]\nmean_velocity_mm_s = [6.5]\nr_init_um = [0.5]\n");
        assert!(err(&repeated).contains("`also[0]`") && err(&repeated).contains("run discocyte_u6.5_r0.5 occurs twice"), "{}", err(&repeated));
        let unknown = format!("{SWEEP}\n[[also]]\nmean_velocity_mm_s = [2.5]\nr_init_um = [0.5]\nstart_shapes = [\"slipper\"]\n");
        assert!(err(&unknown).contains("also[0].start_shapes"), "{}", err(&unknown));
        let negative = format!("{SWEEP}\n[[also]]\nmean_velocity_mm_s = [-2.5]\nr_init_um = [0.5]\n");
        assert!(err(&negative).contains("also[0].mean_velocity_mm_s"), "{}", err(&negative));
        let stray = format!("{SWEEP}\n[[also]]\nmean_velocity_mm_s = [2.5]\nr_init_um = [0.5]\nsteady = 1\n");
        assert!(err(&stray).contains("steady"), "{}", err(&stray));
    }

    /// An `[[also]]` grid's `overrides` set scene fields of its own runs only, after the sweep's
    /// `[overrides]` (a grid's value wins); the fields the grid sets itself are refused, named by
    /// the grid.
    #[test]
    fn an_also_grids_overrides_set_its_runs_scenes_only() {
        let more = format!("{SWEEP}\n[[also]]\nmean_velocity_mm_s = [0.63]\nr_init_um = [1.2]\nstart_shapes = [\"discocyte\"]\noverrides = {{ \"integrator.scheme\" = \"bs23\", \"integrator.h_max_s\" = 2e-4 }}\n");
        let (_d, p) = setup(&more);
        let s = Sweep::read(&p).unwrap();
        let runs = s.runs().unwrap();
        let integrator = |k: usize| runs[k].scene_text.parse::<toml::Table>().unwrap()["integrator"].as_table().unwrap().clone();
        assert_eq!(runs[12].run_id, "discocyte_u0.63_r1.2");
        assert_eq!(integrator(12)["scheme"].as_str(), Some("bs23"), "the grid's override wins over [overrides]");
        assert_eq!(integrator(12)["h_max_s"].as_float(), Some(2e-4));
        for k in 0..12 {
            assert_eq!(integrator(k)["scheme"].as_str(), Some("ros2"), "run {k}: [overrides] alone");
            assert_eq!(integrator(k).get("h_max_s"), integrator_of_base().get("h_max_s"), "run {k}: the base scene's cap");
        }
        for r in &runs {
            crate::scene::Scene::parse(&r.scene_text, &s.base_scene).unwrap();
        }
        let grid_field = more.replace("\"integrator.h_max_s\" = 2e-4", "\"cell.position_um\" = [0.0, 0.0, 0.0]");
        assert!(err(&grid_field).contains("also[0].overrides.cell.position_um") && err(&grid_field).contains("set by the sweep grid"), "{}", err(&grid_field));
    }

    /// The `[integrator]` table of the tests' base scene.
    fn integrator_of_base() -> toml::Table {
        SCENE.parse::<toml::Table>().unwrap().get("integrator").and_then(|t| t.as_table()).cloned().unwrap_or_default()
    }

    /// A start shape used by an `[[also]]` grid alone: its runs are added after the earlier grids,
    /// which keep their runs and numbers; its `[cell]` table must exist and be used by some grid.
    #[test]
    fn an_also_grid_may_add_a_start_shape_of_its_own() {
        let main_only = SWEEP.replace("[\"discocyte\", \"croissant\"]", "[\"discocyte\"]").replace("[start_shape.croissant]", "[start_shape.slipper]");
        let with_slipper = format!("{main_only}\n[[also]]\nmean_velocity_mm_s = [2.5]\nr_init_um = [0.4, 1.2]\nstart_shapes = [\"slipper\"]\n");
        let (_d, p) = setup(&with_slipper);
        let s = Sweep::read(&p).unwrap();
        let runs = s.runs().unwrap();
        assert_eq!(s.start_shapes, ["discocyte"], "the main grid's list is unchanged");
        let ids: Vec<&str> = runs.iter().map(|r| r.run_id.as_str()).collect();
        assert_eq!(ids, ["discocyte_u1_r0", "discocyte_u1_r0.5", "discocyte_u1_r1", "discocyte_u6.5_r0", "discocyte_u6.5_r0.5", "discocyte_u6.5_r1", "slipper_u2.5_r0.4", "slipper_u2.5_r1.2"]);
        let cell: toml::Table = runs[7].scene_text.parse::<toml::Table>().unwrap()["cell"].as_table().unwrap().clone();
        assert_eq!(cell["shape"].as_str(), Some("mesh-from-results"));
        assert_eq!(cell["results"].as_str().map(PathBuf::from), Some(p.parent().unwrap().join("starts.h5")), "resolved against the sweep");
        assert_eq!(runs[7].start_shape, "slipper");
        // a table no grid uses, a shape without a table, a shape listed twice
        let unused = format!("{main_only}\n[[also]]\nmean_velocity_mm_s = [2.5]\nr_init_um = [0.4]\n");
        assert!(err(&unused).contains("start_shape.slipper") && err(&unused).contains("no grid"), "{}", err(&unused));
        let no_table = with_slipper.replace("[\"slipper\"]", "[\"croissant\"]");
        assert!(err(&no_table).contains("also[0].start_shapes") && err(&no_table).contains("[start_shape.croissant]"), "{}", err(&no_table));
        let twice = with_slipper.replace("[\"slipper\"]", "[\"slipper\", \"slipper\"]");
        assert!(err(&twice).contains("also[0].start_shapes") && err(&twice).contains("twice"), "{}", err(&twice));
    }

    #[test]
    fn log_range_and_offset_line() {
        let (_d, p) = setup(&SWEEP.replace(
            "[1.0, 6.5]",
            "{ from = 0.1, to = 10.0, n = 3, spacing = \"log\" }",
        ));
        let s = Sweep::read(&p).unwrap();
        // rounded to 6 significant digits: the ends are exact
        assert_eq!(s.velocities_mm_s, vec![0.1, 1.0, 10.0]);
        let (_d, p) = setup(&SWEEP.replace(
            "[1.0, 6.5]",
            "{ from = 0.13, to = 10.4, n = 11, spacing = \"log\" }",
        ));
        let s = Sweep::read(&p).unwrap();
        assert_eq!(
            (
                s.velocities_mm_s[0],
                s.velocities_mm_s[1],
                s.velocities_mm_s[10]
            ),
            (0.13, 0.201489, 10.4)
        ); // 0.13 * 80^(1/10)
        let (y, z) = offset_yz(106f64.sqrt());
        assert!((y - 9.0).abs() < 1e-12 && (z - 5.0).abs() < 1e-12);
    }

    /// A grid of 2 x 2 x 10000 runs (the fuzzer's hang: an axis of n = 10000) is refused before it is
    /// expanded, naming the largest axis; 2 x 2 x 2500 runs are the most the limit lets through.
    #[test]
    fn a_grid_larger_than_max_runs_is_refused_naming_its_largest_axis() {
        let e = err(&SWEEP.replace("n = 3", "n = 10000"));
        assert!(e.contains("`r_init_um`") && e.contains("2 x 2 x 10000 = 40000 runs") && e.contains("10000"), "{e}");
        let (_d, p) = setup(&SWEEP.replace("n = 3", "n = 2500"));
        assert_eq!(Sweep::read(&p).unwrap().len(), MAX_RUNS);
    }

    #[test]
    fn bad_fields_are_named() {
        assert!(err(&SWEEP.replace("[1.0, 6.5]", "[1.0, -6.5]")).contains("mean_velocity_mm_s"));
        assert!(err(&SWEEP.replace("[1.0, 6.5]", "[1.0, 1.0]")).contains("twice"));
        assert!(err(&SWEEP.replace("n = 3", "n = 0")).contains("r_init_um.n"));
        assert!(err(&SWEEP.replace(
            "[\"discocyte\", \"croissant\"]",
            "[\"discocyte\", \"slipper\"]"
        ))
        .contains("start_shape.slipper"));
        assert!(err(&SWEEP.replace("base.toml", "nope.toml")).contains("base_scene"));
        assert!(
            err(&SWEEP.replace("run = \"c1\"", "run = \"c1\"\nlevel = 3"))
                .contains("start_shape.croissant.level")
        );
        assert!(
            err(&format!("{SWEEP}\n[slurm]\nextra = [\"rm -rf /\"]\n")).contains("slurm.extra[0]")
        );
        assert!(err(&format!("{SWEEP}\n[classify]\nframes = 2\n")).contains("classify.frames"));
        assert!(err(&format!("{SWEEP}\n[classify]\nframe_interval_s = 0.0\n")).contains("classify.frame_interval_s"));
        assert!(err(&format!("{SWEEP}\n[classify]\nframe_interval_s = 0.004\nframe_travel_um = 10.0\n")).contains("not both"));
        assert!(
            err(&SWEEP.replace("max_time_s = 30.0", "max_time_s = -1.0"))
                .contains("steady.max_time_s")
        );
        assert!(
            err(&SWEEP.replace("start_shapes", "start_shape_list")).contains("start_shape_list")
        );
        assert!(err(&SWEEP.replace(
            "\"integrator.scheme\" = \"ros2\"",
            "\"cell.position_um\" = [0.0, 0.0, 0.0]"
        ))
        .contains("overrides.cell.position_um"));
    }

    #[test]
    fn slurm_times_and_the_stop_margin() {
        for (t, s) in [("90", Some(5400)), ("1:30", Some(90)), ("01:00:00", Some(3600)), ("2-03", Some(183_600)),
            ("2-03:04", Some(183_840)), ("7-00:00:00", Some(604_800)), ("0-00:01:05", Some(65)), ("UNLIMITED", None), ("infinite", None)] {
            assert_eq!(slurm_time_s(t), Some(s), "{t}");
        }
        for t in ["", "1:2:3:4", "1-2:3:4:5", "-1", "1h", "1:-2", "a-01", "1:", "1--2"] {
            assert_eq!(slurm_time_s(t), None, "{t}");
        }
        let (_d, p) = setup(SWEEP);
        let s = Sweep::read(&p).unwrap();
        assert_eq!((s.checkpoint_interval_s, s.slurm.stop_before_limit_s), (60.0, None), "defaults");
        let (_d, p) = setup(&format!("checkpoint_interval_s = 2.5\n{SWEEP}\n[slurm]\ntime = \"00:01:00\"\nstop_before_limit_s = 29\n"));
        let s = Sweep::read(&p).unwrap();
        assert_eq!((s.checkpoint_interval_s, s.slurm.stop_before_limit_s), (2.5, Some(29)));
        assert!(err(&format!("{SWEEP}\n[slurm]\ntime = \"00:01:00\"\nstop_before_limit_s = 30\n")).contains("`slurm.stop_before_limit_s`: 30 s must be less than half of slurm.time (60 s)"));
        assert!(err(&format!("{SWEEP}\n[slurm]\nstop_before_limit_s = 0\n")).contains("slurm.stop_before_limit_s"));
        assert!(err(&format!("{SWEEP}\n[slurm]\ntime = \"1h\"\n")).contains("`slurm.time`: \"1h\" is not a Slurm time"));
        assert!(err(&format!("checkpoint_interval_s = 0.0\n{SWEEP}")).contains("checkpoint_interval_s"));
    }

    #[test]
    fn velocity_key_into_a_non_table_is_reported_per_run() {
        let (_d, p) = setup(&format!("velocity_key = \"name.x\"\n{SWEEP}"));
        let e = Sweep::read(&p).unwrap().runs().unwrap_err().to_string();
        assert!(
            e.contains("run discocyte_u1_r0") && e.contains("`name`"),
            "{e}"
        );
    }
}
