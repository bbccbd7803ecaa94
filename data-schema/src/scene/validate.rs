//! Checking a scene file field by field ([`Scene::validate`]): every error names the file and the field, with the value and why it is refused.

use super::raw::*;
use super::*;

pub(super) fn toml_error_with_line(path: &Path, text: &str, e: &toml::de::Error) -> SchemaError {
    let mut message = e.message().replace('\n', " ").trim().to_string();
    if let Some(span) = e.span() {
        let line = crate::recording::line_at(text, span.start);
        message = format!("{message} (line {line})");
    }
    SchemaError::Toml { path: path.to_path_buf(), message }
}

fn require<T>(path: &Path, field: &str, v: Option<T>, why: &str) -> Result<T> {
    v.ok_or_else(|| SchemaError::field(path, field, format!("missing ({why})")))
}

fn refuse<T>(path: &Path, field: &str, v: &Option<T>, why: &str) -> Result<()> {
    if v.is_some() {
        Err(SchemaError::field(path, field, format!("not allowed {why}")))
    } else {
        Ok(())
    }
}

/// Require a finite value in `[lo, hi]`, the range where it still means something physically
/// (`unit` for the message): far outside it a run either overflows or underflows somewhere
/// late (a degenerate mesh, a non-finite velocity at the first step, after a run was appended)
/// or computes nothing a lab could have meant.
fn plausible(path: &Path, field: &str, v: f64, lo: f64, hi: f64, unit: &str) -> Result<()> {
    let unit = if unit.is_empty() { "(the plausible range)".to_string() } else { format!("{unit} (the plausible range)") };
    crate::recording::within(path, field, v, lo, hi, &unit)
}

fn finite3(path: &Path, field: &str, v: [f64; 3]) -> Result<[f64; 3]> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(v)
    } else {
        Err(SchemaError::field(path, field, format!("must be three finite numbers, got {v:?}")))
    }
}

