//! A cell with viscosity contrast in a triply periodic box without walls (the periodic double layer and its deflation on their own; the exact-answer test case of Hasimoto's drop array).
//!
//! Solves, at the cell vertices (see [`super::double_layer`] for the equation and `A`),
//!
//! ```text
//! u - kappa A[u] = 2/(1 + lambda) (U0 + SL_per[f]/mu),      kappa = (1 - lambda)/(1 + lambda)
//! ```
//!
//! with `U0` the mean velocity of the whole box (fluid inside and outside the cell) and the net
//! force of the cell balanced by a uniform pressure gradient (Hasimoto 1959). For `lambda = 1`
//! the double layer is not built.

use nalgebra::Vector3;

use super::cell_layer::{cell_single_layer, StokesletSum};
use super::double_layer::{solve_second_kind, ContrastStats, PeriodicDoubleLayer};
use super::stokes::ChannelOptions;
use super::ChannelError;
use crate::bim::near_field::NearField;
use crate::bim::surface::Surface;
use crate::ewald::PeriodicStokes;
use crate::gmres::{GmresOptions, Tolerance};
use crate::mesh::Mesh;
use crate::viscosity::ViscosityContrast;

/// Membrane velocity (um/s) of `mesh` with membrane force density `f` (Pa) in the periodic box of
/// `ewald`, outer viscosity `mu_pa_s`, viscosity contrast `lambda`, box-mean velocity `mean_velocity` (um/s).
/// Uses the GMRES, deflation and quadrature fields of `opts`.
pub fn periodic_box_velocity(
    ewald: &PeriodicStokes,
    mesh: &Mesh,
    f: &[Vector3<f64>],
    mu_pa_s: f64,
    lambda: ViscosityContrast,
    mean_velocity: Vector3<f64>,
    opts: &ChannelOptions,
) -> Result<(Vec<Vector3<f64>>, ContrastStats), ChannelError> {
    if !(mu_pa_s > 0.0 && mu_pa_s.is_finite()) {
        return Err(ChannelError::InvalidParameter {
            name: "mu_pa_s",
            value: mu_pa_s,
            reason: "must be positive and finite",
        });
    }
    if f.len() != mesh.vertices.len() {
        return Err(ChannelError::LengthMismatch {
            what: "traction",
            expected: mesh.vertices.len(),
            got: f.len(),
        });
    }
    let surface = Surface::new(mesh)?;
    let near = NearField::new(&surface, &opts.near_field);
    let sl = cell_single_layer(
        StokesletSum::Full(ewald),
        &surface,
        f,
        &[],
        opts.duffy_nodes,
        opts.subtract_normal_singularity,
        Some(&near),
    )?;
    let rhs: Vec<Vector3<f64>> = sl
        .at_cell
        .iter()
        .map(|s| mean_velocity + s / mu_pa_s)
        .collect();
    if lambda.is_matched() {
        return Ok((rhs, ContrastStats::default()));
    }
    let kappa = lambda.kappa();
    let scale = lambda.rhs_scale();
    let b: Vec<Vector3<f64>> = rhs.iter().map(|v| v * scale).collect();
    let dl = PeriodicDoubleLayer::new(&surface, mesh.volume(), ewald, &[])?.with_near_field(&near);
    let gopts = GmresOptions {
        tolerance: Tolerance::Relative(opts.gmres_tolerance),
        restart: opts.gmres_restart,
        max_iterations: opts.gmres_max_iterations,
    };
    let (u, stats) = solve_second_kind(
        &surface,
        lambda,
        &b,
        None,
        opts.deflate_rigid_body,
        None,
        &gopts,
        |u| {
            let (a, _) = dl.apply(u)?;
            Ok(u.iter().zip(&a).map(|(u, a)| u - a * kappa).collect())
        },
    )?;
    if let Some(index) = u.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
        return Err(ChannelError::NonFinite {
            what: "cell velocity",
            index,
        });
    }
    Ok((u, stats))
}
