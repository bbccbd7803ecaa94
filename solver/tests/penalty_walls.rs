//! Penalty walls of the periodic channel: the spectrum of the wall operator (relaxation rates `kappa_W lambda(S) / mu`), the empty channel relaxing from unloaded springs to the no-slip flow, and a coarse lambda = 5 cell with penalty walls against exact no-slip walls.

use faer::{Mat, Side};
use nalgebra::Vector3;
use rbc_schema::scene::Scene;
use rbc_solver::channel::stokes::ChannelSolution;
use rbc_solver::channel::{ChannelStats, ChannelStokes};
use std::path::Path;

mod common;
use common::Tap;

/// The coarse channel of tests/channel_scene.rs (wall edge 2 um: 1008 wall triangles, Ewald
/// tolerance 1e-3, 1 mm/s) with a 128-triangle centred discocyte and the wall model `walls`.
fn channel_scene(lambda: f64, walls: &str, scheme: &str, end_s: f64, out_s: f64) -> Scene {
    let text = format!(
        r#"
name = "penalty"
[cell]
shape = "discocyte"
level = 2
position_um = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
{blocks}wall_edge_um = 2.0
ewald_tol = 1e-3
{walls}
[integrator]
scheme = "{scheme}"
atol_um = 3e-3
[time]
end_s = {end_s:e}
output_interval_s = {out_s:e}
"#,
        blocks = rbc_schema::paper_scene::channel_blocks(lambda, 1000.0)
    );
    Scene::parse(&text, Path::new("penalty.toml")).unwrap()
}

fn penalty_walls(kappa_w: f64) -> String {
    format!("wall_model = \"penalty\"\nkappa_w_n_m3 = {kappa_w:e}")
}

/// Eigenvalues (ascending) and eigenvectors of the symmetric part of `D^1/2 S D^-1/2` (`D` the
/// vertex areas, three times each), and the relative size of its antisymmetric part. For a
/// symmetric kernel `S_ij ~ G(x_i - x_j) a_j`, so this similarity transform is what makes it
/// symmetric; the rates `kappa_W lambda / mu` are those of `dd/dt = -(kappa_W / mu) S d`.
fn wall_spectrum(ch: &ChannelStokes) -> (Vec<f64>, Mat<f64>, f64) {
    let s = &ch.wall.matrix;
    let n = s.nrows();
    let a: Vec<f64> = (0..n).map(|r| ch.mesh.vertex_areas[r / 3].sqrt()).collect();
    let m = Mat::<f64>::from_fn(n, n, |i, j| a[i] * s[(i, j)] / a[j]);
    let sym = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (m[(i, j)] + m[(j, i)]));
    let anti = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (m[(i, j)] - m[(j, i)]));
    let evd = sym.self_adjoint_eigen(Side::Lower).unwrap();
    let lam: Vec<f64> = (0..n).map(|k| evd.S()[k]).collect();
    (lam, evd.U().to_owned(), anti.norm_l2() / sym.norm_l2())
}

/// Centre-line velocity (um/s) at `points` for the wall traction and `U0` of an empty-channel
/// penalty solve `sol`, via [`ChannelStokes::flow_at`] with a small force-free sphere far from the
/// points (its single layer is zero).
fn centre_line(ch: &ChannelStokes, sol: &ChannelSolution, points: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let dummy = rbc_solver::mesh::sphere(1, 0.3).transformed(&nalgebra::Rotation3::identity(), &Vector3::new(-20.0, 0.0, 0.0));
    let nv = dummy.vertices.len();
    let sol = ChannelSolution {
        cell_velocity: vec![Vector3::zeros(); nv],
        wall_traction: sol.wall_traction.clone(),
        wall_velocity: Vec::new(),
        stats: ChannelStats { viscosity_ratio: rbc_solver::viscosity::ViscosityContrast::MATCHED, ..sol.stats.clone() },
    };
    ch.flow_at(points, &dummy, &vec![Vector3::zeros(); nv], &sol).unwrap()
}

