//! Near-singular quadrature ([`rbc_solver::bim::near_field`]) on surfaces whose opposite sides come closer than a triangle edge: exact identities of the single and double layer.
//!
//! The identity (Pozrikidis 1992, ch. 4, the boundary-integral representation of a flow that is
//! regular inside `S`): a pure strain `u = E x` (`E` symmetric, traceless; pressure zero) has the
//! traction `2 mu E n` on `S`, and at every point `x` of a closed surface
//!
//! ```text
//! E x = 4 SL[E n](x) - K[E y](x),   SL[q] = 1/(8 pi) Int G . q dS,  K[u] = 1/(4 pi) PV Int u . T . n dS
//! ```
//!
//! (this is the drop equation of `rbc_solver::bim` for an interface that does not disturb the
//! flow: `(1 + lambda)/2 u = u_inf + SL[f]/mu + (1 - lambda)/2 K[u]` with `u = u_inf = E x`,
//! `f = 2 (lambda - 1) mu E n`). On a thin oblate spheroid (half-thickness below the edge
//! length, like the dimples of a folding red blood cell) the 7-point rule on the far side is
//! near-singular; the adaptive correction restores the accuracy of a sphere.

use nalgebra::{Matrix3, Vector3};
use rbc_solver::bim::double_layer::DoubleLayer;
use rbc_solver::bim::near_field::{NearField, NearFieldOptions};
use rbc_solver::bim::single_layer::SingleLayer;
use rbc_solver::bim::surface::Surface;
use rbc_solver::bim::BimOptions;
use rbc_solver::mesh::{spheroid, Mesh};

/// Largest error of `E x = 4 SL[E n] - K[E x]` at the vertices within `rho_max` (um) of the
/// axis, relative to `max |E x|`.
fn identity_error(mesh: &Mesh, near: &NearFieldOptions, rho_max: f64) -> f64 {
    let e = Matrix3::new(0.3, 0.5, -0.2, 0.5, -0.8, 0.4, -0.2, 0.4, 0.5);
    let s = Surface::new(mesh).unwrap();
    let nf = NearField::new(&s, near);
    let q: Vec<Vector3<f64>> = s.vertex_normals.iter().map(|n| e * n).collect();
    let u: Vec<Vector3<f64>> = s.vertices.iter().map(|x| e * x).collect();
    let sl = SingleLayer::new(&s, BimOptions::default().duffy_nodes, true).with_near_field(&nf).apply(&q);
    let k = DoubleLayer::new(&s).with_near_field(&nf).apply(&u);
    let scale = u.iter().map(|v| v.norm()).fold(0.0, f64::max);
    (0..s.n_vertices())
        .filter(|&i| s.vertices[i].xy().norm() < rho_max)
        .map(|i| (sl[i] * 4.0 - k[i] - u[i]).norm())
        .fold(0.0, f64::max)
        / scale
}

/// On a sphere (no near sheets) the identity holds at second order with either rule, and the
/// correction changes it by less than 1 %; on a thin spheroid it does not hurt either. (The
/// identity's error on the thin spheroid is dominated by the flat-triangle geometry of its rim,
/// not by the quadrature: the next test isolates the quadrature.)
#[test]
fn strain_identity_holds_with_the_correction() {
    let off = NearFieldOptions::off();
    let on = NearFieldOptions::default();
    let mut rows = Vec::new();
    for level in [3, 4] {
        let sphere = spheroid(level, 4.0, 4.0);
        let thin = spheroid(level, 4.0, 0.15);
        // On the thin spheroid: the faces (within 2.5 um of the axis), away from the rim whose
        // radius of curvature (c^2/a = 0.006 um) no flat triangle resolves.
        rows.push((
            level,
            identity_error(&sphere, &off, 10.0),
            identity_error(&sphere, &on, 10.0),
            identity_error(&thin, &off, 2.5),
            identity_error(&thin, &on, 2.5),
        ));
    }
    eprintln!("(level, sphere 7-point, sphere near field, thin 7-point, thin near field): {rows:?}");
    // Measured: sphere 5.1e-3 / 1.8e-3 (levels 3 / 4) either way; thin faces 8.6e-3 -> 7.3e-3, 1.5e-3 -> 1.4e-3.
    for &(level, s_off, s_on, t_off, t_on) in &rows {
        assert!((s_on / s_off - 1.0).abs() < 0.01, "level {level}: {rows:?}");
        assert!(t_on < t_off, "level {level}: {rows:?}");
    }
    assert!(rows[0].1 / rows[1].1 > 2.5, "second order on the sphere: {rows:?}");
}

