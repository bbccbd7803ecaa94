//! Discrete curvatures at the vertices of a triangle mesh: cotangent Laplace-Beltrami, mean and Gaussian curvature (Meyer et al. 2003).
//!
//! Sign convention (as in [`crate::mesh::shapes`]): `n` outward, `H = div_s(n)/2`
//! positive on a sphere, `K = k1 k2`. On a smooth surface `Lap_s x = -2 H n`.
//!
//! - Laplace-Beltrami (cotangent formula; Pinkall & Polthier 1993, Meyer,
//!   Desbrun, Schroeder & Barr 2003, eq. 8):
//!   `(Lap f)_i = 1/A_i sum_j (cot a_ij + cot b_ij)/2 (f_j - f_i)`,
//!   `a_ij`, `b_ij` the angles opposite edge `ij`, `A_i` the mixed Voronoi area.
//! - Mean curvature: `H_i = -(Lap x)_i . n_i / 2` with the area-weighted vertex
//!   normal `n_i` (the projection keeps the sign where `H` changes sign, as
//!   on the discocyte's dimple).
//! - Gaussian curvature: angle deficit `K_i = (2 pi - sum_t theta_t) / A_i`.
//! - `Lap_s H`: the same cotangent operator applied to the nodal `H`.
//!
//! Together these are "Method C" of Guckenberger, Schraml, Chen, Leonetti &
//! Gekle, Comput. Phys. Commun. 207, 1 (2016), the method of the paper.

use std::f64::consts::PI;

use nalgebra::Vector3;

use crate::mesh::{Mesh, Topology};

/// Cotangent Laplace-Beltrami operator of a mesh state.
#[derive(Debug, Clone)]
pub struct CotangentLaplacian {
    /// Edges `[i, j]` and their weights `(cot a_ij + cot b_ij) / 2` (dimensionless).
    pub edges: Vec<([usize; 2], f64)>,
    /// Mixed Voronoi vertex areas (um^2).
    pub areas: Vec<f64>,
}

impl CotangentLaplacian {
    /// Builds the operator for the current vertex positions.
    pub fn new(mesh: &Mesh) -> CotangentLaplacian {
        Self::with_topology(mesh, &mesh.topology())
    }

    /// [`Self::new`] with the mesh's connectivity given (`topo = mesh.topology()`, which does
    /// not change while the vertices move): the weight of edge `[a, b]` is half the sum of the
    /// cotangents of the angles opposite it in its two triangles.
    pub fn with_topology(mesh: &Mesh, topo: &Topology) -> CotangentLaplacian {
        let edges = topo
            .edges
            .iter()
            .zip(&topo.edge_triangles)
            .map(|(&[a, b], tris)| {
                let mut w = 0.0;
                for &t in tris.iter().filter(|&&t| t != usize::MAX) {
                    let tri = mesh.triangles[t];
                    let x = mesh.corners(t);
                    let k = (0..3).find(|&k| tri[k] != a && tri[k] != b).expect("an edge's triangle has a third corner");
                    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                    let (u, v) = (x[i] - x[k], x[j] - x[k]);
                    w += 0.5 * (u.dot(&v) / u.cross(&v).norm());
                }
                ([a, b], w)
            })
            .collect();
        CotangentLaplacian { edges, areas: mesh.vertex_areas() }
    }

    /// `(Lap f)_i` for nodal values `f` (units of `f` per um^2).
    pub fn apply_scalar(&self, f: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; f.len()];
        for &([i, j], w) in &self.edges {
            let d = w * (f[j] - f[i]);
            out[i] += d;
            out[j] -= d;
        }
        out.iter_mut().zip(&self.areas).for_each(|(o, a)| *o /= a);
        out
    }

    /// `(Lap x)_i` for nodal vectors.
    pub fn apply_vector(&self, f: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let mut out = vec![Vector3::zeros(); f.len()];
        for &([i, j], w) in &self.edges {
            let d = (f[j] - f[i]) * w;
            out[i] += d;
            out[j] -= d;
        }
        out.iter_mut().zip(&self.areas).for_each(|(o, a)| *o /= *a);
        out
    }
}

