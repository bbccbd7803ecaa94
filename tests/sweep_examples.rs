//! The example sweeps: the paper's phase diagram expands into 330 valid scenes, and the quick
//! demo runs end to end with the real solver (a capsule on the axis of an unbounded Poiseuille
//! flow stops at its steady state, centred and mirror-symmetric, at the Faxen velocity of a
//! rigid sphere), and resumes without rerunning anything.

use rbc_schema::results::{read_runs, FinalShape, RunStatus};
use std::path::Path;
use std::process::Command;

fn examples() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/sweeps"))
}

/// Run from the checkout with the sweep given as a relative path (as the README does): the
/// croissant and slipper start meshes (`starts.h5` beside the sweep, `rbc-sweep start-shape`)
/// resolve against the sweep's folder once.
#[test]
fn paper_phase_diagram_expands_into_330_scenes() {
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["list", "examples/sweeps/paper-phase-diagram.toml"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    assert_eq!(text.lines().count(), 331);
    assert!(text.contains("\tdiscocyte_u0.13_r0\t") && text.contains("\tslipper_u10.4_r2.25\t"));
    // the discocyte's rim (8 um across the flow) reaches the 12 x 10 um channel's wall at the two
    // largest offsets: listed as overlaps-wall (22 runs), the rest to run. The croissant and the
    // slipper are narrower across the channel (the paper: "the different starting shapes admit a
    // larger initial radial position"): read from starts.h5 and checked, all of theirs fit
    let status = |id: &str| text.lines().find(|l| l.split('\t').nth(1) == Some(id)).unwrap().split('\t').nth(7).unwrap().to_string();
    assert_eq!(status("discocyte_u0.13_r1.75"), "to-run");
    assert_eq!(status("discocyte_u0.13_r2"), "overlaps-wall");
    assert_eq!(status("discocyte_u10.4_r2.25"), "overlaps-wall");
    assert_eq!((status("croissant_u10.4_r2.25"), status("slipper_u10.4_r2.25")), ("to-run".into(), "to-run".into()));
    assert_eq!(text.lines().filter(|l| l.contains("\toverlaps-wall\t")).count(), 22);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("22 of 330 runs overlap the channel wall") && !err.contains("not checked"), "{err}");
}

/// The shipped start shapes are the study's settled croissant and slipper at ~4 mm/s (mean flow
/// 2.4 mm/s), each the last snapshot of its run, labelled as such, with the paper's mesh.
#[test]
fn the_shipped_start_shapes_are_the_studys_settled_croissant_and_slipper() {
    let starts = examples().join("starts.h5");
    let state = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies/science-6p5/state");
    for (name, source, shape) in [("croissant-start", "discocyte_u2.4_r0.4", FinalShape::Croissant), ("slipper-start", "discocyte_u2.4_r1.2", FinalShape::Slipper)] {
        let run = read_runs(&starts).unwrap().into_iter().find(|r| r.run_id == name).unwrap_or_else(|| panic!("no {name}"));
        assert_eq!(run.summary.as_ref().map(|s| s.final_shape), Some(shape), "{name}");
        let from = rbc_schema::results::read_snapshots(&state.join(format!("{source}.h5")), source).unwrap();
        let copy = rbc_schema::results::read_snapshots(&starts, name).unwrap();
        assert_eq!((copy.times_s.as_slice(), copy.vertices_um.last(), copy.triangles.len()), (&from.times_s[from.times_s.len() - 1..], from.vertices_um.last(), 2048), "{name}");
        assert!(run.copied_from.as_deref().is_some_and(|c| c.starts_with(&format!("{source}.h5: run {source}"))), "{:?}", run.copied_from);
    }
}

