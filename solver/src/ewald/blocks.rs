//! Real-space Ewald sums frozen into block-sparse matrices over a nodal basis: for sources that are quadrature nodes of linearly interpolated densities, the real-space part of a Stokeslet or stresslet sum is a fixed linear map from the nodal values to the targets, built once and applied as a mat-vec.
//!
//! Source `k` carries the density `sum_{(v, l) in interp_k} l q_v` (nodal values `q_v`, barycentric
//! weights `l`), times a scalar quadrature weight `w_k` (Stokeslet) or with a weighted normal `n_k`
//! (stresslet). The real-space kernels of [`super::split`] then give, for each target `i` and node `v`,
//! a 3 x 3 block `B_iv` with `out_i = sum_v B_iv q_v`:
//!
//! ```text
//! Stokeslet:  B_iv = sum_k l_kv w_k [a(r) I + b(r) r r^T]                       (r = x_i - y_k, |r| < r_cut)
//! stresslet:  B_iv = sum_k l_kv [B(r) (r . n_k) r r^T + A(r) (r n_k^T + (r . n_k) I + n_k r^T)]
//! ```
//!
//! the same sums as [`super::real_space`] regrouped (equal up to rounding, test `blocks_match_real_space`).
//! Both kernels are symmetric 3 x 3 matrices, so every block is: it is built and stored as its
//! upper triangle ([`Sym`], 6 numbers instead of 9: a third less kernel assembly, memory and
//! mat-vec traffic).
//! Within one boundary-integral solve the geometry is fixed while GMRES applies the sums ~10
//! times: one build (a real-space sum's work plus 18 multiply-adds per pair) replaces them all, and
//! each application costs `9 x` (number of blocks) multiply-adds.

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use super::erfc::Erfcx;
use super::lanes::{GroupAtTarget, Kernel, NodeLanes, Sym, WeightedLanes, LANES, SYM_PQ};
use super::lanes32::{BlockPrecision, ErfcxF32};
use super::real_space::CellList;
use super::split::{erfc_and_gauss, stokeslet_ab, stresslet_ab};

/// Barycentric interpolation of a source node from (up to) three nodal values: `(node index, weight)`.
pub type Interp = [(usize, f64); 3];

/// One target's row while it is built: dense accumulators over the basis and the nodes touched,
/// and the real-space single layer a fused build sums beside it.
struct RowAcc {
    acc: Vec<Sym>,
    seen: Vec<bool>,
    touched: Vec<u32>,
    single: [f64; 3],
    /// A source group (shifted target, sorted group) waiting for a second one to share a
    /// 16-lane single-precision evaluation ([`BlockPrecision::Single`]).
    pending: Option<([f64; 3], usize)>,
}

/// One target's finished row: its columns, blocks and fused single-layer sum.
type Row = (Vec<u32>, Vec<Sym>, [f64; 3]);

impl RowAcc {
    /// `B_v += l K`.
    #[inline(always)]
    fn add(&mut self, v: usize, l: f64, k: &Sym) {
        if !self.seen[v] {
            self.seen[v] = true;
            self.touched.push(v as u32);
        }
        for (c, kc) in self.acc[v].iter_mut().zip(k) {
            *c = l.mul_add(*kc, *c);
        }
    }

    /// The touched blocks in column order and the single-layer sum; leaves the accumulators zeroed for the next row.
    fn take(&mut self) -> Row {
        self.touched.sort_unstable();
        let blocks: Vec<Sym> = self
            .touched
            .iter()
            .map(|&v| {
                self.seen[v as usize] = false;
                std::mem::replace(&mut self.acc[v as usize], [0.0; 6])
            })
            .collect();
        (std::mem::take(&mut self.touched), blocks, std::mem::take(&mut self.single))
    }
}

/// Block-sparse matrix of symmetric 3 x 3 blocks: row `i` (a target) holds the blocks `blocks[j]` for the basis nodes `cols[j]`, `j in start[i]..start[i + 1]`.
#[derive(Debug, Clone, Default)]
pub struct BlockRows {
    start: Vec<usize>,
    cols: Vec<u32>,
    blocks: Vec<Sym>,
    n_basis: usize,
}

impl BlockRows {
    /// Number of stored 3 x 3 blocks.
    pub fn n_blocks(&self) -> usize {
        self.blocks.len()
    }

