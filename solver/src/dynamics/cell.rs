//! The kinematic condition of one cell: vertex velocities from the membrane force through a Stokes solve.
//!
//! `u(x) = u_inf(x) + M(x)[f(x)]`, with `f` the membrane force density (Pa,
//! [`crate::membrane::MembraneLaw`]) and `M` the boundary-integral mobility
//! (behind the [`Stokes`] trait, so that the free-space solver and the
//! periodic channel plug in). For the linearly implicit scheme the Jacobian is
//! approximated with the mobility lagged at the start of the step:
//! `J w = M(x_n)[(f(x_n + eps w) - f(x_n - eps w)) / (2 eps)]`, a central directional
//! difference of the *total* force density (elastic, bending and tension alike,
//! vertex areas included), which captures the stiff membrane modes and their
//! coupling to the shape (see [`crate::integrate::rosenbrock`]).

use crate::bim::Stokes;
use crate::error::SolverError;
use crate::integrate::mobility_jacobian::MobilityJacobian;
use crate::integrate::precondition::{self_mobility, LocalJacobian, MOBILITY_SAFETY};
use crate::integrate::{Dynamics, Linearised};
use crate::state::{flatten, state_vectors, StateMap};
use crate::membrane::MembraneLaw;
use crate::mesh::Mesh;
use nalgebra::Vector3;
use std::time::Instant;

/// Counters of the work done by a [`CellDynamics`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CellWork {
    pub force_evals: usize,
    pub stokes_solves: usize,
    /// Wall time in force evaluations and in Stokes solves (s).
    pub force_s: f64,
    pub stokes_s: f64,
}

/// The right-hand side `dx/dt = u(x)` of one cell.
pub struct CellDynamics<'a> {
    triangles: Vec<[usize; 3]>,
    membrane: &'a dyn MembraneLaw,
    stokes: &'a dyn Stokes,
    /// Linearisation point and its force density.
    lin_mesh: Mesh,
    lin_force: Vec<Vector3<f64>>,
    last_velocity: Option<Vec<Vector3<f64>>>,
    /// Local Jacobian at the linearisation point (built on first request).
    local: Option<LocalJacobian>,
    local_valid: bool,
    /// Factor on the self-mobility of the local Jacobian ([`crate::integrate::precondition::MOBILITY_SAFETY`]).
    pub mobility_safety: f64,
    pub work: CellWork,
}

impl<'a> CellDynamics<'a> {
    pub fn new(triangles: Vec<[usize; 3]>, membrane: &'a dyn MembraneLaw, stokes: &'a dyn Stokes) -> Self {
        let lin_mesh = Mesh { vertices: Vec::new(), triangles: triangles.clone() };
        Self {
            triangles,
            membrane,
            stokes,
            lin_mesh,
            lin_force: Vec::new(),
            last_velocity: None,
            local: None,
            local_valid: false,
            mobility_safety: MOBILITY_SAFETY,
            work: CellWork::default(),
        }
    }

    fn force(&mut self, mesh: &Mesh) -> Vec<Vector3<f64>> {
        let t0 = Instant::now();
        let f = self.membrane.force_density(mesh);
        self.work.force_evals += 1;
        self.work.force_s += t0.elapsed().as_secs_f64();
        f
    }

    fn solve(&mut self, mesh: &Mesh, f: &[Vector3<f64>], with_background: bool, use_guess: bool) -> Result<Vec<Vector3<f64>>, SolverError> {
        let t0 = Instant::now();
        let guess = if use_guess { self.last_velocity.as_deref() } else { None };
        let u = self.stokes.velocity(mesh, f, with_background, guess)?;
        self.work.stokes_solves += 1;
        self.work.stokes_s += t0.elapsed().as_secs_f64();
        Ok(u)
    }
}

impl Dynamics for CellDynamics<'_> {
    fn velocity(&mut self, _t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        let mesh = Mesh { vertices: x.to_vec(), triangles: self.triangles.clone() };
        let f = self.force(&mesh);
        let v = self.solve(&mesh, &f, true, true)?;
        u.copy_from_slice(&v);
        self.last_velocity = Some(v);
        Ok(())
    }

    /// The last velocity (um/s), the initial guess of the next iterative Stokes solve (`lambda != 1`).
    fn save_state(&self, prefix: &str, out: &mut StateMap) {
        if let Some(v) = &self.last_velocity {
            out.insert(format!("{prefix}last_velocity_um_s"), flatten(v));
        }
        self.stokes.save_state(&format!("{prefix}stokes_"), out);
    }

    fn restore_state(&mut self, prefix: &str, state: &StateMap) -> Result<(), SolverError> {
        self.last_velocity = state_vectors(state, &format!("{prefix}last_velocity_um_s"))?;
        self.stokes.restore_state(&format!("{prefix}stokes_"), state)
    }
}

