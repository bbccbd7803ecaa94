//! Tests of Helfrich bending (Method C, quartic fit, fit + Galerkin): zero force on a sphere, sign of the force, convergence of H, K, Lap_s H and the force on spheroids and the discocyte.

use std::f64::consts::PI;

use nalgebra::{Matrix3, Vector3};
use rbc_solver::membrane::bending::{BendingMethod, Helfrich};
use rbc_solver::membrane::curvature::{
    cotangent_curvatures, fitted_curvatures, fitted_galerkin_curvatures, VertexCurvatures,
};
use rbc_solver::membrane::{nodal_forces, total_force_and_torque, MembraneLaw, UM};
use rbc_solver::mesh::shapes::AxisymmetricShape;
use rbc_solver::mesh::{self, Mesh};

/// Error norms of nodal values against exact ones: (max |e| / max |exact|,
/// RMS(e) / RMS(exact)), RMS weighted by the vertex areas.
fn norms(values: &[f64], exact: &[f64], areas: &[f64]) -> (f64, f64) {
    let max_exact = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let max_err = values
        .iter()
        .zip(exact)
        .fold(0.0f64, |m, (v, e)| m.max((v - e).abs()));
    let (mut se, mut sx) = (0.0, 0.0);
    for ((v, e), a) in values.iter().zip(exact).zip(areas) {
        se += a * (v - e).powi(2);
        sx += a * e * e;
    }
    (max_err / max_exact, (se / sx).sqrt())
}

struct Errors {
    h: (f64, f64),
    k: (f64, f64),
    lap: (f64, f64),
    force: (f64, f64),
    /// Weak error of the force: `|sum_i Df_i . g(x_i) A_i - int Df . g dA| / int |Df| |g| dA`
    /// for a smooth test field `g`: what an integral operator (the single layer) sees.
    weak: f64,
    /// Error of the Laplace single-layer potential of the force error,
    /// `S[e](x_i) = sum_{j != i} e_j A_j / |x_i - x_j| + e_i 2 sqrt(pi A_i)`
    /// (the last term: `1/r` over a disc of area `A_i`), max and mean over
    /// vertices, relative to `max_i S[|f|](x_i)`: a proxy for the velocity
    /// error a boundary integral solver would make (`G ~ 1/r`).
    single_layer: (f64, f64),
}

fn single_layer(mesh: &Mesh, areas: &[f64], e: &[f64]) -> Vec<f64> {
    let n = mesh.vertices.len();
    (0..n)
        .map(|i| {
            let mut s = e[i] * 2.0 * (PI * areas[i]).sqrt();
            for j in 0..n {
                if j != i {
                    s += e[j] * areas[j] / (mesh.vertices[i] - mesh.vertices[j]).norm();
                }
            }
            s
        })
        .collect()
}

/// A smooth test field without the shapes' symmetries (with them, or for a
/// constant or linear field, the exact integral vanishes: total force, and
/// scale invariance of the bending energy).
fn test_field(x: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(
        (0.7 * x.x + 0.3 * x.y + 0.2 * x.z + 0.4).cos(),
        (0.5 * x.z - 0.2 * x.x + 0.4 * x.y + 0.1).sin(),
        (0.3 * x.x * x.y + 0.5 * x.z + 0.2).cos(),
    )
}

/// `(int Df . g dA, int |Df| |g| dA)` for the exact normal force density
/// (per `2 kB`) of an axisymmetric shape: Gauss-Legendre in `t` (composite,
/// 200 panels x 4), trapezoid in `phi` (400 points, spectrally accurate).
fn exact_weak(shape: &AxisymmetricShape) -> (f64, f64) {
    const X: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const W: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    let (panels, nphi) = (200, 400);
    let ht = PI / panels as f64;
    let (mut s, mut m) = (0.0, 0.0);
    for p in 0..panels {
        for k in 0..4 {
            let t = (p as f64 + 0.5) * ht + 0.5 * ht * X[k];
            let cv = shape.curvatures(t);
            let fnorm = 2.0 * cv.mean * (cv.mean.powi(2) - cv.gaussian) + cv.laplacian_mean;
            let [r, z] = shape.profile_point(t);
            let da = r * shape.speed(t) * 0.5 * ht * W[k] * 2.0 * PI / nphi as f64;
            for j in 0..nphi {
                let phi = 2.0 * PI * j as f64 / nphi as f64;
                let x = Vector3::new(r * phi.cos(), r * phi.sin(), z);
                let n = Vector3::new(
                    cv.normal_rz[0] * phi.cos(),
                    cv.normal_rz[0] * phi.sin(),
                    cv.normal_rz[1],
                );
                let g = test_field(&x);
                s += fnorm * n.dot(&g) * da;
                m += fnorm.abs() * g.norm() * da;
            }
        }
    }
    (s, m)
}

