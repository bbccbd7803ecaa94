//! The periodic double layer of a cell with viscosity contrast, with the box-mean term of the zero-mode convention, and the Wielandt-deflated GMRES driver of the second-kind equation.
//!
//! ## The equation (Pozrikidis 1992, ch. 5-6, in a periodic box)
//! Outer viscosity `mu`, inner `lambda mu`, `f` the force per area the membrane exerts on the fluid.
//! Writing the inner stress as the outer one plus the extra stress `(lambda - 1) mu chi E(u)`
//! (`chi` = 1 inside the cell) and solving the one-viscosity Stokes problem with the periodic
//! Stokeslet `G_per` (no `k = 0` mode; the mean velocity of the box `U0` is added, the net force
//! balanced by a uniform body force), the extra stress becomes, after two integrations by parts,
//! the double layer plus the volume term `(1 - lambda) [chi u(x) - (1/V) Int_{V_b} u dV]`: the
//! periodic kernels produce fields of zero box mean, so the delta function of the free-space
//! derivation arrives with its mean removed (`div_y T_per = -8 pi (delta_per - 1/V)`). Hence, at
//! a point `x` of the fluid outside the cell,
//!
//! ```text
//! u(x) = U0 + 1/(8 pi mu) Int G_per f dS + (1 - lambda) [ 1/(8 pi) Int u . T_per . n dS - (1/V) Int_{V_b} u dV ]
//! ```
//!
//! and on the membrane (principal value, `chi = 1/2`)
//!
//! ```text
//! (1 + lambda)/2 u(x) = U0 + SL_per[f](x)/mu + (1 - lambda)/2 A[u](x),
//! A[u](x) = 1/(4 pi) PV Int_S u(y) . T_per(x - y) . n(y) dS_y - (2/V) Int_{V_b} u dV
//! ```
//!
//! with `Int_{V_b} u dV = Int_S (y - c) (u . n) dS` (divergence theorem, `div u = 0`; `c` any
//! point, the cell's vertex-area centroid here). Outside the cell the double-layer term is
//! `(1 - lambda)/2 E[u]`, `E[u](x) = 1/(4 pi) Int u . T_per . n dS - (2/V) Int_{V_b} u dV`.
//! Check with `u = e` everywhere (a uniform translation of everything, no force): by the periodic
//! identity `Int_S T_per . n dS = -8 pi I (chi - V_b/V)` ([`crate::ewald`]) `A[e] = -e` and `E[e] = 0`, as
//! the extra stress of a rigid motion vanishes.
//!
//! ## Eigenvalues and the deflation
//! `K_per = 1/(4 pi) PV Int u . T_per . n` alone maps a translation to `-(1 - 2 V_b/V) e`
//! (the shifted eigenvalue `-1 + 2 V_b/V`), a rotation about the volume centroid to minus itself;
//! the complete operator `A` maps every rigid motion to minus itself (the box-mean term restores
//! `-1`: exact on the discrete translation, by the subtraction below and the polyhedron's `V_b`).
//! `n` stays a left eigenvector, with eigenvalue `1 - 2 V_b/V` (flux of the periodic
//! double layer). The second-kind equation `u - kappa A[u] - W[u] = b`, `kappa =
//! (1 - lambda)/(1 + lambda)`, `W` the wall response (zero without walls), has the eigenvalue
//! `1 + kappa = 2/(1 + lambda)` on rigid motions, which vanishes as lambda grows. Wielandt's
//! deflation in the form of a right preconditioner removes it exactly whatever `W` is: GMRES
//! solves `L R w = b` with `R w = w - kappa/(1 + kappa) sum_i phi_i <phi_i, w>`
//! ([`crate::bim::deflation::Wielandt::recover`], the six orthonormal rigid modes `phi_i`), and
//! `u = R w` solves the original system; `L R phi_i = phi_i - W phi_i / (1 + kappa)` (the wall
//! response of a rigid motion vanishes in the continuum: `E[phi] = 0`).
//!
//! ## Discretisation
//! Collocation at the vertices, linear densities on flat triangles, the 7-point rule (as the
//! single layer). On the surface the density is subtracted at the target:
//! `A[u](x_i) = 1/(4 pi) sum_j (u_j - u_i) . T_per(x_i - y_j) . n_j - (1 - 2 V_b/V) u_i - (2/V) J[u]`,
//! with `sum_j u_i . T_per . n_j` from the free-space direct sums of constant unit densities plus
//! the smooth periodic part `8 pi V_b/V u_i` (its exact integral), and the PV identity for the rest. The free-space part of the touching (flat) triangles is zero
//! (`r . n = 0`), as in [`crate::bim::double_layer`].

