//! Exact-answer tests of the free-space boundary-integral solve: Hadamard-Rybczynski drops, rigid motions, zero net flux, sign conventions.

use nalgebra::Vector3;
use rbc_solver::bim::{BimError, BimOptions, FreeSpaceStokes, SolveStats};
use rbc_solver::viscosity::ViscosityContrast;
use rbc_solver::flow::{BackgroundFlow, Quiescent, RigidMotion, SimpleShear, UnboundedPoiseuille};
use rbc_solver::mesh::{sphere, Mesh};

const MU: f64 = 1.2e-3; // Pa s, plasma (physics.md)
const A: f64 = 4.0; // um
const C: f64 = 1.0; // Pa

/// `f = c (e_y . n) n` at the vertices (exact sphere normals), the force per area the
/// membrane exerts on the fluid. Total force `F = Int f dS = c 4 pi a^2 / 3` along +y.
fn hr_force(mesh: &Mesh) -> Vec<Vector3<f64>> {
    mesh.vertices.iter().map(|x| x.normalize() * (C * x.normalize().y)).collect()
}

/// Hadamard-Rybczynski velocity `U = F (1 + lambda) / (2 pi mu a (2 + 3 lambda))` (um/s).
fn hr_velocity(lambda: f64) -> f64 {
    let f = C * 4.0 * std::f64::consts::PI * A * A / 3.0;
    f * (1.0 + lambda) / (2.0 * std::f64::consts::PI * MU * A * (2.0 + 3.0 * lambda))
}

/// Exact interface velocity of the Hadamard-Rybczynski drop in the lab frame:
/// `u = U e_y - U / (2 (1 + lambda)) (e_y - (e_y . n) n)`. The shape translates with `U`; the
/// interface also slides tangentially (internal circulation; from the stream function in
/// Batchelor, "An introduction to fluid dynamics", 1967, section 4.9: the slip at `r = a` is
/// `U sin(theta) / (2 (1 + lambda))`), which vanishes for a rigid sphere (lambda -> inf).
fn hr_interface_velocity(x: &Vector3<f64>, lambda: f64) -> Vector3<f64> {
    let (u, n, e) = (hr_velocity(lambda), x.normalize(), Vector3::y());
    e * u - (e - n * n.y) * (u / (2.0 * (1.0 + lambda)))
}

/// Drop speed from the normal velocity: `U = 3 / (4 pi a^2) Int (u . n) n dS` for a translating sphere
/// (discrete: vertex areas and vertex normals of the mesh).
fn drop_velocity(mesh: &Mesh, u: &[Vector3<f64>]) -> Vector3<f64> {
    let (w, n) = (mesh.vertex_areas(), mesh.vertex_normals());
    let s: Vector3<f64> = u.iter().zip(&w).zip(&n).map(|((u, w), n)| n * (w * u.dot(n))).sum();
    s * 3.0 / mesh.area()
}

fn flux(mesh: &Mesh, u: &[Vector3<f64>]) -> f64 {
    let (w, n) = (mesh.vertex_areas(), mesh.vertex_normals());
    u.iter().zip(&w).zip(&n).map(|((u, w), n)| w * u.dot(n)).sum()
}

struct HrResult {
    /// |U_drop - U| / U.
    speed_err: f64,
    /// max_i |u_i - u_exact(x_i)| / U.
    max_err: f64,
    stats: SolveStats,
}

fn hr(level: usize, lambda: f64, opts: BimOptions) -> Result<HrResult, BimError> {
    let mesh = sphere(level, A);
    let (u, stats) = FreeSpaceStokes::new(MU, ViscosityContrast::new(lambda).unwrap(), opts).velocity(&mesh, &hr_force(&mesh), &Quiescent)?;
    let exact = hr_velocity(lambda);
    let speed_err = (drop_velocity(&mesh, &u) - Vector3::new(0.0, exact, 0.0)).norm() / exact;
    let max_err = u
        .iter()
        .zip(&mesh.vertices)
        .map(|(u, x)| (u - hr_interface_velocity(x, lambda)).norm())
        .fold(0.0, f64::max)
        / exact;
    Ok(HrResult { speed_err, max_err, stats })
}

