//! Dense stiff-mode Jacobian of a membrane in Stokes flow: the free-space two-fluid mobility of every vertex pair times the membrane stiffness, and its factorised stage matrix `I - g J_mob`.
//!
//! The Jacobian of the kinematic condition is `J = M K` ([`super::precondition`]: `K = dF/dx`
//! the nodal stiffness, N/um, sparse; `M` the boundary-integral mobility, dense). The local
//! Jacobian `J_loc` keeps only the self-mobility of each vertex; it is exact for the
//! mesh-scale modes and under-estimates the longer ones, which leaves a W-method that uses it
//! stable only up to steps where those modes matter (measured mid-run in the paper's channel:
//! ~100-230 us, `solver/README.md`). This Jacobian keeps every vertex pair:
//!
//! ```text
//! J_mob = M_fs K,
//! M_fs,ij = 2/(1 + lambda) 1/(8 pi mu) G_e(x_i - x_j)            (i != j, per nodal force)
//! M_fs,ii = 2/(1 + lambda) a_i (3 I - n_i n_i) / (8 mu A_i)      (a_i = sqrt(A_i / pi))
//! G_e(r)  = ((|r|^2 + 2 e^2) I + r r^T) / (|r|^2 + e^2)^(3/2)
//! e       = s (1 - |r|^2 / (1.5 s)^2) for |r| < 1.5 s, else 0    (s = (a_i + a_j) / 2)
//! ```
//!
//! with `A_i` the vertex area (um^2) and `n_i` the vertex normal. `G_e` is the regularised
//! Stokeslet of Cortez, Fauci & Medovikov (Phys. Fluids 17, 031504, 2005, eq. 10), the velocity
//! of a force spread over a blob of size `e`; with `e = 0` it is the point Stokeslet
//! `G(r) = I/|r| + r r^T/|r|^3`. So pairs at least `1.5 s` apart see the point Stokeslet (on the
//! paper's cell neighbours sit a median 2.0 s apart; 12-17 % of its edges are shorter than
//! 1.5 s, the shortest 1.3 s at rest, where `e = 0.25 s`), and only pairs closer than their
//! patches' size see a blob that grows as they approach (`e -> s`, `G_e <= 2/s`). The point
//! Stokeslet over-couples such pairs: on a patch strained to an aspect of ~3.6 (the leading rim
//! of the paper's cell 6 ms from rest, edges of 0.16 and 0.57 um) the mobility of a vertex
//! moving against its two close neighbours fell to 0.17 of its self-mobility (0.32 with `G_e`),
//! `J_mob` under-stated that in-plane mode (where `K` is stiffest), and the W-method went
//! unstable on it: steps of 40-60 us and a rejection every two or three for 4 ms, where the
//! cell's accuracy allowed 280-330 us. A blob at every distance (`e = s`) removed that too, but
//! moved a mid-run window's deviations from the reference 2-5x: `J_mob` then differs from the
//! Jacobian in the smooth modes as well (`solver/README.md`, "Session 29").
//!
//! The diagonal block is the centre velocity of a flat disc of area `A_i` carrying a uniform
//! traction, integrated exactly (`Int_disc G dS = pi a (3 I - n n)`); the normal part equals the
//! self-mobility of [`super::precondition::self_mobility`]. The factor `2/(1 + lambda)` is the
//! exact response of a locally flat interface between fluids of viscosity `mu` and `lambda mu` to a
//! traction of any wavelength short against the cell (the two half-space responses add; the double
//! layer of a flat interface vanishes), so `M_fs` matches the mobility of every deformation mode
//! down to wavelengths where the cell's curvature, its double layer, the walls and the periodic
//! images enter, i.e. the slow modes that a W-method does not need (ROS34PW2 is third order for any
//! `J`; stability only needs `J_mob` to over-estimate the stiff modes, which the scheme's scale
//! factor ensures). `K` annihilates rigid motions, so translation and rotation stay explicit.
//!
//! Cost at the paper's 2048 triangles (1026 vertices, 3078 unknowns): `M_fs` is 3078^2
//! doubles (76 MB), the product with the sparse `K` ~2e8 multiply-adds and the LU of `W`
//! `2/3 3078^3 = 1.9e10` flops (in single precision,
//! [`DenseStage`]), i.e. about one velocity evaluation. The scheme can keep one factorisation
//! for several steps ([`super::ros34pw2`]), which is still a W-method (the kept
//! `W = I - g_0 J_mob` is `I - g J'` with `J' = (g_0/g) J_mob`); in the channel it rebuilds it
//! every step (`Reuse::max_age`), except with penalty walls while the cell is quiet
//! (`Reuse::PENALTY_WALLS`: up to 3 steps).
//!
//! With penalty walls the state carries the walls' displacements after the vertices, and the
//! walls' own block `J_ww` joins this one ([`MobilityJacobian::with_wall_block`],
//! [`super::wall_block`]).

use crate::error::SolverError;
use crate::viscosity::ViscosityContrast;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::{Mat, MatMut};
use nalgebra::Vector3;
use std::f64::consts::PI;
use std::sync::Arc;
use super::wall_block::{WallBlock, WallStage};