use std::cell::Cell;
use std::time::Instant;

use nalgebra::{Matrix3, Vector3};

use super::cell_layer::{interpolate, CellNodes};
use super::ChannelError;
use rayon::prelude::*;

use crate::bim::deflation::Wielandt;
use crate::bim::kernels::stresslet_matrix_sum;
use crate::bim::near_field::NearField;
use crate::bim::surface::Surface;
use crate::bim::two_grid::TwoGrid;
use crate::ewald::lanes32::BlockPrecision;
use crate::ewald::{BlockRows, Interp, NodeGroups, PeriodicStokes, StressletSpread};
use crate::gmres::{gmres, gmres_preconditioned, GmresOptions, GmresStop, Tolerance};
use crate::viscosity::ViscosityContrast;

/// Values at the cell vertices and at the extra points.
pub type CellAndExtra = (Vec<Vector3<f64>>, Vec<Vector3<f64>>);

/// The periodic double-layer operator of one cell in the Ewald box, evaluated at the cell's
/// vertices (`A[u]`) and at extra points off the cell (`E[u]`), see the module docs.
pub struct PeriodicDoubleLayer<'a> {
    surface: &'a Surface,
    ewald: &'a PeriodicStokes,
    nodes: CellNodes,
    targets: Vec<Vector3<f64>>,
    /// `sum_j e_c . T_per(x_i - y_j) . n_j` as the columns `c` (dimensionless x 4 pi).
    self_sum: Vec<Matrix3<f64>>,
    centre: Vector3<f64>,
    /// `V_b / V` (polyhedron volume over box volume).
    volume_fraction: f64,
    box_volume: f64,
    /// The real-space part of the stresslet sum frozen into a block-sparse matrix over the
    /// vertex values ([`crate::ewald::blocks`]) and the spreading of the Fourier part as a sparse
    /// map from them ([`StressletSpread`]), when built by [`Self::with_real_blocks_and_single_layer`].
    frozen: Option<(BlockRows, StressletSpread)>,
    /// Near-singular correction at the cell vertices ([`crate::bim::near_field`]), when given.
    near: Option<&'a NearField>,
    /// Ewald sums and their wall time (s) so far.
    pub ewald_sums: Cell<usize>,
    pub ewald_seconds: Cell<f64>,
}

impl<'a> PeriodicDoubleLayer<'a> {
    /// `cell_volume` (um^3): the volume enclosed by the flat triangles; `extra`: points off the
    /// cell where `E[u]` is wanted (e.g. the wall vertices). Costs three free-space direct sums.
    pub fn new(
        surface: &'a Surface,
        cell_volume: f64,
        ewald: &'a PeriodicStokes,
        extra: &[Vector3<f64>],
    ) -> Result<Self, ChannelError> {
        let box_volume = ewald.box_len().iter().product::<f64>();
        let nodes = CellNodes::new(surface);
        // `sum_j T_per(x_i - y_j) . n_j` = the free-space quadrature (direct sums) plus the
        // periodic part, smooth, whose integral is `8 pi V_b/V I` (the periodic identity; the
        // 7-point rule reproduces it to 4e-9, test `periodic_double_layer_eigenvalues`): cheaper
        // than three Ewald sums, and free of their error.
        let volume_fraction = cell_volume / box_volume;
        let periodic = Matrix3::identity() * (8.0 * std::f64::consts::PI * volume_fraction);
        let self_sum: Vec<Matrix3<f64>> = surface
            .vertices
            .par_iter()
            .map(|x| periodic + stresslet_matrix_sum(x, &surface.chunk_template))
            .collect();
        let mut targets = surface.vertices.clone();
        targets.extend_from_slice(extra);
        Ok(Self {
            surface,
            ewald,
            nodes,
            targets,
            self_sum,
            centre: surface.centroid(),
            volume_fraction,
            box_volume,
            frozen: None,
            near: None,
            ewald_sums: Cell::new(0),
            ewald_seconds: Cell::new(0.0),
        })
    }

