//! The Ewald parameters of a channel solve's sums, from the cost model
//! [`crate::ewald::params::sums_cost`]: the shapes of the sums one solve makes, and the sums of
//! GMRES with their frozen real-space pairs ([`ChannelOptions::iteration_sums`]).

use crate::channel::mesh::ChannelMesh;
use crate::channel::wall::WallNodes;
use crate::channel::{ChannelError, ChannelOptions, IterationSums};
use crate::ewald::params::{PairModel, SumShape};
use crate::ewald::{BasisSpread, EwaldParams, PeriodicStokes};
use crate::viscosity::ViscosityContrast;

/// The Ewald sums of GMRES ([`ChannelOptions::iteration_sums`]; none for `Plain` or lambda = 1).
pub(super) fn iteration_sums(
    opts: &ChannelOptions,
    lambda: ViscosityContrast,
    box_len: [f64; 3],
    mesh: &ChannelMesh,
    eval_nodes: &WallNodes,
) -> Result<Option<(PeriodicStokes, BasisSpread)>, ChannelError> {
    if lambda.is_matched() {
        return Ok(None);
    }
    let p = match opts.iteration_sums {
        IterationSums::Plain => return Ok(None),
        IterationSums::Cutoff(r_cut) => {
            if !(r_cut > 0.0 && r_cut.is_finite()) {
                return Err(ChannelError::InvalidParameter {
                    name: "iteration_sums",
                    value: r_cut,
                    reason: "the real-space cutoff must be positive and finite",
                });
            }
            let (s_r, _, _) = crate::ewald::params::accuracy_numbers(opts.ewald_tol);
            EwaldParams::with_xi(box_len, s_r / r_cut, opts.ewald_tol)?
        }
        IterationSums::Model => {
            EwaldParams::for_sums(box_len, &solve_sums(opts, mesh, true), opts.ewald_tol)?
        }
    };
    let e = PeriodicStokes::new(box_len, p)?;
    let spread = e.basis_spread(
        &eval_nodes.positions,
        &eval_nodes.weights,
        &eval_nodes.interp,
        mesh.n_vertices(),
    )?;
    Ok(Some((e, spread)))
}

/// The shapes of the Ewald sums of a solve for the cost model, for a cell of `cell_nodes_hint / 7`
/// triangles (about half as many vertices) on the membrane area `cell_area_hint_um2`; the wall's
/// spreading is precomputed. `iteration`: one GMRES application (the double layer at the cell and
/// wall vertices, the wall at the cell, real space frozen: ~8 ns per pair); otherwise the
/// single-layer sums (cell -> cell + wall vertices, wall -> cell; ~25 ns per pair; the normal-part
/// sum is a free-space direct sum, [`crate::channel::cell_layer`]).
pub(super) fn solve_sums(opts: &ChannelOptions, mesh: &ChannelMesh, iteration: bool) -> Vec<SumShape> {
    let (n_cn, nw) = (opts.cell_nodes_hint.max(7), mesh.n_vertices());
    let n_cv = n_cn / 14 + 2;
    let wall_area: f64 = mesh.triangle_areas.iter().sum();
    let n_wn = 7 * 4usize.pow(opts.wall_eval_refine as u32) * mesh.triangles.len();
    let cell = PairModel::Surface {
        area_um2: opts.cell_area_hint_um2,
    };
    let wall = PairModel::Surface {
        area_um2: wall_area,
    };
    let pair_ns = if iteration { 8.0 } else { 25.0 };
    let sum = |grid_points, components, ffts, pair_sources, pairs| SumShape {
        grid_points,
        components,
        ffts,
        pair_targets: n_cv,
        pair_sources,
        pairs,
        pair_ns,
    };
    if iteration {
        vec![
            sum(n_cn + (n_cv + nw) / 2, 6, 5, n_cn, cell),
            sum(n_cv, 3, 4, n_wn, wall),
        ]
    } else {
        vec![
            sum(n_cn + n_cv + nw, 3, 4, n_cn, cell),
            sum(n_cv, 3, 4, n_wn, wall),
        ]
    }
}
