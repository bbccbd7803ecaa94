//! Triply periodic Stokeslet and stresslet sums by Ewald summation: Hasimoto's split, real space by a cell list, Fourier space by the spectral Ewald method (Gaussian gridding + FFT).
//!
//! [`PeriodicStokes`] evaluates, for targets `x_i` and sources `y_j` in a box
//! `[0, Lx) x [0, Ly) x [0, Lz)` repeated periodically (positions outside are wrapped),
//!
//! ```text
//! stokeslet:  u_i = sum_j G_per(x_i - y_j) . f_j
//! stresslet:  v_i = sum_j u_j . T_per(x_i - y_j) . n_j
//! ```
//!
//! in the conventions of [`crate::bim::kernels`] (`r = x - y`, `G = I/r + r r/r^3`,
//! `u . T . n = 6 (u . r)(r . n) r / r^5`; divide the Stokeslet sum by `8 pi mu` for a velocity,
//! the stresslet sum by `8 pi` or `4 pi` as the boundary integral equation says).
//!
//! ## The zero mode (k = 0)
//! Both periodic kernels are defined by their Fourier series without the `k = 0` term:
//! - Stokeslet: the velocity has zero mean over the box, and a net force `sum_j f_j` is balanced by a
//!   uniform mean pressure gradient `<grad p> = sum_j f_j / V` (Hasimoto 1959). A prescribed mean
//!   flow through the unit cell (the paper's driving) is therefore added by the caller as a uniform
//!   velocity (or, equivalently, as the pressure gradient that drives it).
//! - Stresslet: `(1/V) Int_box T_per dV = 0`. Then the divergence theorem on a closed surface `S`
//!   bounding a volume `V_b` gives (proven in `tests/ewald_identities.rs`)
//!   `Int_S T_per(x - y) . n(y) dS_y = -8 pi I (chi(x) - V_b / V)`, `chi` = 1 inside, 1/2 on `S`
//!   (principal value), 0 outside: the free-space `-4 pi I` on the surface is shifted by `8 pi V_b / V`.
//!   Consequence for a periodic double-layer operator `K = 1/(4 pi) PV Int u . T_per . n dS` on a rigid
//!   motion `u`: by the divergence theorem the extra term is `(2/V) Int_{V_b} u dV`, so a translation has
//!   the eigenvalue `-1 + 2 V_b / V` instead of `-1`, while rotations about the centroid keep `-1`
//!   (a Wielandt deflation of the periodic operator must use these values).
//!
//! ## Coincident target and source
//! A source closer than `1e-12 min(L)` to a target ([`direct::coincidence_radius`]) is "coincident";
//! [`Coincident`] selects what it adds to the Stokeslet sum. The stresslet adds nothing in either
//! case (`T_per - T` is odd and smooth, so it vanishes at 0).
//!
//! ## Accuracy and cost
//! [`EwaldParams::for_tolerance`] picks the parameters from error estimates ([`params`]); the
//! tests `ewald_accuracy` check the achieved error against [`direct`] sums. Real space costs
//! `O(N)` pairs per application at fixed density, the Fourier part `O(N P^3 + M^3 log M)`.
//! [`EwaldParams::for_sums`] balances the two for clustered points (a cell's membrane:
//! pairs `~ r^2`). For repeated sums over fixed geometry, [`blocks`] freezes the real-space part
//! into a block-sparse matrix over nodal values and [`PeriodicStokes::basis_spread`] and
//! [`PeriodicStokes::stresslet_basis_spread`] precompute the spreading of fixed sources (tests `ewald_blocks`).

pub mod blocks;
pub mod direct;
pub mod erfc;
pub mod fft3;
pub mod lanes;
pub mod lanes32;
pub mod params;
pub mod real_space;
pub mod spectral;
pub mod split;

use nalgebra::{Matrix3, Vector3};

