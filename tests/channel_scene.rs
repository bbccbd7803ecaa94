//! The paper's periodic channel as a scene: a coarse red blood cell run end to end (moves downstream between the mean and the centre-line velocity, stays centred, keeps its volume), exact no-slip against penalty walls, and one-line errors for bad channel fields through `rbc-simulate`.

use nalgebra::Vector3;
use rbc_schema::scene::Scene;
use rbc_solver::membrane::MembraneLaw;
use rbc_solver::run::Recorder;
use std::path::Path;
use std::process::Command;

/// A coarse version of the paper's scene (examples/sweeps/paper-channel.toml): discocyte of
/// 128 triangles, wall edge 2 um (1008 wall triangles), Ewald tolerance 1e-3, lambda = 1,
/// mean flow 1 mm/s, centred, 0.2 ms.
static CHANNEL: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    format!(
        r#"
name = "coarse-channel"
[cell]
shape = "discocyte"
level = 2
position_um = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
{}wall_edge_um = 2.0
ewald_tol = 1e-3
[integrator]
scheme = "ros2"
atol_um = 3e-3
[time]
end_s = 2e-4
output_interval_s = 1e-4
"#,
        rbc_schema::paper_scene::channel_blocks(1.0, 1000.0)
    )
});

const MEAN_MM_S: f64 = 1.0;

fn run(text: &str) -> (Recorder, rbc_solver::scene::Built, rbc_solver::run::RunSummary) {
    let scene = Scene::parse(text, Path::new("channel.toml")).unwrap();
    let built = rbc_solver::scene::build(&scene).unwrap();
    let mut rec = Recorder::default();
    let t0 = std::time::Instant::now();
    let (summary, x) = built.run(&mut rec).unwrap();
    eprintln!("{:?}\n{summary:?} ({:.1} s)", built.assembled, t0.elapsed().as_secs_f64());
    assert_eq!(x.len(), built.mesh.vertices.len(), "the final state is the cell's vertices only");
    assert_eq!(rec.vertices.last().unwrap(), &x);
    (rec, built, summary)
}

/// Centroid velocity (mm/s) between samples `a` and `b`.
fn velocity(rec: &Recorder, a: usize, b: usize) -> Vector3<f64> {
    (rec.centroid_um[b] - rec.centroid_um[a]) / (rec.times_s[b] - rec.times_s[a]) * 1e-3
}

/// A centred cell in the channel with exact no-slip walls moves along +x faster than the mean
/// flow (it sits where the flow is fastest) and slower than the centre-line velocity of the
/// empty duct at the same flux (it blocks part of the cross-section and averages the profile);
/// by the mirror symmetries y -> -y and z -> -z of channel and cell it stays centred (up to the
/// asymmetry of the wall mesh and of the Ewald grid); the volume correction keeps its volume
/// to the rescaling threshold 1e-9.
#[test]
fn centred_cell_moves_downstream_between_mean_and_centre_line_velocity() {
    let (rec, built, summary) = run(&CHANNEL);
    assert!(built.assembled.iter().any(|l| l.contains("exact no-slip")), "{:?}", built.assembled);
    assert!(!built.assembled.iter().any(|l| l.contains("double layer")), "lambda = 1 needs no double layer");
    assert!(!built.assembled.iter().any(|l| l.contains("background flow")), "the channel has no free-space background flow");
    let ch = built.channel().expect("a channel");
    let (u, _) = ch.empty_channel_flow(&[Vector3::new(10.0, 0.0, 0.0)], MEAN_MM_S).unwrap();
    let centre_line = u[0].x * 1e-3;
    let n = rec.times_s.len();
    assert_eq!(n, 3, "t = 0, 0.1, 0.2 ms");
    let v = velocity(&rec, 0, n - 1);
    // the instantaneous centroid velocity of the solve at the last state (the paper's u,
    // `cell_mean_velocity_mm_s`) agrees with the backward difference over the last output
    // interval that the time series stores (the cell accelerates by < 1 % per 0.1 ms here)
    let last = rbc_solver::Mesh { vertices: rec.vertices[n - 1].clone(), triangles: built.mesh.triangles.clone() };
    let f = built.membrane.force_density(&last);
    let (u_last, _) = ch.velocity(&last, &f, MEAN_MM_S).unwrap();
    let u_inst = rbc_solver::channel::stokes::cell_mean_velocity_mm_s(&last, &u_last);
    let v_last = velocity(&rec, n - 2, n - 1).x;
    eprintln!("instantaneous {u_inst:.5} mm/s, backward difference {v_last:.5} mm/s");
    // (measured 1.4 %: the difference averages over 0.1 ms while the shape still relaxes, and the
    // positions carry the tolerance 3e-3 um per step, ~20 steps for a displacement of 0.15 um)
    assert!((u_inst - v_last).abs() < 0.03 * v_last, "{u_inst} vs {v_last}");
    eprintln!("cell velocity {v} mm/s (mean flow {MEAN_MM_S}, centre line {centre_line:.4} mm/s); {} steps", summary.accepted);
    assert!(v.x > 1.1 * MEAN_MM_S && v.x < 0.9 * centre_line, "{} not in ({MEAN_MM_S}, {centre_line})", v.x);
    for c in &rec.centroid_um {
        assert!(c.y.abs() < 1e-2 && c.z.abs() < 1e-2, "left the axis: {c}");
    }
    for vol in &rec.volume_um3 {
        assert!((vol / rec.volume_um3[0] - 1.0).abs() < 1e-8, "volume {vol} vs {}", rec.volume_um3[0]);
    }
}

