//! Capsule in simple shear: steady Taylor deformation of a neo-Hookean capsule (lambda = 1) against small-deformation theory and Ramanujan & Pozrikidis (1998).
//!
//! Definitions (module documentation of `rbc_solver::validation`, where
//! the references, their definitions and the measured table are given):
//! - law `w = Gs/2 (I1 - 1 + 1/(I2 + 1))` (Barthes-Biesel, Diaz & Dhenin 2002), the
//!   tension `Es/(3 l1 l2) (l1^2 - 1/(l1 l2)^2)` of Pozrikidis (1995) and Ramanujan &
//!   Pozrikidis (1998) with `Es = 3 Gs` (checked exactly below);
//! - `Ca = mu rate a / Gs` (= 3 x their `mu rate a / Es`);
//! - `D = (L - B)/(L + B)` of the ellipsoid with the capsule's second moment of
//!   volume (Ramanujan & Pozrikidis' definition), read at `rate t = 8`, the end of
//!   their runs (their D(t) passes through a maximum near `rate t = 3.5` first).
//!
//! The 2 % target (issue 3, item 5) is met against small-deformation theory
//! (`D = 25/12 Ca`, Barthes-Biesel & Rallison 1981) at Ca = 0.01: -1.4 % at 512
//! triangles, -0.3 % at 2048, -0.03 % at 8192, +0.07 % extrapolated. At moderate
//! Ca the mesh-converged D lies +3.3 % (Ca = 0.3) and +4.6 % (0.6) above
//! Ramanujan & Pozrikidis, and at Ca = 0.15
//! the finest mesh wrinkles (no converged steady D without bending stiffness); see
//! `moderate_ca_convergence_study` and the validation module for the evidence.
//!
//! Long studies (ignored; each prints its table):
//! `nice -n 10 cargo test -p rbc-solver --test flow_capsule_moderate_ca -- --ignored --nocapture`
//! (measured on the shared 2-core machine under load ~7: 8192 triangles take
//! 2.5-17 min per capillary number).

use nalgebra::{Matrix3, Vector3};
use rbc_solver::validation::{profile_deformation, run_case, Case, CaseResult, RAMANUJAN_POZRIKIDIS_1998_NH};
use rbc_solver::membrane::skalak::Skalak;
use rbc_solver::membrane::{MembraneLaw, UM};
use rbc_solver::mesh::Mesh;

/// Run length in relaxation times `mu a (1 + lambda)/Gs` such that `rate t = 8`
/// (`rate t = 2 Ca x relaxations` at lambda = 1): the end of Ramanujan & Pozrikidis' runs.
fn relaxations_to_rate_t_8(ca: f64) -> f64 {
    8.0 / (2.0 * ca)
}

/// Richardson extrapolation of values at mesh sizes `h` and `h/2` for an `h^2` error.
fn h2_extrapolation(coarse: f64, fine: f64) -> f64 {
    (4.0 * fine - coarse) / 3.0
}

/// Relative change of D over the last 10 % of the run (three samples of twenty).
fn late_drift(r: &CaseResult) -> f64 {
    let h = &r.d_history;
    h[h.len() - 1].1 / h[h.len() - 3].1 - 1.0
}

