//! `rbc-sweep`'s subcommands (`run`, `list`, `task`, `slurm`, `merge`, `figures`, `trajectories`,
//! `xdmf`, `status`) give what the old flag spelling gives on the same input: the same results
//! (bit for bit except provenance, `scripts/results_equal.py`), byte-identical files and the same
//! stdout; an unknown subcommand or a missing argument is one line on stderr and exit code 2.
//! The runs are a tiny real sweep: two capsules in Poiseuille flow for 3 ms (a tenth of a second).

mod output_common;

use std::path::Path;
use std::process::{Command, Output};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn sweep_cmd(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rbc-sweep")).args(args).current_dir(cwd).output().unwrap()
}

/// Run and require success; returns stdout.
fn ok(args: &[&str], cwd: &Path) -> String {
    let o = sweep_cmd(args, cwd);
    assert!(o.status.success(), "rbc-sweep {args:?}: {}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).unwrap()
}

/// The demo sweep cut to 1 velocity x 2 offsets, 3 ms, a snapshot at every sample.
fn tiny_sweep(dir: &Path) {
    let ex = root().join("examples/sweeps");
    std::fs::copy(ex.join("demo-capsule.toml"), dir.join("demo-capsule.toml")).unwrap();
    let text = std::fs::read_to_string(ex.join("demo-poiseuille.toml")).unwrap();
    let edits = [
        ("mean_velocity_mm_s = [0.5, 1.0]", "mean_velocity_mm_s = [1.0]"),
        ("window_s = 0.05", "window_s = 0.002"),
        ("max_time_s = 0.2", "max_time_s = 0.003"),
        ("snapshot_every = 20", "snapshot_every = 1"),
    ];
    let text = edits.iter().fold(text, |t, (a, b)| {
        assert!(t.contains(a), "demo-poiseuille.toml no longer has `{a}`");
        t.replace(a, b)
    });
    std::fs::write(dir.join("sweep.toml"), text).unwrap();
}

/// `scripts/results_equal.py A B`: every dataset and attribute bit for bit, except provenance.
fn results_equal(a: &Path, b: &Path) {
    let o = Command::new("python3").arg(root().join("scripts/results_equal.py")).arg(a).arg(b).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{} vs {}: {text}{}", a.display(), b.display(), String::from_utf8_lossy(&o.stderr));
}

/// Two folders hold the same files, byte for byte, and at least `min` of them.
fn same_files(a: &Path, b: &Path, min: usize) {
    let (fa, fb) = (output_common::files_in(a), output_common::files_in(b));
    assert!(fa.len() >= min, "{}: {:?}", a.display(), fa.keys().collect::<Vec<_>>());
    assert_eq!(fa.keys().collect::<Vec<_>>(), fb.keys().collect::<Vec<_>>());
    for (name, bytes) in &fa {
        assert!(bytes == &fb[name], "{} differs", name.display());
    }
}

#[test]
fn every_subcommand_matches_its_old_spelling() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    tiny_sweep(d);

    // list: the same table
    let listed = ok(&["list", "sweep.toml"], d);
    assert_eq!(listed, ok(&["sweep.toml", "--list"], d));
    assert_eq!(listed.lines().count(), 3, "{listed}");

    // run: the same results (the real solver, 2 runs)
    ok(&["sweep.toml", "--out", "old.h5", "--jobs", "2"], d);
    ok(&["run", "sweep.toml", "--out", "new.h5", "--jobs", "2"], d);
    results_equal(&d.join("old.h5"), &d.join("new.h5"));
    let runs = rbc_schema::results::read_runs(&d.join("new.h5")).unwrap();
    assert_eq!(runs.len(), 2);

    // task: the same run into its part
    ok(&["sweep.toml", "--task", "1", "--out", "t_old.h5"], d);
    ok(&["task", "sweep.toml", "1", "--out", "t_new.h5"], d);
    results_equal(&d.join("t_old.h5"), &d.join("t_new.h5"));
    ok(&["task", "sweep.toml", "0", "--out", "t0.h5"], d);

    // merge: byte-identical merged files
    ok(&["--merge", "t0.h5", "t_old.h5", "--out", "m_old.h5"], d);
    ok(&["merge", "t0.h5", "t_old.h5", "--out", "m_new.h5"], d);
    assert!(std::fs::read(d.join("m_old.h5")).unwrap() == std::fs::read(d.join("m_new.h5")).unwrap());
    results_equal(&d.join("m_new.h5"), &d.join("new.h5"));

    // slurm: the same four files (they name their folder, so both spellings write the same one)
    ok(&["sweep.toml", "--slurm", "cluster"], d);
    let old = output_common::files_in(&d.join("cluster"));
    std::fs::remove_dir_all(d.join("cluster")).unwrap();
    let o = sweep_cmd(&["slurm", "sweep.toml", "cluster"], d);
    assert!(o.status.success() && String::from_utf8_lossy(&o.stderr).contains("submit with") && String::from_utf8_lossy(&o.stderr).trim_end().ends_with("cluster/submit.sh"), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(old.len(), 4);
    assert_eq!(old, output_common::files_in(&d.join("cluster")));

    // figures (of the shipped demo results: steady runs) and trajectories: byte-identical PNG, SVG
    std::fs::copy(root().join("examples/demo-results.h5"), d.join("demo.h5")).unwrap();
    ok(&["--figures", "demo.h5", "--out", "f_old"], d);
    ok(&["figures", "demo.h5", "--out", "f_new"], d);
    same_files(&d.join("f_old"), &d.join("f_new"), 2);
    ok(&["--trajectories", "old.h5", "new.h5", "--out", "tr_old"], d);
    ok(&["trajectories", "old.h5", "new.h5", "--out", "tr_new"], d);
    same_files(&d.join("tr_old"), &d.join("tr_new"), 2);

    // xdmf: the same .xmf files beside the results file
    for (dir, args) in [("x_old", vec!["--xdmf", "x_old/r.h5"]), ("x_new", vec!["xdmf", "x_new/r.h5"])] {
        std::fs::create_dir(d.join(dir)).unwrap();
        std::fs::copy(d.join("new.h5"), d.join(dir).join("r.h5")).unwrap();
        ok(&args, d);
    }
    std::fs::remove_file(d.join("x_old/r.h5")).unwrap();
    std::fs::remove_file(d.join("x_new/r.h5")).unwrap();
    same_files(&d.join("x_old"), &d.join("x_new"), 2);

    // status: the same table, the same single run, the same fields
    let table = ok(&["status", "old.h5", "new.h5", "--sweep", "sweep.toml"], d);
    assert_eq!(table, ok(&["sweep.toml", "--study-status", "old.h5", "new.h5"], d));
    assert_eq!(table.lines().count(), 2 + 4, "{table}");
    let id = &runs[0].run_id;
    assert_eq!(ok(&["status", "new.h5", "--run", id], d), ok(&["--study-status", "new.h5", "--run", id], d));
    let fields = ok(&["status", "new.h5", "--run", id, "--field", "status,t_s"], d);
    assert_eq!(fields, ok(&["--study-status", "new.h5", "--run", id, "--field", "status,t_s"], d));
    assert_eq!(fields, "unsteady 3e-3\n");
}

/// One line on stderr, nothing on stdout, exit code 2.
fn refused(args: &[&str], cwd: &Path, says: &str) {
    let o = sweep_cmd(args, cwd);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(o.stdout.is_empty() && err.lines().count() == 1 && err.starts_with("rbc-sweep: ") && err.contains(says), "{args:?}: {err}");
}

#[test]
fn unknown_subcommands_and_missing_arguments_are_one_line_and_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    refused(&["frobnicate", "x.h5"], d, "unknown subcommand `frobnicate`");
    refused(&[], d, "missing a subcommand");
    refused(&["run"], d, "<SWEEP>");
    refused(&["slurm", "sweep.toml"], d, "<DIR>");
    refused(&["task", "sweep.toml", "--out", "a.h5"], d, "<INDEX>");
    refused(&["task", "sweep.toml", "two", "--out", "a.h5"], d, "'two'");
    refused(&["merge", "a.h5", "b.h5"], d, "--out");
    refused(&["merge", "--out", "m.h5"], d, "<PARTS>");
    refused(&["figures"], d, "<RESULTS>");
    refused(&["trajectories", "--out", "t"], d, "<FILES>");
    refused(&["status", "a.h5", "--field", "t_s"], d, "--run");
    refused(&["run", "sweep.toml", "--bogus"], d, "--bogus");
    // the old spelling's refusals stay
    refused(&["--merge", "a.h5"], d, "--merge needs --out FILE");
    refused(&["--bogus"], d, "--bogus");
    // a missing sweep file is named
    refused(&["list", "absent.toml"], d, "absent.toml");
    // a pool of no workers
    refused(&["run", "sweep.toml", "--jobs", "0"], d, "--jobs 0");
    assert!(!d.join("m.h5").exists() && std::fs::read_dir(d).unwrap().next().is_none(), "nothing written");
}

