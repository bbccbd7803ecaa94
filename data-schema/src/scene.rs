//! Scene TOML files of the solver (what one run contains): raw serde structs and validation into a typed [`Scene`].
//!
//! A scene states everything a run needs, with units in the field names:
//!
//! ```toml
//! name = "shear-capsule"          # optional label, stored with the run
//!
//! [cell]
//! shape = "sphere"                # sphere | discocyte | mesh-from-results
//! level = 3                       # mesh refinement level (triangle count grows 4x per level)
//! radius_um = 4.0                 # sphere only
//! position_um = [0.0, 0.0, 0.0]   # centroid at t = 0
//! # axis = [1.0, 0.0, 0.0]        # discocyte only: symmetry axis (paper: along the channel, x)
//! # results = "results.h5"        # mesh-from-results only: file, run and snapshot index
//! # run = "run-0001"              #   (negative snapshot counts from the end)
//! # snapshot = -1
//!
//! [membrane]
//! reference = "initial"           # reference shape of the elastic law: initial | discocyte | sphere
//! [membrane.skalak]               # optional; the convention is always named:
//! convention = "barthes-biesel"   #   w = Gs/4 (I1^2 + 2 I1 - 2 I2 + C I2^2): Gs = shear modulus,
//! shear_modulus_n_m = 5e-6        #     area modulus Gs (1 + 2C)      (fields shear_modulus_n_m, c)
//! c = 1.0                         # or "krueger": w = kS/12 (I1^2 + 2 I1 - 2 I2) + kA/12 I2^2
//!                                 #     (fields kappa_s_n_m > 0, kappa_a_n_m >= 0; small-strain shear modulus kS/3,
//!                                 #     area modulus (kS + 2 kA)/3: kA = 0 is the Barthes-Biesel form with C = 0,
//!                                 #     still resisting area change with modulus kS/3, so 0 is valid)
//! [membrane.bending]              # optional Canham-Helfrich bending
//! kappa_b_n_m = 3e-19
//! # method = "method-c"           # method-c (the paper's) | quartic-fit (default) | quartic-fit-galerkin
//! [membrane.tension]              # optional isotropic tension (drops)
//! gamma_n_m = 1e-3
//!
//! [fluid]
//! viscosity_pa_s = 1.2e-3         # outer viscosity mu
//! lambda = 1.0                    # viscosity ratio mu_in / mu
//!
//! [flow]
//! kind = "shear"                  # none | shear | poiseuille
//! shear_rate_1_s = 100.0          # shear: u = (rate * z, 0, 0) (flow along x, gradient along z)
//! # max_velocity_um_s = 1000.0    # poiseuille (unbounded, circular): u_x = umax (1 - (y^2 + z^2) / R^2)
//! # radius_um = 6.0
//!
//! [walls]
//! kind = "none"                   # none | periodic-channel
//! # periodic-channel: the paper's channel, periodic along x, flow driven by a prescribed mean flow
//! # length_x_um = 42.7             # period along the flow
//! # width_y_um = 12.0              # cross-section (rounded corners)
//! # height_z_um = 10.0
//! # mean_velocity_um_s = 5000.0    # flux / cross-section ([flow] must be "none")
//! # corner_radius_um = 1.5         # default 1.5
//! # wall_model = "no-slip"         # no-slip (exact, default) | penalty (the paper's springs)
//! # kappa_w_n_m3 = 1.9e7           # penalty only: spring stiffness (paper: 1.9e7 N/m^3)
//! # wall_edge_um = 1.38            # wall mesh edge (default 1.38: 2160 triangles; paper 2166); an edge whose dense
//! #                                 # wall operator would not fit in memory (MemTotal, or RBC_MAX_MEMORY_GB) is refused
//! # ewald_tol = 5e-5               # relative error of the Ewald sums (paper: 5e-5)
//!
//! [integrator]
//! scheme = "bs23"                 # bs23 (explicit, the paper's) | ros2 (linearly implicit) | ros34pw2 (W-method, full
//!                                 #   lagged Jacobian) | ros34pw2-local (W-method, local sparse Jacobian) |
//!                                 #   ros34pw2-mobility (W-method, dense free-space mobility Jacobian) |
//!                                 #   ros3pw-mobility, ros34pw3-mobility, ros34prw-mobility, rosw6s4-mobility (the same
//!                                 #   Jacobian with other W-tableaux; rosw6s4: six stages, order 4, the one to
//!                                 #   use with penalty walls, solver/README.md); the Rosenbrock schemes step across output
//!                                 #   times (Hermite dense output)
//! atol_um = 4e-5                  # absolute tolerance on vertex positions (paper: 1e-5 R_RBC)
//! h0_s = 1e-6                     # first trial step
//! h_min_s = 1e-12                 # below this the run stops (step-size collapse)
//! h_max_s = 1e-3                  # largest step (default: the output interval)
//! volume_correction = true        # no-flux velocity correction + rescaling to the initial volume
//! max_area_change = 0.05          # stop when |A/A0 - 1| exceeds this
//! max_fold_deg = 120.0            # stop when the normals of two adjacent triangles differ by more (under-resolved fold)
//! kinematics = "material"         # material | normal (vertices move with (u.n) n: drops only)
//! controller = "pi"               # step-size control: pi (Gustafsson's PI.3.4) | integral;
//!                                 #   default pi for bs23 and with penalty walls, integral for the
//!                                 #   Rosenbrock schemes otherwise
//! error_norm = "max"              # max (every vertex within atol) | rms (root-mean-square over vertices)
//! wall_atol_um = 4e-5             # penalty walls only: absolute tolerance on the wall displacements
//!                                 #   (default atol_um; solver/README.md, "Session 23")
//! wall_coupling = false           # penalty walls with a -mobility scheme: the walls' answer to the cell
//!                                 #   in each stage (one velocity evaluation more a stage); removes the
//!                                 #   drift towards the axis that the walls' lag adds (solver/README.md, "Session 37")
//!
//! [time]
//! end_s = 0.05
//! output_interval_s = 0.001
//! ```
//!
//! Parsing is in two stages (raw serde structs with unknown fields refused,
//! then `Scene::validate`): every error is one line naming the file and the
//! field (`scene.toml: field `fluid.lambda`: must be a finite number > 0, got -1`).