/// Study: spectrum of the wall operator and the empty channel from `d = 0`. Measured (1008 wall
/// triangles, 1512 x 1512, antisymmetric part 1.2e-2 of the symmetric part after the area
/// similarity; rates at kappa_W = 1.9e7): one near-null mode (83 % the normal "pressure" mode,
/// 75 1/s, carries 1.5e-4 of |d*| and no velocity), then 9.4e2 .. 1.7e3 1/s (modes 1-10),
/// median 3.0e3 1/s, 90th percentile 8.1e3 1/s, and only the smoothest modes reach 1.38e5 1/s
/// (the step-size limit). The empty channel decays at ~6e3 1/s (asserted by the test below).
/// These numbers are asserted (to 5 %, the overlap to 0.02, the antisymmetric part to 10 %).
/// Command: `cargo nextest run -p rbc-solver --run-ignored only --no-capture -E 'test(study_empty_channel_relaxation)'` (6 s idle).
#[test]
#[ignore = "study: the spectrum of the wall operator, asserted"]
fn study_empty_channel_relaxation() {
    let kw = 1.9e7;
    let scene = channel_scene(1.0, &penalty_walls(kw), "ros2", 1e-4, 1e-4);
    let built = rbc_solver::scene::build(&scene).unwrap();
    let ch = built.channel().unwrap();
    let mu = ch.viscosity();
    let k = kw * 1e-6;
    let nw = ch.mesh.n_vertices();
    let t0 = std::time::Instant::now();
    let (lam, u, asym) = wall_spectrum(ch);
    let rate = |l: f64| k * l / mu;
    let n = lam.len();
    eprintln!("wall operator {n} x {n}: antisymmetric part {asym:.2e} of the symmetric part ({:.1} s)", t0.elapsed().as_secs_f64());
    let near = |what: &str, x: f64, measured: f64, rel: f64| assert!((x / measured - 1.0).abs() <= rel, "{what}: {x:.4e}, measured {measured:e}");
    assert_eq!(n, 1512, "wall unknowns");
    near("antisymmetric part", asym, 1.2e-2, 0.1);
    near("rate of the near-null mode", rate(lam[0]), 75.0, 0.05);
    near("rate of mode 1", rate(lam[1]), 9.4e2, 0.05);
    near("rate of mode 10", rate(lam[10]), 1.7e3, 0.05);
    near("median rate", rate(lam[n / 2]), 3.0e3, 0.05);
    near("90th-percentile rate", rate(lam[9 * n / 10]), 8.1e3, 0.05);
    near("fastest rate", rate(lam[n - 1]), 1.38e5, 0.05);
    eprintln!("power-iteration rate (penalty_rate): {:.4e} 1/s", ch.penalty_rate(kw));
    for q in [0usize, 1, 2, 3, 5, 10, n / 100, n / 10, n / 4, n / 2, 3 * n / 4, 9 * n / 10, n - 2, n - 1] {
        eprintln!("  lambda[{q:5}] = {:.4e} um  -> rate {:.4e} 1/s, e-folding time {:.3e} s", lam[q], rate(lam[q]), 1.0 / rate(lam[q]));
    }
    // the smallest eigenvector: how much of it is the normal (pressure) mode?
    let normals: Vec<Vector3<f64>> = {
        // area-weighted vertex normals of the wall mesh
        let mut nn = vec![Vector3::zeros(); nw];
        for t in &ch.mesh.triangles {
            let [a, b, c] = [ch.mesh.vertices[t[0]], ch.mesh.vertices[t[1]], ch.mesh.vertices[t[2]]];
            let w = (b - a).cross(&(c - a));
            for &i in t {
                nn[i] += w;
            }
        }
        nn.iter().map(|v| v.normalize()).collect()
    };
    let nvec: Vec<f64> = (0..3 * nw).map(|r| normals[r / 3][r % 3] * ch.mesh.vertex_areas[r / 3].sqrt()).collect();
    let nn = nvec.iter().map(|v| v * v).sum::<f64>().sqrt();
    for q in 0..4 {
        let overlap: f64 = (0..3 * nw).map(|r| u[(r, q)] * nvec[r]).sum::<f64>() / nn;
        eprintln!("  eigenvector {q}: overlap with the normal (pressure) mode {overlap:.3}");
        if q == 0 {
            assert!((overlap.abs() - 0.83).abs() <= 0.02, "the near-null mode is the pressure mode: overlap {overlap:.3}, measured 0.83");
        }
    }

    // No-slip traction of the empty channel: f* = U0 S^-1 (-mu e_x) with U0 from the calibration.
    let (interior_fraction, _, _) = ch.calibration();
    let u_mean = 1e3 * ch.mean_flow_mm_s;
    let u0_ns = u_mean / interior_fraction;
    let f_star: Vec<Vector3<f64>> = ch.wall.solve(&vec![Vector3::x() * (-mu); nw]).iter().map(|f| f * u0_ns).collect();
    let d_star: Vec<Vector3<f64>> = f_star.iter().map(|f| -f / k).collect();
    // its modal content (D^1/2 d*) and the velocity each mode carries (lambda c)
    let y: Vec<f64> = (0..3 * nw).map(|r| d_star[r / 3][r % 3] * ch.mesh.vertex_areas[r / 3].sqrt()).collect();
    let c: Vec<f64> = (0..n).map(|q| (0..n).map(|r| u[(r, q)] * y[r]).sum::<f64>()).collect();
    let cn = c.iter().map(|v| v * v).sum::<f64>().sqrt();
    let vn = c.iter().zip(&lam).map(|(c, l)| (c * l).powi(2)).sum::<f64>().sqrt();
    for (lo, hi) in [(0usize, 1usize), (1, 10), (10, n / 10), (n / 10, n / 2), (n / 2, 9 * n / 10), (9 * n / 10, n)] {
        let part = c[lo..hi].iter().map(|v| v * v).sum::<f64>().sqrt() / cn;
        let vpart = c[lo..hi].iter().zip(&lam[lo..hi]).map(|(c, l)| (c * l).powi(2)).sum::<f64>().sqrt() / vn;
        eprintln!("  modes [{lo}, {hi}) (rates {:.2e}..{:.2e} 1/s): {part:.3e} of |d*|, {vpart:.3e} of |S d*|", rate(lam[lo]), rate(lam[hi - 1]));
        if lo == 0 {
            near("share of |d*| in the near-null mode", part, 1.5e-4, 0.1);
        }
    }

    let hist = empty_channel_history(ch, rate(lam[n - 1]), 2e-3);
    for r in &hist {
        eprintln!(
            "t {:.3e} s: centre-line error {:+.3e}, (0,3,2) error {:+.3e}; mean wall slip {:+.3e} um/s, max |u_wall| {:.3e} um/s; max |d - d*| {:.3e} um, mean d_x {:.3e} um (d*_x {:.3e})",
            r.t, r.centre_error, r.off_axis_error, r.mean_slip, r.max_wall_velocity, r.max_d_error, r.mean_dx, r.mean_dx_star
        );
    }
}

