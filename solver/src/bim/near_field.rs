//! Near-singular quadrature: accurate integrals over the membrane's own triangles that lie close to a target vertex without touching it, as a block-sparse correction of the 7-point sums.
//!
//! The 7-point rule integrates `G(x - y) q(y)` and `T(x - y) . n` with an error that grows like
//! `(h / d)^6` when a target `x` is at a distance `d` of order the triangle size `h` from a
//! triangle. That happens on the same sheet (the ring of triangles just beyond the ones touching
//! `x`: `d ~ h`, the first-order error of `Int G . n dS = 0` measured in
//! [`super::single_layer`]) and, worse, when two parts of the membrane come close: the two
//! dimples of a folding croissant approach to less than one edge (the science runs of the
//! channel stalled there, with step sizes collapsing to 1e-7 s; `README`, "Measured").
//!
//! For each target vertex `x_i` and each triangle `t` not incident to it whose lower distance
//! bound `|x_i - c_t| - R_t` (centroid `c_t`, circumradius about the centroid `R_t`) is below
//! `reach` times its longest edge, the integrals of the linear basis functions `phi_c` (corners
//! `c` of `t`) against the free-space kernels
//!
//! ```text
//! S_itc = Int_t G(x_i - y) phi_c(y) dS_y           (3x3, um; G = I/r + r r^T/r^3)
//! D_itc = Int_t M(x_i - y) phi_c(y) dS_y           (3x3, 1;  M = 6 (r . n_t) r r^T / r^5)
//! ```
//!
//! are computed by adaptive subdivision (each triangle split into four at its edge midpoints
//! until a piece's longest edge is below `eta` times its centroid distance to `x_i`, or
//! `max_depth` is reached; the 7-point rule on each piece), and the 7-point values on the whole
//! triangle are subtracted. The corrections are linear in the vertex densities and are stored
//! as 3x3 blocks per (target, source vertex):
//!
//! - single layer, density `q - alpha_i n_t` (the normal-part subtraction of
//!   [`super::single_layer`], `alpha_i = q_i . n_i`):
//!   `dSL_i = sum_t sum_c dS_itc q_c - alpha_i sum_t (sum_c dS_itc) n_t` (Pa um, before `1/(8 pi)`);
//! - double layer with the density subtracted at the target ([`super::double_layer`]):
//!   `dDL_i = sum_t sum_c dD_itc (u_c - u_i)` (units of `u`, before `1/(4 pi)`),
//!
//! where `d` is "adaptive minus 7-point". Only free-space kernels appear, so the same blocks
//! correct the periodic operators of [`crate::channel`]: the periodic kernels differ from the
//! free-space ones by a smooth part that the 7-point rule integrates accurately.
//!
//! Reference for the method: adaptive panel subdivision for nearly singular boundary integrals
//! (e.g. Zhao, Isfahani, Olson & Freund, J. Comput. Phys. 229, 3726 (2010), section 3.3, who
//! refine source triangles near a target; Pozrikidis 1992, ch. 6.4). Hand-written because no
//! crate of the workspace offers triangle quadrature.

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use super::surface::{Surface, NODES_PER_TRIANGLE};

/// When a triangle counts as near, and how finely it is subdivided.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NearFieldOptions {
    /// A non-touching triangle is corrected when `|x - c_t| - R_t < reach * h_t`
    /// (`h_t` its longest edge). 0 switches the correction off.
    pub reach: f64,
    /// A piece is accepted when its longest edge is below `eta` times the distance of its centroid from the target.
    pub eta: f64,
    /// Maximum number of four-way splits of one triangle.
    pub max_depth: u32,
    /// Triangles that touch a vertex within `skip_rings - 1` edges of the target are left to
    /// the 7-point rule (1: only the touching triangles, which the Duffy rule handles; 2: also
    /// the next ring of the same sheet, whose near-singular error is small and smooth, so that
    /// only other parts of the membrane, e.g. a facing dimple, are corrected).
    pub skip_rings: usize,
}

