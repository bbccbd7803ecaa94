//! Tests of the mesh generators and geometry: counts, exact areas/volumes under refinement, orientation, transforms, quality.

use std::f64::consts::PI;

use nalgebra::{Rotation3, Vector3};
use rbc_solver::mesh::shapes::{AxisymmetricShape, Placement};
use rbc_solver::mesh::{self, Mesh};

#[test]
fn octahedron_subdivision_counts_match_formulas() {
    for (level, nt, nv) in [
        (2, 128, 66),
        (3, 512, 258),
        (4, 2048, 1026),
        (5, 8192, 4098),
    ] {
        let m = mesh::sphere(level, 1.0);
        assert_eq!(m.triangles.len(), nt);
        assert_eq!(m.vertices.len(), nv);
        assert_eq!(mesh::triangle_count(level), nt);
        assert_eq!(mesh::vertex_count(level), nv);
        assert_eq!(m.edges().len(), 3 * nt / 2);
        // every generated mesh passes the validating constructor
        Mesh::from_arrays(m.vertices.clone(), m.triangles.clone()).unwrap();
    }
}

#[test]
fn paper_mesh_is_1026_vertices_2048_triangles() {
    let d = mesh::discocyte(4);
    assert_eq!((d.vertices.len(), d.triangles.len()), (1026, 2048));
    Mesh::from_arrays(d.vertices.clone(), d.triangles.clone()).unwrap();
}

#[test]
fn discocyte_exact_area_and_volume_are_the_papers() {
    // Spec: Evans-Fung with R0 = 3.91 um has area 134.1 um^2, volume 94.1 um^3;
    // scaled by 4/3.91: 140.3 um^2 and 100.7 um^3 (rounded to 0.1).
    let unscaled = AxisymmetricShape::EvansFung { scale: 1.0 };
    assert!(
        (unscaled.area() - 134.1).abs() < 0.05,
        "{}",
        unscaled.area()
    );
    assert!(
        (unscaled.volume() - 94.1).abs() < 0.05,
        "{}",
        unscaled.volume()
    );
    let rbc = AxisymmetricShape::evans_fung_rbc();
    assert!((rbc.area() - 140.3).abs() < 0.05, "{}", rbc.area());
    assert!((rbc.volume() - 100.7).abs() < 0.05, "{}", rbc.volume());
    // reduced volume 0.644 = 3 V / (4 pi (A / 4 pi)^(3/2))
    let v_red = 3.0 * rbc.volume() / (4.0 * PI * (rbc.area() / (4.0 * PI)).powf(1.5));
    assert!((v_red - 0.644).abs() < 0.0005, "{v_red}");
}

/// Relative errors of the mesh area and volume against the exact surface:
/// flat triangles inscribed in a smooth surface err by O(h^2), so each level
/// (h halves) must cut the error by about 4.
#[test]
fn area_and_volume_converge_at_second_order() {
    for placement in [Placement::Polar, Placement::ArcLength] {
        for shape in [
            AxisymmetricShape::Sphere { radius: 4.0 },
            AxisymmetricShape::Spheroid { a: 4.0, c: 2.0 },
            AxisymmetricShape::evans_fung_rbc(),
        ] {
            let (a0, v0) = (shape.area(), shape.volume());
            let errs: Vec<(f64, f64)> = (2..=5)
                .map(|l| {
                    let m = shape.mesh_with(l, placement);
                    ((m.area() - a0).abs() / a0, (m.volume() - v0).abs() / v0)
                })
                .collect();
            println!(
                "{shape:?} {placement:?}: relative (area, volume) errors per level 2..5: {errs:?}"
            );
            for w in errs.windows(2) {
                let (ra, rv) = (w[0].0 / w[1].0, w[0].1 / w[1].1);
                assert!(ra > 3.5 && ra < 4.5, "area ratio {ra}");
                assert!(rv > 3.5 && rv < 4.5, "volume ratio {rv}");
            }
            assert!(
                errs[2].0 < 0.01 && errs[2].1 < 0.01,
                "level 4 within 1%: {:?}",
                errs[2]
            );
        }
    }
}