    pub fn n_rows(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// `out_i = sum_j B_ij q_cols[j]` (overwrites `out`).
    pub fn apply(&self, q: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        assert_eq!(q.len(), self.n_basis, "BlockRows::apply: basis length");
        assert_eq!(out.len(), self.n_rows(), "BlockRows::apply: output length");
        out.par_iter_mut().with_min_len(16).enumerate().for_each(|(i, o)| {
            let mut acc = [0.0f64; 3];
            for j in self.start[i]..self.start[i + 1] {
                let b = &self.blocks[j];
                let v = &q[self.cols[j] as usize];
                acc[0] += b[0] * v.x + b[1] * v.y + b[2] * v.z;
                acc[1] += b[1] * v.x + b[3] * v.y + b[4] * v.z;
                acc[2] += b[2] * v.x + b[4] * v.y + b[5] * v.z;
            }
            *o = Vector3::new(acc[0], acc[1], acc[2]);
        });
    }

    /// Build from a per-target kernel: `pair(r, r^2, s)` returns the symmetric 3 x 3 kernel of
    /// sorted source `s` at separation `r` (or `None` to skip it), distributed over the source's
    /// interpolation nodes.
    fn build(
        cells: &CellList,
        targets: &[Vector3<f64>],
        interp: &[Interp],
        n_basis: usize,
        pair: impl Fn([f64; 3], f64, usize) -> Option<Sym> + Sync,
    ) -> Self {
        Self::from_sources(cells, targets, n_basis, false, |_| {}, |t, s, row| {
            let r = [t[0] - cells.x[s], t[1] - cells.y[s], t[2] - cells.z[s]];
            let r2 = r[0].mul_add(r[0], r[1].mul_add(r[1], r[2] * r[2]));
            if let Some(k) = pair(r, r2, s) {
                for &(v, l) in &interp[s] {
                    if l != 0.0 {
                        row.add(v, l, &k);
                    }
                }
            }
        })
        .0
    }

    /// The rows of all targets: `visit(shifted_target, sorted_source, row)` adds the blocks of one
    /// source (every periodic image within the cell list's reach) to the target's row, and
    /// `finish(row)` whatever `visit` left pending once all are visited; with `single`, also the
    /// rows' fused single-layer sums.
    fn from_sources(
        cells: &CellList,
        targets: &[Vector3<f64>],
        n_basis: usize,
        single: bool,
        finish: impl Fn(&mut RowAcc) + Sync,
        visit: impl Fn([f64; 3], usize, &mut RowAcc) + Sync,
    ) -> (Self, Option<Vec<Vector3<f64>>>) {
        let rows: Vec<Row> = targets
            .par_iter()
            .with_min_len(8)
            .map_init(
                || RowAcc { acc: vec![[0.0f64; 6]; n_basis], seen: vec![false; n_basis], touched: Vec::new(), single: [0.0; 3], pending: None },
                |row, x| {
                    cells.for_each_neighbour(x, |t, range| range.for_each(|s| visit(t, s, row)));
                    finish(row);
                    row.take()
                },
            )
            .collect();
        let sums = single.then(|| rows.iter().map(|r| Vector3::from(r.2)).collect());
        (Self::from_rows(rows, n_basis), sums)
    }

    fn from_rows(rows: Vec<Row>, n_basis: usize) -> Self {
        let mut me = Self { start: Vec::with_capacity(rows.len() + 1), n_basis, ..Self::default() };
        me.start.push(0);
        for (c, b, _) in rows {
            me.cols.extend_from_slice(&c);
            me.blocks.extend_from_slice(&b);
            me.start.push(me.cols.len());
        }
        me
    }

    /// Real-space Stokeslet blocks (`weights`: scalar quadrature weights of the sources, sorted like
    /// `cells`; `interp` sorted likewise). A source within `eps` of a target adds `self_term w`
    /// (symmetric: its upper triangle is taken).
    #[allow(clippy::too_many_arguments)]
    pub fn stokeslet(
        cells: &CellList,
        xi: f64,
        r_cut: f64,
        eps: f64,
        self_term: &Matrix3<f64>,
        targets: &[Vector3<f64>],
        weights: &[f64],
        interp: &[Interp],
        n_basis: usize,
    ) -> Self {
        let table = Erfcx::get();
        let (rc2, eps2) = (r_cut * r_cut, eps * eps);
        Self::build(cells, targets, interp, n_basis, |r, r2, s| {
            if r2 >= rc2 {
                return None;
            }
            let w = weights[s];
            if r2 <= eps2 {
                let m = self_term * w;
                return Some(SYM_PQ.map(|(p, q)| m[(p, q)]));
            }
            let rn = r2.sqrt();
            let (erfc, e) = erfc_and_gauss(table, xi * rn);
            let (a, b) = stokeslet_ab(xi, rn, erfc, e);
            let (a, b) = (a * w, b * w);
            let [x, y, z] = r;
            Some([b * x * x + a, b * x * y, b * x * z, b * y * y + a, b * y * z, b * z * z + a])
        })
    }

    /// Real-space stresslet blocks (`normals`: weighted normals of the sources, sorted like `cells`;
    /// `interp` sorted likewise). Sources within `eps` of a target add nothing (as [`super::real_space::stresslet`]).
    #[allow(clippy::too_many_arguments)]
    pub fn stresslet(
        cells: &CellList,
        xi: f64,
        r_cut: f64,
        eps: f64,
        targets: &[Vector3<f64>],
        normals: &[Vector3<f64>],
        interp: &[Interp],
        n_basis: usize,
    ) -> Self {
        let table = Erfcx::get();
        let (rc2, eps2) = (r_cut * r_cut, eps * eps);
        Self::build(cells, targets, interp, n_basis, |r, r2, s| {
            if r2 >= rc2 || r2 <= eps2 {
                return None;
            }
            let n = normals[s];
            Some(stresslet_pair(table, xi, r, r2, [n.x, n.y, n.z]))
        })
    }
}

/// The 3 x 3 real-space stresslet kernel ([`Sym`]) of one pair: `B (r . n) r r^T + A (r n^T + (r . n) I + n r^T)`, `r = x - y` (um), `r2 = |r|^2 > 0`, `n` the weighted normal.
#[inline(always)]
fn stresslet_pair(table: &Erfcx, xi: f64, r: [f64; 3], r2: f64, n: [f64; 3]) -> Sym {
    let rn = r2.sqrt();
    let (erfc, e) = erfc_and_gauss(table, xi * rn);
    let (a, b) = stresslet_ab(xi, rn, erfc, e);
    let rdn = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
    let (brn, arn) = (b * rdn, a * rdn);
    SYM_PQ.map(|(p, q)| brn * r[p] * r[q] + a * (r[p] * n[q] + n[p] * r[q]) + if p == q { arn } else { 0.0 })
}

/// Sources in groups of `bary.len()` nodes that all interpolate from the same three basis nodes
/// with the same barycentric weights (the quadrature nodes of one flat triangle): group `g` is
/// sources `g m .. g m + m` (`m = bary.len()`), its basis nodes `groups[g]`.
#[derive(Debug, Clone, Copy)]
pub struct NodeGroups<'a> {
    pub sources: &'a [Vector3<f64>],
    /// Weighted normals `n_k` of the sources (um^2).
    pub normals: &'a [Vector3<f64>],
    pub groups: &'a [[usize; 3]],
    /// Barycentric weights of the `m` nodes of a group on its three basis nodes.
    pub bary: &'a [[f64; 3]],
}