impl Default for NearFieldOptions {
    /// `reach` 1, `eta` 0.5, `max_depth` 6, `skip_rings` 2. Measured (`rbc-bench near-field`, one
    /// core, side by side, lambda = 5 channel, discocyte on the axis): 8.8 / 7.0 pairs per vertex
    /// at 512 / 2048 triangles, 4.2 pieces per pair, under 1 ms / 8 ms to build, a cold solve
    /// within the timing noise (+-5 %) of the uncorrected one, the velocity changed by 3e-6 /
    /// 5e-7 of its maximum. With the next ring (`skip_rings` 1): 26 / 24 pairs per vertex, 8 / 32 ms,
    /// +4-6 %, velocity changed by 5.6e-5 / 2.6e-5. Accuracy: `solver/tests/near_field.rs` and
    /// the tests below.
    fn default() -> Self {
        Self { reach: 1.0, eta: 0.5, max_depth: 6, skip_rings: 2 }
    }
}

impl NearFieldOptions {
    /// Correct the same sheet's next ring too (`skip_rings` 1): the quadrature error of the
    /// 7-point rule next to the touching triangles (first order in h) drops ~150-fold.
    pub fn with_next_ring() -> Self {
        Self { skip_rings: 1, ..Self::default() }
    }

    /// No correction (the plain 7-point rule everywhere but on the touching triangles).
    pub fn off() -> Self {
        Self { reach: 0.0, ..Self::default() }
    }

    /// Whether any triangle can be corrected.
    pub fn is_on(&self) -> bool {
        self.reach > 0.0
    }
}

/// One row block: source vertex `j` and the blocks of the single and double layer.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Block {
    source: usize,
    sl: Matrix3<f64>,
    dl: Matrix3<f64>,
}

/// One target's blocks, its `sl_normal` and `dl_self` terms, its corrected pairs and pieces.
type TargetRow = (Vec<Block>, Vector3<f64>, Matrix3<f64>, usize, usize);

/// The near-field correction of one surface: block-sparse rows over the target vertices (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct NearField {
    rows: Vec<Vec<Block>>,
    /// `sum_t (sum_c dS_itc) n_t` per target (um): the correction of the normal-part subtraction.
    sl_normal: Vec<Vector3<f64>>,
    /// `sum_t sum_c dD_itc` per target: the correction of the density subtracted at the target.
    dl_self: Vec<Matrix3<f64>>,
    /// Corrected (target, triangle) pairs, and the 7-point pieces the adaptive rule used.
    pairs: usize,
    pieces: usize,
}

/// Integrals over one triangle against the basis functions: `[S_c]`, `[D_c]` (adaptive minus 7-point).
struct TriangleIntegrals {
    sl: [Matrix3<f64>; 3],
    dl: [Matrix3<f64>; 3],
    pieces: usize,
}

impl NearField {
    /// Find the near pairs of `surface` and integrate them (parallel over targets, rayon).
    /// With `opts.reach <= 0` the result is empty and [`Self::is_empty`].
    pub fn new(surface: &Surface, opts: &NearFieldOptions) -> Self {
        let nv = surface.n_vertices();
        if !opts.is_on() {
            return Self { rows: vec![Vec::new(); nv], sl_normal: vec![Vector3::zeros(); nv], dl_self: vec![Matrix3::zeros(); nv], ..Self::default() };
        }
        let geo = TriangleGeometry::new(surface);
        let grid = CentroidGrid::new(&geo, opts.reach);
        let per_target: Vec<TargetRow> = (0..nv)
            .into_par_iter()
            .with_min_len(8)
            .map(|i| {
                let x = surface.vertices[i];
                let skipped = skipped_triangles(surface, i, opts.skip_rings);
                let mut blocks: Vec<Block> = Vec::new();
                let mut sl_normal = Vector3::zeros();
                let mut dl_self = Matrix3::zeros();
                let (mut pairs, mut pieces) = (0, 0);
                grid.for_candidates(&x, |t| {
                    if skipped.contains(&t) || geo.lower_distance(&x, t) >= opts.reach * geo.longest_edge[t] {
                        return;
                    }
                    let ti = triangle_integrals(surface, t, &x, opts);
                    pairs += 1;
                    pieces += ti.pieces;
                    let n_t = surface.triangle_normals[t];
                    for (c, &j) in surface.triangles[t].iter().enumerate() {
                        sl_normal += ti.sl[c] * n_t;
                        dl_self += ti.dl[c];
                        match blocks.iter_mut().find(|b| b.source == j) {
                            Some(b) => {
                                b.sl += ti.sl[c];
                                b.dl += ti.dl[c];
                            }
                            None => blocks.push(Block { source: j, sl: ti.sl[c], dl: ti.dl[c] }),
                        }
                    }
                });
                blocks.sort_by_key(|b| b.source);
                (blocks, sl_normal, dl_self, pairs, pieces)
            })
            .collect();
        let mut me = Self::default();
        for (blocks, n, d, pairs, pieces) in per_target {
            me.rows.push(blocks);
            me.sl_normal.push(n);
            me.dl_self.push(d);
            me.pairs += pairs;
            me.pieces += pieces;
        }
        me
    }