/// The neo-Hookean law of the solver is the one of the references, with the moduli
/// the capillary numbers assume: on one triangle stretched by `(l1, l2)`,
/// `E = A0 Gs/2 (I1 - 1 + 1/(I2 + 1))` (Barthes-Biesel, Diaz & Dhenin, JFM 460, 211 (2002)),
/// the principal tension `T1 = (1/l2) dw/dl1` equals Pozrikidis' (JFM 297, 123 (1995);
/// Ramanujan & Pozrikidis 1998) `Es/(3 l1 l2) (l1^2 - 1/(l1 l2)^2)` with `Es = 3 Gs`,
/// and the small-strain moduli are `(Gs, 3 Gs)`. Tolerances: rounding (1e-12) and the
/// central difference (step 1e-5: truncation ~1e-10 relative).
#[test]
fn neo_hookean_law_is_the_references_law() {
    const GS: f64 = 5e-6;
    let reference = Mesh {
        vertices: vec![Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.3, 0.0, 0.0), Vector3::new(0.4, 0.9, 0.0)],
        triangles: vec![[0, 1, 2]],
    };
    let law = Skalak::neo_hookean(&reference, GS).unwrap();
    assert_eq!(law.small_strain_moduli(), (GS, 3.0 * GS));
    let a0 = 0.5 * 1.3 * 0.9 * UM * UM; // m^2
    let energy = |l1: f64, l2: f64| {
        let f = Matrix3::from_diagonal(&Vector3::new(l1, l2, 1.0));
        let m = Mesh { vertices: reference.vertices.iter().map(|p| f * p).collect(), triangles: reference.triangles.clone() };
        law.energy(&m)
    };
    for (l1, l2) in [(1.6, 0.85), (1.2, 1.1), (0.9, 1.4)] {
        let (i1, i2) = (l1 * l1 + l2 * l2 - 2.0, l1 * l1 * l2 * l2 - 1.0);
        let w_bb = GS / 2.0 * (i1 - 1.0 + 1.0 / (i2 + 1.0));
        assert!((energy(l1, l2) / a0 - w_bb).abs() < 1e-12 * w_bb, "energy at ({l1}, {l2})");
        let d = 1e-5;
        let dw_dl1 = (energy(l1 + d, l2) - energy(l1 - d, l2)) / (2.0 * d * a0);
        let t1 = dw_dl1 / l2;
        let es = 3.0 * GS;
        let t1_pozrikidis = es / (3.0 * l1 * l2) * (l1 * l1 - 1.0 / (l1 * l2).powi(2));
        assert!((t1 / t1_pozrikidis - 1.0).abs() < 1e-8, "T1 at ({l1}, {l2}): {t1} vs {t1_pozrikidis}");
    }
}

/// Small-deformation theory, the 2 % target: at Ca = 0.01 (relative O(Ca^2)
/// correction -0.06 %, see the validation module) the steady D of the 512-triangle capsule is
/// `25/12 Ca` within 2 % (measured -1.4 %; -0.3 % at 2048 triangles, -0.03 %
/// at 8192, `small_deformation_convergence_study`), and steady (the last
/// 10 % of 20 relaxation times change D by < 0.1 %).
#[test]
fn neo_hookean_capsule_matches_small_deformation_theory() {
    let r = run_case(Case::NeoHookeanCapsule { ca: 0.01, lambda: 1.0 }, 3, "bs23", 4e-5, 20.0).unwrap();
    eprintln!("NH Ca 0.01, 512 tri: D = {:.5}, 25/12 Ca = {:.5}, error {:+.2} %", r.d, r.d_ref, 100.0 * r.relative_error());
    assert!(r.relative_error().abs() < 0.02, "{}", r.relative_error());
    assert!(late_drift(&r).abs() < 1e-3, "{}", late_drift(&r));
}

/// Moderate Ca at 512 triangles (1-2 s), Ca = 0.3: the cross-section `D12` of
/// Lac et al. 2004 agrees with the equivalent-ellipsoid D within 1 % (the shape is
/// nearly ellipsoidal at this Ca; not at Ca = 0.15, where they differ by 1.4 %),
/// D is steady, and D lies within 4 % of Ramanujan & Pozrikidis (1998): NOT the
/// 2 % target. Measured: D = 0.3922 (+1.9 %); the mesh-converged D is 0.3979
/// (+3.3 %), above R&P by more than the 2 % target at Ca = 0.3 and 0.6; the
/// tolerance is the converged offset plus the 512-triangle mesh error (-1.4 %)
/// with margin, and documents the disagreement rather than hiding it.
#[test]
fn neo_hookean_capsule_near_published_deformation_at_coarse_resolution() {
    let r = run_case(Case::NeoHookeanCapsule { ca: 0.3, lambda: 1.0 }, 3, "bs23", 4e-5, relaxations_to_rate_t_8(0.3)).unwrap();
    eprintln!("NH Ca 0.3, 512 tri: D = {:.4}, Ramanujan & Pozrikidis {:.3}, {:+.2} %", r.d, r.d_ref, 100.0 * r.relative_error());
    assert!(r.relative_error().abs() < 0.04, "{}", r.relative_error());
    assert!(late_drift(&r).abs() < 2e-3, "{}", late_drift(&r));
    let d12 = profile_deformation(&r.vertices, &r.triangles, &Vector3::y());
    assert!((d12 / r.d - 1.0).abs() < 0.01, "{d12} vs {}", r.d);
}

