//! Local sparse Jacobian of a membrane in Stokes flow (stiffness times self-mobility) and its factorised stage matrix `I - gamma h J_loc`.
//!
//! The Jacobian of the kinematic condition is `J = M K_f`: `K_f = dDf/dx` the
//! stiffness of the membrane force density (Pa/um, sparse: a vertex only feels
//! its neighbours) and `M` the boundary-integral mobility (dense: every vertex
//! moves every other). Applying `J` costs a full Stokes solve, so the stage
//! systems `(I - gamma h J) w = r` of the Rosenbrock schemes are solved with
//! Krylov iterations, whose number grows with the spread of the spectrum of
//! `gamma h J` (the stiffness ratio).
//!
//! Why a local mobility captures the stiff part: the stiff eigenmodes are the
//! short-wavelength ones. A surface force density of wavenumber `k` on a locally
//! flat interface between fluids of viscosity `mu` (outside) and `lambda mu` (inside)
//! moves the interface with `u = f / (2 mu (1 + lambda) k)` (the two half-space
//! Stokes responses add; for the normal component this is the 2D Fourier transform
//! `1/(4 mu k)` of the Stokeslet at `lambda = 1`), while the elastic force grows
//! like `k^2` (tension, area dilatation, shear) or `k^4` (bending). So
//! the relaxation rate `~ kappa k / (2 mu (1 + lambda))` is largest at the mesh
//! scale, where the Green's function is dominated by the near field: the
//! velocity of vertex `i` is set by the force on its own patch. The self-mobility
//! of a flat disc of radius `a` carrying a uniform normal traction `f` is
//! `u = f a / (2 mu (1 + lambda))` at its centre (`int_0^a f / (8 pi mu r) 2 pi r dr`
//! for one fluid, `2/(1 + lambda)` for two), i.e. the plane-wave mobility at `k = 1/a`.
//! With `a = sqrt(A_i / pi)` for the vertex area `A_i` this gives the diagonal
//! [`self_mobility`] and
//! ```text
//! J_loc = diag(m_i / A_i) K,     K = dF/dx  (nodal stiffness, N/um, sparse)
//! ```
//! with the same sparsity as `K`. Modes shorter than `2 pi a` (the stiffest) are
//! over-estimated by `J_loc`, longer ones under-estimated. The user of `J_loc`
//! scales it: a Rosenbrock-W scheme is unconditionally stable on a mode whose
//! eigenvalue `J` over-estimates (ROS34PW2: `|R| <= 1` for every `h` when
//! `J_loc >= 0.7 J` on that mode), so the W-method takes `2 J_loc`, which pushes the
//! under-estimated band to wavelengths of ~9 mesh sizes, whose rates are ~10x
//! below the mesh-scale ones; a preconditioner is best when it matches the modes
//! that limit GMRES (measured: `0.5 J_loc`), see [`super::ros34pw2::Ros34pw2::local_scale`].
//!
//! Used two ways: as the right preconditioner `P = I - gamma h J_loc` of the
//! GMRES stage solves with the full lagged-mobility `J` (the preconditioned
//! operator `(I - gamma h J) P^-1` has its stiff part cancelled, leaving a
//! bounded spectrum of the smooth modes), or directly as the `J` of a W-method
//! (any `J` keeps the order; only stability needs the stiff modes), which replaces
//! every Jacobian application by a sparse triangular solve. `P` is factorised
//! once per linearisation and step size with faer's sparse LU (it is not symmetric:
//! `diag(m_i/A_i) K`).

use crate::error::SolverError;
use crate::viscosity::ViscosityContrast;
use faer::sparse::linalg::solvers::Lu;
use faer::sparse::{SparseColMat, Triplet};
use faer::linalg::solvers::Solve;
use faer::Mat;
use nalgebra::Vector3;

/// Default factor on the self-mobility in [`crate::dynamics::cell::CellDynamics`]: 1 (the disc formula;
/// the schemes scale `J_loc` themselves, see the module docs).
pub const MOBILITY_SAFETY: f64 = 1.0;