/// The penalty walls start from the displacement that carries the exact no-slip traction of the
/// initial configuration: there the penalty solve must reproduce the no-slip solve exactly (same
/// operators; the difference is the LU solve's round-off) and the wall vertices must not move.
#[test]
fn penalty_walls_at_the_no_slip_traction_reproduce_the_no_slip_solve() {
    use rbc_solver::integrate::Dynamics;
    let scene = Scene::parse(&penalty(1.9e7), Path::new("channel.toml")).unwrap();
    let built = rbc_solver::scene::build(&scene).unwrap();
    let ch = built.channel().unwrap();
    let nc = built.mesh.vertices.len();
    let mut dynamics = rbc_solver::dynamics::penalty::PenaltyChannelDynamics::new(built.mesh.triangles.clone(), nc, &built.membrane, ch).unwrap();
    let x0 = dynamics.initial_state(&built.mesh.vertices).unwrap();
    assert_eq!(x0.len(), nc + ch.mesh.n_vertices());
    let mut u = vec![Vector3::zeros(); x0.len()];
    dynamics.velocity(0.0, &x0, &mut u).unwrap();
    let f = built.membrane.force_density(&built.mesh);
    let (exact, _) = ch.velocity(&built.mesh, &f, MEAN_MM_S).unwrap();
    let scale = exact.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let cell_diff = u[..nc].iter().zip(&exact).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max) / scale;
    let wall = u[nc..].iter().map(|v| v.norm()).fold(0.0, f64::max) / scale;
    let d_max = rbc_solver::dynamics::penalty::max_wall_displacement(&x0, nc);
    eprintln!("cell velocity difference {cell_diff:.2e}, wall velocity {wall:.2e} of max |u| = {scale:.1} um/s; max wall displacement {d_max:.4} um");
    assert!(cell_diff < 1e-9 && wall < 1e-9, "{cell_diff} {wall}");
    // the springs carry the traction (measured 1.29 um at the cell: the coarse discocyte's
    // bending forces drive membrane velocities of ~10 mm/s at t = 0)
    assert!(d_max > 0.0 && d_max.is_finite(), "{d_max}");
}

fn penalty(kappa_w_n_m3: f64) -> String {
    CHANNEL.replace("wall_edge_um = 2.0", &format!("wall_edge_um = 2.0\nwall_model = \"penalty\"\nkappa_w_n_m3 = {kappa_w_n_m3:e}"))
}