use lanes32::BlockPrecision;
use real_space::CellList;
pub use blocks::{BlockRows, Interp, NodeGroups};
pub use spectral::{BasisSpread, StressletSpread};
use spectral::SpectralGrid;

/// What a source at (numerically) the same position as the target adds to the Stokeslet sum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Coincident {
    /// `lim_{r->0} [G_per(r) - G(r)] . f`: everything except the free-space singularity (its
    /// periodic images, the mean-pressure-gradient backflow). A boundary-integral operator adds the
    /// free-space singular part itself by its singular quadrature.
    #[default]
    Regular,
    /// Nothing: the sum runs over `j != i` only (point particles; the images of particle `i` itself are left out too).
    Exclude,
}

/// Ewald parameters (lengths in um).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EwaldParams {
    /// Splitting parameter (1/um).
    pub xi: f64,
    /// Real-space cutoff (um).
    pub r_cut: f64,
    /// FFT grid points per direction.
    pub grid: [usize; 3],
    /// Gaussian window points per direction (along the coarsest direction).
    pub support: usize,
    /// Coincident target/source handling of the Stokeslet sum.
    pub coincident: Coincident,
}

/// Why an Ewald sum could not be set up or evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EwaldError {
    #[error("invalid Ewald parameter {name} = {value}: {reason}")]
    InvalidParameter { name: &'static str, value: f64, reason: &'static str },
    #[error("{what} has {got} entries, expected {expected}")]
    LengthMismatch { what: &'static str, expected: usize, got: usize },
    #[error("non-finite {what} at index {index}")]
    NonFinite { what: &'static str, index: usize },
}

pub(crate) fn check_box(box_len: [f64; 3]) -> Result<(), EwaldError> {
    for l in box_len {
        if !(l > 0.0 && l.is_finite()) {
            return Err(EwaldError::InvalidParameter { name: "box side", value: l, reason: "must be positive and finite" });
        }
    }
    Ok(())
}

fn check_len(what: &'static str, got: usize, expected: usize) -> Result<(), EwaldError> {
    if got != expected {
        return Err(EwaldError::LengthMismatch { what, expected, got });
    }
    Ok(())
}

fn check_interp(interp: &[Interp], n_basis: usize) -> Result<(), EwaldError> {
    for (k, ip) in interp.iter().enumerate() {
        if ip.iter().any(|&(v, l)| v >= n_basis || !l.is_finite()) {
            return Err(EwaldError::NonFinite { what: "interpolation node (index beyond the basis or weight)", index: k });
        }
    }
    Ok(())
}

fn check_finite(what: &'static str, v: &[Vector3<f64>]) -> Result<(), EwaldError> {
    match v.iter().position(|p| !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite())) {
        Some(index) => Err(EwaldError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Fast periodic Stokeslet and stresslet sums (spectral Ewald) in a box of sides `box_len` (um).
#[derive(Debug)]
pub struct PeriodicStokes {
    box_len: [f64; 3],
    params: EwaldParams,
    grid: SpectralGrid,
    /// `lim_{r->0} [G_per - G]` (1/um), subtracted for [`Coincident::Exclude`].
    self_image: Matrix3<f64>,
    eps: f64,
}

impl PeriodicStokes {
    pub fn new(box_len: [f64; 3], params: EwaldParams) -> Result<Self, EwaldError> {
        check_box(box_len)?;
        let p = params;
        if !(p.xi > 0.0 && p.xi.is_finite()) {
            return Err(EwaldError::InvalidParameter { name: "xi", value: p.xi, reason: "must be positive" });
        }
        if !(p.r_cut > 0.0 && p.r_cut.is_finite()) {
            return Err(EwaldError::InvalidParameter { name: "r_cut", value: p.r_cut, reason: "must be positive" });
        }
        if p.support < 2 || p.grid.iter().any(|&m| m < p.support) {
            return Err(EwaldError::InvalidParameter {
                name: "support",
                value: p.support as f64,
                reason: "needs at least 2 points and no more than the grid",
            });
        }
        let self_image = match p.coincident {
            Coincident::Exclude => direct::self_image_tensor(box_len),
            Coincident::Regular => Matrix3::zeros(),
        };
        let grid = SpectralGrid::new(box_len, p.grid, p.support, p.xi);
        if !grid.window_fits() {
            return Err(EwaldError::InvalidParameter {
                name: "support",
                value: p.support as f64,
                reason: "the Gaussian window is as long as the grid period along some direction (refine the grid) or longer than 40 points",
            });
        }
        Ok(Self {
            box_len,
            params: p,
            grid,
            self_image,
            eps: direct::coincidence_radius(box_len),
        })
    }

    pub fn params(&self) -> &EwaldParams {
        &self.params
    }

    pub fn box_len(&self) -> [f64; 3] {
        self.box_len
    }

    /// The Gaussian shape `eta` of the spectral Ewald window (dimensionless).
    pub fn eta(&self) -> f64 {
        self.grid.eta()
    }

    /// `out_i = sum_j G_per(x_i - y_j) . f_j` (units of `f` per um; divide by `8 pi mu` for a velocity).
    pub fn stokeslet(
        &self,
        targets: &[Vector3<f64>],
        sources: &[Vector3<f64>],
        forces: &[Vector3<f64>],
        out: &mut [Vector3<f64>],
    ) -> Result<(), EwaldError> {
        check_len("forces", forces.len(), sources.len())?;
        check_len("out", out.len(), targets.len())?;
        check_finite("target", targets)?;
        check_finite("source", sources)?;
        check_finite("force", forces)?;
        self.stokeslet_real(targets, sources, forces, out);
        self.grid.stokeslet_add(targets, sources, forces, out);
        Ok(())
    }

    /// Only the real-space part of [`Self::stokeslet`] (for benchmarks and tests), written into `out`.
    pub fn stokeslet_real(&self, targets: &[Vector3<f64>], sources: &[Vector3<f64>], forces: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        let p = &self.params;
        let cells = CellList::new(self.box_len, p.r_cut, sources);
        let f = cells.sorted(forces);
        let (fx, fy, fz): (Vec<f64>, Vec<f64>, Vec<f64>) =
            (f.iter().map(|v| v.x).collect(), f.iter().map(|v| v.y).collect(), f.iter().map(|v| v.z).collect());
        // Coincident pair: the real-space limit -4 xi/sqrt(pi) I, minus all of lim [G_per - G] for `Exclude`.
        let self_term = Matrix3::identity() * split::stokeslet_real_self(p.xi) - self.self_image;
        real_space::stokeslet(&cells, p.xi, p.r_cut, self.eps, &self_term, targets, [&fx, &fy, &fz], out);
    }

    /// The real-space part of [`Self::stokeslet`] for sources carrying `w_k sum_v l_kv q_v` (nodal
    /// forces `q_v`, [`Interp`] per source) as a block-sparse matrix over the `n_basis` nodes
    /// ([`blocks`]): `out = B q` equals [`Self::stokeslet_real`] up to rounding.
    pub fn stokeslet_real_blocks(&self, targets: &[Vector3<f64>], sources: &[Vector3<f64>], weights: &[f64], interp: &[Interp], n_basis: usize) -> Result<BlockRows, EwaldError> {
        check_len("weights", weights.len(), sources.len())?;
        check_len("interp", interp.len(), sources.len())?;
        check_finite("target", targets)?;
        check_finite("source", sources)?;
        check_interp(interp, n_basis)?;
        let p = &self.params;
        let cells = CellList::new(self.box_len, p.r_cut, sources);
        let self_term = Matrix3::identity() * split::stokeslet_real_self(p.xi) - self.self_image;
        Ok(BlockRows::stokeslet(&cells, p.xi, p.r_cut, self.eps, &self_term, targets, &cells.sorted(weights), &cells.sorted(interp), n_basis))
    }

    /// [`Self::stokeslet_real_blocks`] for sources in groups of `m` consecutive quadrature nodes of
    /// one flat triangle each (every node of a group interpolates from the same three basis nodes,
    /// listed in the same order), built group by group in SIMD lanes
    /// ([`BlockRows::stokeslet_grouped`]): the same blocks up to rounding, cheaper. When a target
    /// coincides with a source (within the coincidence radius) the plain build is used, which
    /// gives that pair its self term.
    pub fn stokeslet_real_blocks_grouped(&self, targets: &[Vector3<f64>], sources: &[Vector3<f64>], weights: &[f64], interp: &[Interp], m: usize, n_basis: usize) -> Result<BlockRows, EwaldError> {
        check_len("weights", weights.len(), sources.len())?;
        check_len("interp", interp.len(), sources.len())?;
        check_finite("target", targets)?;
        check_finite("source", sources)?;
        check_interp(interp, n_basis)?;
        if !(1..=lanes::LANES).contains(&m) || !sources.len().is_multiple_of(m) {
            return Err(EwaldError::InvalidParameter { name: "nodes per group", value: m as f64, reason: "must be 1 to 8 and divide the number of sources" });
        }
        if let Some(k) = (0..sources.len()).find(|&k| (0..3).any(|c| interp[k][c].0 != interp[k - k % m][c].0)) {
            return Err(EwaldError::InvalidParameter { name: "interpolation node of a group", value: k as f64, reason: "every node of a group must interpolate from its group's three basis nodes" });
        }
        let p = &self.params;
        match BlockRows::stokeslet_grouped(self.box_len, p.xi, p.r_cut, self.eps, targets, sources, weights, interp, m, n_basis) {
            Some(blocks) => Ok(blocks),
            None => self.stokeslet_real_blocks(targets, sources, weights, interp, n_basis),
        }
    }

    /// The real-space part of [`Self::stresslet`] for sources with the densities `sum_v l_kv u_v`
    /// and weighted normals `n_k` as a block-sparse matrix over the `n_basis` nodes ([`blocks`]).
    pub fn stresslet_real_blocks(&self, targets: &[Vector3<f64>], sources: &[Vector3<f64>], normals_weighted: &[Vector3<f64>], interp: &[Interp], n_basis: usize) -> Result<BlockRows, EwaldError> {
        check_len("normals", normals_weighted.len(), sources.len())?;
        check_len("interp", interp.len(), sources.len())?;
        check_finite("target", targets)?;
        check_finite("source", sources)?;
        check_finite("normal", normals_weighted)?;
        check_interp(interp, n_basis)?;
        let p = &self.params;
        let cells = CellList::new(self.box_len, p.r_cut, sources);
        Ok(BlockRows::stresslet(&cells, p.xi, p.r_cut, self.eps, targets, &cells.sorted(normals_weighted), &cells.sorted(interp), n_basis))
    }

    /// [`Self::stresslet_real_blocks`] for the quadrature nodes of flat triangles ([`NodeGroups`]:
    /// each group's nodes interpolate from its three vertices with the rule's barycentric weights),
    /// built group by group ([`BlockRows::stresslet_grouped`]; the same blocks up to rounding, cheaper).
    pub fn stresslet_real_blocks_grouped(&self, targets: &[Vector3<f64>], src: NodeGroups<'_>, n_basis: usize) -> Result<BlockRows, EwaldError> {
        Ok(self.stresslet_real_blocks_with_single_layer(targets, src, None, n_basis, BlockPrecision::Double)?.0)
    }

    /// [`Self::stresslet_real_blocks_grouped`] and, with `forces` (the weighted forces `w_k f_k` of
    /// the sources, pN), the real-space part of [`Self::stokeslet`] of those forces at the targets
    /// from the same pairs ([`BlockRows::stresslet_grouped`]): with [`Self::stokeslet_fourier_add`]
    /// it is [`Self::stokeslet`] up to rounding, for a few multiply-adds a pair instead of a sum of its own.
    pub fn stresslet_real_blocks_with_single_layer(
        &self,
        targets: &[Vector3<f64>],
        src: NodeGroups<'_>,
        forces: Option<&[Vector3<f64>]>,
        n_basis: usize,
        precision: BlockPrecision,
    ) -> Result<(BlockRows, Option<Vec<Vector3<f64>>>), EwaldError> {
        let m = src.bary.len();
        if let Some(f) = forces {
            check_len("forces", f.len(), src.sources.len())?;
            check_finite("force", f)?;
        }
        check_len("sources", src.sources.len(), m * src.groups.len())?;
        check_len("normals", src.normals.len(), src.sources.len())?;
        check_finite("target", targets)?;
        check_finite("source", src.sources)?;
        check_finite("normal", src.normals)?;
        if let Some(g) = src.groups.iter().position(|g| g.iter().any(|&v| v >= n_basis)) {
            return Err(EwaldError::NonFinite { what: "group vertex (index beyond the basis)", index: g });
        }
        if src.bary.is_empty() || src.bary.len() > lanes::LANES {
            return Err(EwaldError::NonFinite { what: "nodes per group (1 to 8)", index: src.bary.len() });
        }
        if src.bary.iter().flatten().any(|l| !l.is_finite()) {
            return Err(EwaldError::NonFinite { what: "barycentric weight", index: 0 });
        }
        let p = &self.params;
        Ok(BlockRows::stresslet_grouped(self.box_len, p.xi, p.r_cut, self.eps, targets, src, forces, n_basis, precision))
    }

    /// The Fourier-space spreading of fixed sources with forces `w_k sum_v l_kv q_v`, as a sparse
    /// map from the nodal forces ([`SpectralGrid::basis_spread`]); use with [`Self::stokeslet_fourier_basis_add`].
    pub fn basis_spread(&self, sources: &[Vector3<f64>], weights: &[f64], interp: &[Interp], n_basis: usize) -> Result<BasisSpread, EwaldError> {
        check_len("weights", weights.len(), sources.len())?;
        check_len("interp", interp.len(), sources.len())?;
        check_finite("source", sources)?;
        check_interp(interp, n_basis)?;
        Ok(self.grid.basis_spread(sources, weights, interp, n_basis))
    }

    /// Adds the Fourier-space Stokeslet sum of the sources of `spread` with nodal forces `q` to `out`.
    pub fn stokeslet_fourier_basis_add(&self, spread: &BasisSpread, q: &[Vector3<f64>], targets: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), EwaldError> {
        check_len("out", out.len(), targets.len())?;
        check_finite("target", targets)?;
        check_finite("nodal force", q)?;
        self.grid.stokeslet_add_basis(spread, q, targets, out);
        Ok(())
    }

    /// The Fourier-space spreading of fixed sources with the densities `sum_v l_kv u_v` and weighted
    /// normals `n_k` (um^2), as a sparse map from the nodal densities: per node `v` and normal
    /// component `b` the grid weights `B_vb(x_m) = sum_k l_kv n_kb g(x_m - y_k)`, so that the spread
    /// `sym(u n^T)` is `(1/2) sum_v (u_va B_vb + u_vb B_va)` ([`SpectralGrid::stresslet_basis_spread`]);
    /// use with [`Self::stresslet_fourier_basis_add`].
    pub fn stresslet_basis_spread(&self, sources: &[Vector3<f64>], normals_weighted: &[Vector3<f64>], interp: &[Interp], n_basis: usize) -> Result<StressletSpread, EwaldError> {
        check_len("normals", normals_weighted.len(), sources.len())?;
        check_len("interp", interp.len(), sources.len())?;
        check_finite("source", sources)?;
        check_finite("normal", normals_weighted)?;
        check_interp(interp, n_basis)?;
        Ok(self.grid.stresslet_basis_spread(sources, normals_weighted, interp, n_basis))
    }

    /// Adds the Fourier-space stresslet sum of the sources of `spread` with nodal densities `u` to
    /// `out` (units of `u`): [`Self::stresslet_fourier_add`] of the densities `sum_v l_kv u_v`, up to rounding.
    pub fn stresslet_fourier_basis_add(&self, spread: &StressletSpread, u: &[Vector3<f64>], targets: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), EwaldError> {
        check_len("nodal densities", u.len(), spread.n_basis())?;
        check_len("out", out.len(), targets.len())?;
        check_finite("target", targets)?;
        check_finite("nodal density", u)?;
        self.grid.stresslet_add_basis(spread, u, targets, out);
        Ok(())
    }

    /// Only the Fourier-space part of [`Self::stokeslet`], added to `out`.
    pub fn stokeslet_fourier_add(&self, targets: &[Vector3<f64>], sources: &[Vector3<f64>], forces: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        self.grid.stokeslet_add(targets, sources, forces, out);
    }

    /// `out_i = sum_j u_j . T_per(x_i - y_j) . n_j`, `n_j` the quadrature-weighted normals (um^2):
    /// the quadrature of `Int_S u(y) . T_per(x, y) . n(y) dS_y` (units of `u`).
    pub fn stresslet(
        &self,
        targets: &[Vector3<f64>],
        sources: &[Vector3<f64>],
        strengths_u: &[Vector3<f64>],
        normals_weighted: &[Vector3<f64>],
        out: &mut [Vector3<f64>],
    ) -> Result<(), EwaldError> {
        check_len("strengths", strengths_u.len(), sources.len())?;
        check_len("normals", normals_weighted.len(), sources.len())?;
        check_len("out", out.len(), targets.len())?;
        check_finite("target", targets)?;
        check_finite("source", sources)?;
        check_finite("strength", strengths_u)?;
        check_finite("normal", normals_weighted)?;
        self.stresslet_real(targets, sources, strengths_u, normals_weighted, out);
        let q: Vec<[f64; 6]> = strengths_u.iter().zip(normals_weighted).map(|(u, n)| split::sym_outer(u, n)).collect();
        self.grid.stresslet_add(targets, sources, &q, out);
        Ok(())
    }

    /// Only the real-space part of [`Self::stresslet`], written into `out`.
    pub fn stresslet_real(
        &self,
        targets: &[Vector3<f64>],
        sources: &[Vector3<f64>],
        strengths_u: &[Vector3<f64>],
        normals_weighted: &[Vector3<f64>],
        out: &mut [Vector3<f64>],
    ) {
        let p = &self.params;
        let cells = CellList::new(self.box_len, p.r_cut, sources);
        let soa = |v: &[Vector3<f64>]| {
            let s = cells.sorted(v);
            [0, 1, 2].map(|d| s.iter().map(|w| w[d]).collect::<Vec<f64>>())
        };
        let (u, n) = (soa(strengths_u), soa(normals_weighted));
        real_space::stresslet(&cells, p.xi, p.r_cut, self.eps, targets, [&u[0], &u[1], &u[2]], [&n[0], &n[1], &n[2]], out);
    }

    /// Only the Fourier-space part of [`Self::stresslet`], added to `out`.
    pub fn stresslet_fourier_add(
        &self,
        targets: &[Vector3<f64>],
        sources: &[Vector3<f64>],
        strengths_u: &[Vector3<f64>],
        normals_weighted: &[Vector3<f64>],
        out: &mut [Vector3<f64>],
    ) {
        let q: Vec<[f64; 6]> = strengths_u.iter().zip(normals_weighted).map(|(u, n)| split::sym_outer(u, n)).collect();
        self.grid.stresslet_add(targets, sources, &q, out);
    }
}
