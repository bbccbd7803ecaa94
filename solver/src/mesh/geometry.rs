//! Geometry of a mesh: areas, outward normals, vertex areas, volume, centroid, rigid transforms, deformation checks.

use nalgebra::{Rotation3, Vector3};

use super::{Mesh, MeshError, Topology};

/// Cosine between the normals of two triangles sharing an edge below which
/// the surface is considered folded (the surface turns by more than 120 degrees
/// across one edge: never the case for a resolved smooth surface).
pub const FOLD_COSINE: f64 = -0.5;

impl Mesh {
    /// Corner positions of triangle `t` (um).
    #[inline]
    pub fn corners(&self, t: usize) -> [Vector3<f64>; 3] {
        let [a, b, c] = self.triangles[t];
        [self.vertices[a], self.vertices[b], self.vertices[c]]
    }

    /// `(b - a) x (c - a)` of each triangle: outward, length twice the area (um^2).
    pub fn triangle_area_vectors(&self) -> Vec<Vector3<f64>> {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                (b - a).cross(&(c - a))
            })
            .collect()
    }

    /// Triangle areas (um^2).
    pub fn triangle_areas(&self) -> Vec<f64> {
        self.triangle_area_vectors()
            .iter()
            .map(|n| 0.5 * n.norm())
            .collect()
    }

    /// Outward unit normals of the triangles.
    pub fn triangle_normals(&self) -> Vec<Vector3<f64>> {
        self.triangle_area_vectors()
            .iter()
            .map(|n| n.normalize())
            .collect()
    }

    /// Outward unit vertex normals: the area-weighted mean of the adjacent
    /// triangles' normals (sum of the adjacent `(b - a) x (c - a)`, normalised).
    pub fn vertex_normals(&self) -> Vec<Vector3<f64>> {
        let mut n = vec![Vector3::zeros(); self.vertices.len()];
        for (tri, an) in self.triangles.iter().zip(self.triangle_area_vectors()) {
            for &v in tri {
                n[v] += an;
            }
        }
        n.into_iter().map(|v| v.normalize()).collect()
    }

    /// Vertex areas (um^2): the mixed Voronoi areas of Meyer, Desbrun, Schroeder
    /// & Barr ("Discrete differential-geometry operators for triangulated
    /// 2-manifolds", 2003, section 3.3). In a non-obtuse triangle vertex `i`
    /// gets its Voronoi part `(|x_i - x_j|^2 cot theta_k + |x_i - x_k|^2 cot theta_j) / 8`;
    /// in an obtuse one the obtuse vertex gets `A/2`, the others `A/4`. They
    /// partition every triangle, so they sum to [`Mesh::area`].
    ///
    /// These are the areas that turn nodal forces into force densities in the
    /// `membrane` module: the gradient of the surface area is
    /// `2 H n A_mixed + o(A)` (cotangent formula), so `F_i / A_i` converges
    /// pointwise, also at irregular vertices (at the valence-4 vertices of the
    /// octahedron mesh the one-third areas are 1.5 times too small and
    /// `F_i / A_bary` stays 50% off under refinement).
    pub fn vertex_areas(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.vertices.len()];
        for (t, tri) in self.triangles.iter().enumerate() {
            let x = self.corners(t);
            let area = 0.5 * (x[1] - x[0]).cross(&(x[2] - x[0])).norm();
            // cotangent of the angle at each corner
            let cot = |k: usize| {
                let (u, v) = (x[(k + 1) % 3] - x[k], x[(k + 2) % 3] - x[k]);
                u.dot(&v) / u.cross(&v).norm()
            };
            let c = [cot(0), cot(1), cot(2)];
            let obtuse = (0..3).find(|&k| c[k] < 0.0);
            for k in 0..3 {
                let a = match obtuse {
                    None => {
                        let (j, l) = ((k + 1) % 3, (k + 2) % 3);
                        ((x[k] - x[j]).norm_squared() * c[l] + (x[k] - x[l]).norm_squared() * c[j])
                            / 8.0
                    }
                    Some(o) if o == k => area / 2.0,
                    Some(_) => area / 4.0,
                };
                out[tri[k]] += a;
            }
        }
        out
    }

    /// Barycentric vertex areas (um^2): one third of the adjacent triangles.
    /// This is the integral of the vertex's piecewise-linear hat function, so
    /// `sum_i f_i A_i` equals the surface integral of the linear interpolant of
    /// nodal values `f_i`; it sums to [`Mesh::area`].
    pub fn barycentric_vertex_areas(&self) -> Vec<f64> {
        let mut a = vec![0.0; self.vertices.len()];
        for (tri, area) in self.triangles.iter().zip(self.triangle_areas()) {
            for &v in tri {
                a[v] += area / 3.0;
            }
        }
        a
    }

    /// Total area (um^2).
    pub fn area(&self) -> f64 {
        self.triangle_areas().iter().sum()
    }

    /// Enclosed volume (um^3), by the divergence theorem:
    /// `V = sum_t a . (b x c) / 6` (positive for outward orientation).
    pub fn volume(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum()
    }

    /// Centroid of the enclosed volume (um): tetrahedra (origin, a, b, c)
    /// weighted by their signed volumes, `sum_t V_t (a + b + c) / 4 / V`.
    pub fn centroid(&self) -> Vector3<f64> {
        let mut m = Vector3::zeros();
        let mut v = 0.0;
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.corners(t);
            let vt = a.dot(&b.cross(&c)) / 6.0;
            m += vt * (a + b + c) / 4.0;
            v += vt;
        }
        m / v
    }

    /// Unique edges `[a, b]`, `a < b` (see [`Topology`] for full adjacency).
    pub fn edges(&self) -> Vec<[usize; 2]> {
        self.topology().edges
    }

    /// Connectivity (edges, edge/vertex-triangle adjacency, neighbours).
    pub fn topology(&self) -> Topology {
        Topology::new(self)
    }

    /// The mesh rotated about the origin, then translated: `x -> R x + t` (um).
    pub fn transformed(&self, rotation: &Rotation3<f64>, translation: &Vector3<f64>) -> Mesh {
        Mesh {
            vertices: self
                .vertices
                .iter()
                .map(|v| rotation * v + translation)
                .collect(),
            triangles: self.triangles.clone(),
        }
    }

    /// The mesh scaled about the origin by `factor`.
    pub fn scaled(&self, factor: f64) -> Mesh {
        Mesh {
            vertices: self.vertices.iter().map(|v| v * factor).collect(),
            triangles: self.triangles.clone(),
        }
    }

    /// Checks that a deformed mesh is still usable, relative to its reference
    /// (same connectivity): all coordinates finite; no triangle shrunk below
    /// `1e-6` of its reference area; no two adjacent triangles folded onto each
    /// other (normal cosine below `FOLD_COSINE` where the reference's is above).
    /// Returns the first problem found, with its indices.
    pub fn check_deformation(&self, reference: &Mesh) -> Result<(), MeshError> {
        if reference.triangles.len() != self.triangles.len() {
            return Err(MeshError::ConnectivityMismatch {
                expected: reference.triangles.len(),
                found: self.triangles.len(),
            });
        }
        for (i, v) in self.vertices.iter().enumerate() {
            if !v.iter().all(|x| x.is_finite()) {
                return Err(MeshError::NonFiniteVertex {
                    vertex: i,
                    value: [v.x, v.y, v.z],
                });
            }
        }
        let areas = self.triangle_areas();
        let ref_areas = reference.triangle_areas();
        for (t, (&a, &r)) in areas.iter().zip(&ref_areas).enumerate() {
            if a < 1e-6 * r {
                return Err(MeshError::Inverted {
                    triangle: t,
                    area: a,
                    reference: r,
                });
            }
        }
        let normals = self.triangle_normals();
        let ref_normals = reference.triangle_normals();
        let topo = reference.topology();
        for (e, &[t1, t2]) in topo.edge_triangles.iter().enumerate() {
            if t1 == usize::MAX || t2 == usize::MAX {
                continue;
            }
            let cosine = normals[t1].dot(&normals[t2]);
            if cosine < FOLD_COSINE && ref_normals[t1].dot(&ref_normals[t2]) >= FOLD_COSINE {
                let [a, b] = topo.edges[e];
                return Err(MeshError::Folded {
                    t1,
                    t2,
                    a,
                    b,
                    cosine,
                });
            }
        }
        Ok(())
    }

    /// True if [`Mesh::check_deformation`] finds a problem (non-finite vertex,
    /// collapsed or folded triangle).
    pub fn has_inverted_triangles(&self, reference: &Mesh) -> bool {
        self.check_deformation(reference).is_err()
    }
}
