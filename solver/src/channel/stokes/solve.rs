//! One channel solve ([`ChannelStokes::solve_at`]), phase by phase as the equations of the parent
//! module's docs order them: the cell's inputs checked, its double layer built (viscosity
//! contrast), its single layer at the cell and wall vertices, the wall traction and `U0` (no-slip
//! or penalty), the wall's single layer at the cell (the velocity at `lambda = 1`), and the
//! second-kind equation for the membrane velocity with the wall's answer to the double layer.

use std::cell::Cell;
use std::sync::atomic::Ordering;
use std::time::Instant;

use nalgebra::Vector3;

use super::{check_finite, check_per_vertex, wall_force, ChannelSolution, ChannelStats, ChannelStokes, WallMode};
use crate::bim::near_field::NearField;
use crate::bim::surface::Surface;
use crate::bim::two_grid::TwoGrid;
use crate::channel::cell_layer::{cell_single_layer, weighted_node_forces, CellSingleLayer, StokesletSum};
use crate::channel::double_layer::{solve_second_kind, PeriodicDoubleLayer};
use crate::channel::wall::WallNodes;
use crate::channel::ChannelError;
use crate::ewald::{BasisSpread, BlockRows, PeriodicStokes};
use crate::mesh::Mesh;
use crate::viscosity::ViscosityContrast;

/// The cell of one solve: its surface, enclosed volume (um^3), near-field corrections and the
/// force density it exerts on the fluid (Pa, per vertex).
struct CellInput<'a> {
    surface: Surface,
    volume: f64,
    near: NearField,
    f: &'a [Vector3<f64>],
}

/// The real-space part of the cell's single layer summed while the double layer's blocks were
/// built, and the [`weighted_node_forces`] it was summed from.
type FusedSingle = (Vec<Vector3<f64>>, (Vec<Vector3<f64>>, Vec<Vector3<f64>>));

/// The wall's single layer at the cell with the sums of GMRES: their splitting, the wall's
/// spreading to their grid, and the real-space blocks built for this cell.
type FastWall<'a> = (&'a PeriodicStokes, &'a BasisSpread, BlockRows);