/// The dense stiff-mode Jacobian `J_mob = M_fs K` (1/s) on `n` vertices, `3n x 3n`, row `3 i + k`
/// = component `k` of vertex `i` (the ordering of [`super::precondition::LocalJacobian`]). It
/// keeps its factors (the linearisation point and the sparse `K`); the dense product is formed
/// only into a stage matrix ([`DenseStage::factorise`]) or applied ([`Self::apply`]).
#[derive(Debug, Clone)]
pub struct MobilityJacobian {
    x: Vec<Vector3<f64>>,
    areas_um2: Vec<f64>,
    normals: Vec<Vector3<f64>>,
    mu_pa_s: f64,
    lambda: ViscosityContrast,
    /// `K` by vertex column block: for vertex `j`, the rows `r` with `(K[r, 3j], K[r, 3j+1], K[r, 3j+2])`
    /// (N/um), duplicates summed, rows ascending.
    k_blocks: Vec<Vec<(usize, [f64; 3])>>,
    /// The rows of state entries after the cell's (the penalty walls' displacements), shared
    /// between the Jacobians of every step ([`Self::with_wall_block`]).
    wall: Option<Arc<WallBlock>>,
}

/// The factorised stage matrix `W = I - g J_mob` (`g` in s): its LU with partial pivoting in
/// single precision, stored in place; each stage solve is one pair of triangular solves with it
/// ([`Self::solve_in_place`]). A W-method keeps its order for any `J` (ROS34PW2: order 3,
/// Rang & Angermann 2005), so the stages may invert the single-precision product `L U` instead
/// of the double-precision `W`; what differs from stage to stage is the solves' rounding, a
/// backward error of ~1e-7 of `W` (measured against solves refined to 1e-12: the trajectory
/// moves by <= 3e-7 um in 2 ms late in a run and 1.4e-6 um with a 1000x stiffer area modulus,
/// against the scheme's 2.2e-4 um from the bs23 reference; solver/README "Session 18"). The
/// single-precision LU takes half the time of the double one (twice the SIMD lanes; 2/3 (3n)^3 flops, the largest
/// part of a step's overhead at 2048 triangles) and half the memory (38 MB instead of 76 MB at
/// 3078 unknowns). All buffers are kept across refactorisations (allocating and zeroing them
/// anew at every step cost more than the product itself).
#[derive(Debug)]
pub struct DenseStage {
    /// `g` (s) it was built with.
    pub g: f64,
    lu: Mat<f32>,
    /// `M_fs` rounded to single precision, from which `W` is formed: the `J_mob` of this stage
    /// is `M_32 K` (any `J` keeps the W-method's order), half the memory and traffic of the double one.
    m: Mat<f32>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    n: usize,
    /// The walls' part ([`MobilityJacobian::with_wall_block`]).
    wall: Option<WallStage>,
}

/// `out = K w` (N) for `K` by vertex column block (see [`MobilityJacobian`]) and `w(j)` the
/// displacement of vertex `j` (um); `out` (`3n x 1`) is overwritten.
fn stiffness_product(k_blocks: &[Vec<(usize, [f64; 3])>], w: impl Fn(usize) -> [f64; 3], out: &mut Mat<f64>) {
    out.fill(0.0);
    for (j, entries) in k_blocks.iter().enumerate() {
        let wj = w(j);
        for &(r, k) in entries {
            out[(r, 0)] += k[0] * wj[0] + k[1] * wj[1] + k[2] * wj[2];
        }
    }
}

/// `M_fs` (um/s per N of nodal force), dense `3n x 3n`, for vertices `x` (um) with vertex
/// areas `areas_um2` and unit normals `normals`, outer viscosity `mu_pa_s`, ratio `lambda`.
pub fn two_fluid_mobility(x: &[Vector3<f64>], areas_um2: &[f64], normals: &[Vector3<f64>], mu_pa_s: f64, lambda: ViscosityContrast) -> Mat<f64> {
    let mut m = Mat::<f64>::zeros(3 * x.len(), 3 * x.len());
    two_fluid_mobility_into(x, areas_um2, normals, mu_pa_s, lambda, &mut m);
    m
}

/// A real type `M_fs` is stored in: `f64` ([`two_fluid_mobility`]) or `f32` (inside [`DenseStage`]).
pub trait Stored: Copy + 'static {
    const ZERO: Self;
    /// The value rounded to this type.
    fn from_f64(v: f64) -> Self;
    /// The value rounded to single precision.
    fn to_f32(self) -> f32;
}

impl Stored for f64 {
    const ZERO: Self = 0.0;
    #[inline(always)]
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self as f32
    }
}

impl Stored for f32 {
    const ZERO: Self = 0.0;
    #[inline(always)]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self
    }
}

/// The blob size `e` (um) of the regularised Stokeslet between two vertices `|r| = sqrt(r2)` um
/// apart whose patches have the mean radius `s` (um): `s (1 - |r|^2 / (1.5 s)^2)` closer than
/// `1.5 s`, 0 (the point Stokeslet) beyond (module doc).
fn blob_size(r2: f64, s: f64) -> f64 {
    const REACH: f64 = 1.5;
    let reach2 = REACH * REACH * s * s;
    if r2 < reach2 { s * (1.0 - r2 / reach2) } else { 0.0 }
}

