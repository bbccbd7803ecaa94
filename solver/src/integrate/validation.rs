//! Validation cases in flow with published answers: capsule and drop in simple shear (Taylor deformation), discocyte at rest.
//!
//! Each case is written as a scene (TOML), built by [`crate::scene::build`] and
//! run to steady state, so the validation exercises exactly the path a user's
//! run takes. Used by `tests/flow_validation.rs` and by `rbc-bench precision`.
//!
//! Reference answers (small deformation, leading order in the capillary number):
//! - Capsule, membrane with small-strain shear modulus `G` and area modulus `K`
//!   (any `lambda`), in `u = (rate z, 0, 0)`:
//!   `D = 5/8 Ca (3 + G/K)`, `Ca = mu rate a / G` (Barthes-Biesel & Rallison,
//!   JFM 113, 251 (1981)). Derivation: at O(Ca) the membrane, seen from the frame
//!   rotating with the vorticity, is in quasi-static equilibrium with the traction
//!   `5 mu E.n` of a rigid sphere in the straining part `E` of the flow; the l = 2
//!   linear membrane response to it has normal displacement `5 mu a^2/4 (1/K + 3/G) n.E.n`.
//!   For Barthes-Biesel's Skalak form (`G = Gs`, `K = Gs (1 + 2C)`) this is
//!   `D = 5/4 Ca (2 + 3C)/(1 + 2C)`, i.e. `5/4 Ca (2 + nu)/(1 + nu)` with the surface
//!   Poisson ratio `nu = C/(1 + C)`; for a neo-Hookean-like `K = 3G`: `D = 25/12 Ca`
//!   `= 25/4 Ca_E` with `Ca_E = mu rate a / E_s`, `E_s = 3G` (the often quoted "25/4").
//! - Drop with tension `gamma`: `D = Ca (19 lambda + 16)/(16 lambda + 16)`,
//!   `Ca = mu rate a / gamma` (Taylor 1932).

use crate::error::SolverError;
use crate::integrate::cell::CellWork;
use crate::integrate::geometry;
use crate::run::{Recorder, RunSummary};
use nalgebra::Vector3;
use rbc_schema::scene::Scene;
use std::path::Path;

/// Radius of the test capsules and drops (um): `R_RBC`.
pub const RADIUS_UM: f64 = 4.0;
/// Outer viscosity (Pa s): the paper's plasma.
pub const MU_PA_S: f64 = 1.2e-3;
/// Shear modulus of the test capsules (N/m): the paper's `kappa_S`.
pub const GS_N_M: f64 = 5e-6;

/// A validation case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Case {
    /// Skalak capsule (Barthes-Biesel form with `c`) at capillary number `ca = mu rate a / Gs`.
    Capsule { ca: f64, c: f64, lambda: f64 },
    /// Drop with tension, `ca = mu rate a / gamma`.
    Drop { ca: f64, lambda: f64 },
}

impl Case {
    /// Leading-order small-deformation Taylor deformation.
    pub fn reference_d(&self) -> f64 {
        match *self {
            Case::Capsule { ca, c, .. } => 1.25 * ca * (2.0 + 3.0 * c) / (1.0 + 2.0 * c),
            Case::Drop { ca, lambda } => ca * (19.0 * lambda + 16.0) / (16.0 * lambda + 16.0),
        }
    }

    /// Shear rate (1/s).
    pub fn shear_rate(&self) -> f64 {
        match *self {
            Case::Capsule { ca, .. } | Case::Drop { ca, .. } => ca * GS_N_M / (MU_PA_S * RADIUS_UM * 1e-6),
        }
    }

    /// Relaxation time of the membrane (s): `mu a (1 + lambda) / G` (the drop uses `gamma = Gs`).
    pub fn relaxation_s(&self) -> f64 {
        let lambda = match *self {
            Case::Capsule { lambda, .. } | Case::Drop { lambda, .. } => lambda,
        };
        MU_PA_S * RADIUS_UM * 1e-6 * (1.0 + lambda) / GS_N_M
    }

    /// The scene of this case at mesh `level`, with `scheme` and tolerance `atol_um`, run for `t_end_s`.
    pub fn scene_toml(&self, level: u32, scheme: &str, atol_um: f64, t_end_s: f64) -> String {
        let (membrane, lambda) = match *self {
            Case::Capsule { c, lambda, .. } => (
                format!("[membrane.skalak]\nconvention = \"barthes-biesel\"\nshear_modulus_n_m = {GS_N_M:e}\nc = {c}\n"),
                lambda,
            ),
            Case::Drop { lambda, .. } => (format!("[membrane.tension]\ngamma_n_m = {GS_N_M:e}\n"), lambda),
        };
        let kinematics = if matches!(self, Case::Drop { .. }) { "normal" } else { "material" };
        format!(
            "name = \"validation\"\n[cell]\nshape = \"sphere\"\nlevel = {level}\nradius_um = {RADIUS_UM}\n{membrane}\
             [fluid]\nviscosity_pa_s = {MU_PA_S:e}\nlambda = {lambda}\n[flow]\nkind = \"shear\"\nshear_rate_1_s = {rate:e}\n\
             [integrator]\nscheme = \"{scheme}\"\natol_um = {atol_um:e}\nh0_s = 1e-7\nh_min_s = 1e-12\nh_max_s = {hmax:e}\nmax_area_change = 0.2\nkinematics = \"{kinematics}\"\n\
             [time]\nend_s = {t_end_s:e}\noutput_interval_s = {out:e}\n",
            rate = self.shear_rate(),
            hmax = t_end_s / 20.0,
            out = t_end_s / 20.0,
        )
    }
}

/// Outcome of one validation run.
#[derive(Debug, Clone)]
pub struct CaseResult {
    /// Taylor deformation at the end and its reference.
    pub d: f64,
    pub d_ref: f64,
    /// Taylor deformation at every output time.
    pub d_history: Vec<(f64, f64)>,
    /// Inclination of the long axis from the flow direction (rad).
    pub angle_rad: f64,
    pub summary: RunSummary,
    pub work: CellWork,
}

impl CaseResult {
    /// `D / D_ref - 1`.
    pub fn relative_error(&self) -> f64 {
        self.d / self.d_ref - 1.0
    }
}

/// Run `case` for `relaxations` relaxation times; the Taylor deformation is measured in the shear plane (normal y).
pub fn run_case(case: Case, level: u32, scheme: &str, atol_um: f64, relaxations: f64) -> Result<CaseResult, SolverError> {
    let t_end = relaxations * case.relaxation_s();
    let text = case.scene_toml(level, scheme, atol_um, t_end);
    let scene = Scene::parse(&text, Path::new("validation.toml"))?;
    let built = crate::scene::build(&scene)?;
    let mut rec = Recorder::default();
    let (summary, x) = built.run(&mut rec)?;
    let tris = &built.mesh.triangles;
    let (d, angle_rad) = geometry::taylor_deformation(&x, tris, &Vector3::y());
    let d_history = rec.times_s.iter().zip(&rec.vertices).map(|(&t, v)| (t, geometry::taylor_deformation(v, tris, &Vector3::y()).0)).collect();
    Ok(CaseResult { d, d_ref: case.reference_d(), d_history, angle_rad, summary, work: CellWork::default() })
}
