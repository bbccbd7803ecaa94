//! Membrane force densities on triangle meshes: Skalak elasticity (two named conventions), Helfrich bending, isotropic tension.
//!
//! Every law implements [`MembraneLaw`]: it adds, at each vertex, the force
//! per unit area that the membrane exerts on the surrounding fluid, the
//! traction jump `Df` of the boundary integral equation (physics.md). For an
//! energy `E(x)` this is the nodal force `F_i = -dE/dx_i` divided by the vertex
//! area `A_i` ([`Mesh::vertex_areas`]: Meyer's mixed Voronoi area, which makes
//! `F_i / A_i` converge pointwise to the continuum traction also at irregular
//! vertices; see there). The nodal forces are conserved exactly
//! (`sum_i F_i = 0`, `sum_i x_i x F_i = 0` for the elastic laws), but the
//! boundary integral method integrates the *linear interpolant* of `Df`
//! (barycentric weights), for which `F_i / A_i` has a net force of the size of
//! the discretisation error; every law therefore ends with
//! [`remove_net_force_and_torque`], after which total force and torque of the
//! density, integrated the BIM's way ([`total_force_and_torque`]), vanish to
//! round-off (test `membrane_conservation`).
//!
//! Units: lengths in um, moduli in N/m, bending modulus in N m (= J), energy in
//! J, force density in Pa (N/m^2), nodal force in N. The conversion factors
//! are [`UM`] and friends below; each law states its formula with units.
//!
//! Signs: a positive tension pulls the surface inward (`Df = -2 gamma H n` on a
//! sphere with outward `n` and `H = 1/R > 0`), so an inflated capsule pushes
//! the fluid inward, as it must to hold a larger inner pressure.

pub mod bending;
pub mod bending_stiffness;
pub mod curvature;
mod error;
pub mod linear;
pub mod skalak;
pub mod tension;

use nalgebra::{Matrix3, Vector3};

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

    /// The nodal stiffness (N/um, triplets as [`Self::assembled_stiffness`]) of a law that has
    /// no assembled form but whose force at a vertex depends only on nearby vertices (bending),
    /// by central differences over a colouring of the mesh ([`bending_stiffness`]); `None` (the
    /// default) for the others. A few hundred force evaluations: for Jacobians kept over several
    /// steps.
    fn difference_stiffness(&self, _mesh: &Mesh) -> Option<Vec<(usize, usize, f64)>> {
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
/// mixed Voronoi vertex areas of [`Mesh::vertex_areas`] (um^2, converted to
/// m^2): the inverse of the density conversion of the laws before
/// [`remove_net_force_and_torque`] (used to weigh force magnitudes).
pub fn nodal_forces(mesh: &Mesh, density: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    mesh.vertex_areas()
        .iter()
        .zip(density)
        .map(|(&a, f)| f * (a * UM * UM))
        .collect()
}

/// Per-triangle sums of the integrals of the linear interpolants of `x - origin`
/// (um) and `Df` (Pa) over flat triangles: `(area, int r dA, int Df dA, int r x Df dA, int (|r|^2 I - r r^T) dA)`
/// with the exact P1 formulas `int phi_i phi_j dA = A (1 + delta_ij) / 12`.
fn linear_moments(
    mesh: &Mesh,
    density: &[Vector3<f64>],
    origin: &Vector3<f64>,
) -> (f64, Vector3<f64>, Vector3<f64>, Vector3<f64>, Matrix3<f64>) {
    let (mut area, mut first) = (0.0, Vector3::zeros());
    let (mut force, mut torque, mut inertia) = (Vector3::zeros(), Vector3::zeros(), Matrix3::zeros());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let x = mesh.corners(t);
        let a = 0.5 * (x[1] - x[0]).cross(&(x[2] - x[0])).norm();
        let r = x.map(|p| p - origin);
        let f = tri.map(|i| density[i]);
        let (sr, sf) = (r[0] + r[1] + r[2], f[0] + f[1] + f[2]);
        area += a;
        first += sr * (a / 3.0);
        force += sf * (a / 3.0);
        let mut t_sum = sr.cross(&sf);
        let mut j_sum = Matrix3::identity() * sr.norm_squared() - sr * sr.transpose();
        for k in 0..3 {
            t_sum += r[k].cross(&f[k]);
            j_sum += Matrix3::identity() * r[k].norm_squared() - r[k] * r[k].transpose();
        }
        torque += t_sum * (a / 12.0);
        inertia += j_sum * (a / 12.0);
    }
    (area, first, force, torque, inertia)
}