/// Self-mobility (um/s per Pa) of a vertex patch of area `area_um2` (um^2) on an
/// interface between fluids of viscosity `mu_pa_s` (outside) and `lambda mu_pa_s` (inside):
/// `m = a / (2 mu (1 + lambda))`, `a = sqrt(A / pi)` (centre velocity of a uniformly
/// loaded flat disc; um/s per Pa because `a` is in um and `f / mu` in 1/s).
pub fn self_mobility(area_um2: f64, mu_pa_s: f64, lambda: ViscosityContrast) -> f64 {
    (area_um2 / std::f64::consts::PI).sqrt() / (2.0 * mu_pa_s * (1.0 + lambda.lambda()))
}

fn faer_error(what: &str, e: impl std::fmt::Debug) -> SolverError {
    SolverError::Unsupported { field: "integrator.scheme".into(), message: format!("local Jacobian: {what} failed: {e:?}") }
}

/// `J_loc` (1/s) on `n` vertices, `3n x 3n`, row `3 i + k` = component `k` of vertex `i`.
#[derive(Debug, Clone)]
pub struct LocalJacobian {
    n: usize,
    /// Summed entries of `J_loc` (1/s), no duplicates.
    entries: Vec<(usize, usize, f64)>,
}

/// The factorised stage matrix `I - gamma h J_loc`.
#[derive(Debug)]
pub struct StageMatrix {
    /// `gamma h` (s) it was built for.
    pub gamma_h: f64,
    lu: Lu<usize, f64>,
    n: usize,
}

fn to_col(v: &[Vector3<f64>]) -> Mat<f64> {
    Mat::from_fn(3 * v.len(), 1, |r, _| v[r / 3][r % 3])
}

impl LocalJacobian {
    /// `J_loc = diag(mobility_i / (A_i 1e-12)) K`: `stiffness` the nodal stiffness
    /// triplets (N/um, duplicates summed), `vertex_areas_um2` the areas `A_i` that turn
    /// nodal forces into densities, `mobility` the per-vertex mobility (um/s per Pa).
    pub fn new(n: usize, stiffness: &[(usize, usize, f64)], vertex_areas_um2: &[f64], mobility: &[f64]) -> Result<Self, SolverError> {
        let scale: Vec<f64> = vertex_areas_um2.iter().zip(mobility).map(|(&a, &m)| if a > 0.0 { m / (a * 1e-12) } else { 0.0 }).collect();
        let entries: Vec<(usize, usize, f64)> = stiffness.iter().map(|&(r, c, v)| (r, c, scale.get(r / 3).copied().unwrap_or(0.0) * v)).collect();
        Self::from_entries(n, &entries)
    }

    /// `J_loc` (1/s) from its entries `(row, column, value)` (duplicates summed, out-of-range ones dropped).
    pub fn from_entries(n: usize, entries: &[(usize, usize, f64)]) -> Result<Self, SolverError> {
        let trip: Vec<Triplet<usize, usize, f64>> = entries.iter().filter(|t| t.0 < 3 * n && t.1 < 3 * n).map(|&(r, c, v)| Triplet::new(r, c, v)).collect();
        let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(3 * n, 3 * n, &trip).map_err(|e| faer_error("assembly", e))?;
        let mut entries = Vec::with_capacity(matrix.compute_nnz());
        for c in 0..3 * n {
            for (r, &v) in matrix.row_idx_of_col(c).zip(matrix.val_of_col(c)) {
                entries.push((r, c, v));
            }
        }
        Ok(Self { n, entries })
    }

    /// Number of vertices.
    pub fn vertices(&self) -> usize {
        self.n
    }

    /// Stored non-zeros of `J_loc`.
    pub fn nonzeros(&self) -> usize {
        self.entries.len()
    }

    /// `out = J_loc w` (um/s for `w` in um).
    pub fn apply(&self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        out.iter_mut().for_each(|o| *o = Vector3::zeros());
        for &(r, c, v) in &self.entries {
            out[r / 3][r % 3] += v * w[c / 3][c % 3];
        }
    }