    /// As [`Self::new`], with the real-space part of the Ewald stresslet sum built once as a
    /// block-sparse matrix and the spreading of its Fourier part as a sparse map from the vertex
    /// values: each [`Self::apply`] then costs a mat-vec, a sparse spreading and the transforms (the
    /// same result up to rounding). Worth it when the operator is applied several times (GMRES).
    /// With `forces` (the weighted node forces of [`super::cell_layer::weighted_node_forces`], pN)
    /// also the real-space part of the cell's single layer at the same targets (cell vertices,
    /// then `extra`) from the same pairs, with the splitting of `ewald`
    /// ([`PeriodicStokes::stresslet_real_blocks_with_single_layer`]).
    pub fn with_real_blocks_and_single_layer(
        surface: &'a Surface,
        cell_volume: f64,
        ewald: &'a PeriodicStokes,
        extra: &[Vector3<f64>],
        forces: Option<&[Vector3<f64>]>,
        precision: BlockPrecision,
    ) -> Result<(Self, Option<Vec<Vector3<f64>>>), ChannelError> {
        let mut me = Self::new(surface, cell_volume, ewald, extra)?;
        let t0 = Instant::now();
        let bary = rule_bary(surface);
        let (blocks, single) = ewald.stresslet_real_blocks_with_single_layer(
            &me.targets,
            NodeGroups {
                sources: &me.nodes.positions,
                normals: &me.nodes.weighted_normals,
                groups: &surface.triangles,
                bary: &bary,
            },
            forces,
            surface.n_vertices(),
            precision,
        )?;
        let spread = ewald.stresslet_basis_spread(
            &me.nodes.positions,
            &me.nodes.weighted_normals,
            &node_interp(surface),
            surface.n_vertices(),
        )?;
        me.frozen = Some((blocks, spread));
        me.ewald_seconds.set(t0.elapsed().as_secs_f64());
        Ok((me, single))
    }

    /// Correct the free-space 7-point quadrature on the non-touching triangles close to each
    /// cell vertex ([`NearField`], built on the same surface).
    pub fn with_near_field(mut self, near: &'a NearField) -> Self {
        self.near = Some(near);
        self
    }

    /// `V_b / V`.
    pub fn volume_fraction(&self) -> f64 {
        self.volume_fraction
    }

    /// `J[u] = Int_S (y - c)(u . n) dS = Int_{V_b} u dV` (um^3 times the units of `u`), exact for
    /// linear `u` on the flat triangles (the 7-point rule integrates quadratics exactly).
    pub fn volume_integral(&self, u: &[Vector3<f64>]) -> Vector3<f64> {
        interpolate(self.surface, u)
            .iter()
            .zip(&self.nodes.positions)
            .zip(&self.nodes.weighted_normals)
            .map(|((u, y), nw)| (y - self.centre) * u.dot(nw))
            .sum()
    }

    /// `(A[u]` at the cell vertices, `E[u]` at the extra points`)`, in the units of `u`.
    /// One Ewald stresslet sum.
    pub fn apply(&self, u: &[Vector3<f64>]) -> Result<CellAndExtra, ChannelError> {
        let nc = self.surface.n_vertices();
        let mut out = vec![Vector3::zeros(); self.targets.len()];
        let t0 = Instant::now();
        match &self.frozen {
            Some((blocks, spread)) => {
                blocks.apply(u, &mut out);
                self.ewald
                    .stresslet_fourier_basis_add(spread, u, &self.targets, &mut out)?;
            }
            None => self.ewald.stresslet(
                &self.targets,
                &self.nodes.positions,
                &interpolate(self.surface, u),
                &self.nodes.weighted_normals,
                &mut out,
            )?,
        }
        self.ewald_sums.set(self.ewald_sums.get() + 1);
        self.ewald_seconds
            .set(self.ewald_seconds.get() + t0.elapsed().as_secs_f64());
        if let Some(near) = self.near {
            near.add_double_layer(u, 1.0, &mut out[..nc]);
        }
        let inv4pi = 1.0 / (4.0 * std::f64::consts::PI);
        let mean = self.volume_integral(u) * (2.0 / self.box_volume);
        let pv = 1.0 - 2.0 * self.volume_fraction;
        let at_cell = (0..nc)
            .map(|i| (out[i] - self.self_sum[i] * u[i]) * inv4pi - u[i] * pv - mean)
            .collect();
        let at_extra = out[nc..].iter().map(|o| o * inv4pi - mean).collect();
        Ok((at_cell, at_extra))
    }
}

