//! Transient D(t) of the neo-Hookean capsule in shear (lambda = 1, Ca = 0.3 and 0.6) against digitised published transients, with and without the volume correction.
//!
//! The study that asks whether our +3.3 % (Ca = 0.3) / +4.6 % (0.6) offset in the
//! steady D from Ramanujan & Pozrikidis (1998), Doddi & Bagchi (2008) and Huet's
//! Basilisk code is there from the first instants (a time-scale or modulus
//! error) or grows with the strain (nonlinear elasticity, quadrature). Reference
//! points: the digitised curves of D. Huet's Basilisk sandbox
//! (`sandbox/huet/tests/lagrangian_caps/data/nh_shear_3d/`, files
//! `pozrikidis1998_ca_*.csv`, `bagchi_ca*.csv`, `high_res_ca*.txt`; their `Ca` is
//! `mu rate a / Es = Ca/3`), times in units of `1/rate`.
//!
//! Measured (2048 triangles unless said; the whole file ~6 min on the 2-core
//! machine at load ~2-5, most of it the two 8192-triangle runs):
//! - early transient: ours within 0.3-0.8 % (Ca = 0.6) and 0.4-1.5 % (0.3) of
//!   Huet's up to `rate t = 1`, so no time-scale, shear-rate or modulus error;
//!   the offset appears from `rate t ~ 1.5` (D ~ 0.45) and grows to +5.4 % at
//!   `rate t = 3`, settling at +5.1 % (Ca = 0.6; node measure, as Huet's);
//!   R&P's D(t) lies 2-4 % below ours and 1-2 % below Huet's from the start;
//! - over Ca (D of the node distances, Huet's measure): -3.1 % (Ca = 0.075; the
//!   ellipsoid D 0.1516 equals his 0.1517), +1.4 % (0.15), +3.7 % (0.3),
//!   +5.1 % (0.6); inclination 34.4/30.8/25.1/19.7 deg against his
//!   34.6/30.3/25.2/18.4: the offset grows with the deformation, the angle agrees;
//! - our D is steady from `rate t = 8` to 16 (0.5210 -> 0.5206, 0.3966 -> 0.3966);
//! - volume correction: without it the 2048-triangle capsule loses 0.3 % of its
//!   volume by `rate t = 8` and D is 0.15 % larger (512 triangles: 1.6 %, 0.8 %;
//!   8192: 0.05 %, 0.03 %): the correction is not what sets D;
//! - singular quadrature: Duffy (3, 24) instead of (1, 10) changes D by < 1e-5.
//!
//! Run: `nice -n 10 cargo test -p rbc-solver --test capsule_transient -- --ignored --nocapture`

use nalgebra::Vector3;
use rbc_schema::scene::Scene;
use rbc_solver::mesh::slices;
use rbc_solver::viscosity::ViscosityContrast;
use rbc_solver::bim::{BimOptions, FreeSpaceStokes};
use rbc_solver::validation::{profile_deformation, Case, GS_N_M, MU_PA_S};
use rbc_solver::scene::Operator;
use rbc_solver::membrane::skalak::Skalak;
use rbc_solver::membrane::Membrane;
use rbc_solver::run::Recorder;
use std::path::Path;

/// Huet's measure: largest and smallest vertex distance from the centroid.
fn node_deformation(x: &[Vector3<f64>], triangles: &[[usize; 3]]) -> f64 {
    let c = slices::centroid(x, triangles);
    let (mut l, mut b) = (0.0f64, f64::INFINITY);
    for p in x {
        let r = (p - c).norm();
        l = l.max(r);
        b = b.min(r);
    }
    (l - b) / (l + b)
}

struct Transient {
    /// `(rate t, D ellipsoid, D12 cross-section, D nodes, V/V0)`
    rows: Vec<(f64, f64, f64, f64, f64)>,
    /// Inclination of the long axis at the end (rad).
    angle_rad: f64,
}

fn run(ca: f64, level: u32, volume_correction: bool, rate_t_end: f64, samples: usize) -> Transient {
    run_with(ca, level, volume_correction, rate_t_end, samples, BimOptions::default())
}

