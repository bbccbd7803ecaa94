//! Builds exactly what a validated scene needs (mesh, membrane laws, Stokes operator, run configuration) and runs it.
//!
//! Only the operators a scene asks for are assembled: the double layer (and its
//! GMRES) only for `lambda != 1`; no Ewald sums and no wall operators without a
//! periodic channel. `walls.kind = "periodic-channel"` assembles
//! [`crate::channel::ChannelStokes`] (wall mesh, Ewald sums, the dense wall operator
//! factorised once, the flux calibration) with the scene's mean flow; with exact
//! no-slip walls the cell's vertices are the state of the run, with penalty walls the
//! state is the cell's vertices followed by the wall displacements
//! ([`crate::dynamics::penalty`]). A viscosity ratio the channel solve cannot do is
//! refused as `scene field `fluid.lambda`: ...`.

use crate::bim::{BimOptions, FreeSpaceStokes, Stokes};
use crate::channel::{ChannelError, ChannelGeometry, ChannelMesh, ChannelOptions, ChannelStokes, WallMode};
use crate::dynamics::cell::CellDynamics;
use crate::dynamics::kinematics::normal_only;
use crate::dynamics::penalty::{cell_no_flux, cell_normal_only, PenaltyChannelDynamics};
use crate::dynamics::volume::{no_flux, VolumeCorrection};
use crate::error::SolverError;
use crate::flow::{BackgroundFlow, Quiescent, SimpleShear, UnboundedPoiseuille};
use crate::integrate::bs23::BogackiShampine;
use crate::integrate::check::Checks;
use crate::integrate::ros34pw2::{Method, Reuse, Ros34pw2, StageJacobian};
use crate::integrate::rosenbrock::Ros2;
use crate::integrate::wall_block::WallCoupling;
use crate::integrate::Linearised;
use crate::membrane::bending::{BendingMethod, Helfrich};
use crate::membrane::skalak::{Skalak, SkalakConvention};
use crate::membrane::tension::Tension;
use crate::membrane::Membrane;
use crate::mesh::{self, slices, Mesh};
use crate::viscosity::ViscosityContrast;
use crate::run::{CellOutput, Controller, ErrorNorm, Observer, RunConfig, RunSummary, Runner, StepControl};
use nalgebra::{Rotation3, Vector3};
use rbc_schema::scene::{CellShape, FlowSpec, Kinematics, Reference, Scene, Scheme, SkalakSpec, StepController, WallModel, WallsSpec};

/// The free-space Stokes solve with its background flow, as a [`Stokes`] for the integrators.
pub struct FreeSpace {
    pub solver: FreeSpaceStokes,
    pub background: Box<dyn BackgroundFlow>,
}

impl Stokes for FreeSpace {
    fn velocity(&self, mesh: &Mesh, f: &[Vector3<f64>], with_background: bool, guess: Option<&[Vector3<f64>]>) -> Result<Vec<Vector3<f64>>, SolverError> {
        let bg: &dyn BackgroundFlow = if with_background { &*self.background } else { &Quiescent };
        Ok(self.solver.velocity_with_guess(mesh, f, bg, guess)?.0)
    }
    fn viscosities(&self) -> Option<(f64, ViscosityContrast)> {
        Some((self.solver.viscosity(), self.solver.viscosity_ratio()))
    }
}

/// The Stokes operator of a scene.
pub enum Operator {
    /// Unbounded fluid with a background flow.
    FreeSpace(FreeSpace),
    /// The periodic channel (its mean flow set by [`ChannelStokes::with_mean_flow`]).
    Channel(Box<ChannelStokes>),
}

/// The scene's operator as a [`Stokes`] (no-slip channel or free space; penalty walls carry a
/// state and run through [`crate::dynamics::penalty::PenaltyChannelDynamics`] instead).
impl Stokes for Operator {
    fn velocity(&self, mesh: &Mesh, f: &[Vector3<f64>], with_background: bool, guess: Option<&[Vector3<f64>]>) -> Result<Vec<Vector3<f64>>, SolverError> {
        match self {
            Operator::FreeSpace(fs) => fs.velocity(mesh, f, with_background, guess),
            Operator::Channel(ch) => Stokes::velocity(&**ch, mesh, f, with_background, guess),
        }
    }
    fn viscosities(&self) -> Option<(f64, ViscosityContrast)> {
        match self {
            Operator::FreeSpace(fs) => fs.viscosities(),
            Operator::Channel(ch) => Stokes::viscosities(&**ch),
        }
    }
}

