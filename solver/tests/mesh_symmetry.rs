//! Mirror symmetry of the discretised cell about the planes y = y_c and z = z_c through its centroid: the mesh, its membrane force and its free-space velocity in unbounded Poiseuille flow, and the drift of a centred cell.

use nalgebra::Vector3;
use rbc_schema::scene::Scene;
use rbc_solver::bim::Stokes;
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
#[allow(clippy::too_many_arguments, reason = "one argument per study parameter, all named at the call sites' env vars")]
fn scene(level: usize, y0: f64, z0: f64, lambda: f64, u_max: f64, r: f64, scheme: &str, atol: f64, end_s: f64, out_s: f64) -> Scene {
    let text = format!(
        r#"
name = "symmetry"
[cell]
shape = "discocyte"
level = {level}
position_um = [0.0, {y0:e}, {z0:e}]
axis = [1.0, 0.0, 0.0]
{blocks}[flow]
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
"#,
        blocks = rbc_schema::paper_scene::membrane_and_fluid(lambda)
    );
    Scene::parse(&text, Path::new("symmetry.toml")).unwrap()
}

/// The discocyte with its axis along x is mirror-symmetric about the planes y = y_c and z = z_c
/// through its centroid to round-off (measured <= 2.4e-15 um up to level 4; the octahedron
/// subdivision and the polar map are exactly symmetric under x -> -x and y -> -y of the
/// generator's frame, and the axis rotation is an exact permutation), and the mirror is a
/// symmetry of the triangulation itself: a permutation of the vertices that maps triangles onto
/// triangles. A rotation about the axis by 10 degrees keeps the surface but not the vertex set
/// (asymmetry ~0.5 um), which shows the measure sees what it should.
#[test]
fn discocyte_mesh_is_mirror_symmetric_about_the_y_and_z_planes_through_its_centroid() {
    let r = rbc_solver::scene::axis_rotation([1.0, 0.0, 0.0]);
    assert_eq!(r * Vector3::z(), Vector3::x(), "exact rotation of the axis");
    assert_eq!(r * Vector3::y(), Vector3::y());
    for level in 1..=4 {
        let s = scene(level, 0.0, 0.0, 1.0, 1e4, 6.0, "bs23", 1e-3, 1e-3, 1e-3);
        let m = rbc_solver::scene::initial_mesh(&s).unwrap();
        for k in [1, 2] {
            let (map, asym) = mirror_map(&m, k);
            assert!(asym < 1e-12, "level {level}, mirror {k}: {asym:e} um");
            let mut seen = vec![false; map.len()];
            map.iter().for_each(|&j| seen[j] = true);
            assert!(seen.iter().all(|&s| s), "the mirror permutes the vertices");
            let mut tris: Vec<[usize; 3]> = m.triangles.iter().map(|t| { let mut t = *t; t.sort(); t }).collect();
            tris.sort();
            for t in &m.triangles {
                let mut image = [map[t[0]], map[t[1]], map[t[2]]];
                image.sort();
                assert!(tris.binary_search(&image).is_ok(), "level {level}: image of {t:?} is not a triangle");
            }
        }
        let tilted = m.transformed(&nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), 10f64.to_radians()), &Vector3::zeros());
        assert!(mirror_map(&tilted, 1).1 > 0.1 / level as f64, "level {level}: a tilted mesh is not vertex-symmetric");
    }
}

/// The membrane force of the centred discocyte and its free-space velocity in unbounded
/// Poiseuille flow (lambda = 1 and 5, the double layer and GMRES; levels 2 and 3) are
/// mirror-symmetric to round-off: measured 2e-13 (force: curvatures amplify round-off) and
/// 6e-15 (velocity) relative to their largest values at level 3; the centroid velocity has no y
/// or z component (1e-16 of x). (Level 2 and the printout were the ignored study
/// `study_force_velocity_asymmetry`; the mesh's own symmetry, printed by the ignored
/// `study_mesh_asymmetry`, is asserted above.)
#[test]
fn membrane_force_and_poiseuille_velocity_of_the_centred_cell_are_mirror_symmetric() {
    for (lambda, level) in [(1.0, 2), (1.0, 3), (5.0, 2), (5.0, 3)] {
        let s = scene(level, 0.0, 0.0, lambda, 1e4, 6.0, "bs23", 1e-3, 1e-3, 1e-3);
        let built = rbc_solver::scene::build(&s).unwrap();
        let m = &built.mesh;
        let f = built.membrane.force_density(m);
        let u = built.stokes.velocity(m, &f, true, None).unwrap();
        for k in [1, 2] {
            let (map, _) = mirror_map(m, k);
            let (af, au) = (field_asymmetry(&f, &map, k), field_asymmetry(&u, &map, k));
            eprintln!("lambda {lambda}, level {level}, mirror {k}: force {af:.2e}, velocity {au:.2e}");
            assert!(af < 1e-11 && au < 1e-11, "lambda {lambda}, level {level}, mirror {k}: force {af:e}, velocity {au:e}");
        }
        let uc = rbc_solver::channel::stokes::centroid_velocity(m, &u);
        assert!(uc.x > 5e3 && uc.y.abs() < 1e-12 * uc.x && uc.z.abs() < 1e-12 * uc.x, "lambda {lambda}, level {level}: {}", fmt(&uc));
    }
}

