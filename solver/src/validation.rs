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
//! - Next order: reversing the shear is the mirror image `x -> -x`, so the shape's
//!   terms of even order in Ca are mirror-symmetric (diagonal in the x-z second
//!   moment) and those of odd order antisymmetric (off-diagonal); the difference of
//!   the principal axes is then `|Ca| (c1 + c3 Ca^2 + ...)`: `D` has no `Ca^2` term
//!   and `D / (25/12 Ca) - 1 = O(Ca^2)`. Our converged neo-Hookean D at Ca = 0.15
//!   is 13 % below `25/12 Ca`, i.e. a coefficient of about -6, hence -0.06 % at
//!   Ca = 0.01, where the small-deformation comparison is made.
//!
//! Published answers at moderate capillary number (finite deformation), for the
//! neo-Hookean capsule at `lambda = 1`, initially spherical, free space, Stokes flow.
//! Definitions, and how each maps onto ours:
//! - Law: `w = Gs/2 (I1 - 1 + 1/(I2 + 1))` (Barthes-Biesel, Diaz & Dhenin, JFM 460,
//!   211 (2002); area modulus `3 Gs`), i.e. the principal tension
//!   `T1 = Gs/(l1 l2) (l1^2 - 1/(l1 l2)^2)`. Pozrikidis (JFM 297, 123 (1995)) and
//!   Ramanujan & Pozrikidis (JFM 361, 117 (1998)) write it
//!   `Es/(3 l1 l2) (l1^2 - 1/(l1 l2)^2)`, so their `Es = 3 Gs` and their
//!   `Ca_E = mu rate a / Es = Ca / 3` (checked exactly by
//!   `tests/flow_capsule_moderate_ca.rs::neo_hookean_law_is_the_references_law`;
//!   their small-Ca curves approach `25/4 Ca_E = 25/12 Ca`).
//! - D: Ramanujan & Pozrikidis use `(L - B)/(L + B)` of the ellipsoid with the
//!   capsule's inertia tensor, which is ours ([`slices::taylor_deformation`]).
//!   Lac, Barthes-Biesel, Pelekasis & Tsamopoulos (JFM 516, 303 (2004)) use `D12`
//!   of the shear-plane cross-section ([`profile_deformation`]); `D12 / D - 1` is
//!   -1.4 % (Ca = 0.15, 2048 triangles; -3.7 % at 8192, wrinkled), -0.3 % (0.3) and
//!   +0.3 % (0.6) on our 8192-triangle shapes. The Basilisk front-tracking code of
//!   D. Huet uses the largest and smallest node distance from the centroid (equal to
//!   `D12` on smooth shapes: the shortest axis lies in the shear plane).
//! - When D is read: R&P's D(t) passes through a maximum near `rate t = 3.5` and
//!   then decreases slowly (by 1.4 % up to `rate t = 8` at `Ca_E = 0.2`), as ours
//!   does (by 1.4 %); the values below are read at the end of their runs
//!   (`rate t = 8`; `4.9` at `Ca_E = 0.05`, flat from 4.0) and compared with ours
//!   at `rate t = 8`. Lac et al. (abstract) find stable steady shapes of the
//!   neo-Hookean capsule only in an interval of Ca: below it compressive tensions
//!   near the equator make the membrane buckle, above it the tips have no
//!   equilibrium. We see the buckling where the mesh resolves the wrinkles: at
//!   Ca = 0.04 with 2048 triangles (a late growth of D from `rate t ~ 1.2`) and at
//!   Ca = 0.15 with 8192 (D falls from its maximum by 1.4 %, not 0.2 %, and the
//!   cross-section `D12` lies 3.7 % below the ellipsoid D), not at Ca = 0.01
//!   (20 relaxation times at 2048 triangles), 0.3 or 0.6 (`rate t <= 8`, 8192).
//!
//! Digitised values (the data files `tests/lagrangian_caps/data/nh_shear_3d/*.csv`
//! of D. Huet's Basilisk sandbox, which reproduces these figures; reading
//! uncertainty ~ +-0.003):
//!
//! | Ca (ours) | R&P 1998 at end (max) | Doddi & Bagchi 2008 | Huet (Basilisk, IBM) | ours, 8192 tri -> h^2 limit |
//! | --- | --- | --- | --- | --- |
//! | 0.0375 | - | 0.083 (theory 0.078) | - | - |
//! | 0.075 | 0.150 at `rate t = 1.4`, rising | 0.160-0.163 | - | 2048 tri: 0.152 at 1.4 |
//! | 0.15 | 0.261 (0.264) | 0.274 (`rate t = 3.4`) - 0.279 (11.7) | 0.263 | 0.267-0.270, wrinkles (+2.2..+3.5 %) |
//! | 0.3 | 0.385 (0.386) | 0.391-0.393 | 0.382 | 0.3976 -> 0.3979 (+3.3 %) |
//! | 0.6 | 0.500 (0.508) | 0.494-0.497 | 0.496 | 0.5225 -> 0.5230 (+4.6 %) |
//!
//! The references disagree among themselves by more than the 2 % target: Doddi &
//! Bagchi (immersed boundary, wall-bounded, small finite Re) lie 6 % above
//! small-deformation theory at `Ca = 0.0375` and 5 % above R&P at 0.15, but 1 %
//! below R&P at 0.6. Ours agree with small-deformation theory to 0.1 % (mesh-
//! extrapolated), converge as h^2 at Ca = 0.3 and 0.6 (ratio of successive
//! differences 4.7 and 4.5), have time-step error < 1e-5 and do not depend (< 0.1 %)
//! on the vertex area used for the force density (mixed Voronoi or barycentric).
//! R&P lie below ours already where the deformation is nearly linear: at
//! `Ca_E = 0.025` their D(t) is 3-5 % below our `Ca = 0.01` transient scaled by Ca
//! (`D/Ca` against `t Gs/(mu a)`, `rate t = 0.25 ... 1.4`), of which the
//! nonlinearity accounts for 1.3-1.9 % (our `Ca = 0.075` run, 2048 triangles, lies
//! 1.3-3.8 % above R&P over the same times). The remaining +3.3 % (Ca = 0.3) and
//! +4.6 % (0.6) above R&P (the only reference with our definitions) are therefore
//! attributed to their discretisation (coarse meshes under-predict D: ours do, by
//! 1.4-1.7 % at 512 triangles), a
//! conclusion that a tabulated high-accuracy reference (Lac et al. 2004; Walter et
//! al., IJNME 83, 829 (2010)), not available here, should confirm.