/// One sample of the empty channel relaxing from unloaded springs.
struct Relax {
    t: f64,
    /// Relative error of the centre-line velocity at (0, 0, 0) and of the velocity at (0, 3, 2) um.
    centre_error: f64,
    off_axis_error: f64,
    /// Area-mean x velocity of the wall vertices and largest wall speed (um/s).
    mean_slip: f64,
    max_wall_velocity: f64,
    /// Largest distance from the no-slip displacement `d* = -f*/kappa_W`, area-mean x displacement and that of `d*` (um).
    max_d_error: f64,
    mean_dx: f64,
    mean_dx_star: f64,
}

/// The empty channel with penalty walls from `d = 0` (plug flow) to `end_s`, by the real penalty
/// solve ([`ChannelStokes::penalty_velocity`] without a cell) and classical RK4 at
/// `h = 1.5 / max_rate` (inside its stability interval 2.78 / rate); samples at t = 0, h, 2h, 4h, ...
fn empty_channel_history(ch: &ChannelStokes, max_rate: f64, end_s: f64) -> Vec<Relax> {
    let rbc_solver::channel::WallMode::Penalty { kappa_w_n_per_m3 } = ch.wall_mode else { panic!("penalty walls") };
    let k = kappa_w_n_per_m3 * 1e-6;
    let mu = ch.viscosity();
    let nw = ch.mesh.n_vertices();
    // No-slip traction of the empty channel: f* = U0 S^-1 (-mu e_x) with U0 from the calibration.
    let (interior_fraction, _, _) = ch.calibration();
    let u0_ns = 1e3 * ch.mean_flow_mm_s / interior_fraction;
    let d_star: Vec<Vector3<f64>> = ch.wall.solve(&vec![Vector3::x() * (-mu); nw]).iter().map(|f| -f * u0_ns / k).collect();
    let points = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(0.0, 3.0, 2.0)];
    let (u_ns, _) = ch.empty_channel_flow(&points, ch.mean_flow_mm_s).unwrap();
    let h = 1.5 / max_rate;
    let f = |d: &[Vector3<f64>]| ch.penalty_velocity(None, d, ch.mean_flow_mm_s).unwrap();
    let areas = &ch.mesh.vertex_areas;
    let area: f64 = areas.iter().sum();
    let mean_x = |v: &[Vector3<f64>]| v.iter().zip(areas).map(|(v, a)| v.x * a).sum::<f64>() / area;
    let mut d = vec![Vector3::zeros(); nw];
    let (mut t, mut next_out, mut out) = (0.0, 0.0, Vec::new());
    loop {
        if t >= next_out - 1e-15 || t >= end_s {
            let sol = f(&d);
            let cl = centre_line(ch, &sol, &points);
            out.push(Relax {
                t,
                centre_error: cl[0].x / u_ns[0].x - 1.0,
                off_axis_error: cl[1].x / u_ns[1].x - 1.0,
                mean_slip: mean_x(&sol.wall_velocity),
                max_wall_velocity: sol.wall_velocity.iter().map(|v| v.norm()).fold(0.0, f64::max),
                max_d_error: d.iter().zip(&d_star).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max),
                mean_dx: mean_x(&d),
                mean_dx_star: mean_x(&d_star),
            });
            next_out = if next_out == 0.0 { h } else { next_out * 2.0 };
            if t >= end_s {
                return out;
            }
        }
        let add = |d: &[Vector3<f64>], v: &[Vector3<f64>], s: f64| -> Vec<Vector3<f64>> { d.iter().zip(v).map(|(a, b)| a + b * s).collect() };
        let k1 = f(&d).wall_velocity;
        let k2 = f(&add(&d, &k1, 0.5 * h)).wall_velocity;
        let k3 = f(&add(&d, &k2, 0.5 * h)).wall_velocity;
        let k4 = f(&add(&d, &k3, h)).wall_velocity;
        for i in 0..nw {
            d[i] += (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) * (h / 6.0);
        }
        t += h;
    }
}

/// Penalty walls started unloaded (`d = 0`, the cell-free channel carrying plug flow) relax to
/// the exact no-slip flow, but at the rate of the bulk of the wall modes, not at the fastest rate
/// `kappa_W lambda_max(S) / mu` (1.38e5 1/s at the paper's 1.9e7 N/m^3) that limits explicit
/// steps: measured centre-line error -74 % at t = 0, -8 % at 0.35 ms, -0.9 % at 0.69 ms,
/// -1.2e-4 at 1.39 ms, decaying at ~6.3e3 1/s (e-folding 0.16 ms, 22x slower than the fastest
/// mode); the steady state is the no-slip flow (error -5e-6 at 2 ms, still decaying). At 10x the
/// stiffness the same history runs 10x faster (the rates are proportional to kappa_W).
#[test]
fn empty_channel_penalty_walls_relax_to_no_slip_at_the_bulk_rate_of_the_wall_modes() {
    let mut decay = Vec::new();
    for (kw, end) in [(1.9e7, 1.4e-3), (1.9e8, 1.4e-4)] {
        let scene = channel_scene(1.0, &penalty_walls(kw), "ros2", 1e-4, 1e-4);
        let built = rbc_solver::scene::build(&scene).unwrap();
        let ch = built.channel().unwrap();
        let max_rate = ch.penalty_rate(kw);
        let hist = empty_channel_history(ch, max_rate, end);
        for r in &hist {
            eprintln!("kappa_W {kw:e}: t {:.3e} s centre-line error {:+.3e}, mean wall slip {:+.3e} um/s", r.t, r.centre_error, r.mean_slip);
        }
        // plug flow at t = 0 (the box-mean flow, slower than the mean on the centre line)
        assert!(hist[0].centre_error < -0.5, "{}", hist[0].centre_error);
        // monotone approach from below, to the no-slip flow
        for w in hist.windows(2) {
            assert!(w[1].centre_error > w[0].centre_error && w[1].centre_error < 0.0);
            assert!(w[1].mean_slip < w[0].mean_slip && w[1].mean_slip > 0.0);
        }
        let last = hist.last().unwrap();
        assert!(last.centre_error.abs() < 1e-3 && last.off_axis_error.abs() < 1e-3, "{} {}", last.centre_error, last.off_axis_error);
        // decay rate over the second half of the run
        let a = hist.iter().rev().find(|r| r.t <= 0.55 * end).unwrap();
        let b = last;
        let rate = (a.centre_error / b.centre_error).ln() / (b.t - a.t);
        eprintln!("kappa_W {kw:e}: decay rate {rate:.3e} 1/s, fastest wall mode {max_rate:.3e} 1/s");
        assert!(rate < 0.1 * max_rate && rate > 0.01 * max_rate, "{rate}");
        decay.push(rate);
    }
    // the rates scale with kappa_W (same linear operator, 10x the stiffness)
    assert!((decay[1] / decay[0] / 10.0 - 1.0).abs() < 0.2, "{decay:?}");
}