/// Nodal curvatures of a mesh state.
#[derive(Debug, Clone)]
pub struct VertexCurvatures {
    /// Mean curvature `H` (1/um).
    pub mean: Vec<f64>,
    /// Gaussian curvature `K` (1/um^2).
    pub gaussian: Vec<f64>,
    /// `Lap_s H` (1/um^3).
    pub laplacian_mean: Vec<f64>,
    /// Outward unit normals used.
    pub normals: Vec<Vector3<f64>>,
    /// Vertex areas used (um^2, mixed Voronoi).
    pub areas: Vec<f64>,
}

/// Curvatures by the cotangent formulas (Method C of Guckenberger et al. 2016).
pub fn cotangent_curvatures(mesh: &Mesh) -> VertexCurvatures {
    cotangent_curvatures_with(mesh, &mesh.topology())
}

/// [`cotangent_curvatures`] with the mesh's connectivity given (`topo = mesh.topology()`).
pub fn cotangent_curvatures_with(mesh: &Mesh, topo: &Topology) -> VertexCurvatures {
    let lap = CotangentLaplacian::with_topology(mesh, topo);
    let normals = mesh.vertex_normals();
    let lx = lap.apply_vector(&mesh.vertices);
    let mean: Vec<f64> = lx
        .iter()
        .zip(&normals)
        .map(|(l, n)| -0.5 * l.dot(n))
        .collect();
    let laplacian_mean = lap.apply_scalar(&mean);
    let mut angle_sum = vec![0.0; mesh.vertices.len()];
    for t in 0..mesh.triangles.len() {
        let x = mesh.corners(t);
        for k in 0..3 {
            angle_sum[mesh.triangles[t][k]] +=
                (x[(k + 1) % 3] - x[k]).angle(&(x[(k + 2) % 3] - x[k]));
        }
    }
    let gaussian = angle_sum
        .iter()
        .zip(&lap.areas)
        .map(|(s, a)| (2.0 * PI - s) / a)
        .collect();
    VertexCurvatures {
        mean,
        gaussian,
        laplacian_mean,
        normals,
        areas: lap.areas,
    }
}

/// Monomials `u^p v^q`, `1 <= p + q <= 4`, of the quartic height function
/// (no constant: the patch passes through its vertex).
const QUARTIC: [(i32, i32); 14] = [
    (1, 0),
    (0, 1),
    (2, 0),
    (1, 1),
    (0, 2),
    (3, 0),
    (2, 1),
    (1, 2),
    (0, 3),
    (4, 0),
    (3, 1),
    (2, 2),
    (1, 3),
    (0, 4),
];

/// Width (in units of the local mean edge length) of the Gaussian weights of
/// the least-squares fit: 1-ring points weigh ~0.8, 2-ring points ~0.4.
/// Chosen by the convergence study of `membrane_bending`: on the discocyte at
/// 2048 triangles widths 1.0 to 1.75 give force errors within 15% of each
/// other (max 0.18 to 0.22), while width 2 or no weights are worse (max 0.24
/// and 0.30); the orders do not change.
const FIT_WIDTH: f64 = 1.5;

/// A fitted height function `w = f(u, v) = sum c_k u^p_k v^q_k` in a local
/// frame `(t1, t2, n)`, coordinates scaled by the local edge length.
struct HeightFunction {
    c: [f64; 14],
}

impl HeightFunction {
    /// `(f_u, f_v, f_uu, f_uv, f_vv)` at `(u, v)` (exact polynomial derivatives).
    fn derivatives(&self, u: f64, v: f64) -> [f64; 5] {
        // powers u^(k-2) .. with index k: pu[k] = u^(k-2) for k >= 2, 0 below
        let mut pu = [0.0; 7];
        let mut pv = [0.0; 7];
        pu[2] = 1.0;
        pv[2] = 1.0;
        for k in 3..7 {
            pu[k] = pu[k - 1] * u;
            pv[k] = pv[k - 1] * v;
        }
        let p = |x: &[f64; 7], n: i32| x[(n + 2) as usize];
        let mut d = [0.0; 5];
        for (c, &(a, b)) in self.c.iter().zip(&QUARTIC) {
            let (af, bf) = (a as f64, b as f64);
            d[0] += c * af * p(&pu, a - 1) * p(&pv, b);
            d[1] += c * bf * p(&pu, a) * p(&pv, b - 1);
            d[2] += c * af * (af - 1.0) * p(&pu, a - 2) * p(&pv, b);
            d[3] += c * af * bf * p(&pu, a - 1) * p(&pv, b - 1);
            d[4] += c * bf * (bf - 1.0) * p(&pu, a) * p(&pv, b - 2);
        }
        d
    }

