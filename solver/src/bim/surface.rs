//! Geometry a boundary-integral operator needs from a mesh, computed once per solve: flat-triangle normals and areas, vertex normals and areas, vertex-triangle incidence, and the 7-point quadrature nodes laid out in lanes of [`LANES`] (array of structures of arrays).

use nalgebra::Vector3;

use super::kernels::{SourceChunk, LANES};
use super::quadrature::{gauss7, TriangleNode};
use super::BimError;
use crate::mesh::Mesh;

/// Number of quadrature nodes per triangle (the 7-point Gauss rule).
pub const NODES_PER_TRIANGLE: usize = 7;

/// A triangle incident to a vertex, and the corner (0, 1, 2) at which the vertex sits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Incidence {
    pub triangle: usize,
    pub corner: usize,
}

/// Per-mesh data shared by the single- and double-layer operators.
///
/// Lengths in um, areas in um^2. Quadrature node `p = 7 t + k` of triangle `t` lies in
/// lane `p % LANES` of chunk `p / LANES` of [`Surface::chunk_template`]; chunks past the last
/// node are padded with zero weight at a far position (1e30 um), so they add exactly zero.
#[derive(Debug, Clone)]
pub struct Surface {
    pub vertices: Vec<Vector3<f64>>,
    pub triangles: Vec<[usize; 3]>,
    /// Outward unit normal of each flat triangle, `(b - a) x (c - a) / |...|`.
    pub triangle_normals: Vec<Vector3<f64>>,
    /// Area of each triangle (um^2).
    pub triangle_areas: Vec<f64>,
    /// Area-weighted mean of the incident triangle normals, normalised.
    pub vertex_normals: Vec<Vector3<f64>>,
    /// One third of the incident triangle areas (um^2): the weights of the discrete surface
    /// inner product `<a, b> = sum_i A_i a_i . b_i` (exact for the integral of a linear field times a constant).
    pub vertex_areas: Vec<f64>,
    /// CSR incidence: triangles at vertex `i` are `incidence[incidence_start[i]..incidence_start[i+1]]`.
    pub incidence_start: Vec<usize>,
    pub incidence: Vec<Incidence>,
    /// The regular rule (7-point Gauss).
    pub rule: [TriangleNode; NODES_PER_TRIANGLE],
    /// Quadrature positions and `weight * area * normal` (um^2) in lanes; density lanes zeroed.
    pub chunk_template: Vec<SourceChunk>,
    /// Number of real (unpadded) quadrature nodes, `7 * triangles.len()`.
    pub n_nodes: usize,
}

