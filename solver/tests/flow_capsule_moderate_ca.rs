//! Capsule in simple shear at moderate capillary number: steady Taylor deformation of a neo-Hookean capsule against Ramanujan & Pozrikidis (1998).
//!
//! Reference (see `rbc_solver::integrate::validation`): neo-Hookean membrane,
//! lambda = 1, initially spherical, `Ca = mu rate a / Gs`; steady `D` of the
//! equivalent ellipsoid: 0.262 (Ca = 0.15), 0.385 (0.3), 0.502 (0.6), read
//! off their figure of D(t) (reading uncertainty ~ +-0.004, i.e. ~1 %).
//!
//! The full study (512 and 2048 triangles, Ca = 0.15, 0.3, 0.6; ~40 min on the
//! shared 2-core machine):
//! `nice -n 10 cargo test -p rbc-solver --test flow_capsule_moderate_ca -- --ignored --nocapture`

use nalgebra::Vector3;
use rbc_solver::integrate::validation::{profile_deformation, run_case, Case};

/// Run length in relaxation times `mu a (1 + lambda)/Gs`: `rate t = 2 Ca x relaxations`;
/// Ramanujan & Pozrikidis' curves are flat (within 1 %) from `rate t ~ 3` on.
fn relaxations(ca: f64) -> f64 {
    (8.0 / (2.0 * ca)).max(10.0)
}

#[test]
#[ignore]
fn neo_hookean_capsule_moderate_ca_study() {
    let cas: Vec<f64> = std::env::var("CAS").map(|s| s.split(",").map(|v| v.parse().unwrap()).collect()).unwrap_or(vec![0.3, 0.6, 0.15]);
    for ca in cas {
        let case = Case::NeoHookeanCapsule { ca, lambda: 1.0 };
        let mut ds = Vec::new();
        for level in [3, 4] {
            let t0 = std::time::Instant::now();
            let r = run_case(case, level, "bs23", 4e-5, relaxations(ca)).unwrap();
            let h = &r.d_history;
            let drift = h[h.len() - 1].1 / h[h.len() - 3].1 - 1.0;
            eprintln!(
                "Ca {ca} level {level} ({} tri): D = {:.4} (profile D12 {:.4}), published {:.3}, error {:+.2} %, last-10%-drift {drift:+.1e}, angle {:.1} deg, steps {} (rejected {}), wall {:.0} s",
                8 * 4usize.pow(level),
                r.d,
                profile_deformation(&r.vertices, &r.triangles, &Vector3::y()),
                r.d_ref,
                100.0 * r.relative_error(),
                r.angle_rad.to_degrees(),
                r.summary.accepted,
                r.summary.rejected,
                t0.elapsed().as_secs_f64()
            );
            ds.push((r.d, r.d_ref));
        }
        let ext = (4.0 * ds[1].0 - ds[0].0) / 3.0;
        eprintln!("Ca {ca}: h^2 extrapolation D = {ext:.4}, error {:+.2} %", 100.0 * (ext / ds[1].1 - 1.0));
        // measured (2048 triangles): +3.0 %, +3.6 %, +3.1 % at Ca = 0.3, 0.6, 0.15
        assert!((ds[1].0 / ds[1].1 - 1.0).abs() < 0.04);
    }
}

/// Fast check at 512 triangles (1-2 s each), Ca = 0.3: D = 0.3922 measured, published 0.385.
/// Tolerance 4 %: the 512-triangle mesh error is -1.5 % (against the h^2
/// extrapolation of 512 and 2048 triangles, D = 0.398) and the converged D lies
/// +3.4 % above Ramanujan & Pozrikidis' value (whose reading uncertainty is ~1 %;
/// Doddi & Bagchi 2008 give 0.392 for the same case, +1.8 % above it).
/// Also the small-Ca limit of the same law: D = 25/12 Ca within 2 % at Ca = 0.01
/// (both neo-Hookean and Skalak C = 1 have `K = 3 Gs`).
#[test]
fn neo_hookean_capsule_matches_published_deformation_at_coarse_resolution() {
    let r = run_case(Case::NeoHookeanCapsule { ca: 0.3, lambda: 1.0 }, 3, "bs23", 4e-5, relaxations(0.3)).unwrap();
    eprintln!("NH Ca 0.3, 512 tri: D = {:.4}, published {:.3}, error {:+.2} %", r.d, r.d_ref, 100.0 * r.relative_error());
    assert!(r.relative_error().abs() < 0.04, "{}", r.relative_error());
    // steady: the last two samples agree to 0.5 %
    let h = &r.d_history;
    assert!((h[h.len() - 1].1 / h[h.len() - 2].1 - 1.0).abs() < 5e-3);
    // the profile (cross-section) D12 agrees with the equivalent-ellipsoid D (nearly ellipsoidal shape)
    let d12 = profile_deformation(&r.vertices, &r.triangles, &Vector3::y());
    assert!((d12 / r.d - 1.0).abs() < 0.01, "{d12} vs {}", r.d);
    let small = run_case(Case::NeoHookeanCapsule { ca: 0.01, lambda: 1.0 }, 3, "bs23", 4e-5, 30.0).unwrap();
    eprintln!("NH Ca 0.01, 512 tri: D = {:.5}, 25/12 Ca = {:.5}", small.d, small.d_ref);
    assert!(small.relative_error().abs() < 0.02, "{}", small.relative_error());
}