    /// Mean curvature of the graph with `n` along `+w` (outward):
    /// `H = -[(1 + f_v^2) f_uu - 2 f_u f_v f_uv + (1 + f_u^2) f_vv] / (2 W^3)`,
    /// `W = sqrt(1 + f_u^2 + f_v^2)` (do Carmo 3-3; sign so that `H = 1/R` on a sphere).
    fn mean(&self, u: f64, v: f64) -> f64 {
        let [fu, fv, fuu, fuv, fvv] = self.derivatives(u, v);
        let w2 = 1.0 + fu * fu + fv * fv;
        -((1.0 + fv * fv) * fuu - 2.0 * fu * fv * fuv + (1.0 + fu * fu) * fvv)
            / (2.0 * w2.powf(1.5))
    }

    /// Gaussian curvature `(f_uu f_vv - f_uv^2) / W^4`.
    fn gaussian(&self, u: f64, v: f64) -> f64 {
        let [fu, fv, fuu, fuv, fvv] = self.derivatives(u, v);
        let w2 = 1.0 + fu * fu + fv * fv;
        (fuu * fvv - fuv * fuv) / (w2 * w2)
    }

    /// `Lap_s H = (1/W) d_a (W g^{ab} d_b H)` at the origin (metric
    /// `g = I + grad f grad f^T`, `W = sqrt(det g)`), the derivatives of the
    /// exactly evaluated rational function `H(u, v)` by nested central
    /// differences of step `d = 1e-4` (scaled units): truncation O(d^2) ~ 1e-8,
    /// rounding ~1e-16 / d^2 ~ 1e-8 relative, far below the fit error.
    fn laplacian_mean(&self) -> f64 {
        let d = 1e-4;
        let flux = |u: f64, v: f64| -> [f64; 2] {
            let [fu, fv, ..] = self.derivatives(u, v);
            let w = (1.0 + fu * fu + fv * fv).sqrt();
            let hu = (self.mean(u + d, v) - self.mean(u - d, v)) / (2.0 * d);
            let hv = (self.mean(u, v + d) - self.mean(u, v - d)) / (2.0 * d);
            // W g^{-1} grad H with g^{-1} = [[1 + fv^2, -fu fv], [-fu fv, 1 + fu^2]] / W^2
            [
                ((1.0 + fv * fv) * hu - fu * fv * hv) / w,
                (-fu * fv * hu + (1.0 + fu * fu) * hv) / w,
            ]
        };
        let [fu, fv, ..] = self.derivatives(0.0, 0.0);
        let w = (1.0 + fu * fu + fv * fv).sqrt();
        ((flux(d, 0.0)[0] - flux(-d, 0.0)[0]) + (flux(0.0, d)[1] - flux(0.0, -d)[1]))
            / (2.0 * d * w)
    }

    /// Outward unit normal at the origin, in the local frame: `(-f_u, -f_v, 1) / W`.
    fn normal(&self) -> [f64; 3] {
        let [fu, fv, ..] = self.derivatives(0.0, 0.0);
        let w = (1.0 + fu * fu + fv * fv).sqrt();
        [-fu / w, -fv / w, 1.0 / w]
    }
}

/// Vertices within `rings` edges of `i` (excluding `i`), by breadth-first search.
fn k_ring(neighbours: &[Vec<usize>], i: usize, rings: usize) -> Vec<usize> {
    let mut seen = vec![i];
    let mut frontier = vec![i];
    for _ in 0..rings {
        let mut next = Vec::new();
        for &v in &frontier {
            for &w in &neighbours[v] {
                if !seen.contains(&w) {
                    seen.push(w);
                    next.push(w);
                }
            }
        }
        frontier = next;
    }
    seen.remove(0);
    seen
}