/// Over 2 ms (15 um downstream) at 10 mm/s in a Poiseuille flow of radius 6 um, the centred
/// 128-triangle cell stays centred and mirror-symmetric to round-off (measured: centroid offset
/// 8e-15 um, rms surface asymmetry 2e-13 um), while the same cell started 1e-3 um off the axis,
/// symmetric in shape at t = 0 (3e-16 um), is 1.5e-3 um asymmetric about y = y_c after 2 ms and
/// keeps its z mirror: the discretisation keeps the symmetry; the dynamics amplify an asymmetry
/// once there is one (at this coarse resolution the centred state is unstable, see `study_drift`).
#[test]
fn centred_cell_stays_centred_in_free_space_poiseuille_while_an_offset_one_grows() {
    let mut asym = Vec::new();
    for y0 in [0.0, 1e-3] {
        let s = scene(2, y0, 0.0, 1.0, 1e4, 6.0, "bs23", 1e-4, 2e-3, 1e-3);
        let built = rbc_solver::scene::build(&s).unwrap();
        let mut rec = Recorder::default();
        built.run(&mut rec).unwrap();
        let last = Mesh { vertices: rec.vertices.last().unwrap().clone(), triangles: built.mesh.triangles.clone() };
        let c = rec.centroid_um.last().unwrap();
        let (sy, sz) = surface_asymmetry(&last);
        eprintln!("y0 {y0:e}: centroid {} um, surface asymmetry y {sy:.2e} z {sz:.2e} um", fmt(c));
        assert!(c.x > 10.0, "moved downstream: {}", fmt(c));
        if y0 == 0.0 {
            assert!(c.y.abs() < 1e-12 && c.z.abs() < 1e-12, "left the axis: {}", fmt(c));
            assert!(sy < 1e-10 && sz < 1e-10, "{sy:e} {sz:e}");
        } else {
            assert!(sz < 1e-10, "the offset along y keeps the z mirror: {sz:e}");
        }
        asym.push(sy);
    }
    assert!(asym[1] > 1e-4, "the offset cell's asymmetry grows: {:e}", asym[1]);
}

/// RMS distance (um) of the mirrored vertices from the surface, for the planes y = y_c and
/// z = z_c through the volume centroid ([`rbc_solver::classify::mirror_asymmetry`]).
fn surface_asymmetry(m: &Mesh) -> (f64, f64) {
    let v: Vec<[f64; 3]> = m.vertices.iter().map(|p| [p.x, p.y, p.z]).collect();
    let c = m.centroid();
    (rbc_solver::classify::mirror_asymmetry(&v, &m.triangles, 1, c.y), rbc_solver::classify::mirror_asymmetry(&v, &m.triangles, 2, c.z))
}

