//! `rbc-simulate --resume` end to end: a run SIGKILLed several times and resumed equals the uninterrupted run bit-for-bit; refusals are one line.
//!
//! Bit-for-bit (not to a tolerance) because the checkpoint holds the whole state
//! the next step depends on (vertices, next trial step, output clock, counters,
//! Bogacki-Shampine's first-same-as-last stage, the GMRES initial guess of
//! `lambda != 1`) as exact `f64`, and the solver is deterministic (two
//! uninterrupted runs are identical, checked below): any difference would be a
//! lost piece of state, and a tolerance would hide it.

use rbc_schema::results::{read_runs, read_snapshots, read_timeseries};
use std::path::Path;
use std::process::{Child, Command, Output};
use std::time::{Duration, Instant};

/// A capsule (Skalak + bending, 258 vertices) in shear at Ca ~ 0.07 with a tight tolerance:
/// about 140 adaptive steps with rejections and volume rescalings, 51 samples, about 1 s.
const CAPSULE: &str = r#"
name = "cap"
[cell]
shape = "sphere"
level = 3
radius_um = 3.0
[membrane.skalak]
convention = "barthes-biesel"
shear_modulus_n_m = 5e-6
c = 1.0
[membrane.bending]
kappa_b_n_m = 3e-19
[fluid]
viscosity_pa_s = 1.2e-3
lambda = LAMBDA
[flow]
kind = "shear"
shear_rate_1_s = 100.0
[integrator]
atol_um = ATOL
[time]
end_s = 0.01
output_interval_s = 0.0002
"#;

fn scene(lambda: f64, atol: f64) -> String {
    CAPSULE.replace("LAMBDA", &format!("{lambda:?}")).replace("ATOL", &format!("{atol:e}"))
}

fn command(args: &[&str], dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_rbc-simulate"));
    c.args(args).current_dir(dir);
    c
}

fn simulate(args: &[&str], dir: &Path) -> Output {
    command(args, dir).output().expect("run rbc-simulate")
}

fn spawn(args: &[&str], dir: &Path) -> Child {
    command(args, dir).stdout(std::process::Stdio::null()).stderr(std::process::Stdio::null()).spawn().expect("spawn rbc-simulate")
}

/// Wait up to `d` for the child; `true` when it exited by itself.
fn exited_within(child: &mut Child, d: Duration) -> bool {
    let t0 = Instant::now();
    while t0.elapsed() < d {
        if child.try_wait().expect("wait").is_some() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    false
}

/// Run the scene into `out`, SIGKILLing it after each delay of `kills` and resuming;
/// returns the number of kills that hit a running process.
fn run_with_kills(dir: &Path, out: &str, kills: &[u64]) -> usize {
    let mut hits = 0;
    for (i, &ms) in kills.iter().chain(std::iter::repeat(&u64::MAX)).enumerate() {
        assert!(i < kills.len() + 1, "the run did not finish");
        let status = read_runs(&dir.join(out)).ok().and_then(|r| r.first().map(|r| r.status));
        if status.is_some_and(|s| s.is_finished()) {
            break;
        }
        let mut args = vec!["s.toml", "--out", out, "--checkpoint-every", "2"];
        if status.is_some() {
            args.push("--resume"); // (a kill before the run was created leaves nothing to resume)
        }
        let mut child = spawn(&args, dir);
        if ms == u64::MAX {
            assert!(child.wait().unwrap().success(), "the last resume must finish the run");
            break;
        }
        if !exited_within(&mut child, Duration::from_millis(ms)) {
            child.kill().expect("SIGKILL"); // std's kill is SIGKILL on Unix
            child.wait().unwrap();
            hits += 1;
        }
    }
    hits
}

fn assert_identical(dir: &Path, a: &str, b: &str) {
    let (pa, pb) = (dir.join(a), dir.join(b));
    let (ta, tb) = (read_timeseries(&pa, "cap").unwrap(), read_timeseries(&pb, "cap").unwrap());
    assert_eq!(ta.len(), 51, "t = 0, 0.2, ..., 10 ms");
    assert_eq!(tb.len(), ta.len(), "no duplicated or missing sample rows");
    for (k, (x, y)) in ta.iter().zip(&tb).enumerate() {
        assert_eq!(x, y, "sample {k} differs");
        assert!((x.t_s - 2e-4 * k as f64).abs() < 1e-15, "row {k} at t = {}", x.t_s);
    }
    let (sa, sb) = (read_snapshots(&pa, "cap").unwrap(), read_snapshots(&pb, "cap").unwrap());
    assert_eq!(sa.times_s.len(), 6, "every 10th sample and the last");
    assert_eq!(sa, sb, "snapshots (the last one is the final mesh) differ");
    assert_eq!(sa.fields["mean_curvature_per_um"].len(), 6, "the curvature of every snapshot, also across the kills");
    let (ra, rb) = (&read_runs(&pa).unwrap()[0], &read_runs(&pb).unwrap()[0]);
    let (mut ma, mut mb) = (ra.summary.clone().unwrap(), rb.summary.clone().unwrap());
    assert_eq!(ma.evidence.remove("steps_accepted"), mb.evidence.remove("steps_accepted"));
    assert_eq!(ma.evidence.remove("steps_rejected"), mb.evidence.remove("steps_rejected"));
    for m in [&mut ma, &mut mb] {
        m.evidence.remove("wall_s");
    }
    assert_eq!(ma, mb, "summary attributes differ");
    // each run keeps one checkpoint: the one of its end state, at its last sample
    for (p, t) in [(&pa, &ta), (&pb, &tb)] {
        let name = format!("{}.cap.ckpt", p.file_name().unwrap().to_string_lossy());
        let ckpts: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(&*p.file_name().unwrap().to_string_lossy()) && n.ends_with(".ckpt"))
            .collect();
        assert_eq!(ckpts, std::slice::from_ref(&name), "one checkpoint left, the end state's");
        let ck = rbc_schema::checkpoint::read(&dir.join(&name)).unwrap();
        assert_eq!(ck.t_s, t.last().unwrap().t_s, "{name} holds the end state");
        assert_eq!(ck.n_samples, t.len());
    }
}