/// Groups of `m` consecutive sources binned by their centroids: a group farther than `reach`
/// (the cutoff plus the largest node-to-centroid distance) from a target has no pair within
/// the cutoff, so it is skipped with one distance check.
struct GroupCells {
    centroids: Vec<Vector3<f64>>,
    reach: f64,
    cells: CellList,
}

impl GroupCells {
    fn new(box_len: [f64; 3], sources: &[Vector3<f64>], m: usize, r_cut: f64) -> Self {
        let n_groups = sources.len() / m;
        let centroids: Vec<Vector3<f64>> = (0..n_groups).map(|g| sources[g * m..(g + 1) * m].iter().sum::<Vector3<f64>>() / m as f64).collect();
        let radius = centroids.iter().enumerate().fold(0.0f64, |r, (g, c)| sources[g * m..(g + 1) * m].iter().fold(r, |r, y| r.max((y - c).norm())));
        let reach = r_cut + radius;
        let cells = CellList::new(box_len, reach, &centroids);
        Self { centroids, reach, cells }
    }

    /// The shift of sorted group `s` from its centroid to its binned (wrapped) image (um).
    fn shift(&self, s: usize) -> Vector3<f64> {
        let c = &self.cells;
        Vector3::new(c.x[s], c.y[s], c.z[s]) - self.centroids[c.order[s]]
    }

    /// Whether sorted group `s` may hold a pair within the cutoff of the shifted target `t`.
    #[inline(always)]
    fn near(&self, t: [f64; 3], s: usize) -> bool {
        let c = [t[0] - self.cells.x[s], t[1] - self.cells.y[s], t[2] - self.cells.z[s]];
        c[0].mul_add(c[0], c[1].mul_add(c[1], c[2] * c[2])) < self.reach * self.reach
    }
}