#[test]
fn hadamard_rybczynski_ratio_is_18_over_17_at_lambda_5() {
    // U / U_Stokes with U_Stokes = F / (6 pi mu a): 3 (1 + lambda) / (2 + 3 lambda).
    let f = C * 4.0 * std::f64::consts::PI * A * A / 3.0;
    let stokes = f / (6.0 * std::f64::consts::PI * MU * A);
    assert!((hr_velocity(5.0) / stokes - 18.0 / 17.0).abs() < 1e-14);
}

/// The drop translates along +y (this fixes the sign of `traction_jump`: the force
/// the membrane exerts on the fluid) at the Hadamard-Rybczynski speed, for every lambda,
/// with second-order convergence; < 1 % at 2048 triangles. The measured table is printed
/// (`cargo test -p rbc-solver --test bim_free_space -- --nocapture`).
#[test]
fn hadamard_rybczynski_drop_converges_for_every_lambda() {
    eprintln!("lambda level triangles  speed_err  max_err    iterations residual");
    for lambda in [0.1, 1.0, 5.0, 20.0] {
        let mut errs = Vec::new();
        for level in [2, 3, 4] {
            let r = hr(level, lambda, BimOptions::default()).unwrap();
            eprintln!(
                "{lambda:6} {level:5} {:9}  {:.3e}  {:.3e}  {:10} {:.1e}",
                8 * 4usize.pow(level as u32),
                r.speed_err,
                r.max_err,
                r.stats.iterations,
                r.stats.residual
            );
            if lambda == 1.0 {
                assert_eq!(r.stats.iterations, 0, "lambda = 1 builds no double layer");
            } else {
                assert!(r.stats.residual <= 1e-5);
                // Deflated second-kind equation: eigenvalues in [1/3, 5/3] at lambda = 5; measured 5-9 iterations.
                assert!(r.stats.iterations <= 30, "lambda {lambda} level {level}: {:?}", r.stats);
            }
            errs.push(r);
        }
        // The requirement of the issue: < 1 % at 2048 triangles (level 4), pointwise.
        assert!(errs[2].max_err < 1e-2, "lambda {lambda}: max error {}", errs[2].max_err);
        // Second order: halving h divides the error by ~4 (at least 2.5 allowing for pre-asymptotics).
        assert!(errs[1].max_err / errs[2].max_err > 2.5, "lambda {lambda}");
        assert!(errs[1].speed_err / errs[2].speed_err > 2.5, "lambda {lambda}");
    }
}

/// Without Wielandt deflation the solve still converges at lambda = 5 (eigenvalue 1 + kappa = 1/3
/// kept), but more slowly; at lambda = 1000 the rigid-body eigenvalue 1 + kappa ~ 2e-3 makes the
/// undeflated equation nearly singular while the deflated one converges as fast as at lambda = 5.
#[test]
fn deflation_keeps_large_viscosity_ratio_well_conditioned() {
    let no_defl = BimOptions { deflate_rigid_body: false, deflate_flux: false, ..BimOptions::default() };
    let d5 = hr(3, 5.0, BimOptions::default()).unwrap();
    let n5 = hr(3, 5.0, no_defl.clone()).unwrap();
    let d1000 = hr(3, 1000.0, BimOptions::default()).unwrap();
    let n1000 = hr(3, 1000.0, no_defl);
    eprintln!(
        "iterations: deflated lambda=5 {}, undeflated lambda=5 {}, deflated lambda=1000 {}, undeflated lambda=1000 {:?}",
        d5.stats.iterations,
        n5.stats.iterations,
        d1000.stats.iterations,
        n1000.as_ref().map(|r| r.stats.iterations)
    );
    assert!(d5.stats.iterations < n5.stats.iterations);
    assert!(d1000.stats.iterations <= d5.stats.iterations + 5);
    // Same physics either way: both answers agree to the GMRES tolerance scale.
    assert!((d5.speed_err - n5.speed_err).abs() < 1e-4);
    // lambda -> inf is a rigid sphere: Stokes drag (HR with lambda = 1000 differs from Stokes by 1e-4).
    assert!(d1000.max_err < 3e-2);
    // (measured: it converges, in 7 iterations against the deflated solve's 4)
    let r = n1000.expect("the undeflated lambda = 1000 solve converges, slowly");
    assert!(r.stats.iterations > d1000.stats.iterations);
}

