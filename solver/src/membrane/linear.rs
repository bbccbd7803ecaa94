//! Linearisation of the elastic laws (Skalak, tension) for stiff-aware time integrators.

use nalgebra::{SMatrix, Vector3};

use crate::mesh::Mesh;

/// A law whose nodal force `F(x) = -dE/dx` (N) can be linearised about a state.
///
/// The stiffness `K = dF/dx = -d^2E/dx^2` is symmetric (a Hessian) and, about a
/// stress-free state, negative semi-definite. Units: `K v` is in N when the
/// displacement `v` is in um (so `K` is in N/um). To linearise the force
/// *density* at frozen vertex areas divide row `i` by `A_i` (um^2) and by
/// `1e-12` (m^2/um^2).
pub trait LinearisedLaw: Send + Sync {
    /// Per-triangle stiffness blocks: for triangle `t`, `K_t` is `9 x 9`,
    /// ordered `(vertex 0: x, y, z; vertex 1: ...; vertex 2: ...)` of
    /// `mesh.triangles[t]`; `K = sum_t K_t` assembled on those vertices (N/um).
    fn triangle_stiffness(&self, mesh: &Mesh, t: usize) -> SMatrix<f64, 9, 9>;

    /// Adds `K v` to `out` (N for `v` in um): the change of the nodal forces
    /// for a small displacement `v`.
    fn add_nodal_force_jvp(&self, mesh: &Mesh, v: &[Vector3<f64>], out: &mut [Vector3<f64>]);

    /// The assembled stiffness `K` (3n x 3n, N/um) as `(row, column, value)`
    /// triplets, duplicates to be summed (e.g. by faer's
    /// `SparseColMat::try_new_from_triplets`); row `3 i + k` is component `k` of vertex `i`.
    fn stiffness_triplets(&self, mesh: &Mesh) -> Vec<(usize, usize, f64)> {
        let mut out = Vec::with_capacity(81 * mesh.triangles.len());
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let k = self.triangle_stiffness(mesh, t);
            for a in 0..3 {
                for b in 0..3 {
                    for i in 0..3 {
                        for j in 0..3 {
                            out.push((3 * tri[a] + i, 3 * tri[b] + j, k[(3 * a + i, 3 * b + j)]));
                        }
                    }
                }
            }
        }
        out
    }
}