impl BlockRows {
    /// The blocks of [`Self::stresslet`] for sources in [`NodeGroups`] (equal up to rounding), and
    /// with `forces` (the weighted forces `w_k f_k` of the sources, pN) the real-space Stokeslet
    /// sum `sum_k G^R(x_i - y_k) w_k f_k` at the targets from the same pairs (their distances,
    /// `erfc` and `exp` shared: the single layer's real-space part for a few multiply-adds a pair).
    ///
    /// Same pairs and kernels, visited group by group: the group centroids are binned with the
    /// cutoff `r_cut + rho` (`rho` the largest node-to-centroid distance), a group farther than
    /// that from a target is skipped with one distance check, and the kernels of a group's nodes
    /// (at most [`LANES`]) are evaluated together in SIMD lanes ([`super::lanes`]: branch-free
    /// `exp` and `erfc`) and summed into its three blocks before one scattered update each (the
    /// plain build evaluates pair by pair with table lookups and does three scattered 9-value
    /// updates per pair). With [`BlockPrecision::Single`] (on a CPU with AVX-512 and for
    /// `xi r_cut < 4`) the kernels of two groups at a time run in single precision
    /// ([`super::lanes32`]: each value within a few 1e-7 of the double one); the first group a
    /// target meets waits in its row for the second.
    #[allow(clippy::too_many_arguments)]
    pub fn stresslet_grouped(
        box_len: [f64; 3],
        xi: f64,
        r_cut: f64,
        eps: f64,
        targets: &[Vector3<f64>],
        src: NodeGroups<'_>,
        forces: Option<&[Vector3<f64>]>,
        n_basis: usize,
        precision: BlockPrecision,
    ) -> (Self, Option<Vec<Vector3<f64>>>) {
        let m = src.bary.len();
        assert!(m <= LANES, "BlockRows::stresslet_grouped: at most {LANES} nodes per group");
        let grouped = GroupCells::new(box_len, &src.sources[..src.groups.len() * m], m, r_cut);
        let cells = &grouped.cells;
        // node coordinates in the frame of their group's wrapped centroid, in lanes, sorted like the cells
        let lanes: Vec<NodeLanes> = cells
            .order
            .iter()
            .enumerate()
            .map(|(s, &g)| {
                let shift = grouped.shift(s);
                let mut nl = NodeLanes::default();
                for k in 0..m {
                    let (y, n) = (src.sources[g * m + k] + shift, src.normals[g * m + k]);
                    let f = forces.map_or_else(Vector3::zeros, |f| f[g * m + k]);
                    for d in 0..3 {
                        nl.x[d][k] = y[d];
                        nl.n[d][k] = n[d];
                        nl.f[d][k] = f[d];
                    }
                    nl.valid[k] = 1.0;
                }
                nl
            })
            .collect();
        let kernel = Kernel {
            xi,
            rc2: r_cut * r_cut,
            eps2: eps * eps,
            erfcx: Erfcx::get(),
            bary: std::array::from_fn(|v| std::array::from_fn(|k| if k < m { src.bary[k][v] } else { 0.0 })),
        };
        let avx512 = crate::bim::kernels::avx512_available();
        let visit = |s: usize, row: &mut RowAcc, local: Option<super::lanes::TriangleAtTarget>| {
            if let Some((local, single)) = local {
                for (&v, lv) in src.groups[cells.order[s]].iter().zip(&local) {
                    row.add(v, 1.0, lv);
                }
                for (a, b) in row.single.iter_mut().zip(single) {
                    *a += b;
                }
            }
        };
        #[cfg(target_arch = "x86_64")]
        if precision == BlockPrecision::Single && avx512 && xi * r_cut < super::lanes32::X_MAX {
            let tab = ErfcxF32::get();
            let bary: [[f32; 16]; 3] = std::array::from_fn(|v| std::array::from_fn(|l| kernel.bary[v][l % LANES] as f32));
            let empty = NodeLanes::default();
            // two groups per evaluation: the first waits in the row for the second
            let pair = |sl: bool, (ta, sa): ([f64; 3], usize), b: Option<([f64; 3], usize)>, row: &mut RowAcc| {
                let (tb, nb) = b.map_or((ta, &empty), |(tb, sb)| (tb, &lanes[sb]));
                let mut out = [[0.0f64; 24]; 2];
                // SAFETY: `avx512` was set from `crate::bim::kernels::avx512_available`
                let inside = unsafe {
                    if sl {
                        super::lanes32::zmm::blocks_x2::<true>(&kernel, tab, &bary, ta, &lanes[sa], tb, nb, &mut out)
                    } else {
                        super::lanes32::zmm::blocks_x2::<false>(&kernel, tab, &bary, ta, &lanes[sa], tb, nb, &mut out)
                    }
                };
                for ((s, o), inside) in [Some(sa), b.map(|(_, sb)| sb)].into_iter().zip(&out).zip(inside) {
                    if let (Some(s), true) = (s, inside) {
                        for (j, &v) in src.groups[cells.order[s]].iter().enumerate() {
                            let block: &Sym = o[6 * j..6 * j + 6].try_into().expect("six entries");
                            row.add(v, 1.0, block);
                        }
                        for (a, b) in row.single.iter_mut().zip(&o[18..21]) {
                            *a += b;
                        }
                    }
                }
            };
            let sl = forces.is_some();
            return Self::from_sources(
                cells,
                targets,
                n_basis,
                sl,
                |row| {
                    if let Some(a) = row.pending.take() {
                        pair(sl, a, None, row);
                    }
                },
                |t, s, row| {
                    if grouped.near(t, s) {
                        match row.pending.take() {
                            Some(a) => pair(sl, a, Some((t, s)), row),
                            None => row.pending = Some((t, s)),
                        }
                    }
                },
            );
        }
        let _ = precision;
        match forces {
            Some(_) => Self::from_sources(cells, targets, n_basis, true, |_| {}, |t, s, row| {
                if grouped.near(t, s) {
                    visit(s, row, kernel.blocks::<true>(t, &lanes[s], avx512));
                }
            }),
            None => Self::from_sources(cells, targets, n_basis, false, |_| {}, |t, s, row| {
                if grouped.near(t, s) {
                    visit(s, row, kernel.blocks::<false>(t, &lanes[s], avx512));
                }
            }),
        }
    }