/// As [`run`], with the boundary-integral options `bim` (quadrature).
fn run_with(ca: f64, level: u32, volume_correction: bool, rate_t_end: f64, samples: usize, bim: BimOptions) -> Transient {
    let case = Case::NeoHookeanCapsule { ca, lambda: 1.0 };
    let rate = case.shear_rate();
    let t_end = rate_t_end / rate;
    let mut text = case.scene_toml(level, "bs23", 4e-5, t_end);
    // finer output than the validation runs, and the volume correction switch
    text = text.replace(&format!("output_interval_s = {:e}", t_end / 20.0), &format!("output_interval_s = {:e}", t_end / samples as f64));
    text = text.replace("kinematics = \"material\"\n", &format!("kinematics = \"material\"\nvolume_correction = {volume_correction}\n"));
    let scene = Scene::parse(&text, Path::new("transient.toml")).unwrap();
    let mut built = rbc_solver::scene::build(&scene).unwrap();
    built.run.checks.max_area_change = 1.0;
    built.membrane = Membrane::new().with(Skalak::neo_hookean(&built.mesh, GS_N_M).unwrap());
    match &mut built.stokes {
        Operator::FreeSpace(fs) => fs.solver = FreeSpaceStokes::new(MU_PA_S, ViscosityContrast::MATCHED, bim),
        Operator::Channel(_) => unreachable!("the validation scene is free space"),
    }
    let mut rec = Recorder::default();
    built.run(&mut rec).unwrap();
    let tris = &built.mesh.triangles;
    let v0 = slices::volume(&built.mesh.vertices, tris);
    let rows = rec
        .times_s
        .iter()
        .zip(&rec.vertices)
        .map(|(&t, x)| {
            (
                t * rate,
                slices::taylor_deformation(x, tris, &Vector3::y()).0,
                profile_deformation(x, tris, &Vector3::y()),
                node_deformation(x, tris),
                slices::volume(x, tris) / v0,
            )
        })
        .collect();
    let angle_rad = slices::taylor_deformation(rec.vertices.last().unwrap(), tris, &Vector3::y()).1;
    Transient { rows, angle_rad }
}

/// Digitised reference transients `(rate t, D)`, see the module documentation.
/// Ca = 0.6 (their Ca_E = 0.2) and 0.3 (0.1).
const RP_06: [(f64, f64); 9] = [(0.256, 0.117), (0.505, 0.219), (1.040, 0.370), (1.533, 0.444), (2.106, 0.486), (3.109, 0.507), (4.111, 0.506), (6.051, 0.501), (7.992, 0.5005)];
const HUET_06: [(f64, f64); 10] = [(0.25, 0.1194), (0.5, 0.2229), (0.75, 0.3056), (1.0, 0.3686), (1.5, 0.4451), (2.0, 0.4798), (3.0, 0.4970), (4.0, 0.4962), (6.0, 0.4957), (8.0, 0.4959)];
const RP_03: [(f64, f64); 8] = [(0.239, 0.1046), (0.519, 0.2025), (1.019, 0.3081), (1.585, 0.3610), (2.015, 0.3769), (3.017, 0.3857), (5.022, 0.3851), (7.971, 0.3845)];
const HUET_03: [(f64, f64); 8] = [(0.25, 0.1149), (0.5, 0.2045), (0.75, 0.2689), (1.0, 0.3123), (1.5, 0.3585), (2.0, 0.3752), (3.0, 0.3812), (5.0, 0.3811)];

fn interp(rows: &[(f64, f64, f64, f64, f64)], t: f64, col: fn(&(f64, f64, f64, f64, f64)) -> f64) -> f64 {
    let k = rows.iter().position(|r| r.0 >= t).unwrap_or(rows.len() - 1).max(1);
    let (a, b) = (&rows[k - 1], &rows[k]);
    let s = (t - a.0) / (b.0 - a.0);
    col(a) + s * (col(b) - col(a))
}