#[test]
fn each_subcommand_has_its_own_help() {
    let tmp = tempfile::tempdir().unwrap();
    let top = ok(&["--help"], tmp.path());
    assert!(top.contains("The old flag spelling still works"), "{top}");
    for (cmd, usage) in [
        ("run", "rbc-sweep run [OPTIONS] <SWEEP>"),
        ("list", "rbc-sweep list <SWEEP>"),
        ("task", "rbc-sweep task --out <OUT> <SWEEP> <INDEX>"),
        ("slurm", "rbc-sweep slurm <SWEEP> <DIR>"),
        ("merge", "rbc-sweep merge --out <OUT> <PARTS>..."),
        ("start-shape", "rbc-sweep start-shape --as <NAME> --out <OUT> <RESULTS> <RUN>"),
        ("figures", "rbc-sweep figures [OPTIONS] <RESULTS>"),
        ("trajectories", "rbc-sweep trajectories [OPTIONS] <FILES>..."),
        ("xdmf", "rbc-sweep xdmf [OPTIONS] <RESULTS>"),
        ("status", "rbc-sweep status [OPTIONS] <FILES>..."),
        ("events", "rbc-sweep events [OPTIONS] <FILES>..."),
    ] {
        let text = ok(&[cmd, "--help"], tmp.path());
        assert!(text.contains(&format!("Usage: {usage}")), "{cmd}: {text}");
        assert_eq!(text, ok(&["help", cmd], tmp.path()));
        // the commands that build channel scenes name the memory override (issue 14)
        if matches!(cmd, "run" | "task") {
            assert!(text.contains("RBC_MAX_MEMORY_GB") && text.contains("walls.wall_edge_um"), "{cmd}: {text}");
        }
    }
    assert!(top.contains("RBC_MAX_MEMORY_GB"), "{top}");
    let simulate = std::process::Command::new(env!("CARGO_BIN_EXE_rbc-simulate")).arg("--help").output().unwrap();
    let text = String::from_utf8_lossy(&simulate.stdout);
    assert!(simulate.status.success() && text.contains("RBC_MAX_MEMORY_GB") && text.contains("MemTotal"), "{text}");
}

