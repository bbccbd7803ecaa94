//! Mirror symmetry of the discretised cell about the planes y = y_c and z = z_c through its centroid: the mesh, its membrane force and its free-space velocity in unbounded Poiseuille flow, and the drift of a centred cell.

use nalgebra::Vector3;
use rbc_schema::scene::Scene;
use rbc_solver::integrate::cell::Stokes;
use rbc_solver::membrane::MembraneLaw;
use rbc_solver::mesh::Mesh;
use rbc_solver::run::Recorder;
use std::path::Path;

/// `(x, y, z)` with 3 significant digits.
fn fmt(v: &Vector3<f64>) -> String {
    format!("({:.3e}, {:.3e}, {:.3e})", v.x, v.y, v.z)
}

/// Mirror image of `p` in the plane `x_k = c_k`.
fn mirror(p: &Vector3<f64>, k: usize, c: &Vector3<f64>) -> Vector3<f64> {
    let mut q = *p;
    q[k] = 2.0 * c[k] - p[k];
    q
}

/// For the mirror in the plane `x_k = c_k` through the volume centroid `c`: the nearest vertex
/// to the image of every vertex, and the largest such distance (um), i.e. the Hausdorff distance
/// between the vertex set and its mirror image (O(N^2): fine up to level 4).
fn mirror_map(mesh: &Mesh, k: usize) -> (Vec<usize>, f64) {
    let c = mesh.centroid();
    let mut worst = 0.0f64;
    let map = mesh
        .vertices
        .iter()
        .map(|p| {
            let q = mirror(p, k, &c);
            let (j, d) = mesh.vertices.iter().enumerate().map(|(j, v)| (j, (v - q).norm())).fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
            worst = worst.max(d);
            j
        })
        .collect();
    (map, worst)
}

/// Largest `|a_i - M a_{P(i)}|` over vertices, relative to `max |a|`: the mirror asymmetry of a
/// nodal vector field `a` for the mirror `M` in the plane normal to axis `k` with vertex map `P`.
fn field_asymmetry(a: &[Vector3<f64>], map: &[usize], k: usize) -> f64 {
    let scale = a.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let zero = Vector3::zeros();
    a.iter().zip(map).map(|(ai, &j)| (ai - mirror(&a[j], k, &zero)).norm()).fold(0.0, f64::max) / scale
}

/// Free-space scene: discocyte (axis x) of level `level` at `(0, y0, z0)` in unbounded
/// Poiseuille flow (centre-line `u_max` um/s, radius `r` um), paper membrane, viscosity ratio `lambda`.
fn scene(level: usize, y0: f64, z0: f64, lambda: f64, u_max: f64, r: f64, scheme: &str, atol: f64, end_s: f64, out_s: f64) -> Scene {
    let text = format!(
        r#"
name = "symmetry"
[cell]
shape = "discocyte"
level = {level}
position_um = [0.0, {y0:e}, {z0:e}]
axis = [1.0, 0.0, 0.0]
[membrane]
reference = "discocyte"
[membrane.skalak]
convention = "krueger"
kappa_s_n_m = 5e-6
kappa_a_n_m = 5e-4
[membrane.bending]
kappa_b_n_m = 3e-19
[fluid]
viscosity_pa_s = 1.2e-3
lambda = {lambda:?}
[flow]
kind = "poiseuille"
max_velocity_um_s = {u_max:?}
radius_um = {r:?}
[walls]
kind = "none"
[integrator]
scheme = "{scheme}"
atol_um = {atol:e}
[time]
end_s = {end_s:e}
output_interval_s = {out_s:e}
"#
    );
    Scene::parse(&text, Path::new("symmetry.toml")).unwrap()
}

#[test]
#[ignore]
fn study_mesh_asymmetry() {
    for level in 1..=4 {
        let s = scene(level, 0.0, 0.0, 1.0, 1e4, 6.0, "bs23", 1e-3, 1e-3, 1e-3);
        let m = rbc_solver::scene::initial_mesh(&s).unwrap();
        let c = m.centroid();
        let (_, ay) = mirror_map(&m, 1);
        let (_, az) = mirror_map(&m, 2);
        let (_, ax) = mirror_map(&m, 0);
        let first: Vector3<f64> = m.vertices.iter().sum::<Vector3<f64>>() / m.vertices.len() as f64;
        eprintln!("level {level}: centroid {}; Hausdorff to mirror: y {ay:.2e} z {az:.2e} x {ax:.2e} um; mean vertex {}", fmt(&c), fmt(&first));
    }
}