/// Prints ours against `refs`; returns the largest `|ours/ref - 1|` at `rate t <= 1`.
fn compare(name: &str, tr: &Transient, refs: &[(f64, f64)], col: fn(&(f64, f64, f64, f64, f64)) -> f64) -> f64 {
    let mut early = 0.0f64;
    for &(t, d) in refs {
        let ours = interp(&tr.rows, t, col);
        eprintln!("  {name:>5} rate t {t:5.2}: ref {d:.4}, ours {ours:.4} ({:+.1} %)", 100.0 * (ours / d - 1.0));
        if t <= 1.0 {
            early = early.max((ours / d - 1.0).abs());
        }
    }
    early
}

/// Transients at 512 and 2048 triangles, Ca = 0.6 and 0.3: prints our D (three
/// measures) against the references at their digitised times, and the run
/// without the volume correction (its volume drift and D). Asserts what the
/// study established: the early deformation follows the affine straining
/// `D ~ rate t / 2` (membrane unstressed at t = 0), and at 2048 triangles our
/// transient lies within 2 % of Huet's up to `rate t = 1` (measured 0.3-0.8 %
/// at Ca = 0.6, 0.4-1.5 % at 0.3), while at `rate t = 8` it lies 4-5 % above.
#[test]
#[ignore]
fn transient_against_published_curves() {
    for (ca, rp, huet) in [(0.6, &RP_06[..], &HUET_06[..]), (0.3, &RP_03[..], &HUET_03[..])] {
        for level in [3u32, 4] {
            let t0 = std::time::Instant::now();
            let tr = run(ca, level, true, 8.0, 64);
            eprintln!("Ca {ca}, {} triangles ({:.0} s):", 8 * 4usize.pow(level), t0.elapsed().as_secs_f64());
            compare("R&P", &tr, rp, |r| r.1);
            let early = compare("Huet", &tr, huet, |r| r.3);
            if level == 4 {
                assert!(early < 0.02, "Ca {ca}: early transient {early} from Huet's");
            }
            eprintln!("  (Huet vs our ellipsoid D, D12 at 8: {:.4} {:.4})", interp(&tr.rows, 8.0, |r| r.1), interp(&tr.rows, 8.0, |r| r.2));
            let d_early = interp(&tr.rows, 0.125, |r| r.1);
            assert!((d_early / 0.0625 - 1.0).abs() < 0.1, "early D {d_early}");
            if level == 3 {
                let t0 = std::time::Instant::now();
                let nv = run(ca, level, false, 8.0, 16);
                let last = nv.rows.last().unwrap();
                let with = tr.rows.last().unwrap();
                eprintln!(
                    "  no volume correction ({:.0} s): V/V0 - 1 at rate t 8 = {:+.2e}, D {:.4} vs {:.4} with correction ({:+.2} %)",
                    t0.elapsed().as_secs_f64(),
                    last.4 - 1.0,
                    last.1,
                    with.1,
                    100.0 * (last.1 / with.1 - 1.0)
                );
            }
        }
    }
}

/// Huet's Basilisk runs (high resolution; `high_res_ca*.txt`, columns t, r_min,
/// r_max, D, angle in rad) at the end of the run (`rate t = 8`; 6.3 at his
/// Ca_E = 0.05, 5.5 at 0.1): `(our Ca, D nodes, angle rad)`.
const HUET_END: [(f64, f64, f64); 4] = [(0.075, 0.1517, 0.6031), (0.15, 0.2626, 0.5281), (0.3, 0.3817, 0.4399), (0.6, 0.4959, 0.3219)];

