//! The frozen sums inside GMRES (`ChannelOptions::iteration_sums`: real-space blocks built once per solve, precomputed wall spreading, a coarser splitting) give the membrane velocity of the plain sums within the Ewald tolerance, and the difference shrinks with it.

use nalgebra::{Rotation3, Vector3};
use rbc_solver::channel::{ChannelGeometry, ChannelOptions, ChannelStokes, IterationSums, WallMode};
use rbc_solver::viscosity::ViscosityContrast;
use rbc_solver::mesh::discocyte;

fn rel(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_squared()).sum();
    let den: f64 = b.iter().map(|y| y.norm_squared()).sum();
    (num / den).sqrt()
}

/// Velocities (fast, plain) and the GMRES iterations of each for a pushed, off-centre discocyte
/// (128 triangles) at lambda = 5 in the channel with 2 um wall edges, Ewald tolerance `tol`.
fn fast_and_plain(tol: f64) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>, usize, usize) {
    let opts = ChannelOptions { ewald_tol: tol, wall_edge_um: 2.0, cell_nodes_hint: 7 * 128, gmres_tolerance: 1e-9, ..ChannelOptions::default() };
    assert_eq!(opts.iteration_sums, IterationSums::Model, "the default takes the fast path");
    let ch = ChannelStokes::new(ChannelGeometry::default(), 1.2e-3, ViscosityContrast::new(5.0).unwrap(), WallMode::NoSlip, opts).unwrap();
    assert!(ch.fast_iterations());
    let rot = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
    let m = discocyte(2).transformed(&rot, &Vector3::new(8.0, 0.9, -0.5));
    let c = m.centroid();
    let f: Vec<Vector3<f64>> = m.vertices.iter().map(|x| Vector3::new(4.0, x.y - c.y, -0.5 * (x.z - c.z))).collect();
    let fast = ch.velocity_with_guess(&m, &f, 3.0, None).unwrap();
    let ch = ch.with_iteration_sums(IterationSums::Plain).unwrap();
    assert!(!ch.fast_iterations());
    let plain = ch.velocity_with_guess(&m, &f, 3.0, None).unwrap();
    (fast.cell_velocity, plain.cell_velocity, fast.stats.gmres_iterations, plain.stats.gmres_iterations)
}

/// Both paths are Ewald evaluations of the same discrete operator with relative error ~`tol`
/// each (GMRES at 1e-9 is far below): their difference stays below `2 tol` at 1e-4, and drops
/// by more than 10 from 1e-4 to 1e-6 (a discretisation difference would not).
#[test]
fn frozen_gmres_sums_match_the_plain_sums() {
    let (fast, plain, it_fast, it_plain) = fast_and_plain(1e-4);
    let d4 = rel(&fast, &plain);
    eprintln!("fast vs plain, Ewald tol 1e-4: {d4:e}, GMRES iterations {it_fast} / {it_plain}");
    assert!(d4 < 2e-4, "fast vs plain at Ewald tolerance 1e-4: {d4:e}");
    assert!(it_fast.abs_diff(it_plain) <= 1, "GMRES iterations {it_fast} vs {it_plain}");
    let (fast, plain, _, _) = fast_and_plain(1e-6);
    let d6 = rel(&fast, &plain);
    eprintln!("fast vs plain, Ewald tol 1e-6: {d6:e}");
    assert!(d6 < 2e-6 && d6 < d4 / 10.0, "fast vs plain at Ewald tolerance 1e-6: {d6:e} (1e-4: {d4:e})");
}

/// The time integration's velocity (the `Stokes` trait, which skips the double-layer sum that
/// only the wall traction needs after GMRES) is the full solve's cell velocity bit for bit.
#[test]
fn the_trait_velocity_equals_the_full_solve() {
    use rbc_solver::bim::Stokes;
    let opts = ChannelOptions { ewald_tol: 1e-4, wall_edge_um: 2.0, cell_nodes_hint: 7 * 128, ..ChannelOptions::default() };
    let ch = ChannelStokes::new(ChannelGeometry::default(), 1.2e-3, ViscosityContrast::new(5.0).unwrap(), WallMode::NoSlip, opts).unwrap().with_mean_flow(3.0);
    let (f, at) = squeezed_path();
    let m = at(0);
    let full = ch.velocity_with_guess(&m, &f, 3.0, None).unwrap();
    assert!(full.stats.gmres_iterations > 0);
    let u = Stokes::velocity(&ch, &m, &f, true, None).unwrap();
    assert_eq!(u, full.cell_velocity);
    let guess: Vec<Vector3<f64>> = u.iter().map(|v| v * 1.01).collect();
    let full = ch.velocity_with_guess(&at(1), &f, 3.0, Some(&guess)).unwrap();
    assert_eq!(Stokes::velocity(&ch, &at(1), &f, true, Some(&guess)).unwrap(), full.cell_velocity);
}

