//! Conservation of the membrane force densities as the boundary integral method sees them: zero total force and torque of the linearly interpolated density, for every law.
//!
//! The BIM ([`rbc_solver::bim`]) interpolates the nodal force density linearly
//! on each flat triangle and integrates it with the 7-point Gauss rule. A free
//! membrane exerts no net force and no net torque on the fluid, so
//! `int Df dA = 0` and `int (x - c) x Df dA = 0` must hold for that
//! interpolant. The integrals here are computed independently of
//! [`rbc_solver::membrane::total_force_and_torque`], by the Gauss rule of the
//! BIM itself, and must vanish to rounding (1e-12 of `int |Df| dA`, and of
//! `R int |Df| dA` for the torque). The same integrals of the uncorrected
//! densities (`F_i / A_mixed_i`, and the node-wise bending formula) are
//! printed and must be far from zero: that is the inconsistency the
//! correction removes (measured: ~1e-3 of `int |Df| dA` on this mesh).

use nalgebra::{Matrix3, Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rbc_solver::bim::quadrature::gauss7;
use rbc_solver::membrane::bending::{BendingMethod, Helfrich};
use rbc_solver::membrane::skalak::{Skalak, SkalakConvention};
use rbc_solver::membrane::tension::Tension;
use rbc_solver::membrane::{total_force_and_torque, LinearisedLaw, MembraneLaw, UM};
use rbc_solver::mesh::{self, Mesh};

/// `(int Df dA, int (x - c) x Df dA, int |Df| dA)` of the linear interpolant by
/// the 7-point rule (exact: the integrands are polynomials of degree <= 2).
fn gauss_resultants(m: &Mesh, df: &[Vector3<f64>], c: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>, f64) {
    let rule = gauss7();
    let (mut f, mut t, mut mag) = (Vector3::zeros(), Vector3::zeros(), 0.0);
    for (k, tri) in m.triangles.iter().enumerate() {
        let x = m.corners(k);
        let area = 0.5 * (x[1] - x[0]).cross(&(x[2] - x[0])).norm();
        for node in &rule {
            let b = node.bary;
            let y = x[0] * b[0] + x[1] * b[1] + x[2] * b[2];
            let d = df[tri[0]] * b[0] + df[tri[1]] * b[1] + df[tri[2]] * b[2];
            let w = node.weight * area;
            f += d * w;
            t += (y - c).cross(&d) * w;
            mag += d.norm() * w;
        }
    }
    (f, t, mag)
}

/// A seeded, deformed, asymmetric discocyte: affine stretch, rotation, a smooth
/// bump and 2% random vertex noise (no symmetry can cancel a net force).
fn deformed(reference: &Mesh, seed: u64) -> Mesh {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let f = Rotation3::from_euler_angles(0.4, 0.2, -0.9).matrix() * Matrix3::from_diagonal(&Vector3::new(1.2, 0.9, 1.1));
    let h = reference.quality().mean_edge_um;
    let vertices = reference
        .vertices
        .iter()
        .map(|x| {
            let noise = Vector3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            f * x + Vector3::new(0.3 * (0.5 * x.x + 0.3).sin(), 0.02 * x.x * x.x, 0.1 * (0.4 * x.y).cos()) + noise * (0.02 * h)
        })
        .collect();
    Mesh { vertices, triangles: reference.triangles.clone() }
}

#[test]
fn force_densities_have_zero_total_force_and_torque_as_the_bim_integrates_them() {
    let reference = mesh::discocyte(3);
    let m = deformed(&reference, 5);
    let c = m.centroid();
    let arm = 4.0; // um
    let mut elastic: Vec<Box<dyn LinearisedLaw>> = vec![
        Box::new(Skalak::new(&reference, SkalakConvention::Krueger, 5e-6, 5e-4).unwrap()),
        Box::new(Skalak::barthes_biesel(&reference, 5e-6, 1.0).unwrap()),
        Box::new(Skalak::neo_hookean(&reference, 5e-6).unwrap()),
    ];
    elastic.push(Box::new(Tension::new(2e-6).unwrap()));
    let areas = m.vertex_areas();
    for law in &elastic {
        let df = law.force_density(&m);
        let (f, t, mag) = gauss_resultants(&m, &df, &c);
        // the uncorrected density F_i / A_mixed_i
        let mut raw = vec![Vector3::zeros(); m.vertices.len()];
        law.add_nodal_forces(&m, &mut raw);
        raw.iter_mut().zip(&areas).for_each(|(r, a)| *r /= a * UM * UM);
        let (fr, tr, _) = gauss_resultants(&m, &raw, &c);
        println!(
            "{}: |int Df| / int|Df| = {:.1e} (uncorrected {:.1e}), |int r x Df| / (R int|Df|) = {:.1e} (uncorrected {:.1e})",
            law.name(),
            f.norm() / mag,
            fr.norm() / mag,
            t.norm() / (arm * mag),
            tr.norm() / (arm * mag)
        );
        assert!(f.norm() < 1e-12 * mag && t.norm() < 1e-12 * arm * mag, "{}", law.name());
        assert!(fr.norm() > 1e-5 * mag, "{}: the uncorrected density should show the inconsistency", law.name());
    }
    for method in [BendingMethod::CotangentMethodC, BendingMethod::QuarticFit, BendingMethod::QuarticFitGalerkin] {
        let law = Helfrich::with_method(3e-19, method).unwrap();
        let df = law.force_density(&m);
        let (f, t, mag) = gauss_resultants(&m, &df, &c);
        let (fr, tr, _) = gauss_resultants(&m, &law.node_wise_force_density(&m), &c);
        println!(
            "{}: |int Df| / int|Df| = {:.1e} (node-wise {:.1e}), |int r x Df| / (R int|Df|) = {:.1e} (node-wise {:.1e})",
            law.name(),
            f.norm() / mag,
            fr.norm() / mag,
            t.norm() / (arm * mag),
            tr.norm() / (arm * mag)
        );
        assert!(f.norm() < 1e-12 * mag && t.norm() < 1e-12 * arm * mag, "{}", law.name());
        assert!(fr.norm() > 1e-5 * mag, "{}", law.name());
    }
    // the library's own resultants agree with the Gauss-rule integrals (N, N m)
    let law = Skalak::neo_hookean(&reference, 5e-6).unwrap();
    let mut raw = vec![Vector3::zeros(); m.vertices.len()];
    law.add_nodal_forces(&m, &mut raw);
    raw.iter_mut().zip(&areas).for_each(|(r, a)| *r /= a * UM * UM);
    let (fg, tg, _) = gauss_resultants(&m, &raw, &c);
    let (fl, tl) = total_force_and_torque(&m, &raw, &c);
    assert!((fl - fg * (UM * UM)).norm() < 1e-12 * fl.norm());
    assert!((tl - tg * (UM * UM * UM)).norm() < 1e-12 * tl.norm());
}
