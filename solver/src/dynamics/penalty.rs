//! The kinematic condition of one cell in the periodic channel with penalty walls: the state is the cell's vertices followed by the wall displacements.
//!
//! With the paper's penalty walls (Guckenberger et al., "Simulation setup"; Tahiri et al.,
//! 2013) the wall vertices are material points tied to their rest positions `X_0` by springs
//! of stiffness `kappa_W`: the wall traction is `f_w = -kappa_W d` with the displacement
//! `d = X - X_0`, and the wall vertices move with the fluid, `dd/dt = u(X_0)` (the wall
//! geometry itself stays at `X_0`: the displacements are small, `|d| ~ |f_w| / kappa_W`,
//! ~0.1 um at 5 mm/s and the paper's 1.9e7 N/m^3). Both velocities come from one solve,
//! [`ChannelStokes::penalty_velocity`]. So the state integrated by the runner is
//!
//! ```text
//! state = [x_1 .. x_Nc, d_1 .. d_Nw]   (um),   d(state)/dt = [u_cell, u_wall]   (um/s)
//! ```
//!
//! and everything that concerns the cell only (geometry, checks, volume correction, output)
//! uses the first `Nc` entries: the runner's geometry goes through the cell's triangles, the
//! volume rescaling leaves the vertices past the last one the triangles reference alone
//! ([`super::volume::rescale_to_volume`]), the projections here act on the cell part only, and
//! [`crate::run::CellOutput`] hands the observers the cell part of each sample. The step-size controller
//! measures the local error of the wall displacements in um as well (the same tolerance).
//!
//! Linearisation (for [`crate::integrate::rosenbrock::Ros2`]): the solve is linear in the membrane force
//! and the wall displacement at fixed cell geometry, so
//! `J [w_c, w_d] = PenaltySolve(f = dF/dx(x_n) w_c, d = w_d, mean flow 0)`: the force
//! linearised by a directional difference (as [`super::cell::CellDynamics`]) and the wall part
//! exact; the cell's mobility is lagged at the start of the step. For the `ros34pw2-mobility`
//! W-method: the cell's dense stiff-mode Jacobian and the walls' own block
//! ([`PenaltyChannelDynamics::wall_jacobian`], [`crate::integrate::wall_block`]), the coupling
//! explicit unless `integrator.wall_coupling` puts the walls' answer to the cell into the stages
//! ([`crate::integrate::wall_block::WallCoupling`]); the walls may take a tolerance of their own
//! (`integrator.wall_atol_um`).

use super::cell::CellWork;
use super::projected::Projected;
use crate::channel::{ChannelStokes, WallMode};
use crate::error::SolverError;
use crate::integrate::{Dynamics, Linearised};
use crate::membrane::MembraneLaw;
use crate::mesh::{slices, Mesh};
use crate::state::{flatten, state_vectors, StateMap};
use nalgebra::Vector3;
use crate::integrate::wall_block::WallBlock;
use std::sync::Arc;
use std::time::Instant;

/// The right-hand side of a cell plus penalty walls (see the module docs).
pub struct PenaltyChannelDynamics<'a> {
    triangles: Vec<[usize; 3]>,
    n_cell: usize,
    membrane: &'a dyn MembraneLaw,
    channel: &'a ChannelStokes,
    lin_mesh: Mesh,
    lin_force: Vec<Vector3<f64>>,
    /// The cell velocity of the last full solve (um/s): the GMRES starting point of the next one
    /// (lambda != 1), kept in the checkpoint like [`super::cell::CellDynamics`]'s.
    last_velocity: Option<Vec<Vector3<f64>>>,
    /// The cell velocity of the solve at the linearisation point (the last solve when
    /// [`Linearised::linearise`] was called): the GMRES starting point of
    /// [`Linearised::velocity_near_linearisation`].
    lin_velocity: Option<Vec<Vector3<f64>>>,
    /// The walls' block of the mobility Jacobian ([`Self::wall_jacobian`]), built once.
    wall_jacobian: Option<Arc<WallBlock>>,
    pub work: CellWork,
}

impl<'a> PenaltyChannelDynamics<'a> {
    /// The cell has `n_cell` vertices and the connectivity `triangles`; `channel` must have
    /// [`WallMode::Penalty`] walls (else [`crate::channel::ChannelError::InvalidParameter`]); its
    /// [`ChannelStokes::mean_flow_mm_s`] drives the flow.
    pub fn new(triangles: Vec<[usize; 3]>, n_cell: usize, membrane: &'a dyn MembraneLaw, channel: &'a ChannelStokes) -> Result<Self, SolverError> {
        if !matches!(channel.wall_mode, WallMode::Penalty { .. }) {
            return Err(crate::channel::ChannelError::InvalidParameter { name: "wall_mode", value: 0.0, reason: "penalty dynamics need WallMode::Penalty" }.into());
        }
        let lin_mesh = Mesh { vertices: Vec::new(), triangles: triangles.clone() };
        Ok(Self { triangles, n_cell, membrane, channel, lin_mesh, lin_force: Vec::new(), last_velocity: None, lin_velocity: None, wall_jacobian: None, work: CellWork::default() })
    }