/// Bending force per unit `2 kB`, normal component: `2 H (H^2 - K) + Lap_s H` (1/um^3).
fn errors(
    shape: &AxisymmetricShape,
    mesh: &Mesh,
    c: &VertexCurvatures,
    exact_weak: (f64, f64),
) -> Errors {
    let exact: Vec<_> = mesh
        .vertices
        .iter()
        .map(|x| shape.curvatures_at(x).0)
        .collect();
    let col = |f: &dyn Fn(usize) -> f64| (0..mesh.vertices.len()).map(f).collect::<Vec<f64>>();
    let fe = col(&|i| {
        2.0 * exact[i].mean * (exact[i].mean.powi(2) - exact[i].gaussian) + exact[i].laplacian_mean
    });
    let fd = col(&|i| 2.0 * c.mean[i] * (c.mean[i].powi(2) - c.gaussian[i]) + c.laplacian_mean[i]);
    Errors {
        h: norms(&c.mean, &col(&|i| exact[i].mean), &c.areas),
        k: norms(&c.gaussian, &col(&|i| exact[i].gaussian), &c.areas),
        lap: norms(
            &c.laplacian_mean,
            &col(&|i| exact[i].laplacian_mean),
            &c.areas,
        ),
        force: norms(&fd, &fe, &c.areas),
        single_layer: {
            let err: Vec<f64> = fd.iter().zip(&fe).map(|(a, b)| a - b).collect();
            let mag: Vec<f64> = fe.iter().map(|v| v.abs()).collect();
            let se = single_layer(mesh, &c.areas, &err);
            let sm = single_layer(mesh, &c.areas, &mag)
                .iter()
                .fold(0.0f64, |m, v| m.max(*v));
            let mx = se.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let mean = se.iter().map(|v| v.abs()).sum::<f64>() / se.len() as f64;
            (mx / sm, mean / sm)
        },
        weak: {
            let s: f64 = (0..mesh.vertices.len())
                .map(|i| fd[i] * c.normals[i].dot(&test_field(&mesh.vertices[i])) * c.areas[i])
                .sum();
            (s - exact_weak.0).abs() / exact_weak.1
        },
    }
}

fn order(e0: f64, e1: f64) -> f64 {
    (e0 / e1).log2()
}

