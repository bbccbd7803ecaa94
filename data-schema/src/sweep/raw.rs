//! The sweep file as serde reads it (unknown fields refused); [`super::validate`] turns it into a
//! [`super::Sweep`].

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::PathBuf;


#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub(super) enum RawAxis {
    List(Vec<f64>),
    Range {
        from: f64,
        to: f64,
        n: i64,
        spacing: Option<String>,
    },
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSweep {
    pub(super) base_scene: PathBuf,
    pub(super) mean_velocity_mm_s: RawAxis,
    pub(super) r_init_um: RawAxis,
    pub(super) start_shapes: Vec<String>,
    pub(super) velocity_key: Option<String>,
    pub(super) threads_per_run: Option<i64>,
    pub(super) snapshot_every: Option<i64>,
    pub(super) checkpoint_interval_s: Option<f64>,
    #[serde(default)]
    pub(super) start_shape: BTreeMap<String, toml::Table>,
    #[serde(default)]
    pub(super) also: Vec<RawGrid>,
    #[serde(default)]
    pub(super) overrides: toml::Table,
    pub(super) steady: Option<RawSteady>,
    pub(super) classify: Option<RawClassify>,
    pub(super) slurm: Option<RawSlurm>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawGrid {
    pub(super) mean_velocity_mm_s: RawAxis,
    pub(super) r_init_um: RawAxis,
    pub(super) start_shapes: Option<Vec<String>>,
    #[serde(default)]
    pub(super) overrides: toml::Table,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSteady {
    pub(super) window_s: Option<f64>,
    pub(super) max_time_s: Option<f64>,
    pub(super) position_tol_um: Option<f64>,
    pub(super) asphericity_tol: Option<f64>,
    pub(super) min_cycles: Option<i64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawClassify {
    pub(super) centred_um: Option<f64>,
    pub(super) symmetric_rel: Option<f64>,
    pub(super) rigid_rel: Option<f64>,
    pub(super) frames: Option<i64>,
    pub(super) frame_interval_s: Option<f64>,
    pub(super) frame_travel_um: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSlurm {
    pub(super) partition: Option<String>,
    pub(super) time: Option<String>,
    pub(super) mem: Option<String>,
    pub(super) account: Option<String>,
    pub(super) max_concurrent: Option<i64>,
    pub(super) stop_before_limit_s: Option<i64>,
    #[serde(default)]
    pub(super) extra: Vec<String>,
}