/// [`two_fluid_mobility`] written into `m`, each entry computed in double precision and rounded
/// to `T` (resized to `3n x 3n` when it is not; every entry is overwritten).
fn two_fluid_mobility_into<T: Stored>(x: &[Vector3<f64>], areas_um2: &[f64], normals: &[Vector3<f64>], mu_pa_s: f64, lambda: ViscosityContrast, m: &mut Mat<T>) {
    let n = x.len();
    if m.nrows() != 3 * n || m.ncols() != 3 * n {
        *m = Mat::<T>::from_fn(3 * n, 3 * n, |_, _| T::ZERO);
    }
    let s = lambda.rhs_scale();
    // 1 N / (Pa s um) = 1e12 um/s
    let c_pair = 1e12 * s / (8.0 * PI * mu_pa_s);
    let radii: Vec<f64> = areas_um2.iter().map(|a| (a / PI).sqrt()).collect();
    for j in 0..n {
        for b in 0..3 {
            let col = m.col_mut(3 * j + b).try_as_col_major_mut().expect("a Mat is column-major");
            let out = col.as_slice_mut();
            for (i, o) in out.chunks_exact_mut(3).enumerate() {
                if i == j {
                    // traction F / (A 1e-12) Pa on a disc: a (3 I - n n) / (8 mu) per Pa
                    let c = s * radii[i] / (8.0 * mu_pa_s * areas_um2[i].max(f64::MIN_POSITIVE) * 1e-12);
                    let nv = normals[i];
                    for (a_, o_) in o.iter_mut().enumerate() {
                        let delta = if a_ == b { 3.0 } else { 0.0 };
                        *o_ = T::from_f64((delta - nv[a_] * nv[b]) * c);
                    }
                } else {
                    let r = x[i] - x[j];
                    let r2 = r.norm_squared();
                    let e = blob_size(r2, 0.5 * (radii[i] + radii[j]));
                    let q = r2 + e * e;
                    let iq3 = 1.0 / (q * q.sqrt());
                    let diagonal = (r2 + 2.0 * e * e) * iq3;
                    for (a_, o_) in o.iter_mut().enumerate() {
                        let delta = if a_ == b { diagonal } else { 0.0 };
                        *o_ = T::from_f64((delta + r[a_] * r[b] * iq3) * c_pair);
                    }
                }
            }
        }
    }
}

impl MobilityJacobian {
    /// `J_mob = M_fs K`: `stiffness` the nodal stiffness triplets (N/um, duplicates summed),
    /// the other arguments those of [`two_fluid_mobility`].
    pub fn new(x: &[Vector3<f64>], areas_um2: &[f64], normals: &[Vector3<f64>], stiffness: &[(usize, usize, f64)], mu_pa_s: f64, lambda: ViscosityContrast) -> Self {
        let n = x.len();
        // duplicates summed first (a triangle law lists each pair once per triangle it shares,
        // the bending differences once more)
        let mut by_block: Vec<Vec<(usize, usize, f64)>> = vec![Vec::new(); n];
        for &(r, c, v) in stiffness {
            if r < 3 * n && c < 3 * n && v != 0.0 {
                by_block[c / 3].push((r, c % 3, v));
            }
        }
        let k_blocks = by_block
            .into_iter()
            .map(|mut e| {
                e.sort_unstable_by_key(|t| t.0);
                let mut out: Vec<(usize, [f64; 3])> = Vec::with_capacity(e.len());
                for (r, b, v) in e {
                    match out.last_mut() {
                        Some(last) if last.0 == r => last.1[b] += v,
                        _ => {
                            let mut k = [0.0; 3];
                            k[b] = v;
                            out.push((r, k));
                        }
                    }
                }
                out
            })
            .collect();
        Self { x: x.to_vec(), areas_um2: areas_um2.to_vec(), normals: normals.to_vec(), mu_pa_s, lambda, k_blocks, wall: None }
    }

    /// The same Jacobian for a state that carries the displacements of the penalty walls'
    /// vertices after the cell's vertices, with the walls' own block:
    /// `J = [[J_mob, 0], [0, J_ww]]` ([`super::wall_block`]: why the coupling stays explicit).
    pub fn with_wall_block(mut self, block: Arc<WallBlock>) -> Self {
        self.wall = Some(block);
        self
    }

    /// Number of vertices.
    pub fn vertices(&self) -> usize {
        self.x.len()
    }

    /// Length of the state it acts on: the vertices and the wall vertices.
    pub fn state_len(&self) -> usize {
        self.x.len() + self.wall.as_ref().map_or(0, |w| w.vertices())
    }

    /// `out = J_mob w = M_fs (K w)` (um/s for `w` in um), and `J_ww w` on the wall part.
    pub fn apply(&self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        let n = self.x.len();
        let mut kw = Mat::<f64>::zeros(3 * n, 1);
        stiffness_product(&self.k_blocks, |j| [w[j].x, w[j].y, w[j].z], &mut kw);
        let m = two_fluid_mobility(&self.x, &self.areas_um2, &self.normals, self.mu_pa_s, self.lambda);
        let y = &m * &kw;
        for (i, o) in out.iter_mut().enumerate().take(n) {
            *o = Vector3::new(y[(3 * i, 0)], y[(3 * i + 1, 0)], y[(3 * i + 2, 0)]);
        }
        if let Some(block) = &self.wall {
            block.apply(&w[n..], &mut out[n..]);
        }
    }

    /// Factorise `I - g J_mob` into a new [`DenseStage`] (see [`DenseStage::factorise`]).
    pub fn stage_matrix(&self, g: f64) -> Result<DenseStage, SolverError> {
        let mut stage = DenseStage::empty();
        stage.factorise(self, g)?;
        Ok(stage)
    }