fn study(
    shape: AxisymmetricShape,
    levels: std::ops::RangeInclusive<usize>,
    method: fn(&Mesh) -> VertexCurvatures,
    name: &str,
) -> Vec<Errors> {
    let weak = exact_weak(&shape);
    let errs: Vec<Errors> = levels
        .clone()
        .map(|l| {
            let m = shape.mesh(l);
            errors(&shape, &m, &method(&m), weak)
        })
        .collect();
    println!("{name} on {shape:?}: relative errors (max, L2) per level {levels:?}");
    for (name, pick) in [
        ("H", &(|e: &Errors| e.h) as &dyn Fn(&Errors) -> (f64, f64)),
        ("K", &|e: &Errors| e.k),
        ("Lap H", &|e: &Errors| e.lap),
        ("force", &|e: &Errors| e.force),
    ] {
        let v: Vec<(f64, f64)> = errs.iter().map(pick).collect();
        let orders: Vec<String> = v
            .windows(2)
            .map(|w| format!("{:.2}/{:.2}", order(w[0].0, w[1].0), order(w[0].1, w[1].1)))
            .collect();
        println!(
            "  {name:6} max {:?}\n         L2  {:?}\n         orders (max/L2) {:?}",
            v.iter().map(|e| format!("{:.2e}", e.0)).collect::<Vec<_>>(),
            v.iter().map(|e| format!("{:.2e}", e.1)).collect::<Vec<_>>(),
            orders
        );
    }
    let w: Vec<String> = errs.iter().map(|e| format!("{:.2e}", e.weak)).collect();
    let o: Vec<String> = errs
        .windows(2)
        .map(|p| format!("{:.2}", order(p[0].weak, p[1].weak)))
        .collect();
    println!("  weak force error {w:?}, orders {o:?}");
    let w: Vec<String> = errs
        .iter()
        .map(|e| format!("{:.2e}/{:.2e}", e.single_layer.0, e.single_layer.1))
        .collect();
    let o: Vec<String> = errs
        .windows(2)
        .map(|p| {
            format!(
                "{:.2}/{:.2}",
                order(p[0].single_layer.0, p[1].single_layer.0),
                order(p[0].single_layer.1, p[1].single_layer.1)
            )
        })
        .collect();
    println!("  single-layer potential of the force error (max/mean) {w:?}, orders {o:?}");
    errs
}

const OBLATE: AxisymmetricShape = AxisymmetricShape::Spheroid { a: 4.0, c: 2.0 };
const PROLATE: AxisymmetricShape = AxisymmetricShape::Spheroid { a: 3.0, c: 4.5 };

/// The quartic fit converges at every vertex: max and L2 errors of `H`, `K`
/// (order ~3), `Lap_s H` and the force (order > 1 in max, > 1.4 in L2) between
/// levels 3, 4, 5 (512, 2048, 8192 triangles), on two spheroids and the
/// discocyte; the L2 force error at the paper's 2048 triangles is bounded by
/// the value measured when this test was written (+~20%).
#[test]
fn quartic_fit_converges_at_every_vertex() {
    for (shape, force_l2_at_2048) in [
        (OBLATE, 0.1),
        (PROLATE, 0.22),
        (AxisymmetricShape::evans_fung_rbc(), 0.17),
    ] {
        let e = study(shape, 3..=5, fitted_curvatures, "quartic fit");
        for w in e.windows(2) {
            assert!(
                order(w[0].h.0, w[1].h.0) > 2.5 && order(w[0].k.0, w[1].k.0) > 2.5,
                "{shape:?}"
            );
            assert!(
                order(w[0].force.0, w[1].force.0) > 1.0 && order(w[0].force.1, w[1].force.1) > 1.4,
                "{shape:?}"
            );
            assert!(
                order(w[0].lap.0, w[1].lap.0) > 1.0 && order(w[0].lap.1, w[1].lap.1) > 1.4,
                "{shape:?}"
            );
            assert!(
                order(w[0].single_layer.0, w[1].single_layer.0) > 1.8,
                "{shape:?}"
            );
            assert!(order(w[0].weak, w[1].weak) > 1.8, "{shape:?}");
        }
        assert!(
            e[1].force.1 < force_l2_at_2048,
            "{shape:?}: L2 force error at 2048 triangles {}",
            e[1].force.1
        );
    }
}

/// Method C (the paper's) on the same meshes, reported honestly: `H` and `K`
/// converge in L2 (order ~1) but not in max (the valence-4 vertices keep an
/// O(1) error), and `Lap_s H` (hence the force) does not converge at all:
/// its max error grows ~4x per level and its L2 error grows from level 4 on.
/// Integrated against smooth functions (weak error) it converges (~1.5), and
/// the mean single-layer potential of its error falls (~order 1) while the
/// max rises. This pins the known behaviour (Guckenberger et al. 2016: no
/// node-wise method converges everywhere on irregular meshes).
#[test]
fn method_c_does_not_converge_for_laplacian_of_h() {
    for shape in [OBLATE, PROLATE, AxisymmetricShape::evans_fung_rbc()] {
        let e = study(shape, 3..=5, cotangent_curvatures, "cotangent (Method C)");
        assert!(
            e[2].h.1 < e[0].h.1 && e[2].k.1 < e[0].k.1,
            "H, K converge in L2"
        );
        assert!(e[2].lap.0 > 3.0 * e[1].lap.0, "Lap H max error grows");
        assert!(e[2].force.1 > e[1].force.1, "force L2 error grows");
        assert!(
            e[2].weak < e[0].weak && e[2].single_layer.1 < e[0].single_layer.1,
            "integrated errors fall"
        );
    }
}