/// Everything a run of a scene needs.
pub struct Built {
    /// Initial membrane (um).
    pub mesh: Mesh,
    pub membrane: Membrane,
    pub stokes: Operator,
    pub run: RunConfig,
    pub scheme: Scheme,
    pub kinematics: Kinematics,
    /// The penalty walls' answer to the cell in the W-method's stages (`integrator.wall_coupling`).
    pub wall_coupling: bool,
    /// What was assembled, one line each (for logs and tests).
    pub assembled: Vec<String>,
}

fn unsupported(field: &str, message: impl Into<String>) -> SolverError {
    SolverError::Unsupported { field: field.to_string(), message: message.into() }
}

/// Rotation taking the generators' symmetry axis (z) onto `axis` (unit vector).
///
/// When `axis` is a coordinate axis (`+-x`, `+-y`, `+-z`) the rotation is a signed permutation
/// matrix and is returned exactly: `rotation_between` gives it with `cos(pi/2) = 6e-17` entries,
/// which would tilt the mesh by ~1e-16 rad and break the mirror symmetries that the octahedron
/// subdivision has exactly (the planes through the axis and the generators' x and y axes,
/// i.e. `y = 0` and `z = 0` for the channel axis x; `tests/mesh_symmetry.rs`).
pub fn axis_rotation(axis: [f64; 3]) -> Rotation3<f64> {
    let r = Rotation3::rotation_between(&Vector3::z(), &Vector3::from(axis)).unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
    let m = r.matrix();
    let snapped = m.map(|v| v.round());
    if (m - snapped).amax() < 1e-12 {
        Rotation3::from_matrix_unchecked(snapped)
    } else {
        r
    }
}

/// The initial mesh of the cell, centred on `cell.position_um`.
pub fn initial_mesh(scene: &Scene) -> Result<Mesh, SolverError> {
    let level = scene.cell.level as usize;
    let pos = Vector3::from(scene.cell.position_um);
    let m = match &scene.cell.shape {
        CellShape::Sphere { radius_um } => mesh::sphere(level, *radius_um),
        CellShape::Discocyte { axis } => mesh::discocyte(level).transformed(&axis_rotation(*axis), &Vector3::zeros()),
        CellShape::MeshFromResults { results, run, snapshot } => {
            let snaps = rbc_schema::results::read_snapshots(results, run)?;
            let k = snaps.times_s.len() as i64;
            let idx = if *snapshot < 0 { k + snapshot } else { *snapshot };
            if idx < 0 || idx >= k {
                return Err(unsupported("cell.snapshot", format!("{snapshot} is out of range: run {run} in {} has {k} snapshots", results.display())));
            }
            let verts = snaps.vertices_um[idx as usize].iter().map(|v| Vector3::from(*v)).collect();
            let tris = snaps.triangles.iter().map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
            let m = Mesh::from_arrays(verts, tris)?;
            let c = m.centroid();
            return Ok(m.transformed(&Rotation3::identity(), &(pos - c)));
        }
    };
    let c = m.centroid();
    Ok(m.transformed(&Rotation3::identity(), &(pos - c)))
}

/// The cross-section of a channel scene (`None` without walls).
fn channel_geometry(walls: &WallsSpec) -> Option<ChannelGeometry> {
    match *walls {
        WallsSpec::PeriodicChannel { length_x_um, width_y_um, height_z_um, corner_radius_um, .. } => {
            Some(ChannelGeometry { length_x: length_x_um, width_y: width_y_um, height_z: height_z_um, corner_radius: corner_radius_um })
        }
        WallsSpec::None => None,
    }
}

/// Where the initial cell of a channel scene meets the wall: the vertex closest to the wall of the
/// mesh the solver starts from, when it is closer than the channel solve allows
/// ([`ChannelOptions::min_wall_gap_um`], 0.1 um; the solve refuses such a cell at its first step).
#[derive(Debug, Clone, PartialEq)]
pub struct WallOverlap {
    /// Signed distance (um) of that vertex to the wall: negative beyond it.
    pub distance_um: f64,
    /// Its (y, z) (um).
    pub at_yz_um: [f64; 2],
    /// The gap the channel solve needs (um).
    pub min_gap_um: f64,
    /// The channel's cross-section (um).
    pub width_y_um: f64,
    pub height_z_um: f64,
}