    /// True when no pair is corrected.
    pub fn is_empty(&self) -> bool {
        self.pairs == 0
    }

    /// Corrected (target vertex, triangle) pairs.
    pub fn pairs(&self) -> usize {
        self.pairs
    }

    /// 7-point pieces used by the adaptive rule in all.
    pub fn pieces(&self) -> usize {
        self.pieces
    }

    /// `dSL_i` (Pa um, before `1/(8 pi)`) for the vertex density `q` (Pa) and the normal parts
    /// `alpha_i` subtracted at each target (Pa; all zero without the subtraction).
    pub fn single_layer(&self, q: &[Vector3<f64>], alpha: &[f64]) -> Vec<Vector3<f64>> {
        self.rows
            .iter()
            .zip(&self.sl_normal)
            .zip(alpha)
            .map(|((row, n), a)| row.iter().map(|b| b.sl * q[b.source]).sum::<Vector3<f64>>() - n * *a)
            .collect()
    }

    /// `dDL_i` (units of `u`, before `1/(4 pi)`) for the vertex field `u`.
    pub fn double_layer(&self, u: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        self.rows
            .iter()
            .zip(&self.dl_self)
            .zip(u)
            .map(|((row, d), ui)| row.iter().map(|b| b.dl * u[b.source]).sum::<Vector3<f64>>() - d * ui)
            .collect()
    }

    /// Add `scale * dDL` to `out` (for the operators applied inside GMRES: no allocation).
    pub fn add_double_layer(&self, u: &[Vector3<f64>], scale: f64, out: &mut [Vector3<f64>]) {
        if self.is_empty() {
            return;
        }
        for (i, o) in out.iter_mut().enumerate().take(self.rows.len()) {
            let v: Vector3<f64> = self.rows[i].iter().map(|b| b.dl * u[b.source]).sum::<Vector3<f64>>() - self.dl_self[i] * u[i];
            *o += v * scale;
        }
    }
}

/// Triangles touching a vertex within `rings - 1` edges of vertex `i` (at least the incident ones).
fn skipped_triangles(s: &Surface, i: usize, rings: usize) -> Vec<usize> {
    let mut verts = vec![i];
    let mut frontier = vec![i];
    for _ in 1..rings.max(1) {
        let mut next = Vec::new();
        for &v in &frontier {
            for inc in s.incident(v) {
                for &w in &s.triangles[inc.triangle] {
                    if !verts.contains(&w) {
                        verts.push(w);
                        next.push(w);
                    }
                }
            }
        }
        frontier = next;
    }
    let mut tris: Vec<usize> = verts.iter().flat_map(|&v| s.incident(v).iter().map(|inc| inc.triangle)).collect();
    tris.sort_unstable();
    tris.dedup();
    tris
}

/// Centroids, circumradii about the centroid and longest edges of the flat triangles.
struct TriangleGeometry {
    centroid: Vec<Vector3<f64>>,
    radius: Vec<f64>,
    longest_edge: Vec<f64>,
}

impl TriangleGeometry {
    fn new(s: &Surface) -> Self {
        let mut g = Self { centroid: Vec::new(), radius: Vec::new(), longest_edge: Vec::new() };
        for tri in &s.triangles {
            let [a, b, c] = tri.map(|i| s.vertices[i]);
            let m = (a + b + c) / 3.0;
            g.centroid.push(m);
            g.radius.push((a - m).norm().max((b - m).norm()).max((c - m).norm()));
            g.longest_edge.push((b - a).norm().max((c - b).norm()).max((a - c).norm()));
        }
        g
    }

    /// A lower bound of the distance from `x` to triangle `t`.
    fn lower_distance(&self, x: &Vector3<f64>, t: usize) -> f64 {
        (x - self.centroid[t]).norm() - self.radius[t]
    }
}