/// The penalty-wall study is science-6p5's model but for the walls: its scene equals
/// science-6p5's with `wall_model = "penalty"` (the paper's kappa_W) up to the step method, its
/// steady-state and classification settings are science-6p5's, and it lists the ~2.5 mm/s column
/// (mean flow 1.5 mm/s) from r_init 0.8 um on and the ~6.5 mm/s column's r_init 1.2 and 0.4 um
/// (mean flow 3.8 mm/s), in the order they take the jobs (the slowly settling ~2.5 mm/s r_init
/// 1.2 um run after them, then the ~6.5 mm/s r_init 0.6 and 0.8 um runs of session 31), each run
/// fitting the channel and starting where science-6p5's did.
#[test]
fn the_penalty_wall_study_is_science_6p5_but_for_the_walls() {
    let studies = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies");
    let read = |name: &str| rbc_schema::scene::Scene::read(&studies.join(name).join("scene.toml")).unwrap();
    let (exact, penalty) = (read("science-6p5"), read("science-6p5-penalty"));
    match penalty.walls {
        rbc_schema::scene::WallsSpec::PeriodicChannel { wall_model, .. } => assert_eq!(wall_model, rbc_schema::scene::WallModel::Penalty { kappa_w_n_m3: 1.9e7 }),
        ref other => panic!("{other:?}"),
    }
    assert_eq!((penalty.integrator.atol_um, penalty.integrator.wall_atol_um), (2e-3, 1e-4));
    let as_exact = rbc_schema::scene::Scene::parse(
        &penalty.source.replace("wall_model = \"penalty\"", "wall_model = \"no-slip\"").replace("kappa_w_n_m3 = 1.9e7\n", "").replace("wall_atol_um = 1e-4\n", "").replace("name = \"science-6p5-penalty\"", "name = \"science-6p5\""),
        &studies.join("science-6p5/scene.toml"),
    )
    .unwrap();
    assert!(as_exact.same_but_stepping(&exact), "the model differs from science-6p5's beyond the walls");
    let settings = |name: &str| {
        let text = std::fs::read_to_string(studies.join(name).join("sweep.toml")).unwrap();
        text[text.find("[steady]").unwrap()..].lines().take_while(|l| !l.starts_with("[[also]]") && !l.starts_with("# Issue 12")).filter(|l| !l.starts_with('#') && !l.trim().is_empty()).map(str::to_string).collect::<Vec<_>>()
    };
    assert_eq!(settings("science-6p5-penalty"), settings("science-6p5"));
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).args(["list"]).arg(studies.join("science-6p5-penalty/sweep.toml")).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ids: Vec<String> = String::from_utf8(o.stdout).unwrap().lines().skip(1).map(|l| format!("{} {}", l.split('\t').nth(1).unwrap(), l.split('\t').nth(7).unwrap())).collect();
    assert_eq!(
        ids,
        ["discocyte_u1.5_r0.8 to-run", "discocyte_u1.5_r0.6 to-run", "discocyte_u1.5_r0.4 to-run", "discocyte_u3.8_r1.2 to-run", "discocyte_u3.8_r0.4 to-run", "discocyte_u1.5_r1.2 to-run", "discocyte_u3.8_r0.6 to-run", "discocyte_u3.8_r0.8 to-run", "discocyte_u3.8_r1 to-run", "discocyte_u2.4_r1.2 to-run", "discocyte_u2.4_r0.8 to-run", "discocyte_u0.63_r1.2 to-run", "discocyte_u0.63_r0.4 to-run", "discocyte_u2.4_r1 to-run", "discocyte_u0.63_r0.8 to-run", "discocyte_u1.9_r1.2 to-run", "discocyte_u1.25_r1.2 to-run", "discocyte_u0.31_r1.2 to-run", "discocyte_u0.63_r0.6 to-run", "discocyte_u2.4_r1.1 to-run", "discocyte_u2.15_r1.2 to-run", "discocyte_u0.31_r0.4 to-run", "discocyte_u0.16_r1.2 to-run", "discocyte_u0.31_r0.2 to-run", "discocyte_u0.23_r1.2 to-run", "discocyte_u0.2_r1.2 to-run", "discocyte_u6.1_r0.4 to-run", "discocyte_u6.1_r1.2 to-run", "croissant_u0.31_r0.2 to-run", "croissant_u0.31_r1.2 to-run", "croissant_u0.63_r1.2 to-run"]
    );
    // the runs its file `first` gives the jobs first (scripts/study.sh) are runs of it, each once
    let first = std::fs::read_to_string(studies.join("science-6p5-penalty/first")).unwrap();
    let first: Vec<&str> = first.lines().filter_map(|l| l.split('#').next().unwrap().split_whitespace().next()).collect();
    assert!(!first.is_empty() && first.iter().all(|r| ids.contains(&format!("{r} to-run"))), "{first:?}");
    assert!(first.iter().enumerate().all(|(i, r)| !first[..i].contains(r)), "{first:?}");
    // the ~6.5, ~4 and ~1 mm/s runs start where science-6p5's runs of the same name started
    let listed = |name: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).args(["list"]).arg(studies.join(name).join("sweep.toml")).output().unwrap();
        String::from_utf8(o.stdout).unwrap().lines().skip(1).map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            (f[1].to_string(), f[2..7].join(" "))
        }).collect::<std::collections::HashMap<_, _>>()
    };
    let (exact_runs, penalty_runs) = (listed("science-6p5"), listed("science-6p5-penalty"));
    for id in ["discocyte_u3.8_r1.2", "discocyte_u3.8_r0.4", "discocyte_u3.8_r0.6", "discocyte_u3.8_r0.8", "discocyte_u1.5_r0.8", "discocyte_u2.4_r1.2", "discocyte_u2.4_r0.8", "discocyte_u0.63_r1.2", "discocyte_u0.63_r0.4"] {
        assert_eq!(penalty_runs[id], exact_runs[id], "{id}");
    }
}