    /// Number of wall vertices (length of the displacement part of the state).
    pub fn n_wall(&self) -> usize {
        self.channel.mesh.n_vertices()
    }

    /// The walls' block of the Jacobian ([`crate::integrate::wall_block`], from
    /// [`ChannelStokes::penalty_wall_jacobian`]), built once and shared by the Jacobians of every step.
    pub fn wall_jacobian(&mut self) -> Arc<WallBlock> {
        let ch = self.channel;
        self.wall_jacobian
            .get_or_insert_with(|| {
                let WallMode::Penalty { kappa_w_n_per_m3 } = ch.wall_mode else { unreachable!("checked in new") };
                Arc::new(WallBlock::new(ch.penalty_wall_jacobian(kappa_w_n_per_m3)))
            })
            .clone()
    }

    /// The initial state: the cell's vertices `cell` (um) followed by the wall displacements
    /// `d_0 = -f_w / kappa_W` that carry the exact no-slip wall traction `f_w` of the initial
    /// configuration (cell force and mean flow), so that the walls hold from `t = 0` and only
    /// lag the cell as it moves. (Starting from `d = 0` would switch the walls off at `t = 0`:
    /// the cell is carried by a plug flow until the springs load up, for ~0.1 ms and longer.)
    ///
    /// `f_w` from the solve's linearity: a penalty solve with `d = 0` gives the cell's single
    /// layer at the wall, `SL = mu (u_wall - U0' e_x)`, and its net force; then, as in the
    /// no-slip solve, `f_r = -S^-1 SL`, the body force `b_r = -(F_r + F_cell) / V_box`, the box
    /// velocity `U0 = (U_mean A + K_E b_r) / (K_I b_1)` and `f_w = f_r + U0 f_e` with
    /// `f_e = -mu S^-1 e_x` (see [`crate::channel::stokes`]).
    pub fn initial_state(&mut self, cell: &[Vector3<f64>]) -> Result<Vec<Vector3<f64>>, SolverError> {
        let nc = self.n_cell;
        self.check_len(cell.len() + self.n_wall())?;
        let nw = self.n_wall();
        let ch = self.channel;
        let WallMode::Penalty { kappa_w_n_per_m3 } = ch.wall_mode else {
            unreachable!("checked in new")
        };
        let mesh = Mesh { vertices: cell.to_vec(), triangles: self.triangles.clone() };
        let f = self.force(&mesh);
        let zero = vec![Vector3::zeros(); nw];
        let sol = ch.penalty_velocity(Some((&mesh, &f)), &zero, ch.mean_flow_mm_s)?;
        let mu = ch.viscosity();
        let box_volume: f64 = ch.box_len().iter().product();
        // with f_w = 0 the pressure gradient is -F_cell,x / V_box
        let cell_force_x = -sol.stats.pressure_gradient_pa_per_um * box_volume;
        let sl: Vec<Vector3<f64>> = sol.wall_velocity.iter().map(|w| (w - Vector3::x() * sol.stats.u0_um_s) * mu).collect();
        let f_r: Vec<Vector3<f64>> = ch.wall.solve(&sl).iter().map(|v| -v).collect();
        let wall_force_x: f64 = f_r.iter().zip(&ch.mesh.vertex_areas).map(|(f, a)| f.x * a).sum();
        let b_r = -(wall_force_x + cell_force_x) / box_volume;
        let (interior_fraction, _, k_exterior) = ch.calibration();
        let area = ch.geometry.cross_section_area();
        let u0 = (ch.mean_flow_mm_s * 1e3 * area + k_exterior * b_r) / (interior_fraction * area);
        let f_e = ch.wall.solve(&vec![Vector3::x() * (-mu); nw]);
        // kappa_W (N/m^3) = 1e-6 Pa/um
        let k = kappa_w_n_per_m3 * 1e-6;
        let mut x = cell.to_vec();
        debug_assert_eq!(x.len(), nc);
        x.extend(f_r.iter().zip(&f_e).map(|(r, e)| -(r + e * u0) / k));
        Ok(x)
    }

    fn check_len(&self, n: usize) -> Result<(), SolverError> {
        let expected = self.n_cell + self.n_wall();
        if n != expected {
            return Err(crate::channel::ChannelError::LengthMismatch { what: "cell + wall state", expected, got: n }.into());
        }
        Ok(())
    }