/// Runs `scene`; returns the recorder, the summary and the assembly lines.
fn run(scene: &Scene) -> (rbc_solver::run::Recorder, rbc_solver::run::RunSummary, Vec<String>) {
    run_logged(scene, None)
}

/// [`run`], writing the step log to `log` when given.
fn run_logged(scene: &Scene, log: Option<&Path>) -> (rbc_solver::run::Recorder, rbc_solver::run::RunSummary, Vec<String>) {
    let built = rbc_solver::scene::build(scene).unwrap();
    let mut rec = rbc_solver::run::Recorder::default();
    let t0 = std::time::Instant::now();
    let (summary, _) = match log {
        Some(path) => {
            let mut log = rbc_solver::run::step_log::StepLog::create(path, &built.mesh.triangles).unwrap();
            built.run(&mut rbc_solver::run::Fanout(vec![&mut rec, &mut log])).unwrap()
        }
        None => built.run(&mut rec).unwrap(),
    };
    eprintln!("{summary:?} ({:.1} s)", t0.elapsed().as_secs_f64());
    (rec, summary, built.assembled)
}

/// Penalty walls at lambda = 5 over a few steps (40 us, the 128-triangle discocyte, 1008 wall
/// triangles): the state carries the wall displacements through the double-layer solve, the
/// volume correction keeps the cell's volume, and the cell moves as with exact no-slip walls
/// within the lag of the springs.
#[test]
fn penalty_walls_at_lambda_5_track_the_no_slip_run_over_a_few_steps() {
    let end = 4e-5;
    // steps of at most 10 us: the first accepted step would otherwise grow to the end at once
    // (the runner's fac_max_first), and the displacements are to be carried over several
    let capped = |s: Scene| Scene::parse(&s.source.replace("atol_um = 3e-3\n", "atol_um = 3e-3\nh_max_s = 1e-5\n"), Path::new("penalty.toml")).unwrap();
    let (ns, _, _) = run(&capped(channel_scene(5.0, "", "bs23", end, end)));
    let (pen, summary, assembled) = run(&capped(channel_scene(5.0, &penalty_walls(1.9e7), "bs23", end, end)));
    assert!(assembled.iter().any(|l| l.contains("penalty springs")) && assembled.iter().any(|l| l.contains("lambda = 5")), "{assembled:?}");
    assert!(summary.accepted >= 3, "a few steps: {summary:?}");
    let v = |r: &rbc_solver::run::Recorder| (r.centroid_um[1] - r.centroid_um[0]) / (r.times_s[1] - r.times_s[0]);
    let (vn, vp) = (v(&ns), v(&pen));
    eprintln!("centroid velocity no-slip ({:.4}, {:.2e}, {:.2e}) um/s, penalty ({:.4}, {:.2e}, {:.2e}) um/s: relative difference {:.3e}", vn.x, vn.y, vn.z, vp.x, vp.y, vp.z, vp.x / vn.x - 1.0);
    for vol in &pen.volume_um3 {
        assert!((vol / pen.volume_um3[0] - 1.0).abs() < 1e-8, "volume {vol} vs {}", pen.volume_um3[0]);
    }
    // Measured -1.24 % (steps of at most 10 us): the springs start at the exact no-slip traction
    // of t = 0 but lag the coarse discocyte, which relaxes with membrane velocities of ~10 mm/s; most wall modes
    // follow at 2e3..8e3 1/s (`study_empty_channel_relaxation`), so after 40 us the walls still
    // carry nearly the traction of t = 0. Over 0.2 ms this lag reaches -13 % at lambda = 1
    // (tests/channel_scene.rs). The lateral velocity is the wall mesh's asymmetry (< 1e-3 of x).
    let rel = vp.x / vn.x - 1.0;
    assert!(rel.abs() < 0.03 && rel.abs() > 1e-4, "{rel}");
    assert!(vp.y.abs() < 1e-3 * vp.x && vp.z.abs() < 1e-3 * vp.x);
}