    /// `w = I - g M K` into `w` (`m` holds `M_fs`), by blocks of [`STAGE_ROWS`] rows: for each
    /// block the three columns of every vertex `j` are summed from the columns of `M_fs` that
    /// vertex `j`'s rows of `K` name (~40-60 of them, two rings of Method C bending) into three
    /// accumulators in L1, and written once; the block of all the columns of `M_fs` (3 MB in
    /// single precision) stays in cache while every vertex reads it. The sums are single
    /// precision (16 lanes, no conversions: half the time of double-precision sums): each entry
    /// of `W` is then within a few single roundings (~1e-7) of `|g| sum |M_ik K_kj|`, the size of
    /// the backward error the single-precision LU adds anyway, and a W-method keeps its order for
    /// any `W` (`integrate::ros34pw2`).
    fn stage_into<T: Stored>(&self, g: f64, m: &Mat<T>, w: &mut Mat<f32>) {
        let dim = 3 * self.x.len();
        if w.nrows() != dim || w.ncols() != dim {
            *w = Mat::<f32>::zeros(dim, dim);
        }
        let cols: Vec<&[T]> = (0..dim).map(|c| m.col(c).try_as_col_major().expect("column-major").as_slice()).collect();
        let entries: Vec<Vec<(usize, [f32; 3])>> = self
            .k_blocks
            .iter()
            .map(|e| e.iter().map(|&(r, k)| (r, k.map(|k| (-g * k) as f32))).collect())
            .collect();
        // the last rows (fewer than a block) of every column, padded to a block with zeros: every
        // block's loop then runs over a fixed length, which the compiler vectorises without a
        // remainder (1.5x faster than over a slice of the same rows)
        let full = dim / STAGE_ROWS * STAGE_ROWS;
        let tail: Vec<[T; STAGE_ROWS]> = if full < dim {
            cols.iter()
                .map(|c| {
                    let mut t = [T::ZERO; STAGE_ROWS];
                    t[..dim - full].copy_from_slice(&c[full..]);
                    t
                })
                .collect()
        } else {
            Vec::new()
        };
        let mut acc = [[0.0f32; STAGE_ROWS]; 3];
        for i0 in (0..dim).step_by(STAGE_ROWS) {
            let i1 = (i0 + STAGE_ROWS).min(dim);
            for (j, entries) in entries.iter().enumerate() {
                acc.iter_mut().for_each(|a| a.fill(0.0));
                for &(r, k) in entries {
                    let src: &[T; STAGE_ROWS] = if i0 < full { cols[r][i0..i1].try_into().expect("a full block") } else { &tail[r] };
                    for (a, k) in acc.iter_mut().zip(k) {
                        for (a, s) in a.iter_mut().zip(src) {
                            *a = k.mul_add(s.to_f32(), *a);
                        }
                    }
                }
                for (b, col) in acc.iter_mut().enumerate() {
                    let d = 3 * j + b;
                    if (i0..i1).contains(&d) {
                        col[d - i0] += 1.0;
                    }
                    w.col_mut(d).try_as_col_major_mut().expect("column-major").as_slice_mut()[i0..i1].copy_from_slice(&col[..i1 - i0]);
                }
            }
        }
    }
}

/// Rows of a block of [`MobilityJacobian::stage_into`] (1 KB of a column of `M_fs`, so that
/// a read of a column's block pays its page's translation once; 128 rows took 1.35x as long,
/// 256 to 1024 the same).
const STAGE_ROWS: usize = 256;

impl DenseStage {
    pub(crate) fn empty() -> Self {
        Self { g: 0.0, lu: Mat::new(), m: Mat::new(), perm: Vec::new(), perm_inv: Vec::new(), n: 0, wall: None }
    }

    /// Factorise `I - g J_mob` in place (dense LU with partial pivoting in single precision,
    /// faer's blocked kernels), reusing this stage's buffers. A non-finite or zero pivot (a geometric-stiffness mode with
    /// `g lambda = 1`) is an error, which the scheme turns into a rejected step.
    pub fn factorise(&mut self, j: &MobilityJacobian, g: f64) -> Result<(), SolverError> {
        self.factorise_with_wall_g(j, g, g)
    }

    /// [`DenseStage::factorise`] with the walls' part (if any) at its own `g_wall` (s), kept when
    /// it is already factorised at that `g` for the same walls ([`super::wall_block`]).
    pub fn factorise_with_wall_g(&mut self, j: &MobilityJacobian, g: f64, g_wall: f64) -> Result<(), SolverError> {
        let n = j.vertices();
        let dim = 3 * n;
        two_fluid_mobility_into(&j.x, &j.areas_um2, &j.normals, j.mu_pa_s, j.lambda, &mut self.m);
        j.stage_into(g, &self.m, &mut self.lu);
        self.perm.resize(dim, 0);
        self.perm_inv.resize(dim, 0);
        let par = faer::get_global_parallelism();
        let mut buf = MemBuffer::new(factor::lu_in_place_scratch::<usize, f32>(dim, dim, par, Default::default()));
        factor::lu_in_place(self.lu.as_mut(), &mut self.perm, &mut self.perm_inv, par, MemStack::new(&mut buf), Default::default());
        self.n = n;
        self.g = g;
        self.wall = match (j.wall.as_ref(), self.wall.take()) {
            (Some(block), Some(mut kept)) if kept.is_of(block) => {
                kept.set_g(g_wall);
                Some(kept)
            }
            (Some(block), _) => Some(WallStage::factorise(block, g_wall)),
            (None, _) => None,
        };
        if (0..dim).any(|i| {
            let p = self.lu[(i, i)];
            !(p.is_finite() && p != 0.0)
        }) {
            self.n = 0;
            return Err(SolverError::Unsupported {
                field: "integrator.scheme".into(),
                message: format!("dense stage matrix I - g J_mob (g = {g:e} s) is singular"),
            });
        }
        Ok(())
    }

