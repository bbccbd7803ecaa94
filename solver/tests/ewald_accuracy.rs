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
    let s = setup(400, 100, 2);
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