/// Curvatures of one vertex by the quartic fit: `(H, K, Lap_s H, n)`.
/// Non-finite values (a degenerate neighbourhood) are returned as NaN so the
/// caller's blow-up detection sees them.
fn fit_vertex(
    mesh: &Mesh,
    neighbours: &[Vec<usize>],
    normal: &Vector3<f64>,
    i: usize,
) -> (f64, f64, f64, Vector3<f64>) {
    fit_vertex_with(mesh, neighbours, normal, i, false)
}

/// [`fit_vertex`], optionally solving the least-squares problem by SVD of the
/// weighted ring matrix instead of the normal equations (for the cross-check test).
fn fit_vertex_with(
    mesh: &Mesh,
    neighbours: &[Vec<usize>],
    normal: &Vector3<f64>,
    i: usize,
    svd: bool,
) -> (f64, f64, f64, Vector3<f64>) {
    let mut ring = k_ring(neighbours, i, 2);
    if ring.len() < 18 {
        ring = k_ring(neighbours, i, 3);
    }
    let x0 = mesh.vertices[i];
    let nz = *normal;
    let t1 = if nz.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let t1 = (t1 - nz * nz.dot(&t1)).normalize();
    let t2 = nz.cross(&t1);
    let nb = &neighbours[i];
    let h = nb
        .iter()
        .map(|&j| (mesh.vertices[j] - x0).norm())
        .sum::<f64>()
        / nb.len() as f64;
    // Weighted least squares by the normal equations (14 x 14, Cholesky): the
    // scaled coordinates keep the Gram matrix's condition number modest (the
    // unit test `normal_equations_agree_with_svd` bounds the difference to an
    // SVD solve), and this is several times faster than an SVD of the ring matrix.
    let mut gram = nalgebra::SMatrix::<f64, 14, 14>::zeros();
    let mut rhs = nalgebra::SVector::<f64, 14>::zeros();
    let mut rows = Vec::new();
    for &j in &ring {
        let d = (mesh.vertices[j] - x0) / h;
        let (u, v) = (d.dot(&t1), d.dot(&t2));
        let weight = (-(u * u + v * v) / (FIT_WIDTH * FIT_WIDTH)).exp(); // squared Gaussian weight
        let row = nalgebra::SVector::<f64, 14>::from_fn(|k, _| {
            u.powi(QUARTIC[k].0) * v.powi(QUARTIC[k].1)
        });
        gram += row * row.transpose() * weight;
        rhs += row * (weight * d.dot(&nz));
        if svd {
            rows.push((row * weight.sqrt(), weight.sqrt() * d.dot(&nz)));
        }
    }
    let c = if svd {
        let a = nalgebra::DMatrix::<f64>::from_fn(rows.len(), 14, |r, k| rows[r].0[k]);
        let b = nalgebra::DVector::<f64>::from_fn(rows.len(), |r, _| rows[r].1);
        match a.svd(true, true).solve(&b, 1e-14) {
            Ok(c) => nalgebra::SVector::<f64, 14>::from_fn(|k, _| c[k]),
            Err(_) => return (f64::NAN, f64::NAN, f64::NAN, nz),
        }
    } else {
        match gram.cholesky() {
            Some(ch) => ch.solve(&rhs),
            None => return (f64::NAN, f64::NAN, f64::NAN, nz),
        }
    };
    let f = HeightFunction {
        c: std::array::from_fn(|k| c[k]),
    };
    let [nu, nv, nw] = f.normal();
    (
        f.mean(0.0, 0.0) / h,
        f.gaussian(0.0, 0.0) / (h * h),
        f.laplacian_mean() / (h * h * h),
        t1 * nu + t2 * nv + nz * nw,
    )
}