/// A rigid motion of the interface is reproduced: with zero membrane force and a rigid-body
/// background flow, the double-layer equation returns that motion at every vertex.
#[test]
fn rigid_body_motion_is_reproduced() {
    let mesh = sphere(3, A).transformed(
        &nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 0.5),
        &Vector3::new(1.0, -2.0, 0.5),
    );
    let rigid = RigidMotion {
        translation_um_per_s: Vector3::new(30.0, -10.0, 5.0),
        angular_velocity_per_s: Vector3::new(2.0, 5.0, -3.0),
        center_um: Vector3::new(0.5, 0.5, 0.0),
    };
    let zero = vec![Vector3::zeros(); mesh.vertices.len()];
    for lambda in [0.1, 5.0, 20.0] {
        for (rb, fl) in [(true, true), (false, false)] {
            let opts = BimOptions { deflate_rigid_body: rb, deflate_flux: fl, ..BimOptions::default() };
            let (u, st) = FreeSpaceStokes::new(MU, ViscosityContrast::new(lambda).unwrap(), opts).velocity(&mesh, &zero, &rigid).unwrap();
            let scale = 30.0;
            let err = u
                .iter()
                .zip(&mesh.vertices)
                .map(|(u, x)| (u - rigid.velocity(x)).norm())
                .fold(0.0, f64::max)
                / scale;
            // GMRES tolerance 1e-5 relative; the discrete operator reproduces rigid motions exactly.
            assert!(err < 1e-5, "lambda {lambda}, deflation {rb}: {err} ({st:?})");
        }
    }
}

/// A drop in a linear (shear) or quadratic (Poiseuille) background flow with zero membrane
/// force is a passive fluid region with the same viscosity when lambda = 1: the velocity is
/// the background flow itself. For lambda != 1 the drop disturbs the flow but conserves volume.
#[test]
fn background_flows_pass_through_a_matched_drop() {
    let mesh = sphere(3, A);
    let zero = vec![Vector3::zeros(); mesh.vertices.len()];
    let shear = SimpleShear { shear_rate_per_s: 100.0 };
    let pois = UnboundedPoiseuille { max_velocity_um_per_s: 1000.0, radius_um: 10.0 };
    for flow in [&shear as &dyn BackgroundFlow, &pois] {
        let (u, _) = FreeSpaceStokes::new(MU, ViscosityContrast::MATCHED, BimOptions::default()).velocity(&mesh, &zero, flow).unwrap();
        for (u, x) in u.iter().zip(&mesh.vertices) {
            assert!((u - flow.velocity(x)).norm() < 1e-12);
        }
        let (u5, st) = FreeSpaceStokes::new(MU, ViscosityContrast::new(5.0).unwrap(), BimOptions::default()).velocity(&mesh, &zero, flow).unwrap();
        let scale = u5.iter().map(|u| u.norm()).fold(0.0, f64::max);
        assert!(flux(&mesh, &u5).abs() / (scale * mesh.area()) < 1e-6, "{st:?}");
    }
}

/// Bad input gives typed errors, not panics or NaNs.
#[test]
fn invalid_input_is_rejected() {
    let mesh = sphere(2, A);
    let f = hr_force(&mesh);
    let s = FreeSpaceStokes::new(MU, ViscosityContrast::new(5.0).unwrap(), BimOptions::default());
    assert!(matches!(s.velocity(&mesh, &f[1..], &Quiescent), Err(BimError::LengthMismatch { .. })));
    let mut g = f.clone();
    g[7].x = f64::NAN;
    assert!(matches!(s.velocity(&mesh, &g, &Quiescent), Err(BimError::NonFiniteInput { vertex: 7, .. })));
    let bad = FreeSpaceStokes::new(-1.0, ViscosityContrast::new(5.0).unwrap(), BimOptions::default());
    assert!(matches!(bad.velocity(&mesh, &f, &Quiescent), Err(BimError::InvalidParameter { .. })));
    let mut m = mesh.clone();
    let t = m.triangles[3];
    m.vertices[t[1]] = m.vertices[t[0]];
    assert!(matches!(s.velocity(&m, &f, &Quiescent), Err(BimError::BadTriangle { .. })));
    // A GMRES budget too small to converge is reported with the iteration count and residual.
    let tight = BimOptions { gmres_max_iterations: 1, gmres_tolerance: 1e-12, ..BimOptions::default() };
    let e = FreeSpaceStokes::new(MU, ViscosityContrast::new(5.0).unwrap(), tight).velocity(&mesh, &f, &Quiescent).unwrap_err();
    assert!(matches!(e, BimError::GmresDiverged { iterations: 1, .. }), "{e:?}");
}