    fn force(&mut self, mesh: &Mesh) -> Vec<Vector3<f64>> {
        let t0 = Instant::now();
        let f = self.membrane.force_density(mesh);
        self.work.force_evals += 1;
        self.work.force_s += t0.elapsed().as_secs_f64();
        f
    }

    /// `use_guess`: start GMRES from the last full solve's cell velocity (the velocity
    /// evaluations; not the Jacobian's directional solves, whose answer is unrelated).
    fn solve(&mut self, mesh: &Mesh, f: &[Vector3<f64>], d: &[Vector3<f64>], mean_mm_s: f64, u: &mut [Vector3<f64>], use_guess: bool) -> Result<(), SolverError> {
        let t0 = Instant::now();
        let guess = if use_guess { self.last_velocity.as_deref() } else { None };
        let sol = self.channel.penalty_velocity_with_guess(Some((mesh, f)), d, mean_mm_s, guess)?;
        self.work.stokes_solves += 1;
        self.work.stokes_s += t0.elapsed().as_secs_f64();
        let nc = self.n_cell;
        u[..nc].copy_from_slice(&sol.cell_velocity);
        u[nc..].copy_from_slice(&sol.wall_velocity);
        Ok(())
    }
}

impl Dynamics for PenaltyChannelDynamics<'_> {
    fn velocity(&mut self, _t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        self.check_len(x.len())?;
        let nc = self.n_cell;
        let mesh = Mesh { vertices: x[..nc].to_vec(), triangles: self.triangles.clone() };
        let f = self.force(&mesh);
        let mean = self.channel.mean_flow_mm_s;
        self.solve(&mesh, &f, &x[nc..], mean, u, true)?;
        self.last_velocity = Some(u[..nc].to_vec());
        Ok(())
    }

    /// The last cell velocity (um/s), the initial guess of the next GMRES solve (`lambda != 1`).
    fn save_state(&self, prefix: &str, out: &mut StateMap) {
        if let Some(v) = &self.last_velocity {
            out.insert(format!("{prefix}last_velocity_um_s"), flatten(v));
        }
    }

    fn restore_state(&mut self, prefix: &str, state: &StateMap) -> Result<(), SolverError> {
        self.last_velocity = state_vectors(state, &format!("{prefix}last_velocity_um_s"))?;
        Ok(())
    }
}

impl Linearised for PenaltyChannelDynamics<'_> {
    /// The cell's dense stiff-mode Jacobian ([`crate::dynamics::cell::CellDynamics`]'s: the
    /// free-space two-fluid mobility times the membrane stiffness) with the walls' own block
    /// ([`Self::wall_jacobian`]), so that the `ros34pw2-mobility` W-method runs the paper's
    /// penalty walls. The coupling through the fluid (wall tractions at the cell, the cell's
    /// forces at the wall) is not in it ([`crate::integrate::wall_block`]: why, what it costs,
    /// and the stepper's own `J_wc` of `integrator.wall_coupling`).
    fn mobility_jacobian(&mut self) -> Result<Option<crate::integrate::mobility_jacobian::MobilityJacobian>, SolverError> {
        use crate::bim::Stokes;
        let cell = super::cell::membrane_mobility_jacobian(self.membrane, &self.lin_mesh, self.channel.viscosities());
        Ok(cell.map(|j| j.with_wall_block(self.wall_jacobian())))
    }

    fn linearise(&mut self, _t_s: f64, x: &[Vector3<f64>]) -> Result<(), SolverError> {
        self.check_len(x.len())?;
        self.lin_mesh.vertices.clear();
        self.lin_mesh.vertices.extend_from_slice(&x[..self.n_cell]);
        let mesh = self.lin_mesh.clone();
        self.lin_force = self.force(&mesh);
        self.lin_velocity.clone_from(&self.last_velocity);
        Ok(())
    }

    /// GMRES started from the linearisation point's cell velocity; the ordinary evaluations'
    /// starting point (the last of them) is kept.
    fn velocity_near_linearisation(&mut self, t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        let kept = std::mem::replace(&mut self.last_velocity, self.lin_velocity.clone());
        let result = self.velocity(t_s, x, u);
        self.last_velocity = kept;
        result
    }

    fn jacobian_apply(&mut self, w: &[Vector3<f64>], out: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        self.check_len(w.len())?;
        let nc = self.n_cell;
        let (wc, wd) = w.split_at(nc);
        let wmax = wc.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let df: Vec<Vector3<f64>> = if wmax == 0.0 {
            vec![Vector3::zeros(); nc]
        } else {
            // forward difference with a step of ~sqrt(machine epsilon) relative to the cell's coordinates
            let scale = self.lin_mesh.vertices.iter().map(|v| v.norm()).fold(1.0, f64::max);
            let eps = 1.5e-8 * scale / wmax;
            let mut mesh = self.lin_mesh.clone();
            for (p, wi) in mesh.vertices.iter_mut().zip(wc) {
                *p += eps * wi;
            }
            let f1 = self.force(&mesh);
            f1.iter().zip(&self.lin_force).map(|(a, b)| (a - b) / eps).collect()
        };
        let lin = self.lin_mesh.clone();
        self.solve(&lin, &df, wd, 0.0, out, false)
    }
}

