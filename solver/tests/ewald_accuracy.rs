//! Accuracy of the periodic Ewald sums: the direct reference sums are independent of the splitting parameter, and the spectral Ewald sums meet the requested error against them.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rbc_solver::ewald::{direct, Coincident, EwaldParams, PeriodicStokes};

fn random_vectors(n: usize, scale: [f64; 3], offset: f64, rng: &mut ChaCha8Rng) -> Vec<Vector3<f64>> {
    (0..n)
        .map(|_| Vector3::from_fn(|d, _| (rng.random::<f64>() - offset) * scale[d]))
        .collect()
}

/// `(rms relative, max relative)` error: `sqrt(sum |a-b|^2 / sum |b|^2)` and `max |a-b| / max |b|`.
fn rel_errors(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> (f64, f64) {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_squared()).sum();
    let den: f64 = b.iter().map(|y| y.norm_squared()).sum();
    let maxd = a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max);
    let maxb = b.iter().map(|y| y.norm()).fold(0.0, f64::max);
    ((num / den).sqrt(), maxd / maxb)
}

struct Setup {
    box_len: [f64; 3],
    targets: Vec<Vector3<f64>>,
    sources: Vec<Vector3<f64>>,
    forces: Vec<Vector3<f64>>,
    normals: Vec<Vector3<f64>>,
}

/// `n` random sources in a non-cubic box (some outside it, to exercise wrapping); the targets are
/// the sources themselves (coincident pairs) followed by `extra` random points.
fn setup(n: usize, extra: usize, seed: u64) -> Setup {
    let box_len = [6.0, 3.0, 2.5];
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let sources = random_vectors(n, box_len, 0.1, &mut rng);
    let forces = random_vectors(n, [1.0; 3], 0.5, &mut rng);
    let normals = random_vectors(n, [0.1; 3], 0.5, &mut rng);
    let mut targets = sources.clone();
    targets.extend(random_vectors(extra, box_len, 0.0, &mut rng));
    Setup { box_len, targets, sources, forces, normals }
}

/// Hasimoto's split moves work between real and Fourier space without changing the sum: the direct
/// sums at three splitting parameters (a factor 2.3 apart) agree to 1e-10 (relative rms). The sums
/// are truncated where the terms fall below ~1e-17, so only round-off remains.
#[test]
fn direct_sum_is_independent_of_xi() {
    let s = setup(40, 20, 1);
    let xi0 = direct::balanced_xi(s.box_len);
    let g = |xi: f64, c| direct::stokeslet(s.box_len, xi, &s.targets, &s.sources, &s.forces, c);
    let t = |xi: f64| direct::stresslet(s.box_len, xi, &s.targets, &s.sources, &s.forces, &s.normals);
    for c in [Coincident::Regular, Coincident::Exclude] {
        let reference = g(xi0, c);
        for f in [0.7, 1.6] {
            let (rms, max) = rel_errors(&g(xi0 * f, c), &reference);
            assert!(rms < 1e-10 && max < 1e-10, "Stokeslet {c:?}, xi x {f}: rms {rms:e}, max {max:e}");
        }
    }
    let reference = t(xi0);
    for f in [0.7, 1.6] {
        let (rms, max) = rel_errors(&t(xi0 * f), &reference);
        assert!(rms < 1e-10 && max < 1e-10, "stresslet, xi x {f}: rms {rms:e}, max {max:e}");
    }
}

/// The spectral Ewald sums with parameters from `EwaldParams::for_tolerance` meet the requested
/// relative error (rms over all targets and, more strictly, max error over max value) against the
/// direct sums, for the Stokeslet (both coincident-pair conventions) and the stresslet.
#[test]
fn spectral_ewald_meets_requested_tolerance() {
    let s = setup(300, 60, 2);
    let xi0 = direct::balanced_xi(s.box_len);
    let g_ref = direct::stokeslet(s.box_len, xi0, &s.targets, &s.sources, &s.forces, Coincident::Regular);
    let gx_ref = direct::stokeslet(s.box_len, xi0, &s.targets, &s.sources, &s.forces, Coincident::Exclude);
    let t_ref = direct::stresslet(s.box_len, xi0, &s.targets, &s.sources, &s.forces, &s.normals);
    for tol in [1e-3, 5e-5, 1e-5, 1e-7] {
        let mut p = EwaldParams::for_tolerance(s.box_len, s.sources.len(), tol).unwrap();
        let ps = PeriodicStokes::new(s.box_len, p).unwrap();
        let mut out = vec![Vector3::zeros(); s.targets.len()];
        ps.stokeslet(&s.targets, &s.sources, &s.forces, &mut out).unwrap();
        let eg = rel_errors(&out, &g_ref);
        ps.stresslet(&s.targets, &s.sources, &s.forces, &s.normals, &mut out).unwrap();
        let et = rel_errors(&out, &t_ref);
        p.coincident = Coincident::Exclude;
        let ps = PeriodicStokes::new(s.box_len, p).unwrap();
        ps.stokeslet(&s.targets, &s.sources, &s.forces, &mut out).unwrap();
        let ex = rel_errors(&out, &gx_ref);
        println!(
            "tol {tol:e}: xi {:.3} r_cut {:.3} grid {:?} P {} eta {:.3} | G rms {:.2e} max {:.2e} | G excl rms {:.2e} max {:.2e} | T rms {:.2e} max {:.2e}",
            p.xi, p.r_cut, p.grid, p.support, ps.eta(), eg.0, eg.1, ex.0, ex.1, et.0, et.1
        );
        for (name, e) in [("Stokeslet", eg), ("Stokeslet (exclude)", ex), ("stresslet", et)] {
            assert!(e.0 <= tol && e.1 <= tol, "{name} at tol {tol:e}: rms {:e}, max {:e}", e.0, e.1);
        }
    }
}