fn killed_and_resumed_equals_uninterrupted(lambda: f64, atol: f64, kills: &[u64]) {
    killed_and_resumed_equals_uninterrupted_scene(&scene(lambda, atol), kills)
}

fn killed_and_resumed_equals_uninterrupted_scene(text: &str, kills: &[u64]) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), text).unwrap();
    for out in ["a.h5", "a2.h5"] {
        let o = simulate(&["s.toml", "--out", out], dir.path());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    assert_identical(dir.path(), "a.h5", "a2.h5"); // the solver is deterministic
    let hits = run_with_kills(dir.path(), "b.h5", kills);
    assert!(hits >= 3, "only {hits} kills hit a running process: the test proves nothing");
    assert_identical(dir.path(), "a.h5", "b.h5");
    let runs = read_runs(&dir.path().join("b.h5")).unwrap();
    assert_eq!(runs.len(), 1, "resuming appends no run");
}

#[test]
fn killed_and_resumed_equals_uninterrupted_bit_for_bit() {
    // kills from 40 ms (before or during the start) to 400 ms after each (re)start
    killed_and_resumed_equals_uninterrupted(1.0, 2e-7, &[250, 40, 400, 300, 150, 350, 200, 400, 300]);
}

#[test]
fn killed_and_resumed_equals_uninterrupted_with_dense_output() {
    // ros34pw2-local steps across output times (dense output): a checkpoint is taken at the end of
    // the step that produced a sample and carries the next output index and the next step's first
    // stage, whose GMRES guess (lambda = 5) would otherwise differ
    let text = scene(5.0, 1e-6).replace("[integrator]\n", "[integrator]\nscheme = \"ros34pw2-local\"\n");
    assert!(text.contains("ros34pw2-local"));
    killed_and_resumed_equals_uninterrupted_scene(&text, &[300, 250, 350, 300, 200, 400]);
}

#[test]
fn killed_and_resumed_equals_uninterrupted_with_viscosity_contrast() {
    // lambda = 5: the double layer's GMRES starts from the last velocity, which the checkpoint carries
    killed_and_resumed_equals_uninterrupted(5.0, 1e-6, &[300, 250, 350, 300, 200, 400]);
}