/// Study: the steady error of penalty walls for a cell translating at `V`: in the frame of the
/// cell the wall traction pattern moves at `-V`, so the springs must move the wall vertices at
/// `u_s = -(1/kappa_W) df*/dt = (V / kappa_W) df*/dx` (quasi-static, valid while `V / l` is
/// below the relaxation rates of the wall modes). The cell velocity that this slip causes is
/// computed with the penalty solve itself: `d = -(f* + mu S^-1 u_s) / kappa_W`.
/// Measured at 1 mm/s (V = 1.58 mm/s centred, 1.48 mm/s at y = 1.5 um): slip rms 1.7 % (2.1 %),
/// max 10 % (13 %) of V, cell velocity +3.4 % (+3.6 %) at kappa_W = 1.9e7, +0.36 % at 1.9e8
/// (the slip runs backwards under the cell, against its motion, and the fixed flux pushes the
/// difference through the middle); the lateral velocity of the offset cell changes by 4 %. The
/// error is proportional to V / kappa_W, so ~+17 % at 5 mm/s with the paper's kappa_W if the
/// quasi-static picture still held there (it does not: V / l ~ 1e3 1/s per mm/s approaches the
/// bulk wall rates 2e3..8e3 1/s, and modes that cannot follow carry less slip). The full run
/// (`study_penalty_over_time`) shows +1.7..+1.9 % between 0.3 and 0.9 ms: same sign, half the size.
/// Asserted per case (kappa_W, y): V to 1 %, the slip's rms to 0.1 and its max to 1 percentage
/// point of V, the cell velocity error to 0.15 (0.03 at 1.9e8) percentage points.
/// Command: `cargo nextest run -p rbc-solver --run-ignored only --no-capture -E 'test(study_translating_cell_slip)'`.
#[test]
#[ignore = "study: the steady slip error of penalty walls, asserted"]
fn study_translating_cell_slip() {
    // (kappa_W, cell offset y, V um/s, slip rms / V, slip max / V, cell velocity error), measured
    for (kw, y, v, rms, max, err) in [(1.9e7, 0.0, 1.58e3, 0.017, 0.10, 0.034), (1.9e7, 1.5, 1.48e3, 0.021, 0.13, 0.036), (1.9e8, 0.0, 1.58e3, f64::NAN, f64::NAN, 0.0036)] {
        let (vx, found_rms, found_max, found_err) = translating_cell_slip(kw, y);
        let case = format!("kappa_W {kw:e}, y {y} um: V {vx:.1} um/s, slip rms {found_rms:.4} max {found_max:.4} of V, cell velocity error {found_err:+.4}");
        assert!((vx / v - 1.0).abs() <= 0.01, "{case}; measured V {v}");
        assert!(rms.is_nan() || (found_rms - rms).abs() <= 1e-3, "{case}; measured slip rms {rms}");
        assert!(max.is_nan() || (found_max - max).abs() <= 1e-2, "{case}; measured slip max {max}");
        let tol = if kw > 1e8 { 3e-4 } else { 1.5e-3 };
        assert!((found_err - err).abs() <= tol, "{case}; measured error {err}");
    }
}

/// One case of [`study_translating_cell_slip`]: the no-slip centroid velocity (um/s), the rms and
/// max of the quasi-static slip over V, and the relative error of the cell velocity it causes.
fn translating_cell_slip(kw: f64, y: f64) -> (f64, f64, f64, f64) {
    let k = kw * 1e-6;
    let scene = channel_scene(1.0, &penalty_walls(kw), "ros2", 1e-4, 1e-4);
    let built = rbc_solver::scene::build(&scene).unwrap();
    let ch = built.channel().unwrap();
    let mu = ch.viscosity();
    let mean = ch.mean_flow_mm_s;
    use rbc_solver::membrane::MembraneLaw;
    let mesh = built.mesh.transformed(&nalgebra::Rotation3::identity(), &Vector3::new(0.0, y, 0.0));
    let f = built.membrane.force_density(&mesh);
    let s0 = ch.velocity_with_guess(&mesh, &f, mean, None).unwrap();
    let v = rbc_solver::channel::stokes::centroid_velocity(&mesh, &s0.cell_velocity);
    eprintln!("no-slip centroid velocity ({:.3}, {:.3e}, {:.3e}) um/s", v.x, v.y, v.z);
    let dx = 0.25;
    let shifted = mesh.transformed(&nalgebra::Rotation3::identity(), &Vector3::new(dx, 0.0, 0.0));
    let s1 = ch.velocity_with_guess(&shifted, &f, mean, None).unwrap();
    // the traction at a wall vertex after dt is that of the cell shifted by V dt: df/dt = V (f1 - f0) / dx
    let u_s: Vec<Vector3<f64>> = s1.wall_traction.iter().zip(&s0.wall_traction).map(|(a, b)| (a - b) * (-v.x / (k * dx))).collect();
    let areas = &ch.mesh.vertex_areas;
    let area: f64 = areas.iter().sum();
    let rms = (u_s.iter().zip(areas).map(|(u, a)| u.norm_squared() * a).sum::<f64>() / area).sqrt();
    let max = u_s.iter().map(|u| u.norm()).fold(0.0, f64::max);
    let mean_x = u_s.iter().zip(areas).map(|(u, a)| u.x * a).sum::<f64>() / area;
    let fmax = s0.wall_traction.iter().map(|f| f.norm()).fold(0.0, f64::max);
    eprintln!("kappa_W {kw:e}, cell at y = {y}: V = {:.2} um/s; max |f*| {fmax:.3} Pa (|d| {:.3} um); slip u_s: rms {rms:.3e}, max {max:.3e}, mean x {mean_x:.3e} um/s ({:.2e}, {:.2e} of V)", v.x, fmax / k, rms / v.x, max / v.x);
    let df = ch.wall.solve(&u_s.iter().map(|u| u * mu).collect::<Vec<_>>());
    let d: Vec<Vector3<f64>> = s0.wall_traction.iter().zip(&df).map(|(f, g)| -(f + g) / k).collect();
    let sp = ch.penalty_velocity(Some((&mesh, &f)), &d, mean).unwrap();
    let vp = rbc_solver::channel::stokes::centroid_velocity(&mesh, &sp.cell_velocity);
    let wall_err = sp.wall_velocity.iter().zip(&u_s).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
    let d0: Vec<Vector3<f64>> = s0.wall_traction.iter().map(|f| -f / k).collect();
    let sq = ch.penalty_velocity(Some((&mesh, &f)), &d0, mean).unwrap();
    let vq = rbc_solver::channel::stokes::centroid_velocity(&mesh, &sq.cell_velocity);
    eprintln!(
        "penalty at d(f*): V {:.3} (consistency {:.1e}); with the slip: wall velocity - u_s {wall_err:.2e} um/s (uniform U0 shift), cell velocity ({:.3}, {:.3e}, {:.3e}) um/s: relative error {:+.3e}",
        vq.x, vq.x / v.x - 1.0, vp.x, vp.y, vp.z, vp.x / v.x - 1.0
    );
    (v.x, rms / v.x, max / v.x, vp.x / v.x - 1.0)
}