/// The barycentric weights of the surface's quadrature rule: with the triangles, the
/// [`NodeGroups`] of the cell's nodes (in the order of [`CellNodes`]).
pub fn rule_bary(surface: &Surface) -> Vec<[f64; 3]> {
    surface.rule.iter().map(|node| node.bary).collect()
}

/// The cell's quadrature nodes (in the order of [`CellNodes`]) as barycentric combinations of its vertices.
pub fn node_interp(surface: &Surface) -> Vec<Interp> {
    let mut out = Vec::with_capacity(surface.n_nodes);
    for tri in &surface.triangles {
        for node in surface.rule.iter() {
            out.push([0, 1, 2].map(|c| (tri[c], node.bary[c])));
        }
    }
    out
}

/// GMRES settings and the outcome of a solve.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContrastStats {
    pub iterations: usize,
    pub residual: f64,
    pub restarts: usize,
    /// Wall time of GMRES including its operator applications (s).
    pub seconds: f64,
}

/// `L R`: the operator `L` after the Wielandt map `R` (identity without deflation).
struct Deflated<'a, F> {
    surface: &'a Surface,
    kappa: f64,
    deflation: Option<&'a Wielandt>,
    op: F,
}

impl<F> Deflated<'_, F>
where
    F: Fn(&[Vector3<f64>]) -> Result<Vec<Vector3<f64>>, ChannelError>,
{
    fn recover(&self, w: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
        match self.deflation {
            Some(d) => d.recover(self.surface, self.kappa, w),
            None => w.to_vec(),
        }
    }

    fn apply(&self, w: &[Vector3<f64>], y: &mut [Vector3<f64>]) -> Result<(), ChannelError> {
        y.copy_from_slice(&(self.op)(&self.recover(w))?);
        Ok(())
    }
}

/// Solve `L[u] = b` (`L` linear on the vertex velocities, e.g. `u - kappa A[u] - W[u]`) by GMRES,
/// right-preconditioned by the rigid-body Wielandt map `R` when `deflate` (see the module docs).
/// `guess` (a velocity) starts GMRES. `two_grid` (built for the same `kappa` and deflation)
/// right-preconditions the deflated equation as well ([`TwoGrid`]). Non-convergence is
/// [`ChannelError::GmresDiverged`].
#[allow(clippy::too_many_arguments)]
pub fn solve_second_kind<F>(
    surface: &Surface,
    lambda: ViscosityContrast,
    b: &[Vector3<f64>],
    guess: Option<&[Vector3<f64>]>,
    deflate: bool,
    two_grid: Option<&TwoGrid>,
    opts: &GmresOptions,
    op: F,
) -> Result<(Vec<Vector3<f64>>, ContrastStats), ChannelError>
where
    F: Fn(&[Vector3<f64>]) -> Result<Vec<Vector3<f64>>, ChannelError>,
{
    let t0 = Instant::now();
    let kappa = lambda.kappa();
    let wielandt = deflate.then(|| Wielandt::new(surface, true, false));
    let d = Deflated {
        surface,
        kappa,
        deflation: wielandt.as_ref(),
        op,
    };
    let mut x = match (guess, &wielandt) {
        (Some(g), Some(w)) => w.deflate_guess(surface, kappa, g),
        (Some(g), None) => g.to_vec(),
        (None, _) => vec![Vector3::zeros(); surface.n_vertices()],
    };
    let gs = match two_grid {
        Some(p) => gmres_preconditioned(|w, y| d.apply(w, y), |v| p.apply(v), b, &mut x, opts)?,
        None => gmres(|w, y| d.apply(w, y), b, &mut x, opts)?,
    };
    match gs.stop {
        GmresStop::Converged => {}
        GmresStop::NonFinite => {
            return Err(ChannelError::GmresNonFinite {
                lambda: lambda.lambda(),
                iteration: gs.iterations,
            })
        }
        GmresStop::MaxIterations | GmresStop::Stagnated => {
            return Err(ChannelError::GmresDiverged {
                lambda: lambda.lambda(),
                iterations: gs.iterations,
                residual: gs.relative_residual,
                tolerance: match opts.tolerance {
                    Tolerance::Relative(t) | Tolerance::Absolute(t) => t,
                },
            })
        }
    }
    let u = d.recover(&x);
    Ok((
        u,
        ContrastStats {
            iterations: gs.iterations,
            residual: gs.relative_residual,
            restarts: gs.restarts,
            seconds: t0.elapsed().as_secs_f64(),
        },
    ))
}