impl std::fmt::Display for WallOverlap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [y, z] = self.at_yz_um;
        let (w, h, gap) = (self.width_y_um, self.height_z_um, self.min_gap_um);
        let channel = format!("the wall of the {w} x {h} um channel (walls.width_y_um x walls.height_z_um) at (y, z) = ({y:.2}, {z:.2}) um");
        if self.distance_um < 0.0 {
            write!(f, "the cell reaches {:.2} um into {channel}", -self.distance_um)
        } else {
            write!(f, "the cell comes within {:.3} um of {channel}, closer than the {gap} um the channel solve needs", self.distance_um)
        }
    }
}

/// The cell of `scene` where the run would start, against its channel's walls (see [`WallOverlap`]);
/// `None` without walls or when the cell fits. Builds the initial mesh only (a `mesh-from-results`
/// cell is read from its file).
pub fn wall_overlap(scene: &Scene) -> Result<Option<WallOverlap>, SolverError> {
    if channel_geometry(&scene.walls).is_none() {
        return Ok(None);
    }
    Ok(wall_overlap_of(&scene.walls, &initial_mesh(scene)?.vertices))
}

/// [`wall_overlap`] for the cell `vertices` (um), e.g. a start mesh moved to each offset of a sweep.
pub fn wall_overlap_of(walls: &WallsSpec, vertices: &[Vector3<f64>]) -> Option<WallOverlap> {
    let g = channel_geometry(walls)?;
    let min_gap_um = ChannelOptions::default().min_wall_gap_um;
    let (distance_um, v) = vertices.iter().map(|v| (g.wall_distance(v.y, v.z), v)).min_by(|a, b| a.0.total_cmp(&b.0))?;
    (distance_um < min_gap_um).then(|| WallOverlap { distance_um, at_yz_um: [v.y, v.z], min_gap_um, width_y_um: g.width_y, height_z_um: g.height_z })
}

/// The stress-free reference of the elastic law (same connectivity as `initial`).
fn reference_mesh(scene: &Scene, initial: &Mesh) -> Result<Mesh, SolverError> {
    let level = scene.cell.level as usize;
    let r = match scene.membrane.reference {
        Reference::Initial => return Ok(initial.clone()),
        Reference::Discocyte => {
            let axis = match &scene.cell.shape {
                CellShape::Discocyte { axis } => *axis,
                _ => [1.0, 0.0, 0.0],
            };
            mesh::discocyte(level).transformed(&axis_rotation(axis), &Vector3::zeros())
        }
        Reference::Sphere => {
            let v = initial.volume();
            mesh::sphere(level, (3.0 * v / (4.0 * std::f64::consts::PI)).cbrt())
        }
    };
    if r.triangles != initial.triangles {
        return Err(unsupported(
            "membrane.reference",
            format!("the reference shape at level {level} does not share the cell mesh's connectivity ({} vs {} triangles)", r.triangles.len(), initial.triangles.len()),
        ));
    }
    Ok(r)
}