use crate::error::SolverError;
use crate::dynamics::cell::CellWork;
use crate::mesh::slices;
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
    /// Neo-Hookean capsule (shear modulus `Gs`, area modulus `3 Gs`), `ca = mu rate a / Gs`.
    NeoHookeanCapsule { ca: f64, lambda: f64 },
}

/// Taylor deformation of the neo-Hookean capsule at `lambda = 1` at the end of
/// Ramanujan & Pozrikidis' (1998) runs (`rate t = 8`; see the module documentation):
/// `(Ca = mu rate a / Gs, D)`.
pub const RAMANUJAN_POZRIKIDIS_1998_NH: [(f64, f64); 3] = [(0.15, 0.261), (0.3, 0.385), (0.6, 0.500)];

impl Case {
    /// Leading-order small-deformation Taylor deformation.
    pub fn reference_d(&self) -> f64 {
        match *self {
            Case::Capsule { ca, c, .. } => 1.25 * ca * (2.0 + 3.0 * c) / (1.0 + 2.0 * c),
            Case::Drop { ca, lambda } => ca * (19.0 * lambda + 16.0) / (16.0 * lambda + 16.0),
            Case::NeoHookeanCapsule { ca, .. } => 25.0 / 12.0 * ca,
        }
    }

    /// The published finite-deformation answer, where there is one
    /// ([`RAMANUJAN_POZRIKIDIS_1998_NH`] for the neo-Hookean capsule at lambda = 1).
    pub fn published_d(&self) -> Option<f64> {
        match *self {
            Case::NeoHookeanCapsule { ca, lambda: 1.0 } => {
                RAMANUJAN_POZRIKIDIS_1998_NH.iter().find(|(c, _)| (c - ca).abs() < 1e-12).map(|p| p.1)
            }
            _ => None,
        }
    }

    /// Capillary number and viscosity ratio.
    fn ca_lambda(&self) -> (f64, f64) {
        match *self {
            Case::Capsule { ca, lambda, .. } | Case::Drop { ca, lambda } | Case::NeoHookeanCapsule { ca, lambda } => (ca, lambda),
        }
    }