/// The paper's penalty walls (kappa_W = 1.9e7 N/m^3) against exact no-slip walls, both started
/// from the same state: the penalty walls lag the moving and relaxing cell,
/// `u_wall = -(1/kappa_W) df_w/dt`, and the error vanishes as kappa_W grows. Measured over the
/// first 0.2 ms at 1 mm/s (128-triangle cell, 1008 wall triangles, membrane velocities up to
/// 10 mm/s while the coarse discocyte relaxes): mean cell velocity +0.38 % at kappa_W = 1.9e7,
/// +0.02 % at 1.9e8 (measured in session 3; session 2 recorded -13.3 % / +0.6 % with code that
/// has changed since, not reproduced). The walls need ~1.4 ms (1.9e7) to reach their own steady
/// state: the longer study is `solver/tests/penalty_walls.rs`. ~2.5 minutes on a loaded 2-core
/// machine: `cargo test --test channel_scene -- --ignored penalty_walls_approach`.
#[test]
#[ignore]
fn penalty_walls_approach_the_no_slip_cell_velocity() {
    let (exact, _, _) = run(&CHANNEL);
    let n = exact.times_s.len();
    let ve = velocity(&exact, 0, n - 1);
    let mut diffs = Vec::new();
    for kappa in [1.9e7, 1.9e8] {
        let (pen, built, summary) = run(&penalty(kappa));
        assert!(built.assembled.iter().any(|l| l.contains("penalty springs")), "{:?}", built.assembled);
        assert_eq!(pen.times_s, exact.times_s);
        let vp = velocity(&pen, 0, n - 1);
        let rel = (vp.x - ve.x) / ve.x;
        eprintln!("kappa_W {kappa:e}: no-slip {:.5} mm/s, penalty {:.5} mm/s: relative difference {rel:.2e}; steps {} (h in [{:.2e}, {:.2e}] s)", ve.x, vp.x, summary.accepted, summary.h_min_s, summary.h_max_s);
        for vol in &pen.volume_um3 {
            assert!((vol / pen.volume_um3[0] - 1.0).abs() < 1e-8);
        }
        diffs.push(rel);
    }
    assert!(diffs[1].abs() < 0.02 && diffs[1].abs() < 0.2 * diffs[0].abs(), "{diffs:?}");
}

fn simulate(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rbc-simulate")).args(args).current_dir(dir).output().expect("run rbc-simulate")
}

/// Bad channel fields: exit code 2, one line naming the file and the field, no output file.
#[test]
fn bad_channel_fields_give_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (CHANNEL.replace("wall_edge_um = 2.0", "wall_edge_um = 2.0\nwall_model = \"penalty\""), "walls.kappa_w_n_m3"),
        (CHANNEL.replace("wall_edge_um = 2.0", "wall_edge_um = 2.0\nwall_model = \"springs\""), "walls.wall_model"),
        (CHANNEL.replace("wall_edge_um = 2.0", "wall_edge_um = 2.0\nkappa_w_n_m3 = 1.9e7"), "walls.kappa_w_n_m3"),
        (CHANNEL.replace("wall_edge_um = 2.0", "wall_edge_um = 4.0"), "walls.wall_edge_um"),
        // walls too fine for the memory: refused before any allocation (was an abort)
        (CHANNEL.replace("wall_edge_um = 2.0", "wall_edge_um = 0.3"), "walls.wall_edge_um"),
        (CHANNEL.replace("wall_edge_um = 2.0", "wall_edge_um = 0.001"), "walls.wall_edge_um"),
        (CHANNEL.replace("ewald_tol = 1e-3", "ewald_tol = 0.0"), "walls.ewald_tol"),
        (CHANNEL.replace("mean_velocity_um_s = 1000.0\n", ""), "walls.mean_velocity_um_s"),
        (CHANNEL.replace("[walls]", "[flow]\nkind = \"shear\"\nshear_rate_1_s = 10.0\n[walls]"), "flow.kind"),
    ];
    for (text, field) in cases {
        std::fs::write(dir.path().join("bad.toml"), &text).unwrap();
        let out = simulate(&["bad.toml", "--out", "res.h5"], dir.path());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{field}: {err}");
        assert!(err.contains("bad.toml") && err.contains(field), "{field}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!dir.path().join("res.h5").exists());
    }
}

/// The wall operator's memory estimate is checked against `RBC_MAX_MEMORY_GB` when it is set
/// (the override of this machine's memory): the test channel's walls (~0.04 GB) are refused
/// under a limit of 1e-4 GB with one line naming the field, the estimate and the override, and
/// nothing is written.
#[test]
fn memory_limit_override_refuses_a_scene_that_needs_more() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("ch.toml"), CHANNEL.as_str()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_rbc-simulate"))
        .args(["ch.toml", "--out", "res.h5"])
        .env("RBC_MAX_MEMORY_GB", "1e-4")
        .current_dir(dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("ch.toml") && err.contains("walls.wall_edge_um") && err.contains("GB") && err.contains("(RBC_MAX_MEMORY_GB;"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!dir.path().join("res.h5").exists());
}

