//! Penalty walls of the periodic channel: the spectrum of the wall operator (relaxation rates `kappa_W lambda(S) / mu`), the empty channel relaxing from unloaded springs to the no-slip flow, and a coarse lambda = 5 cell with penalty walls against exact no-slip walls.

use faer::{Mat, Side};
use nalgebra::Vector3;
use rbc_schema::scene::Scene;
use rbc_solver::channel::stokes::ChannelSolution;
use rbc_solver::channel::{ChannelStats, ChannelStokes};
use std::path::Path;

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
[membrane]
reference = "discocyte"
[membrane.skalak]
convention = "krueger"
kappa_s_n_m = 5e-6
kappa_a_n_m = 5e-4
[membrane.bending]
kappa_b_n_m = 3e-19
[fluid]
viscosity_pa_s = 1.2e-3
lambda = {lambda:?}
[walls]
kind = "periodic-channel"
length_x_um = 42.7
width_y_um = 12.0
height_z_um = 10.0
mean_velocity_um_s = 1000.0
wall_edge_um = 2.0
ewald_tol = 1e-3
{walls}
[integrator]
scheme = "{scheme}"
atol_um = 3e-3
[time]
end_s = {end_s:e}
output_interval_s = {out_s:e}
"#
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
        stats: ChannelStats { viscosity_ratio: 1.0, ..sol.stats.clone() },
    };
    ch.flow_at(points, &dummy, &vec![Vector3::zeros(); nv], &sol).unwrap()
}

fn env(name: &str, default: f64) -> f64 {
    std::env::var(name).ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

/// Study: spectrum of the wall operator and the empty channel from `d = 0`.
/// `PEN_KW` (N/m^3, default 1.9e7), `PEN_END` (s).
#[test]
#[ignore]
fn study_empty_channel_relaxation() {
    let kw = env("PEN_KW", 1.9e7);
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
    }

    // The empty channel from d = 0, the real penalty solve, RK4 at h = 1.5 / rate_max.
    let points = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(10.0, 0.0, 0.0), Vector3::new(0.0, 3.0, 2.0)];
    let (u_ns, _) = ch.empty_channel_flow(&points, ch.mean_flow_mm_s).unwrap();
    let h = 1.5 / rate(lam[n - 1]);
    let end = env("PEN_END", 2e-3);
    let f = |d: &[Vector3<f64>]| ch.penalty_velocity(None, d, ch.mean_flow_mm_s).unwrap();
    let mut d = vec![Vector3::zeros(); nw];
    let mut t = 0.0;
    let mut next_out = 0.0;
    let area: f64 = ch.mesh.vertex_areas.iter().sum();
    eprintln!("no-slip centre line {:.3} um/s (at x = 10: {:.3}; at (0, 3, 2): {:.3}); RK4 step {h:.2e} s", u_ns[0].x, u_ns[1].x, u_ns[2].x);
    loop {
        if t >= next_out - 1e-15 || t >= end {
            let sol = f(&d);
            let cl = centre_line(ch, &sol, &points);
            let slip: f64 = sol.wall_velocity.iter().zip(&ch.mesh.vertex_areas).map(|(v, a)| v.x * a).sum::<f64>() / area;
            let slip_max = sol.wall_velocity.iter().map(|v| v.norm()).fold(0.0, f64::max);
            let dd = d.iter().zip(&d_star).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            eprintln!(
                "t {t:.3e} s: centre-line error {:+.3e}, (0,3,2) error {:+.3e}; mean wall slip {slip:+.3e} um/s, max |u_wall| {slip_max:.3e} um/s; max |d - d*| {dd:.3e} um, mean d_x {:.3e} um (d*_x {:.3e})",
                cl[0].x / u_ns[0].x - 1.0,
                cl[2].x / u_ns[2].x - 1.0,
                d.iter().zip(&ch.mesh.vertex_areas).map(|(v, a)| v.x * a).sum::<f64>() / area,
                d_star.iter().zip(&ch.mesh.vertex_areas).map(|(v, a)| v.x * a).sum::<f64>() / area,
            );
            next_out = if next_out == 0.0 { h } else { next_out * 2.0 };
            if t >= end {
                break;
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
