//! The assembled free-space solve: membrane velocity from the membrane force density, viscosity ratio and background flow.

use std::convert::Infallible;
use std::time::Instant;

use nalgebra::Vector3;

use super::deflation::Wielandt;
use super::double_layer::DoubleLayer;
use super::near_field::NearField;
use super::single_layer::SingleLayer;
use super::surface::Surface;
use super::{BimError, BimOptions, SolveStats};
use crate::flow::BackgroundFlow;
use crate::gmres::{gmres, GmresOptions, GmresStop, Tolerance};
use crate::mesh::Mesh;
use crate::viscosity::ViscosityContrast;

/// A drop or capsule in unbounded Stokes flow: outer viscosity `mu` (Pa s), inner `lambda mu`.
///
/// Solves, at the vertices `x_i` of the membrane (see [`super`] for the discretisation),
///
/// ```text
/// (1+lambda)/2 u(x) = u_inf(x) + 1/(8 pi mu) Int_S G(x,y) . f(y) dS_y
///                     + (1-lambda)/(8 pi) PV Int_S u(y) . T(x,y) . n(y) dS_y
/// ```
///
/// i.e. `u - kappa K[u] = 2/(1+lambda) (u_inf + SL[f]/mu)`, `kappa = (1-lambda)/(1+lambda)`,
/// with `K` the [`DoubleLayer`] and `SL` the [`SingleLayer`]. For `lambda = 1` the double layer
/// vanishes and is not built: `u = u_inf + SL[f]/mu`.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeSpaceStokes {
    mu: f64,
    lambda: ViscosityContrast,
    opts: BimOptions,
}

/// `u - kappa K'[u]` (the GMRES operator; `K'` the double layer with the Wielandt deflation).
struct SecondKind<'a> {
    surface: &'a Surface,
    dl: DoubleLayer<'a>,
    kappa: f64,
    deflation: &'a Wielandt,
}

impl SecondKind<'_> {
    fn apply(&self, u: &[Vector3<f64>], y: &mut [Vector3<f64>]) -> Result<(), Infallible> {
        let mut k = self.dl.apply(u);
        self.deflation.apply(self.surface, u, &mut k);
        for ((y, u), k) in y.iter_mut().zip(u).zip(&k) {
            *y = u - k * self.kappa;
        }
        Ok(())
    }
}

impl FreeSpaceStokes {
    /// Outer viscosity `mu_pa_s` (Pa s, > 0), viscosity contrast `lambda = mu_in / mu` (valid by
    /// its type). The viscosity and the options are checked by [`Self::velocity`] (which returns
    /// [`BimError::InvalidParameter`]).
    pub fn new(mu_pa_s: f64, lambda: ViscosityContrast, opts: BimOptions) -> Self {
        Self { mu: mu_pa_s, lambda, opts }
    }

    /// Outer viscosity (Pa s).
    pub fn viscosity(&self) -> f64 {
        self.mu
    }

    /// Viscosity contrast `lambda = mu_in / mu`.
    pub fn viscosity_ratio(&self) -> ViscosityContrast {
        self.lambda
    }

    /// The numerical options.
    pub fn options(&self) -> &BimOptions {
        &self.opts
    }

    /// Membrane velocity (um/s) at the vertices of `mesh`.
    ///
    /// `traction_jump[i]` (Pa) is the force per unit area that the membrane exerts on the
    /// fluid at vertex `i`: `f = (sigma_in - sigma_out) . n` with `n` the outward normal, which
    /// is what the membrane laws return (elastic + bending force density). It is the negative of
    /// Pozrikidis' traction jump `Df = (sigma_out - sigma_in) . n`, so a positive `f . e` pushes
    /// the fluid, and a free drop, along `+e` (the Hadamard-Rybczynski test fixes this sign).
    /// `background` is the undisturbed flow `u_inf` (um/s), which must be a Stokes flow.
    pub fn velocity(
        &self,
        mesh: &Mesh,
        traction_jump: &[Vector3<f64>],
        background: &dyn BackgroundFlow,
    ) -> Result<(Vec<Vector3<f64>>, SolveStats), BimError> {
        self.velocity_with_guess(mesh, traction_jump, background, None)
    }