#[test]
fn negative_iteration_cutoff_is_rejected() {
    let opts = ChannelOptions { ewald_tol: 1e-3, wall_edge_um: 3.0, iteration_sums: IterationSums::Cutoff(-1.0), ..ChannelOptions::default() };
    let e = ChannelStokes::new(ChannelGeometry::default(), 1.2e-3, ViscosityContrast::new(5.0).unwrap(), WallMode::NoSlip, opts).unwrap_err();
    assert!(e.to_string().contains("iteration_sums"), "{e}");
}

/// A pushed, off-centre 128-triangle discocyte moving along a path (0.02 um steps downstream,
/// as between stages of a time step, with a small squeeze so the velocity changes too): the
/// force density and the mesh at path point `k`.
fn squeezed_path() -> (Vec<Vector3<f64>>, impl Fn(usize) -> rbc_solver::mesh::Mesh) {
    let rot = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
    let base = discocyte(2).transformed(&rot, &Vector3::new(8.0, 0.9, -0.5));
    let c = base.centroid();
    let f: Vec<Vector3<f64>> = base.vertices.iter().map(|x| Vector3::new(4.0, x.y - c.y, -0.5 * (x.z - c.z))).collect();
    let at = move |k: usize| {
        let mut m = base.clone();
        let s = 0.02 * k as f64;
        m.vertices.iter_mut().for_each(|x| *x += Vector3::new(s, 0.0, 0.05 * s * (x.z - c.z)));
        m
    };
    (f, at)
}

/// The extrapolated GMRES guess (`ChannelOptions::extrapolate_guess`) only moves the starting
/// point: along a path of four cell positions (0.02 um steps downstream, as between stages of a
/// time step) the last velocity equals the one started from the last velocity to the GMRES
/// tolerance (1e-9 here), and it needs fewer iterations.
#[test]
fn extrapolated_guess_changes_only_the_start() {
    use rbc_solver::bim::Stokes;
    let opts = ChannelOptions { ewald_tol: 1e-4, wall_edge_um: 2.0, cell_nodes_hint: 7 * 128, gmres_tolerance: 1e-9, ..ChannelOptions::default() };
    let mut ch = ChannelStokes::new(ChannelGeometry::default(), 1.2e-3, ViscosityContrast::new(5.0).unwrap(), WallMode::NoSlip, opts).unwrap().with_mean_flow(3.0);
    let (f, at) = squeezed_path();
    let mut ends = Vec::new();
    for extrapolate in [false, true] {
        ch.set_extrapolate_guess(extrapolate);
        let mut last: Option<Vec<Vector3<f64>>> = None;
        let before = ch.gmres_totals().1;
        for k in 0..4 {
            let u = Stokes::velocity(&ch, &at(k), &f, true, last.as_deref()).unwrap();
            last = Some(u);
        }
        ends.push((last.unwrap(), ch.gmres_totals().1 - before));
    }
    let d = rel(&ends[1].0, &ends[0].0);
    eprintln!("extrapolated vs last-velocity guess: {d:e}, GMRES iterations {} vs {}", ends[1].1, ends[0].1);
    assert!(d < 1e-7, "{d:e}");
    assert!(ends[1].1 < ends[0].1, "{} vs {}", ends[1].1, ends[0].1);
}