    /// Number of the cell's vertices the factor is of (the penalty walls' follow them in a stage).
    pub fn cell_vertices(&self) -> usize {
        self.n
    }

    /// Refactorise the walls' part (if any) at `g` (s) when it is of another `g`: the walls take
    /// the step's own `gamma h`, the cell the scaled and possibly kept one ([`super::wall_block`]).
    pub fn set_wall_g(&mut self, g: f64) {
        if let Some(w) = &mut self.wall {
            w.set_g(g);
        }
    }

    /// Number of penalty-wall vertices the factor carries after the cell's (0 without walls).
    pub fn wall_vertices(&self) -> usize {
        self.wall.as_ref().map_or(0, |w| w.vertices())
    }

    /// The cell's part of [`DenseStage::solve_in_place`] alone (`v` the cell's vertices; the
    /// stage of [`super::wall_block::WallCoupling`] solves it before the walls' part).
    pub fn solve_cell_in_place(&self, v: &mut [Vector3<f64>]) {
        assert_eq!(v.len(), self.n, "a cell stage solve on a factor of another size");
        let dim = 3 * self.n;
        let x = self.lu_solve(&Mat::from_fn(dim, 1, |r, _| v[r / 3][r % 3]));
        for (i, o) in v.iter_mut().enumerate() {
            *o = Vector3::new(x[(3 * i, 0)], x[(3 * i + 1, 0)], x[(3 * i + 2, 0)]);
        }
    }

    /// The walls' part of [`DenseStage::solve_in_place`] alone (`v` the walls' vertices).
    pub fn solve_wall_in_place(&self, v: &mut [Vector3<f64>]) {
        assert_eq!(v.len(), self.wall_vertices(), "a walls' stage solve on a factor of another size");
        if let Some(wall) = &self.wall {
            wall.solve_in_place(v);
        }
    }

    /// `v <- (L U)^-1 v`, `L U` the single-precision factors of `I - g J_mob` (see the type's docs
    /// for why the stages need no refinement towards the double-precision `W`).
    /// The wall part (if any) by the walls' own factor ([`WallStage`]).
    pub fn solve_in_place(&self, v: &mut [Vector3<f64>]) {
        assert_eq!(v.len(), self.n + self.wall_vertices(), "a stage solve on a factor of another size (or a singular one)");
        let (cell, wall) = v.split_at_mut(self.n);
        self.solve_cell_in_place(cell);
        self.solve_wall_in_place(wall);
    }