/// `status` on a results file cut in half (an interrupted copy) or missing says so, naming the
/// file, instead of "no run and no checkpoint".
#[test]
fn status_names_a_cut_short_or_missing_results_file() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let bytes = std::fs::read(root().join("examples/demo-results.h5")).unwrap();
    std::fs::write(d.join("half.h5"), &bytes[..bytes.len() / 2]).unwrap();
    for (file, says) in [("half.h5", "cut short"), ("absent.h5", "absent.h5")] {
        let o = sweep_cmd(&["status", file], d);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && o.stdout.is_empty(), "{file}: {err}");
        assert!(err.lines().count() == 1 && err.contains(file) && err.contains(says) && !err.contains("no run and no checkpoint"), "{file}: {err}");
    }
}

/// `status --sweep` gives a run's periodic gap whether or not the sweep file sets
/// `steady.max_time_s` (the end does not enter the gap), and the orbit drift over that period: the paper's-walls study's ~0.37 mm/s
/// run, folding every ~0.89 s, with the study's sweep file and with the same file without it.
#[test]
fn status_gives_the_periodic_gap_without_a_max_time_in_the_sweep() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let study = root().join("examples/studies/science-6p5-penalty");
    let run = "discocyte_u0.23_r1.2";
    for f in [format!("{run}.h5"), format!("{run}.h5.{run}.ckpt")] {
        std::fs::copy(study.join("state").join(&f), d.join(&f)).unwrap();
    }
    for f in ["scene.toml", "starts.h5"] {
        std::fs::copy(study.join(f), d.join(f)).unwrap();
    }
    let text = std::fs::read_to_string(study.join("sweep.toml")).unwrap();
    assert!(text.contains("\nmax_time_s = 30.0\n"), "the study's sweep sets max_time_s");
    std::fs::write(d.join("with.toml"), &text).unwrap();
    std::fs::write(d.join("without.toml"), text.replace("\nmax_time_s = 30.0\n", "\n")).unwrap();
    let gap = |sweep: &str| {
        let out = ok(&["status", &format!("{run}.h5"), "--sweep", sweep, "--run", run, "--field", "periodic_gap,orbit_drift_um_s"], d);
        out.trim().to_string()
    };
    let (with, without) = (gap("with.toml"), gap("without.toml"));
    assert!(!with.starts_with('-') && !with.is_empty(), "the study's run has a periodic gap: {with:?}");
    assert_eq!(without, with);
}