/// A viscosity ratio the channel solve cannot do is refused by the builder as one line naming
/// `fluid.lambda` (exit 2, before any output); once the channel supports it (branch `chanlam`),
/// the builder lists the periodic double layer instead.
#[test]
fn viscosity_ratio_is_refused_cleanly_or_assembled() {
    let dir = tempfile::tempdir().unwrap();
    let text = CHANNEL.replace("lambda = 1.0", "lambda = 5.0");
    let scene = Scene::parse(&text, Path::new("lam.toml")).unwrap();
    match rbc_solver::scene::build(&scene) {
        Ok(built) => assert!(built.assembled.iter().any(|l| l.contains("double layer")), "{:?}", built.assembled),
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.contains("fluid.lambda") && !msg.contains('\n'), "{msg}");
            std::fs::write(dir.path().join("lam.toml"), &text).unwrap();
            let out = simulate(&["lam.toml", "--out", "res.h5"], dir.path());
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{err}");
            assert!(err.contains("lam.toml") && err.contains("fluid.lambda"), "{err}");
            assert_eq!(err.trim().lines().count(), 1, "{err}");
            assert!(!dir.path().join("res.h5").exists());
        }
    }
}

/// A cell placed across the wall is refused when the scene is read (it used to pass, build the
/// operators and fail its first solve, appending a failed run): exit 2, one line naming the file,
/// `cell.position_um`, the channel's width and height and how far the cell reaches into the wall,
/// and nothing written. A cell closer to the wall than the solve's 0.1 um gap is refused alike.
#[test]
fn cell_across_the_wall_is_refused_when_the_scene_is_read() {
    let dir = tempfile::tempdir().unwrap();
    for (position, says) in [("[0.0, 3.0, 2.0]", "reaches 1.00 um into the wall"), ("[0.0, 0.0, 0.95]", "comes within 0.050 um of the wall")] {
        std::fs::write(dir.path().join("wall.toml"), CHANNEL.replace("position_um = [0.0, 0.0, 0.0]", &format!("position_um = {position}"))).unwrap();
        let out = simulate(&["wall.toml", "--out", "res.h5"], dir.path());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        for part in ["wall.toml", "field `cell.position_um`", says, "12 x 10 um channel (walls.width_y_um x walls.height_z_um)"] {
            assert!(err.contains(part), "{part}: {err}");
        }
        assert!(!dir.path().join("res.h5").exists(), "nothing written");
    }
}

/// A channel sweep with one offset that puts the cell into the wall: `list` shows that run as
/// `overlaps-wall` with the overlap, `run` records it so (not failed, exit 0) and runs the other
/// with the solver, and `status` shows both.
#[test]
fn sweep_marks_the_run_that_overlaps_the_wall_and_runs_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("base.toml"), CHANNEL.as_str()).unwrap();
    std::fs::write(d.join("sweep.toml"), "base_scene = \"base.toml\"\nmean_velocity_mm_s = [1.0]\nr_init_um = [0.0, 2.5]\nstart_shapes = [\"discocyte\"]\n").unwrap();
    let sweep = |args: &[&str]| Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).args(args).current_dir(d).output().unwrap();
    let o = sweep(&["list", "sweep.toml"]);
    let (listed, err) = (String::from_utf8_lossy(&o.stdout).to_string(), String::from_utf8_lossy(&o.stderr).to_string());
    assert!(o.status.success(), "{err}");
    let lines: Vec<&str> = listed.lines().collect();
    assert!(lines[0].ends_with("\tstatus\tnote"), "{listed}");
    assert!(lines[1].starts_with("0\tdiscocyte_u1_r0\t") && lines[1].ends_with("\tto-run\t"), "{listed}");
    assert!(lines[2].starts_with("1\tdiscocyte_u1_r2.5\t") && lines[2].contains("\toverlaps-wall\tr_init_um = 2.5: the cell reaches "), "{listed}");
    assert!(err.contains("1 of 2 runs overlap the channel wall and are not run"), "{err}");

    let o = sweep(&["run", "sweep.toml", "--out", "res.h5", "--jobs", "1"]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    let runs = rbc_schema::results::read_runs(&d.join("res.h5")).unwrap();
    let status = |id: &str| runs.iter().find(|r| r.run_id == id).unwrap().status;
    assert_eq!(status("discocyte_u1_r2.5"), rbc_schema::results::RunStatus::OverlapsWall);
    assert!(status("discocyte_u1_r0").is_finished(), "{err}");
    let o = sweep(&["status", "res.h5"]);
    let table = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(table.lines().any(|l| l.contains("discocyte_u1_r2.5") && l.contains("overlaps-wall")), "{table}");
}