    /// Factorise `I - gamma_h J_loc` (sparse LU with partial pivoting).
    pub fn stage_matrix(&self, gamma_h: f64) -> Result<StageMatrix, SolverError> {
        let m = 3 * self.n;
        let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(self.entries.len() + m);
        trip.extend((0..m).map(|i| Triplet::new(i, i, 1.0)));
        trip.extend(self.entries.iter().map(|&(r, c, v)| Triplet::new(r, c, -gamma_h * v)));
        let p = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &trip).map_err(|e| faer_error("assembly", e))?;
        let lu = p.sp_lu().map_err(|e| faer_error("sparse LU", e))?;
        Ok(StageMatrix { gamma_h, lu, n: self.n })
    }
}

impl StageMatrix {
    /// `v <- (I - gamma h J_loc)^-1 v`.
    pub fn solve_in_place(&self, v: &mut [Vector3<f64>]) {
        debug_assert_eq!(v.len(), self.n);
        let x = self.lu.solve(to_col(v));
        for (i, o) in v.iter_mut().enumerate() {
            *o = Vector3::new(x[(3 * i, 0)], x[(3 * i + 1, 0)], x[(3 * i + 2, 0)]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn self_mobility_is_the_disc_formula() {
        // a = 1 um (A = pi um^2), mu = 1 mPa s, lambda = 1: a / (4 mu) = 1 um / 4e-3 Pa s = 250 um/(s Pa)
        assert!((self_mobility(std::f64::consts::PI, 1e-3, ViscosityContrast::MATCHED) - 250.0).abs() < 1e-9);
        // lambda = 5 divides by 1 + lambda = 6 instead of 2
        assert!((self_mobility(std::f64::consts::PI, 1e-3, ViscosityContrast::new(5.0).unwrap()) - 250.0 / 3.0).abs() < 1e-9);
    }

    #[test]
    fn stage_matrix_inverts_i_minus_gamma_h_j_and_apply_matches_dense() {
        // random sparse stiffness on 30 vertices (seeded), areas and mobilities of a few orders
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let n = 30;
        let mut trip = Vec::new();
        for i in 0..3 * n {
            trip.push((i, i, -rng.random_range(1e-6..1e-5)));
            for _ in 0..4 {
                let j = rng.random_range(0..3 * n);
                let v = rng.random_range(-1e-6..1e-6);
                trip.push((i, j, v));
                trip.push((j, i, v)); // duplicates are summed
            }
        }
        let areas: Vec<f64> = (0..n).map(|_| rng.random_range(0.05..0.2)).collect();
        let mob: Vec<f64> = areas.iter().map(|&a| self_mobility(a, 1.2e-3, ViscosityContrast::new(5.0).unwrap())).collect();
        let j = LocalJacobian::new(n, &trip, &areas, &mob).unwrap();
        // dense reference J_ij = m_i / (A_i 1e-12) K_ij
        let mut dense = nalgebra::DMatrix::<f64>::zeros(3 * n, 3 * n);
        for &(r, c, v) in &trip {
            dense[(r, c)] += mob[r / 3] / (areas[r / 3] * 1e-12) * v;
        }
        let w: Vec<Vector3<f64>> = (0..n).map(|_| Vector3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))).collect();
        let wf = nalgebra::DVector::from_iterator(3 * n, w.iter().flat_map(|p| [p.x, p.y, p.z]));
        let jw_dense = &dense * &wf;
        let mut jw = vec![Vector3::zeros(); n];
        j.apply(&w, &mut jw);
        let scale = jw_dense.amax();
        for i in 0..3 * n {
            assert!((jw[i / 3][i % 3] - jw_dense[i]).abs() < 1e-12 * scale);
        }
        // (I - gh J) (solve(w)) = w
        let gh = 1e-4;
        let p = j.stage_matrix(gh).unwrap();
        let mut x = w.clone();
        p.solve_in_place(&mut x);
        let xf = nalgebra::DVector::from_iterator(3 * n, x.iter().flat_map(|p| [p.x, p.y, p.z]));
        let back = &xf - gh * (&dense * &xf);
        assert!((back - wf).amax() < 1e-10, "residual of the LU solve");
    }
}
