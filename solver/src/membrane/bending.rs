//! Helfrich bending with zero spontaneous curvature: node-wise force density from discrete `H`, `K`, `Lap_s H` (Method C).
//!
//! Energy (Helfrich 1973 with `H0 = 0`; the paper's convention):
//! `E = 2 kB int H^2 dA`, `H = (k1 + k2)/2`.
//!
//! Force density on the fluid, with `n` outward and `H = div_s(n)/2 > 0` on a sphere:
//!
//! `Df = 2 kB [2 H (H^2 - K) + Lap_s H] n`.
//!
//! Proof of the sign: for a normal variation `dx = psi n`, `d(dA) = 2 H psi dA`
//! and `dH = -(Lap_s psi)/2 - (2 H^2 - K) psi` (e.g. Zhong-can & Helfrich,
//! PRA 39, 5280 (1989), with their `H` of opposite sign), so after two
//! integrations by parts
//! `dE = 2 kB int [2 H dH + H^2 2 H psi] dA = -2 kB int [Lap_s H + 2 H (H^2 - K)] psi dA`,
//! and `Df = -dE/dx` per area is the formula above. (physics.md writes
//! `-2 kB [...] n` with the opposite sign of `H`.) The test
//! `membrane_bending::analytic_force_is_minus_energy_variation` checks this
//! on spheroids by differentiating the exact energy.
//!
//! All three discrete methods ([`BendingMethod`]) evaluate `H`, `K` and `Lap_s H`
//! at the nodes and insert them in this formula (the "node-wise" family of
//! Guckenberger et al., Comput. Phys. Commun. 207, 1 (2016)):
//! - [`BendingMethod::CotangentMethodC`]: the cotangent formulas, the paper's
//!   Method C ([`super::curvature::cotangent_curvatures`]). On the octahedron
//!   meshes `Lap_s H` does not converge pointwise (its max error grows as
//!   h^-2 at the valence-4 vertices): kept for comparison with the paper.
//! - [`BendingMethod::QuarticFit`]: local quartic fits
//!   ([`super::curvature::fitted_curvatures`]); the only one of the three
//!   whose force converges at every vertex (max error order ~1.2, L2 ~1.7),
//!   but with a smooth systematic error that is large at the paper's resolution.
//! - [`BendingMethod::QuarticFitGalerkin`] (default): `H`, `K`, `n` from the
//!   fits, `Lap_s H` by the P1 Galerkin Laplacian (consistent mass matrix) of
//!   the fitted `H` ([`super::curvature::fitted_galerkin_curvatures`]):
//!   smallest L2 and integrated errors, an O(1) error at the six valence-4
//!   vertices only.
//!
//! Choice of the default, from the evidence (tables in `CONVERGENCE.md`):
//! 1. Dynamics, the decisive test: relaxation rate of shape mode l of a
//!    nearly spherical bending-only membrane against linear theory
//!    ([`crate::validation::bending_mode_rate`], `rbc-bench bending-relaxation`),
//!    relative errors at 512 / 2048 triangles:
//!    fit + Galerkin -1.3 % / -0.6 % (l = 2, lambda = 1), -0.5 % at lambda = 5 (2048),
//!    +1.2 % / +0.25 % (l = 3); Method C -6.5 % / -2.3 % (l = 2), -9.9 % / -2.7 % (l = 3);
//!    quartic fit -46 % / -9.9 % (l = 2), -9.8 % / -3.1 % (l = 3). (The O(eps)
//!    nonlinear bias of the eps0 = 0.01 runs is +-0.8 %, measured with -eps0.)
//! 2. What the boundary integral sees, the single layer of the force error on
//!    the discocyte (max / mean) at 2048 triangles: fit + Galerkin 5.0 % / 0.5 %,
//!    Method C 3.9 % / 0.8 % (its max grows under refinement: 13 % at 32768),
//!    quartic fit 9.3 % / 8.1 %.
//! 3. Pointwise (discocyte, max / L2, 2048 triangles): Method C 0.79 / 0.46,
//!    fit 0.19 / 0.14, fit + Galerkin 0.96 / 0.24 (the max at the valence-4
//!    vertices, which the flow averages out, as item 1 shows).
//!
//! So the default is the fit + Galerkin method: best in the dynamics and in
//! the BIM-weighted norm, converging in both; its cost (6 ms per force at 2048
//! triangles vs 0.9 ms for Method C) is small next to a Stokes solve, but its
//! stiffer high modes need ~2x more explicit steps than Method C when bending
//! limits the step (not for the paper's cell, where the area modulus does).
//!
//! The energy reported is the discrete `2 kB sum_i H_i^2 A_i`; the force is not
//! its exact gradient (no method here is variational), so the node-wise force
//! has a net force and torque of the size of the discretisation error; the
//! law removes them ([`super::remove_net_force_and_torque`]).

use nalgebra::Vector3;

use super::curvature::{
    cotangent_curvatures, cotangent_curvatures_with, fitted_curvatures, fitted_galerkin_curvatures, VertexCurvatures,
};
use super::error::{check_modulus, MembraneError};
use super::{MembraneLaw, UM};
use crate::mesh::{Mesh, Topology};

/// How the nodal curvatures are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BendingMethod {
    /// Cotangent Laplace-Beltrami, angle deficit: Method C of Guckenberger et al. 2016 (the paper's).
    CotangentMethodC,
    /// Local quartic height-function fits (converges at every vertex).
    QuarticFit,
    /// Quartic fits for `H`, `K`, `n`; Galerkin (consistent-mass) Laplacian for `Lap_s H`.
    QuarticFitGalerkin,
}