/// Run `text` to 5 ms into `out`, then `--resume` it with the end time 10 ms.
fn run_then_extend(dir: &Path, text: &str, out: &str) {
    std::fs::write(dir.join("half.toml"), text.replace("end_s = 0.01", "end_s = 0.005")).unwrap();
    let o = simulate(&["half.toml", "--out", out], dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rec = read_runs(&dir.join(out)).unwrap().remove(0);
    assert_eq!(rec.status, rbc_schema::results::RunStatus::Unsteady);
    assert_eq!(read_timeseries(&dir.join(out), "cap").unwrap().len(), 26);
    let o = simulate(&["s.toml", "--out", out, "--resume"], dir);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("resuming run `cap`") && err.contains("at t = 5e-3 s (sample 26)"), "{err}");
    assert_eq!(read_runs(&dir.join(out)).unwrap().len(), 1, "continued, no run appended");
}

/// A run that reached its end time continues to a later one (`--resume` with the scene's
/// `time.end_s` raised) from the checkpoint of its end state. Explicit Bogacki-Shampine lands
/// every step on an output time, so the continuation takes the very steps of the uninterrupted
/// run: equal bit for bit, rows, snapshots (the extra final snapshot at the old end cut back)
/// and summary.
#[test]
fn a_run_that_reached_its_end_time_continues_to_a_later_one_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("s.toml"), scene(5.0, 1e-6)).unwrap();
    let o = simulate(&["s.toml", "--out", "a.h5"], d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    run_then_extend(d, &scene(5.0, 1e-6), "b.h5");
    assert_identical(d, "a.h5", "b.h5");
}

/// With dense output (ROS34PW2, lambda = 5) the last step before the old end time was shortened
/// to land on it, so the continuation departs from the uninterrupted run by the step control's
/// error only: every sample's centroid within the tolerance (1e-6 um), the same rows and snapshots.
#[test]
fn a_dense_output_run_continues_past_its_end_time_within_the_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = scene(5.0, 1e-6).replace("[integrator]\n", "[integrator]\nscheme = \"ros34pw2-local\"\n");
    assert!(text.contains("ros34pw2-local"));
    std::fs::write(d.join("s.toml"), &text).unwrap();
    let o = simulate(&["s.toml", "--out", "a.h5"], d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    run_then_extend(d, &text, "b.h5");
    let (ta, tb) = (read_timeseries(&d.join("a.h5"), "cap").unwrap(), read_timeseries(&d.join("b.h5"), "cap").unwrap());
    assert_eq!(ta.len(), 51);
    assert_eq!(tb.len(), 51);
    let mut worst = 0.0f64;
    for (k, (x, y)) in ta.iter().zip(&tb).enumerate() {
        assert_eq!(x.t_s, y.t_s, "row {k}");
        for c in 0..3 {
            worst = worst.max((x.centroid_um[c] - y.centroid_um[c]).abs());
        }
    }
    assert_eq!(ta[0], tb[0]);
    assert!(worst < 1e-6, "the continuation departs by {worst:e} um");
    let rec = read_runs(&d.join("b.h5")).unwrap().remove(0);
    assert_eq!(rec.status, rbc_schema::results::RunStatus::Unsteady);
    assert_eq!(read_snapshots(&d.join("b.h5"), "cap").unwrap().times_s, read_snapshots(&d.join("a.h5"), "cap").unwrap().times_s);
}