/// The channel sweeps of the examples (the 10 ms channel demo, the science
/// study at ~6.5 mm/s) expand into valid channel scenes at lambda = 5 (their runs take minutes
/// and days: the commands are in the sweep files' headers).
#[test]
fn demo_channel_sweep_expands_into_channel_scenes() {
    let sweeps = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/sweeps"));
    for (file, n) in [("demo-channel.toml", 6), ("science-6p5.toml", 2)] {
    let sweep = rbc_schema::sweep::Sweep::read(&sweeps.join(file)).unwrap();
    let runs = sweep.runs().unwrap();
    assert_eq!(runs.len(), n, "{file}");
    for r in &runs {
        let scene = Scene::parse(&r.scene_text, &sweep.base_scene).unwrap();
        assert_eq!(scene.fluid.lambda, 5.0);
        match scene.walls {
            rbc_schema::scene::WallsSpec::PeriodicChannel { mean_velocity_um_s, .. } => assert_eq!(mean_velocity_um_s, 1000.0 * r.velocity_mm_s),
            other => panic!("{other:?}"),
        }
        assert_eq!(scene.cell.position_um, [0.0, r.y_init_um, r.z_init_um]);
        // the integrator and tolerance of rbc-bench channel-tol's recommendation
        assert_eq!((scene.integrator.scheme, scene.integrator.atol_um), (rbc_schema::scene::Scheme::Ros34pw2Local, 1e-3), "{file}");
    }
    }
    let paper = rbc_schema::sweep::Sweep::read(&sweeps.join("paper-phase-diagram.toml")).unwrap();
    let first = &paper.runs().unwrap()[0];
    assert!(matches!(Scene::parse(&first.scene_text, &paper.base_scene).unwrap().walls, rbc_schema::scene::WallsSpec::PeriodicChannel { .. }));
}

/// With penalty walls the mobility W-method keeps the cell's dense factor over up to 3 steps
/// while the cell is quiet (`rbc_solver::integrate::ros34pw2::Reuse::PENALTY_WALLS`,
/// `solver/README.md` "Session 33"), which it decides from the cell's own error norm of the last
/// accepted step; the run's end checkpoint (`rbc-simulate`) carries that norm with penalty walls,
/// and not with exact walls, where a factor serves one step whatever the cell's error. The norm
/// is of the cell's vertices only: finite and below the step's acceptance (<= 1).
#[test]
fn with_penalty_walls_the_checkpoint_carries_the_cells_error_norm() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text, penalty) in [("exact", CHANNEL.clone(), false), ("penalty", penalty(1.9e7), true)] {
        let file = format!("{name}.toml");
        std::fs::write(dir.path().join(&file), text.replace("scheme = \"ros2\"", "scheme = \"ros34pw2-mobility\"")).unwrap();
        let out = simulate(&[&file, "--out", &format!("{name}.h5")], dir.path());
        assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        let ck = dir.path().join(format!("{name}.h5.coarse-channel.ckpt"));
        let fields = rbc_schema::checkpoint::read(&ck).unwrap().fields;
        let norm: Vec<&Vec<f64>> = fields.iter().filter(|(k, _)| k.ends_with("cell_error")).map(|(_, v)| v).collect();
        if penalty {
            assert!(norm.len() == 1 && norm[0].len() == 1 && (0.0..=1.0).contains(&norm[0][0]), "{name}: {norm:?} in {:?}", fields.keys().collect::<Vec<_>>());
        } else {
            assert!(norm.is_empty(), "{name}: {norm:?}");
        }
    }
}