/// Triangle centroids binned on a uniform grid whose cell is at least the largest search radius
/// `R_t + reach h_t`, so that the candidates of a target lie in its 27 neighbouring cells.
/// (A uniform grid suffices: the membrane's triangles have similar sizes.)
struct CentroidGrid {
    origin: Vector3<f64>,
    cell: f64,
    dims: [usize; 3],
    start: Vec<usize>,
    items: Vec<usize>,
}

impl CentroidGrid {
    fn new(g: &TriangleGeometry, reach: f64) -> Self {
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for c in &g.centroid {
            lo = lo.inf(c);
            hi = hi.sup(c);
        }
        // At least the search radius; at most 1024 cells along an axis (then larger cells).
        let cell = g
            .radius
            .iter()
            .zip(&g.longest_edge)
            .map(|(r, h)| r + reach * h)
            .fold(0.0, f64::max)
            .max((hi - lo).max() / 1024.0)
            .max(1e-12);
        let dims = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / cell).floor() as usize + 1);
        let n_cells = dims[0] * dims[1] * dims[2];
        let mut me = Self { origin: lo, cell, dims, start: vec![0; n_cells + 1], items: vec![0; g.centroid.len()] };
        let keys: Vec<usize> = g.centroid.iter().map(|c| me.key(me.coords(c))).collect();
        for &k in &keys {
            me.start[k + 1] += 1;
        }
        for k in 0..n_cells {
            me.start[k + 1] += me.start[k];
        }
        let mut fill = me.start.clone();
        for (t, &k) in keys.iter().enumerate() {
            me.items[fill[k]] = t;
            fill[k] += 1;
        }
        me
    }

    fn coords(&self, x: &Vector3<f64>) -> [i64; 3] {
        [0, 1, 2].map(|k| (((x[k] - self.origin[k]) / self.cell).floor() as i64).clamp(0, self.dims[k] as i64 - 1))
    }

    fn key(&self, c: [i64; 3]) -> usize {
        (c[0] as usize * self.dims[1] + c[1] as usize) * self.dims[2] + c[2] as usize
    }

    /// Call `f` with every triangle whose centroid lies in the cells around `x`.
    fn for_candidates(&self, x: &Vector3<f64>, mut f: impl FnMut(usize)) {
        // Points beyond the box are clamped to its border cells; a triangle is then still found
        // when it is within one cell of x, since the distance test is done by the caller.
        let c = [0, 1, 2].map(|k| ((x[k] - self.origin[k]) / self.cell).floor() as i64);
        for i in c[0] - 1..=c[0] + 1 {
            for j in c[1] - 1..=c[1] + 1 {
                for k in c[2] - 1..=c[2] + 1 {
                    let cc = [i, j, k];
                    if (0..3).any(|d| cc[d] < 0 || cc[d] >= self.dims[d] as i64) {
                        continue;
                    }
                    let key = self.key(cc);
                    for &t in &self.items[self.start[key]..self.start[key + 1]] {
                        f(t);
                    }
                }
            }
        }
    }
}

/// `G(r)` and `M(r) = 6 (r . n) r r^T / r^5` at one point.
#[inline]
fn kernels(r: &Vector3<f64>, n: &Vector3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let r2 = r.norm_squared();
    let ir = 1.0 / r2.sqrt();
    let ir3 = ir * ir * ir;
    let rr = r * r.transpose();
    let g = Matrix3::identity() * ir + rr * ir3;
    let m = rr * (6.0 * r.dot(n) * ir3 * ir * ir);
    (g, m)
}

/// Adaptive minus 7-point integrals of triangle `t` against its three basis functions, seen from `x`.
fn triangle_integrals(s: &Surface, t: usize, x: &Vector3<f64>, opts: &NearFieldOptions) -> TriangleIntegrals {
    let tri = s.triangles[t];
    let corners = tri.map(|i| s.vertices[i]);
    let n = s.triangle_normals[t];
    let area = s.triangle_areas[t];
    let mut out = TriangleIntegrals { sl: [Matrix3::zeros(); 3], dl: [Matrix3::zeros(); 3], pieces: 0 };
    // Minus the 7-point rule on the whole triangle, at the very nodes the vectorised sums use.
    for k in 0..NODES_PER_TRIANGLE {
        let (y, _) = s.node(t, k);
        let node = s.rule[k];
        let (g, m) = kernels(&(x - y), &n);
        for c in 0..3 {
            let w = node.weight * area * node.bary[c];
            out.sl[c] -= g * w;
            out.dl[c] -= m * w;
        }
    }
    // Plus the adaptive rule: pieces given by the barycentric coordinates of their corners.
    let identity = [Vector3::x(), Vector3::y(), Vector3::z()];
    subdivide(s, &corners, &n, area, x, identity, 0, opts, &mut out);
    out
}