    /// `W_32^-1 b` with the single-precision factors (the right-hand side scaled to unit maximum
    /// before the rounding to single precision, so that no part of it underflows).
    fn lu_solve(&self, b: &Mat<f64>) -> Mat<f64> {
        let dim = b.nrows();
        let scale = (0..dim).map(|i| b[(i, 0)].abs()).fold(0.0f64, f64::max);
        if !(scale > 0.0 && scale.is_finite()) {
            return b.clone();
        }
        let mut x = Mat::<f32>::from_fn(dim, 1, |i, _| (b[(i, 0)] / scale) as f32);
        let xm: MatMut<'_, f32> = x.as_mut();
        let par = faer::get_global_parallelism();
        // `perm` and `perm_inv`: the inverse pair lu_in_place wrote (checked here, O(n))
        let perm = PermRef::new_checked(&self.perm, &self.perm_inv, dim);
        let mut buf = MemBuffer::new(solve::solve_in_place_scratch::<usize, f32>(dim, 1, par));
        solve::solve_in_place(self.lu.as_ref(), self.lu.as_ref(), perm, xm, par, MemStack::new(&mut buf));
        Mat::from_fn(dim, 1, |i, _| x[(i, 0)] as f64 * scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bim::single_layer::SingleLayer;
    use crate::bim::surface::Surface;
    use crate::mesh::sphere;

    /// The nodal stiffness (N/um) of springs of 1e-6 N/um along the edges of `mesh` (a graph
    /// Laplacian: `K e = 0` for a translation `e`), as triplets.
    fn springs(mesh: &crate::mesh::Mesh) -> Vec<(usize, usize, f64)> {
        let mut trip = Vec::new();
        for [a, b] in mesh.edges() {
            for c in 0..3 {
                trip.push((3 * a + c, 3 * a + c, -1e-6));
                trip.push((3 * b + c, 3 * b + c, -1e-6));
                trip.push((3 * a + c, 3 * b + c, 1e-6));
                trip.push((3 * b + c, 3 * a + c, 1e-6));
            }
        }
        trip
    }

    fn apply_m(m: &Mat<f64>, v: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        let x = Mat::from_fn(m.nrows(), 1, |r, _| v[r / 3][r % 3]);
        let y = m * &x;
        (0..v.len()).map(|i| Vector3::new(y[(3 * i, 0)], y[(3 * i + 1, 0)], y[(3 * i + 2, 0)])).collect()
    }

    #[test]
    fn free_space_mobility_reproduces_the_single_layer_on_a_smooth_traction() {
        // sphere of radius 3 um, 512 triangles, lambda = 1 (factor 2/(1 + lambda) = 1): the point
        // collocation with the disc self term against the project's single layer (7-point Gauss,
        // Duffy rule, validated in tests/bim_free_space.rs) for a smooth traction with normal and
        // tangential parts. The crude near field costs accuracy at the mesh scale only; on a smooth
        // field the two agree to a few per cent
        let mesh = sphere(3, 3.0);
        let mu = 1.2e-3;
        let q: Vec<Vector3<f64>> = mesh.vertices.iter().map(|p: &Vector3<f64>| Vector3::new(p.x * p.y, 0.5 * p.z + p.x, (0.7 * p.y).sin())).collect();
        let surface = Surface::new(&mesh).unwrap();
        let reference: Vec<Vector3<f64>> = SingleLayer::new(&surface, (1, 10), true).apply(&q).iter().map(|v| v / mu).collect();
        let areas = mesh.vertex_areas();
        let normals = mesh.vertex_normals();
        let forces: Vec<Vector3<f64>> = q.iter().zip(&areas).map(|(q, a)| q * (a * 1e-12)).collect();
        let m = two_fluid_mobility(&mesh.vertices, &areas, &normals, mu, ViscosityContrast::MATCHED);
        let u = apply_m(&m, &forces);
        let rms = |v: &[Vector3<f64>]| (v.iter().map(|x| x.norm_squared()).sum::<f64>() / v.len() as f64).sqrt();
        let diff: Vec<Vector3<f64>> = u.iter().zip(&reference).map(|(a, b)| a - b).collect();
        let rel = rms(&diff) / rms(&reference);
        assert!(rel < 0.05, "relative rms difference {rel}");
        // lambda scales the whole matrix by 2/(1 + lambda)
        let m5 = two_fluid_mobility(&mesh.vertices, &areas, &normals, mu, ViscosityContrast::new(5.0).unwrap());
        let u5 = apply_m(&m5, &forces);
        for (a, b) in u5.iter().zip(&u) {
            assert!((a - b / 3.0).norm() <= 1e-12 * b.norm().max(1e-300));
        }
    }

    #[test]
    fn a_pair_sees_the_point_stokeslet_beyond_its_patches_and_a_bounded_blob_closer() {
        // two vertices of area pi um^2 (a = 1 um, so s = 1 um) on the x axis, lambda = 1 and
        // mu = 1e12 / (8 pi) Pa s: the entries in units of 1 / (8 pi mu) (um/s per N)
        let mu = 1e12 / (8.0 * PI);
        for d in [0.0f64, 0.5, 1.0, 1.4, 1.5, 2.0, 10.0] {
            let x = [Vector3::zeros(), Vector3::new(d, 0.0, 0.0)];
            let m = two_fluid_mobility(&x, &[PI, PI], &[Vector3::z(), Vector3::z()], mu, ViscosityContrast::MATCHED);
            // Cortez et al. (2005) eq. 10: along r (2 d^2 + 2 e^2) / q^1.5, across (d^2 + 2 e^2) / q^1.5
            let e = if d < 1.5 { 1.0 - d * d / 2.25 } else { 0.0 };
            let q = d * d + e * e;
            let (along, across) = ((2.0 * d * d + 2.0 * e * e) / q.powf(1.5), (d * d + 2.0 * e * e) / q.powf(1.5));
            for (r, c, want) in [(0, 3, along), (1, 4, across), (2, 5, across), (0, 4, 0.0), (1, 5, 0.0)] {
                assert!((m[(r, c)] - want).abs() <= 1e-14 * along, "d = {d}: entry ({r}, {c}) {} against {want}", m[(r, c)]);
            }
            if d >= 1.5 {
                // the point Stokeslet itself
                assert!((along - 2.0 / d).abs() <= 1e-14 && (across - 1.0 / d).abs() <= 1e-14);
            } else {
                // closer, below it and bounded by the value at contact, 2 / s
                assert!(along <= 2.0 + 1e-12 && across <= 2.0 + 1e-12);
                assert!(d == 0.0 || along < 2.0 / d);
            }
            // the disc's self-mobility: 3 / a across the normal, 2 / a along it
            assert!((m[(0, 0)] - 3.0).abs() <= 1e-12 && (m[(2, 2)] - 2.0).abs() <= 1e-12);
        }
    }

    #[test]
    fn a_vertex_squeezed_between_two_close_neighbours_keeps_a_third_of_its_mobility() {
        // session 29's strained rim patch: three vertices in a row 0.16 um apart, each of area
        // 0.088 um^2 (a = 0.167 um), the middle one moving against the outer two (u = -1/2, 1, -1/2
        // along the row). With point Stokeslets between them that mode's mobility falls to 0.17 of
        // the self-mobility; the blob gives 0.32, and J_mob = M_fs K damps the mode K stiffens most
        let mu = 1.2e-3;
        let x = [Vector3::new(-0.16, 0.0, 0.0), Vector3::zeros(), Vector3::new(0.16, 0.0, 0.0)];
        let m = two_fluid_mobility(&x, &[0.088; 3], &[Vector3::z(); 3], mu, ViscosityContrast::new(5.0).unwrap());
        let mode = [-0.5, 1.0, -0.5];
        let quotient = |pair: &dyn Fn(usize, usize) -> f64| {
            let mut num = 0.0;
            for i in 0..3 {
                for j in 0..3 {
                    num += mode[i] * mode[j] * if i == j { m[(3 * i, 3 * i)] } else { pair(i, j) };
                }
            }
            num / 1.5
        };
        let blob = quotient(&|i, j| m[(3 * i, 3 * j)]);
        let c_pair = 1e12 * ViscosityContrast::new(5.0).unwrap().rhs_scale() / (8.0 * PI * mu);
        let point = quotient(&|i, j| c_pair * 2.0 / (x[i] - x[j]).norm());
        let own = m[(3, 3)];
        assert!(point / own < 0.2, "point Stokeslets: {}", point / own);
        assert!(blob / own > 0.3, "blob: {}", blob / own);
    }

    #[test]
    fn the_mobility_is_symmetric_entry_by_entry() {
        // reciprocity: G(r) = G(-r) is a symmetric matrix, and so is each disc block
        let mesh = sphere(2, 2.0);
        let m = two_fluid_mobility(&mesh.vertices, &mesh.vertex_areas(), &mesh.vertex_normals(), 1.2e-3, ViscosityContrast::new(5.0).unwrap());
        let dim = m.nrows();
        for i in 0..dim {
            for j in 0..dim {
                assert_eq!(m[(i, j)], m[(j, i)], "M_fs is symmetric entry by entry ({i}, {j})");
            }
        }
    }

    #[test]
    fn the_stage_matrix_in_row_blocks_is_i_minus_g_m_k() {
        // several full row blocks and a partial one
        let mesh = sphere(3, 2.0);
        let n = mesh.vertices.len();
        let dim = 3 * n;
        assert!(dim > STAGE_ROWS && !dim.is_multiple_of(STAGE_ROWS));
        let mut trip = Vec::new();
        for [a, b] in mesh.edges() {
            for c in 0..3 {
                trip.push((3 * a + c, 3 * a + c, -1e-6));
                trip.push((3 * b + c, 3 * b + c, -1e-6));
                trip.push((3 * a + c, 3 * b + (c + 1) % 3, 0.3e-6));
                trip.push((3 * b + (c + 1) % 3, 3 * a + c, 0.3e-6));
            }
        }
        let j = MobilityJacobian::new(&mesh.vertices, &mesh.vertex_areas(), &mesh.vertex_normals(), &trip, 1.2e-3, ViscosityContrast::new(5.0).unwrap());
        let m = two_fluid_mobility(&mesh.vertices, &mesh.vertex_areas(), &mesh.vertex_normals(), 1.2e-3, ViscosityContrast::new(5.0).unwrap());
        let mut k = Mat::<f64>::zeros(dim, dim);
        for &(r, c, v) in &trip {
            k[(r, c)] += v;
        }
        let g = 2e-4;
        let mk = &m * &k;
        let mut w = Mat::<f32>::new();
        j.stage_into(g, &m, &mut w);
        let scale = (0..dim).flat_map(|c| (0..dim).map(move |r| (r, c))).map(|(r, c)| (g * mk[(r, c)]).abs()).fold(1.0f64, f64::max);
        for c in 0..dim {
            for r in 0..dim {
                let want = if r == c { 1.0 } else { 0.0 } - g * mk[(r, c)];
                assert!((w[(r, c)] as f64 - want).abs() <= 1e-6 * scale, "W[{r}, {c}] = {} against {want}", w[(r, c)]);
            }
        }
    }

    #[test]
    fn a_stage_refactorised_into_reused_buffers_equals_a_fresh_one() {
        // the scheme refactorises into the buffers of the previous step's factor: the result must
        // not depend on what they held (another state, another g)
        let mesh = sphere(2, 2.0);
        let n = mesh.vertices.len();
        let trip = springs(&mesh);
        let moved: Vec<Vector3<f64>> = mesh.vertices.iter().map(|p| p * 1.1 + Vector3::new(0.0, 0.2 * p.x, 0.0)).collect();
        let j1 = MobilityJacobian::new(&mesh.vertices, &mesh.vertex_areas(), &mesh.vertex_normals(), &trip, 1.2e-3, ViscosityContrast::new(5.0).unwrap());
        let j2 = MobilityJacobian::new(&moved, &mesh.vertex_areas(), &mesh.vertex_normals(), &trip, 1.2e-3, ViscosityContrast::new(5.0).unwrap());
        let mut reused = j1.stage_matrix(3e-4).unwrap();
        reused.factorise(&j2, 1e-4).unwrap();
        let fresh = j2.stage_matrix(1e-4).unwrap();
        let w: Vec<Vector3<f64>> = mesh.vertices.iter().map(|p| Vector3::new(p.y * p.z, p.x.cos(), p.z)).collect();
        let (mut a, mut b) = (w.clone(), w.clone());
        reused.solve_in_place(&mut a);
        fresh.solve_in_place(&mut b);
        assert_eq!(a, b);
        assert_eq!(reused.g, 1e-4);
        assert_eq!(a.len(), n);
    }

    /// A wall block (the penalty walls' displacements) leaves the cell's block as it was and
    /// acts on its own entries: `J` applies `J_ww w` there, and a stage solve inverts
    /// `I - g J_ww` on them, so that `(I - g J) solve(v) = v` on the wall part.
    #[test]
    fn a_wall_block_acts_on_the_wall_part_and_leaves_the_cell_block_alone() {
        let mesh = sphere(2, 2.0);
        let n = mesh.vertices.len();
        let trip = springs(&mesh);
        let cell = MobilityJacobian::new(&mesh.vertices, &mesh.vertex_areas(), &mesh.vertex_normals(), &trip, 1.2e-3, ViscosityContrast::new(5.0).unwrap());
        // a non-symmetric, strongly damped wall block (rates ~1e5 /s), as -(kappa_W / mu) S
        let (g, m) = (2e-4, 5);
        let j_ww = Mat::from_fn(3 * m, 3 * m, |r, c| if r == c { -1.4e5 } else { 1e4 * ((r * 7 + c * 3) as f64).sin() });
        let j = cell.clone().with_wall_block(Arc::new(WallBlock::new(j_ww.clone())));
        assert_eq!((j.vertices(), j.state_len(), cell.state_len()), (n, n + m, n));
        let w: Vec<Vector3<f64>> = (0..n + m).map(|i| Vector3::new((i as f64).sin(), 0.5, (0.3 * i as f64).cos())).collect();
        let (mut jw, mut jw_cell) = (vec![Vector3::zeros(); n + m], vec![Vector3::zeros(); n]);
        j.apply(&w, &mut jw);
        cell.apply(&w[..n], &mut jw_cell);
        assert_eq!(&jw[..n], &jw_cell[..]);
        for i in 0..m {
            for a in 0..3 {
                let want: f64 = (0..3 * m).map(|c| j_ww[(3 * i + a, c)] * w[n + c / 3][c % 3]).sum();
                assert!((jw[n + i][a] - want).abs() <= 1e-9 * want.abs().max(1.0), "J_ww w at ({i}, {a}): {} against {want}", jw[n + i][a]);
            }
        }
        let (stage, stage_cell) = (j.stage_matrix(g).unwrap(), cell.stage_matrix(g).unwrap());
        let (mut v, mut v_cell) = (w.clone(), w[..n].to_vec());
        stage.solve_in_place(&mut v);
        stage_cell.solve_in_place(&mut v_cell);
        assert_eq!(&v[..n], &v_cell[..]);
        let mut back = vec![Vector3::zeros(); n + m];
        j.apply(&v, &mut back);
        let scale = w.iter().map(|x| x.norm()).fold(0.0, f64::max);
        // (I - g J) v = w on the wall part (the cell block is the cell's own solve, above)
        for (i, ((vi, bi), wi)) in v.iter().zip(&back).zip(&w).enumerate().skip(n) {
            assert!((vi - g * bi - wi).norm() <= 1e-12 * scale, "entry {i}: {:?}", vi - g * bi - wi);
        }
    }

    #[test]
    fn the_product_with_the_stiffness_annihilates_translations_and_stage_solves_invert() {
        // K = a graph Laplacian (nodal stiffness of springs, N/um): K e = 0 for a translation e,
        // so J_mob e = M K e = 0 whatever M; and (I - g J) (solve v) = v
        let mesh = sphere(2, 2.0);
        let n = mesh.vertices.len();
        let k_spring = 1e-6;
        let mut trip = Vec::new();
        for [a, b] in mesh.edges() {
            for c in 0..3 {
                trip.push((3 * a + c, 3 * a + c, -k_spring));
                trip.push((3 * b + c, 3 * b + c, -k_spring));
                trip.push((3 * a + c, 3 * b + c, k_spring));
                trip.push((3 * b + c, 3 * a + c, k_spring));
            }
        }
        let j = MobilityJacobian::new(&mesh.vertices, &mesh.vertex_areas(), &mesh.vertex_normals(), &trip, 1.2e-3, ViscosityContrast::new(5.0).unwrap());
        assert_eq!(j.vertices(), n);
        let e = vec![Vector3::new(0.3, -1.0, 0.2); n];
        let mut je = vec![Vector3::zeros(); n];
        j.apply(&e, &mut je);
        let w: Vec<Vector3<f64>> = mesh.vertices.iter().map(|p| Vector3::new(p.y * p.z, p.x.cos(), p.z)).collect();
        let mut jw = vec![Vector3::zeros(); n];
        j.apply(&w, &mut jw);
        let scale = jw.iter().map(|v| v.norm()).fold(0.0, f64::max);
        assert!(scale > 0.0);
        assert!(je.iter().all(|v| v.norm() < 1e-12 * scale), "J_mob of a translation");
        // stiff: g |J| ~ 10-100 at g = 1e-4 s
        let g = 1e-4;
        let stage = j.stage_matrix(g).unwrap();
        let mut x = w.clone();
        stage.solve_in_place(&mut x);
        // the stage's J is M_32 K (M_fs rounded to single precision) and its solves are single
        // precision triangular solves with the LU of W = I - g M_32 K: backward stable, their
        // residual is a few eps_32 (6e-8) of |W| |x| (normwise backward error: 1.0e-7 here, where
        // |W| ~ 1e5), whether measured against W or against the double-precision I - g M K
        let dim = 3 * n;
        let mut k = Mat::<f64>::zeros(dim, dim);
        for &(r, c, v) in &trip {
            k[(r, c)] += v;
        }
        let m = two_fluid_mobility(&mesh.vertices, &mesh.vertex_areas(), &mesh.vertex_normals(), 1.2e-3, ViscosityContrast::new(5.0).unwrap());
        let m32 = Mat::from_fn(dim, dim, |r, c| m[(r, c)] as f32 as f64);
        let xv = Mat::from_fn(dim, 1, |r, _| x[r / 3][r % 3]);
        let wv = Mat::from_fn(dim, 1, |r, _| w[r / 3][r % 3]);
        let inf = |a: &Mat<f64>| (0..a.nrows()).map(|r| (0..a.ncols()).map(|c| a[(r, c)].abs()).sum::<f64>()).fold(0.0, f64::max);
        for (name, mm) in [("M_32", &m32), ("M", &m)] {
            let wm = Mat::<f64>::identity(dim, dim) - (mm * &k) * g;
            let backward = inf(&(&wv - &wm * &xv)) / (inf(&wm) * inf(&xv));
            assert!(backward < 1e-6, "normwise backward error of the solve against I - g {name} K: {backward:e}");
            assert!(inf(&wm) > 100.0, "a stiff stage: |W| = {}", inf(&wm));
        }
    }
}