#[test]
fn demo_sweep_runs_with_the_solver_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo.h5");
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
            .arg(examples().join("demo-poiseuille.toml"))
            .arg("--out")
            .arg(&out)
            .args(["--jobs", "2"])
            .output()
            .unwrap()
    };
    let o = run();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    let runs = read_runs(&out).unwrap();
    assert_eq!(runs.len(), 4);
    for r in &runs {
        let s = r
            .summary
            .as_ref()
            .unwrap_or_else(|| panic!("{} not finished: {:?}", r.run_id, r.failure));
        if r.attrs.as_ref().unwrap().r_init_um == 0.0 {
            // on the axis: steady, centred, symmetric -> "croissant" by the classifier's definition;
            // a steady capsule moves as a rigid body: Faxen's law for a sphere of radius a in
            // u = umax (1 - r^2/R^2) gives U = umax (1 - 2 a^2 / (3 R^2)); level-2 mesh: 1 %
            assert_eq!(
                (s.status, s.final_shape, s.tank_treading),
                (RunStatus::Steady, FinalShape::Croissant, false),
                "{}",
                r.run_id
            );
            let umax = if r.run_id.contains("_u0.5_") {
                0.5
            } else {
                1.0
            };
            let faxen = umax * (1.0 - 2.0 * 2.5f64.powi(2) / (3.0 * 36.0));
            println!(
                "{}: U = {:.5} mm/s, Faxen {:.5} mm/s",
                r.run_id, s.mean_velocity_mm_s, faxen
            );
            assert!(
                (s.mean_velocity_mm_s / faxen - 1.0).abs() < 0.01,
                "{} vs {faxen}",
                s.mean_velocity_mm_s
            );
            assert!(
                s.evidence["steady_end_s"] < 0.2,
                "stopped before the maximal time"
            );
        }
    }
    let stale = differences_from_shipped(&out);
    assert!(
        stale.is_empty(),
        "examples/demo-results.h5 is stale (no longer what its sweep makes): {}; regenerate with `bash scripts/examples.sh demo`",
        stale.join("; ")
    );
    let o = run();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        o.status.success() && err.contains("4 of 4 runs already finished") && err.contains("0 to run") && err.contains("4 runs already in") && err.contains("0 done now"),
        "{err}"
    );
}

/// How far apart the shipped snapshots may be from a fresh sweep's, um. The demo integrates with
/// `atol_um = 1e-3`; the same code on the same machine makes the file bit for bit, but another
/// CPU (other SIMD kernels, another libm) rounds differently, which can flip an accepted step and
/// move the trajectory by a few times the tolerance. Ten times atol keeps that, and is ~60 x
/// below what a real change of the solver moved the shipped file by (0.57 um).
const SHIPPED_VERTEX_TOL_UM: f64 = 1e-2;

/// What differs between `examples/demo-results.h5` and the fresh demo sweep `made`: run ids, statuses,
/// shapes, snapshot times and counts exactly; mean velocities to 1e-3 (relative); snapshot
/// vertices to [`SHIPPED_VERTEX_TOL_UM`].
fn differences_from_shipped(made: &Path) -> Vec<String> {
    use rbc_schema::results::read_snapshots;
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/demo-results.h5");
    let (a, b) = (read_runs(&shipped).unwrap(), read_runs(made).unwrap());
    let ids = |r: &[rbc_schema::results::RunRecord]| r.iter().map(|r| r.run_id.clone()).collect::<Vec<_>>();
    if ids(&a) != ids(&b) {
        return vec![format!("runs {:?} shipped, {:?} made", ids(&a), ids(&b))];
    }
    let mut diffs = Vec::new();
    for (x, y) in a.iter().zip(&b) {
        let id = &x.run_id;
        let (sx, sy) = (x.summary.as_ref(), y.summary.as_ref());
        let key = |s: Option<&rbc_schema::results::RunSummary>| s.map(|s| (s.status, s.final_shape));
        if key(sx) != key(sy) {
            diffs.push(format!("{id}: status and shape {:?} shipped, {:?} made", key(sx), key(sy)));
            continue;
        }
        if let (Some(sx), Some(sy)) = (sx, sy) {
            if (sx.mean_velocity_mm_s / sy.mean_velocity_mm_s - 1.0).abs() > 1e-3 {
                diffs.push(format!("{id}: mean velocity {} mm/s shipped, {} made", sx.mean_velocity_mm_s, sy.mean_velocity_mm_s));
            }
        }
        let (px, py) = (read_snapshots(&shipped, id).unwrap(), read_snapshots(made, id).unwrap());
        if px.times_s != py.times_s || px.triangles != py.triangles {
            diffs.push(format!("{id}: snapshots at {} times shipped, {} made (or other times or triangles)", px.times_s.len(), py.times_s.len()));
            continue;
        }
        let worst = px
            .vertices_um
            .iter()
            .flatten()
            .zip(py.vertices_um.iter().flatten())
            .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max);
        if worst > SHIPPED_VERTEX_TOL_UM {
            diffs.push(format!("{id}: vertices differ by up to {worst:.3} um (tolerance {SHIPPED_VERTEX_TOL_UM} um)"));
        }
    }
    diffs
}