impl std::str::FromStr for BendingMethod {
    type Err = MembraneError;
    /// `method-c`, `quartic-fit` or `quartic-fit-galerkin` (the names used in scene files and logs).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "method-c" => Ok(BendingMethod::CotangentMethodC),
            "quartic-fit" => Ok(BendingMethod::QuarticFit),
            "quartic-fit-galerkin" => Ok(BendingMethod::QuarticFitGalerkin),
            _ => Err(MembraneError::UnknownName {
                what: "bending method",
                name: s.to_string(),
                expected: "method-c, quartic-fit, quartic-fit-galerkin",
            }),
        }
    }
}

/// Helfrich bending law (`kB` in N m = J).
#[derive(Debug, Clone, Copy)]
pub struct Helfrich {
    kappa_b: f64,
    method: BendingMethod,
}

impl Helfrich {
    /// Bending modulus `kappa_b_n_m` in N m (J), `>= 0` (paper: 3e-19), with
    /// the default [`BendingMethod::QuarticFitGalerkin`] (the choice is
    /// documented in the module header).
    pub fn new(kappa_b_n_m: f64) -> Result<Helfrich, MembraneError> {
        Self::with_method(kappa_b_n_m, BendingMethod::QuarticFitGalerkin)
    }

    /// Bending modulus (N m) and discrete method.
    pub fn with_method(kappa_b_n_m: f64, method: BendingMethod) -> Result<Helfrich, MembraneError> {
        Ok(Helfrich {
            kappa_b: check_modulus("Helfrich", "bending modulus", kappa_b_n_m, false)?,
            method,
        })
    }

    /// The discrete method in use.
    pub fn method(&self) -> BendingMethod {
        self.method
    }

    /// The node-wise force density `2 kB [2 H (H^2 - K) + Lap_s H] n` (Pa)
    /// before [`super::remove_net_force_and_torque`] (for the convergence
    /// studies, which measure its net force as a discretisation error).
    pub fn node_wise_force_density(&self, mesh: &Mesh) -> Vec<Vector3<f64>> {
        self.node_wise_force_density_with(mesh, None)
    }

    /// [`Self::node_wise_force_density`], with the mesh's connectivity when the caller has it
    /// (`topo = mesh.topology()`; Method C only uses it).
    pub fn node_wise_force_density_with(&self, mesh: &Mesh, topo: Option<&Topology>) -> Vec<Vector3<f64>> {
        let c = match (self.method, topo) {
            (BendingMethod::CotangentMethodC, Some(topo)) => cotangent_curvatures_with(mesh, topo),
            _ => self.curvatures(mesh),
        };
        let scale = 2.0 * self.kappa_b / (UM * UM * UM);
        (0..mesh.vertices.len())
            .map(|i| {
                let h = c.mean[i];
                c.normals[i] * (scale * (2.0 * h * (h * h - c.gaussian[i]) + c.laplacian_mean[i]))
            })
            .collect()
    }

    /// Nodal curvatures by the chosen method.
    pub fn curvatures(&self, mesh: &Mesh) -> VertexCurvatures {
        match self.method {
            BendingMethod::CotangentMethodC => cotangent_curvatures(mesh),
            BendingMethod::QuarticFit => fitted_curvatures(mesh),
            BendingMethod::QuarticFitGalerkin => fitted_galerkin_curvatures(mesh),
        }
    }
}

impl MembraneLaw for Helfrich {
    /// `Df_i = 2 kB [2 H_i (H_i^2 - K_i) + (Lap_s H)_i] n_i` (Pa: kB in J over
    /// curvatures in 1/um^3 gives 1e18 Pa), then
    /// [`super::remove_net_force_and_torque`] (the node-wise force is not an
    /// exact gradient, so its net force and torque are discretisation error).
    fn add_force_density(&self, mesh: &Mesh, out: &mut [Vector3<f64>]) {
        let mut f = self.node_wise_force_density(mesh);
        super::remove_net_force_and_torque(mesh, &mut f);
        for (o, fi) in out.iter_mut().zip(&f) {
            *o += fi;
        }
    }

    /// `K_b = dF_b/dx` (N/um) of the nodal bending force `F_i = Df_i A_i` (before the net force
    /// and torque are removed), by central differences over a distance colouring
    /// ([`super::bending_stiffness`]): the dense mobility Jacobian of `ros34pw2-mobility` then
    /// sees the bending modes, which otherwise limit its steps (`solver/README.md`).
    fn difference_stiffness(&self, mesh: &Mesh) -> Option<Vec<(usize, usize, f64)>> {
        if self.kappa_b == 0.0 {
            return None;
        }
        // the connectivity is that of `mesh` in every perturbed state: built once, not per force
        // evaluation (a few hundred of them)
        let topo = mesh.topology();
        let force = |m: &Mesh| -> Vec<Vector3<f64>> { super::nodal_forces(m, &self.node_wise_force_density_with(m, Some(&topo))) };
        let reach = super::bending_stiffness::measured_reach(mesh, &topo.vertex_neighbours, &force);
        Some(super::bending_stiffness::stiffness_triplets(mesh, &topo.vertex_neighbours, reach, &force))
    }

    /// Discrete energy `2 kB sum_i H_i^2 A_i` (J).
    fn energy(&self, mesh: &Mesh) -> f64 {
        let c = self.curvatures(mesh);
        2.0 * self.kappa_b
            * c.mean
                .iter()
                .zip(&c.areas)
                .map(|(h, a)| h * h * a)
                .sum::<f64>()
    }

    fn name(&self) -> &str {
        match self.method {
            BendingMethod::CotangentMethodC => "helfrich-method-c",
            BendingMethod::QuarticFit => "helfrich-quartic-fit",
            BendingMethod::QuarticFitGalerkin => "helfrich-quartic-fit-galerkin",
        }
    }
}