/// Fits for `H`, `K`, `n` and the Galerkin Laplacian for `Lap_s H`: the L2
/// force error and the integrated errors converge (weak and mean single
/// layer at order ~2), the max force error does not (O(1) at the valence-4
/// vertices and their neighbours).
#[test]
fn fit_galerkin_converges_in_l2_not_in_max() {
    for shape in [OBLATE, PROLATE, AxisymmetricShape::evans_fung_rbc()] {
        let e = study(
            shape,
            3..=5,
            fitted_galerkin_curvatures,
            "quartic fit + Galerkin Laplacian",
        );
        for w in e.windows(2) {
            assert!(order(w[0].force.1, w[1].force.1) > 1.0, "{shape:?}");
            assert!(
                order(w[0].single_layer.1, w[1].single_layer.1) > 1.8
                    && order(w[0].weak, w[1].weak) > 1.8,
                "{shape:?}"
            );
        }
        assert!(e[2].force.0 > 0.5, "{shape:?}: max error stays O(1)");
    }
}

/// Full study, levels 2 to 6 (up to 32768 triangles), all three methods: the
/// tables quoted in `src/membrane/CONVERGENCE.md` and in `membrane::bending`.
/// The discocyte's rows of those tables are asserted ([`DISCOCYTE_TABLE`], each
/// number to half a unit of its last printed digit + 3 %). Run with
/// `cargo nextest run -p rbc-solver --run-ignored only --no-capture -E 'test(full_convergence_study)'`
/// (about a minute).
#[test]
#[ignore = "study: bending convergence to 32768 triangles, asserted on the discocyte"]
fn full_convergence_study() {
    for (method, name) in [
        (
            cotangent_curvatures as fn(&Mesh) -> VertexCurvatures,
            "cotangent (Method C)",
        ),
        (fitted_curvatures, "quartic fit"),
        (
            fitted_galerkin_curvatures,
            "quartic fit + Galerkin Laplacian",
        ),
    ] {
        for (i, shape) in [OBLATE, PROLATE, AxisymmetricShape::evans_fung_rbc()].into_iter().enumerate() {
            let e = study(shape, 2..=6, method, name);
            if i == 2 {
                check_discocyte_table(name, &e);
            }
        }
    }
}

/// The discocyte's rows of `src/membrane/CONVERGENCE.md` as printed there: per method, quantity
/// and level 2..=6 the (max, L2) relative error (`None`: not tabulated); then the weak error and
/// the single layer of the error (max, mean) at levels 4..=6.
#[allow(clippy::type_complexity)]
const DISCOCYTE_TABLE: [(&str, &[(&str, [Option<(&str, &str)>; 5])], [&str; 3], [(&str, &str); 3]); 3] = [
    (
        "cotangent (Method C)",
        &[
            ("H", [Some((".21", ".14")), Some((".10", ".060")), Some((".058", ".022")), Some((".061", ".0084")), Some((".063", ".0034"))]),
            ("Lap H", [Some(("1.1", "1.0")), Some((".66", ".64")), Some((".69", ".44")), Some(("2.7", ".54")), Some(("10.7", ".94"))]),
            ("force", [Some(("1.1", ".99")), Some((".71", ".66")), Some((".79", ".46")), Some(("3.1", ".58")), Some(("12.3", "1.0"))]),
        ],
        ["7.9e-4", "2.6e-4", "9.9e-5"],
        [(".039", ".0079"), (".068", ".0030"), (".13", ".0015")],
    ),
    (
        "quartic fit",
        &[
            ("H", [Some(("3.8", "1.8")), Some((".088", ".036")), Some(("5.4e-3", "2.6e-3")), Some(("7.7e-4", "2.3e-4")), Some(("1.0e-4", "2.1e-5"))]),
            ("Lap H", [None, Some((".94", ".57")), Some((".17", ".13")), Some((".063", ".036")), Some((".027", ".011"))]),
            ("force", [None, Some(("1.05", ".60")), Some((".19", ".14")), Some((".072", ".039")), Some((".031", ".012"))]),
        ],
        ["8.9e-3", "2.0e-3", "4.7e-4"],
        [(".093", ".081"), (".025", ".021"), (".0068", ".0055")],
    ),
    (
        "quartic fit + Galerkin Laplacian",
        &[("force", [None, Some(("1.4", ".68")), Some((".96", ".24")), Some((".96", ".089")), Some((".94", ".038"))])],
        ["1.9e-3", "4.5e-4", "1.1e-4"],
        [(".050", ".0049"), (".025", ".0011"), (".012", ".0003")],
    ),
];

