//! The periodic single layer of a cell at its own vertices and at other points (Ewald sum + normal-part removal + Duffy rule on the touching triangles), shared by the channel and the wall-free periodic box.
//!
//! ```text
//! SL[f](x) = 1/(8 pi) Int_cell G_per(x - y) . f(y) dS_y          (Pa um; divide by mu for um/s)
//! ```
//!
//! At a cell vertex `x_i` the normal part `f(x_i) . n(x_i) n` is removed with
//! `Int_cell G_per . n dS = 0` (the periodic Stokeslet is divergence-free, also without its
//! `k = 0` mode), and on the triangles touching `x_i` the 7-point free-space part is replaced by
//! the Duffy rule (as [`crate::bim::single_layer`]); on the non-touching triangles close to `x_i`
//! the adaptive rule of [`crate::bim::near_field`] corrects it when given. Off the cell the plain
//! 7-point sum is used.

use nalgebra::Vector3;

use super::wall::stokeslet_matrix;
use super::ChannelError;
use crate::bim::kernels::{stokeslet_sum, tiled_sums, LANES};
use crate::bim::near_field::NearField;
use crate::bim::quadrature::{duffy, TriangleNode};
use crate::bim::surface::{Surface, NODES_PER_TRIANGLE};
use crate::ewald::PeriodicStokes;

/// The cell's single layer: at the vertices, at the extra points, and the net force.
#[derive(Debug, Clone)]
pub struct CellSingleLayer {
    /// `SL[f]` at the cell vertices (Pa um).
    pub at_cell: Vec<Vector3<f64>>,
    /// `SL[f]` at the extra targets (Pa um).
    pub at_extra: Vec<Vector3<f64>>,
    /// `Int f dS` (pN) by the 7-point rule.
    pub force: Vector3<f64>,
    /// Ewald sums used.
    pub ewald_sums: usize,
}

/// Quadrature nodes of the cell (7-point rule per flat triangle): positions (um), weighted
/// normals `w_k A_t n_t` (um^2) and the densities interpolated from vertex values.
#[derive(Debug, Clone)]
pub struct CellNodes {
    pub positions: Vec<Vector3<f64>>,
    pub weighted_normals: Vec<Vector3<f64>>,
}

impl CellNodes {
    /// Read the nodes back from the surface's lanes (bit-identical to the free-space kernels).
    pub fn new(surface: &Surface) -> Self {
        let n = surface.n_nodes;
        let mut positions = Vec::with_capacity(n);
        let mut weighted_normals = Vec::with_capacity(n);
        for t in 0..surface.triangles.len() {
            for k in 0..NODES_PER_TRIANGLE {
                let (p, nw) = surface.node(t, k);
                positions.push(p);
                weighted_normals.push(nw);
            }
        }
        Self {
            positions,
            weighted_normals,
        }
    }
}

/// Linear interpolation of the vertex field `u` at the quadrature nodes (unweighted).
pub fn interpolate(surface: &Surface, u: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let mut out = Vec::with_capacity(surface.n_nodes);
    for tri in &surface.triangles {
        let [a, b, c] = tri.map(|i| u[i]);
        for node in surface.rule.iter() {
            out.push(a * node.bary[0] + b * node.bary[1] + c * node.bary[2]);
        }
    }
    out
}

/// The cell's quadrature nodes (um) and their weighted forces `w_k A_t f(y_k)` (pN), `f`
/// interpolated linearly from the vertex tractions (Pa): the sources of the single layer's Ewald
/// sum, in the order of [`CellNodes`].
pub fn weighted_node_forces(surface: &Surface, f: &[Vector3<f64>]) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
    let chunks = surface.chunks_with_density(f, true);
    let mut pos = Vec::with_capacity(surface.n_nodes);
    let mut force = Vec::with_capacity(surface.n_nodes);
    for p in 0..surface.n_nodes {
        let (ch, l) = (&chunks[p / LANES], p % LANES);
        pos.push(Vector3::new(ch.x[l], ch.y[l], ch.z[l]));
        force.push(Vector3::new(ch.dx[l], ch.dy[l], ch.dz[l]));
    }
    (pos, force)
}

/// How the single layer's periodic Stokeslet sum over the cell's nodes is had.
#[derive(Debug, Clone, Copy)]
pub enum StokesletSum<'a> {
    /// A sum of its own ([`PeriodicStokes::stokeslet`]).
    Full(&'a PeriodicStokes),
    /// The real-space part already summed at the cell vertices and the extra targets (in that
    /// order) with the splitting of `ewald`, e.g. fused into the double layer's block build
    /// ([`PeriodicStokes::stresslet_real_blocks_with_single_layer`]) from `nodes`, the
    /// [`weighted_node_forces`] it was summed from; only the Fourier part is added.
    RealDone { ewald: &'a PeriodicStokes, real: &'a [Vector3<f64>], nodes: (&'a [Vector3<f64>], &'a [Vector3<f64>]) },
}