/// Steady D and inclination against Huet's over Ca (2048 triangles, rate t = 8),
/// and the effect of the volume correction at 2048 and 8192 triangles, Ca = 0.6.
/// Asserts the inclination within 1.5 deg of Huet's (measured 0.1-1.3 deg) and a
/// volume-correction effect on D below 0.5 % (measured +0.15 % at 2048 triangles,
/// +0.03 % at 8192).
#[test]
#[ignore]
fn offset_and_angle_over_ca() {
    for (ca, d_huet, angle_huet) in HUET_END {
        let t0 = std::time::Instant::now();
        let tr = run(ca, 4, true, 8.0, 32);
        let last = tr.rows.last().unwrap();
        eprintln!(
            "Ca {ca}: D ellipsoid {:.4}, D nodes {:.4} (Huet {d_huet:.4}, {:+.1} %), angle {:.1} deg (Huet {:.1}), wall {:.0} s",
            last.1,
            last.3,
            100.0 * (last.3 / d_huet - 1.0),
            tr.angle_rad.to_degrees(),
            angle_huet.to_degrees(),
            t0.elapsed().as_secs_f64()
        );
        assert!((tr.angle_rad - angle_huet).abs().to_degrees() < 1.5, "Ca {ca}: angle");
    }
    for level in [4u32, 5] {
        let with = run(0.6, level, true, 8.0, 16);
        let without = run(0.6, level, false, 8.0, 16);
        let (a, b) = (with.rows.last().unwrap(), without.rows.last().unwrap());
        eprintln!(
            "Ca 0.6, {} tri: without volume correction V/V0 - 1 = {:+.2e}, D {:.4} vs {:.4} ({:+.2} %)",
            8 * 4usize.pow(level),
            b.4 - 1.0,
            b.1,
            a.1,
            100.0 * (b.1 / a.1 - 1.0)
        );
        assert!((b.1 / a.1 - 1.0).abs() < 5e-3, "volume correction changes D by more than 0.5 %");
    }
}

/// Whether our D is still falling at `rate t = 8` (where the references are read):
/// Ca = 0.3 and 0.6, 2048 triangles, run to `rate t = 16`. Measured (module docs): steady,
/// D 0.5210 -> 0.5206 (Ca = 0.6) and 0.3966 -> 0.3966 (0.3) from `rate t = 8` to 16; asserted
/// (each D to 1e-3, the change from 8 to 16 below 1e-3).
/// `nice -n 10 cargo nextest run -p rbc-solver --run-ignored only --no-capture -E 'test(long_time_decay)'`
#[test]
#[ignore = "study: D to rate t = 16 at 2048 triangles, asserted"]
fn long_time_decay() {
    for (ca, d8, d16) in [(0.6, 0.5210, 0.5206), (0.3, 0.3966, 0.3966)] {
        let tr = run(ca, 4, true, 16.0, 16);
        let line: Vec<String> = tr.rows.iter().filter(|r| (r.0.round() - r.0).abs() < 1e-6 && r.0.round() as i64 % 2 == 0).map(|r| format!("{:.0}: {:.4}", r.0, r.1)).collect();
        eprintln!("Ca {ca}, 2048 tri, D at rate t = {}", line.join(", "));
        let at = |rate_t: f64| tr.rows.iter().find(|r| (r.0 - rate_t).abs() < 1e-6).unwrap_or_else(|| panic!("no sample at rate t = {rate_t}")).1;
        let (a, b) = (at(8.0), at(16.0));
        assert!((a - d8).abs() <= 1e-3 && (b - d16).abs() <= 1e-3, "Ca {ca}: D {a:.4} at rate t = 8, {b:.4} at 16; measured {d8}, {d16}");
        assert!((b - a).abs() <= 1e-3, "Ca {ca}: D still changing from rate t = 8 to 16: {a:.4} -> {b:.4}");
    }
}

/// Sensitivity of D (Ca = 0.6, 2048 triangles, rate t = 8) to the singular
/// quadrature: Duffy rule (1, 10) (default) against (3, 24); measured identical to
/// 5 digits, asserted within 1e-4.
#[test]
#[ignore]
fn quadrature_sensitivity() {
    let base = run(0.6, 4, true, 8.0, 8);
    let fine = run_with(0.6, 4, true, 8.0, 8, BimOptions { duffy_nodes: (3, 24), ..BimOptions::default() });
    let (a, b) = (base.rows.last().unwrap().1, fine.rows.last().unwrap().1);
    eprintln!("Ca 0.6, 2048 tri: D with Duffy (1, 10) {a:.5}, (3, 24) {b:.5} ({:+.3} %)", 100.0 * (b / a - 1.0));
    assert!((b / a - 1.0).abs() < 1e-4);
}