use crate::error::{Result, SchemaError};
use crate::recording::{non_negative, positive};
use std::path::{Path, PathBuf};

mod raw;
mod validate;

// ---------------------------------------------------------------------------
// Typed, validated scene.

/// Initial shape of the cell.
#[derive(Debug, Clone, PartialEq)]
pub enum CellShape {
    /// Sphere of radius `radius_um` (um).
    Sphere { radius_um: f64 },
    /// Evans-Fung discocyte scaled to R_RBC = 4 um (physics.md), symmetry axis `axis` (unit vector).
    Discocyte { axis: [f64; 3] },
    /// A snapshot of an earlier run in a results file (`snapshot` < 0 counts from the end).
    MeshFromResults { results: PathBuf, run: String, snapshot: i64 },
}

/// The cell: initial shape, mesh level and centroid position.
#[derive(Debug, Clone, PartialEq)]
pub struct CellSpec {
    pub shape: CellShape,
    /// Refinement level of the mesh generator (0..=6).
    pub level: u32,
    /// Centroid at t = 0 (um).
    pub position_um: [f64; 3],
}

/// Reference (stress-free) shape of the in-plane elastic law.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reference {
    /// The initial shape of the run.
    Initial,
    /// The Evans-Fung discocyte (the paper's choice).
    Discocyte,
    /// A sphere of the cell's volume.
    Sphere,
}

/// The Skalak law, with its convention named (physics.md, "Membrane forces").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SkalakSpec {
    /// Barthes-Biesel: `w = Gs/4 (I1^2 + 2 I1 - 2 I2 + C I2^2)`; shear modulus `Gs` (N/m), area modulus `Gs (1 + 2C)`.
    BarthesBiesel { shear_modulus_n_m: f64, c: f64 },
    /// Krueger / the authors' group: `w = kS/12 (I1^2 + 2 I1 - 2 I2) + kA/12 I2^2` (N/m).
    Krueger { kappa_s_n_m: f64, kappa_a_n_m: f64 },
}

/// Membrane mechanics: any combination of Skalak elasticity, bending and tension (at least one).
#[derive(Debug, Clone, PartialEq)]
pub struct MembraneSpec {
    pub reference: Reference,
    pub skalak: Option<SkalakSpec>,
    /// Canham-Helfrich bending modulus (N m).
    pub bending_n_m: Option<f64>,
    /// Discrete bending method (`method-c`, `quartic-fit`, `quartic-fit-galerkin`; checked by the solver); None: the solver's default.
    pub bending_method: Option<String>,
    /// Isotropic surface tension (N/m).
    pub tension_n_m: Option<f64>,
}

/// Newtonian fluids outside and inside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluidSpec {
    /// Outer viscosity (Pa s).
    pub viscosity_pa_s: f64,
    /// Viscosity ratio inner / outer.
    pub lambda: f64,
}

/// Undisturbed background flow.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FlowSpec {
    None,
    /// `u = (rate z, 0, 0)` (1/s): flow along x, gradient along z, vorticity along -y.
    Shear { rate_1_s: f64 },
    /// Unbounded circular Poiseuille flow `u_x = umax (1 - (y^2 + z^2)/R^2)`.
    Poiseuille { max_velocity_um_s: f64, radius_um: f64 },
}

/// How the channel walls are imposed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WallModel {
    /// Exact no-slip: the wall traction solves a first-kind equation (dense operator factorised once).
    NoSlip,
    /// The paper's penalty springs: wall traction `-kappa_W d` for the wall displacement `d`
    /// (stiffness in N/m^3; the paper: 1.9e7); the wall vertices move with the fluid.
    Penalty { kappa_w_n_m3: f64 },
}

/// Confinement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WallsSpec {
    None,
    /// The paper's periodic rectangular channel with rounded corners (lengths in um, mean
    /// velocity = flux / cross-section in um/s), its wall model, the wall mesh edge (um) and
    /// the relative error of the Ewald sums.
    PeriodicChannel {
        length_x_um: f64,
        width_y_um: f64,
        height_z_um: f64,
        mean_velocity_um_s: f64,
        corner_radius_um: f64,
        wall_model: WallModel,
        wall_edge_um: f64,
        ewald_tol: f64,
    },
}

impl WallsSpec {
    /// Penalty walls: their displacements are part of a run's state, after the cell's vertices.
    pub fn has_penalty_walls(&self) -> bool {
        matches!(self, WallsSpec::PeriodicChannel { wall_model: WallModel::Penalty { .. }, .. })
    }
}

/// Defaults of the periodic channel: corner radius 1.5 um, wall edge 1.38 um (2160 wall
/// triangles in the paper's channel; the paper: 2166), Ewald tolerance 5e-5 (the paper's).
pub const DEFAULT_CORNER_RADIUS_UM: f64 = 1.5;
pub const DEFAULT_WALL_EDGE_UM: f64 = 1.38;
pub const DEFAULT_EWALD_TOL: f64 = 5e-5;