impl Linearised for CellDynamics<'_> {
    fn linearise(&mut self, _t_s: f64, x: &[Vector3<f64>]) -> Result<(), SolverError> {
        self.lin_mesh.vertices.clear();
        self.lin_mesh.vertices.extend_from_slice(x);
        let mesh = self.lin_mesh.clone();
        self.lin_force = self.force(&mesh);
        self.local_valid = false;
        Ok(())
    }

    /// `J_loc = diag(s m_i / A_i) K` at the linearisation point: `K` the assembled stiffness of
    /// the membrane laws that have one (bending has none and is left to the full `J`), `m_i` the
    /// self-mobility of vertex `i` with the Stokes operator's viscosities, `s` [`Self::mobility_safety`].
    fn local_jacobian(&mut self) -> Result<Option<&LocalJacobian>, SolverError> {
        if !self.local_valid {
            self.local_valid = true;
            self.local = None;
            let (Some((mu, lambda)), Some(k)) = (self.stokes.viscosities(), self.membrane.assembled_stiffness(&self.lin_mesh)) else {
                return Ok(None);
            };
            let areas = self.lin_mesh.vertex_areas();
            let mobility: Vec<f64> = areas.iter().map(|&a| self.mobility_safety * self_mobility(a, mu, lambda)).collect();
            self.local = Some(LocalJacobian::new(areas.len(), &k, &areas, &mobility)?);
        }
        Ok(self.local.as_ref())
    }

    /// `J_mob = M_fs K` at the linearisation point: `K` the assembled stiffness of
    /// [`Self::local_jacobian`] plus the bending stiffness by differences
    /// ([`MembraneLaw::difference_stiffness`]; measured mid-run in the paper's channel, the bending
    /// modes otherwise cap this scheme's steps near 300 us), `M_fs` the free-space two-fluid
    /// mobility of every vertex pair with the Stokes operator's viscosities.
    fn mobility_jacobian(&mut self) -> Result<Option<MobilityJacobian>, SolverError> {
        Ok(membrane_mobility_jacobian(self.membrane, &self.lin_mesh, self.stokes.viscosities()))
    }

    fn jacobian_apply(&mut self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        let wmax = w.iter().map(|v| v.norm()).fold(0.0, f64::max);
        if wmax == 0.0 {
            out.iter_mut().for_each(|o| *o = Vector3::zeros());
            return Ok(());
        }
        // central difference with a step of 1e-5 of the cell size: the bending force (fourth
        // derivatives of the shape, least-squares fits) carries round-off ~1e-12 of its size, which a
        // forward difference at sqrt(machine epsilon) amplifies into a map that is not linear in w
        // (3e-3 relative on the paper's cell with bending; 3.5e-6 with this central difference, 8e-9
        // without bending: `tests/integrate_precondition.rs`, fd_linearity). GMRES and the
        // W-methods need a fixed linear J; the extra force evaluation is cheap beside the Stokes solve.
        let scale = self.lin_mesh.vertices.iter().map(|v| v.norm()).fold(1.0, f64::max);
        let eps = 1e-5 * scale / wmax;
        let mut mesh = self.lin_mesh.clone();
        for (p, (x0, wi)) in mesh.vertices.iter_mut().zip(self.lin_mesh.vertices.iter().zip(w)) {
            *p = x0 + eps * wi;
        }
        let fp = self.force(&mesh);
        for (p, (x0, wi)) in mesh.vertices.iter_mut().zip(self.lin_mesh.vertices.iter().zip(w)) {
            *p = x0 - eps * wi;
        }
        let fm = self.force(&mesh);
        let df: Vec<Vector3<f64>> = fp.iter().zip(&fm).map(|(a, b)| (a - b) / (2.0 * eps)).collect();
        let lin = self.lin_mesh.clone();
        let v = self.solve(&lin, &df, false, false)?;
        out.copy_from_slice(&v);
        Ok(())
    }
}

/// `J_mob = M_fs K` of `membrane` at the vertices of `mesh` (the linearisation point) in a fluid
/// of `viscosities` (outer viscosity, ratio): `K` the assembled stiffness plus the bending
/// stiffness by differences, `M_fs` the free-space two-fluid mobility
/// ([`MobilityJacobian`]); `None` without an assembled stiffness or known viscosities. The
/// cell's block of every dynamics that runs the `ros34pw2-mobility` W-method.
pub(crate) fn membrane_mobility_jacobian(membrane: &dyn MembraneLaw, mesh: &Mesh, viscosities: Option<(f64, crate::viscosity::ViscosityContrast)>) -> Option<MobilityJacobian> {
    let (Some((mu, lambda)), Some(mut k)) = (viscosities, membrane.assembled_stiffness(mesh)) else {
        return None;
    };
    if let Some(kb) = membrane.difference_stiffness(mesh) {
        k.extend(kb);
    }
    Some(MobilityJacobian::new(&mesh.vertices, &mesh.vertex_areas(), &mesh.vertex_normals(), &k, mu, lambda))
}
