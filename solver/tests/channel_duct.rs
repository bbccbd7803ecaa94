//! The empty periodic channel: the prescribed mean flow reproduces the rectangular-duct Poiseuille flow (Boussinesq series) with exact no-slip walls; penalty walls relax to it.

use nalgebra::Vector3;
use rbc_solver::channel::duct::{duct_profile_error, RectangularDuct};
use rbc_solver::viscosity::ViscosityContrast;
use rbc_solver::channel::{ChannelGeometry, ChannelOptions, ChannelStokes, WallMode};

const MU: f64 = 1.2e-3;

/// Exact no-slip walls, 2160 wall triangles (the paper's 2166), Ewald tolerance 1e-6: the
/// axial velocity matches the Boussinesq profile within 1 % of the centre velocity at interior
/// points >= 2 um from the walls, the flow is axial, and the centre velocity / mean flow ratio is
/// that of the duct (the driving: flux = mean flow x cross-section).
#[test]
fn no_slip_channel_reproduces_duct_poiseuille() {
    let g = ChannelGeometry::default();
    let opts = ChannelOptions {
        ewald_tol: 1e-6,
        ..ChannelOptions::default()
    };
    let ch = ChannelStokes::new(g, MU, ViscosityContrast::MATCHED, WallMode::NoSlip, opts).unwrap();
    eprintln!(
        "wall: {} triangles, {} unknowns, assembly {:.2} s ({} Ewald sums), LU {:.2} s; Ewald {:?}",
        ch.mesh.triangles.len(),
        3 * ch.mesh.n_vertices(),
        ch.wall.assembly_seconds,
        ch.wall.ewald_sums,
        ch.wall.factor_seconds,
        ch.ewald_params()
    );
    eprintln!(
        "calibration (interior flux fraction, b per U0, K_E): {:?}",
        ch.calibration()
    );
    let mean = 2.0; // mm/s
    let (err, transverse, grad) = duct_profile_error(&ch, 2.0, mean).unwrap();
    let duct = RectangularDuct::new(g.width_y, g.height_z, MU);
    let centre = ch
        .empty_channel_flow(&[Vector3::new(5.0, 0.0, 0.0)], mean)
        .unwrap()
        .0[0]
        .x;
    // Expected centre/mean: Boussinesq centre velocity over the rounded-duct mean velocity at the same gradient.
    let ratio_expected = duct.max_velocity(1.0)
        / (rbc_solver::channel::duct::rounded_flux(&g, MU, 1.0, 0.05) / g.cross_section_area());
    eprintln!(
        "no-slip: max profile error {err:.3e}, transverse {transverse:.2e}, -dp/dx {grad:.4e} Pa/um, centre/mean {:.5} (rounded duct {:.5})",
        centre / (mean * 1e3),
        ratio_expected
    );
    assert!(err < 0.01, "{err}");
    assert!(transverse < 0.01, "{transverse}");
    assert!(((centre / (mean * 1e3)) / ratio_expected - 1.0).abs() < 0.01);
}

/// Penalty walls (the paper's kappa_W = 1.9e7 N/m^3), no cell: from rest, explicit Euler steps of
/// the wall displacement `dd/dt = u(wall)` relax the wall velocity to zero; the wall traction then
/// equals the no-slip one (up to the relaxation left), the walls have moved by `|f_w| / kappa_W`,
/// and the step must stay below `2 / rate` with `rate = kappa_W lambda_max(S) / mu`: at 2.2 / rate
/// the iteration diverges. Prints the step limit and the relaxation time.
#[test]
fn penalty_walls_relax_to_no_slip() {
    let g = ChannelGeometry::default();
    let kappa = 1.9e7;
    let opts = ChannelOptions {
        ewald_tol: 1e-5,
        ..ChannelOptions::default()
    };
    let ch = ChannelStokes::new(
        g,
        MU,
        ViscosityContrast::MATCHED,
        WallMode::Penalty {
            kappa_w_n_per_m3: kappa,
        },
        opts,
    )
    .unwrap();
    let rate = ch.penalty_rate(kappa);
    let mean = 2.0;
    let nw = ch.mesh.n_vertices();
    let run = |dt: f64, steps: usize| {
        let mut d = vec![Vector3::zeros(); nw];
        let mut history = Vec::new();
        let mut last = None;
        for _ in 0..steps {
            let s = ch.penalty_velocity(None, &d, mean).unwrap();
            let slip = s.wall_velocity.iter().map(|v| v.norm()).fold(0.0, f64::max);
            history.push(slip);
            if !slip.is_finite() || slip > 1e12 {
                break;
            }
            d.iter_mut()
                .zip(&s.wall_velocity)
                .for_each(|(d, v)| *d += v * dt);
            last = Some(s);
        }
        (history, last, d)
    };
    let dt = 1.0 / rate;
    let (hist, sol, d) = run(dt, 400);
    let sol = sol.unwrap();
    let first_below = |tol: f64| hist.iter().position(|&s| s < tol * mean * 1e3);
    let dmax = d.iter().map(|v| v.norm()).fold(0.0, f64::max);
    eprintln!(
        "penalty: rate {rate:.3e} 1/s (explicit step < {:.3e} s); slip < 1% of the mean after {:?} steps, < 1e-4 after {:?}; final slip {:.3e} um/s; max wall displacement {dmax:.3e} um",
        2.0 / rate,
        first_below(1e-2),
        first_below(1e-4),
        hist.last().unwrap()
    );
    // Compare the relaxed traction with the exact no-slip one.
    let exact = ChannelStokes::new(
        g,
        MU,
        ViscosityContrast::MATCHED,
        WallMode::NoSlip,
        ChannelOptions {
            ewald_tol: 1e-5,
            ..ChannelOptions::default()
        },
    )
    .unwrap();
    let (_, grad_exact) = exact.empty_channel_flow(&[Vector3::zeros()], mean).unwrap();
    let grad = sol.stats.pressure_gradient_pa_per_um;
    eprintln!("penalty -dp/dx {grad:.5e} vs no-slip {grad_exact:.5e} Pa/um");
    assert!(first_below(1e-4).is_some(), "{:?}", &hist[hist.len() - 5..]);
    assert!((grad / grad_exact - 1.0).abs() < 1e-3);
    // Wall displacement |f| / kappa: ~0.1 um at 2 mm/s.
    assert!(dmax > 1e-3 && dmax < 0.5);
    // Above the explicit limit the iteration diverges.
    let (hist_bad, _, _) = run(2.2 / rate, 400);
    assert!(
        hist_bad.last().unwrap() > &(10.0 * hist_bad[0]),
        "{:?}",
        &hist_bad[hist_bad.len() - 3..]
    );
}