    /// As [`Self::velocity`], starting GMRES from `guess` (um/s at the vertices, e.g. the
    /// previous time step's velocity), which saves iterations in a time loop.
    pub fn velocity_with_guess(
        &self,
        mesh: &Mesh,
        traction_jump: &[Vector3<f64>],
        background: &dyn BackgroundFlow,
        guess: Option<&[Vector3<f64>]>,
    ) -> Result<(Vec<Vector3<f64>>, SolveStats), BimError> {
        self.check_parameters()?;
        let nv = mesh.vertices.len();
        if traction_jump.len() != nv {
            return Err(BimError::LengthMismatch { what: "traction_jump", expected: nv, got: traction_jump.len() });
        }
        if let Some(i) = traction_jump.iter().position(|f| !f.iter().all(|c| c.is_finite())) {
            return Err(BimError::NonFiniteInput { what: "traction_jump", vertex: i });
        }
        if let Some(g) = guess {
            if g.len() != nv {
                return Err(BimError::LengthMismatch { what: "guess", expected: nv, got: g.len() });
            }
        }
        let surface = Surface::new(mesh)?;
        let mut stats = SolveStats::default();

        // Right-hand side u_inf + SL[f] / mu (um/s).
        let t0 = Instant::now();
        let near = NearField::new(&surface, &self.opts.near_field);
        let sl = SingleLayer::new(&surface, self.opts.duffy_nodes, self.opts.subtract_normal_singularity)
            .with_near_field(&near)
            .apply(traction_jump);
        stats.single_layer_seconds = t0.elapsed().as_secs_f64();
        let mut rhs = Vec::with_capacity(nv);
        for (i, (x, v)) in surface.vertices.iter().zip(&sl).enumerate() {
            let ub = background.velocity(x);
            if !ub.iter().all(|c| c.is_finite()) {
                return Err(BimError::NonFiniteInput { what: "background velocity", vertex: i });
            }
            rhs.push(ub + v / self.mu);
        }

        let u = if self.lambda.is_matched() {
            rhs
        } else {
            let t1 = Instant::now();
            let kappa = self.lambda.kappa();
            let deflation = Wielandt::new(&surface, self.opts.deflate_rigid_body, self.opts.deflate_flux);
            let op = SecondKind { surface: &surface, dl: DoubleLayer::new(&surface).with_near_field(&near), kappa, deflation: &deflation };
            let scale = self.lambda.rhs_scale();
            let b: Vec<Vector3<f64>> = rhs.iter().map(|v| v * scale).collect();
            // Start from the guess mapped to the deflated unknown, else from 0: then the first
            // residual is b itself (no operator application), and the first Krylov step already
            // contains the best multiple of b.
            let mut x = match guess {
                Some(g) => deflation.deflate_guess(&surface, kappa, g),
                None => vec![Vector3::zeros(); b.len()],
            };
            let gopts = GmresOptions {
                tolerance: Tolerance::Relative(self.opts.gmres_tolerance),
                restart: self.opts.gmres_restart,
                max_iterations: self.opts.gmres_max_iterations,
            };
            let Ok(gs) = gmres(|u, y| op.apply(u, y), &b, &mut x, &gopts);
            match gs.stop {
                GmresStop::Converged => {}
                GmresStop::NonFinite => return Err(BimError::GmresNonFinite { iteration: gs.iterations }),
                GmresStop::MaxIterations | GmresStop::Stagnated => {
                    return Err(BimError::GmresDiverged { iterations: gs.iterations, residual: gs.relative_residual, tolerance: self.opts.gmres_tolerance })
                }
            }
            stats.iterations = gs.iterations;
            stats.operator_applications = gs.operator_applications;
            stats.restarts = gs.restarts;
            stats.residual = gs.relative_residual;
            let u = deflation.recover(&surface, kappa, &x);
            stats.gmres_seconds = t1.elapsed().as_secs_f64();
            u
        };
        if let Some(i) = u.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(BimError::NonFinite { vertex: i });
        }
        Ok((u, stats))
    }

    fn check_parameters(&self) -> Result<(), BimError> {
        let bad = |name, value, reason| Err(BimError::InvalidParameter { name, value, reason });
        if !(self.mu > 0.0 && self.mu.is_finite()) {
            return bad("mu_pa_s", self.mu, "the viscosity must be positive and finite");
        }
        let o = &self.opts;
        if !(o.gmres_tolerance > 0.0 && o.gmres_tolerance < 1.0) {
            return bad("gmres_tolerance", o.gmres_tolerance, "must lie in (0, 1)");
        }
        if o.gmres_restart == 0 || o.gmres_max_iterations == 0 {
            return bad("gmres_restart/gmres_max_iterations", 0.0, "must be positive");
        }
        Ok(())
    }
}
