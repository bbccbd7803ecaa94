//! rbc-solver: 3D Stokes boundary integral method (BIM) for a red blood cell in flow.
//!
//! Data flow: scene -> operators -> time loop -> results (written by `rbc-schema`).
//! - [`mesh`]: triangulated surfaces (sphere, Evans-Fung discocyte), geometry, quality.
//! - [`membrane`]: membrane force densities: Skalak (two named conventions), Helfrich bending, isotropic tension.
//! - [`gmres`]: the one Krylov solver (restarted, matrix-free, optionally right-preconditioned GMRES on vertex vectors)
//!   of the viscosity-contrast equation and of the implicit stages.
//! - [`bim`]: single and double layer operators on flat triangles, singularity removal, Wielandt deflation;
//!   the [`bim::Stokes`] trait every operator a cell sees implements.
//! - [`ewald`]: triply periodic Stokeslet and stresslet sums (spectral Ewald).
//! - [`channel`]: the paper's periodic microchannel: wall mesh, duct flow, wall operator, the solve with a cell.
//! - [`flow`]: undisturbed background flows (shear, unbounded Poiseuille).
//! - [`viscosity`]: the viscosity contrast `lambda` (one validated type) and the coefficients it gives the equation.
//! - [`dynamics`]: the right-hand sides: a cell's vertex velocities through a Stokes operator (free space, channel,
//!   penalty walls), the volume and kinematic projections.
//! - [`integrate`]: the time-stepping schemes only (adaptive Bogacki-Shampine 3(2), Rosenbrock-W ROS2 and ROS34PW2
//!   with their stiff-mode Jacobians and preconditioner) and failure detection; imports neither operators nor runner.
//! - [`state`]: the named arrays every stateful part saves in a checkpoint.
//! - [`scene`]: builds exactly the operators a scene needs.
//! - [`run`]: the driver loop, output callbacks and timing.
//! - [`steady`], [`classify`]: steady-state detection and the 3D shape class of a run.
//! - [`validation`]: the validation cases (scenes with a known answer from the literature) the tests and `rbc-bench` run.
//!
//! Levels (each imports only those before it, besides the error hub [`error`]): `mesh`, `flow`,
//! `state`, `viscosity`, `gmres` -> `membrane`, `bim` -> `ewald` -> `channel` -> `integrate` -> `dynamics` -> `run` ->
//! `scene` -> `validation`.
//!
//! Library code only: the speed measurements of these modules live with `rbc-bench`
//! (`src/bench/` of the `rbc` package), on their public API.
//!
//! Units: the solver works in SI-derived micro units: lengths in um, time in s,
//! viscosity in Pa s, moduli in N/m, bending modulus in N m; force densities in
//! Pa (N/m^2) converted where needed. Each function states its units.

pub mod bim;
pub mod channel;
pub mod classify;
pub mod dynamics;
pub mod error;
pub mod ewald;
pub mod flow;
pub mod gmres;
pub mod integrate;
pub mod membrane;
pub mod mesh;
pub mod run;
pub mod scene;
pub mod state;
pub mod steady;
pub mod validation;
pub mod viscosity;

pub use error::SolverError;
pub use mesh::Mesh;