/// Integrate the piece with corner barycentrics `l` (in the parent triangle) or split it.
#[allow(clippy::too_many_arguments)]
fn subdivide(
    s: &Surface,
    corners: &[Vector3<f64>; 3],
    n: &Vector3<f64>,
    parent_area: f64,
    x: &Vector3<f64>,
    l: [Vector3<f64>; 3],
    depth: u32,
    opts: &NearFieldOptions,
    out: &mut TriangleIntegrals,
) {
    let pos = |b: &Vector3<f64>| corners[0] * b.x + corners[1] * b.y + corners[2] * b.z;
    let p = l.map(|b| pos(&b));
    let longest = (p[1] - p[0]).norm().max((p[2] - p[1]).norm()).max((p[0] - p[2]).norm());
    let dist = (x - (p[0] + p[1] + p[2]) / 3.0).norm();
    if longest < opts.eta * dist || depth >= opts.max_depth {
        let piece_area = parent_area / f64::from(1u32 << (2 * depth));
        for node in s.rule.iter() {
            let b = l[0] * node.bary[0] + l[1] * node.bary[1] + l[2] * node.bary[2];
            let (g, m) = kernels(&(x - pos(&b)), n);
            for c in 0..3 {
                let w = node.weight * piece_area * b[c];
                out.sl[c] += g * w;
                out.dl[c] += m * w;
            }
        }
        out.pieces += 1;
        return;
    }
    let m01 = (l[0] + l[1]) * 0.5;
    let m12 = (l[1] + l[2]) * 0.5;
    let m20 = (l[2] + l[0]) * 0.5;
    for piece in [[l[0], m01, m20], [m01, l[1], m12], [m20, m12, l[2]], [m12, m20, m01]] {
        subdivide(s, corners, n, parent_area, x, piece, depth + 1, opts, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::sphere;

    /// Two parallel unit squares (two triangles each) a distance `d` apart: the near-field
    /// correction makes the 7-point sum of the upper sheet at a vertex of the lower one equal
    /// to a deep reference (the same adaptive rule with `eta` 0.05): the correction blocks are
    /// checked against an independent brute-force integral on a 64 x 64 refined grid of pieces.
    #[test]
    fn correction_reaches_a_brute_force_integral() {
        // Lower sheet: a big triangle pair (the target vertex at the origin); upper sheet at height d.
        let d = 0.3;
        let mesh = crate::mesh::Mesh {
            vertices: vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(5.0, 0.0, 0.0),
                Vector3::new(0.0, 5.0, 0.0),
                Vector3::new(-0.4, -0.3, d),
                Vector3::new(0.6, -0.3, d),
                Vector3::new(-0.4, 0.7, d),
            ],
            // Lower triangle oriented +z, upper one -z (the sheets face each other).
            triangles: vec![[0, 1, 2], [3, 5, 4]],
        };
        let s = Surface::new(&mesh).unwrap();
        let nf = NearField::new(&s, &NearFieldOptions::default());
        // Target 0 sees triangle 1 (not incident).
        let q: Vec<Vector3<f64>> = vec![Vector3::zeros(), Vector3::zeros(), Vector3::zeros(), Vector3::new(1.0, 0.5, -0.2), Vector3::new(-0.3, 0.8, 0.1), Vector3::new(0.2, -0.6, 0.9)];
        let corr = nf.single_layer(&q, &[0.0; 6])[0];
        let dcorr = nf.double_layer(&q)[0];
        // Brute force: 7-point rule on a uniform 4^6 refinement of triangle 1, minus the plain 7-point rule.
        let (mut fine, mut fine_dl) = (Vector3::zeros(), Vector3::zeros());
        let (mut coarse, mut coarse_dl) = (Vector3::zeros(), Vector3::zeros());
        let x = s.vertices[0];
        let tri = s.triangles[1];
        let [a, b, c] = tri.map(|i| s.vertices[i]);
        let [qa, qb, qc] = tri.map(|i| q[i]);
        let n_t = s.triangle_normals[1];
        let area = s.triangle_areas[1];
        let m = 64usize;
        for i in 0..m {
            for j in 0..m - i {
                for up in [true, false] {
                    if !up && i + j + 1 >= m {
                        continue;
                    }
                    let (fi, fj) = (i as f64, j as f64);
                    let mf = m as f64;
                    let corners = if up {
                        [(fi, fj), (fi + 1.0, fj), (fi, fj + 1.0)]
                    } else {
                        [(fi + 1.0, fj), (fi + 1.0, fj + 1.0), (fi, fj + 1.0)]
                    };
                    for node in s.rule.iter() {
                        let (u, v) = corners
                            .iter()
                            .zip(node.bary)
                            .fold((0.0, 0.0), |(u, v), ((cu, cv), w)| (u + cu * w / mf, v + cv * w / mf));
                        let y = a + (b - a) * u + (c - a) * v;
                        let qy = qa * (1.0 - u - v) + qb * u + qc * v;
                        let w = node.weight * area / (mf * mf);
                        let (g, mm) = kernels(&(x - y), &n_t);
                        fine += g * qy * w;
                        fine_dl += mm * qy * w;
                    }
                }
            }
        }
        for k in 0..NODES_PER_TRIANGLE {
            let node = s.rule[k];
            let (y, _) = s.node(1, k);
            let qy = qa * node.bary[0] + qb * node.bary[1] + qc * node.bary[2];
            let (g, mm) = kernels(&(x - y), &n_t);
            coarse += g * qy * (node.weight * area);
            coarse_dl += mm * qy * (node.weight * area);
        }
        let want = fine - coarse;
        let want_dl = fine_dl - coarse_dl;
        eprintln!("SL correction {corr:?} vs brute force {want:?}; DL {dcorr:?} vs {want_dl:?}; 7-point SL {coarse:?} vs {fine:?}");
        // The correction is a large part of the integral at d/h = 0.3 (the plain rule is off by tens of percent) ...
        assert!(want.norm() > 0.05 * fine.norm(), "{want} {fine}");
        // ... and the adaptive rule reproduces it to 1e-3 of the integral (SL) and 1e-2 (DL, 1/r^2 kernel).
        assert!((corr - want).norm() < 1e-3 * fine.norm(), "{corr} vs {want}");
        assert!((dcorr - want_dl).norm() < 1e-2 * fine_dl.norm(), "{dcorr} vs {want_dl}");
    }

    /// On a sphere the pairs are the same sheet's next ring when it is included, none by default
    /// (no other part of the membrane comes within an edge), and none when switched off.
    #[test]
    fn pairs_on_a_sphere_are_the_next_rings() {
        let s = Surface::new(&sphere(3, 1.0)).unwrap();
        let nf = NearField::new(&s, &NearFieldOptions::with_next_ring());
        let per_target = nf.pairs() as f64 / s.n_vertices() as f64;
        eprintln!("sphere level 3: {} pairs ({per_target:.1} per target), {} pieces", nf.pairs(), nf.pieces());
        assert!(per_target > 5.0 && per_target < 40.0, "{per_target}");
        // Without the next ring: the triangles at one edge's distance that touch no neighbour of the target.
        let default = NearField::new(&s, &NearFieldOptions::default());
        assert!(default.pairs() < nf.pairs() / 2, "{} vs {}", default.pairs(), nf.pairs());
        assert!(NearField::new(&s, &NearFieldOptions::off()).is_empty());
    }

    /// The grid finds exactly the pairs of a brute-force search over all (target, triangle)
    /// pairs, on a thin spheroid whose faces are within reach of each other.
    #[test]
    fn grid_search_finds_every_near_pair() {
        let s = Surface::new(&crate::mesh::spheroid(3, 4.0, 0.3)).unwrap();
        for opts in [NearFieldOptions::default(), NearFieldOptions::with_next_ring(), NearFieldOptions { reach: 2.5, ..NearFieldOptions::default() }] {
            let geo = TriangleGeometry::new(&s);
            let mut brute = 0;
            for i in 0..s.n_vertices() {
                let skipped = skipped_triangles(&s, i, opts.skip_rings);
                for t in 0..s.triangles.len() {
                    if !skipped.contains(&t) && geo.lower_distance(&s.vertices[i], t) < opts.reach * geo.longest_edge[t] {
                        brute += 1;
                    }
                }
            }
            let nf = NearField::new(&s, &opts);
            assert!(brute > 0);
            assert_eq!(nf.pairs(), brute, "{opts:?}");
        }
    }
}
