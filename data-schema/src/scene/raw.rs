//! The scene file exactly as TOML gives it, no interpretation: the serde mirror that [`super::validate`] checks and turns into a [`super::Scene`].

use serde::Deserialize;
use std::path::PathBuf;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawScene {
    pub(super) name: Option<String>,
    pub(super) cell: RawCell,
    pub(super) membrane: RawMembrane,
    pub(super) fluid: RawFluid,
    #[serde(default)]
    pub(super) flow: Option<RawFlow>,
    #[serde(default)]
    pub(super) walls: Option<RawWalls>,
    #[serde(default)]
    pub(super) integrator: Option<RawIntegrator>,
    pub(super) time: RawTime,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCell {
    pub(super) shape: String,
    pub(super) level: Option<i64>,
    pub(super) radius_um: Option<f64>,
    pub(super) position_um: Option<[f64; 3]>,
    pub(super) axis: Option<[f64; 3]>,
    pub(super) results: Option<PathBuf>,
    pub(super) run: Option<String>,
    pub(super) snapshot: Option<i64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMembrane {
    pub(super) reference: Option<String>,
    pub(super) skalak: Option<RawSkalak>,
    pub(super) bending: Option<RawBending>,
    pub(super) tension: Option<RawTension>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSkalak {
    pub(super) convention: String,
    pub(super) shear_modulus_n_m: Option<f64>,
    pub(super) c: Option<f64>,
    pub(super) kappa_s_n_m: Option<f64>,
    pub(super) kappa_a_n_m: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBending {
    pub(super) kappa_b_n_m: f64,
    pub(super) method: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTension {
    pub(super) gamma_n_m: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFluid {
    pub(super) viscosity_pa_s: f64,
    pub(super) lambda: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFlow {
    pub(super) kind: String,
    pub(super) shear_rate_1_s: Option<f64>,
    pub(super) max_velocity_um_s: Option<f64>,
    pub(super) radius_um: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawWalls {
    pub(super) kind: String,
    pub(super) length_x_um: Option<f64>,
    pub(super) width_y_um: Option<f64>,
    pub(super) height_z_um: Option<f64>,
    pub(super) mean_velocity_um_s: Option<f64>,
    pub(super) corner_radius_um: Option<f64>,
    pub(super) wall_model: Option<String>,
    pub(super) kappa_w_n_m3: Option<f64>,
    pub(super) wall_edge_um: Option<f64>,
    pub(super) ewald_tol: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawIntegrator {
    pub(super) scheme: Option<String>,
    pub(super) atol_um: Option<f64>,
    pub(super) h0_s: Option<f64>,
    pub(super) h_min_s: Option<f64>,
    pub(super) h_max_s: Option<f64>,
    pub(super) volume_correction: Option<bool>,
    pub(super) max_area_change: Option<f64>,
    pub(super) max_fold_deg: Option<f64>,
    pub(super) kinematics: Option<String>,
    pub(super) controller: Option<String>,
    pub(super) error_norm: Option<String>,
    pub(super) wall_atol_um: Option<f64>,
    pub(super) wall_coupling: Option<bool>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawTime {
    pub(super) end_s: f64,
    pub(super) output_interval_s: f64,
}