/// Total force (N) and torque about `origin` (N m; `origin` in um) of the
/// force density `Df` (Pa) as the boundary integral method sees it: the
/// surface integrals `int Df dA` and `int (x - origin) x Df dA` of the
/// piecewise-linear interpolant of the nodal values on the flat triangles
/// (what the 7-point Gauss rule of [`crate::bim`] integrates exactly).
pub fn total_force_and_torque(
    mesh: &Mesh,
    density: &[Vector3<f64>],
    origin: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let (_, _, f, t, _) = linear_moments(mesh, density, origin);
    (f * (UM * UM), t * (UM * UM * UM))
}

/// Makes the total force and torque of a force density (Pa), integrated the
/// boundary integral method's way ([`total_force_and_torque`]), vanish to
/// round-off, by subtracting the rigid-body field `g(x) = a + b x (x - c)`
/// with `int g dA = int Df dA` and `int (x - c) x g dA = int (x - c) x Df dA`:
/// `c` the area centroid, `a = int Df dA / A`, `b = J^{-1} int (x - c) x Df dA`,
/// `J = int (|x - c|^2 I - (x - c)(x - c)^T) dA` (the surface's inertia
/// tensor, positive definite for a closed surface). `g` is linear in `x`, so
/// its nodal values interpolate it exactly and the subtraction is exact.
///
/// Why: the laws divide nodal forces by the mixed Voronoi areas (pointwise
/// convergence, see [`Mesh::vertex_areas`]), while the BIM integrates the
/// linear interpolant, i.e. weighs node `i` by its barycentric area; the two
/// differ by O(1) at irregular vertices (valence 4 on the octahedron meshes),
/// which gave a net force of ~6e-3 of `sum |F_i|` on deformed capsules, and the
/// node-wise bending force has a discretisation error with a net force and
/// torque. A free membrane exerts no net force or torque on the fluid; the
/// correction is of the size of that discretisation error (O(h^2) for the
/// elastic laws), so it keeps the pointwise convergence of the density while
/// removing the spurious drift and rotation it would cause. (Dividing by the
/// barycentric areas instead, or by the consistent mass matrix, makes the
/// total force exact but the density 50% wrong at valence-4 vertices: the
/// area gradient is `2 H n A_mixed`, not `2 H n A_bary`.)
pub fn remove_net_force_and_torque(mesh: &Mesh, density: &mut [Vector3<f64>]) {
    if mesh.triangles.is_empty() {
        return;
    }
    let (area, first, _, _, _) = linear_moments(mesh, density, &Vector3::zeros());
    let c = first / area;
    let (_, _, f, t, j) = linear_moments(mesh, density, &c);
    let a = f / area;
    // J is SPD for any closed surface with non-zero area; if it is not
    // invertible (degenerate input) only the force is removed.
    let b = j.try_inverse().map(|ji| ji * t).unwrap_or_else(Vector3::zeros);
    for (d, x) in density.iter_mut().zip(&mesh.vertices) {
        *d -= a + b.cross(&(x - c));
    }
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
    /// The summed difference stiffness of the laws that have one.
    fn difference_stiffness(&self, mesh: &Mesh) -> Option<Vec<(usize, usize, f64)>> {
        let parts: Vec<_> = self.laws.iter().filter_map(|l| l.difference_stiffness(mesh)).collect();
        (!parts.is_empty()).then(|| parts.concat())
    }
}