/// Study: the coarse lambda = 1 cell (centred, 1 mm/s) with exact no-slip and with penalty walls
/// (kappa_W = 1.9e7) over 1 ms, ROS2: centroid velocity per 0.1 ms output interval and the
/// relative difference, to see the transient of the springs decay to the steady lag error.
/// Measured (asserted to 0.1 percentage point per window, and 31-36 steps): +0.32 %, +0.45 % in the
/// first two 0.1 ms (the 0.2 ms comparison of tests/channel_scene.rs now gives +0.38 %, and
/// +0.02 % at 1.9e8; its doc's -13.3 % / +0.6 % are not reproduced by this code), then +1.2,
/// +1.8, +1.9, +1.9, +1.8, +1.9, +1.7, +1.1 % up to 1 ms; 33-34 ROS2 steps per ms for both wall
/// models (h up to 9e-5 s, 5x the explicit limit 1.8e-5 s of the springs). Over 3 ms (0.25 ms
/// windows; measured, not asserted): +0.5, +1.75, +1.8, +1.5, +0.3, -0.03, +0.2, +0.7, +0.9, +0.9, +0.8, +0.9 %: the
/// difference follows the cell's shape relaxation and settles near +0.9 % by 2-3 ms. At
/// kappa_W = 1.9e8 the same windows stay within -0.055 .. +0.12 % (10x smaller; same step count).
/// Command: `cargo nextest run -p rbc-solver --run-ignored only --no-capture -E 'test(study_penalty_over_time)'`.
#[test]
#[ignore = "study: penalty against no-slip walls over 1 ms, asserted"]
fn study_penalty_over_time() {
    const MEASURED: [f64; 10] = [0.0032, 0.0045, 0.012, 0.018, 0.019, 0.019, 0.018, 0.019, 0.017, 0.011];
    let (end, out) = (1e-3, 1e-4);
    let (ns, s_ns, _) = run(&channel_scene(1.0, "", "ros2", end, out));
    let (pen, s_pen, _) = run(&channel_scene(1.0, &penalty_walls(1.9e7), "ros2", end, out));
    let mut found = Vec::new();
    for i in 1..ns.times_s.len().min(pen.times_s.len()) {
        let dt = ns.times_s[i] - ns.times_s[i - 1];
        let vn = (ns.centroid_um[i] - ns.centroid_um[i - 1]) / dt;
        let vp = (pen.centroid_um[i] - pen.centroid_um[i - 1]) / dt;
        eprintln!(
            "t {:.2e}..{:.2e} s: no-slip ({:.2}, {:+.2e}, {:+.2e}) um/s, penalty ({:.2}, {:+.2e}, {:+.2e}) um/s, difference {:+.3e}",
            ns.times_s[i - 1], ns.times_s[i], vn.x, vn.y, vn.z, vp.x, vp.y, vp.z, vp.x / vn.x - 1.0
        );
        found.push(vp.x / vn.x - 1.0);
    }
    eprintln!("steps: no-slip {} (h {:.2e}..{:.2e} s), penalty {} (h {:.2e}..{:.2e} s)", s_ns.accepted, s_ns.h_min_s, s_ns.h_max_s, s_pen.accepted, s_pen.h_min_s, s_pen.h_max_s);
    assert_eq!(found.len(), MEASURED.len(), "{found:?}");
    for (k, (f, m)) in found.iter().zip(MEASURED).enumerate() {
        assert!((f - m).abs() <= 1e-3, "window {k}: difference {f:+.4}, measured {m:+}");
    }
    for s in [&s_ns, &s_pen] {
        assert!((31..=36).contains(&s.accepted), "ROS2 steps over 1 ms: {s:?}, measured 33-34");
    }
}

/// A lambda = 5 run with penalty walls resumed from a checkpoint repeats the uninterrupted run
/// bit for bit, with the paper's integrator and with the study's W-method: the checkpoint holds
/// the wall displacements (part of the state) and the last cell velocity that starts the next
/// GMRES solve (without it the resumed solve would start cold and differ within the GMRES
/// tolerance), and for the W-method the dense factor's linearisation point, which the resumed
/// run factorises again with the walls' block.
#[test]
fn penalty_run_resumed_from_a_checkpoint_repeats_the_uninterrupted_one() {
    // (the W-method steps across outputs: its checkpoints fall at step ends, its samples after a
    // checkpoint are those the resumed run writes)
    for (scheme, end, out) in [("bs23", 6e-5, 2e-5), ("ros34pw2-mobility", 6e-4, 1e-4), ("rosw6s4-mobility", 6e-4, 1e-4)] {
        let scene = channel_scene(5.0, &penalty_walls(1.9e7), scheme, end, out);
        let built = rbc_solver::scene::build(&scene).unwrap();
        let mut full = Tap::default();
        let (s_full, x_full) = built.run(&mut full).unwrap();
        let times: Vec<f64> = full.states.iter().map(|s| s.t_s).collect();
        eprintln!("{scheme}: checkpoints at {times:?} s, {} steps", s_full.accepted);
        assert!(full.states.len() >= 3, "{scheme}: a checkpoint at t = 0 and at two steps or more: {times:?}");
        let st = rbc_solver::run::checkpoint::RunState::from_fields(&full.states[1].to_fields(), "").unwrap();
        assert!(st.t_s > 0.0 && st.t_s < end);
        assert!(st.dynamics.keys().any(|k| k.contains("last_velocity")), "{:?}", st.dynamics.keys().collect::<Vec<_>>());
        let mut part = Tap { from: Some(st), ..Default::default() };
        let (s, x) = built.run(&mut part).unwrap();
        assert_eq!(x, x_full, "{scheme}: final state after resuming at t = {} s", times[1]);
        let later = full.rec.times_s.iter().filter(|t| **t > times[1]).count();
        assert_eq!(part.rec.vertices.len(), later, "{scheme}");
        assert_eq!(part.rec.vertices[..], full.rec.vertices[full.rec.vertices.len() - later..]);
        assert_eq!((s.accepted, s.rejected), (s_full.accepted, s_full.rejected), "{scheme}");
    }
}