#[test]
#[ignore]
fn study_force_velocity_asymmetry() {
    for lambda in [1.0, 5.0] {
        for level in 2..=3 {
            let s = scene(level, 0.0, 0.0, lambda, 1e4, 6.0, "bs23", 1e-3, 1e-3, 1e-3);
            let built = rbc_solver::scene::build(&s).unwrap();
            let m = &built.mesh;
            let (py, _) = mirror_map(m, 1);
            let (pz, _) = mirror_map(m, 2);
            let f = built.membrane.force_density(m);
            let u = built.stokes.velocity(m, &f, true, None).unwrap();
            let uc = rbc_solver::channel::stokes::centroid_velocity(m, &u);
            eprintln!(
                "lambda {lambda} level {level}: force asym y {:.2e} z {:.2e}; velocity asym y {:.2e} z {:.2e}; centroid velocity {} um/s (y/x {:.1e}, z/x {:.1e})",
                field_asymmetry(&f, &py, 1),
                field_asymmetry(&f, &pz, 2),
                field_asymmetry(&u, &py, 1),
                field_asymmetry(&u, &pz, 2),
                fmt(&uc),
                uc.y / uc.x,
                uc.z / uc.x
            );
        }
    }
}

/// RMS distance (um) of the mirrored vertices from the surface, for the planes y = y_c and
/// z = z_c through the volume centroid ([`rbc_solver::classify::mirror_asymmetry`]).
fn surface_asymmetry(m: &Mesh) -> (f64, f64) {
    let v: Vec<[f64; 3]> = m.vertices.iter().map(|p| [p.x, p.y, p.z]).collect();
    let c = m.centroid();
    (rbc_solver::classify::mirror_asymmetry(&v, &m.triangles, 1, c.y), rbc_solver::classify::mirror_asymmetry(&v, &m.triangles, 2, c.z))
}

fn env(name: &str, default: f64) -> f64 {
    std::env::var(name).ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

/// Drift study: SYM_LEVEL, SYM_LAMBDA, SYM_UMAX (um/s), SYM_R (um), SYM_Y0 (um), SYM_ROT (degrees about x),
/// SYM_END (s), SYM_OUT (s), SYM_ATOL (um), SYM_SCHEME (bs23 | ros2).
#[test]
#[ignore]
fn study_drift() {
    let level = env("SYM_LEVEL", 2.0) as usize;
    let scheme = std::env::var("SYM_SCHEME").unwrap_or("bs23".into());
    let s = scene(level, env("SYM_Y0", 0.0), 0.0, env("SYM_LAMBDA", 1.0), env("SYM_UMAX", 1e4), env("SYM_R", 6.0), &scheme, env("SYM_ATOL", 1e-4), env("SYM_END", 2e-3), env("SYM_OUT", 2e-4));
    let mut built = rbc_solver::scene::build(&s).unwrap();
    let rot = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), env("SYM_ROT", 0.0).to_radians());
    let c = built.mesh.centroid();
    built.mesh = built.mesh.transformed(&nalgebra::Rotation3::identity(), &-c).transformed(&rot, &c);
    let (_, ay) = mirror_map(&built.mesh, 1);
    let (_, az) = mirror_map(&built.mesh, 2);
    eprintln!("initial mesh mirror asymmetry y {ay:.2e} z {az:.2e} um");
    let mut rec = Recorder::default();
    let t0 = std::time::Instant::now();
    let result = built.run(&mut rec);
    for (i, t) in rec.times_s.iter().enumerate() {
        let m = Mesh { vertices: rec.vertices[i].clone(), triangles: built.mesh.triangles.clone() };
        let (_, ay) = mirror_map(&m, 1);
        let (_, az) = mirror_map(&m, 2);
        let (sy, sz) = surface_asymmetry(&m);
        eprintln!("t {:.3e} s: centroid {} um, vertex asymmetry y {ay:.2e} z {az:.2e} um, surface asymmetry (rms) y {sy:.2e} z {sz:.2e} um, step {}", t, fmt(&rec.centroid_um[i]), rec.steps[i]);
    }
    eprintln!("{:?} ({:.1} s)", result.map(|r| r.0), t0.elapsed().as_secs_f64());
}
