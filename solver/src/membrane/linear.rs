//! Linearisation of the elastic laws (Skalak, tension) for stiff-aware time integrators.

use nalgebra::{SMatrix, Vector3};

use super::MembraneLaw;
use crate::mesh::Mesh;

/// A law whose nodal force `F(x) = -dE/dx` (N) can be linearised about a state.
///
/// The stiffness `K = dF/dx = -d^2E/dx^2` is symmetric (a Hessian) and, about a
/// stress-free state, negative semi-definite. Units: `K v` is in N when the
/// displacement `v` is in um (so `K` is in N/um). To linearise the force
/// *density* at frozen vertex areas divide row `i` by `A_i` (um^2) and by
/// `1e-12` (m^2/um^2).
pub trait LinearisedLaw: MembraneLaw {
    /// Adds the nodal forces `F_i = -dE/dx_i` (N) to `out`.
    fn add_nodal_forces(&self, mesh: &Mesh, out: &mut [Vector3<f64>]);

    /// Per-triangle stiffness blocks: for triangle `t`, `K_t` is `9 x 9`,
    /// ordered `(vertex 0: x, y, z; vertex 1: ...; vertex 2: ...)` of
    /// `mesh.triangles[t]`; `K = sum_t K_t` assembled on those vertices (N/um).
    fn triangle_stiffness(&self, mesh: &Mesh, t: usize) -> SMatrix<f64, 9, 9>;

    /// Adds `K v` to `out` (N for `v` in um): the change of the nodal forces
    /// for a small displacement `v`.
    fn add_nodal_force_jvp(&self, mesh: &Mesh, v: &[Vector3<f64>], out: &mut [Vector3<f64>]);

    /// Adds the linearised change of the force *density* `Df = P(x)[r]`,
    /// `r_i = F_i / A_i` (Pa per um of displacement `v`), with `P` the
    /// rigid-body correction [`super::remove_net_force_and_torque`]:
    /// `d(Df) = P[dr] + dP[r]`, `dr_i = (K v)_i / A_i - r_i dA_i / A_i`, with
    /// the mixed Voronoi areas `A_i` and their directional derivative `dA_i`
    /// along `v`. `dA_i` and `dP[r]` (purely geometric) are taken by central
    /// differences with a step of `1e-6` of the mesh size (relative error
    /// ~1e-9; the exact derivatives of Meyer's piecewise area formula and of
    /// the projection are not worth their code here).
    fn add_force_density_jvp(&self, mesh: &Mesh, v: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        let mut kv = vec![Vector3::zeros(); mesh.vertices.len()];
        self.add_nodal_force_jvp(mesh, v, &mut kv);
        let mut density = vec![Vector3::zeros(); mesh.vertices.len()];
        self.add_nodal_forces(mesh, &mut density);
        let areas = mesh.vertex_areas();
        for (d, a) in density.iter_mut().zip(&areas) {
            *d /= a * 1e-12;
        }
        let size = mesh
            .vertices
            .iter()
            .map(|x| x.norm())
            .fold(0.0, f64::max)
            .max(1e-12);
        let vmax = v.iter().map(|x| x.norm()).fold(0.0, f64::max);
        if vmax == 0.0 {
            return;
        }
        let eps = 1e-6 * size / vmax;
        let shifted = |s: f64| Mesh {
            vertices: mesh
                .vertices
                .iter()
                .zip(v)
                .map(|(x, d)| x + d * s)
                .collect(),
            triangles: mesh.triangles.clone(),
        };
        let (mp, mm) = (shifted(eps), shifted(-eps));
        let (ap, am) = (mp.vertex_areas(), mm.vertex_areas());
        let mut dr: Vec<Vector3<f64>> = (0..out.len())
            .map(|i| {
                let da = (ap[i] - am[i]) / (2.0 * eps);
                kv[i] / (areas[i] * 1e-12) - density[i] * (da / areas[i])
            })
            .collect();
        super::remove_net_force_and_torque(mesh, &mut dr);
        let (mut pp, mut pm) = (density.clone(), density);
        super::remove_net_force_and_torque(&mp, &mut pp);
        super::remove_net_force_and_torque(&mm, &mut pm);
        for i in 0..out.len() {
            out[i] += dr[i] + (pp[i] - pm[i]) / (2.0 * eps);
        }
    }

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

/// Several linearisable laws together (e.g. Skalak + tension): forces and
/// stiffnesses add. Usable both as the membrane and as its linearisation.
#[derive(Default)]
pub struct LinearisedSum {
    pub laws: Vec<Box<dyn LinearisedLaw>>,
}

impl LinearisedSum {
    /// An empty sum (zero stiffness).
    pub fn new() -> Self {
        LinearisedSum { laws: Vec::new() }
    }

    /// Adds a law (builder style).
    pub fn with(mut self, law: impl LinearisedLaw + 'static) -> Self {
        self.laws.push(Box::new(law));
        self
    }
}

impl MembraneLaw for LinearisedSum {
    fn assembled_stiffness(&self, mesh: &Mesh) -> Option<Vec<(usize, usize, f64)>> {
        Some(self.stiffness_triplets(mesh))
    }
    fn add_force_density(&self, mesh: &Mesh, out: &mut [Vector3<f64>]) {
        for l in &self.laws {
            l.add_force_density(mesh, out);
        }
    }
    fn energy(&self, mesh: &Mesh) -> f64 {
        self.laws.iter().map(|l| l.energy(mesh)).sum()
    }
    fn name(&self) -> &str {
        "elastic-sum"
    }
}

impl LinearisedLaw for LinearisedSum {
    fn add_nodal_forces(&self, mesh: &Mesh, out: &mut [Vector3<f64>]) {
        for l in &self.laws {
            l.add_nodal_forces(mesh, out);
        }
    }

    fn triangle_stiffness(&self, mesh: &Mesh, t: usize) -> SMatrix<f64, 9, 9> {
        self.laws
            .iter()
            .map(|l| l.triangle_stiffness(mesh, t))
            .sum()
    }

    fn add_nodal_force_jvp(&self, mesh: &Mesh, v: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        for l in &self.laws {
            l.add_nodal_force_jvp(mesh, v, out);
        }
    }
}