/// The walls' block of the W-method's Jacobian is the exact derivative of the wall velocity
/// with respect to the wall displacement (`ChannelStokes::penalty_wall_jacobian`): at
/// lambda = 1 the penalty solve is linear in `d`, so `J_ww delta` equals the difference of two
/// solves to rounding, for a displacement with an axial net part (the flux's rank-one term) and
/// one without; and its largest rate is `penalty_rate`'s (that of `S` alone) to 1 %: the
/// fastest mode is the smoothest, whose axial part carries a net force, the flux's term
/// (measured 1.3816e5 against 1.3758e5 1/s).
#[test]
fn the_wall_block_is_the_derivative_of_the_penalty_wall_velocity() {
    let kw = 1.9e7;
    let scene = channel_scene(1.0, &penalty_walls(kw), "bs23", 1e-4, 1e-4);
    let built = rbc_solver::scene::build(&scene).unwrap();
    let ch = built.channel().unwrap();
    let j = ch.penalty_wall_jacobian(kw);
    let nw = ch.mesh.n_vertices();
    assert_eq!((j.nrows(), j.ncols()), (3 * nw, 3 * nw));
    let d0: Vec<Vector3<f64>> = (0..nw).map(|i| Vector3::new(0.02 * (i as f64 * 0.37).sin(), 0.01, -0.015 * (i as f64 * 0.11).cos())).collect();
    let base = ch.penalty_velocity(None, &d0, 1.0).unwrap();
    let mut net_x = Vec::new();
    for (name, delta) in [
        ("axial", (0..nw).map(|i| Vector3::new(0.01 + 0.005 * (i as f64).cos(), 0.0, 0.0)).collect::<Vec<_>>()),
        ("mixed", (0..nw).map(|i| Vector3::new((i as f64 * 0.9).sin(), (i as f64 * 0.3).cos(), 0.5) * 0.01).collect()),
    ] {
        let d1: Vec<Vector3<f64>> = d0.iter().zip(&delta).map(|(a, b)| a + b).collect();
        let moved = ch.penalty_velocity(None, &d1, 1.0).unwrap();
        let x = Mat::from_fn(3 * nw, 1, |r, _| delta[r / 3][r % 3]);
        let jd = &j * &x;
        let (mut err, mut size) = (0.0f64, 0.0f64);
        for i in 0..nw {
            let diff = moved.wall_velocity[i] - base.wall_velocity[i];
            let want = Vector3::new(jd[(3 * i, 0)], jd[(3 * i + 1, 0)], jd[(3 * i + 2, 0)]);
            err = err.max((diff - want).norm());
            size = size.max(diff.norm());
        }
        eprintln!("{name}: largest |J delta - du| {err:.3e} um/s of {size:.3e}");
        assert!(size > 1.0 && err <= 1e-9 * size, "{name}: {err:e} of {size:e}");
        let area_x: f64 = delta.iter().zip(&ch.mesh.vertex_areas).map(|(d, a)| d.x * a).sum();
        net_x.push(area_x);
    }
    assert!(net_x[0].abs() > 1.0, "the axial displacement carries a net force: {net_x:?}");
    // the largest rate: a power iteration on -J_ww (as penalty_rate's on S)
    let mut v = Mat::from_fn(3 * nw, 1, |r, _| 1.0 + (r as f64).sin());
    let mut lam = 0.0;
    for _ in 0..200 {
        let w = &j * &v;
        lam = w.norm_l2() / v.norm_l2();
        v = &w * (1.0 / w.norm_l2());
    }
    let rate = ch.penalty_rate(kw);
    assert!((lam / rate - 1.0).abs() < 1e-2, "largest rate {lam:e} against penalty_rate {rate:e}");
}