/// The paper's setting: a cell-sized sphere (radius 4 um, 258 mesh vertices) and points on the channel
/// walls (12 x 10 um cross-section) in the unit cell `L_x = 42.7 um` (box 42.7 x 14 x 12 um), at the
/// paper's error 5e-5: strongly non-uniform sources, the case the parameter estimates must also cover.
#[test]
fn channel_cell_at_paper_tolerance() {
    let box_len = [42.7, 14.0, 12.0];
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut pts: Vec<Vector3<f64>> =
        rbc_solver::mesh::sphere(3, 4.0).vertices.iter().map(|v| v + Vector3::new(20.0, 7.8, 6.4)).collect();
    for _ in 0..250 {
        let x = rng.random::<f64>() * box_len[0];
        let s = rng.random::<f64>() * 2.0 - 1.0;
        let side = rng.random::<f64>() < 0.5;
        let p = if side {
            Vector3::new(x, 7.0 + 6.0 * s.signum(), 7.0 + 5.0 * (2.0 * rng.random::<f64>() - 1.0) - 1.0)
        } else {
            Vector3::new(x, 7.0 + 6.0 * (2.0 * rng.random::<f64>() - 1.0), 6.0 + 5.0 * s.signum())
        };
        pts.push(p);
    }
    let f = random_vectors(pts.len(), [1.0; 3], 0.5, &mut rng);
    let n = random_vectors(pts.len(), [0.1; 3], 0.5, &mut rng);
    let xi0 = direct::balanced_xi(box_len);
    let g_ref = direct::stokeslet(box_len, xi0, &pts, &pts, &f, Coincident::Regular);
    let t_ref = direct::stresslet(box_len, xi0, &pts, &pts, &f, &n);
    let tol = 5e-5;
    let p = EwaldParams::for_tolerance(box_len, pts.len(), tol).unwrap();
    let ps = PeriodicStokes::new(box_len, p).unwrap();
    let mut out = vec![Vector3::zeros(); pts.len()];
    ps.stokeslet(&pts, &pts, &f, &mut out).unwrap();
    let eg = rel_errors(&out, &g_ref);
    ps.stresslet(&pts, &pts, &f, &n, &mut out).unwrap();
    let et = rel_errors(&out, &t_ref);
    println!("channel cell, {} points, {p:?}: G rms {:.2e} max {:.2e} | T rms {:.2e} max {:.2e}", pts.len(), eg.0, eg.1, et.0, et.1);
    assert!(eg.0 <= tol && eg.1 <= tol && et.0 <= tol && et.1 <= tol);
}

/// Bad input gives typed errors naming the parameter or the array, never a panic.
#[test]
fn invalid_input_is_reported() {
    use rbc_solver::ewald::EwaldError;
    assert!(matches!(EwaldParams::for_tolerance([1.0, -1.0, 1.0], 10, 1e-5), Err(EwaldError::InvalidParameter { name: "box side", .. })));
    assert!(matches!(EwaldParams::for_tolerance([1.0; 3], 10, 0.5), Err(EwaldError::InvalidParameter { name: "tol", .. })));
    let p = EwaldParams::for_tolerance([1.0; 3], 10, 1e-5).unwrap();
    let bad = EwaldParams { grid: [p.support; 3], ..p };
    assert!(matches!(PeriodicStokes::new([1.0; 3], bad), Err(EwaldError::InvalidParameter { name: "support", .. })));
    let ps = PeriodicStokes::new([1.0; 3], p).unwrap();
    let x = vec![Vector3::new(0.1, 0.2, 0.3); 2];
    let mut out = vec![Vector3::zeros(); 2];
    assert!(matches!(ps.stokeslet(&x, &x, &x[..1], &mut out), Err(EwaldError::LengthMismatch { what: "forces", .. })));
    let nan = vec![Vector3::new(f64::NAN, 0.0, 0.0); 2];
    assert!(matches!(ps.stresslet(&x, &x, &nan, &x, &mut out), Err(EwaldError::NonFinite { what: "strength", index: 0 })));
}

