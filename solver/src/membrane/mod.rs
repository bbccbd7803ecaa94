//! Membrane force densities on triangle meshes: Skalak elasticity (two named conventions), Helfrich bending, isotropic tension.
//!
//! Every law implements [`MembraneLaw`]: it adds, at each vertex, the force
//! per unit area that the membrane exerts on the surrounding fluid, the
//! traction jump `Df` of the boundary integral equation (physics.md). For an
//! energy `E(x)` this is the nodal force `F_i = -dE/dx_i` divided by the vertex
//! area `A_i` ([`Mesh::vertex_areas`]: Meyer's mixed Voronoi area, which makes
//! `F_i / A_i` converge pointwise to the continuum traction also at irregular
//! vertices; see there). The nodal forces are conserved exactly
//! (`sum_i F_i = 0`, `sum_i x_i x F_i = 0` for the elastic laws); the surface
//! integral of the linearly interpolated density, `sum_i Df_i A_bary_i`,
//! differs from `sum_i F_i` by the discretisation error (O(h^2) on smooth meshes).
//!
//! Units: lengths in um, moduli in N/m, bending modulus in N m (= J), energy in
//! J, force density in Pa (N/m^2), nodal force in N. The conversion factors
//! are [`UM`] and friends below; each law states its formula with units.
//!
//! Signs: a positive tension pulls the surface inward (`Df = -2 gamma H n` on a
//! sphere with outward `n` and `H = 1/R > 0`), so an inflated capsule pushes
//! the fluid inward, as it must to hold a larger inner pressure.

pub mod bending;
pub mod curvature;
mod error;
pub mod linear;
pub mod skalak;
pub mod tension;
pub mod timing;

use nalgebra::Vector3;

use crate::mesh::Mesh;

pub use error::MembraneError;
pub use linear::{LinearisedLaw, LinearisedSum};

/// One micrometre in metres.
pub const UM: f64 = 1e-6;

/// A membrane constitutive law evaluated on a deformed mesh.
pub trait MembraneLaw: Send + Sync {
    /// Adds to `out[i]` the force per unit area (Pa) that the membrane exerts
    /// on the fluid at vertex `i` (`out.len() == mesh.vertices.len()`).
    fn add_force_density(&self, mesh: &Mesh, out: &mut [Vector3<f64>]);

    /// Energy of the membrane in this state (J). For energy-based laws the
    /// force density is exactly `-dE/dx_i / A_i`; for the node-wise bending
    /// method it is the discrete energy the method approximates (see there).
    fn energy(&self, mesh: &Mesh) -> f64;

    /// Short name for logs and scene files.
    fn name(&self) -> &str;

    /// The assembled nodal stiffness `K = dF/dx` (N/um) as `(row, column, value)`
    /// triplets, duplicates to be summed ([`LinearisedLaw::stiffness_triplets`]), for the
    /// laws that can assemble it (Skalak, tension); `None` (the default) otherwise.
    /// Used by the local Jacobian that preconditions implicit time steps
    /// ([`crate::integrate::precondition`]).
    fn assembled_stiffness(&self, _mesh: &Mesh) -> Option<Vec<(usize, usize, f64)>> {
        None
    }

    /// Convenience: a fresh vector of force densities (Pa).
    fn force_density(&self, mesh: &Mesh) -> Vec<Vector3<f64>> {
        let mut out = vec![Vector3::zeros(); mesh.vertices.len()];
        self.add_force_density(mesh, &mut out);
        out
    }
}

/// Nodal forces (N) from force densities (Pa): `F_i = Df_i A_i` with the
/// vertex areas of [`Mesh::vertex_areas`] (um^2, converted to m^2); the exact
/// inverse of the density conversion used by every law.
pub fn nodal_forces(mesh: &Mesh, density: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    mesh.vertex_areas()
        .iter()
        .zip(density)
        .map(|(&a, f)| f * (a * UM * UM))
        .collect()
}

/// Total force (N) and torque about `origin` (N m; `origin` in um) of the
/// nodal forces of densities `Df` (Pa): `sum_i F_i` and `sum_i (x_i - origin) x F_i`
/// with `F_i = Df_i A_i` ([`nodal_forces`]).
pub fn total_force_and_torque(
    mesh: &Mesh,
    density: &[Vector3<f64>],
    origin: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let f = nodal_forces(mesh, density);
    let total = f.iter().sum();
    let torque = mesh
        .vertices
        .iter()
        .zip(&f)
        .map(|(x, fi)| (x - origin).cross(fi) * UM)
        .sum();
    (total, torque)
}

/// Several laws acting together (e.g. Skalak + Helfrich): forces and energies add.
#[derive(Default)]
pub struct Membrane {
    pub laws: Vec<Box<dyn MembraneLaw>>,
}

impl Membrane {
    /// An empty membrane (no force).
    pub fn new() -> Self {
        Membrane { laws: Vec::new() }
    }

    /// Adds a law (builder style).
    pub fn with(mut self, law: impl MembraneLaw + 'static) -> Self {
        self.laws.push(Box::new(law));
        self
    }
}

impl MembraneLaw for Membrane {
    fn add_force_density(&self, mesh: &Mesh, out: &mut [Vector3<f64>]) {
        for law in &self.laws {
            law.add_force_density(mesh, out);
        }
    }
    fn energy(&self, mesh: &Mesh) -> f64 {
        self.laws.iter().map(|l| l.energy(mesh)).sum()
    }
    fn name(&self) -> &str {
        "membrane"
    }
    /// The summed stiffness of the laws that have one (laws without, e.g. bending, are left out).
    fn assembled_stiffness(&self, mesh: &Mesh) -> Option<Vec<(usize, usize, f64)>> {
        let parts: Vec<_> = self.laws.iter().filter_map(|l| l.assembled_stiffness(mesh)).collect();
        (!parts.is_empty()).then(|| parts.concat())
    }
}