/// Whether `found` rounds to `printed`: within half a unit of its last digit, plus 3 %.
fn matches_printed(found: f64, printed: &str) -> bool {
    let (mantissa, exponent) = printed.split_once('e').map_or((printed, 0), |(m, e)| (m, e.parse::<i32>().unwrap()));
    let decimals = mantissa.split_once('.').map_or(0, |(_, d)| d.len()) as i32;
    let value: f64 = printed.parse().unwrap();
    (found - value).abs() <= 0.5 * 10f64.powi(exponent - decimals) + 0.03 * value.abs()
}

/// Asserts the discocyte's errors `e` (levels 2..=6) of method `name` against [`DISCOCYTE_TABLE`].
fn check_discocyte_table(name: &str, e: &[Errors]) {
    let (_, rows, weak, single) = DISCOCYTE_TABLE.iter().find(|r| r.0 == name).expect("a tabulated method");
    let check = |what: String, found: f64, printed: &str| assert!(matches_printed(found, printed), "{name}, discocyte, {what}: {found:.3e}, CONVERGENCE.md {printed}");
    for (quantity, levels) in rows.iter() {
        for (l, cell) in levels.iter().enumerate() {
            let Some((max, l2)) = cell else { continue };
            let found = match *quantity {
                "H" => e[l].h,
                "Lap H" => e[l].lap,
                _ => e[l].force,
            };
            check(format!("{quantity} max, level {}", l + 2), found.0, max);
            check(format!("{quantity} L2, level {}", l + 2), found.1, l2);
        }
    }
    for k in 0..3 {
        check(format!("weak error, level {}", k + 4), e[k + 2].weak, weak[k]);
        check(format!("single layer max, level {}", k + 4), e[k + 2].single_layer.0, single[k].0);
        check(format!("single layer mean, level {}", k + 4), e[k + 2].single_layer.1, single[k].1);
    }
}

/// On a sphere `2 H (H^2 - K) + Lap_s H = 0` exactly. Discretely, the force
/// must vanish up to the method's error, measured against the natural scale
/// `2 kB H^3`: the fit's residual falls by more than 3x per level (Method C's
/// stalls at ~6%, printed for the record).
#[test]
fn bending_force_vanishes_on_a_sphere() {
    let r = 4.0;
    let kb = 3e-19;
    let scale = 2.0 * kb / (r * UM).powi(3);
    let mut fit_res = Vec::new();
    for level in 2..=5 {
        let s = mesh::sphere(level, r);
        for method in [BendingMethod::CotangentMethodC, BendingMethod::QuarticFit] {
            let f = Helfrich::with_method(kb, method).unwrap().force_density(&s);
            let res = f.iter().map(|v| v.norm()).fold(0.0, f64::max) / scale;
            println!("sphere level {level} {method:?}: max |Df| / (2 kB / R^3) = {res:.2e}");
            if method == BendingMethod::QuarticFit {
                fit_res.push(res);
            }
        }
    }
    assert!(fit_res[3] < 0.1, "{fit_res:?}");
    for w in fit_res.windows(2) {
        assert!(w[0] / w[1] > 3.0, "{fit_res:?}");
    }
}