/// Mesh-refinement study up to 8192 triangles (5 s on 2 cores):
/// `cargo test -p rbc-solver --test bim_free_space -- --ignored --nocapture hadamard_rybczynski_study`.
/// Found (2026-11-25): at 8192 triangles the speed error is 0.77-1.10e-3 (lambda 1 .. 0.1) and
/// halving h from 2048 to 8192 triangles divides the speed and the pointwise error by 3.8-3.9
/// (second order holds to the finest mesh), in 2-3 deflated GMRES iterations; asserted with
/// margins below.
#[test]
#[ignore]
fn hadamard_rybczynski_study_to_8192_triangles() {
    eprintln!("lambda level triangles  speed_err  max_err    iterations residual  seconds");
    for lambda in [0.1, 1.0, 5.0, 20.0] {
        let mut errs = Vec::new();
        for level in [2, 3, 4, 5] {
            let t = std::time::Instant::now();
            let r = hr(level, lambda, BimOptions::default()).unwrap();
            eprintln!(
                "{lambda:6} {level:5} {:9}  {:.3e}  {:.3e}  {:10} {:.1e}  {:.2}",
                8 * 4usize.pow(level as u32),
                r.speed_err,
                r.max_err,
                r.stats.iterations,
                r.stats.residual,
                t.elapsed().as_secs_f64()
            );
            assert!(r.stats.iterations <= 5, "lambda {lambda} level {level}: {:?}", r.stats);
            errs.push(r);
        }
        let (fine, finest) = (&errs[2], &errs[3]);
        assert!(finest.speed_err < 1.5e-3, "lambda {lambda}: speed error {:e} at 8192 triangles", finest.speed_err);
        assert!(fine.speed_err / finest.speed_err > 3.5, "lambda {lambda}: {:e} -> {:e}", fine.speed_err, finest.speed_err);
        assert!(fine.max_err / finest.max_err > 3.5, "lambda {lambda}: {:e} -> {:e}", fine.max_err, finest.max_err);
    }
}

/// A smooth force density without parity in any coordinate (Pa): the meshes are symmetric
/// under `x -> -x` etc., and a force of definite parity would make the net flux vanish by symmetry.
fn generic_force(mesh: &Mesh) -> Vec<Vector3<f64>> {
    mesh.vertices
        .iter()
        .map(|x| {
            Vector3::new(
                (0.6 * x.x + 0.7 * x.y + 0.3).sin(),
                (0.5 * x.z - 0.4 * x.y).cos(),
                0.2 + (0.5 * x.z + 0.3 * x.x).sin(),
            )
        })
        .collect()
}

/// The paper's cell (Evans-Fung discocyte, 2048 triangles) at lambda = 5 with a generic load in
/// shear flow: the deflated GMRES converges in a few tens of iterations at most, fewer than
/// without deflation, and large lambda stays cheap. Iteration counts are printed.
#[test]
fn discocyte_gmres_iterations() {
    let mesh = rbc_solver::mesh::discocyte(4);
    let f = generic_force(&mesh);
    let shear = SimpleShear { shear_rate_per_s: 200.0 };
    let no_defl = BimOptions { deflate_rigid_body: false, deflate_flux: false, ..BimOptions::default() };
    let mut rows = Vec::new();
    for lambda in [5.0, 20.0, 1000.0] {
        let (_, d) = FreeSpaceStokes::new(MU, ViscosityContrast::new(lambda).unwrap(), BimOptions::default()).velocity(&mesh, &f, &shear).unwrap();
        let (_, n) = FreeSpaceStokes::new(MU, ViscosityContrast::new(lambda).unwrap(), no_defl.clone()).velocity(&mesh, &f, &shear).unwrap();
        rows.push((lambda, d.iterations, n.iterations));
    }
    eprintln!("discocyte 2048 triangles (lambda, deflated iterations, undeflated iterations): {rows:?}");
    for &(lambda, d, n) in &rows {
        assert!(d <= 30, "lambda {lambda}: {d} iterations");
        assert!(d <= n, "lambda {lambda}: deflation should not cost iterations ({d} vs {n})");
    }
    // At lambda = 1000 the undeflated equation has the eigenvalue 1 + kappa = 2e-3: clearly slower.
    assert!(rows[2].2 >= rows[2].1 + 5, "{rows:?}");
}