/// Convergence to small-deformation theory: Ca = 0.01 at 512, 2048 and 8192
/// triangles; the error falls as h^2 (ratio of successive differences 3.9) and the
/// extrapolated D is `25/12 Ca` within 0.5 % (the O(Ca^2) relative correction is
/// -0.06 %, see the validation module; measured +0.07 %). 15 min on the shared machine (load ~8).
#[test]
#[ignore]
fn small_deformation_convergence_study() {
    let case = Case::NeoHookeanCapsule { ca: 0.01, lambda: 1.0 };
    let mut ds = Vec::new();
    for level in [3, 4, 5] {
        let t0 = std::time::Instant::now();
        let r = run_case(case, level, "bs23", 4e-5, 20.0).unwrap();
        eprintln!(
            "Ca 0.01, {} tri: D = {:.6}, error {:+.3} %, late drift {:+.1e}, wall {:.0} s",
            8 * 4usize.pow(level),
            r.d,
            100.0 * r.relative_error(),
            late_drift(&r),
            t0.elapsed().as_secs_f64()
        );
        assert!(late_drift(&r).abs() < 1e-3);
        ds.push((r.d, r.d_ref));
    }
    let ext = h2_extrapolation(ds[1].0, ds[2].0);
    eprintln!("h^2 extrapolation: D = {ext:.6}, error {:+.3} %", 100.0 * (ext / ds[2].1 - 1.0));
    assert!((ext / ds[2].1 - 1.0).abs() < 5e-3);
}

/// Moderate Ca: Ca = 0.15, 0.3, 0.6 at 512, 2048 and 8192 triangles, read at
/// `rate t = 8`; prints D (ellipsoid and cross-section), the h^2 extrapolation and
/// the difference from Ramanujan & Pozrikidis 1998 (+3.3 % at Ca = 0.3, +4.6 % at
/// 0.6: above the 2 % target; printed, not asserted; see the validation module).
/// Asserts what the study establishes:
/// - Ca = 0.3 and 0.6: the discretisation error converges as h^2 (ratio of
///   successive differences 3-5.5, measured 4.7 and 4.5), so the extrapolated D is
///   known to ~0.1 %;
/// - Ca = 0.15: no mesh-converged steady D. The 8192-triangle membrane wrinkles
///   (the buckling under compressive tension that Lac et al. 2004 report below a
///   critical Ca for this law): its cross-section `D12` falls more than 2 % below
///   the ellipsoid D (measured 3.7 %; 1.2-1.4 % on the coarser meshes, which do
///   not resolve the wrinkles) and D is not monotone in the mesh size.
///
/// D is steady to 0.3 % over the last 10 % of every run. 25 min on the shared machine (load ~8).
#[test]
#[ignore]
fn moderate_ca_convergence_study() {
    for (ca, d_rp) in RAMANUJAN_POZRIKIDIS_1998_NH {
        let case = Case::NeoHookeanCapsule { ca, lambda: 1.0 };
        let mut ds = Vec::new();
        let mut d12_finest = 0.0;
        for level in [3, 4, 5] {
            let t0 = std::time::Instant::now();
            let r = run_case(case, level, "bs23", 4e-5, relaxations_to_rate_t_8(ca)).unwrap();
            let d12 = profile_deformation(&r.vertices, &r.triangles, &Vector3::y());
            eprintln!(
                "Ca {ca}, {} tri: D = {:.4} (cross-section D12 {d12:.4}), R&P {d_rp:.3} ({:+.2} %), late drift {:+.1e}, angle {:.1} deg, steps {}, wall {:.0} s",
                8 * 4usize.pow(level),
                r.d,
                100.0 * (r.d / d_rp - 1.0),
                late_drift(&r),
                r.angle_rad.to_degrees(),
                r.summary.accepted,
                t0.elapsed().as_secs_f64()
            );
            assert!(late_drift(&r).abs() < 3e-3);
            ds.push(r.d);
            d12_finest = d12;
        }
        let ratio = (ds[1] - ds[0]) / (ds[2] - ds[1]);
        let ext = h2_extrapolation(ds[1], ds[2]);
        eprintln!("Ca {ca}: h^2 extrapolation D = {ext:.4} (ratio of differences {ratio:.2}), R&P {d_rp:.3}: {:+.2} %", 100.0 * (ext / d_rp - 1.0));
        if ca < 0.2 {
            assert!(d12_finest / ds[2] < 0.98, "Ca {ca}: no wrinkling at 8192 triangles (D12 {d12_finest} vs D {})", ds[2]);
        } else {
            assert!((3.0..5.5).contains(&ratio), "Ca {ca}: mesh convergence ratio {ratio}");
        }
    }
}