    /// Shear rate (1/s).
    pub fn shear_rate(&self) -> f64 {
        self.ca_lambda().0 * GS_N_M / (MU_PA_S * RADIUS_UM * 1e-6)
    }

    /// Relaxation time of the membrane (s): `mu a (1 + lambda) / G` (the drop uses `gamma = Gs`).
    pub fn relaxation_s(&self) -> f64 {
        let lambda = self.ca_lambda().1;
        MU_PA_S * RADIUS_UM * 1e-6 * (1.0 + lambda) / GS_N_M
    }

    /// The scene of this case at mesh `level`, with `scheme` and tolerance `atol_um`, run for `t_end_s`.
    /// (Scenes have no neo-Hookean law: its scene is the Skalak `C = 1` one, with the
    /// same small-strain moduli, whose law [`run_case`] replaces after building.)
    pub fn scene_toml(&self, level: u32, scheme: &str, atol_um: f64, t_end_s: f64) -> String {
        let (membrane, lambda) = match *self {
            Case::Capsule { c, lambda, .. } => (
                format!("[membrane.skalak]\nconvention = \"barthes-biesel\"\nshear_modulus_n_m = {GS_N_M:e}\nc = {c}\n"),
                lambda,
            ),
            Case::NeoHookeanCapsule { lambda, .. } => (
                format!("[membrane.skalak]\nconvention = \"barthes-biesel\"\nshear_modulus_n_m = {GS_N_M:e}\nc = 1\n"),
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
    /// Taylor deformation at the end and its reference ([`Case::published_d`]
    /// where there is one, else the small-deformation [`Case::reference_d`]).
    pub d: f64,
    pub d_ref: f64,
    /// Taylor deformation at every output time.
    pub d_history: Vec<(f64, f64)>,
    /// Inclination of the long axis from the flow direction (rad).
    pub angle_rad: f64,
    pub summary: RunSummary,
    pub work: CellWork,
    /// Final vertex positions (um) and the triangles.
    pub vertices: Vec<Vector3<f64>>,
    pub triangles: Vec<[usize; 3]>,
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
    let mut built = crate::scene::build(&scene)?;
    // finite deformation: for the neo-Hookean capsule the area-change check (20 % in the
    // scene) allows 100 % above Ca = 0.05 (at Ca = 0.6 its membrane stretches by ~25 %)
    if case.ca_lambda().0 > 0.05 && matches!(case, Case::NeoHookeanCapsule { .. }) {
        built.run.checks.max_area_change = 1.0;
    }
    if let Case::NeoHookeanCapsule { .. } = case {
        let law = crate::membrane::skalak::Skalak::neo_hookean(&built.mesh, GS_N_M)?;
        built.membrane = crate::membrane::Membrane::new().with(law);
    }
    let mut rec = Recorder::default();
    let (summary, x) = built.run(&mut rec)?;
    let tris = &built.mesh.triangles;
    let (d, angle_rad) = slices::taylor_deformation(&x, tris, &Vector3::y());
    let d_history = rec.times_s.iter().zip(&rec.vertices).map(|(&t, v)| (t, slices::taylor_deformation(v, tris, &Vector3::y()).0)).collect();
    Ok(CaseResult { d, d_ref: case.published_d().unwrap_or_else(|| case.reference_d()), d_history, angle_rad, summary, work: CellWork::default(), vertices: x, triangles: tris.clone() })
}

/// Taylor deformation `D12 = (L - B) / (L + B)` of the *profile*: the cross-section
/// of the surface with the plane through the volume centroid normal to
/// `plane_normal` (the shear plane), `L` and `B` the largest and smallest
/// distances of the cross-section from the centroid (the definition of Lac et al.
/// 2004), from the exact intersections of the flat triangles with the plane.
pub fn profile_deformation(x: &[Vector3<f64>], triangles: &[[usize; 3]], plane_normal: &Vector3<f64>) -> f64 {
    let c = slices::centroid(x, triangles);
    let n = plane_normal.normalize();
    let (mut l, mut b) = (0.0f64, f64::INFINITY);
    for t in triangles {
        for k in 0..3 {
            let (p, q) = (x[t[k]], x[t[(k + 1) % 3]]);
            let (sp, sq) = ((p - c).dot(&n), (q - c).dot(&n));
            if (sp <= 0.0) != (sq <= 0.0) {
                let y = p + (q - p) * (sp / (sp - sq));
                let r = (y - c).norm();
                l = l.max(r);
                b = b.min(r);
            }
        }
    }
    (l - b) / (l + b)
}

/// Normal mobility of shape mode `l` of a spherical drop: a normal force density
/// `f = F P_l(cos theta) n` (Pa, exerted by the interface on the fluid) on a sphere
/// of radius `a` with outer viscosity `mu` and inner `lambda mu` moves the
/// interface with the normal velocity `u_n = m_l(lambda) F a / mu P_l(cos theta)`.
///
/// Derivation (Lamb's solution, written with the axisymmetric stream function):
/// inside `psi = (A r^(l+1) + B r^(l+3)) sin^2(theta) P_l'(cos theta)`, outside
/// `psi = (C r^-l + D r^(2-l)) sin^2(theta) P_l'(cos theta)`; pressure from the
/// momentum equation; at `r = a` continuous velocity and tangential stress and a
/// normal-stress jump `(sigma_in - sigma_out)_rr = F P_l`. Solving the four linear
/// conditions (done symbolically, sympy; the script is reproduced in
/// `CONVERGENCE.md`) gives
/// - `m_2 = 10 (lambda + 1) / ((2 lambda + 3)(19 lambda + 16))`,
/// - `m_3 = 28 (lambda + 1) / ((11 lambda + 10)(16 lambda + 19))`,
/// - `m_4 = 20 (lambda + 1) / ((10 lambda + 11)(17 lambda + 16))`.
///
/// Check: with a tension `gamma` the mode-2 force is `-gamma 4 eps/a P_2`, so
/// the relaxation rate is `4 m_2 gamma / (mu a) = 40 (lambda + 1) gamma / ((2 lambda + 3)(19 lambda + 16) mu a)`,
/// Taylor's (1932) drop relaxation; at lambda = 1, `m_l = 2 l (l + 1) / ((2l - 1)(2l + 1)(2l + 3))`.
/// `None` for other `l`.
pub fn drop_mode_mobility(l: u32, lambda: f64) -> Option<f64> {
    let k = lambda;
    match l {
        2 => Some(10.0 * (k + 1.0) / ((2.0 * k + 3.0) * (19.0 * k + 16.0))),
        3 => Some(28.0 * (k + 1.0) / ((11.0 * k + 10.0) * (16.0 * k + 19.0))),
        4 => Some(20.0 * (k + 1.0) / ((10.0 * k + 11.0) * (17.0 * k + 16.0))),
        _ => None,
    }
}

/// Linear relaxation rate (1/s) of shape mode `l` of a nearly spherical
/// membrane with Helfrich bending only (no spontaneous curvature, no tension,
/// no area constraint), bending modulus `kappa_b` (N m = J), radius `a_um`,
/// outer viscosity `mu` (Pa s), viscosity ratio `lambda`:
///
/// `sigma_l = kappa_b (l - 1) l (l + 1)(l + 2) m_l(lambda) / (mu a^3)`,
///
/// the amplitude of `r = a (1 + eps(t) P_l(cos theta))` decaying as `exp(-sigma_l t)`.
/// Derivation: for `r = a (1 + eps Y_l)`, `2 H = 2/a + (l - 1)(l + 2) eps/a Y_l`,
/// `H^2 - K = ((k1 - k2)/2)^2 = O(eps^2)` and `Lap_s Y_l = -l (l + 1)/a^2 Y_l`, so
/// the force density of [`crate::membrane::bending`],
/// `Df = 2 kB [2 H (H^2 - K) + Lap_s H] n`, is to first order
/// `-kB (l - 1) l (l + 1)(l + 2) eps / a^3 Y_l n` (the restoring force of the
/// Helfrich spectrum `kappa (l - 1) l (l + 1)(l + 2)` of a tensionless sphere;
/// Milner & Safran, PRA 36, 4371 (1987); Seifert, Adv. Phys. 46, 13 (1997));
/// with [`drop_mode_mobility`], `a d eps/dt = u_n = m_l Df a / mu`.
/// `None` where the mobility is not tabulated.
pub fn bending_mode_rate(l: u32, lambda: f64, kappa_b: f64, mu: f64, a_um: f64) -> Option<f64> {
    let lf = l as f64;
    let a = a_um * 1e-6;
    drop_mode_mobility(l, lambda).map(|m| kappa_b * (lf - 1.0) * lf * (lf + 1.0) * (lf + 2.0) * m / (mu * a * a * a))
}

/// Legendre polynomial `P_l(z)` by the three-term recurrence.
fn legendre(l: u32, z: f64) -> f64 {
    let (mut p0, mut p1) = (1.0, z);
    if l == 0 {
        return 1.0;
    }
    for k in 2..=l {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * z * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    p1
}

/// Amplitude `eps` (dimensionless) of mode `P_l(cos theta)` about the z axis through
/// the volume centroid: `sum_i A_i (r_i/a - 1) P_l / sum_i A_i P_l^2` with the
/// barycentric vertex areas `A_i` (the discrete `L2` projection of the radius).
pub fn mode_amplitude(x: &[Vector3<f64>], triangles: &[[usize; 3]], l: u32, a_um: f64) -> f64 {
    let c = slices::centroid(x, triangles);
    let mesh = crate::mesh::Mesh { vertices: x.to_vec(), triangles: triangles.to_vec() };
    let (mut num, mut den) = (0.0, 0.0);
    for (p, w) in x.iter().zip(mesh.barycentric_vertex_areas()) {
        let d = p - c;
        let r = d.norm();
        let pl = legendre(l, d.z / r);
        num += w * (r / a_um - 1.0) * pl;
        den += w * pl * pl;
    }
    num / den
}

/// Outcome of a bending-relaxation run.
#[derive(Debug, Clone)]
pub struct RelaxationResult {
    /// Decay rate fitted to `ln eps(t)` by least squares over the samples (1/s), and the theory.
    pub rate_1_s: f64,
    pub rate_ref_1_s: f64,
    /// `(t, eps)` at every sample.
    pub amplitudes: Vec<(f64, f64)>,
    /// Energy of the membrane (J) at every sample.
    pub energies: Vec<f64>,
    pub summary: RunSummary,
}

impl RelaxationResult {
    /// `rate / rate_ref - 1`.
    pub fn relative_error(&self) -> f64 {
        self.rate_1_s / self.rate_ref_1_s - 1.0
    }
}

/// Relaxation of shape mode `l` of a sphere of radius [`RADIUS_UM`] with bending
/// only (`kappa_b = 3e-19` J, the paper's; outer viscosity [`MU_PA_S`]), viscosity
/// ratio `lambda`, mesh `level`, bending `method`, initial amplitude `eps0`
/// (`r = a (1 + eps0 P_l(z/a))`), run for `e_folds / sigma_l` with BS23 at
/// `atol_um` (material kinematics, no-flux volume correction, free space).
#[allow(clippy::too_many_arguments)]
pub fn run_bending_relaxation(
    l: u32,
    lambda: f64,
    level: usize,
    method: crate::membrane::bending::BendingMethod,
    eps0: f64,
    e_folds: f64,
    atol_um: f64,
) -> Result<RelaxationResult, SolverError> {
    use crate::bim::{BimOptions, FreeSpaceStokes};
    use crate::integrate::bs23::BogackiShampine;
    use crate::dynamics::cell::CellDynamics;
    use crate::integrate::check::Checks;
    use crate::dynamics::volume::{no_flux, VolumeCorrection};
    use crate::membrane::{bending::Helfrich, MembraneLaw};
    use crate::run::{RunConfig, Runner, StepControl};
    const KB: f64 = 3e-19;
    let rate_ref = bending_mode_rate(l, lambda, KB, MU_PA_S, RADIUS_UM).ok_or_else(|| SolverError::Unsupported {
        field: "l".to_string(),
        message: format!("no tabulated drop mobility for mode l = {l} (2, 3, 4 are)"),
    })?;
    let contrast = crate::viscosity::ViscosityContrast::new(lambda).map_err(|e| SolverError::Unsupported { field: "lambda".to_string(), message: e.to_string() })?;
    let sphere = crate::mesh::sphere(level, RADIUS_UM);
    let mut x: Vec<Vector3<f64>> = sphere.vertices.iter().map(|p| p * (1.0 + eps0 * legendre(l, p.z / p.norm()))).collect();
    let tris = sphere.triangles.clone();
    let law = Helfrich::with_method(KB, method)?;
    let stokes = crate::scene::FreeSpace {
        solver: FreeSpaceStokes::new(MU_PA_S, contrast, BimOptions::default()),
        background: Box::new(crate::flow::Quiescent),
    };
    let t_end = e_folds / rate_ref;
    let config = RunConfig {
        t_start_s: 0.0,
        t_end_s: t_end,
        output_interval_s: t_end / 20.0,
        control: StepControl::new(atol_um, 1e-6, 1e-12, t_end / 20.0),
        checks: Checks { max_area_change: 0.2, ..Checks::default() },
        volume: Some(VolumeCorrection::new(slices::volume(&x, &tris))),
    };
    let mut rec = Recorder::default();
    let cell = CellDynamics::new(tris.clone(), &law, &stokes);
    let summary = Runner::new(config).run(&mut no_flux(cell, &tris), &mut BogackiShampine::new(), &tris, &mut x, &mut rec)?;
    let amplitudes: Vec<(f64, f64)> = rec.times_s.iter().zip(&rec.vertices).map(|(&t, v)| (t, mode_amplitude(v, &tris, l, RADIUS_UM))).collect();
    let energies = rec.vertices.iter().map(|v| law.energy(&crate::mesh::Mesh { vertices: v.clone(), triangles: tris.clone() })).collect();
    // least-squares slope of ln|eps| against t
    let n = amplitudes.len() as f64;
    let (st, sy) = amplitudes.iter().fold((0.0, 0.0), |(a, b), (t, e)| (a + t, b + e.abs().ln()));
    let (mt, my) = (st / n, sy / n);
    let (sxy, sxx) = amplitudes.iter().fold((0.0, 0.0), |(a, b), (t, e)| (a + (t - mt) * (e.abs().ln() - my), b + (t - mt) * (t - mt)));
    Ok(RelaxationResult { rate_1_s: -sxy / sxx, rate_ref_1_s: rate_ref, amplitudes, energies, summary })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The references the flow validation compares with, against the papers' numbers written
    /// out: Taylor (1932) at lambda = 1 and Ca = 0.1, `0.1 x 35/32`; Barthes-Biesel & Rallison
    /// (1981) for the Skalak capsule, `5/4 Ca (2 + 3C)/(1 + 2C)`, at C = 1: `25/12 Ca`, and the
    /// neo-Hookean's `25/4 Ca_E` (`Ca_E = Ca/3`); Ramanujan & Pozrikidis (1998) at lambda = 1,
    /// none elsewhere.
    #[test]
    fn the_reference_deformations_are_the_published_numbers() {
        assert!((Case::Drop { ca: 0.1, lambda: 1.0 }.reference_d() - 0.109375).abs() < 1e-15);
        assert!((Case::Drop { ca: 0.1, lambda: 0.0 }.reference_d() - 0.1).abs() < 1e-15);
        assert!((Case::Capsule { ca: 0.012, c: 1.0, lambda: 1.0 }.reference_d() - 0.025).abs() < 1e-15);
        assert!((Case::Capsule { ca: 0.01, c: 0.0, lambda: 5.0 }.reference_d() - 0.025).abs() < 1e-15);
        assert!((Case::NeoHookeanCapsule { ca: 0.03, lambda: 1.0 }.reference_d() - 25.0 / 4.0 * 0.01).abs() < 1e-15);
        assert_eq!(Case::NeoHookeanCapsule { ca: 0.15, lambda: 1.0 }.published_d(), Some(0.261));
        assert_eq!(Case::NeoHookeanCapsule { ca: 0.3, lambda: 1.0 }.published_d(), Some(0.385));
        assert_eq!(Case::NeoHookeanCapsule { ca: 0.6, lambda: 1.0 }.published_d(), Some(0.500));
        assert_eq!(Case::NeoHookeanCapsule { ca: 0.2, lambda: 1.0 }.published_d(), None);
        assert_eq!(Case::NeoHookeanCapsule { ca: 0.15, lambda: 5.0 }.published_d(), None);
        assert_eq!(Case::Drop { ca: 0.15, lambda: 1.0 }.published_d(), None);
    }
}