/// Zero net flux `Int u . n dS = 0` (incompressible interior) to discretisation accuracy on the
/// discocyte with a generic load: second-order decrease with the mesh, with and without the flux deflation.
#[test]
fn velocity_has_no_net_flux() {
    let mut rows = Vec::new();
    for level in [2, 3, 4] {
        let mesh = rbc_solver::mesh::discocyte(level);
        let f = generic_force(&mesh);
        let mut row = vec![level as f64];
        for deflate_flux in [true, false] {
            let opts = BimOptions { deflate_flux, ..BimOptions::default() };
            let (u, _) = FreeSpaceStokes::new(MU, ViscosityContrast::new(5.0).unwrap(), opts).velocity(&mesh, &f, &Quiescent).unwrap();
            let scale = u.iter().map(|u| u.norm()).fold(0.0, f64::max) * mesh.area();
            row.push(flux(&mesh, &u) / scale);
        }
        rows.push(row);
    }
    eprintln!("flux / (max|u| area) on the discocyte, lambda = 5 (level, flux-deflated, not): {rows:?}");
    for k in [1, 2] {
        assert!(rows[2][k].abs() < 1e-3, "{rows:?}");
        assert!(rows[1][k].abs() / rows[2][k].abs() > 2.5, "{rows:?}");
    }
}

/// Warm start: the converged velocity as the guess needs no iteration and returns the same
/// velocity; a perturbed guess (1 % noise, as from the previous time step) needs fewer iterations than none.
#[test]
fn warm_start_from_a_guess() {
    let mesh = rbc_solver::mesh::discocyte(3);
    let f = generic_force(&mesh);
    let shear = SimpleShear { shear_rate_per_s: 200.0 };
    let solver = FreeSpaceStokes::new(MU, ViscosityContrast::new(5.0).unwrap(), BimOptions { gmres_tolerance: 1e-8, ..BimOptions::default() });
    let (u, cold) = solver.velocity(&mesh, &f, &shear).unwrap();
    let (u2, warm) = solver.velocity_with_guess(&mesh, &f, &shear, Some(&u)).unwrap();
    assert_eq!(warm.iterations, 0, "{warm:?}");
    let scale = u.iter().map(|u| u.norm()).fold(0.0, f64::max);
    assert!(u.iter().zip(&u2).all(|(a, b)| (a - b).norm() < 1e-7 * scale));
    let noisy: Vec<_> = u
        .iter()
        .enumerate()
        .map(|(i, v)| v + Vector3::new((i as f64 * 1.3).sin(), (i as f64 * 2.1).cos(), (i as f64 * 0.7).sin()) * (0.01 * scale))
        .collect();
    let (_, near) = solver.velocity_with_guess(&mesh, &f, &shear, Some(&noisy)).unwrap();
    eprintln!("iterations to 1e-8: cold {}, exact guess {}, 1% noisy guess {}", cold.iterations, warm.iterations, near.iterations);
    assert!(near.iterations < cold.iterations, "{near:?} vs {cold:?}");
}