/// A run asked to suspend (`<out>.suspend`, created while it runs) stops at a checkpoint of its
/// next sample with exit 0, unfinished (status running, the checkpoint kept, rows up to it); a
/// start is refused while the request is in place; once it is removed, `--resume` ends the run
/// bit-for-bit as the uninterrupted one.
#[test]
fn a_suspended_run_stops_at_a_checkpoint_and_resumes_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.toml"), scene(1.0, 2e-7)).unwrap();
    let o = simulate(&["s.toml", "--out", "a.h5"], dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ckpt = dir.path().join("b.h5.cap.ckpt");
    let suspend = dir.path().join("b.h5.suspend");
    let child = command(&["s.toml", "--out", "b.h5"], dir.path()).stdout(std::process::Stdio::null()).stderr(std::process::Stdio::piped()).spawn().unwrap();
    // the first checkpoint is written at the first sample, after the operators are built; the
    // run then takes about a second for its 51 samples
    let t0 = Instant::now();
    while !ckpt.exists() {
        assert!(t0.elapsed() < Duration::from_secs(60), "no first checkpoint");
        std::thread::sleep(Duration::from_millis(2));
    }
    std::thread::sleep(Duration::from_millis(100));
    std::fs::write(&suspend, "").unwrap();
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("suspended at its checkpoint"), "{err}");
    let b = dir.path().join("b.h5");
    let rec = read_runs(&b).unwrap().remove(0);
    assert_eq!(rec.status, rbc_schema::results::RunStatus::Running, "suspended, not finished: {err}");
    let ck = rbc_schema::checkpoint::read(&ckpt).unwrap();
    let rows = read_timeseries(&b, "cap").unwrap();
    assert!(rows.len() > 1 && rows.len() < 51, "stopped mid-run: {} rows", rows.len());
    assert_eq!(ck.t_s, rows.last().unwrap().t_s, "the checkpoint is the last row's state");

    // refused while the request is in place, nothing changed
    let o = simulate(&["s.toml", "--out", "b.h5", "--resume"], dir.path());
    one_line_refusal(&o, "b.h5.suspend: a suspend request");
    assert_eq!(read_timeseries(&b, "cap").unwrap(), rows);

    std::fs::remove_file(&suspend).unwrap();
    let o = simulate(&["s.toml", "--out", "b.h5", "--resume"], dir.path());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_identical(dir.path(), "a.h5", "b.h5");
}

fn one_line_refusal(o: &Output, needle: &str) {
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    let last = err.trim().lines().last().unwrap_or("");
    assert!(last.starts_with("rbc-simulate: ") && last.contains(needle), "{err}");
}

#[test]
fn resume_refuses_a_changed_scene_a_finished_run_and_a_missing_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("s.toml"), scene(1.0, 2e-7)).unwrap();
    one_line_refusal(&simulate(&["s.toml", "--out", "r.h5", "--resume"], d), "nothing to resume (no such file)");
    assert!(!d.join("r.h5").exists());
    // a run killed mid-way
    let mut child = spawn(&["s.toml", "--out", "r.h5", "--checkpoint-every", "1"], d);
    // (the results file is locked while the run writes it: watch for its checkpoint instead)
    let t0 = Instant::now();
    while !d.join("r.h5.cap.ckpt").exists() {
        assert!(t0.elapsed() < Duration::from_secs(60), "no checkpoint appeared");
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(!exited_within(&mut child, Duration::from_millis(200)), "the run finished before it could be killed");
    child.kill().unwrap();
    child.wait().unwrap();
    let state = || (read_timeseries(&d.join("r.h5"), "cap").unwrap(), read_runs(&d.join("r.h5")).unwrap(), std::fs::read(d.join("r.h5.cap.ckpt")).unwrap());
    let before = state();
    // a different shear rate: refused, nothing touched
    std::fs::write(d.join("other.toml"), scene(1.0, 2e-7).replace("shear_rate_1_s = 100.0", "shear_rate_1_s = 101.0")).unwrap();
    one_line_refusal(&simulate(&["other.toml", "--out", "r.h5", "--resume"], d), "scene differs");
    assert!(state() == before, "a refused resume leaves the run and its checkpoint as they were");
    // a damaged checkpoint (one bit of its global heap's size, where libhdf5 1.10.8 loops or crashes):
    // refused by its checksum with one line naming it, before libhdf5 reads it; the results are kept
    let good = std::fs::read(d.join("r.h5.cap.ckpt")).unwrap();
    let mut bad = good.clone();
    let gcol = bad.windows(4).position(|w| w == b"GCOL").expect("the checkpoint's strings are in a global heap");
    bad[gcol + 9] ^= 0x01;
    std::fs::write(d.join("r.h5.cap.ckpt"), &bad).unwrap();
    one_line_refusal(&simulate(&["s.toml", "--out", "r.h5", "--resume"], d), "r.h5.cap.ckpt: checkpoint damaged (checksum mismatch");
    std::fs::write(d.join("r.h5.cap.ckpt"), &good).unwrap();
    assert!(state() == before, "a refused resume leaves the run as it was");
    // a whole checkpoint whose state is not finite: refused naming the file and the field, the run
    // and its checkpoint as they were (it used to end the run `failed` and remove its checkpoint)
    let mut nan = rbc_schema::checkpoint::read(&d.join("r.h5.cap.ckpt")).unwrap();
    nan.fields.get_mut("runner.vertices_um").unwrap()[4] = f64::NAN;
    rbc_schema::checkpoint::write(&d.join("r.h5.cap.ckpt"), &nan).unwrap();
    one_line_refusal(&simulate(&["s.toml", "--out", "r.h5", "--resume"], d), "r.h5.cap.ckpt: field `runner.vertices_um`: vertex 1 is");
    std::fs::write(d.join("r.h5.cap.ckpt"), &good).unwrap();
    assert!(state() == before, "a refused resume leaves the run and its checkpoint as they were");
    one_line_refusal(&simulate(&["s.toml", "--out", "r.h5", "--resume", "--run-id", "nope"], d), "nothing to resume (no run `nope`)");
    // the same scene with other comments and spacing resumes, then there is nothing left to resume
    std::fs::write(d.join("same.toml"), format!("# a comment\n{}", scene(1.0, 2e-7).replace("c = 1.0", "c   = 1.0"))).unwrap();
    let o = simulate(&["same.toml", "--out", "r.h5", "--resume"], d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("resuming run `cap`"));
    one_line_refusal(&simulate(&["s.toml", "--out", "r.h5", "--resume"], d), "nothing to resume (the run reached its end time 1e-2 s: set time.end_s later to continue it)");
    // an earlier end time does not cut it back either
    std::fs::write(d.join("short.toml"), scene(1.0, 2e-7).replace("end_s = 0.01", "end_s = 0.005")).unwrap();
    one_line_refusal(&simulate(&["short.toml", "--out", "r.h5", "--resume"], d), "nothing to resume (the run reached its end time");
    // a run that ended before end checkpoints were kept
    let kept = std::fs::read(d.join("r.h5.cap.ckpt")).unwrap();
    std::fs::remove_file(d.join("r.h5.cap.ckpt")).unwrap();
    std::fs::write(d.join("long.toml"), scene(1.0, 2e-7).replace("end_s = 0.01", "end_s = 0.02")).unwrap();
    one_line_refusal(&simulate(&["long.toml", "--out", "r.h5", "--resume"], d), "the run ended with status unsteady and kept no checkpoint of its end");
    std::fs::write(d.join("r.h5.cap.ckpt"), kept).unwrap();
    // without --resume a new run is appended, the finished one is kept
    let o = simulate(&["s.toml", "--out", "r.h5", "--checkpoint-interval", "0"], d);
    assert!(o.status.success());
    let ids: Vec<String> = read_runs(&d.join("r.h5")).unwrap().into_iter().map(|r| r.run_id).collect();
    assert_eq!(ids, ["cap", "cap-2"]);
}