/// The sign of the force formula, in the continuum: along the family of
/// spheroids with polar semi-axis `c + eps` (displacement `dx = (z / c) e_z`),
/// `dE/d(eps)` of the exact `E = 2 kB int H^2 dA` equals `-int Df . dx dA`
/// with the exact `Df = 2 kB [2H(H^2 - K) + Lap_s H] n`. Both integrals by the
/// midpoint rule in the profile parameter (4000 points; smooth integrands),
/// the energy derivative by central differences (step 1e-4: error ~1e-8).
#[test]
fn analytic_force_is_minus_energy_variation() {
    let (a, c) = (4.0, 2.5);
    let n = 4000;
    let energy = |c: f64| {
        let s = AxisymmetricShape::Spheroid { a, c };
        (0..n)
            .map(|k| {
                let t = (k as f64 + 0.5) * PI / n as f64;
                let speed = (a * a * t.cos().powi(2) + c * c * t.sin().powi(2)).sqrt();
                2.0 * s.curvatures(t).mean.powi(2) * 2.0 * PI * a * t.sin() * speed * PI / n as f64
            })
            .sum::<f64>()
    };
    let eps = 1e-4;
    let de = (energy(c + eps) - energy(c - eps)) / (2.0 * eps);
    let s = AxisymmetricShape::Spheroid { a, c };
    let work: f64 = (0..n)
        .map(|k| {
            let t = (k as f64 + 0.5) * PI / n as f64;
            let cv = s.curvatures(t);
            let speed = (a * a * t.cos().powi(2) + c * c * t.sin().powi(2)).sqrt();
            let f_normal =
                2.0 * (2.0 * cv.mean * (cv.mean.powi(2) - cv.gaussian) + cv.laplacian_mean);
            let dx_dot_n = t.cos() * cv.normal_rz[1]; // (z / c) e_z . n
            f_normal * dx_dot_n * 2.0 * PI * a * t.sin() * speed * PI / n as f64
        })
        .sum();
    println!("dE/dc = {de:.8}, -int Df.dx = {:.8}", -work);
    assert!((de + work).abs() < 1e-6 * de.abs(), "{de} vs {}", -work);
}

/// The same identity for the discrete force: `d/d(eps) E_h(x + eps dx)` against
/// `-sum_i Df_i . dx_i A_i` on a spheroid, for a smooth non-axisymmetric
/// displacement. Neither method is variational, so they agree only up to the
/// discretisation error: measured, and required to shrink under refinement
/// for the quartic fit.
#[test]
fn discrete_force_approximates_minus_energy_gradient() {
    let kb = 1e-19;
    let shape = OBLATE;
    let mut rel = Vec::new();
    for level in 3..=5 {
        let m = shape.mesh(level);
        let dx: Vec<Vector3<f64>> = m
            .vertices
            .iter()
            .map(|x| {
                Vector3::new(
                    0.1 * x.y * x.z,
                    0.05 * x.x * x.x,
                    0.2 * x.z + 0.03 * x.x * x.y,
                )
            })
            .collect();
        for method in [BendingMethod::CotangentMethodC, BendingMethod::QuarticFit] {
            let law = Helfrich::with_method(kb, method).unwrap();
            let shifted = |e: f64| Mesh {
                vertices: m.vertices.iter().zip(&dx).map(|(x, d)| x + d * e).collect(),
                triangles: m.triangles.clone(),
            };
            let h = 1e-5;
            let de = (law.energy(&shifted(h)) - law.energy(&shifted(-h))) / (2.0 * h * UM);
            let f = nodal_forces(&m, &law.force_density(&m));
            let work: f64 = f.iter().zip(&dx).map(|(fi, d)| fi.dot(d)).sum();
            let r = (de + work).abs() / de.abs();
            println!("level {level} {method:?}: dE/deps = {de:.4e} J/m, -sum F.dx = {:.4e}, relative difference {r:.2e}", -work);
            if method == BendingMethod::QuarticFit {
                rel.push(r);
            }
        }
    }
    assert!(rel[2] < 0.02 && rel[2] < rel[0], "{rel:?}");
}