/// The quadrature alone: the single and double layer of the strain-flow densities at the face
/// vertices of a spheroid 4 x 4 x 0.15 um (faces 0.3 um apart, edge ~0.8 um: the far face is at
/// 0.4 edge lengths) against a reference with a much wider and finer near field (`reach` 4,
/// `eta` 0.1; both leave the same sheet's next ring to the 7-point rule, whose error the
/// single-layer test `stokeslet_times_normal_integrates_to_zero` covers). The plain 7-point rule is off by percent of the local value; the default near
/// field agrees with the reference to a small fraction of that.
#[test]
fn near_field_converges_to_a_refined_reference_on_a_thin_spheroid() {
    let e = Matrix3::new(0.3, 0.5, -0.2, 0.5, -0.8, 0.4, -0.2, 0.4, 0.5);
    let s = Surface::new(&spheroid(3, 4.0, 0.15)).unwrap();
    let q: Vec<Vector3<f64>> = s.vertex_normals.iter().map(|n| e * n).collect();
    let u: Vec<Vector3<f64>> = s.vertices.iter().map(|x| e * x).collect();
    let eval = |opts: &NearFieldOptions| {
        let nf = NearField::new(&s, opts);
        let sl = SingleLayer::new(&s, BimOptions::default().duffy_nodes, true).with_near_field(&nf).apply(&q);
        let k = DoubleLayer::new(&s).with_near_field(&nf).apply(&u);
        (sl, k, nf.pieces())
    };
    let (sl_ref, k_ref, pieces_ref) = eval(&NearFieldOptions { reach: 4.0, eta: 0.1, max_depth: 9, ..NearFieldOptions::default() });
    let faces: Vec<usize> = (0..s.n_vertices()).filter(|&i| s.vertices[i].xy().norm() < 2.5).collect();
    let err = |sl: &[Vector3<f64>], k: &[Vector3<f64>]| {
        let sl_scale = faces.iter().map(|&i| sl_ref[i].norm()).fold(0.0, f64::max);
        let k_scale = faces.iter().map(|&i| k_ref[i].norm()).fold(0.0, f64::max);
        let e_sl = faces.iter().map(|&i| (sl[i] - sl_ref[i]).norm()).fold(0.0, f64::max) / sl_scale;
        let e_k = faces.iter().map(|&i| (k[i] - k_ref[i]).norm()).fold(0.0, f64::max) / k_scale;
        (e_sl, e_k)
    };
    let (sl_off, k_off, _) = eval(&NearFieldOptions::off());
    let (sl_on, k_on, pieces) = eval(&NearFieldOptions::default());
    let (off, on) = (err(&sl_off, &k_off), err(&sl_on, &k_on));
    eprintln!("thin spheroid, relative error against the reference ({pieces_ref} pieces): 7-point SL {:.2e} DL {:.2e}; near field ({pieces} pieces) SL {:.2e} DL {:.2e}", off.0, off.1, on.0, on.1);
    // Measured: 7-point 1.5e-3 (SL) and 5.9e-3 (DL); near field 1.0e-6 and 1.0e-6.
    assert!(off.0 > 1e-3 && off.1 > 1e-3, "the plain rule should be visibly off: {off:?}");
    assert!(on.0 < 0.1 * off.0 && on.1 < 0.1 * off.1, "{off:?} {on:?}");
}