/// Time-stepping scheme.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// Explicit adaptive Bogacki-Shampine 3(2) (the paper's).
    Bs23,
    /// Linearly implicit Rosenbrock-W ROS2 (stiff membrane modes implicit).
    Ros2,
    /// Rosenbrock-W ROS34PW2 (order 3, embedded 2), preconditioned stage solves.
    Ros34pw2,
    /// ROS34PW2 with the local sparse Jacobian as its `J` (direct stage solves, no extra Stokes solves).
    Ros34pw2Local,
    /// ROS34PW2 with the dense free-space two-fluid mobility times the stiffness as its `J`
    /// (dense LU kept for several steps, no extra Stokes solves).
    Ros34pw2Mobility,
    /// The same Jacobian with the three-stage W-method ROS3Pw (Rang & Angermann 2005): order 3 (2),
    /// three velocity evaluations a step instead of four.
    Ros3pwMobility,
    /// The same Jacobian with ROS34PW3 (Rang & Angermann 2005): four stages, W-order 3, classical order 4.
    Ros34pw3Mobility,
    /// The same Jacobian with ROS34PRw (Rang 2015): four stages, W-order 3, L-stable, stiffly accurate.
    Ros34prwMobility,
    /// The same Jacobian with RosW6S4 (Rahunanthan & Stanescu 2010): six stages, W-order 4, with an
    /// embedded W-order-3 solution of this crate's choosing.
    Rosw6s4Mobility,
}

impl Scheme {
    /// A W-method with the dense mobility Jacobian (`-mobility`), the schemes that carry the
    /// penalty walls' own block in their stage matrix.
    pub fn is_mobility(self) -> bool {
        match self {
            Scheme::Ros34pw2Mobility | Scheme::Ros3pwMobility | Scheme::Ros34pw3Mobility | Scheme::Ros34prwMobility | Scheme::Rosw6s4Mobility => true,
            Scheme::Bs23 | Scheme::Ros2 | Scheme::Ros34pw2 | Scheme::Ros34pw2Local => false,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Scheme::Bs23 => "bs23",
            Scheme::Ros2 => "ros2",
            Scheme::Ros34pw2 => "ros34pw2",
            Scheme::Ros34pw2Local => "ros34pw2-local",
            Scheme::Ros34pw2Mobility => "ros34pw2-mobility",
            Scheme::Ros3pwMobility => "ros3pw-mobility",
            Scheme::Ros34pw3Mobility => "ros34pw3-mobility",
            Scheme::Ros34prwMobility => "ros34prw-mobility",
            Scheme::Rosw6s4Mobility => "rosw6s4-mobility",
        }
    }
}

/// How vertices move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kinematics {
    /// With the fluid (material points; required with in-plane elasticity).
    Material,
    /// With the normal component of the fluid velocity only (drops: keeps the mesh regular).
    Normal,
}

/// Step-size controller of the adaptive schemes (`e_n` the error norm of step n, `k` the order of
/// the local error estimate; equations in `rbc_solver::run::Controller`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepController {
    /// Integral controller `h_new = h 0.9 e_n^(-1/k)` (Hairer, Norsett & Wanner I, sec. II.4).
    Integral,
    /// PI controller `h_new = h 0.9^0.3 e_n^(-0.7/k) e_(n-1)^(0.4/k)` (Gustafsson's PI.3.4, ACM TOMS 17, 1991).
    Pi,
}

impl StepController {
    /// The default of `scheme` when a scene names none, chosen by measurement (the module docs
    /// of `src/bench/channel_tol.rs` and `src/bench/controller.rs`): PI for the explicit bs23,
    /// whose rejections PI cuts 2-4x in the channel (9-14 % fewer velocity evaluations, equal
    /// errors); integral for the linearly implicit schemes, which reject less and which PI.3.4's
    /// slower step growth (integral gain 0.3 instead of 1) gives 11-16 % more accepted steps,
    /// 6 % more evaluations in the channel at ros34pw2-local's 1e-3 um, for 1.4-2.3x smaller errors.
    /// With penalty walls (`penalty_walls`) PI for every scheme: there the walls set the step, and
    /// their error norm swings 0.45-1.1 at a constant step as the traction pattern that travels
    /// with the cell passes the wall vertices (a period of ~4-5 steps), which the integral
    /// controller follows into a rejection every ~5 steps; PI.3.4 rejects ~10x less on a settled
    /// croissant (33 of 173 attempts against 3 of 140 over 10 ms; 2.3x less on a slipper)
    /// (`solver/README.md`, "Session 33").
    pub fn default_for(scheme: Scheme, penalty_walls: bool) -> Self {
        match scheme {
            _ if penalty_walls => StepController::Pi,
            Scheme::Bs23 => StepController::Pi,
            Scheme::Ros2 | Scheme::Ros34pw2 | Scheme::Ros34pw2Local | Scheme::Ros34pw2Mobility | Scheme::Ros3pwMobility | Scheme::Ros34pw3Mobility | Scheme::Ros34prwMobility | Scheme::Rosw6s4Mobility => StepController::Integral,
        }
    }
}

/// Integrator and tolerances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntegratorSpec {
    pub scheme: Scheme,
    /// Absolute tolerance on vertex positions (um). Default 4e-5 = 1e-5 R_RBC (paper).
    pub atol_um: f64,
    /// First trial step (s). Default 1e-6.
    pub h0_s: f64,
    /// Minimal step (s) before the run is declared failed. Default 1e-12.
    pub h_min_s: f64,
    /// Maximal step (s). Default: the output interval.
    pub h_max_s: f64,
    /// No-flux correction and rescaling to the initial volume. Default true.
    pub volume_correction: bool,
    /// Maximal relative area change before the run stops. Default 0.05.
    pub max_area_change: f64,
    /// Largest angle (degrees) between the normals of two triangles sharing an edge before the
    /// run stops as under-resolved. Default 120.
    pub max_fold_deg: f64,
    /// Vertex motion. Default material.
    pub kinematics: Kinematics,
    /// Step-size controller. Default [`StepController::default_for`] the scheme and the walls.
    pub controller: StepController,
    /// Error norm of the step control: `max_i |err_i|` (default) or the root-mean-square over
    /// the vertices (`rbc_solver::run::ErrorNorm`).
    pub error_norm_rms: bool,
    /// Absolute tolerance (um) on the local error of the penalty walls' displacements, which
    /// are part of the state (`rbc_solver::dynamics::penalty`). Default `atol_um`; only with
    /// `walls.wall_model = "penalty"`.
    pub wall_atol_um: f64,
    /// The penalty walls' answer to the cell in the W-methods' stage matrix
    /// (`rbc_solver::integrate::wall_block::WallCoupling`). Default false; only with
    /// `walls.wall_model = "penalty"` and a `-mobility` scheme.
    pub wall_coupling: bool,
}