impl ChannelStokes {
    /// `wall_answer`: with no-slip walls and a viscosity contrast, the wall traction and `U0` of
    /// the solution take one more double-layer sum after GMRES; `false` skips it (the returned
    /// `wall_traction`, `u0_um_s`, `wall_force_x_pn` and pressure gradient then leave out the
    /// wall's answer to the double layer), for callers that take the cell velocity alone, which
    /// is the same bit for bit.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn solve_at(
        &self,
        cell: Option<(&Mesh, &[Vector3<f64>])>,
        mean_flow_mm_s: f64,
        penalty: Option<&[Vector3<f64>]>,
        guess: Option<&[Vector3<f64>]>,
        double_layer: bool,
        lambda: ViscosityContrast,
        wall_answer: bool,
    ) -> Result<ChannelSolution, ChannelError> {
        let t_all = Instant::now();
        if !mean_flow_mm_s.is_finite() {
            return Err(ChannelError::InvalidParameter {
                name: "mean_flow_mm_s",
                value: mean_flow_mm_s,
                reason: "must be finite",
            });
        }
        let nw = self.mesh.n_vertices();
        let mut stats = ChannelStats {
            viscosity_ratio: lambda,
            ..ChannelStats::default()
        };
        let u_t = mean_flow_mm_s * 1e3;
        let volume = self.box_volume();
        let cell = match cell {
            Some((mesh, f)) => Some(self.cell_input(mesh, f, guess, &mut stats)?),
            None => None,
        };
        // Viscosity contrast: the cell's double layer. With the frozen sums inside GMRES its
        // real-space blocks are built once for this solve, and the single layer's real-space
        // part comes from the same pairs (the single layer then takes GMRES's splitting).
        let contrast = double_layer || !lambda.is_matched();
        let t_dl = Instant::now();
        let (dl, fused) = match (&cell, contrast) {
            (Some(c), true) => {
                let (dl, fused) = self.double_layer(c, lambda)?;
                (Some(dl), fused)
            }
            _ => (None, None),
        };
        stats.double_layer_build_seconds = t_dl.elapsed().as_secs_f64();
        // Cell single layer at the cell and wall vertices (Pa um).
        let (sl_cell_at_cell, sl_cell_at_wall, cell_force) = match &cell {
            Some(c) => {
                let sl = self.cell_layer(c, fused.as_ref(), &mut stats)?;
                (sl.at_cell, sl.at_extra, sl.force)
            }
            None => (Vec::new(), vec![Vector3::zeros(); nw], Vector3::zeros()),
        };
        // Wall traction (without the cell's double layer).
        let t1 = Instant::now();
        let (mut f_w, mut u0) = match penalty {
            None => self.no_slip_response(&sl_cell_at_wall, cell_force.x, u_t),
            Some(d) => self.penalty_traction(d, cell_force.x, u_t)?,
        };
        stats.wall_solve_seconds += t1.elapsed().as_secs_f64();
        // The sums inside GMRES (viscosity contrast): the wall's real-space blocks at the cell,
        // frozen for this solve when configured ([`super::ChannelOptions::iteration_sums`]).
        let t = Instant::now();
        let fast = match (&self.iteration, &cell, contrast) {
            (Some((e, spread)), Some(c), true) => Some((
                e,
                spread,
                e.stokeslet_real_blocks_grouped(
                    &c.surface.vertices,
                    &self.eval_nodes.positions,
                    &self.eval_nodes.weights,
                    &self.eval_nodes.interp,
                    WallNodes::PER_SUB_TRIANGLE,
                    nw,
                )?,
            )),
            _ => None,
        };
        stats.ewald_seconds += t.elapsed().as_secs_f64();
        // Wall single layer at the cell: the cell velocity for lambda = 1, the right-hand side otherwise.
        let mut cell_velocity = Vec::new();
        if let Some(c) = &cell {
            let t2 = Instant::now();
            // (at lambda = 1 the plain sum, so that the forced general path reproduces the
            // single-layer path to rounding)
            let w = self.wall_layer_at_cell(fast.as_ref().filter(|_| !lambda.is_matched()), &c.surface.vertices, &f_w)?;
            stats.ewald_sums += 1;
            stats.ewald_seconds += t2.elapsed().as_secs_f64();
            cell_velocity = w
                .iter()
                .zip(&sl_cell_at_cell)
                .map(|(w, c)| Vector3::x() * u0 + (w + c) / self.mu)
                .collect();
        }
        // Viscosity contrast: the second-kind equation with the periodic double layer.
        let mut dl_at_wall = vec![Vector3::zeros(); nw];
        if let (Some(c), Some(dl)) = (&cell, &dl) {
            let no_slip = penalty.is_none();
            let u = self.second_kind(&c.surface, dl, lambda, fast.as_ref(), &cell_velocity, guess, no_slip, &mut stats)?;
            // The wall traction and U0 of the solution (one more double-layer sum), unless the
            // caller takes the cell velocity alone (no-slip: nothing else depends on them).
            if wall_answer || !no_slip {
                let (_, e) = dl.apply(&u)?;
                let half = lambda.half_one_minus();
                if no_slip {
                    let t = Instant::now();
                    let v: Vec<Vector3<f64>> = e.iter().map(|e| e * (self.mu * half)).collect();
                    let (f_lin, u0_lin) = self.no_slip_response(&v, 0.0, 0.0);
                    f_w.iter_mut().zip(&f_lin).for_each(|(f, g)| *f += g);
                    u0 += u0_lin;
                    stats.wall_solve_seconds += t.elapsed().as_secs_f64();
                } else {
                    dl_at_wall = e.iter().map(|e| e * half).collect();
                }
            }
            stats.ewald_sums += dl.ewald_sums.get();
            stats.ewald_seconds += dl.ewald_seconds.get();
            cell_velocity = u;
        }
        stats.u0_um_s = u0;
        let wf = wall_force(&self.mesh, &f_w);
        stats.wall_force_x_pn = wf.x;
        stats.pressure_gradient_pa_per_um = -(wf.x + cell_force.x) / volume;
        let wall_velocity: Vec<Vector3<f64>> = match penalty {
            None => vec![Vector3::zeros(); nw],
            Some(_) => {
                let sw = self.wall.apply(&f_w);
                sw.iter()
                    .zip(&sl_cell_at_wall)
                    .zip(&dl_at_wall)
                    .map(|((w, c), d)| Vector3::x() * u0 + (w + c) / self.mu + d)
                    .collect()
            }
        };
        check_finite("cell velocity", &cell_velocity)?;
        check_finite("wall velocity", &wall_velocity)?;
        stats.total_seconds = t_all.elapsed().as_secs_f64();
        Ok(ChannelSolution {
            cell_velocity,
            wall_traction: f_w,
            wall_velocity,
            stats,
        })
    }

    /// The cell's inputs checked (lengths, finite values, every vertex at least
    /// `min_wall_gap_um` inside the channel), its surface and near-field corrections built.
    fn cell_input<'a>(
        &self,
        mesh: &Mesh,
        f: &'a [Vector3<f64>],
        guess: Option<&[Vector3<f64>]>,
        stats: &mut ChannelStats,
    ) -> Result<CellInput<'a>, ChannelError> {
        check_per_vertex("traction", f, mesh.vertices.len())?;
        if let Some(g) = guess {
            check_per_vertex("velocity guess", g, mesh.vertices.len())?;
        }
        let surface = Surface::new(mesh)?;
        for (i, v) in surface.vertices.iter().enumerate() {
            if self.geometry.wall_distance(v.y, v.z) < self.opts.min_wall_gap_um {
                return Err(ChannelError::CellOutsideChannel {
                    vertex: i,
                    y: v.y,
                    z: v.z,
                    min_gap_um: self.opts.min_wall_gap_um,
                });
            }
        }
        let t0 = Instant::now();
        let near = NearField::new(&surface, &self.opts.near_field);
        stats.near_field_seconds = t0.elapsed().as_secs_f64();
        Ok(CellInput { surface, volume: mesh.volume(), near, f })
    }

    /// The cell's periodic double layer at the cell and wall vertices; with the frozen sums of
    /// GMRES also the real-space part of its single layer, summed from the same pairs
    /// (`lambda != 1`; at lambda = 1, forced through this path, the single layer keeps its own
    /// sum, so that the path reproduces the single-layer path to rounding).
    fn double_layer<'c>(&'c self, cell: &'c CellInput, lambda: ViscosityContrast) -> Result<(PeriodicDoubleLayer<'c>, Option<FusedSingle>), ChannelError> {
        let (dl, fused) = match &self.iteration {
            Some((e, _)) => {
                let nodes = (!lambda.is_matched()).then(|| weighted_node_forces(&cell.surface, cell.f));
                let (dl, single) = PeriodicDoubleLayer::with_real_blocks_and_single_layer(
                    &cell.surface,
                    cell.volume,
                    e,
                    &self.mesh.vertices,
                    nodes.as_ref().map(|n| n.1.as_slice()),
                    self.opts.block_precision,
                )?;
                (dl, single.zip(nodes))
            }
            None => (PeriodicDoubleLayer::new(&cell.surface, cell.volume, &self.ewald, &self.mesh.vertices)?, None),
        };
        Ok((dl.with_near_field(&cell.near), fused))
    }

    /// The cell's single layer at its vertices and at the wall vertices (the extra targets, Pa
    /// um) and its net force (pN); its real-space part from `fused` when the double layer's build summed it.
    fn cell_layer(
        &self,
        cell: &CellInput,
        fused: Option<&FusedSingle>,
        stats: &mut ChannelStats,
    ) -> Result<CellSingleLayer, ChannelError> {
        let t0 = Instant::now();
        let sum = match (&self.iteration, fused) {
            (Some((e, _)), Some((real, (pos, force)))) => StokesletSum::RealDone { ewald: e, real, nodes: (pos, force) },
            _ => StokesletSum::Full(&self.ewald),
        };
        let sl = cell_single_layer(
            sum,
            &cell.surface,
            cell.f,
            &self.mesh.vertices,
            self.opts.duffy_nodes,
            self.opts.subtract_normal_singularity,
            Some(&cell.near),
        )?;
        stats.ewald_sums += sl.ewald_sums;
        stats.single_layer_seconds = t0.elapsed().as_secs_f64();
        stats.ewald_seconds += stats.single_layer_seconds;
        Ok(sl)
    }

    /// Penalty walls: the traction `f_w = -kappa_W d` of the wall displacement `d` (um) and `U0`
    /// (um/s) from the flux with the walls' and the cell's net x-force (`cell_force_x`, pN).
    fn penalty_traction(&self, d: &[Vector3<f64>], cell_force_x: f64, u_t: f64) -> Result<(Vec<Vector3<f64>>, f64), ChannelError> {
        let WallMode::Penalty { kappa_w_n_per_m3: k } = self.wall_mode else {
            return Err(ChannelError::InvalidParameter {
                name: "wall_mode",
                value: 0.0,
                reason: "penalty_velocity needs WallMode::Penalty",
            });
        };
        check_per_vertex("wall displacement", d, self.mesh.n_vertices())?;
        let volume = self.box_volume();
        let f_w: Vec<Vector3<f64>> = d.iter().map(|d| d * (-k * 1e-6)).collect();
        let b = -(wall_force(&self.mesh, &f_w).x + cell_force_x) / volume;
        // Flux inside = U0 A_box - K_E b (the exterior flow is b times a fixed field).
        let a_box = self.box_len[1] * self.box_len[2];
        let u0 = (u_t * self.geometry.cross_section_area() + self.k_exterior * b) / a_box;
        Ok((f_w, u0))
    }

    /// The wall's single layer of the traction `f_w` at the cell vertices `targets` (Pa um): with
    /// the sums of GMRES when `fast` is given, else the plain sums.
    fn wall_layer_at_cell(&self, fast: Option<&FastWall>, targets: &[Vector3<f64>], f_w: &[Vector3<f64>]) -> Result<Vec<Vector3<f64>>, ChannelError> {
        match fast {
            Some((e, spread, blocks)) => self.wall_single_layer_fast(e, spread, blocks, targets, f_w),
            None => self.wall_single_layer(targets, f_w),
        }
    }

    /// The membrane velocity (um/s) from the second-kind equation of the module docs, by GMRES
    /// from `guess`; `lambda_one` is the velocity at lambda = 1 (the right-hand side before its
    /// scaling). With no-slip walls every application adds the wall's answer to the double layer
    /// (`S f = -mu (1 - lambda)/2 E[u]`, `U0` by the flux).
    #[allow(clippy::too_many_arguments)]
    fn second_kind(
        &self,
        surface: &Surface,
        dl: &PeriodicDoubleLayer,
        lambda: ViscosityContrast,
        fast: Option<&FastWall>,
        lambda_one: &[Vector3<f64>],
        guess: Option<&[Vector3<f64>]>,
        no_slip: bool,
        stats: &mut ChannelStats,
    ) -> Result<Vec<Vector3<f64>>, ChannelError> {
        let kappa = lambda.kappa();
        let half = lambda.half_one_minus();
        let scale = lambda.rhs_scale();
        let b: Vec<Vector3<f64>> = lambda_one.iter().map(|v| v * scale).collect();
        let extra_ewald = Cell::new((0usize, 0.0));
        let wall_seconds = Cell::new(0.0f64);
        let two_grid = match self.opts.two_grid_level {
            Some(level) => TwoGrid::new(surface, kappa, level, self.opts.deflate_rigid_body)?,
            None => None,
        };
        let (u, gs) = solve_second_kind(
            surface,
            lambda,
            &b,
            guess,
            self.opts.deflate_rigid_body,
            two_grid.as_ref(),
            &self.gmres_options(),
            |u| {
                let (a, e) = dl.apply(u)?;
                let mut l: Vec<Vector3<f64>> = u.iter().zip(&a).map(|(u, a)| u - a * kappa).collect();
                if no_slip {
                    // The wall's answer to the double layer: S f = -mu (1 - lambda)/2 E[u], U0 by the flux.
                    let t = Instant::now();
                    let v: Vec<Vector3<f64>> = e.iter().map(|e| e * (self.mu * half)).collect();
                    let (f_lin, u0_lin) = self.no_slip_response(&v, 0.0, 0.0);
                    wall_seconds.set(wall_seconds.get() + t.elapsed().as_secs_f64());
                    let t = Instant::now();
                    let w = self.wall_layer_at_cell(fast, &surface.vertices, &f_lin)?;
                    let (n, s) = extra_ewald.get();
                    extra_ewald.set((n + 1, s + t.elapsed().as_secs_f64()));
                    l.iter_mut().zip(&w).for_each(|(l, w)| *l -= (Vector3::x() * u0_lin + w / self.mu) * scale);
                }
                Ok(l)
            },
        )?;
        let (n, s) = extra_ewald.get();
        stats.ewald_sums += n;
        stats.ewald_seconds += s;
        stats.wall_solve_seconds += wall_seconds.get();
        stats.gmres_iterations = gs.iterations;
        self.gmres_counts[0].fetch_add(1, Ordering::Relaxed);
        self.gmres_counts[1].fetch_add(gs.iterations, Ordering::Relaxed);
        self.gmres_counts[2].fetch_add(usize::from(guess.is_some()), Ordering::Relaxed);
        stats.gmres_residual = gs.residual;
        stats.gmres_seconds = gs.seconds;
        Ok(u)
    }
}