/// Assemble what `scene` needs.
pub fn build(scene: &Scene) -> Result<Built, SolverError> {
    let mut assembled = Vec::new();
    let mesh = initial_mesh(scene)?;
    assembled.push(format!("cell: {} triangles, {} vertices", mesh.triangles.len(), mesh.vertices.len()));

    let mut membrane = Membrane::new();
    if let Some(sk) = scene.membrane.skalak {
        let reference = reference_mesh(scene, &mesh)?;
        let law = match sk {
            SkalakSpec::BarthesBiesel { shear_modulus_n_m, c } => Skalak::barthes_biesel(&reference, shear_modulus_n_m, c)?,
            SkalakSpec::Krueger { kappa_s_n_m, kappa_a_n_m } => Skalak::new(&reference, SkalakConvention::Krueger, kappa_s_n_m, kappa_a_n_m)?,
        };
        let (g, k) = law.small_strain_moduli();
        assembled.push(format!("skalak ({:?}): small-strain shear modulus {g:e} N/m, area modulus {k:e} N/m", law.convention()));
        membrane = membrane.with(law);
    }
    if let Some(kb) = scene.membrane.bending_n_m {
        let law = match &scene.membrane.bending_method {
            None => Helfrich::new(kb)?,
            Some(name) => {
                let method: BendingMethod = name.parse().map_err(|e: crate::membrane::MembraneError| unsupported("membrane.bending.method", e.to_string()))?;
                Helfrich::with_method(kb, method)?
            }
        };
        assembled.push(format!("helfrich bending {kb:e} N m ({})", scene.membrane.bending_method.as_deref().unwrap_or("default method")));
        membrane = membrane.with(law);
    }
    if let Some(gamma) = scene.membrane.tension_n_m {
        membrane = membrane.with(Tension::new(gamma)?);
        assembled.push(format!("tension {gamma:e} N/m"));
    }

    // the one viscosity contrast of the run, checked here (the parser already holds the scene's
    // `fluid.lambda` to the same rule; a scene made in code meets it here)
    let lambda = ViscosityContrast::new(scene.fluid.lambda).map_err(|e| unsupported("fluid.lambda", e.to_string()))?;
    let stokes = match scene.walls {
        WallsSpec::None => {
            let background: Box<dyn BackgroundFlow> = match scene.flow {
                FlowSpec::None => Box::new(Quiescent),
                FlowSpec::Shear { rate_1_s } => Box::new(SimpleShear { shear_rate_per_s: rate_1_s }),
                FlowSpec::Poiseuille { max_velocity_um_s, radius_um } => Box::new(UnboundedPoiseuille { max_velocity_um_per_s: max_velocity_um_s, radius_um }),
            };
            assembled.push(format!("background flow: {:?}", scene.flow));
            assembled.push("single layer".to_string());
            if !lambda.is_matched() {
                assembled.push(format!("double layer with GMRES (lambda = {lambda})"));
            }
            Operator::FreeSpace(FreeSpace { solver: FreeSpaceStokes::new(scene.fluid.viscosity_pa_s, lambda, BimOptions::default()), background })
        }
        WallsSpec::PeriodicChannel { .. } => Operator::Channel(Box::new(channel(scene, &mesh, lambda, &mut assembled)?)),
    };

    let i = &scene.integrator;
    let triangles = &mesh.triangles;
    let mut control = StepControl::new(i.atol_um, i.h0_s, i.h_min_s, i.h_max_s)
        .with_controller(controller(i.controller))
        .with_norm(if i.error_norm_rms { ErrorNorm::Rms } else { ErrorNorm::Max });
    let penalty = matches!(&stokes, Operator::Channel(ch) if matches!(ch.wall_mode, WallMode::Penalty { .. }));
    if penalty && i.wall_atol_um != i.atol_um {
        // the wall displacements follow the cell's vertices in the state (dynamics::penalty);
        // the step log finds the same boundary from the triangles (`slices::cell_len`)
        control = control.with_tail_atol(slices::cell_len(triangles), i.wall_atol_um);
    }
    let run = RunConfig {
        t_start_s: 0.0,
        t_end_s: scene.time.end_s,
        output_interval_s: scene.time.output_interval_s,
        control,
        checks: Checks { max_area_change: i.max_area_change, max_fold_rad: i.max_fold_deg.to_radians(), ..Checks::default() },
        volume: i.volume_correction.then(|| VolumeCorrection::new(slices::volume(&mesh.vertices, triangles))),
    };
    assembled.push(format!(
        "integrator {} (atol {:e} um{}, {} error norm, {:?} step control), volume correction {}, kinematics {:?}",
        i.scheme.name(),
        i.atol_um,
        if penalty { format!(", wall displacements {:e} um{}", i.wall_atol_um, if i.wall_coupling { ", coupled to the cell in the stages" } else { "" }) } else { String::new() },
        if i.error_norm_rms { "rms" } else { "max" },
        i.controller,
        i.volume_correction,
        i.kinematics
    ));
    Ok(Built { mesh, membrane, stokes, run, scheme: i.scheme, kinematics: i.kinematics, wall_coupling: i.wall_coupling, assembled })
}

/// The runner's controller for the scene's `integrator.controller` (`pi`: Gustafsson's PI.3.4).
pub fn controller(c: StepController) -> Controller {
    match c {
        StepController::Integral => Controller::Integral,
        StepController::Pi => Controller::PI34,
    }
}