/// Simulated interval and output cadence.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeSpec {
    pub end_s: f64,
    pub output_interval_s: f64,
}

/// A validated scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The file it was read from (for messages).
    pub path: PathBuf,
    /// The scene's text, stored with the run (results.h5 attribute `scene`).
    pub source: String,
    pub name: String,
    pub cell: CellSpec,
    pub membrane: MembraneSpec,
    pub fluid: FluidSpec,
    pub flow: FlowSpec,
    pub walls: WallsSpec,
    pub integrator: IntegratorSpec,
    pub time: TimeSpec,
}

/// Largest accepted mesh level (level 6 is 80k triangles on an icosahedral sphere).
pub const MAX_LEVEL: u32 = 6;


/// Radius of the Evans-Fung discocyte (um): `R_RBC` (physics.md).
pub const DISCOCYTE_RADIUS_UM: f64 = 4.0;
/// Half the largest thickness of the Evans-Fung discocyte at `R_RBC = 4 um` (um): the maximum over the
/// profile of `0.5 (4 / 3.91) sqrt(1 - s^2) (0.81 + 7.83 s^2 - 4.39 s^4)` is 1.3124 um, rounded up.
pub const DISCOCYTE_HALF_THICKNESS_UM: f64 = 1.32;

/// Half extents (um) of the initial cell along x, y and z, from its shape alone (not its position):
/// exact for spheres and for a discocyte whose axis is a coordinate axis, an upper bound for tilted
/// axes (`R sqrt(1 - a_k^2) + T |a_k|`); `None` for a mesh from a results file (size unknown here).
pub fn cell_half_extents_um(shape: &CellShape) -> Option<[f64; 3]> {
    match shape {
        CellShape::Sphere { radius_um } => Some([*radius_um; 3]),
        CellShape::Discocyte { axis } => Some(axis.map(|a| DISCOCYTE_RADIUS_UM * (1.0 - a * a).max(0.0).sqrt() + DISCOCYTE_HALF_THICKNESS_UM * a.abs())),
        CellShape::MeshFromResults { .. } => None,
    }
}

impl Scene {
    /// Whether `other` describes the same simulation as `self` up to how its time steps are
    /// taken and how long it runs: everything equal (cell, membrane, fluid, flow, walls, the
    /// output interval, and the integrator's volume correction, area and fold limits and
    /// kinematics, which are part of the model) except the integrator's scheme, tolerances (the
    /// walls' `wall_atol_um` too), step bounds, controller, error norm and `wall_coupling`, and
    /// the end time `time.end_s`. A run may continue from
    /// a checkpoint of such a scene with the other step method (a study switching to a faster
    /// scheme keeps its simulated time) or run on to a later end (the paper's croissants settle
    /// only after 10-30 s, Guckenberger et al. 2018 Sec. 4.1); the text and path are not compared,
    /// nor the folder of a `mesh-from-results` start shape's file (its name, run and snapshot
    /// are): a sweep writes that path resolved, and a study's checkout may move between sessions.
    pub fn same_but_stepping(&self, other: &Scene) -> bool {
        let mut o = other.clone();
        o.source.clone_from(&self.source);
        o.path.clone_from(&self.path);
        if let (CellShape::MeshFromResults { results: a, .. }, CellShape::MeshFromResults { results: b, .. }) = (&self.cell.shape, &mut o.cell.shape) {
            if a.file_name() == b.file_name() {
                b.clone_from(a);
            }
        }
        o.time.end_s = self.time.end_s;
        let (a, b) = (&self.integrator, &mut o.integrator);
        b.scheme = a.scheme;
        b.atol_um = a.atol_um;
        b.h0_s = a.h0_s;
        b.h_min_s = a.h_min_s;
        b.h_max_s = a.h_max_s;
        b.controller = a.controller;
        b.error_norm_rms = a.error_norm_rms;
        b.wall_atol_um = a.wall_atol_um;
        b.wall_coupling = a.wall_coupling;
        o == *self
    }

    /// Whether the scene text `stored` (a results file's `scene` attribute) describes the same
    /// run as `self`: the same text, or a scene that is [`Self::same_but_stepping`] this one. The
    /// one test `rbc-simulate --resume`, a sweep task's resume and `rbc-sweep run`'s check of
    /// the runs it keeps all apply. `Err` when `stored` does not parse (read against `self.path`).
    pub fn runs_as(&self, stored: &str) -> Result<bool> {
        if stored == self.source {
            return Ok(true);
        }
        Ok(self.same_but_stepping(&Scene::parse(stored, &self.path)?))
    }

    /// One line naming the step method: scheme, atol (and the walls' own, if any), largest
    /// step, controller, norm.
    pub fn stepping_summary(&self) -> String {
        let i = &self.integrator;
        let mut walls = if i.wall_atol_um != i.atol_um { format!(" (walls {:e} um)", i.wall_atol_um) } else { String::new() };
        if i.wall_coupling {
            walls.push_str(" with the walls coupled");
        }
        format!("{} at atol {:e} um{walls}, h_max {:e} s, {:?} control, {} norm", i.scheme.name(), i.atol_um, i.h_max_s, i.controller, if i.error_norm_rms { "rms" } else { "max" })
    }

    /// Read and validate a scene file.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| SchemaError::io(path, e))?;
        Self::parse(&text, path)
    }

    /// Parse and validate scene text; `path` names the file in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let raw: raw::RawScene = toml::from_str(text).map_err(|e| validate::toml_error_with_line(path, text, &e))?;
        Self::validate(raw, text, path)
    }

}

#[cfg(test)]
mod tests {
    use super::*;