/// Drift study (measured, lambda = 1, R = 6 um, BS23 atol 1e-4 um, paper membrane; "asymmetry" is
/// the rms surface distance of the mirrored vertices):
/// - centred cell: asymmetry 1e-15 um at t = 0; at 10 mm/s it grows from round-off at ~600 1/s
///   (level 2: 1e-6 um vertex asymmetry at 25 ms; level 3: 7e-8 um at 24 ms), the centroid stays
///   within 1e-9 um; lambda = 5 at level 2: 3e-12 um at 25 ms.
/// - 1e-3 um offset along y at 10 mm/s: level 2 and level 3 leave the axis (asymmetry 1e-3 um
///   -> 0.5 um within 4-8 ms, growth ~850 1/s at level 2 and ~2000 1/s at level 3; level 2 fails
///   its 5 % area check at 14 ms); level 4 (2048 triangles) does not: the offset decays
///   (1e-3 -> 7.2e-4 um in 10 ms) and the asymmetry stays at 1.9e-3 um, slaved to the offset.
///   At level 2 the growth also depends on the flow: none at 2 mm/s (offset 1e-3 -> 0.93e-3 um in
///   25 ms), ~360 1/s at 5 mm/s, ~850 1/s at 10 mm/s.
/// - lambda = 5, 1e-3 um offset at 10 mm/s: the offset grows slowly and the same at level 3 and
///   level 4 (1e-3 -> 1.52e-3 and 1.64e-3 um in 6 ms, ~80 1/s at first): resolved, plausibly
///   physical (outward migration at lambda = 5), and far too slow to take a round-off seed to
///   microns in 23 ms (~35 e-foldings would take ~0.4 s).
/// - level 3, lambda = 1, 10 mm/s with BS23 at atol 1e-5 um or with ROS2: the same history to
///   3 digits (asymmetry 0.08 um at 4 ms), so the time integration is not the cause.
///
/// So the drift of centred coarse cells is a numerical instability of the coarse meshes (levels
/// 2-3) at high flow that amplifies round-off (1e-15 um x e^(2000 x 0.023) is microns), not an
/// asymmetry of the discretisation (1e-15 um) and not seen at the paper's resolution over 10 ms.
/// A rotation of the mesh about x keeps its 4-fold symmetry, which forbids a lateral centroid
/// velocity: 22.5 degrees gave the same 1e-9 um centroid offset at 25 ms as 0 degrees.
/// The level-4 finding is asserted (the offset after 10 ms within 7.2e-4 +- 0.4e-4 um and never
/// above its start, the asymmetry at 10 ms within 10 % of 1.9e-3 um); the other cases above are
/// [`drift`] with their parameters.
/// Command: `cargo nextest run -p rbc-solver --run-ignored only --no-capture -E 'test(study_drift)'`
/// (150 s at level 4 on a loaded 2-core machine).
#[test]
#[ignore = "study: a 2048-triangle cell 1e-3 um off the axis over 10 ms, asserted"]
fn study_drift() {
    let s = scene(4, 1e-3, 0.0, 1.0, 1e4, 6.0, "bs23", 1e-4, 1e-2, 1e-3);
    let samples = drift(&s, 0.0);
    let &(t, y, sy) = samples.last().unwrap();
    assert!((t - 1e-2).abs() < 1e-9, "ran to the end: {t:e} s");
    assert!((y - 7.2e-4).abs() <= 0.4e-4, "offset after 10 ms {y:.3e} um, measured 7.2e-4");
    assert!(samples.iter().all(|s| s.1 <= 1.0e-3 * (1.0 + 1e-6)), "the offset grew: {samples:?}");
    assert!((sy / 1.9e-3 - 1.0).abs() <= 0.1, "asymmetry after 10 ms {sy:.3e} um, measured 1.9e-3");
}

/// Runs `scene` with the cell rotated by `rot_deg` about x through its centroid and prints, per
/// output, the centroid, the vertex and the surface asymmetries; returns `(t, centroid y, surface
/// asymmetry about y = y_c)` per output.
fn drift(scene: &Scene, rot_deg: f64) -> Vec<(f64, f64, f64)> {
    let mut built = rbc_solver::scene::build(scene).unwrap();
    let rot = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), rot_deg.to_radians());
    let c = built.mesh.centroid();
    built.mesh = built.mesh.transformed(&nalgebra::Rotation3::identity(), &-c).transformed(&rot, &c);
    let (_, ay) = mirror_map(&built.mesh, 1);
    let (_, az) = mirror_map(&built.mesh, 2);
    eprintln!("initial mesh mirror asymmetry y {ay:.2e} z {az:.2e} um");
    let mut rec = Recorder::default();
    let t0 = std::time::Instant::now();
    let result = built.run(&mut rec);
    let mut out = Vec::new();
    for (i, t) in rec.times_s.iter().enumerate() {
        let m = Mesh { vertices: rec.vertices[i].clone(), triangles: built.mesh.triangles.clone() };
        let (_, ay) = mirror_map(&m, 1);
        let (_, az) = mirror_map(&m, 2);
        let (sy, sz) = surface_asymmetry(&m);
        eprintln!("t {:.3e} s: centroid {} um, vertex asymmetry y {ay:.2e} z {az:.2e} um, surface asymmetry (rms) y {sy:.2e} z {sz:.2e} um, step {}", t, fmt(&rec.centroid_um[i]), rec.steps[i]);
        out.push((*t, rec.centroid_um[i].y, sy));
    }
    eprintln!("{:?} ({:.1} s)", result.map(|r| r.0), t0.elapsed().as_secs_f64());
    out
}