impl Scene {
    pub(super) fn validate(raw: RawScene, text: &str, p: &Path) -> Result<Self> {
        // cell
        let c = raw.cell;
        let level_raw = require(p, "cell.level", c.level, "mesh refinement level")?;
        if !(0..=MAX_LEVEL as i64).contains(&level_raw) {
            return Err(SchemaError::field(p, "cell.level", format!("must be an integer in 0..={MAX_LEVEL}, got {level_raw}")));
        }
        let position_um = finite3(p, "cell.position_um", c.position_um.unwrap_or([0.0; 3]))?;
        for x in position_um {
            plausible(p, "cell.position_um", x, -1e6, 1e6, "um per coordinate")?;
        }
        let shape = match c.shape.as_str() {
            "sphere" => {
                let r = require(p, "cell.radius_um", c.radius_um, "required for shape = \"sphere\"")?;
                positive(p, "cell.radius_um", r)?;
                plausible(p, "cell.radius_um", r, 0.01, 1e3, "um")?;
                refuse(p, "cell.axis", &c.axis, "for shape = \"sphere\"")?;
                refuse(p, "cell.results", &c.results, "for shape = \"sphere\"")?;
                CellShape::Sphere { radius_um: r }
            }
            "discocyte" => {
                refuse(p, "cell.radius_um", &c.radius_um, "for shape = \"discocyte\" (its size is fixed by R_RBC = 4 um)")?;
                refuse(p, "cell.results", &c.results, "for shape = \"discocyte\"")?;
                let a = finite3(p, "cell.axis", c.axis.unwrap_or([1.0, 0.0, 0.0]))?;
                let n = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
                if n == 0.0 {
                    return Err(SchemaError::field(p, "cell.axis", "must be a non-zero vector"));
                }
                CellShape::Discocyte { axis: [a[0] / n, a[1] / n, a[2] / n] }
            }
            "mesh-from-results" => {
                refuse(p, "cell.radius_um", &c.radius_um, "for shape = \"mesh-from-results\"")?;
                let results = require(p, "cell.results", c.results, "path of the results file")?;
                let run = require(p, "cell.run", c.run, "run id inside the results file")?;
                // relative paths are relative to the scene file
                let results = if results.is_relative() {
                    p.parent().map(|d| d.join(&results)).unwrap_or(results)
                } else {
                    results
                };
                CellShape::MeshFromResults { results, run, snapshot: c.snapshot.unwrap_or(-1) }
            }
            other => {
                return Err(SchemaError::field(p, "cell.shape", format!("unknown shape \"{other}\" (expected sphere, discocyte or mesh-from-results)")))
            }
        };
        let cell = CellSpec { shape, level: level_raw as u32, position_um };

        // membrane
        let m = raw.membrane;
        let reference = match m.reference.as_deref().unwrap_or("initial") {
            "initial" => Reference::Initial,
            "discocyte" => Reference::Discocyte,
            "sphere" => Reference::Sphere,
            other => return Err(SchemaError::field(p, "membrane.reference", format!("unknown reference \"{other}\" (expected initial, discocyte or sphere)"))),
        };
        let skalak = match m.skalak {
            None => None,
            Some(s) => Some(match s.convention.as_str() {
                "barthes-biesel" => {
                    refuse(p, "membrane.skalak.kappa_s_n_m", &s.kappa_s_n_m, "with convention = \"barthes-biesel\" (use shear_modulus_n_m and c)")?;
                    refuse(p, "membrane.skalak.kappa_a_n_m", &s.kappa_a_n_m, "with convention = \"barthes-biesel\" (use shear_modulus_n_m and c)")?;
                    let gs = require(p, "membrane.skalak.shear_modulus_n_m", s.shear_modulus_n_m, "Gs of the Barthes-Biesel form")?;
                    let c = require(p, "membrane.skalak.c", s.c, "C of the Barthes-Biesel form; area modulus = Gs (1 + 2C)")?;
                    positive(p, "membrane.skalak.shear_modulus_n_m", gs)?;
                    plausible(p, "membrane.skalak.shear_modulus_n_m", gs, 1e-12, 1e3, "N/m")?;
                    if !(c.is_finite() && c >= 0.0) {
                        return Err(SchemaError::field(p, "membrane.skalak.c", format!("must be a finite number >= 0 (area modulus Gs (1 + 2C) >= Gs), got {c}")));
                    }
                    plausible(p, "membrane.skalak.c", c, 0.0, 1e6, "")?;
                    SkalakSpec::BarthesBiesel { shear_modulus_n_m: gs, c }
                }
                "krueger" => {
                    refuse(p, "membrane.skalak.shear_modulus_n_m", &s.shear_modulus_n_m, "with convention = \"krueger\" (use kappa_s_n_m and kappa_a_n_m)")?;
                    refuse(p, "membrane.skalak.c", &s.c, "with convention = \"krueger\" (use kappa_s_n_m and kappa_a_n_m)")?;
                    let ks = require(p, "membrane.skalak.kappa_s_n_m", s.kappa_s_n_m, "kS of the Krueger form")?;
                    let ka = require(p, "membrane.skalak.kappa_a_n_m", s.kappa_a_n_m, "kA of the Krueger form")?;
                    positive(p, "membrane.skalak.kappa_s_n_m", ks)?;
                    plausible(p, "membrane.skalak.kappa_s_n_m", ks, 1e-12, 1e3, "N/m")?;
                    // kA = 0 is valid: the Barthes-Biesel form with C = 0, area modulus kS/3 > 0
                    non_negative(p, "membrane.skalak.kappa_a_n_m", ka)?;
                    plausible(p, "membrane.skalak.kappa_a_n_m", ka, 0.0, 1e3, "N/m")?;
                    SkalakSpec::Krueger { kappa_s_n_m: ks, kappa_a_n_m: ka }
                }
                other => {
                    return Err(SchemaError::field(p, "membrane.skalak.convention", format!("unknown convention \"{other}\" (expected barthes-biesel or krueger)")))
                }
            }),
        };
        if let Some(b) = &m.bending {
            positive(p, "membrane.bending.kappa_b_n_m", b.kappa_b_n_m)?;
            plausible(p, "membrane.bending.kappa_b_n_m", b.kappa_b_n_m, 1e-25, 1e-12, "N m (J)")?;
        }
        if let Some(t) = &m.tension {
            positive(p, "membrane.tension.gamma_n_m", t.gamma_n_m)?;
            plausible(p, "membrane.tension.gamma_n_m", t.gamma_n_m, 1e-12, 10.0, "N/m")?;
        }
        if skalak.is_none() && m.bending.is_none() && m.tension.is_none() {
            return Err(SchemaError::field(p, "membrane", "needs at least one of [membrane.skalak], [membrane.bending], [membrane.tension]"));
        }
        let membrane = MembraneSpec {
            reference,
            skalak,
            bending_n_m: m.bending.as_ref().map(|b| b.kappa_b_n_m),
            bending_method: m.bending.and_then(|b| b.method),
            tension_n_m: m.tension.map(|t| t.gamma_n_m),
        };

        // fluid
        positive(p, "fluid.viscosity_pa_s", raw.fluid.viscosity_pa_s)?;
        // the viscosity contrast's rule (finite, > 0) is the solver's `ViscosityContrast::new`;
        // here it is met where the file is read, with the field named
        positive(p, "fluid.lambda", raw.fluid.lambda)?;
        plausible(p, "fluid.viscosity_pa_s", raw.fluid.viscosity_pa_s, 1e-6, 1e6, "Pa s")?;
        plausible(p, "fluid.lambda", raw.fluid.lambda, 1e-4, 1e4, "")?;
        let fluid = FluidSpec { viscosity_pa_s: raw.fluid.viscosity_pa_s, lambda: raw.fluid.lambda };

        // flow
        let flow = match raw.flow {
            None => FlowSpec::None,
            Some(f) => match f.kind.as_str() {
                "none" => {
                    refuse(p, "flow.shear_rate_1_s", &f.shear_rate_1_s, "with kind = \"none\"")?;
                    refuse(p, "flow.max_velocity_um_s", &f.max_velocity_um_s, "with kind = \"none\"")?;
                    FlowSpec::None
                }
                "shear" => {
                    refuse(p, "flow.max_velocity_um_s", &f.max_velocity_um_s, "with kind = \"shear\"")?;
                    refuse(p, "flow.radius_um", &f.radius_um, "with kind = \"shear\"")?;
                    let r = require(p, "flow.shear_rate_1_s", f.shear_rate_1_s, "required for kind = \"shear\"")?;
                    if !r.is_finite() {
                        return Err(SchemaError::field(p, "flow.shear_rate_1_s", format!("must be finite, got {r}")));
                    }
                    plausible(p, "flow.shear_rate_1_s", r, -1e7, 1e7, "1/s")?;
                    FlowSpec::Shear { rate_1_s: r }
                }
                "poiseuille" => {
                    refuse(p, "flow.shear_rate_1_s", &f.shear_rate_1_s, "with kind = \"poiseuille\"")?;
                    let u = require(p, "flow.max_velocity_um_s", f.max_velocity_um_s, "required for kind = \"poiseuille\"")?;
                    let r = require(p, "flow.radius_um", f.radius_um, "required for kind = \"poiseuille\"")?;
                    if !u.is_finite() {
                        return Err(SchemaError::field(p, "flow.max_velocity_um_s", format!("must be finite, got {u}")));
                    }
                    plausible(p, "flow.max_velocity_um_s", u, -1e9, 1e9, "um/s")?;
                    positive(p, "flow.radius_um", r)?;
                    plausible(p, "flow.radius_um", r, 0.01, 1e6, "um")?;
                    FlowSpec::Poiseuille { max_velocity_um_s: u, radius_um: r }
                }
                other => return Err(SchemaError::field(p, "flow.kind", format!("unknown kind \"{other}\" (expected none, shear or poiseuille)"))),
            },
        };

        // walls
        let walls = match raw.walls {
            None => WallsSpec::None,
            Some(w) => match w.kind.as_str() {
                "none" => {
                    for (field, v) in [
                        ("walls.length_x_um", w.length_x_um),
                        ("walls.width_y_um", w.width_y_um),
                        ("walls.height_z_um", w.height_z_um),
                        ("walls.mean_velocity_um_s", w.mean_velocity_um_s),
                        ("walls.corner_radius_um", w.corner_radius_um),
                        ("walls.kappa_w_n_m3", w.kappa_w_n_m3),
                        ("walls.wall_edge_um", w.wall_edge_um),
                        ("walls.ewald_tol", w.ewald_tol),
                    ] {
                        refuse(p, field, &v, "with kind = \"none\"")?;
                    }
                    refuse(p, "walls.wall_model", &w.wall_model, "with kind = \"none\"")?;
                    WallsSpec::None
                }
                "periodic-channel" => {
                    let lx = require(p, "walls.length_x_um", w.length_x_um, "periodic length (paper: 42.7)")?;
                    let ly = require(p, "walls.width_y_um", w.width_y_um, "channel width (paper: 12)")?;
                    let lz = require(p, "walls.height_z_um", w.height_z_um, "channel height (paper: 10)")?;
                    let u = require(p, "walls.mean_velocity_um_s", w.mean_velocity_um_s, "prescribed mean flow through the unit cell")?;
                    positive(p, "walls.length_x_um", lx)?;
                    positive(p, "walls.width_y_um", ly)?;
                    positive(p, "walls.height_z_um", lz)?;
                    if !u.is_finite() {
                        return Err(SchemaError::field(p, "walls.mean_velocity_um_s", format!("must be finite, got {u}")));
                    }
                    plausible(p, "walls.mean_velocity_um_s", u, -1e9, 1e9, "um/s")?;
                    if !matches!(flow, FlowSpec::None) {
                        return Err(SchemaError::field(p, "flow.kind", "must be \"none\" in a periodic channel (the flow is driven by walls.mean_velocity_um_s)"));
                    }
                    if let Some(h) = cell_half_extents_um(&cell.shape) {
                        for (k, (field, side)) in [("walls.length_x_um", lx), ("walls.width_y_um", ly), ("walls.height_z_um", lz)].into_iter().enumerate() {
                            if 2.0 * h[k] >= side {
                                return Err(SchemaError::field(
                                    p,
                                    field,
                                    format!("{side} um does not hold the cell, which spans {:.2} um along this axis (cell.shape, cell.radius_um, cell.axis)", 2.0 * h[k]),
                                ));
                            }
                        }
                    }
                    let rc = w.corner_radius_um.unwrap_or(DEFAULT_CORNER_RADIUS_UM);
                    if !(rc.is_finite() && rc >= 0.0 && rc < 0.5 * ly.min(lz)) {
                        return Err(SchemaError::field(p, "walls.corner_radius_um", format!("must be >= 0 and below half the smaller side ({}), got {rc}", 0.5 * ly.min(lz))));
                    }
                    let wall_model = match w.wall_model.as_deref().unwrap_or("no-slip") {
                        "no-slip" => {
                            refuse(p, "walls.kappa_w_n_m3", &w.kappa_w_n_m3, "with wall_model = \"no-slip\" (only the penalty walls have springs)")?;
                            WallModel::NoSlip
                        }
                        "penalty" => {
                            let k = require(p, "walls.kappa_w_n_m3", w.kappa_w_n_m3, "spring stiffness of the penalty walls (paper: 1.9e7)")?;
                            positive(p, "walls.kappa_w_n_m3", k)?;
                            WallModel::Penalty { kappa_w_n_m3: k }
                        }
                        other => return Err(SchemaError::field(p, "walls.wall_model", format!("unknown wall model \"{other}\" (expected no-slip or penalty)"))),
                    };
                    let edge = w.wall_edge_um.unwrap_or(DEFAULT_WALL_EDGE_UM);
                    positive(p, "walls.wall_edge_um", edge)?;
                    if edge > 0.25 * ly.min(lz) {
                        return Err(SchemaError::field(p, "walls.wall_edge_um", format!("must not exceed a quarter of the smaller side ({}), got {edge}", 0.25 * ly.min(lz))));
                    }
                    let tol = w.ewald_tol.unwrap_or(DEFAULT_EWALD_TOL);
                    if !(tol.is_finite() && tol > 0.0 && tol <= 1e-2) {
                        return Err(SchemaError::field(p, "walls.ewald_tol", format!("must be in (0, 1e-2] (relative error of the Ewald sums; paper: 5e-5), got {tol}")));
                    }
                    WallsSpec::PeriodicChannel {
                        length_x_um: lx,
                        width_y_um: ly,
                        height_z_um: lz,
                        mean_velocity_um_s: u,
                        corner_radius_um: rc,
                        wall_model,
                        wall_edge_um: edge,
                        ewald_tol: tol,
                    }
                }
                other => return Err(SchemaError::field(p, "walls.kind", format!("unknown kind \"{other}\" (expected none or periodic-channel)"))),
            },
        };

        // time
        positive(p, "time.end_s", raw.time.end_s)?;
        positive(p, "time.output_interval_s", raw.time.output_interval_s)?;
        plausible(p, "time.end_s", raw.time.end_s, 1e-9, 1e6, "s")?;
        plausible(p, "time.output_interval_s", raw.time.output_interval_s, 1e-9, 1e6, "s")?;
        if raw.time.output_interval_s > raw.time.end_s {
            return Err(SchemaError::field(p, "time.output_interval_s", format!("must not exceed time.end_s = {}", raw.time.end_s)));
        }
        let time = TimeSpec { end_s: raw.time.end_s, output_interval_s: raw.time.output_interval_s };

        // integrator
        let i = raw.integrator.unwrap_or(RawIntegrator {
            scheme: None,
            atol_um: None,
            h0_s: None,
            h_min_s: None,
            h_max_s: None,
            volume_correction: None,
            max_area_change: None,
            max_fold_deg: None,
            kinematics: None,
            controller: None,
            error_norm: None,
            wall_atol_um: None,
            wall_coupling: None,
        });
        let scheme = match i.scheme.as_deref().unwrap_or("bs23") {
            "bs23" => Scheme::Bs23,
            "ros2" => Scheme::Ros2,
            "ros34pw2" => Scheme::Ros34pw2,
            "ros34pw2-local" => Scheme::Ros34pw2Local,
            "ros34pw2-mobility" => Scheme::Ros34pw2Mobility,
            "ros3pw-mobility" => Scheme::Ros3pwMobility,
            "ros34pw3-mobility" => Scheme::Ros34pw3Mobility,
            "ros34prw-mobility" => Scheme::Ros34prwMobility,
            "rosw6s4-mobility" => Scheme::Rosw6s4Mobility,
            other => return Err(SchemaError::field(p, "integrator.scheme", format!("unknown scheme \"{other}\" (expected bs23, ros2, ros34pw2, ros34pw2-local, ros34pw2-mobility, ros3pw-mobility, ros34pw3-mobility, ros34prw-mobility or rosw6s4-mobility)"))),
        };
        let kinematics = match i.kinematics.as_deref().unwrap_or("material") {
            "material" => Kinematics::Material,
            "normal" => {
                if membrane.skalak.is_some() {
                    return Err(SchemaError::field(p, "integrator.kinematics", "\"normal\" is only for interfaces without in-plane elasticity (remove [membrane.skalak] or use \"material\")"));
                }
                Kinematics::Normal
            }
            other => return Err(SchemaError::field(p, "integrator.kinematics", format!("unknown kinematics \"{other}\" (expected material or normal)"))),
        };
        let controller = match i.controller.as_deref() {
            None => StepController::default_for(scheme, walls.has_penalty_walls()),
            Some("pi") => StepController::Pi,
            Some("integral") => StepController::Integral,
            Some(other) => return Err(SchemaError::field(p, "integrator.controller", format!("unknown controller \"{other}\" (expected pi or integral)"))),
        };
        let error_norm_rms = match i.error_norm.as_deref() {
            None | Some("max") => false,
            Some("rms") => true,
            Some(other) => return Err(SchemaError::field(p, "integrator.error_norm", format!("unknown error norm \"{other}\" (expected max or rms)"))),
        };
        let integrator = IntegratorSpec {
            kinematics,
            controller,
            error_norm_rms,
            scheme,
            atol_um: i.atol_um.unwrap_or(4e-5),
            h0_s: i.h0_s.unwrap_or(1e-6),
            h_min_s: i.h_min_s.unwrap_or(1e-12),
            h_max_s: i.h_max_s.unwrap_or(time.output_interval_s),
            volume_correction: i.volume_correction.unwrap_or(true),
            max_area_change: i.max_area_change.unwrap_or(0.05),
            max_fold_deg: i.max_fold_deg.unwrap_or(120.0),
            wall_atol_um: i.wall_atol_um.unwrap_or(i.atol_um.unwrap_or(4e-5)),
            wall_coupling: i.wall_coupling.unwrap_or(false),
        };
        positive(p, "integrator.atol_um", integrator.atol_um)?;
        plausible(p, "integrator.atol_um", integrator.atol_um, 1e-15, 1.0, "um")?;
        positive(p, "integrator.h0_s", integrator.h0_s)?;
        positive(p, "integrator.h_min_s", integrator.h_min_s)?;
        positive(p, "integrator.h_max_s", integrator.h_max_s)?;
        positive(p, "integrator.max_area_change", integrator.max_area_change)?;
        if !(integrator.max_fold_deg > 0.0 && integrator.max_fold_deg <= 180.0) {
            return Err(SchemaError::field(p, "integrator.max_fold_deg", format!("must lie in (0, 180] degrees, got {}", integrator.max_fold_deg)));
        }
        if integrator.h_min_s > integrator.h_max_s {
            return Err(SchemaError::field(p, "integrator.h_min_s", format!("must not exceed integrator.h_max_s = {}", integrator.h_max_s)));
        }
        if i.wall_atol_um.is_some() {
            if !walls.has_penalty_walls() {
                return Err(SchemaError::field(p, "integrator.wall_atol_um", "is for penalty walls only (walls.wall_model = \"penalty\"): exact walls carry no state"));
            }
            positive(p, "integrator.wall_atol_um", integrator.wall_atol_um)?;
            plausible(p, "integrator.wall_atol_um", integrator.wall_atol_um, 1e-15, 1.0, "um")?;
        }
        if integrator.wall_coupling {
            if !walls.has_penalty_walls() {
                return Err(SchemaError::field(p, "integrator.wall_coupling", "is for penalty walls only (walls.wall_model = \"penalty\"): exact walls carry no state"));
            }
            if !scheme.is_mobility() {
                return Err(SchemaError::field(p, "integrator.wall_coupling", format!("needs a W-method with the dense Jacobian (a -mobility scheme), not {}", scheme.name())));
            }
        }

        let name = raw.name.unwrap_or_else(|| p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default());
        // the name is the run id in a results file (an HDF5 group)
        if !crate::results::is_valid_run_id(&name) {
            return Err(SchemaError::field(p, "name", format!("`{name}` cannot name a run: it must not be empty, hold `/`, or be `.` or `..`")));
        }
        Ok(Scene { path: p.to_path_buf(), source: text.to_string(), name, cell, membrane, fluid, flow, walls, integrator, time })
    }
}