/// The study's W-method (`ros34pw2-mobility`) runs penalty walls: the wall displacements enter
/// its Jacobian with their own dense block (`MobilityJacobian::with_wall_block`,
/// `ChannelStokes::penalty_wall_jacobian`), and `integrator.wall_atol_um` reaches the step control. Over 0.2 ms of the coarse lambda = 5 scene from an
/// offset start it stays within a quarter of its tolerance (3e-3 um) of the explicit bs23 run of the same walls (which the
/// springs hold at its stability limit, ~2.5 / rate = 18 us), in fewer steps (measured: largest
/// vertex deviation 6.0e-4 um over a travel of 0.29 um, 5 steps against 11; 5.5e-4 with the
/// walls' factor at the cell's scaled `g` before session 24, where the cell's own error dominates
/// over these 0.2 ms; with the walls as a scalar rate instead, session 22: 1.8e-3 um), and keeps the cell's volume. The paper's channel
/// at 2048 triangles: `solver/README.md`, "Session 23".
#[test]
fn the_mobility_w_method_runs_penalty_walls_as_bs23_does() {
    // (the outputs bound the steps: one every 0.1 ms)
    let (end, out) = (2e-4, 1e-4);
    let offset = |s: Scene, wall_atol: &str| {
        let text = s.source.replace("position_um = [0.0, 0.0, 0.0]", "position_um = [0.0, 0.9, 0.5]").replace("atol_um = 3e-3\n", &format!("atol_um = 3e-3\n{wall_atol}"));
        Scene::parse(&text, Path::new("penalty.toml")).unwrap()
    };
    let walls = penalty_walls(1.9e7);
    let (reference, s_ref, _) = run(&offset(channel_scene(5.0, &walls, "bs23", end, out), ""));
    let deviation = |w: &rbc_solver::run::Recorder| {
        assert_eq!(w.times_s, reference.times_s);
        w.vertices.iter().zip(&reference.vertices).flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| (p - q).norm())).fold(0.0, f64::max)
    };
    let (w, s_w, assembled) = run(&offset(channel_scene(5.0, &walls, "ros34pw2-mobility", end, out), ""));
    assert!(assembled.iter().any(|l| l.contains("penalty springs")), "{assembled:?}");
    let dev = deviation(&w);
    let moved = (w.centroid_um.last().unwrap() - w.centroid_um[0]).norm();
    // the walls held to their own, tighter tolerance
    // (with the step log: it splits each attempt's error between the cell and the walls)
    let dir = tempfile::tempdir().unwrap();
    let log_path = dir.path().join("steps.csv");
    let (tight, s_tight, assembled_tight) = run_logged(&offset(channel_scene(5.0, &walls, "ros34pw2-mobility", end, out), "wall_atol_um = 3e-4\n"), Some(&log_path));
    assert!(assembled_tight.iter().any(|l| l.contains("wall displacements 3e-4 um")), "{assembled_tight:?}");
    let text = std::fs::read_to_string(&log_path).unwrap();
    let head: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<String>> = text.lines().skip(1).map(|l| l.split(',').map(str::to_string).collect()).collect();
    assert_eq!(rows.len(), s_tight.accepted + s_tight.rejected, "one row per attempt");
    let n_cell = tight.vertices[0].len();
    let mut wall_set = 0;
    for r in &rows {
        let f = |name: &str| r[col(name)].parse::<f64>().unwrap();
        let (e, cell, wall, worst) = (f("error_norm"), f("cell_error_norm"), f("wall_error_norm"), f("worst_vertex") as usize);
        // the max norm over the whole state is the larger part's, and the worst vertex lies in it
        assert!((e - cell.max(wall)).abs() <= 1e-5 * e, "{r:?}");
        assert_eq!(worst >= n_cell, wall > cell, "{r:?}");
        wall_set += usize::from(wall > cell);
    }
    // the walls' tolerance, 10x tighter than the cell's, sets the step on some attempts
    assert!(wall_set > 0, "{text}");
    let dev_tight = deviation(&tight);
    eprintln!("largest vertex deviation {dev:.2e} um over a travel of {moved:.3} um; steps {} (bs23 {}); walls at 3e-4 um: {dev_tight:.2e} um, {} steps", s_w.accepted, s_ref.accepted, s_tight.accepted);
    assert!(moved > 0.1, "the cell moves: {moved} um");
    assert!(dev < 7.5e-4, "within a quarter of the tolerance (3e-3 um) of bs23: {dev:.2e} um");
    assert!(s_w.accepted < s_ref.accepted, "fewer steps than bs23 at its stability limit: {} against {}", s_w.accepted, s_ref.accepted);
    // (over these 0.2 ms the cell's own error dominates: measured 5.2e-4 um in 6 steps; mid-run in
    // the paper's channel the walls' does, solver/README.md "Session 23")
    assert!(dev_tight < 6e-4 && s_tight.accepted > s_w.accepted, "the walls' own tolerance: {dev_tight:.2e} um in {} steps", s_tight.accepted);
    // the walls' answer to the cell in the stages (`integrator.wall_coupling`): one velocity
    // evaluation more for each of the four stages, in the same steps, and as close to bs23 here,
    // where the cell's own error dominates (measured 6.08e-4 um in 5 steps, 8 evaluations a step)
    let (coupled, s_c, assembled_c) = run(&offset(channel_scene(5.0, &walls, "ros34pw2-mobility", end, out), "wall_coupling = true\n"));
    assert!(assembled_c.iter().any(|l| l.contains("coupled to the cell in the stages")), "{assembled_c:?}");
    let attempts = |s: &rbc_solver::run::RunSummary| s.accepted + s.rejected;
    assert_eq!(attempts(&s_c), attempts(&s_w), "the same steps: {s_c:?} against {s_w:?}");
    assert_eq!(s_c.velocity_evals, s_w.velocity_evals + 4 * attempts(&s_c), "one evaluation more a stage: {s_c:?} against {s_w:?}");
    let dev_c = deviation(&coupled);
    assert!(dev_c < 6.5e-4, "coupled: {dev_c:.2e} um from bs23 in {} steps", s_c.accepted);
    // the steps end on the corrected volume (1e-9); the outputs between them are the scheme's
    // dense output (measured 2.2e-7)
    for vol in &w.volume_um3 {
        assert!((vol / w.volume_um3[0] - 1.0).abs() < 1e-6, "volume {vol} vs {}", w.volume_um3[0]);
    }
}