impl Surface {
    /// Validate the mesh (finite positions, valid indices, non-degenerate triangles) and precompute.
    pub fn new(mesh: &Mesh) -> Result<Self, BimError> {
        let nv = mesh.vertices.len();
        if nv == 0 || mesh.triangles.is_empty() {
            return Err(BimError::EmptyMesh);
        }
        for (i, v) in mesh.vertices.iter().enumerate() {
            if !(v.x.is_finite() && v.y.is_finite() && v.z.is_finite()) {
                return Err(BimError::NonFiniteInput { what: "vertex position", vertex: i });
            }
        }
        let nt = mesh.triangles.len();
        let mut triangle_normals = Vec::with_capacity(nt);
        let mut triangle_areas = Vec::with_capacity(nt);
        let mut vertex_normals = vec![Vector3::zeros(); nv];
        let mut vertex_areas = vec![0.0; nv];
        let mut count = vec![0usize; nv + 1];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            if tri.iter().any(|&i| i >= nv) || tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
                return Err(BimError::BadTriangle { triangle: t, reason: "vertex index out of range or repeated" });
            }
            let [a, b, c] = tri.map(|i| mesh.vertices[i]);
            let cross = (b - a).cross(&(c - a));
            let norm = cross.norm();
            let scale = (b - a).norm_squared().max((c - a).norm_squared());
            if norm.is_nan() || norm <= 1e-12 * scale {
                return Err(BimError::BadTriangle { triangle: t, reason: "degenerate (zero area)" });
            }
            let area = 0.5 * norm;
            triangle_normals.push(cross / norm);
            triangle_areas.push(area);
            for &i in tri {
                vertex_normals[i] += cross; // |cross| = 2 area: area weighting
                vertex_areas[i] += area / 3.0;
                count[i + 1] += 1;
            }
        }
        for (i, n) in vertex_normals.iter_mut().enumerate() {
            let norm = n.norm();
            if norm.is_nan() || norm <= 0.0 {
                return Err(BimError::BadVertex { vertex: i, reason: "no incident triangle or cancelling normals" });
            }
            *n /= norm;
        }
        for i in 0..nv {
            count[i + 1] += count[i];
        }
        let incidence_start = count.clone();
        let mut fill = count;
        let mut incidence = vec![Incidence { triangle: 0, corner: 0 }; incidence_start[nv]];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for (corner, &i) in tri.iter().enumerate() {
                incidence[fill[i]] = Incidence { triangle: t, corner };
                fill[i] += 1;
            }
        }

        let rule = gauss7();
        let n_nodes = NODES_PER_TRIANGLE * nt;
        let n_chunks = n_nodes.div_ceil(LANES);
        let mut chunk_template = vec![SourceChunk::padding(); n_chunks];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| mesh.vertices[i]);
            let wn = triangle_normals[t] * triangle_areas[t];
            for (k, node) in rule.iter().enumerate() {
                let p = NODES_PER_TRIANGLE * t + k;
                let y = a * node.bary[0] + b * node.bary[1] + c * node.bary[2];
                let ch = &mut chunk_template[p / LANES];
                let l = p % LANES;
                ch.x[l] = y.x;
                ch.y[l] = y.y;
                ch.z[l] = y.z;
                ch.nx[l] = node.weight * wn.x;
                ch.ny[l] = node.weight * wn.y;
                ch.nz[l] = node.weight * wn.z;
            }
        }
        Ok(Self {
            vertices: mesh.vertices.clone(),
            triangles: mesh.triangles.clone(),
            triangle_normals,
            triangle_areas,
            vertex_normals,
            vertex_areas,
            incidence_start,
            incidence,
            rule,
            chunk_template,
            n_nodes,
        })
    }

    /// Number of vertices (collocation points).
    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Triangles incident to vertex `i`.
    pub fn incident(&self, i: usize) -> &[Incidence] {
        &self.incidence[self.incidence_start[i]..self.incidence_start[i + 1]]
    }

    /// Total area (um^2).
    pub fn area(&self) -> f64 {
        self.triangle_areas.iter().sum()
    }

    /// Area-weighted centroid of the surface (um): the centre of the rigid rotations used by the deflation.
    pub fn centroid(&self) -> Vector3<f64> {
        let mut c = Vector3::zeros();
        for (i, v) in self.vertices.iter().enumerate() {
            c += v * self.vertex_areas[i];
        }
        c / self.vertex_areas.iter().sum::<f64>()
    }

    /// Discrete surface inner product `sum_i A_i a_i . b_i` (um^2 times the units of `a` and `b`).
    pub fn inner(&self, a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
        a.iter().zip(b).zip(&self.vertex_areas).map(|((a, b), w)| w * a.dot(b)).sum()
    }

    /// Copy of the quadrature chunks with the density lanes filled by linear interpolation
    /// of the vertex field `f`, multiplied by `weight * area` when `weighted` (single layer)
    /// or not (double layer, which needs the density itself).
    pub fn chunks_with_density(&self, f: &[Vector3<f64>], weighted: bool) -> Vec<SourceChunk> {
        let mut chunks = self.chunk_template.clone();
        for (t, tri) in self.triangles.iter().enumerate() {
            let [fa, fb, fc] = tri.map(|i| f[i]);
            let area = self.triangle_areas[t];
            for (k, node) in self.rule.iter().enumerate() {
                let p = NODES_PER_TRIANGLE * t + k;
                let mut v = fa * node.bary[0] + fb * node.bary[1] + fc * node.bary[2];
                if weighted {
                    v *= node.weight * area;
                }
                let ch = &mut chunks[p / LANES];
                let l = p % LANES;
                ch.dx[l] = v.x;
                ch.dy[l] = v.y;
                ch.dz[l] = v.z;
            }
        }
        chunks
    }
}