/// Calibration study behind the constants of `ewald::params`: the real-space part alone (the rest
/// converged), then the window P on the grid of the Fourier estimate and on the 1.2x finer grid
/// actually used, at xi = 2 in the 6 x 3 x 2.5 box (tol 1e-5 for the grid: s_k^2 = 11.5 + 0.5).
/// Run: `cargo test -p rbc-solver --test ewald_accuracy -- --ignored --nocapture error_parts` (~1 s).
///
/// Measured (session 57; rms relative errors of the Stokeslet G and the stresslet T):
/// - real space, s_r = 2, 3, 4: G 4.14e-3, 3.78e-5, 3.87e-8; T 4.87e-3, 5.92e-5, 8.05e-8, i.e.
///   0.23-0.73 exp(-s_r^2);
/// - window P = 6, 8, 10, 12 on the finer grid: G 1.88e-4, 1.35e-5, 1.53e-6, 9.69e-8; T 6.93e-5,
///   7.24e-6, 1.12e-6, 7.54e-8, i.e. 0.9-15 exp(-pi P / 2), each at most the estimate's grid's
///   (at P = 12 the two grids coincide).
///
/// Asserted: each error within 25 % of the measured one, and the orders of magnitude the
/// constants rest on (each error below exp(-s_r^2), and below 25 exp(-pi P / 2)).
#[test]
#[ignore]
fn error_parts_calibration() {
    use rbc_solver::ewald::params::grid_for;
    let s = setup(300, 0, 2);
    let xi = 2.0;
    let g_ref = direct::stokeslet(s.box_len, xi, &s.targets, &s.sources, &s.forces, Coincident::Regular);
    let t_ref = direct::stresslet(s.box_len, xi, &s.targets, &s.sources, &s.forces, &s.normals);
    let run = |p: EwaldParams| {
        let ps = PeriodicStokes::new(s.box_len, p).unwrap();
        let mut out = vec![Vector3::zeros(); s.targets.len()];
        ps.stokeslet(&s.targets, &s.sources, &s.forces, &mut out).unwrap();
        let eg = rel_errors(&out, &g_ref);
        ps.stresslet(&s.targets, &s.sources, &s.forces, &s.normals, &mut out).unwrap();
        (eg, rel_errors(&out, &t_ref), ps.eta())
    };
    let fine = grid_for(s.box_len, xi, 7.0, 30);
    let base = EwaldParams { xi, r_cut: 7.0 / xi, grid: fine, support: 30, coincident: Coincident::Regular };
    let near = |found: f64, measured: f64| (found / measured - 1.0).abs() <= 0.25;
    for (sr, g_was, t_was) in [(2.0f64, 4.14e-3, 4.87e-3), (3.0, 3.78e-5, 5.92e-5), (4.0, 3.87e-8, 8.05e-8)] {
        let (g, t, _) = run(EwaldParams { r_cut: sr / xi, ..base });
        let bound = (-sr * sr).exp();
        println!("real s_r {sr}: exp(-s^2) {bound:.1e}  G rms {:.2e}  T rms {:.2e}", g.0, t.0);
        assert!(near(g.0, g_was) && near(t.0, t_was) && g.0 < bound && t.0 < bound, "s_r {sr}: G {:e}, T {:e}", g.0, t.0);
    }
    for (p, g_was, t_was) in [(6usize, 1.88e-4, 6.93e-5), (8, 1.35e-5, 7.24e-6), (10, 1.53e-6, 1.12e-6), (12, 9.69e-8, 7.54e-8)] {
        let bound = (-std::f64::consts::PI * p as f64 / 2.0).exp();
        let mut on = Vec::new();
        for refine in [1.0, 1.2] {
            let grid = grid_for(s.box_len, xi, refine * (11.5f64 + 0.5).sqrt(), p);
            let (g, t, eta) = run(EwaldParams { grid, support: p, ..base });
            println!("window P {p} grid {grid:?} eta {eta:.2}: exp(-pi P/2) {bound:.1e}  G rms {:.2e}  T rms {:.2e}", g.0, t.0);
            on.push((g.0, t.0));
        }
        let ((g_est, t_est), (g, t)) = (on[0], on[1]);
        assert!(near(g, g_was) && near(t, t_was) && g < 25.0 * bound && t < 25.0 * bound, "P {p}: G {g:e}, T {t:e}");
        assert!(g <= g_est && t <= t_est, "P {p}: the finer grid is no worse: G {g:e} against {g_est:e}, T {t:e} against {t_est:e}");
    }
}