    const CAPSULE: &str = r#"
name = "capsule"
[cell]
shape = "sphere"
level = 3
radius_um = 4.0
[membrane.skalak]
convention = "barthes-biesel"
shear_modulus_n_m = 5e-6
c = 1.0
[fluid]
viscosity_pa_s = 1.2e-3
lambda = 1.0
[flow]
kind = "shear"
shear_rate_1_s = 10.0
[time]
end_s = 0.1
output_interval_s = 0.01
"#;

    fn p() -> &'static Path {
        Path::new("scenes/capsule.toml")
    }

    #[test]
    fn every_scheme_name_parses_to_its_scheme() {
        for scheme in [Scheme::Bs23, Scheme::Ros2, Scheme::Ros34pw2, Scheme::Ros34pw2Local, Scheme::Ros34pw2Mobility, Scheme::Ros3pwMobility, Scheme::Ros34pw3Mobility, Scheme::Ros34prwMobility, Scheme::Rosw6s4Mobility] {
            let s = Scene::parse(&format!("{CAPSULE}[integrator]\nscheme = \"{}\"\n", scheme.name()), p()).unwrap();
            assert_eq!(s.integrator.scheme, scheme);
        }
        let err = Scene::parse(&format!("{CAPSULE}[integrator]\nscheme = \"ros3p\"\n"), p()).unwrap_err().to_string();
        assert!(err.contains("ros3pw-mobility"), "{err}");
    }

    /// The step method may change between a checkpoint and its resume; the model may not.
    #[test]
    fn same_but_stepping_ignores_the_step_method_and_end_time_only() {
        let base = Scene::parse(CAPSULE, p()).unwrap();
        let with = |extra: &str| Scene::parse(&format!("{CAPSULE}{extra}"), p()).unwrap();
        let stepping = with("[integrator]\nscheme = \"ros34pw2-mobility\"\natol_um = 1e-2\nh0_s = 1e-7\nh_min_s = 1e-14\nh_max_s = 0.005\ncontroller = \"pi\"\nerror_norm = \"rms\"\n");
        assert!(base.same_but_stepping(&stepping) && stepping.same_but_stepping(&base));
        assert!(base.same_but_stepping(&with("# a comment changes the text only\n")));
        for model in ["volume_correction = false", "max_area_change = 0.1", "max_fold_deg = 100.0"] {
            assert!(!base.same_but_stepping(&with(&format!("[integrator]\n{model}\n"))), "{model}");
        }
        assert!(!base.same_but_stepping(&Scene::parse(&CAPSULE.replace("lambda = 1.0", "lambda = 5.0"), p()).unwrap()));
        assert!(base.same_but_stepping(&Scene::parse(&CAPSULE.replace("end_s = 0.1", "end_s = 0.2"), p()).unwrap()));
        let every = CAPSULE.lines().find(|l| l.starts_with("output_interval_s")).unwrap();
        assert!(!base.same_but_stepping(&Scene::parse(&CAPSULE.replace(every, "output_interval_s = 0.05"), p()).unwrap()));
        assert!(stepping.stepping_summary().starts_with("ros34pw2-mobility at atol 1e-2 um"), "{}", stepping.stepping_summary());
    }

    /// A stored scene text is this run's when it is the same text or the same model stepped
    /// otherwise; one this build cannot read is an error, not silently another run.
    #[test]
    fn runs_as_accepts_the_same_model_and_reports_an_unreadable_stored_scene() {
        let base = Scene::parse(CAPSULE, p()).unwrap();
        assert!(base.runs_as(CAPSULE).unwrap());
        assert!(base.runs_as(&format!("{CAPSULE}# only a comment\n")).unwrap());
        assert!(base.runs_as(&CAPSULE.replace("end_s = 0.1", "end_s = 0.2")).unwrap());
        assert!(!base.runs_as(&CAPSULE.replace("lambda = 1.0", "lambda = 5.0")).unwrap());
        let err = base.runs_as("name = \"broken\"\n[cell\n").unwrap_err().to_string();
        assert!(err.contains(&p().display().to_string()), "{err}");
    }

    /// A start shape read from a file is the same start wherever the file's folder is (a study's
    /// checkout moved), not under another file name, run or snapshot.
    #[test]
    fn same_but_stepping_compares_a_start_shapes_file_by_name_run_and_snapshot() {
        let cell = |results: &str, run: &str, snapshot: i64| {
            let text = CAPSULE.replace("shape = \"sphere\"", &format!("shape = \"mesh-from-results\"\nresults = \"{results}\"\nrun = \"{run}\"\nsnapshot = {snapshot}")).replace("radius_um = 4.0\n", "");
            Scene::parse(&text, p()).unwrap()
        };
        let here = cell("/work/a/examples/sweeps/starts.h5", "croissant-start", -1);
        assert!(here.same_but_stepping(&cell("/elsewhere/examples/sweeps/starts.h5", "croissant-start", -1)));
        for other in [cell("/work/a/examples/sweeps/other.h5", "croissant-start", -1), cell("/work/a/examples/sweeps/starts.h5", "slipper-start", -1), cell("/work/a/examples/sweeps/starts.h5", "croissant-start", 0)] {
            assert!(!here.same_but_stepping(&other), "{:?}", other.cell.shape);
        }
    }

    fn err(text: &str) -> String {
        let e = Scene::parse(text, p()).unwrap_err().to_string();
        assert!(e.contains("scenes/capsule.toml"), "error does not name the file: {e}");
        assert!(!e.contains('\n'), "error is not one line: {e}");
        e
    }

    #[test]
    fn parses_capsule_with_defaults() {
        let s = Scene::parse(CAPSULE, p()).unwrap();
        assert_eq!(s.name, "capsule");
        assert_eq!(s.cell.shape, CellShape::Sphere { radius_um: 4.0 });
        assert_eq!(s.cell.position_um, [0.0; 3]);
        assert_eq!(s.membrane.reference, Reference::Initial);
        assert_eq!(s.membrane.skalak, Some(SkalakSpec::BarthesBiesel { shear_modulus_n_m: 5e-6, c: 1.0 }));
        assert_eq!(s.flow, FlowSpec::Shear { rate_1_s: 10.0 });
        assert_eq!(s.walls, WallsSpec::None);
        // defaults: the paper's tolerance 1e-5 R_RBC, h_max = output interval
        assert_eq!(s.integrator.scheme, Scheme::Bs23);
        assert_eq!(s.integrator.atol_um, 4e-5);
        assert_eq!(s.integrator.h_max_s, 0.01);
        assert!(s.integrator.volume_correction);
        assert_eq!(s.integrator.max_fold_deg, 120.0);
        assert_eq!(s.integrator.controller, StepController::Pi, "the default of bs23");
        assert_eq!(s.source, CAPSULE);
    }

    #[test]
    fn error_norm_is_parsed_and_checked() {
        assert!(!Scene::parse(CAPSULE, p()).unwrap().integrator.error_norm_rms, "max by default");
        for (name, rms) in [("max", false), ("rms", true)] {
            let s = Scene::parse(&format!("{CAPSULE}[integrator]\nerror_norm = \"{name}\"\n"), p()).unwrap();
            assert_eq!(s.integrator.error_norm_rms, rms, "{name}");
        }
        let e = err(&format!("{CAPSULE}[integrator]\nerror_norm = \"l2\"\n"));
        assert!(e.contains("integrator.error_norm") && e.contains("l2") && e.lines().count() == 1, "{e}");
    }

    #[test]
    fn step_controller_is_parsed_and_checked() {
        for (name, want) in [("pi", StepController::Pi), ("integral", StepController::Integral)] {
            let s = Scene::parse(&format!("{CAPSULE}[integrator]\ncontroller = \"{name}\"\n"), p()).unwrap();
            assert_eq!(s.integrator.controller, want, "{name}");
        }
        let ros = Scene::parse(&format!("{CAPSULE}[integrator]\nscheme = \"ros34pw2-local\"\n"), p()).unwrap();
        assert_eq!(ros.integrator.controller, StepController::Integral, "the default of the Rosenbrock schemes");
        let e = err(&format!("{CAPSULE}[integrator]\ncontroller = \"pid\"\n"));
        assert!(e.contains("integrator.controller") && e.contains("pid"), "{e}");
        // a wrong type is refused by the raw stage, with the line
        let e = err(&format!("{CAPSULE}[integrator]\ncontroller = 1\n"));
        assert!(e.contains("string") && e.contains("line 21"), "{e}");
    }

    #[test]
    fn out_of_range_fields_are_named() {
        assert!(err(&CAPSULE.replace("lambda = 1.0", "lambda = -1.0")).contains("fluid.lambda"));
        assert!(err(&CAPSULE.replace("level = 3", "level = 9")).contains("cell.level"));
        assert!(err(&CAPSULE.replace("radius_um = 4.0", "radius_um = 0.0")).contains("cell.radius_um"));
        assert!(err(&CAPSULE.replace("c = 1.0", "c = -0.1")).contains("membrane.skalak.c"));
        assert!(err(&CAPSULE.replace("output_interval_s = 0.01", "output_interval_s = 1.0")).contains("time.output_interval_s"));
        assert!(err(&format!("{CAPSULE}[integrator]\nscheme = \"euler\"\n")).contains("integrator.scheme"));
        assert!(err(&format!("{CAPSULE}[integrator]\nmax_fold_deg = 200.0\n")).contains("integrator.max_fold_deg"));
        // normal-only kinematics would detach the elastic reference from the material
        assert!(err(&format!("{CAPSULE}[integrator]\nkinematics = \"normal\"\n")).contains("integrator.kinematics"));
        assert!(err(&CAPSULE.replace("kind = \"shear\"", "kind = \"couette\"")).contains("flow.kind"));
        // the name is the run id of the results file: refused here, naming the scene's field
        for bad in ["a/b", "", ".", ".."] {
            assert!(err(&CAPSULE.replace("name = \"capsule\"", &format!("name = \"{bad}\""))).contains("`name`"), "{bad}");
        }
    }

    /// Values far outside what they can mean physically (found by a probe: a radius of 1e-300 um
    /// gave a degenerate mesh without naming the field, lambda, C or a shear rate of 1e300 a
    /// non-finite first step after the run was appended, an output interval of 1e-300 s an error
    /// naming integrator.h_min_s) are refused when the scene is read, naming the field.
    #[test]
    fn physically_meaningless_values_are_named() {
        let integrator = |line: &str| format!("{CAPSULE}[integrator]\n{line}\n");
        let cases = [
            (CAPSULE.replace("radius_um = 4.0", "radius_um = 1e-300"), "cell.radius_um"),
            (CAPSULE.replace("radius_um = 4.0", "radius_um = 1e300"), "cell.radius_um"),
            (CAPSULE.replace("shape = \"sphere\"", "shape = \"sphere\"\nposition_um = [1e300, 0.0, 0.0]"), "cell.position_um"),
            (CAPSULE.replace("c = 1.0", "c = 1e300"), "membrane.skalak.c"),
            (CAPSULE.replace("shear_modulus_n_m = 5e-6", "shear_modulus_n_m = 1e-300"), "membrane.skalak.shear_modulus_n_m"),
            (CAPSULE.replace("viscosity_pa_s = 1.2e-3", "viscosity_pa_s = 1e300"), "fluid.viscosity_pa_s"),
            (CAPSULE.replace("lambda = 1.0", "lambda = 1e300"), "fluid.lambda"),
            (CAPSULE.replace("shear_rate_1_s = 10.0", "shear_rate_1_s = 1e300"), "flow.shear_rate_1_s"),
            (CAPSULE.replace("end_s = 0.1", "end_s = 1e300"), "time.end_s"),
            (CAPSULE.replace("output_interval_s = 0.01", "output_interval_s = 1e-300"), "time.output_interval_s"),
            (integrator("atol_um = 1e-300"), "integrator.atol_um"),
            (integrator("atol_um = 1e300"), "integrator.atol_um"),
        ];
        for (text, field) in cases {
            let e = err(&text);
            assert!(e.contains(field) && e.contains("plausible range") && !e.contains('\n') && e.len() < 200, "{field}: {e}");
        }
        let krueger = CAPSULE.replace("convention = \"barthes-biesel\"\nshear_modulus_n_m = 5e-6\nc = 1.0", "convention = \"krueger\"\nkappa_s_n_m = 5e-6\nkappa_a_n_m = 1e300");
        assert!(err(&krueger).contains("membrane.skalak.kappa_a_n_m"));
        // the paper's and the examples' values stay far inside
        assert!(Scene::parse(&krueger.replace("kappa_a_n_m = 1e300", "kappa_a_n_m = 5e-4"), p()).is_ok());
        assert!(Scene::parse(&krueger.replace("kappa_a_n_m = 1e300", "kappa_a_n_m = 0.0"), p()).is_ok());
    }

    #[test]
    fn missing_fields_are_named() {
        assert!(err(&CAPSULE.replace("radius_um = 4.0\n", "")).contains("cell.radius_um"));
        assert!(err(&CAPSULE.replace("shear_rate_1_s = 10.0\n", "")).contains("flow.shear_rate_1_s"));
        assert!(err(&CAPSULE.replace("c = 1.0\n", "")).contains("membrane.skalak.c"));
        let e = err(&CAPSULE.replace("lambda = 1.0\n", ""));
        assert!(e.contains("lambda") && e.contains("line"), "{e}");
    }

    #[test]
    fn convention_fields_cannot_be_mixed() {
        let e = err(&CAPSULE.replace("c = 1.0", "kappa_a_n_m = 5e-4"));
        assert!(e.contains("membrane.skalak.kappa_a_n_m"), "{e}");
        let krueger = CAPSULE.replace(
            "convention = \"barthes-biesel\"\nshear_modulus_n_m = 5e-6\nc = 1.0",
            "convention = \"krueger\"\nkappa_s_n_m = 5e-6\nkappa_a_n_m = 5e-4",
        );
        let s = Scene::parse(&krueger, p()).unwrap();
        assert_eq!(s.membrane.skalak, Some(SkalakSpec::Krueger { kappa_s_n_m: 5e-6, kappa_a_n_m: 5e-4 }));
        assert!(err(&krueger.replace("kappa_s_n_m = 5e-6", "kappa_s_n_m = 5e-6\nc = 1.0")).contains("membrane.skalak.c"));
    }

    #[test]
    fn unknown_fields_are_refused() {
        let e = err(&CAPSULE.replace("lambda = 1.0", "lambda = 1.0\nlamda = 2.0"));
        assert!(e.contains("lamda"), "{e}");
    }

    #[test]
    fn periodic_channel_parses_with_its_fields() {
        let text = CAPSULE.replace("[flow]\nkind = \"shear\"\nshear_rate_1_s = 10.0\n", "")
            + "[walls]\nkind = \"periodic-channel\"\nlength_x_um = 42.7\nwidth_y_um = 12.0\nheight_z_um = 10.0\nmean_velocity_um_s = 1000.0\n";
        let s = Scene::parse(&text, p()).unwrap();
        assert_eq!(
            s.walls,
            WallsSpec::PeriodicChannel {
                length_x_um: 42.7,
                width_y_um: 12.0,
                height_z_um: 10.0,
                mean_velocity_um_s: 1000.0,
                corner_radius_um: DEFAULT_CORNER_RADIUS_UM,
                wall_model: WallModel::NoSlip,
                wall_edge_um: DEFAULT_WALL_EDGE_UM,
                ewald_tol: DEFAULT_EWALD_TOL,
            }
        );
        assert!(err(&text.replace("height_z_um = 10.0\n", "")).contains("walls.height_z_um"));
        // penalty walls need their stiffness; no-slip walls refuse one
        let penalty = format!("{text}wall_model = \"penalty\"\nkappa_w_n_m3 = 1.9e7\nwall_edge_um = 2.0\newald_tol = 1e-4\n");
        match Scene::parse(&penalty, p()).unwrap().walls {
            WallsSpec::PeriodicChannel { wall_model, wall_edge_um, ewald_tol, .. } => {
                assert_eq!(wall_model, WallModel::Penalty { kappa_w_n_m3: 1.9e7 });
                assert_eq!((wall_edge_um, ewald_tol), (2.0, 1e-4));
            }
            other => panic!("{other:?}"),
        }
        assert!(err(&penalty.replace("kappa_w_n_m3 = 1.9e7\n", "")).contains("walls.kappa_w_n_m3"));
        assert!(err(&penalty.replace("kappa_w_n_m3 = 1.9e7", "kappa_w_n_m3 = -1.0")).contains("walls.kappa_w_n_m3"));
        assert!(err(&penalty.replace("\"penalty\"", "\"no-slip\"")).contains("walls.kappa_w_n_m3"));
        assert!(err(&penalty.replace("\"penalty\"", "\"springs\"")).contains("walls.wall_model"));
        assert!(err(&penalty.replace("wall_edge_um = 2.0", "wall_edge_um = 3.0")).contains("walls.wall_edge_um"));
        // the step controller's default: PI with penalty walls for every scheme, an explicit one kept
        for scheme in ["bs23", "ros34pw2-mobility", "ros34pw2-local"] {
            let with = |walls: &str, controller: &str| Scene::parse(&format!("{walls}[integrator]\nscheme = \"{scheme}\"\n{controller}"), p()).unwrap().integrator.controller;
            assert_eq!(with(&penalty, ""), StepController::Pi, "{scheme} with penalty walls");
            assert_eq!(with(&penalty, "controller = \"integral\"\n"), StepController::Integral, "{scheme}: the scene's own choice");
            let exact = if scheme == "bs23" { StepController::Pi } else { StepController::Integral };
            assert_eq!(with(&text, ""), exact, "{scheme} with exact walls");
        }
        assert!(err(&penalty.replace("ewald_tol = 1e-4", "ewald_tol = 0.5")).contains("walls.ewald_tol"));
        assert!(err(&format!("{text}corner_radius_um = 5.0\n")).contains("walls.corner_radius_um"));
        // the walls' displacements take atol_um unless given their own tolerance; exact walls
        // carry no state and refuse one
        assert_eq!(Scene::parse(&format!("{penalty}[integrator]\natol_um = 2e-3\n"), p()).unwrap().integrator.wall_atol_um, 2e-3);
        let own = Scene::parse(&format!("{penalty}[integrator]\natol_um = 2e-3\nwall_atol_um = 4e-5\n"), p()).unwrap();
        assert_eq!((own.integrator.atol_um, own.integrator.wall_atol_um), (2e-3, 4e-5));
        assert!(own.stepping_summary().contains("walls 4e-5 um"), "{}", own.stepping_summary());
        assert!(own.same_but_stepping(&Scene::parse(&format!("{penalty}[integrator]\natol_um = 2e-3\n"), p()).unwrap()), "a step-method key");
        assert!(err(&format!("{text}[integrator]\nwall_atol_um = 4e-5\n")).contains("integrator.wall_atol_um"));
        assert!(err(&format!("{penalty}[integrator]\nwall_atol_um = -1.0\n")).contains("integrator.wall_atol_um"));
        // the walls' answer to the cell in the stages: off by default, for penalty walls with a -mobility scheme only
        assert!(!own.integrator.wall_coupling);
        let coupled = Scene::parse(&format!("{penalty}[integrator]\nscheme = \"rosw6s4-mobility\"\nwall_coupling = true\n"), p()).unwrap();
        assert!(coupled.integrator.wall_coupling && coupled.stepping_summary().contains("walls coupled"), "{}", coupled.stepping_summary());
        assert!(coupled.same_but_stepping(&Scene::parse(&format!("{penalty}[integrator]\nscheme = \"rosw6s4-mobility\"\n"), p()).unwrap()), "a step-method key");
        assert!(err(&format!("{text}[integrator]\nscheme = \"rosw6s4-mobility\"\nwall_coupling = true\n")).contains("integrator.wall_coupling"));
        let bs23 = err(&format!("{penalty}[integrator]\nwall_coupling = true\n"));
        assert!(bs23.contains("integrator.wall_coupling") && bs23.contains("bs23"), "{bs23}");
    }

    /// A channel narrower, lower or shorter than the cell was accepted and left to the solver (found by
    /// probing); the scene is now refused where it is read, naming the wall dimension.
    #[test]
    fn channel_smaller_than_the_cell_is_refused_by_its_dimension() {
        let channel = CAPSULE.replace("[flow]\nkind = \"shear\"\nshear_rate_1_s = 10.0\n", "")
            + "[walls]\nkind = \"periodic-channel\"\nlength_x_um = 42.7\nwidth_y_um = 12.0\nheight_z_um = 10.0\nmean_velocity_um_s = 1000.0\nwall_edge_um = 2.0\ncorner_radius_um = 1.0\n";
        assert!(Scene::parse(&channel, p()).is_ok(), "a sphere of radius 4 um fits a 12 x 10 um channel");
        for (from, to, field) in [
            ("width_y_um = 12.0", "width_y_um = 8.0", "walls.width_y_um"),
            ("height_z_um = 10.0", "height_z_um = 7.9", "walls.height_z_um"),
            ("length_x_um = 42.7", "length_x_um = 8.0", "walls.length_x_um"),
        ] {
            let e = err(&channel.replace(from, to));
            assert!(e.contains(field) && e.contains("spans 8.00 um"), "{e}");
        }
        // the paper's discocyte (axis along the flow) spans 8 um across and 2.64 um along the channel
        let disco = channel.replace("shape = \"sphere\"", "shape = \"discocyte\"\naxis = [1.0, 0.0, 0.0]").replace("radius_um = 4.0\n", "");
        assert!(Scene::parse(&disco.replace("length_x_um = 42.7", "length_x_um = 3.0"), p()).is_ok());
        let e = err(&disco.replace("width_y_um = 12.0", "width_y_um = 7.5"));
        assert!(e.contains("walls.width_y_um") && e.contains("spans 8.00 um"), "{e}");
        let e = err(&disco.replace("length_x_um = 42.7", "length_x_um = 2.5"));
        assert!(e.contains("walls.length_x_um") && e.contains("spans 2.64 um"), "{e}");
        assert_eq!(cell_half_extents_um(&CellShape::Discocyte { axis: [0.0, 0.0, 1.0] }), Some([4.0, 4.0, DISCOCYTE_HALF_THICKNESS_UM]));
    }

    #[test]
    fn membrane_needs_a_law_and_discocyte_needs_no_radius() {
        let no_law = CAPSULE.replace("[membrane.skalak]\nconvention = \"barthes-biesel\"\nshear_modulus_n_m = 5e-6\nc = 1.0\n", "[membrane]\n");
        assert!(err(&no_law).contains("`membrane`"));
        let disco = CAPSULE.replace("shape = \"sphere\"", "shape = \"discocyte\"");
        assert!(err(&disco).contains("cell.radius_um"));
        let s = Scene::parse(&disco.replace("radius_um = 4.0\n", "axis = [0.0, 0.0, 2.0]\n"), p()).unwrap();
        assert_eq!(s.cell.shape, CellShape::Discocyte { axis: [0.0, 0.0, 1.0] });
    }

    #[test]
    fn mesh_from_results_path_is_relative_to_the_scene() {
        let text = CAPSULE.replace("shape = \"sphere\"", "shape = \"mesh-from-results\"\nresults = \"out/results.h5\"\nrun = \"r1\"").replace("radius_um = 4.0\n", "");
        let s = Scene::parse(&text, p()).unwrap();
        assert_eq!(s.cell.shape, CellShape::MeshFromResults { results: PathBuf::from("scenes/out/results.h5"), run: "r1".into(), snapshot: -1 });
    }
}