/// What the mobility W-methods are given beside their tableau: how they keep their dense factor
/// ([`Reuse::PENALTY_WALLS`] with penalty walls, the default otherwise) and whether their stages
/// carry the penalty walls' answer to the cell ([`WallCoupling`], `integrator.wall_coupling`).
#[derive(Debug, Clone, Copy)]
struct MobilitySetup {
    reuse: Reuse,
    wall_coupling: bool,
}

impl MobilitySetup {
    /// A cell alone: the default reuse, no walls.
    fn without_walls() -> Self {
        Self { reuse: Reuse::default(), wall_coupling: false }
    }
}

/// The W-method with the dense mobility Jacobian and the given tableau.
fn mobility(method: Method, setup: MobilitySetup) -> Ros34pw2 {
    let mut m = Ros34pw2::with(StageJacobian::Mobility, false).with_method(method);
    m.reuse = setup.reuse;
    m.wall_coupling = setup.wall_coupling.then(|| WallCoupling::new(WallCoupling::DELTA_UM));
    m
}

/// Run `scheme` (`setup`: the mobility W-methods').
#[allow(clippy::too_many_arguments)]
fn run_scheme<D: Linearised>(runner: &Runner, scheme: Scheme, setup: MobilitySetup, dynamics: &mut D, triangles: &[[usize; 3]], x: &mut Vec<Vector3<f64>>, observer: &mut dyn Observer) -> Result<RunSummary, SolverError> {
    match scheme {
        Scheme::Bs23 => runner.run(dynamics, &mut BogackiShampine::new(), triangles, x, observer),
        Scheme::Ros2 => runner.run(dynamics, &mut Ros2::new(), triangles, x, observer),
        Scheme::Ros34pw2 => runner.run(dynamics, &mut Ros34pw2::new(), triangles, x, observer),
        Scheme::Ros34pw2Local => runner.run(dynamics, &mut Ros34pw2::with(StageJacobian::Local, false), triangles, x, observer),
        Scheme::Ros34pw2Mobility => runner.run(dynamics, &mut mobility(Method::Ros34pw2, setup), triangles, x, observer),
        Scheme::Ros3pwMobility => runner.run(dynamics, &mut mobility(Method::Ros3pw, setup), triangles, x, observer),
        Scheme::Ros34pw3Mobility => runner.run(dynamics, &mut mobility(Method::Ros34pw3, setup), triangles, x, observer),
        Scheme::Ros34prwMobility => runner.run(dynamics, &mut mobility(Method::Ros34prw, setup), triangles, x, observer),
        Scheme::Rosw6s4Mobility => runner.run(dynamics, &mut mobility(Method::Rosw6s4, setup), triangles, x, observer),
    }
}

/// The memory a scene may plan for (GB) and where the figure comes from: `RBC_MAX_MEMORY_GB`
/// when set, else this machine's `MemTotal` (`/proc/meminfo`), else unlimited.
fn memory_limit_gb() -> (f64, &'static str) {
    if let Some(gb) = std::env::var("RBC_MAX_MEMORY_GB").ok().and_then(|v| v.trim().parse::<f64>().ok()).filter(|g| *g > 0.0) {
        return (gb, "RBC_MAX_MEMORY_GB");
    }
    let total_kb = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines().find(|l| l.starts_with("MemTotal:")).and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse::<f64>().ok()))
    });
    match total_kb {
        Some(kb) => (kb * 1024.0 / 1e9, "this machine's memory"),
        None => (f64::INFINITY, "no limit known"),
    }
}