    /// The blocks of [`Self::stokeslet`] for sources in groups of `m <= 8` consecutive nodes that
    /// interpolate from the same three basis nodes (the quadrature nodes of one flat triangle:
    /// `interp[k]` lists the same nodes in the same order for every `k` of a group, weights free),
    /// built group by group in SIMD lanes ([`Kernel::stokeslet_blocks`]) as
    /// [`Self::stresslet_grouped`] does: equal up to rounding. `None` when a target lies within
    /// `eps` of a source (that pair's self term is the plain build's, which the caller then uses).
    #[allow(clippy::too_many_arguments)]
    pub fn stokeslet_grouped(
        box_len: [f64; 3],
        xi: f64,
        r_cut: f64,
        eps: f64,
        targets: &[Vector3<f64>],
        sources: &[Vector3<f64>],
        weights: &[f64],
        interp: &[Interp],
        m: usize,
        n_basis: usize,
    ) -> Option<Self> {
        assert!((1..=LANES).contains(&m) && sources.len().is_multiple_of(m), "BlockRows::stokeslet_grouped: groups of 1 to {LANES} nodes");
        let grouped = GroupCells::new(box_len, sources, m, r_cut);
        let cells = &grouped.cells;
        let lanes: Vec<WeightedLanes> = cells
            .order
            .iter()
            .enumerate()
            .map(|(s, &g)| {
                let shift = grouped.shift(s);
                let mut wl = WeightedLanes::default();
                for k in 0..m {
                    let (y, ip) = (sources[g * m + k] + shift, &interp[g * m + k]);
                    for d in 0..3 {
                        wl.x[d][k] = y[d];
                        wl.c[d][k] = ip[d].1 * weights[g * m + k];
                    }
                    wl.valid[k] = 1.0;
                }
                wl
            })
            .collect();
        let kernel = Kernel { xi, rc2: r_cut * r_cut, eps2: eps * eps, erfcx: Erfcx::get(), bary: [[0.0; LANES]; 3] };
        let avx512 = crate::bim::kernels::avx512_available();
        let coincident = std::sync::atomic::AtomicBool::new(false);
        let (rows, _) = Self::from_sources(cells, targets, n_basis, false, |_| {}, |t, s, row| {
            if !grouped.near(t, s) {
                return;
            }
            match kernel.stokeslet_blocks(t, &lanes[s], avx512) {
                GroupAtTarget::Outside => {}
                GroupAtTarget::Blocks(local) => {
                    let ip = &interp[cells.order[s] * m];
                    for (&(v, _), lv) in ip.iter().zip(&local) {
                        row.add(v, 1.0, lv);
                    }
                }
                GroupAtTarget::Coincident => coincident.store(true, std::sync::atomic::Ordering::Relaxed),
            }
        });
        (!coincident.into_inner()).then_some(rows)
    }
}
