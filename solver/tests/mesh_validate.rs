//! Tests of the validating constructor `Mesh::from_arrays` and of the deformation check: each defect is named.

use nalgebra::Vector3;
use rbc_solver::mesh::{self, Mesh, MeshError};

fn tetra() -> (Vec<Vector3<f64>>, Vec<[usize; 3]>) {
    let v = vec![
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
        Vector3::new(0.0, 0.0, 1.0),
    ];
    // outward: (1,0,0)x... checked by the constructor's volume sign
    let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    (v, t)
}

#[test]
fn valid_tetrahedron_is_accepted_with_positive_volume() {
    let (v, t) = tetra();
    let m = Mesh::from_arrays(v, t).unwrap();
    assert!((m.volume() - 1.0 / 6.0).abs() < 1e-15);
}

#[test]
fn each_defect_is_reported() {
    let (v, t) = tetra();
    let inward: Vec<[usize; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
    assert!(matches!(
        Mesh::from_arrays(v.clone(), inward),
        Err(MeshError::InwardOriented { .. })
    ));

    let mut flipped = t.clone();
    flipped[3] = [1, 3, 2];
    assert!(matches!(
        Mesh::from_arrays(v.clone(), flipped),
        Err(MeshError::EdgeOrientation { .. } | MeshError::OpenEdge { .. })
    ));

    let open = t[..3].to_vec();
    assert!(matches!(
        Mesh::from_arrays(v.clone(), open),
        Err(MeshError::Empty { .. })
    ));
    let s = mesh::sphere(1, 1.0);
    let open: Vec<[usize; 3]> = s.triangles[1..].to_vec();
    assert!(matches!(
        Mesh::from_arrays(s.vertices.clone(), open),
        Err(MeshError::OpenEdge { .. })
    ));

    let mut bad = t.clone();
    bad[0] = [0, 2, 7];
    assert!(matches!(
        Mesh::from_arrays(v.clone(), bad),
        Err(MeshError::IndexOutOfRange {
            triangle: 0,
            index: 7,
            ..
        })
    ));

    let mut rep = t.clone();
    rep[1] = [0, 0, 3];
    assert!(matches!(
        Mesh::from_arrays(v.clone(), rep),
        Err(MeshError::RepeatedVertex { triangle: 1, .. })
    ));

    let mut nan = v.clone();
    nan[2].y = f64::NAN;
    assert!(matches!(
        Mesh::from_arrays(nan, t.clone()),
        Err(MeshError::NonFiniteVertex { vertex: 2, .. })
    ));

    let mut extra = v.clone();
    extra.push(Vector3::new(5.0, 5.0, 5.0));
    assert!(matches!(
        Mesh::from_arrays(extra, t.clone()),
        Err(MeshError::UnusedVertex { vertex: 4 })
    ));

    let mut flat = v.clone();
    flat[3] = Vector3::new(0.5, 0.5, 0.0); // on the plane of the others' hull edge -> zero-area faces
    assert!(Mesh::from_arrays(flat, t.clone()).is_err());

    // two disjoint tetrahedra: closed and oriented but chi = 4
    let mut v2 = v.clone();
    v2.extend(v.iter().map(|p| p + Vector3::new(3.0, 0.0, 0.0)));
    let mut t2 = t.clone();
    t2.extend(t.iter().map(|&[a, b, c]| [a + 4, b + 4, c + 4]));
    assert!(matches!(
        Mesh::from_arrays(v2, t2),
        Err(MeshError::NotSphereLike { chi: 4 })
    ));
}

#[test]
fn deformation_check_finds_nan_collapse_and_fold() {
    let r = mesh::sphere(3, 4.0);
    assert!(!r.has_inverted_triangles(&r));
    let mut m = r.clone();
    m.vertices[10].x = f64::NAN;
    assert!(matches!(
        m.check_deformation(&r),
        Err(MeshError::NonFiniteVertex { vertex: 10, .. })
    ));
    // a deep inward dent is a bad but valid surface: not flagged
    let mut m = r.clone();
    m.vertices[100] *= 0.5;
    assert!(m.check_deformation(&r).is_ok());
    // drag one vertex tangentially across its one-ring: its triangles flip over
    let mut m = r.clone();
    let j = r.topology().vertex_neighbours[100][0];
    m.vertices[100] = r.vertices[j] + 1.5 * (r.vertices[j] - r.vertices[100]);
    assert!(matches!(
        m.check_deformation(&r),
        Err(MeshError::Folded { .. } | MeshError::Inverted { .. })
    ));
    // collapse a triangle onto a point
    let mut m = r.clone();
    let [a, b, c] = m.triangles[7];
    m.vertices[b] = m.vertices[a];
    m.vertices[c] = m.vertices[a];
    assert!(m.has_inverted_triangles(&r));
}

/// Round trip through flat arrays (the `results.h5` layout) and length checks.
#[test]
fn flat_arrays_round_trip() {
    let d = mesh::discocyte(3);
    let flat_v: Vec<f64> = d.vertices.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
    let flat_t: Vec<usize> = d.triangles.iter().flat_map(|t| t.iter().copied()).collect();
    let back = Mesh::from_flat_arrays(&flat_v, &flat_t).unwrap();
    assert_eq!(back, d);
    assert!(matches!(
        Mesh::from_flat_arrays(&flat_v[1..], &flat_t),
        Err(MeshError::FlatLength {
            array: "vertices",
            ..
        })
    ));
    assert!(matches!(
        Mesh::from_flat_arrays(&flat_v, &flat_t[1..]),
        Err(MeshError::FlatLength {
            array: "triangles",
            ..
        })
    ));
}