/// `SL[f]` of the cell `surface` at its vertices and at `extra` (see the module docs).
pub fn cell_single_layer(
    ewald: StokesletSum<'_>,
    surface: &Surface,
    f: &[Vector3<f64>],
    extra: &[Vector3<f64>],
    duffy_nodes: (usize, usize),
    subtract_normal_singularity: bool,
    near: Option<&NearField>,
) -> Result<CellSingleLayer, ChannelError> {
    let scale = 1.0 / (8.0 * std::f64::consts::PI);
    let nc = surface.n_vertices();
    let owned;
    let (pos, force) = match ewald {
        StokesletSum::RealDone { nodes, .. } => nodes,
        StokesletSum::Full(_) => {
            owned = weighted_node_forces(surface, f);
            (owned.0.as_slice(), owned.1.as_slice())
        }
    };
    let cell_force = force.iter().sum();
    let mut targets = surface.vertices.clone();
    targets.extend_from_slice(extra);
    let mut out = vec![Vector3::zeros(); targets.len()];
    match ewald {
        StokesletSum::Full(e) => e.stokeslet(&targets, pos, force, &mut out)?,
        StokesletSum::RealDone { ewald, real, .. } => {
            if real.len() != targets.len() {
                return Err(ChannelError::LengthMismatch { what: "real-space single layer", expected: targets.len(), got: real.len() });
            }
            out.copy_from_slice(real);
            ewald.stokeslet_fourier_add(&targets, pos, force, &mut out);
        }
    }
    let sums = 1;
    let alpha: Vec<f64> = if subtract_normal_singularity {
        f.iter()
            .zip(&surface.vertex_normals)
            .map(|(q, n)| q.dot(n))
            .collect()
    } else {
        vec![0.0; nc]
    };
    // `Int_cell G_per . n dS` at the cell vertices by its free-space part alone: the periodic
    // remainder `G_per - G` is smooth and divergence-free, so its integral over the closed
    // polyhedron vanishes (divergence theorem) and the 7-point rule reproduces that zero to
    // ~1e-9 (as for the double layer's `self_sum`, [`super::double_layer`]). A direct sum over
    // the cell's nodes costs a fraction of an Ewald sum (measured in `rbc-bench channel-profile`).
    let mut sn = vec![Vector3::zeros(); nc];
    if subtract_normal_singularity {
        // (the template's density lanes are zero: alpha = -1 sums G . n)
        tiled_sums(&surface.chunk_template, &mut sn, |i, tile| stokeslet_sum(&surface.vertices[i], -1.0, tile));
    }
    let duffy_rule = duffy(duffy_nodes.0.max(1), duffy_nodes.1.max(1));
    let near_corr = match near {
        Some(n) if !n.is_empty() => n.single_layer(f, &alpha),
        _ => vec![Vector3::zeros(); nc],
    };
    let at_cell = (0..nc)
        .map(|i| {
            (out[i] - sn[i] * alpha[i]
                + near_corr[i]
                + touching_correction(surface, &duffy_rule, i, alpha[i], f))
                * scale
        })
        .collect();
    let at_extra = out[nc..].iter().map(|v| v * scale).collect();
    Ok(CellSingleLayer {
        at_cell,
        at_extra,
        force: cell_force,
        ewald_sums: sums,
    })
}

/// Duffy integral minus the 7-point sum of the free-space Stokeslet over the triangles touching
/// cell vertex `i`, for the density `q - alpha n_T` (Pa um, before the `1/(8 pi)`).
fn touching_correction(
    s: &Surface,
    rule: &[TriangleNode],
    i: usize,
    alpha: f64,
    q: &[Vector3<f64>],
) -> Vector3<f64> {
    let x = s.vertices[i];
    let mut corr = Vector3::zeros();
    for inc in s.incident(i) {
        let t = inc.triangle;
        let tri = s.triangles[t];
        let k = inc.corner;
        let (ia, ib, ic) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
        let (a, b, c) = (s.vertices[ia], s.vertices[ib], s.vertices[ic]);
        let n_t = s.triangle_normals[t];
        let area = s.triangle_areas[t];
        let (qa, qb, qc) = (
            q[ia] - n_t * alpha,
            q[ib] - n_t * alpha,
            q[ic] - n_t * alpha,
        );
        let [q0, q1, q2] = tri.map(|v| q[v] - n_t * alpha);
        let [c0, c1, c2] = tri.map(|v| s.vertices[v]);
        for node in s.rule.iter().take(NODES_PER_TRIANGLE) {
            let [l0, l1, l2] = node.bary;
            let y = c0 * l0 + c1 * l1 + c2 * l2;
            corr -=
                stokeslet_matrix(&(x - y)) * ((q0 * l0 + q1 * l1 + q2 * l2) * (node.weight * area));
        }
        for node in rule {
            let [la, lb, lc] = node.bary;
            let r = -((b - a) * lb + (c - a) * lc);
            corr += stokeslet_matrix(&r) * ((qa * la + qb * lb + qc * lc) * (node.weight * area));
        }
    }
    corr
}