/// Curvatures by local quartic fitting (this crate's improvement on Method C,
/// in the spirit of the fitting methods compared by Guckenberger et al. 2016).
///
/// At each vertex, in the frame of its area-weighted normal, the height
/// function `w = f(u, v)`, a quartic without constant term (14 coefficients),
/// is fitted by Gaussian-weighted least squares (`FIT_WIDTH`) to the
/// vertex's 2-ring (3-ring where the 2-ring has fewer than 18 vertices, e.g.
/// at the valence-4 vertices of the octahedron mesh). `H`, `K`, the normal
/// and `Lap_s H` (which needs the 4th derivatives of the surface) are those
/// of the fitted patch at the vertex. Measured pointwise orders on spheroids
/// and the discocyte (test `membrane_bending`): `H`, `K` ~3, `Lap_s H` ~1.2
/// (max) and ~1.7 (L2), at every vertex, unlike the cotangent formulas.
/// Coordinates are scaled by the local mean edge length so that the
/// least-squares problem is well conditioned (normal equations). Vertices are
/// processed in parallel (rayon).
pub fn fitted_curvatures(mesh: &Mesh) -> VertexCurvatures {
    use rayon::prelude::*;
    let topo = mesh.topology();
    let approx_normals = mesh.vertex_normals();
    let per_vertex: Vec<(f64, f64, f64, Vector3<f64>)> = (0..mesh.vertices.len())
        .into_par_iter()
        .map(|i| fit_vertex(mesh, &topo.vertex_neighbours, &approx_normals[i], i))
        .collect();
    VertexCurvatures {
        mean: per_vertex.iter().map(|p| p.0).collect(),
        gaussian: per_vertex.iter().map(|p| p.1).collect(),
        laplacian_mean: per_vertex.iter().map(|p| p.2).collect(),
        normals: per_vertex.iter().map(|p| p.3).collect(),
        areas: mesh.vertex_areas(),
    }
}

/// Consistent (P1 finite-element) mass matrix of a mesh, `M_ij = int phi_i phi_j dA`
/// (um^2): per triangle `A/6` on the diagonal and `A/12` off it.
#[derive(Debug, Clone)]
pub struct MassMatrix {
    diagonal: Vec<f64>,
    /// Edges `[i, j]` (`i < j`) and their entries.
    off: Vec<([usize; 2], f64)>,
}

impl MassMatrix {
    /// Assembles the mass matrix of the current mesh state.
    pub fn new(mesh: &Mesh) -> MassMatrix {
        let topo = mesh.topology();
        let mut index = std::collections::HashMap::with_capacity(topo.edges.len());
        for (e, &[a, b]) in topo.edges.iter().enumerate() {
            index.insert((a, b), e);
        }
        let mut diagonal = vec![0.0; mesh.vertices.len()];
        let mut off = vec![0.0; topo.edges.len()];
        for (tri, area) in mesh.triangles.iter().zip(mesh.triangle_areas()) {
            for k in 0..3 {
                diagonal[tri[k]] += area / 6.0;
                let (a, b) = (tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3]));
                off[index[&(a, b)]] += area / 12.0;
            }
        }
        MassMatrix {
            diagonal,
            off: topo.edges.iter().copied().zip(off).collect(),
        }
    }

    /// `M x`.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut y: Vec<f64> = self.diagonal.iter().zip(x).map(|(d, v)| d * v).collect();
        for &([i, j], m) in &self.off {
            y[i] += m * x[j];
            y[j] += m * x[i];
        }
        y
    }

    /// Solves `M x = b` by Jacobi-preconditioned conjugate gradients to a
    /// relative residual `tol` (the P1 mass matrix is spectrally equivalent to
    /// its diagonal, condition number bounded independently of `h`, so a few
    /// tens of iterations suffice; written here because the alternative, a
    /// sparse Cholesky from faer, would be refactorised at every call).
    pub fn solve(&self, b: &[f64], tol: f64) -> Vec<f64> {
        let n = b.len();
        let mut x: Vec<f64> = b.iter().zip(&self.diagonal).map(|(v, d)| v / d).collect();
        let ax = self.apply(&x);
        let mut r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
        let mut z: Vec<f64> = r.iter().zip(&self.diagonal).map(|(r, d)| r / d).collect();
        let mut p = z.clone();
        let mut rz: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let bnorm = b
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt()
            .max(f64::MIN_POSITIVE);
        for _ in 0..200 {
            if r.iter().map(|v| v * v).sum::<f64>().sqrt() <= tol * bnorm {
                break;
            }
            let ap = self.apply(&p);
            let alpha = rz / p.iter().zip(&ap).map(|(a, b)| a * b).sum::<f64>();
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            z = r.iter().zip(&self.diagonal).map(|(r, d)| r / d).collect();
            let rz_new: f64 = r.iter().zip(&z).map(|(a, b)| a * b).sum();
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                p[i] = z[i] + beta * p[i];
            }
        }
        x
    }
}

