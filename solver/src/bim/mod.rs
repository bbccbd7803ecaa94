//! Boundary integral method for Stokes flow past a membrane with viscosity contrast, on flat triangles (free space).
//!
//! The membrane velocity `u` at the vertices `x` of a closed triangulated surface `S`
//! (outward normal `n`) solves (Pozrikidis, "Boundary integral and singularity methods for
//! linearized viscous flow", 1992, ch. 5-6, with his `Df = -f` below)
//!
//! ```text
//! (1+lambda)/2 u(x) = u_inf(x) + 1/(8 pi mu) Int_S G(x,y) . f(y) dS_y
//!                     + (1-lambda)/(8 pi) PV Int_S u(y) . T(x,y) . n(y) dS_y
//! ```
//!
//! where `f` is the force per area that the membrane exerts on the fluid (Pa), i.e.
//! `f = (sigma_in - sigma_out) . n`, minus Pozrikidis' traction jump
//! `Df = (sigma_out - sigma_in) . n`; `G` is the Stokeslet and `T` the stresslet in
//! Pozrikidis' sign convention (see [`kernels`]), for which `PV Int_S T . n dS = -4 pi I`
//! on a closed surface (proven by the tests `double_layer` and `bim_free_space`).
//!
//! Discretisation (as in the paper, Guckenberger et al. 2018, "Simulation setup"):
//! collocation at the vertices, linear interpolation of nodal quantities on flat triangles,
//! the 7-point Gauss rule ([`quadrature::gauss7`]), singularity removal
//! ([`single_layer`]: `Int G . n dS = 0` for the normal part plus a Duffy rule on the
//! triangles touching the target; [`double_layer`]: subtraction of `u(x)`), restarted
//! GMRES ([`crate::gmres`]) on the Wielandt-deflated second-kind equation ([`deflation`]).
//!
//! Units: lengths um, viscosity Pa s, force per area Pa, velocities um/s
//! (`Pa um / (Pa s) = um/s`).

pub mod deflation;
pub mod double_layer;
pub mod free_space;
pub mod kernels;
pub mod near_field;
pub mod quadrature;
pub mod single_layer;
pub mod stokes;
pub mod surface;
pub mod two_grid;

pub use free_space::FreeSpaceStokes;
pub use stokes::Stokes;

/// Numerical options of the boundary-integral solve. `Default` gives the paper's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct BimOptions {
    /// GMRES stops at `|b - A u| <= tolerance |b|` (the paper: 1e-5).
    pub gmres_tolerance: f64,
    /// Krylov dimension before a restart (40: the deflated operator at lambda = 5 converges in ~10, so restarts are rare).
    pub gmres_restart: usize,
    /// Total GMRES iterations (operator applications) before giving up with [`BimError::GmresDiverged`].
    pub gmres_max_iterations: usize,
    /// Wielandt deflation of the eigenvalue -1 of the double-layer operator (rigid-body motions);
    /// it keeps the equation well conditioned as lambda grows (Pozrikidis 1992, ch. 4 and 6).
    pub deflate_rigid_body: bool,
    /// Wielandt deflation of the eigenvalue +1 (left eigenvector `n`), which makes the equation
    /// singular as lambda -> 0 (lambda itself is > 0: [`crate::viscosity`]). The deflated solution has the net flux
    /// `<n, u> = <n, b>` of the right-hand side, which is zero up to the discretisation error
    /// of the single layer (measured: 1.2e-4 of `max|u| area` on the 2048-triangle discocyte at
    /// lambda = 5, vs 7e-5 without this deflation; both second order in h).
    pub deflate_flux: bool,
    /// Subtract `q(x) . n(x) Int_S G . n dS (= 0)` from the single layer.
    pub subtract_normal_singularity: bool,
    /// Duffy rule on the triangles touching the target: Gauss-Legendre points in the radial (`s`)
    /// and angular (`t`) direction. (1, 10): the transformed integrand is linear in `s` (one point
    /// is exact) and analytic in `t` (10 points: relative error ~1e-9 on a right triangle).
    pub duffy_nodes: (usize, usize),
    /// Adaptive quadrature on the non-touching triangles close to a target ([`near_field`]):
    /// the next rings of the same sheet and other parts of the membrane that come within
    /// `reach` triangle sizes (folding cells). [`near_field::NearFieldOptions::off`] restores the plain 7-point rule.
    pub near_field: near_field::NearFieldOptions,
}

impl Default for BimOptions {
    fn default() -> Self {
        Self {
            gmres_tolerance: 1e-5,
            gmres_restart: 40,
            gmres_max_iterations: 400,
            deflate_rigid_body: true,
            deflate_flux: true,
            subtract_normal_singularity: true,
            duffy_nodes: (1, 10),
            near_field: near_field::NearFieldOptions::default(),
        }
    }
}

/// What a solve cost and how well it converged.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolveStats {
    /// GMRES iterations (double-layer applications inside Arnoldi); 0 when lambda = 1.
    pub iterations: usize,
    /// Final relative residual `|b - A u| / |b|` of the (deflated) second-kind equation; 0 when lambda = 1.
    pub residual: f64,
    /// GMRES restarts.
    pub restarts: usize,
    /// Double-layer applications (GMRES iterations plus true residuals at warm starts and restarts).
    pub operator_applications: usize,
    /// Wall time of the single layer (s).
    pub single_layer_seconds: f64,
    /// Wall time of GMRES including its double-layer applications (s).
    pub gmres_seconds: f64,
}

/// Why a boundary-integral solve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BimError {
    #[error("GMRES did not reach the relative residual {tolerance:e} after {iterations} iterations (residual {residual:e})")]
    GmresDiverged { iterations: usize, residual: f64, tolerance: f64 },
    #[error("GMRES produced a non-finite value at iteration {iteration}")]
    GmresNonFinite { iteration: usize },
    #[error("non-finite velocity at vertex {vertex}")]
    NonFinite { vertex: usize },
    #[error("non-finite {what} at vertex {vertex}")]
    NonFiniteInput { what: &'static str, vertex: usize },
    #[error("{what} has {got} entries for a mesh of {expected} vertices")]
    LengthMismatch { what: &'static str, expected: usize, got: usize },
    #[error("triangle {triangle}: {reason}")]
    BadTriangle { triangle: usize, reason: &'static str },
    #[error("vertex {vertex}: {reason}")]
    BadVertex { vertex: usize, reason: &'static str },
    #[error("the mesh has no vertices or no triangles")]
    EmptyMesh,
    #[error("invalid parameter {name} = {value}: {reason}")]
    InvalidParameter { name: &'static str, value: f64, reason: &'static str },
}