#[test]
fn normals_are_outward_and_vertex_areas_sum_to_area() {
    let d = mesh::discocyte(3);
    let c = d.centroid();
    assert!(
        c.norm() < 1e-12,
        "symmetric mesh has its centroid at the origin: {c}"
    );
    // On the sphere the outward normal is the radial direction.
    let s = mesh::sphere(3, 2.0);
    for (v, n) in s.vertices.iter().zip(s.vertex_normals()) {
        assert!(n.dot(&v.normalize()) > 0.995, "{}", n.dot(&v.normalize()));
    }
    for (t, n) in s.triangle_normals().iter().enumerate() {
        let [a, b, cc] = s.corners(t);
        assert!(n.dot(&((a + b + cc) / 3.0).normalize()) > 0.99);
    }
    for areas in [d.vertex_areas(), d.barycentric_vertex_areas()] {
        let sum: f64 = areas.iter().sum();
        assert!((sum - d.area()).abs() < 1e-10 * d.area());
    }
    // mixed Voronoi area at a valence-4 octahedron vertex of a sphere is 1.5x
    // the barycentric one (its four triangles are right-angled there)
    let (mixed, bary) = (s.vertex_areas(), s.barycentric_vertex_areas());
    assert!(
        (mixed[0] / bary[0] - 1.5).abs() < 0.02,
        "{}",
        mixed[0] / bary[0]
    );
}

#[test]
fn rigid_transform_keeps_area_volume_and_moves_centroid() {
    let d = mesh::discocyte(3);
    let rot = Rotation3::from_axis_angle(&Vector3::y_axis(), PI / 2.0); // cell axis z -> x
    let shift = Vector3::new(1.0, 0.5, -0.3);
    let m = d.transformed(&rot, &shift);
    assert!((m.area() - d.area()).abs() < 1e-10 * d.area());
    assert!((m.volume() - d.volume()).abs() < 1e-10 * d.volume());
    assert!((m.centroid() - shift).norm() < 1e-10);
    // the symmetry axis is now x: the extent along x is the thickness
    let ext = |k: usize| {
        let v: Vec<f64> = m.vertices.iter().map(|p| p[k]).collect();
        v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
    };
    assert!(ext(0) < 3.0 && (ext(1) - 8.0).abs() < 1e-9 && (ext(2) - 8.0).abs() < 1e-9);
}

/// Prints the triangle quality table (the numbers quoted in the report) and
/// checks bounds that the projected octahedron is known to satisfy.
#[test]
fn triangle_quality_report() {
    for level in 2..=5 {
        let s = mesh::sphere(level, 4.0);
        let d = mesh::discocyte(level);
        let da = AxisymmetricShape::evans_fung_rbc().mesh_with(level, Placement::ArcLength);
        let (qs, qd, qa) = (s.quality(), d.quality(), da.quality());
        println!("sphere              l={level}: {qs}");
        println!("discocyte polar     l={level}: {qd}");
        println!("discocyte arclength l={level}: {qa}");
        // bounds measured when written (min angle 45.0 / 28.6 / 38.2 deg at level 5)
        assert!(qs.min_angle_deg > 44.0 && qs.max_aspect_ratio < 1.4, "{qs}");
        assert!(qd.min_angle_deg > 28.0 && qd.max_aspect_ratio < 1.7, "{qd}");
        assert!(
            qa.min_angle_deg > 38.0
                && qa.max_aspect_ratio < 1.45
                && qa.min_angle_deg > qd.min_angle_deg,
            "{qa}"
        );
        // both placements put the vertices on the same exact surface: same area to O(h^2)
        assert!(
            (da.area() - d.area()).abs()
                < 0.1
                    * (AxisymmetricShape::evans_fung_rbc().area() - d.area())
                        .abs()
                        .max(1e-3)
                    + 0.02 * d.area()
        );
    }
}