/// Total force and torque of the bending force on a smoothly deformed,
/// asymmetric discocyte: not zero by construction (node-wise methods),
/// measured relative to the sum of nodal force magnitudes; for the fit they
/// must shrink under refinement and be below 1% at 8192 triangles.
#[test]
fn bending_total_force_and_torque_are_small() {
    let f3 = Matrix3::new(1.1, 0.2, 0.0, 0.0, 0.9, 0.1, 0.05, 0.0, 1.2);
    let mut res = Vec::new();
    for level in 3..=5 {
        let m0 = mesh::discocyte(level);
        let m = Mesh {
            vertices: m0
                .vertices
                .iter()
                .map(|x| {
                    f3 * x
                        + Vector3::new(
                            0.3 * (0.5 * x.x + 0.3).sin(),
                            0.02 * x.x * x.x,
                            0.1 * (0.4 * x.y).cos(),
                        )
                })
                .collect(),
            triangles: m0.triangles.clone(),
        };
        for method in [BendingMethod::CotangentMethodC, BendingMethod::QuarticFit] {
            let df = Helfrich::with_method(3e-19, method)
                .unwrap()
                .node_wise_force_density(&m);
            let mag: f64 = nodal_forces(&m, &df).iter().map(|v| v.norm()).sum();
            let (tf, tt) = total_force_and_torque(&m, &df, &m.centroid());
            let (rf, rt) = (tf.norm() / mag, tt.norm() / (4.0 * UM * mag));
            println!("level {level} {method:?}: |sum F| / sum |F| = {rf:.2e}, |torque| / (R sum |F|) = {rt:.2e}");
            if method == BendingMethod::QuarticFit {
                res.push((rf, rt));
            }
        }
    }
    assert!(res[2].0 < 0.01 && res[2].1 < 0.01, "{res:?}");
    assert!(res[2].0 < res[0].0 && res[2].1 < res[0].1, "{res:?}");
}

/// Objectivity: rotating and translating the mesh rotates the bending force
/// density with it (exact up to rounding for every method: the fits use
/// isotropic weights and a polynomial space closed under rotations of the
/// local frame), and the force stays finite on a noisy, deformed mesh.
#[test]
fn bending_force_is_objective_and_finite_on_noisy_meshes() {
    use nalgebra::Rotation3;
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
    let mut m = mesh::discocyte(4);
    let h = m.quality().mean_edge_um;
    for v in &mut m.vertices {
        *v += Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ) * (0.02 * h);
    }
    let rot = Rotation3::from_euler_angles(0.9, -0.4, 2.2);
    let moved = m.transformed(&rot, &Vector3::new(3.0, -1.0, 7.0));
    for method in [
        BendingMethod::CotangentMethodC,
        BendingMethod::QuarticFit,
        BendingMethod::QuarticFitGalerkin,
    ] {
        let law = Helfrich::with_method(3e-19, method).unwrap();
        let (f0, f1) = (law.force_density(&m), law.force_density(&moved));
        let scale = f0.iter().map(|v| v.norm()).fold(0.0, f64::max);
        assert!(
            f0.iter().all(|v| v.iter().all(|c| c.is_finite())),
            "{method:?}"
        );
        let dev = f0
            .iter()
            .zip(&f1)
            .map(|(a, b)| (rot * a - b).norm())
            .fold(0.0, f64::max);
        // tolerance: the fit's Lap_s H uses central differences of step 1e-4
        // whose rounding (~1e-16 / 1e-8 relative to local values) differs
        // between the two frames; measured 3e-8 of the largest force
        assert!(dev < 1e-6 * scale, "{method:?}: {dev:e} of {scale:e}");
        assert!((law.energy(&m) - law.energy(&moved)).abs() < 1e-10 * law.energy(&m));
    }
}