/// Self-convergence on the paper's shape (no exact answer exists): the octahedron subdivision keeps
/// the vertices of coarser levels (same indices), so velocities at common vertices can be compared
/// across levels. Differences shrink by ~4 per level (second order) at lambda = 5 in shear with a
/// generic load. Returns `max_i |u_L - u_{L+1}| / max |u|` for consecutive levels.
fn discocyte_self_convergence(levels: &[usize]) -> Vec<f64> {
    let shear = SimpleShear { shear_rate_per_s: 200.0 };
    let solver = FreeSpaceStokes::new(MU, ViscosityContrast::new(5.0).unwrap(), BimOptions { gmres_tolerance: 1e-8, ..BimOptions::default() });
    let sols: Vec<(Mesh, Vec<Vector3<f64>>)> = levels
        .iter()
        .map(|&l| {
            let mesh = rbc_solver::mesh::discocyte(l);
            let (u, _) = solver.velocity(&mesh, &generic_force(&mesh), &shear).unwrap();
            (mesh, u)
        })
        .collect();
    sols.windows(2)
        .map(|w| {
            let (coarse, fine) = (&w[0], &w[1]);
            let n = coarse.0.vertices.len();
            assert!(coarse.0.vertices.iter().zip(&fine.0.vertices[..n]).all(|(a, b)| (a - b).norm() < 1e-12));
            let scale = fine.1.iter().map(|u| u.norm()).fold(0.0, f64::max);
            coarse.1.iter().zip(&fine.1[..n]).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max) / scale
        })
        .collect()
}

#[test]
fn discocyte_velocity_converges_under_refinement() {
    let d = discocyte_self_convergence(&[2, 3, 4]);
    eprintln!("discocyte, lambda = 5: max |u_L - u_(L+1)| / max|u| for L = 2, 3: {d:?}");
    assert!(d[0] / d[1] > 2.5, "{d:?}");
    assert!(d[1] < 2e-2, "{d:?}");
}

/// The same study to 8192 triangles (8 s on 2 cores):
/// `cargo test -p rbc-solver --test bim_free_space -- --ignored --nocapture discocyte_self_convergence_study`.
/// Found (2026-11-25): 0.062, 0.019, 0.0049 for L = 2, 3, 4 (ratios 3.3 and 3.8: second order
/// sets in by 2048 triangles); asserted with margins.
#[test]
#[ignore]
fn discocyte_self_convergence_study() {
    let d = discocyte_self_convergence(&[2, 3, 4, 5]);
    eprintln!("discocyte, lambda = 5: max |u_L - u_(L+1)| / max|u| for L = 2, 3, 4: {d:?}");
    assert!(d[0] / d[1] > 2.5 && d[1] / d[2] > 3.2, "{d:?}");
    assert!(d[2] < 6e-3, "{d:?}");
}

/// Small viscosity ratio: the eigenvalue 1 - kappa of the flux mode tends to 0 as lambda -> 0;
/// with the flux deflation lambda = 1e-3 converges like lambda = 0.1, without it lambda = 0.01
/// needs more iterations. A bubble (lambda = 0) is no cell: the viscosity contrast refuses it,
/// as it refuses it for every operator (`rbc_solver::viscosity`).
#[test]
fn flux_deflation_handles_small_viscosity_ratios() {
    let mesh = rbc_solver::mesh::discocyte(3);
    let f = generic_force(&mesh);
    let shear = SimpleShear { shear_rate_per_s: 200.0 };
    let no_flux = BimOptions { deflate_flux: false, ..BimOptions::default() };
    let it = |lambda: f64, opts: BimOptions| FreeSpaceStokes::new(MU, ViscosityContrast::new(lambda).unwrap(), opts).velocity(&mesh, &f, &shear).map(|r| r.1.iterations);
    let d0 = it(1e-3, BimOptions::default()).unwrap();
    let d01 = it(0.1, BimOptions::default()).unwrap();
    let d001 = it(0.01, BimOptions::default()).unwrap();
    let n001 = it(0.01, no_flux.clone()).unwrap();
    eprintln!("iterations: lambda 1e-3 {d0}, 0.1 {d01}, 0.01 {d001} (without flux deflation {n001})");
    assert!(ViscosityContrast::new(0.0).is_err());
    assert!(d0 <= d01 + 5, "{d0} vs {d01}");
    assert!(n001 > d001, "{n001} vs {d001}");
}

/// Reproducibility: each target's sums run on one thread in a fixed order, so the velocity is
/// bitwise the same for any number of threads.
#[test]
fn result_is_independent_of_thread_count() {
    let mesh = rbc_solver::mesh::discocyte(3);
    let f = generic_force(&mesh);
    let shear = SimpleShear { shear_rate_per_s: 200.0 };
    let solve = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| FreeSpaceStokes::new(MU, ViscosityContrast::new(5.0).unwrap(), BimOptions::default()).velocity(&mesh, &f, &shear).unwrap().0)
    };
    assert_eq!(solve(1), solve(2));
}