/// The two-grid preconditioner (`ChannelOptions::two_grid_level`, the cell's own level-2 mesh)
/// changes only the iterations: a 512-triangle discocyte off the axis at lambda = 5 between
/// exact walls has the same velocity with and without it to the GMRES tolerance (1e-9 here), and
/// needs fewer iterations; at level 2 itself (no coarser mesh of that level) nothing changes.
#[test]
fn two_grid_preconditioner_changes_only_the_iterations() {
    use rbc_solver::bim::Stokes;
    let opts = ChannelOptions { ewald_tol: 1e-4, wall_edge_um: 2.0, cell_nodes_hint: 7 * 512, gmres_tolerance: 1e-9, extrapolate_guess: false, ..ChannelOptions::default() };
    assert_eq!(opts.two_grid_level, Some(2), "on by default");
    let mut ch = ChannelStokes::new(ChannelGeometry::default(), 1.2e-3, ViscosityContrast::new(5.0).unwrap(), WallMode::NoSlip, opts).unwrap().with_mean_flow(3.0);
    let rot = Rotation3::from_axis_angle(&Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
    let cell = discocyte(3).transformed(&rot, &Vector3::new(8.0, 0.9, -0.5));
    let c = cell.centroid();
    let f: Vec<Vector3<f64>> = cell.vertices.iter().map(|x| Vector3::new(4.0, x.y - c.y, -0.5 * (x.z - c.z))).collect();
    let mut runs = Vec::new();
    for level in [None, Some(2)] {
        ch.set_two_grid_level(level);
        let before = ch.gmres_totals().1;
        let u = Stokes::velocity(&ch, &cell, &f, true, None).unwrap();
        runs.push((u, ch.gmres_totals().1 - before));
    }
    let d = rel(&runs[1].0, &runs[0].0);
    eprintln!("two-grid vs plain: {d:e}, GMRES iterations {} vs {}", runs[1].1, runs[0].1);
    assert!(d < 1e-8, "{d:e}");
    assert!(runs[1].1 < runs[0].1, "{} vs {}", runs[1].1, runs[0].1);
    // a level-2 cell has no coarser level-2 mesh: the preconditioner is left out, bit for bit
    let coarse = discocyte(2).transformed(&rot, &Vector3::new(8.0, 0.9, -0.5));
    let fc: Vec<Vector3<f64>> = coarse.vertices.iter().map(|x| Vector3::new(4.0, x.y - c.y, 0.0)).collect();
    let with = Stokes::velocity(&ch, &coarse, &fc, true, None).unwrap();
    ch.set_two_grid_level(None);
    assert_eq!(Stokes::velocity(&ch, &coarse, &fc, true, None).unwrap(), with);
}

/// The path behind the extrapolated guess is checkpoint state: saved after three solves and
/// restored into a fresh solver, the fourth solve is bit-identical to the uninterrupted one
/// (a fresh solver without it starts from the plain last velocity and differs within the GMRES
/// tolerance).
#[test]
fn extrapolation_path_survives_a_checkpoint() {
    use rbc_solver::bim::Stokes;
    let opts = ChannelOptions { ewald_tol: 1e-4, wall_edge_um: 2.0, cell_nodes_hint: 7 * 128, extrapolate_guess: true, ..ChannelOptions::default() };
    let make = || ChannelStokes::new(ChannelGeometry::default(), 1.2e-3, ViscosityContrast::new(5.0).unwrap(), WallMode::NoSlip, opts.clone()).unwrap().with_mean_flow(3.0);
    let (f, at) = squeezed_path();
    let ch = make();
    let mut last = None;
    for k in 0..3 {
        last = Some(Stokes::velocity(&ch, &at(k), &f, true, last.as_deref()).unwrap());
    }
    let u2 = last.unwrap();
    let mut state = rbc_solver::state::StateMap::new();
    ch.save_state("stokes_", &mut state);
    assert_eq!(state.len(), 6, "three path points, vertices and velocity each: {:?}", state.keys().collect::<Vec<_>>());
    let uninterrupted = Stokes::velocity(&ch, &at(3), &f, true, Some(&u2)).unwrap();
    let restored = make();
    restored.restore_state("stokes_", &state).unwrap();
    assert_eq!(Stokes::velocity(&restored, &at(3), &f, true, Some(&u2)).unwrap(), uninterrupted);
    let fresh = Stokes::velocity(&make(), &at(3), &f, true, Some(&u2)).unwrap();
    assert_ne!(fresh, uninterrupted, "without the path the start (and so the last digits) differ");
}

/// The wall-time breakdown that `rbc-simulate` prints (`ChannelStokes::solve_times`) counts every
/// solve of the time integration's interface once, and its parts (GMRES, the double layer's
/// build, the single layer, the near field) are disjoint parts of the solves' total.
#[test]
fn solve_times_count_the_trait_solves_and_their_parts_fit_in_the_total() {
    use rbc_solver::bim::Stokes;
    let opts = ChannelOptions { ewald_tol: 1e-4, wall_edge_um: 2.0, cell_nodes_hint: 7 * 128, ..ChannelOptions::default() };
    let ch = ChannelStokes::new(ChannelGeometry::default(), 1.2e-3, ViscosityContrast::new(5.0).unwrap(), WallMode::NoSlip, opts).unwrap().with_mean_flow(3.0);
    let (f, at) = squeezed_path();
    assert_eq!(ch.solve_times().solves, 0);
    let mut last: Option<Vec<Vector3<f64>>> = None;
    for k in 0..2 {
        last = Some(Stokes::velocity(&ch, &at(k), &f, true, last.as_deref()).unwrap());
    }
    let t = ch.solve_times();
    eprintln!("{t:?}");
    assert_eq!(t.solves, 2);
    let parts = [t.gmres_s, t.double_layer_build_s, t.single_layer_s, t.near_field_s];
    assert!(parts.iter().all(|&p| p > 0.0), "{t:?}");
    assert!(parts.iter().sum::<f64>() <= t.total_s && t.rest_s() >= 0.0, "{t:?}");
    assert!(t.wall_solve_s <= t.total_s, "{t:?}");
}