/// `status` on a running run whose checkpoint holds a state its run could not continue from (a
/// vertex that is not finite: `rbc-simulate --resume` refuses it) is one line naming the
/// checkpoint and the field, not a row of NaN; the same run with its checkpoint as saved reads.
#[test]
fn status_refuses_a_checkpoint_its_run_could_not_continue_from() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let (run, state) = ("discocyte_u0.31_r0.2", root().join("examples/studies/science-6p5-penalty/state"));
    let (h5, ck) = (format!("{run}.h5"), format!("{run}.h5.{run}.ckpt"));
    std::fs::copy(state.join(&h5), d.join(&h5)).unwrap();
    std::fs::copy(state.join(&ck), d.join(&ck)).unwrap();
    let table = ok(&["status", &h5], d);
    assert!(table.contains(&format!("| {run} | running |")) && !table.contains("NaN"), "{table}");
    let mut c = rbc_schema::checkpoint::read(&d.join(&ck)).unwrap();
    c.fields.get_mut("runner.vertices_um").expect("the state's vertices")[4] = f64::NAN;
    rbc_schema::checkpoint::write(&d.join(&ck), &c).unwrap();
    let o = sweep_cmd(&["status", &h5], d);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && o.stdout.is_empty(), "{err}");
    assert!(err.lines().count() == 1 && err.contains(&ck) && err.contains("runner.vertices_um") && err.contains("vertex 1"), "{err}");
}

/// `events`: the study's ~0.32 mm/s run (its committed state) as CSV: a header and one row per
/// collapse of its length along the flow, its overturn (broadside, `across` ~1) then its folds
/// (`across` <= 0.83), the intervals between them; the exact-wall study's ~1 mm/s slipper (it
/// tank-treads: its swings stay above the threshold) has none. Bad input is one line and exit 2,
/// naming the fraction, the run or the file.
#[test]
fn events_lists_the_turn_overs_and_folds_and_refuses_bad_input() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let folding = root().join("examples/studies/science-6p5-penalty/state/discocyte_u0.2_r1.2.h5");
    let slipper = root().join("examples/studies/science-6p5/state/discocyte_u0.63_r1.2.h5");
    let (folding, slipper) = (folding.to_str().unwrap(), slipper.to_str().unwrap());
    let out = ok(&["events", folding, slipper], d);
    let mut lines = out.lines();
    assert_eq!(lines.next(), Some("file,run_id,event,t_s,start_s,end_s,x_min_um,x_min_rel,y_max_um,across,interval_s"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() >= 5 && rows.iter().all(|r| r.len() == 11 && r[0] == folding && r[1] == "discocyte_u0.2_r1.2"), "{out}");
    let num = |r: &[&str], k: usize| r[k].parse::<f64>().unwrap();
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r[2], (k + 1).to_string());
        assert!(num(r, 4) < num(r, 3) && num(r, 3) < num(r, 5), "{r:?}");
        if k == 0 {
            assert!(r[10].is_empty() && num(r, 9) > 0.9 && (0.6..0.7).contains(&num(r, 3)), "the overturn: {r:?}");
        } else {
            let previous = num(&rows[k - 1], 3);
            assert!((num(r, 10) - (num(r, 3) - previous)).abs() < 2e-4, "{r:?}");
            assert!(num(r, 9) < 0.85 && (0.72..0.8).contains(&num(r, 7)), "a fold: {r:?}");
        }
    }
    assert_eq!(ok(&["events", slipper], d).lines().count(), 1, "the tank-treading slipper: no event");
    // and stderr says what was read: a line per run
    let o = sweep_cmd(&["events", folding, slipper], d);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.lines().count() == 2 && err.contains("discocyte_u0.2_r1.2") && err.contains(&format!("{} collapse(s)", rows.len())) && err.contains("discocyte_u0.63_r1.2") && err.contains(" 0 collapse(s)"), "{err}");
    // with the last interval of the CSV and its change on the one before
    // (to the CSV's rounding)
    let last = rows[rows.len() - 1][10];
    let change = num(&rows[rows.len() - 1], 10) - num(&rows[rows.len() - 2], 10);
    let said = err.split(&format!("the last {last} s (")).nth(1).and_then(|r| r.split(" s,").next()).map(|c| c.parse::<f64>().unwrap());
    assert!(said.is_some_and(|c| (c - change).abs() < 2e-4), "{err}");
    // --run: that run alone, the same rows
    assert_eq!(ok(&["events", folding, slipper, "--run", "discocyte_u0.2_r1.2"], d), out);
    refused(&["events", folding, "--fraction", "1.2"], d, "--fraction 1.2");
    refused(&["events", folding, "--run", "nobody"], d, "nobody");
    refused(&["events", "absent.h5"], d, "absent.h5");
    refused(&["events"], d, "<FILES>");
}

