//! Isotropic surface tension (a drop interface): energy `gamma A`, force `-gamma dA/dx`.

use nalgebra::{Matrix3, SMatrix, Vector3};

use super::error::{check_modulus, MembraneError};
use super::linear::LinearisedLaw;
use super::{MembraneLaw, UM};
use crate::mesh::Mesh;

/// Constant isotropic tension `gamma` (N/m): `E = gamma A` and
/// `Df_i = -gamma (dA/dx_i) / A_i` (then [`super::remove_net_force_and_torque`]), the discrete form of `Df = -2 gamma H n`
/// (Laplace: `H = 1/R` on a sphere, `n` outward). For triangle `(x0, x1, x2)`
/// with `N = (x1 - x0) x (x2 - x0)`, `A = |N|/2`:
/// `dA/dx1 = (x2 - x0) x N^ / 2`, `dA/dx2 = N^ x (x1 - x0) / 2`, `dA/dx0 = -(dA/dx1 + dA/dx2)`.
#[derive(Debug, Clone, Copy)]
pub struct Tension {
    gamma: f64,
}

impl Tension {
    /// Tension `gamma_n_m` in N/m (>= 0).
    pub fn new(gamma_n_m: f64) -> Result<Tension, MembraneError> {
        Ok(Tension {
            gamma: check_modulus("Tension", "gamma", gamma_n_m, false)?,
        })
    }

    /// `(dA/dx1, dA/dx2)` of one triangle (um).
    #[inline]
    fn area_gradient(e1: &Vector3<f64>, e2: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let n = e1.cross(e2).normalize();
        (0.5 * e2.cross(&n), 0.5 * n.cross(e1))
    }

    /// Directional derivative of the area gradient along edge changes `(de1, de2)`.
    #[inline]
    fn area_gradient_jvp(
        e1: &Vector3<f64>,
        e2: &Vector3<f64>,
        de1: &Vector3<f64>,
        de2: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let nv = e1.cross(e2);
        let len = nv.norm();
        let n = nv / len;
        let dnv = de1.cross(e2) + e1.cross(de2);
        let dn = (Matrix3::identity() - n * n.transpose()) * dnv / len;
        (
            0.5 * (de2.cross(&n) + e2.cross(&dn)),
            0.5 * (dn.cross(e1) + n.cross(de1)),
        )
    }
}

impl MembraneLaw for Tension {
    fn assembled_stiffness(&self, mesh: &Mesh) -> Option<Vec<(usize, usize, f64)>> {
        Some(self.stiffness_triplets(mesh))
    }
    fn add_force_density(&self, mesh: &Mesh, out: &mut [Vector3<f64>]) {
        let mut g = vec![Vector3::zeros(); mesh.vertices.len()];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let [x0, x1, x2] = mesh.corners(t);
            let (g1, g2) = Self::area_gradient(&(x1 - x0), &(x2 - x0));
            g[tri[0]] -= g1 + g2;
            g[tri[1]] += g1;
            g[tri[2]] += g2;
        }
        // gamma (N/m) dA/dx (um) / A_i (um^2) = gamma / um units = 1e6 Pa
        for (gi, a) in g.iter_mut().zip(mesh.vertex_areas()) {
            *gi *= -self.gamma / (a * UM);
        }
        super::remove_net_force_and_torque(mesh, &mut g);
        for (o, gi) in out.iter_mut().zip(&g) {
            *o += gi;
        }
    }

    /// `E = gamma A` (J).
    fn energy(&self, mesh: &Mesh) -> f64 {
        self.gamma * mesh.area() * UM * UM
    }

    fn name(&self) -> &str {
        "tension"
    }
}

impl LinearisedLaw for Tension {
    /// `F_i = -gamma dA/dx_i` (N).
    fn add_nodal_forces(&self, mesh: &Mesh, out: &mut [Vector3<f64>]) {
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let [x0, x1, x2] = mesh.corners(t);
            let (g1, g2) = Self::area_gradient(&(x1 - x0), &(x2 - x0));
            let s = self.gamma * UM;
            out[tri[0]] += (g1 + g2) * s;
            out[tri[1]] -= g1 * s;
            out[tri[2]] -= g2 * s;
        }
    }

    fn triangle_stiffness(&self, mesh: &Mesh, t: usize) -> SMatrix<f64, 9, 9> {
        let [x0, x1, x2] = mesh.corners(t);
        let (e1, e2) = (x1 - x0, x2 - x0);
        let mut k = SMatrix::<f64, 9, 9>::zeros();
        for col in 0..9 {
            let (vertex, comp) = (col / 3, col % 3);
            let mut d = Vector3::zeros();
            d[comp] = 1.0;
            let (de1, de2) = match vertex {
                0 => (-d, -d),
                1 => (d, Vector3::zeros()),
                _ => (Vector3::zeros(), d),
            };
            let (h1, h2) = Self::area_gradient_jvp(&e1, &e2, &de1, &de2);
            let cols = [h1 + h2, -h1, -h2]; // = -d(dA/dx_a), times gamma
            for (a, v) in cols.iter().enumerate() {
                for i in 0..3 {
                    k[(3 * a + i, col)] = self.gamma * v[i] * UM;
                }
            }
        }
        k
    }

    fn add_nodal_force_jvp(&self, mesh: &Mesh, v: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let [x0, x1, x2] = mesh.corners(t);
            let (de1, de2) = (v[tri[1]] - v[tri[0]], v[tri[2]] - v[tri[0]]);
            let (h1, h2) = Self::area_gradient_jvp(&(x1 - x0), &(x2 - x0), &de1, &de2);
            let s = self.gamma * UM;
            out[tri[0]] += (h1 + h2) * s;
            out[tri[1]] -= h1 * s;
            out[tri[2]] -= h2 * s;
        }
    }
}
