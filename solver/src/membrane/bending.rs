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
//! Both discrete methods ([`BendingMethod`]) evaluate `H`, `K` and `Lap_s H`
//! at the nodes and insert them in this formula (the "node-wise" family of
//! Guckenberger et al., Comput. Phys. Commun. 207, 1 (2016)):
//! - [`BendingMethod::CotangentMethodC`]: the cotangent formulas, the paper's
//!   Method C ([`super::curvature::cotangent_curvatures`]). On the octahedron
//!   meshes `Lap_s H` does not converge (its max error grows as h^-2 at the
//!   valence-4 vertices, and even its L2 error stops decreasing): kept for
//!   comparison with the paper.
//! - [`BendingMethod::QuarticFit`] (default): local quartic fits
//!   ([`super::curvature::fitted_curvatures`]); the only one of the three
//!   whose force converges at every vertex (max error order ~1.2, L2 ~1.7).
//! - [`BendingMethod::QuarticFitGalerkin`]: `H`, `K`, `n` from the fits,
//!   `Lap_s H` by the P1 Galerkin Laplacian (consistent mass matrix) of the
//!   fitted `H` ([`super::curvature::fitted_galerkin_curvatures`]): smallest
//!   L2 and integrated errors, but an O(1) error at the valence-4 vertices.
//!
//! Measured errors (test `membrane_bending`, ignored study; tables in
//! `CONVERGENCE.md` beside this file): at 2048 triangles on the discocyte the
//! force errors (max / L2, relative) are 0.79 / 0.46 (Method C), 0.19 / 0.14
//! (fit), 0.96 / 0.24 (fit + Galerkin). The Laplace single layer of the force
//! error, a proxy of the velocity error of the BIM, is (max / mean) 3.9% /
//! 0.8% (Method C), 9.3% / 8.1% (fit), 5.0% / 0.5% (fit + Galerkin) at 2048
//! triangles and 6.8% / 0.3%, 2.5% / 2.1%, 2.5% / 0.1% at 8192: Method C's
//! max grows under refinement, the fit's errors are smooth and fall as h^2.
//!
//! The energy reported is the discrete `2 kB sum_i H_i^2 A_i`; the force is not
//! its exact gradient (neither method is variational), so total force and
//! torque vanish only up to the discretisation error (measured in the tests).

use nalgebra::Vector3;

use super::curvature::{
    cotangent_curvatures, fitted_curvatures, fitted_galerkin_curvatures, VertexCurvatures,
};
use super::error::{check_modulus, MembraneError};
use super::{MembraneLaw, UM};
use crate::mesh::Mesh;

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
    /// the default [`BendingMethod::QuarticFit`].
    pub fn new(kappa_b_n_m: f64) -> Result<Helfrich, MembraneError> {
        Self::with_method(kappa_b_n_m, BendingMethod::QuarticFit)
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
        let c = self.curvatures(mesh);
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