/// `start-shape`: an ended run's last shape becomes a start shape that a sweep's
/// `[start_shape.NAME]` table starts a run from (listed with its start mesh checked against the
/// wall); the same name again, or a missing `--as`, is one line and exit 2, the file unchanged.
#[test]
fn start_shape_makes_a_start_that_a_sweep_reads() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::copy(root().join("examples/demo-results.h5"), d.join("demo.h5")).unwrap();
    let run = rbc_schema::results::read_runs(&d.join("demo.h5")).unwrap().into_iter().find(|r| r.summary.is_some()).unwrap();
    let o = sweep_cmd(&["start-shape", "demo.h5", &run.run_id, "--as", "capsule-start", "--out", "starts/s.h5"], d);
    assert!(o.status.success() && String::from_utf8_lossy(&o.stderr).contains("start shape capsule-start"), "{}", String::from_utf8_lossy(&o.stderr));
    let copy = rbc_schema::results::read_snapshots(&d.join("starts/s.h5"), "capsule-start").unwrap();
    let from = rbc_schema::results::read_snapshots(&d.join("demo.h5"), &run.run_id).unwrap();
    assert_eq!((copy.vertices_um.as_slice(), copy.triangles), (&from.vertices_um[from.vertices_um.len() - 1..], from.triangles));
    let before = std::fs::read(d.join("starts/s.h5")).unwrap();
    refused(&["start-shape", "demo.h5", &run.run_id, "--as", "capsule-start", "--out", "starts/s.h5"], d, "`capsule-start` already exists");
    refused(&["start-shape", "demo.h5", &run.run_id, "--out", "starts/s.h5"], d, "--as");
    // a name that cannot name a run: refused naming the output, not its temporary copy
    refused(&["start-shape", "demo.h5", &run.run_id, "--as", "a/b", "--out", "starts/s.h5"], d, "starts/s.h5: `a/b` cannot name a run (--as)");
    assert_eq!(std::fs::read(d.join("starts/s.h5")).unwrap(), before);
    // a sweep of the demo's scene starts from it (in its folder, given relatively)
    tiny_sweep(d);
    let sweep = std::fs::read_to_string(d.join("sweep.toml")).unwrap();
    let (sphere, mesh) = ("[start_shape.capsule]\nshape = \"sphere\"\nradius_um = 2.5", "[start_shape.capsule]\nshape = \"mesh-from-results\"\nresults = \"starts/s.h5\"\nrun = \"capsule-start\"");
    assert!(sweep.contains(sphere), "the demo sweep's capsule: {sweep}");
    std::fs::write(d.join("sweep.toml"), sweep.replace(sphere, mesh)).unwrap();
    let o = sweep_cmd(&["list", "sweep.toml"], d);
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success() && !err.contains("not checked"), "{err}");
    assert!(out.lines().skip(1).all(|l| l.contains("\tcapsule\t") && l.contains("\tto-run\t")), "{out}");
    // and a run starts from that shape, moved to its offset
    ok(&["task", "sweep.toml", "1", "--out", "t.h5"], d);
    let first = rbc_schema::results::read_snapshots(&d.join("t.h5"), "capsule_u1_r1").unwrap().vertices_um.swap_remove(0);
    let start = &copy.vertices_um[0];
    let shift = |v: &[f64; 3], w: &[f64; 3]| [v[0] - w[0], v[1] - w[1], v[2] - w[2]];
    let d0 = shift(&first[0], &start[0]);
    assert!(first.iter().zip(start).all(|(a, b)| shift(a, b).iter().zip(&d0).all(|(x, y)| (x - y).abs() < 1e-12)), "the start shape, translated");
    assert!(d0[1] > 0.5 && d0[2] > 0.3, "moved to r_init = 1 um along z = 5 y / 9: {d0:?}");
}