/// [`super::volume::remove_flux`] on the cell part of the state only.
fn no_flux_cell(x: &[Vector3<f64>], t: &[[usize; 3]], u: &mut [Vector3<f64>], g: &mut [Vector3<f64>]) {
    let n = slices::cell_len(t);
    super::volume::remove_flux(&x[..n], t, &mut u[..n], &mut g[..n]);
}

/// [`super::kinematics::project_normal`] on the cell part of the state only.
fn normal_cell(x: &[Vector3<f64>], t: &[[usize; 3]], u: &mut [Vector3<f64>], g: &mut [Vector3<f64>]) {
    let n = slices::cell_len(t);
    super::kinematics::project_normal(&x[..n], t, &mut u[..n], &mut g[..n]);
}

/// No-flux correction of the cell's velocity; the wall velocities pass unchanged.
pub fn cell_no_flux<D>(inner: D, triangles: &[[usize; 3]]) -> Projected<'_, D> {
    Projected::new(inner, triangles, no_flux_cell)
}

/// Normal-only kinematics of the cell's vertices; the wall velocities pass unchanged.
pub fn cell_normal_only<D>(inner: D, triangles: &[[usize; 3]]) -> Projected<'_, D> {
    Projected::new(inner, triangles, normal_cell)
}

/// Largest wall displacement (um) in a state with `n_cell` cell vertices.
pub fn max_wall_displacement(x: &[Vector3<f64>], n_cell: usize) -> f64 {
    x.get(n_cell..).unwrap_or(&[]).iter().map(|d| d.norm()).fold(0.0, f64::max)
}

/// Volume (um^3) of the cell part of a state (for checks in tests and benchmarks).
pub fn cell_volume(x: &[Vector3<f64>], triangles: &[[usize; 3]]) -> f64 {
    slices::volume(x, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::volume::rescale_to_volume;

    /// The projections and the volume rescaling touch the cell part only: wall entries appended
    /// to a sphere's vertices keep their velocities and positions, while the cell part is
    /// treated exactly as without them.
    #[test]
    fn cell_projections_and_rescaling_leave_the_wall_part_alone() {
        let m = crate::mesh::sphere(2, 2.0);
        let n = m.vertices.len();
        assert_eq!(slices::cell_len(&m.triangles), n);
        let tail = [Vector3::new(0.3, -0.2, 0.1), Vector3::new(-1.0, 2.0, 0.5)];
        let mut x = m.vertices.clone();
        x.extend_from_slice(&tail);
        let u_cell: Vec<Vector3<f64>> = m.vertices.iter().map(|p| 0.3 * p + Vector3::new(1.0, 0.0, 0.0)).collect();
        for (project, reference) in [
            (no_flux_cell as super::super::projected::Projection, (|x: &[Vector3<f64>], t: &[[usize; 3]], u: &mut [Vector3<f64>], g: &mut [Vector3<f64>]| {
                super::super::volume::remove_flux(x, t, u, g);
            }) as super::super::projected::Projection),
            (normal_cell, super::super::kinematics::project_normal),
        ] {
            let mut u = u_cell.clone();
            u.extend_from_slice(&tail);
            let mut g = vec![Vector3::zeros(); u.len()];
            project(&x, &m.triangles, &mut u, &mut g);
            let mut expected = u_cell.clone();
            let mut g0 = vec![Vector3::zeros(); n];
            reference(&m.vertices, &m.triangles, &mut expected, &mut g0);
            assert_eq!(&u[..n], &expected[..]);
            assert_eq!(&u[n..], &tail[..]);
        }
        let v0 = slices::volume(&m.vertices, &m.triangles);
        let mut y: Vec<Vector3<f64>> = x.iter().map(|p| p * 1.01).collect();
        y[n..].copy_from_slice(&tail);
        rescale_to_volume(&mut y, &m.triangles, v0);
        assert!((cell_volume(&y, &m.triangles) / v0 - 1.0).abs() < 1e-14);
        assert_eq!(&y[n..], &tail[..]);
        assert_eq!(max_wall_displacement(&y, n), tail[1].norm());
    }
}