/// A checkpoint written before checkpoints carried a checksum (the science-6p5 study's r_init =
/// 0.8 um run as saved at 26.5 ms in session 11, `examples/fixtures/pre-checksum/`, from a copy
/// in a temporary folder) still reopens its run: read unchecked, the results cut back to it.
#[test]
fn a_checkpoint_of_an_older_build_still_reopens_its_run() {
    use rbc_schema::checkpoint::{self, Integrity};
    use rbc_schema::results::ResultsFile;
    use rbc_solver::run::persist;
    let dir = tempfile::tempdir().unwrap();
    let run = "discocyte_u3.8_r0.8";
    let state = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/fixtures/pre-checksum");
    let out = dir.path().join(format!("{run}.h5"));
    std::fs::copy(state.join(format!("{run}.h5")), &out).unwrap();
    let ck = checkpoint::checkpoint_path(&out, run);
    std::fs::copy(state.join(ck.file_name().unwrap()), &ck).unwrap();
    let integrity = checkpoint::verify(&ck, &std::fs::read(&ck).unwrap()).unwrap();
    assert_ne!(integrity, Integrity::Verified, "the fixture is of the layout without a checksum");
    let mut file = ResultsFile::create_or_open(&out).unwrap();
    let r = persist::reopen(&mut file, run, &|_| true).unwrap().unwrap_or_else(|why| panic!("not resumable: {why:?}"));
    assert!(r.state.t_s > 0.0 && r.rows.len() > 1 && r.rows.last().unwrap().t_s <= r.state.t_s, "t = {} s, {} rows", r.state.t_s, r.rows.len());
}