/// Assemble the periodic channel of `scene` for the cell `mesh` (lists what it built in `assembled`).
fn channel(scene: &Scene, mesh: &Mesh, lambda: ViscosityContrast, assembled: &mut Vec<String>) -> Result<ChannelStokes, SolverError> {
    let (WallsSpec::PeriodicChannel { mean_velocity_um_s, wall_model, wall_edge_um, ewald_tol, .. }, Some(geometry)) = (scene.walls, channel_geometry(&scene.walls)) else {
        return Err(unsupported("walls.kind", "not a periodic channel"));
    };
    let mode = match wall_model {
        WallModel::NoSlip => WallMode::NoSlip,
        WallModel::Penalty { kappa_w_n_m3 } => WallMode::Penalty { kappa_w_n_per_m3: kappa_w_n_m3 },
    };
    // the dense wall operator and its LU factors, 2 (3 N_w)^2 doubles: refused before any allocation
    let (n_s, n_x) = ChannelMesh::counts_for_edge(&geometry, wall_edge_um);
    let n_w = n_s as f64 * n_x as f64;
    let need_gb = 2.0 * (3.0 * n_w).powi(2) * 8.0 / 1e9;
    let (limit_gb, source) = memory_limit_gb();
    if need_gb > limit_gb {
        return Err(unsupported(
            "walls.wall_edge_um",
            format!("{wall_edge_um} um gives {n_w:.0} wall vertices, whose dense wall operator and LU need ~{need_gb:.1} GB, more than {limit_gb:.1} GB ({source}; RBC_MAX_MEMORY_GB overrides)"),
        ));
    }
    let opts = ChannelOptions { ewald_tol, wall_edge_um, cell_nodes_hint: 7 * mesh.triangles.len(), ..ChannelOptions::default() };
    let ch = ChannelStokes::new(geometry, scene.fluid.viscosity_pa_s, lambda, mode, opts).map_err(|e| match e {
        ChannelError::InvalidParameter { name, .. } => unsupported(&format!("walls ({name})"), e.to_string()),
        other => SolverError::Channel(other),
    })?;
    let ch = ch.with_mean_flow(mean_velocity_um_s * 1e-3);
    let p = ch.ewald_params();
    let b = ch.box_len();
    assembled.push(format!(
        "periodic channel {} x {} x {} um (corner radius {} um), mean flow {} mm/s",
        geometry.length_x,
        geometry.width_y,
        geometry.height_z,
        geometry.corner_radius,
        mean_velocity_um_s * 1e-3
    ));
    assembled.push(format!(
        "wall mesh: {} triangles, {} vertices (edge {wall_edge_um} um); dense wall operator {n} x {n} assembled in {:.2} s, LU in {:.2} s",
        ch.mesh.triangles.len(),
        ch.mesh.n_vertices(),
        ch.wall.assembly_seconds,
        ch.wall.factor_seconds,
        n = 3 * ch.mesh.n_vertices()
    ));
    assembled.push(format!(
        "ewald sums: tolerance {ewald_tol:e}, box {:.2} x {:.2} x {:.2} um, xi {:.3} 1/um, cutoff {:.2} um, grid {:?}",
        b[0], b[1], b[2], p.xi, p.r_cut, p.grid
    ));
    assembled.push(match mode {
        WallMode::NoSlip => "walls: exact no-slip (wall traction from the factorised operator)".to_string(),
        WallMode::Penalty { kappa_w_n_per_m3 } => {
            let rate = ch.penalty_rate(kappa_w_n_per_m3);
            format!(
                "walls: penalty springs kappa_W = {kappa_w_n_per_m3:e} N/m^3 (state: cell + {} wall displacements; relaxation rate {rate:.3e} 1/s, explicit steps below ~{:.2e} s)",
                ch.mesh.n_vertices(),
                2.5 / rate
            )
        }
    });
    assembled.push("single layer (periodic)".to_string());
    if !lambda.is_matched() {
        assembled.push(format!("double layer (periodic, lambda = {lambda})"));
    }
    Ok(ch)
}

/// Run one cell whose vertices are the whole state, with the scene's projections.
fn run_cell(built: &Built, stokes: &dyn Stokes, observer: &mut dyn Observer) -> Result<(RunSummary, Vec<Vector3<f64>>), SolverError> {
    let mut x = built.mesh.vertices.clone();
    let tris = built.mesh.triangles.clone();
    let cell = CellDynamics::new(tris.clone(), &built.membrane, stokes);
    let runner = Runner::new(built.run.clone());
    let (s, t) = (built.scheme, &tris);
    let summary = match (built.run.volume.is_some(), built.kinematics) {
        (true, Kinematics::Material) => run_scheme(&runner, s, MobilitySetup::without_walls(), &mut no_flux(cell, t), t, &mut x, observer),
        (true, Kinematics::Normal) => run_scheme(&runner, s, MobilitySetup::without_walls(), &mut normal_only(no_flux(cell, t), t), t, &mut x, observer),
        (false, Kinematics::Material) => run_scheme(&runner, s, MobilitySetup::without_walls(), &mut { cell }, t, &mut x, observer),
        (false, Kinematics::Normal) => run_scheme(&runner, s, MobilitySetup::without_walls(), &mut normal_only(cell, t), t, &mut x, observer),
    };
    summary.map(|s| (s, x))
}

