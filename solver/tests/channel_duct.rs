//! The empty periodic channel: the prescribed mean flow reproduces the rectangular-duct Poiseuille flow (Boussinesq series) with exact no-slip walls; penalty walls relax to it.

use nalgebra::Vector3;
use rbc_solver::channel::duct::RectangularDuct;
use rbc_solver::channel::{ChannelGeometry, ChannelOptions, ChannelStokes, WallMode};

const MU: f64 = 1.2e-3;

/// Interior sample points of the cross-section at least `margin` um from the walls of the
/// sharp rectangle (the rounded corners, r_c = 1.5 um, then lie >= margin + 0.6 um away).
fn samples(g: &ChannelGeometry, margin: f64, x: f64) -> Vec<Vector3<f64>> {
    let mut out = Vec::new();
    let (hy, hz) = (0.5 * g.width_y - margin, 0.5 * g.height_z - margin);
    for i in 0..=6 {
        for j in 0..=6 {
            out.push(Vector3::new(x, -hy + 2.0 * hy * i as f64 / 6.0, -hz + 2.0 * hz * j as f64 / 6.0));
        }
    }
    out
}

/// Max relative error (to the centre velocity) of the axial velocity against Boussinesq's
/// series at the solve's own pressure gradient, and the largest transverse velocity.
fn profile_error(ch: &ChannelStokes, margin: f64, mean_mm_s: f64) -> (f64, f64, f64) {
    let g = ch.geometry;
    let duct = RectangularDuct::new(g.width_y, g.height_z, MU);
    let mut pts = samples(&g, margin, 0.37 * g.length_x);
    pts.extend(samples(&g, margin, 0.81 * g.length_x));
    let (u, grad) = ch.empty_channel_flow(&pts, mean_mm_s).unwrap();
    let umax = duct.max_velocity(grad);
    let mut err: f64 = 0.0;
    let mut transverse: f64 = 0.0;
    for (p, v) in pts.iter().zip(&u) {
        err = err.max((v.x - duct.velocity(grad, p.y, p.z)).abs() / umax);
        transverse = transverse.max(v.y.abs().max(v.z.abs()) / umax);
    }
    (err, transverse, grad)
}

/// Exact no-slip walls, 2160 wall triangles (the paper's 2166), Ewald tolerance 1e-6: the
/// axial velocity matches the Boussinesq profile within 1 % of the centre velocity at interior
/// points >= 2 um from the walls, the flow is axial, and the centre velocity / mean flow ratio is
/// that of the duct (the driving: flux = mean flow x cross-section).
#[test]
fn no_slip_channel_reproduces_duct_poiseuille() {
    let g = ChannelGeometry::default();
    let opts = ChannelOptions { ewald_tol: 1e-6, ..ChannelOptions::default() };
    let ch = ChannelStokes::new(g, MU, 1.0, WallMode::NoSlip, opts).unwrap();
    eprintln!(
        "wall: {} triangles, {} unknowns, assembly {:.2} s ({} Ewald sums), LU {:.2} s; Ewald {:?}",
        ch.mesh.triangles.len(),
        3 * ch.mesh.n_vertices(),
        ch.wall.assembly_seconds,
        ch.wall.ewald_sums,
        ch.wall.factor_seconds,
        ch.ewald_params()
    );
    eprintln!("calibration (interior flux fraction, b per U0, K_E): {:?}", ch.calibration());
    let mean = 2.0; // mm/s
    let (err, transverse, grad) = profile_error(&ch, 2.0, mean);
    let duct = RectangularDuct::new(g.width_y, g.height_z, MU);
    let centre = ch.empty_channel_flow(&[Vector3::new(5.0, 0.0, 0.0)], mean).unwrap().0[0].x;
    // Expected centre/mean: Boussinesq centre velocity over the rounded-duct mean velocity at the same gradient.
    let ratio_expected = duct.max_velocity(1.0) / (rbc_solver::channel::duct::rounded_flux(&g, MU, 1.0, 0.05) / g.cross_section_area());
    eprintln!(
        "no-slip: max profile error {err:.3e}, transverse {transverse:.2e}, -dp/dx {grad:.4e} Pa/um, centre/mean {:.5} (rounded duct {:.5})",
        centre / (mean * 1e3),
        ratio_expected
    );
    assert!(err < 0.01, "{err}");
    assert!(transverse < 0.01, "{transverse}");
    assert!(((centre / (mean * 1e3)) / ratio_expected - 1.0).abs() < 0.01);
}
