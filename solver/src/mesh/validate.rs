//! Validated construction of a mesh from vertex/triangle arrays (e.g. read back from a results file).

use std::collections::HashMap;

use nalgebra::Vector3;

use super::{Mesh, MeshError};

impl Mesh {
    /// Builds a mesh from arrays and checks that it is a valid cell surface:
    /// non-empty, finite coordinates, indices in range, no repeated corner,
    /// no zero-area triangle (below `1e-12` of the mean), every directed edge
    /// used once and its reverse once (closed, manifold, consistently
    /// oriented), every vertex used, Euler characteristic 2, and positive
    /// enclosed volume (outward orientation). Returns the first violation.
    pub fn from_arrays(
        vertices: Vec<Vector3<f64>>,
        triangles: Vec<[usize; 3]>,
    ) -> Result<Mesh, MeshError> {
        let nv = vertices.len();
        if nv < 4 || triangles.len() < 4 {
            return Err(MeshError::Empty {
                vertices: nv,
                triangles: triangles.len(),
            });
        }
        for (i, v) in vertices.iter().enumerate() {
            if !v.iter().all(|x| x.is_finite()) {
                return Err(MeshError::NonFiniteVertex {
                    vertex: i,
                    value: [v.x, v.y, v.z],
                });
            }
        }
        let mut used = vec![false; nv];
        for (t, tri) in triangles.iter().enumerate() {
            for &i in tri {
                if i >= nv {
                    return Err(MeshError::IndexOutOfRange {
                        triangle: t,
                        index: i,
                        vertices: nv,
                    });
                }
                used[i] = true;
            }
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                return Err(MeshError::RepeatedVertex {
                    triangle: t,
                    corners: *tri,
                });
            }
        }
        if let Some(vertex) = used.iter().position(|u| !u) {
            return Err(MeshError::UnusedVertex { vertex });
        }
        let mesh = Mesh {
            vertices,
            triangles,
        };
        let areas = mesh.triangle_areas();
        let mean = areas.iter().sum::<f64>() / areas.len() as f64;
        for (t, &a) in areas.iter().enumerate() {
            if a.is_nan() || a <= 1e-12 * mean {
                return Err(MeshError::Degenerate {
                    triangle: t,
                    area: a,
                    reference: mean,
                });
            }
        }
        let mut directed: HashMap<(usize, usize), (usize, usize)> = HashMap::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let e = (tri[k], tri[(k + 1) % 3]);
                directed.entry(e).or_insert((0, t)).0 += 1;
            }
        }
        let mut keys: Vec<_> = directed.keys().copied().collect();
        keys.sort_unstable();
        for &(a, b) in &keys {
            let (count, triangle) = directed[&(a, b)];
            if count != 1 {
                return Err(MeshError::EdgeOrientation { a, b, count });
            }
            if !directed.contains_key(&(b, a)) {
                return Err(MeshError::OpenEdge { a, b, triangle });
            }
        }
        let n_edges = keys.len() / 2;
        let chi = nv as i64 - n_edges as i64 + mesh.triangles.len() as i64;
        if chi != 2 {
            return Err(MeshError::NotSphereLike { chi });
        }
        let volume = mesh.volume();
        if volume.is_nan() || volume <= 0.0 {
            return Err(MeshError::InwardOriented { volume });
        }
        Ok(mesh)
    }

    /// [`Mesh::from_arrays`] from flat row-major arrays as stored in
    /// `results.h5` (`vertices_um[nv, 3]`, `triangles[nt, 3]`).
    pub fn from_flat_arrays(vertices_um: &[f64], triangles: &[usize]) -> Result<Mesh, MeshError> {
        if !vertices_um.chunks_exact(3).remainder().is_empty() {
            return Err(MeshError::FlatLength {
                array: "vertices",
                len: vertices_um.len(),
            });
        }
        if !triangles.chunks_exact(3).remainder().is_empty() {
            return Err(MeshError::FlatLength {
                array: "triangles",
                len: triangles.len(),
            });
        }
        let v = vertices_um
            .chunks_exact(3)
            .map(|c| Vector3::new(c[0], c[1], c[2]))
            .collect();
        let t = triangles
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        Mesh::from_arrays(v, t)
    }
}