/// Galerkin Laplace-Beltrami: `Lap f = M^{-1} L f` with the cotangent
/// stiffness `(L f)_i = sum_j (cot a_ij + cot b_ij)/2 (f_j - f_i)` and the
/// consistent mass matrix `M` (the P1 finite-element Laplacian), instead of
/// the lumped `A_i^{-1} L f` of the cotangent formula.
pub fn galerkin_laplacian(mesh: &Mesh, f: &[f64]) -> Vec<f64> {
    let lap = CotangentLaplacian::new(mesh);
    let lumped = lap.apply_scalar(f);
    let lf: Vec<f64> = lumped.iter().zip(&lap.areas).map(|(l, a)| l * a).collect();
    MassMatrix::new(mesh).solve(&lf, 1e-12)
}

/// Quartic-fit `H`, `K`, normals, with `Lap_s H` by the Galerkin Laplacian of the fitted `H`.
pub fn fitted_galerkin_curvatures(mesh: &Mesh) -> VertexCurvatures {
    let mut c = fitted_curvatures(mesh);
    c.laplacian_mean = galerkin_laplacian(mesh, &c.mean);
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh;

    /// The normal-equation solve of the fits agrees with an SVD solve (relative
    /// difference below 1e-10 for H and 1e-5 for Lap_s H on the paper's discocyte mesh and
    /// a coarse one, far below the discretisation errors of ~1e-3 and ~1e-1).
    #[test]
    fn normal_equations_agree_with_svd() {
        for level in [2, 4] {
            let m = mesh::discocyte(level);
            let topo = m.topology();
            let normals = m.vertex_normals();
            let (mut dh, mut dl) = (0.0f64, 0.0f64);
            for (i, normal) in normals.iter().enumerate() {
                let a = fit_vertex_with(&m, &topo.vertex_neighbours, normal, i, false);
                let b = fit_vertex_with(&m, &topo.vertex_neighbours, normal, i, true);
                dh = dh.max((a.0 - b.0).abs() / b.0.abs().max(0.1));
                dl = dl.max((a.2 - b.2).abs() / b.2.abs().max(0.1));
            }
            assert!(dh < 1e-10 && dl < 1e-5, "level {level}: {dh:e} {dl:e}");
        }
    }

    /// Cotangent Laplacian of a linear function on a flat mesh is zero, and
    /// the Galerkin Laplacian of a constant is zero (exact identities).
    #[test]
    fn laplacians_annihilate_what_they_must() {
        let m = mesh::sphere(3, 2.0);
        let ones = vec![1.0; m.vertices.len()];
        assert!(galerkin_laplacian(&m, &ones).iter().all(|v| v.abs() < 1e-9));
        let lap = CotangentLaplacian::new(&m);
        assert!(lap.apply_scalar(&ones).iter().all(|v| v.abs() < 1e-12));
        // mass matrix: sum of all entries = area
        let mm = MassMatrix::new(&m);
        let total: f64 = mm.apply(&ones).iter().sum();
        assert!((total - m.area()).abs() < 1e-10 * m.area());
        // solve inverts apply
        let x: Vec<f64> = m.vertices.iter().map(|p| p.x * p.y + p.z).collect();
        let y = mm.solve(&mm.apply(&x), 1e-13);
        assert!(x.iter().zip(&y).all(|(a, b)| (a - b).abs() < 1e-9));
    }
}