/// Run one cell in the channel with penalty walls: the state is the cell's vertices followed by
/// the wall displacements; the observer sees the cell part only.
fn run_penalty(built: &Built, ch: &ChannelStokes, observer: &mut dyn Observer) -> Result<(RunSummary, Vec<Vector3<f64>>), SolverError> {
    let tris = built.mesh.triangles.clone();
    let nc = built.mesh.vertices.len();
    let mut cell = PenaltyChannelDynamics::new(tris.clone(), nc, &built.membrane, ch)?;
    let mut x = cell.initial_state(&built.mesh.vertices)?;
    let runner = Runner::new(built.run.clone());
    let mut obs = CellOutput { inner: observer, n_cell: nc };
    let (s, t) = (built.scheme, &tris);
    let setup = MobilitySetup { reuse: Reuse::PENALTY_WALLS, wall_coupling: built.wall_coupling };
    let summary = match (built.run.volume.is_some(), built.kinematics) {
        (true, Kinematics::Material) => run_scheme(&runner, s, setup, &mut cell_no_flux(cell, t), t, &mut x, &mut obs),
        (true, Kinematics::Normal) => run_scheme(&runner, s, setup, &mut cell_normal_only(cell_no_flux(cell, t), t), t, &mut x, &mut obs),
        (false, Kinematics::Material) => run_scheme(&runner, s, setup, &mut { cell }, t, &mut x, &mut obs),
        (false, Kinematics::Normal) => run_scheme(&runner, s, setup, &mut cell_normal_only(cell, t), t, &mut x, &mut obs),
    };
    x.truncate(nc);
    summary.map(|s| (s, x))
}

impl Built {
    /// Run the scene from its initial mesh; returns the summary and the final vertices (um).
    pub fn run(&self, observer: &mut dyn Observer) -> Result<(RunSummary, Vec<Vector3<f64>>), SolverError> {
        match &self.stokes {
            Operator::FreeSpace(fs) => run_cell(self, fs, observer),
            Operator::Channel(ch) => match ch.wall_mode {
                WallMode::NoSlip => run_cell(self, &**ch, observer),
                WallMode::Penalty { .. } => run_penalty(self, ch, observer),
            },
        }
    }

    /// The periodic channel, if the scene has one.
    pub fn channel(&self) -> Option<&ChannelStokes> {
        match &self.stokes {
            Operator::Channel(ch) => Some(ch),
            Operator::FreeSpace(_) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A drop of 32 triangles in shear (cheap to build), with `integrator` lines appended.
    fn scene(integrator: &str) -> Scene {
        let text = format!(
            "[cell]\nshape = \"sphere\"\nlevel = 1\nradius_um = 4.0\n[membrane.tension]\ngamma_n_m = 1e-3\n\
             [fluid]\nviscosity_pa_s = 1.2e-3\nlambda = 1.0\n[flow]\nkind = \"shear\"\nshear_rate_1_s = 10.0\n\
             [integrator]\nkinematics = \"normal\"\n{integrator}[time]\nend_s = 1e-3\noutput_interval_s = 1e-3\n"
        );
        Scene::parse(&text, std::path::Path::new("drop.toml")).unwrap()
    }

    #[test]
    fn the_scene_controller_reaches_the_runner() {
        let cases = [
            ("", Controller::PI34),
            ("scheme = \"ros34pw2-local\"\n", Controller::Integral),
            ("scheme = \"ros34pw2-local\"\ncontroller = \"pi\"\n", Controller::PI34),
            ("controller = \"integral\"\n", Controller::Integral),
        ];
        for (lines, want) in cases {
            let built = build(&scene(lines)).unwrap();
            assert_eq!(built.run.control.controller, want, "{lines:?}");
            assert!(built.assembled.iter().any(|l| l.contains("step control")), "{:?}", built.assembled);
        }
    }

    #[test]
    fn the_scene_error_norm_reaches_the_runner() {
        for (lines, want) in [("", ErrorNorm::Max), ("error_norm = \"max\"\n", ErrorNorm::Max), ("error_norm = \"rms\"\n", ErrorNorm::Rms)] {
            let built = build(&scene(lines)).unwrap();
            assert_eq!(built.run.control.norm, want, "{lines:?}");
        }
    }
}
