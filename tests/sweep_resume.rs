//! A sweep run killed mid-way, or suspended on request, continues from its checkpoint (not from t = 0) and ends bit-for-bit as the uninterrupted run.
//!
//! The sweep's scenes are periodic channels, so the run here is driven by the real
//! `Runner` (Bogacki-Shampine, adaptive steps) on an analytic rigid motion of a
//! sphere (translation along x plus a fast rotation about its centroid), which
//! the steady-state detector declares steady after one window. A kill is
//! emulated in-process by an observer that stops forwarding samples after
//! `after` of them and never calls `finish` (as a dead process would not); the
//! part file is then left `running` with rows written after its last checkpoint.

mod sweep_common;

use nalgebra::Vector3;
use rbc::sweep::solver_exec::execute_run;
use rbc_schema::results::*;
use rbc_schema::scene::Scene;
use rbc_schema::sweep::Sweep;
use rbc_solver::integrate::bs23::BogackiShampine;
use rbc_solver::integrate::check::Checks;
use rbc_solver::integrate::Dynamics;
use rbc_solver::run::checkpoint::RunState;
use rbc_solver::run::persist::CheckpointPolicy;
use rbc_solver::run::{Observer, RunConfig, RunSummary as SolverSummary, Runner, Sample, StepControl};
use rbc_solver::SolverError;
use std::cell::Cell;
use sweep_common::*;

const SWEEP_FAST: &str = r#"
base_scene = "base.toml"
mean_velocity_mm_s = [2.0]
r_init_um = [0.5]
start_shapes = ["discocyte"]
snapshot_every = 7
[steady]
window_s = 0.03
position_tol_um = 0.5
max_time_s = 0.5
[classify]
frames = 10
"#;

/// `u = U e_x + Omega x (x - c(t))`, `c(t) = c0 + U t e_x`: a rigid translation and rotation (um/s).
struct Rigid {
    c0: Vector3<f64>,
}

const U_UM_S: f64 = 2000.0;
const OMEGA: [f64; 3] = [40.0, 300.0, -120.0];

impl Dynamics for Rigid {
    fn velocity(&mut self, t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        let c = self.c0 + Vector3::new(U_UM_S * t_s, 0.0, 0.0);
        let w = Vector3::from(OMEGA);
        for (ui, xi) in u.iter_mut().zip(x) {
            *ui = Vector3::new(U_UM_S, 0.0, 0.0) + w.cross(&(xi - c));
        }
        Ok(())
    }
}

/// What the wrapping observer does after `after` samples.
#[derive(Clone)]
enum Action {
    /// Die: refuse the next sample and never finish (a killed process).
    Dies,
    /// Create the suspend request file (as `scripts/study.sh save` does) and forward everything.
    RequestsSuspend(std::path::PathBuf),
}

/// Forwards everything, and acts after `after` samples.
struct Tap<'a> {
    inner: &'a mut dyn Observer,
    after: usize,
    action: Action,
    seen: usize,
    first_t: Option<f64>,
}

impl Tap<'_> {
    fn dead(&self) -> bool {
        matches!(self.action, Action::Dies) && self.seen > self.after
    }
}

impl Observer for Tap<'_> {
    fn sample(&mut self, s: &Sample<'_>) -> Result<(), SolverError> {
        self.first_t.get_or_insert(s.t_s);
        self.seen += 1;
        if self.dead() {
            return Err(SolverError::Output("killed".into()));
        }
        if let (Action::RequestsSuspend(file), true) = (&self.action, self.seen == self.after) {
            std::fs::write(file, b"").unwrap();
        }
        self.inner.sample(s)
    }
    fn finish(&mut self, summary: &SolverSummary, failure: Option<&SolverError>) -> Result<(), SolverError> {
        if self.dead() {
            return Ok(()); // a killed process finishes nothing
        }
        self.inner.finish(summary, failure)
    }
    fn checkpoint_due(&mut self, t_s: f64) -> bool {
        self.inner.checkpoint_due(t_s)
    }
    fn checkpoint(&mut self, state: &RunState) -> Result<(), SolverError> {
        self.inner.checkpoint(state)
    }
    fn checkpoint_at_end(&mut self) -> bool {
        !self.dead() && self.inner.checkpoint_at_end()
    }
    fn checkpoint_at_stop(&mut self) -> bool {
        !self.dead() && self.inner.checkpoint_at_stop()
    }
    fn resume(&mut self) -> Result<Option<RunState>, SolverError> {
        self.inner.resume()
    }
    fn resumed(&mut self, state: &RunState) {
        self.inner.resumed(state)
    }
}

/// The runner's settings for `scene`: its end time and output interval, bs23 at 1e-7 um.
fn run_config(scene: &Scene) -> RunConfig {
    RunConfig {
        t_start_s: 0.0,
        t_end_s: scene.time.end_s,
        output_interval_s: scene.time.output_interval_s,
        control: StepControl::new(1e-7, 1e-5, 1e-14, 1e-3),
        checks: Checks::default(),
        volume: None,
    }
}

/// Run the sweep's run into `out`, dying after `after` samples (`usize::MAX`: never);
/// returns the time of the first sample this attempt produced.
fn attempt(sweep: &Sweep, out: &std::path::Path, after: usize, policy: CheckpointPolicy) -> f64 {
    attempt_with(sweep, out, after, Action::Dies, policy)
}

/// As [`attempt`], with `action` after `after` samples.
fn attempt_with(sweep: &Sweep, out: &std::path::Path, after: usize, action: Action, policy: CheckpointPolicy) -> f64 {
    try_attempt(sweep, out, after, action, policy).unwrap()
}

/// As [`attempt_with`], returning the executor's error.
fn try_attempt(sweep: &Sweep, out: &std::path::Path, after: usize, action: Action, policy: CheckpointPolicy) -> Result<f64, rbc::sweep::SweepError> {
    let run = &sweep.runs().unwrap()[0];
    let first = Cell::new(f64::NAN);
    let solve = |scene: &Scene, obs: &mut dyn Observer| -> Result<(), SolverError> {
        let mesh = rbc_solver::mesh::sphere(2, 3.6);
        let c0 = Vector3::new(0.0, run.y_init_um, run.z_init_um);
        let mut x: Vec<Vector3<f64>> = mesh.vertices.iter().map(|p| p + c0).collect();
        let cfg = run_config(scene);
        let mut tap = Tap { inner: obs, after, action: action.clone(), seen: 0, first_t: None };
        let r = Runner::new(cfg).run(&mut Rigid { c0 }, &mut BogackiShampine::new(), &mesh.triangles, &mut x, &mut tap);
        first.set(tap.first_t.unwrap_or(f64::NAN));
        r.map(|_| ())
    };
    execute_run(&solve, policy, sweep, run, out)?;
    Ok(first.get())
}

/// A study switching to a faster step method keeps its simulated time: a checkpoint continues
/// under a scene that differs only in the integrator's method keys (the change is logged) or in
/// its end time, while
/// a scene with another model refuses, naming the part file, instead of silently starting again
/// from t = 0.
#[test]
fn a_changed_step_method_resumes_and_a_changed_model_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let sweep_path = write_sweep(dir.path(), SWEEP_FAST);
    let sweep = Sweep::read(&sweep_path).unwrap();
    let b = dir.path().join("b.h5");
    let every4 = CheckpointPolicy { every_outputs: 4, every_wall_s: 0.0 };
    assert_eq!(attempt(&sweep, &b, 14, every4), 0.0);
    let edit = |extra: &str| {
        std::fs::write(dir.path().join("base.toml"), format!("{}[integrator]\n{extra}\n", &*BASE_SCENE)).unwrap();
        Sweep::read(&sweep_path).unwrap()
    };
    // another step method: resumed at the last checkpoint (13 ms), not at 0
    let stepping = edit("scheme = \"ros34pw2-mobility\"\natol_um = 1e-2\nh_max_s = 1e-3");
    assert_ne!(stepping.runs().unwrap()[0].scene_text, sweep.runs().unwrap()[0].scene_text);
    let t1 = attempt(&stepping, &b, 11, every4);
    assert!((t1 - 0.013).abs() < 1e-12, "resumed at {t1} s");
    // another model (the area limit is part of it): refused, the part file named, nothing lost
    let model = edit("max_area_change = 0.2");
    let rows = read_timeseries(&b, &sweep.runs().unwrap()[0].run_id).unwrap();
    let e = try_attempt(&model, &b, usize::MAX, Action::Dies, every4).unwrap_err().to_string();
    assert!(e.contains("b.h5") && e.contains("different scene"), "{e}");
    assert_eq!(read_timeseries(&b, &sweep.runs().unwrap()[0].run_id).unwrap(), rows, "the rows are kept");
    // a later end time (the paper's croissants settle after 10-30 s): resumed at the checkpoint
    // the last attempt wrote, not at 0
    let later = BASE_SCENE.replace("end_s = 40.0", "end_s = 60.0");
    assert_ne!(later, *BASE_SCENE);
    std::fs::write(dir.path().join("base.toml"), format!("{later}[integrator]\nscheme = \"ros34pw2-mobility\"\natol_um = 1e-2\nh_max_s = 1e-3\n")).unwrap();
    let t2 = attempt(&Sweep::read(&sweep_path).unwrap(), &b, usize::MAX, every4);
    assert!(t2 > t1 + 1e-3, "resumed at {t2} s");
}

/// A damaged checkpoint does not cost the run its simulated time: the sweep refuses, naming the
/// part file and the checkpoint's fault, and keeps the rows (it used to start the run again from
/// t = 0 over them); with the checkpoint restored from a copy the run continues where it was.
#[test]
fn a_damaged_checkpoint_refuses_and_keeps_the_runs_time() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP_FAST)).unwrap();
    let id = sweep.runs().unwrap()[0].run_id.clone();
    let b = dir.path().join("b.h5");
    let every4 = CheckpointPolicy { every_outputs: 4, every_wall_s: 0.0 };
    assert_eq!(attempt(&sweep, &b, 14, every4), 0.0);
    let ck = b.with_file_name(format!("b.h5.{id}.ckpt"));
    let good = std::fs::read(&ck).unwrap();
    let mut bad = good.clone();
    let k = bad.len() / 2;
    bad[k] ^= 0x10;
    std::fs::write(&ck, &bad).unwrap();
    let rows = read_timeseries(&b, &id).unwrap();
    let e = try_attempt(&sweep, &b, usize::MAX, Action::Dies, every4).unwrap_err().to_string();
    assert!(e.contains("b.h5") && e.contains("cannot continue from its checkpoint") && e.contains("are kept"), "{e}");
    assert_eq!(read_timeseries(&b, &id).unwrap(), rows, "the rows are kept");
    // a whole checkpoint whose state no run could continue from: refused before anything is cut
    // back, the run kept as it was (it used to be marked failed and its checkpoint removed, or,
    // for the observer's fields, skipped without a word)
    let refused_with = |edit: &dyn Fn(&mut rbc_schema::checkpoint::Checkpoint), why: &str, kept: &[rbc_schema::results::TimeSample]| {
        let mut unfit = rbc_schema::checkpoint::read(&ck_copy(&ck, &good)).unwrap();
        edit(&mut unfit);
        rbc_schema::checkpoint::write(&ck, &unfit).unwrap();
        let e = try_attempt(&sweep, &b, usize::MAX, Action::Dies, every4).unwrap_err().to_string();
        assert!(e.contains("b.h5") && e.contains("cannot continue from its checkpoint") && e.contains(why) && e.contains("are kept"), "{e}");
        assert_eq!(read_timeseries(&b, &id).unwrap(), kept, "the rows are kept");
        assert_eq!(rbc_schema::results::ResultsFile::open(&b).unwrap().run(&id).unwrap().status, rbc_schema::results::RunStatus::Running, "not marked failed");
        assert!(ck.exists(), "the checkpoint is kept");
    };
    let edited = |k: &'static str, f: fn(&mut Vec<f64>)| move |c: &mut rbc_schema::checkpoint::Checkpoint| f(c.fields.get_mut(k).unwrap());
    refused_with(&edited("runner.vertices_um", |v| v.truncate(v.len() - 3)), "`runner.vertices_um` holds 65 vertices, fewer than the run's 66", &rows);
    refused_with(&edited("runner.vertices_um", |v| v[7] = f64::NAN), "`runner.vertices_um`: vertex 2 is", &rows);
    refused_with(&edited("runner.h_s", |v| v[0] = 0.0), "`runner.h_s` is 0", &rows);
    // one whose state does not fit what only the run knows (the observer's own fields, the
    // scheme's state): refused before any step, after the rows were cut back to the checkpoint
    // (the row after it, which the resumed run writes again)
    let cut = &rows[..rbc_schema::checkpoint::read(&ck_copy(&ck, &good)).unwrap().n_samples];
    refused_with(&|c| drop(c.fields.remove("observer.frame_t_s")), "field `observer.frame_t_s` is missing or malformed", cut);
    refused_with(&edited("integrator.k1_um_s", |v| v.truncate(v.len() - 1)), "k1_um_s: length 197 is not a multiple of 3", cut);
    std::fs::write(&ck, &good).unwrap();
    let t1 = attempt(&sweep, &b, usize::MAX, every4);
    assert!((t1 - 0.013).abs() < 1e-12, "resumed at {t1} s");
}

/// `bytes` written to a file beside `ck` (so that `rbc_schema::checkpoint::read` verifies them).
fn ck_copy(ck: &std::path::Path, bytes: &[u8]) -> std::path::PathBuf {
    let p = ck.with_extension("copy.ckpt");
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn a_killed_sweep_run_continues_from_its_checkpoint_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP_FAST)).unwrap();
    let id = sweep.runs().unwrap()[0].run_id.clone();
    let (a, b) = (dir.path().join("a.h5"), dir.path().join("b.h5"));
    assert_eq!(attempt(&sweep, &a, usize::MAX, CheckpointPolicy::default()), 0.0);
    let every4 = CheckpointPolicy { every_outputs: 4, every_wall_s: 0.0 };
    assert_eq!(attempt(&sweep, &b, 14, every4), 0.0);
    assert_eq!(read_runs(&b).unwrap()[0].status, RunStatus::Running);
    assert!(b.with_file_name(format!("b.h5.{id}.ckpt")).exists());
    // checkpoints at samples 1, 5, 9, 13 (t = 12 ms); the kill came at sample 15: resume at 13 ms
    let t1 = attempt(&sweep, &b, 11, every4);
    assert!((t1 - 0.013).abs() < 1e-12, "second attempt started at {t1} s");
    let t2 = attempt(&sweep, &b, usize::MAX, every4);
    assert!(t2 > t1, "third attempt started at {t2} s");

    let (ra, rb) = (read_runs(&a).unwrap().remove(0), read_runs(&b).unwrap().remove(0));
    assert_eq!(ra.status, RunStatus::Steady, "the detector decided");
    // the entrance record (10 frames) as it passed; 10 mm not reached: the steady state carried there
    assert_eq!(ra.transits.iter().map(|t| (t.distance_mm, t.from_steady)).collect::<Vec<_>>(), [(0.0, false), (10.0, true)], "{:?}", ra.transits);
    assert_eq!(ra.transits, rb.transits, "recorded once, before the kill, and kept");
    assert_eq!(read_timeseries(&a, &id).unwrap(), read_timeseries(&b, &id).unwrap());
    assert_eq!(read_snapshots(&a, &id).unwrap(), read_snapshots(&b, &id).unwrap());
    let strip = |r: RunRecord| {
        let mut s = r.summary.unwrap();
        s.evidence.remove("wall_s");
        s
    };
    assert_eq!(strip(ra), strip(rb), "status, classification and statistics");
    // the checkpoint of the end state stays, at the last sample (for `rbc-sweep reopen`)
    let ck = rbc_schema::checkpoint::read(&b.with_file_name(format!("b.h5.{id}.ckpt"))).expect("the end checkpoint is kept");
    let rows = read_timeseries(&b, &id).unwrap();
    assert_eq!((ck.t_s, ck.n_samples), (rows.last().unwrap().t_s, rows.len()));
}

/// A suspend request stops the run at a checkpoint of the very sample at which it appeared,
/// unfinished (status running, the checkpoint kept, the rows cut there); the progress read from
/// the checkpoint names that time and state; without the request the run resumes and ends
/// bit-for-bit as the uninterrupted one.
#[test]
fn a_suspended_run_stops_at_a_checkpoint_and_resumes_bit_for_bit() {
    use rbc::sweep::solver_exec::suspend_path;
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP_FAST)).unwrap();
    let run = sweep.runs().unwrap().remove(0);
    let id = run.run_id.clone();
    let (a, b) = (dir.path().join("a.h5"), dir.path().join("b.h5"));
    attempt(&sweep, &a, usize::MAX, CheckpointPolicy::default());

    let suspend = suspend_path(&b);
    assert_eq!(suspend, dir.path().join("b.h5.suspend"));
    // the default policy (every 60 s of wall time) would take no checkpoint after the first sample
    assert_eq!(attempt_with(&sweep, &b, 9, Action::RequestsSuspend(suspend.clone()), CheckpointPolicy::default()), 0.0);
    let rec = read_runs(&b).unwrap().remove(0);
    assert_eq!(rec.status, RunStatus::Running, "suspended, not finished");
    assert_eq!(rec.n_samples, 9, "rows up to the sample of the request");
    let ck = rbc_schema::checkpoint::read(&b.with_file_name(format!("b.h5.{id}.ckpt"))).unwrap();
    let rows_a = read_timeseries(&a, &id).unwrap();
    assert_eq!(ck.t_s, rows_a[8].t_s, "checkpoint at the 9th sample");

    // progress from the checkpoint (the topology from the scene: the level-2 discocyte has the
    // sphere's triangles)
    let scene = Scene::parse(&run.scene_text, &sweep.base_scene).unwrap();
    assert_eq!(rbc_solver::scene::initial_mesh(&scene).unwrap().triangles, rbc_solver::mesh::sphere(2, 3.6).triangles);
    let cfg = rbc_solver::classify::ClassifyConfig::default();
    let p = rbc::sweep::study::run_progress(&b, &id, &cfg, None).unwrap();
    assert_eq!((p.status.as_str(), p.t_s), ("running", rows_a[8].t_s));
    assert!(p.steps > 0);
    // a rigid motion: centroid and velocity of the uninterrupted run's row, x-velocity U
    assert!((p.y_um - rows_a[8].centroid_um[1]).abs() < 1e-9 && (p.z_um - rows_a[8].centroid_um[2]).abs() < 1e-9, "{p:?}");
    assert!((p.velocity_mm_s - U_UM_S * 1e-3).abs() < 1e-6, "{p:?}");
    assert!(p.sharpest_fold_deg > 0.0 && p.sharpest_fold_deg < 60.0, "{p:?}");
    let table = rbc::sweep::study::table(&[p]);
    assert!(table.lines().nth(2).unwrap().starts_with(&format!("| {id} | running | ")), "{table}");
    // with a criterion, the steady gap of the 9 stored rows (the file is closed: it opens),
    // none when they span less than one window
    let mut c = rbc::sweep::verdict::criterion(&sweep.steady, f64::INFINITY);
    let rows_b = read_timeseries(&b, &id).unwrap();
    c.window_s = rows_b[8].t_s - rows_b[3].t_s;
    c.min_samples = 6;
    let gap = rbc::sweep::study::run_progress(&b, &id, &cfg, Some(&c)).unwrap().steady_gap;
    // the window is the rows 3..=8 (rows 3..8 and the one at its start): the largest range of
    // a watched quantity over them against its tolerance
    let obs: Vec<[f64; 5]> = rows_b[3..=8].iter().map(rbc_solver::steady::observables).collect();
    let expected = (0..5)
        .map(|k| {
            let col = obs.iter().map(|o| o[k]);
            (col.clone().fold(f64::NEG_INFINITY, f64::max) - col.fold(f64::INFINITY, f64::min)) / c.tolerances[k]
        })
        .fold(f64::NEG_INFINITY, f64::max);
    let (g, _) = gap.unwrap();
    assert!((g - expected).abs() <= 1e-12 * expected.max(1.0) && g > 0.0, "{gap:?} against {expected}");
    c.window_s = 1.0;
    assert_eq!(rbc::sweep::study::run_progress(&b, &id, &cfg, Some(&c)).unwrap().steady_gap, None);

    // resumed without the request: the uninterrupted run, bit for bit
    std::fs::remove_file(&suspend).unwrap();
    let t = attempt(&sweep, &b, usize::MAX, CheckpointPolicy::default());
    assert_eq!(t, rows_a[9].t_s, "resumed after the checkpoint's sample");
    assert_eq!(read_timeseries(&a, &id).unwrap(), read_timeseries(&b, &id).unwrap());
    assert_eq!(read_snapshots(&a, &id).unwrap(), read_snapshots(&b, &id).unwrap());
    let strip = |r: RunRecord| {
        let mut s = r.summary.unwrap();
        s.evidence.remove("wall_s");
        s
    };
    assert_eq!(strip(read_runs(&a).unwrap().remove(0)), strip(read_runs(&b).unwrap().remove(0)));
}

/// A running run's steady and periodic gaps and radial drift in `rbc-sweep status`: its results
/// file is locked by its process, so they are the ones its detector computed at the checkpoint,
/// stored there; they are those of the stored rows under the sweep's criterion (tolerances far
/// below the rotating sphere's ranges, so the run stays undecided), the gaps none before its
/// samples span a window, the drift none before they hold a span of whole periods (or of a
/// window, with no candidate period).
#[test]
fn a_running_runs_checkpoint_holds_its_steady_gap() {
    let dir = tempfile::tempdir().unwrap();
    let text = SWEEP_FAST.replace("window_s = 0.03\nposition_tol_um = 0.5", "window_s = 0.02\nposition_tol_um = 1e-6\nasphericity_tol = 1e-9");
    assert_ne!(text, SWEEP_FAST);
    let sweep = Sweep::read(&write_sweep(dir.path(), &text)).unwrap();
    let id = sweep.runs().unwrap()[0].run_id.clone();
    let c = rbc::sweep::verdict::criterion(&sweep.steady, f64::INFINITY);
    let cfg = rbc_solver::classify::ClassifyConfig::default();
    let stored = |out: &std::path::Path| {
        let ck = rbc_schema::checkpoint::read(&rbc_schema::checkpoint::checkpoint_path(out, &id)).unwrap();
        let own = rbc_solver::run::persist::observer_fields(&ck.fields);
        (rbc::sweep::observer_state::stored_gap(&own), rbc::sweep::observer_state::stored_periodic_gap(&own), rbc::sweep::observer_state::stored_orbit_drift(&own))
    };
    for (samples, spans_a_window) in [(12, false), (30, true), (120, true)] {
        let out = dir.path().join(format!("s{samples}.h5"));
        attempt_with(&sweep, &out, samples, Action::RequestsSuspend(rbc::sweep::solver_exec::suspend_path(&out)), CheckpointPolicy::default());
        let rows = read_timeseries(&out, &id).unwrap();
        assert_eq!((rows.len(), read_runs(&out).unwrap()[0].status), (samples, RunStatus::Running));
        let (gap, orbit, drift) = stored(&out);
        assert_eq!(gap, rbc_solver::steady::steady_gap(&rows, &c), "{samples} samples");
        assert_eq!(orbit, rbc_solver::steady::periodic_gap(&rows, &c), "{samples} samples");
        // the radial drift over the candidate's period (a quarter of the window without one:
        // 12 samples hold less than the 20 ms of a span), from the same rows
        let expected = rbc_solver::steady::radial_orbit_drift(&rows, rbc_solver::steady::drift_interval_s(orbit.as_ref(), c.window_s));
        assert_eq!(drift, expected, "{samples} samples");
        // the rigid rotation keeps the radial position: no drift, its rate once four of the
        // candidate's periods are stored (29 ms of ~3.7 ms periods), the earlier rate once eight
        assert_eq!(drift.is_some_and(|d| d.rate.abs() < 1e-9), samples >= 30, "{samples} samples: {drift:?}");
        assert_eq!(drift.is_some_and(|d| d.earlier_rate.is_some_and(|e| e.abs() < 1e-9)), samples >= 120, "{samples} samples: {drift:?}");
        assert_eq!(orbit.is_some(), spans_a_window, "{orbit:?}");
        assert_eq!(gap.is_some_and(|(g, _)| g > 1.0), spans_a_window, "{gap:?}");
        // the checkpoint alone (as when the file is locked) gives the status its gap
        let alone = dir.path().join(format!("alone{samples}.h5"));
        std::fs::copy(rbc_schema::checkpoint::checkpoint_path(&out, &id), rbc_schema::checkpoint::checkpoint_path(&alone, &id)).unwrap();
        let p = rbc::sweep::study::run_progress(&alone, &id, &cfg, Some(&c)).unwrap();
        assert_eq!((p.status.as_str(), p.t_s, p.steady_gap, p.periodic_gap, p.orbit_drift), ("running", rows[samples - 1].t_s, gap, orbit, drift));
        let p = rbc::sweep::study::run_progress(&alone, &id, &cfg, None).unwrap();
        assert_eq!((p.steady_gap, p.periodic_gap, p.orbit_drift), (None, None, None), "no criterion, no gap");
    }
}

/// A run that ended (steady after a 30 ms window) without an end checkpoint (as before session
/// 28) and is reopened under a longer window (60 ms) continues from its last snapshot, not from t = 0: its rows up to the old end are kept, the new
/// ones follow at the next output times, and it ends where the run that had the longer window
/// from the start ends, with the same samples and snapshot times and positions equal to the
/// integrator's tolerance (the reopened run restarts the step-size controller, so not bit for
/// bit). A running or failed run, or a missing one, is refused with the file and run named,
/// and nothing is changed.
#[test]
fn an_ended_run_reopened_under_a_longer_window_continues_from_its_end() {
    use rbc::sweep::reopen::reopen_ended;
    let dir = tempfile::tempdir().unwrap();
    let short = Sweep::read(&write_sweep(dir.path(), SWEEP_FAST)).unwrap();
    let long_path = dir.path().join("long.toml");
    std::fs::write(&long_path, SWEEP_FAST.replace("window_s = 0.03", "window_s = 0.06")).unwrap();
    let long = Sweep::read(&long_path).unwrap();
    let id = short.runs().unwrap()[0].run_id.clone();
    let (a, b) = (dir.path().join("a.h5"), dir.path().join("b.h5"));
    attempt(&long, &a, usize::MAX, CheckpointPolicy::default());
    attempt(&short, &b, usize::MAX, CheckpointPolicy::default());
    let ended = read_runs(&b).unwrap().remove(0);
    let t_end = ended.summary.as_ref().unwrap().evidence["steady_end_s"];
    assert_eq!(ended.status, RunStatus::Steady);
    let rows_ended = read_timeseries(&b, &id).unwrap();
    // a run that ended before end checkpoints were kept: reopened from its last snapshot
    std::fs::remove_file(b.with_file_name(format!("b.h5.{id}.ckpt"))).unwrap();

    let t = reopen_ended(&b, &id, long.snapshot_every).unwrap();
    assert_eq!(t, t_end);
    let rec = read_runs(&b).unwrap().remove(0);
    assert_eq!((rec.status, rec.summary.is_none()), (RunStatus::Running, true));
    let e = reopen_ended(&b, &id, long.snapshot_every).unwrap_err().to_string();
    assert!(e.contains("b.h5") && e.contains(&id) && e.contains("has not ended"), "{e}");
    assert!(reopen_ended(&b, "nope", 7).unwrap_err().to_string().contains("nope"));

    let first = attempt(&long, &b, usize::MAX, CheckpointPolicy::default());
    assert_eq!(first, rows_ended[rows_ended.len() - 1].t_s + 1e-3, "continued at the next output");
    let (ra, rb) = (read_runs(&a).unwrap().remove(0), read_runs(&b).unwrap().remove(0));
    let (sa, sb) = (ra.summary.unwrap(), rb.summary.unwrap());
    assert_eq!((sb.status, sb.evidence["steady_end_s"]), (sa.status, sa.evidence["steady_end_s"]));
    assert!(sb.evidence["steady_end_s"] > t_end + 0.02);
    assert_eq!((sb.final_shape, sb.tank_treading), (sa.final_shape, sa.tank_treading));
    let (rows_a, rows_b) = (read_timeseries(&a, &id).unwrap(), read_timeseries(&b, &id).unwrap());
    assert_eq!(rows_b[..rows_ended.len()], rows_ended[..], "the rows before the reopening are kept");
    assert_eq!(rows_a.len(), rows_b.len());
    for (x, y) in rows_a.iter().zip(&rows_b) {
        assert_eq!(x.t_s, y.t_s);
        let d = (0..3).map(|j| (x.centroid_um[j] - y.centroid_um[j]).abs()).fold(0.0, f64::max);
        assert!(d < 1e-5, "t = {} s: centroids differ by {d} um", x.t_s);
    }
    let (na, nb) = (read_snapshots(&a, &id).unwrap(), read_snapshots(&b, &id).unwrap());
    assert_eq!(na.times_s, nb.times_s, "the same snapshots: the regular ones, the ring, the final state");

    // a failed run is a diagnosis: refused, unchanged
    let c = dir.path().join("c.h5");
    let run = &short.runs().unwrap()[0];
    let mut f = ResultsFile::create_or_open(&c).unwrap();
    let mut w = f.begin_run(&id, &rbc::sweep::run_attrs(run, 5.0), &[[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]]).unwrap();
    w.append_sample(&rows_ended[0]).unwrap();
    w.append_snapshot(0.0, &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).unwrap();
    w.fail("NaN velocity at vertex 3").unwrap();
    drop(f);
    let before = read_runs(&c).unwrap();
    let e = reopen_ended(&c, &id, 7).unwrap_err().to_string();
    assert!(e.contains("c.h5") && e.contains("failed"), "{e}");
    assert_eq!(read_runs(&c).unwrap(), before);

    // a run with penalty walls ended steady: its walls' displacements are not in the results, so
    // a checkpoint of its last snapshot would not fit it: refused, unchanged
    let p = dir.path().join("p.h5");
    let scene = std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/studies/science-6p5-penalty/scene.toml")).unwrap();
    assert!(scene.contains("wall_model = \"penalty\""));
    let attrs = rbc_schema::results::RunAttrs { start_shape: "discocyte".into(), r_init_um: 0.8, y_init_um: 0.8, z_init_um: 0.0, lambda: 5.0, scene };
    let mut f = ResultsFile::create_or_open(&p).unwrap();
    let mut w = f.begin_run(&id, &attrs, &[[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]]).unwrap();
    w.append_sample(&rows_ended[0]).unwrap();
    w.append_snapshot(rows_ended[0].t_s, &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).unwrap();
    w.finish(ended.summary.as_ref().unwrap()).unwrap();
    drop(f);
    let before = read_runs(&p).unwrap();
    assert_eq!(before[0].status, RunStatus::Steady);
    let e = reopen_ended(&p, &id, 7).unwrap_err().to_string();
    assert!(e.contains("p.h5") && e.contains("penalty walls"), "{e}");
    assert_eq!(read_runs(&p).unwrap(), before);
    assert!(!p.with_file_name(format!("p.h5.{id}.ckpt")).exists(), "no checkpoint written");
}

/// The rigid motion of [`Rigid`] for the cell, followed by `TAIL` entries that relax towards a
/// value moving with the cell, as penalty walls' displacements follow the cell's traction
/// (`rbc_solver::dynamics::penalty`: the state is the cell's vertices, then the walls').
struct RigidWithWalls {
    cell: Rigid,
    n_cell: usize,
}

const TAIL: usize = 5;

impl Dynamics for RigidWithWalls {
    fn velocity(&mut self, t_s: f64, x: &[Vector3<f64>], u: &mut [Vector3<f64>]) -> Result<(), SolverError> {
        let n = self.n_cell;
        self.cell.velocity(t_s, &x[..n], &mut u[..n])?;
        for (k, (ui, xi)) in u[n..].iter_mut().zip(&x[n..]).enumerate() {
            let target = Vector3::new(0.1 * (1e3 * t_s + k as f64).sin(), 0.02, 0.0);
            *ui = (target - xi) * 2e3;
        }
        Ok(())
    }
}

/// Run the first run of `sweep` (penalty walls) with [`RigidWithWalls`] into `out`, the observer
/// tapped by `after` and `action` (see [`Tap`]).
fn run_with_walls(sweep: &Sweep, out: &std::path::Path, after: usize, action: Action) {
    use rbc_solver::run::CellOutput;
    let run = sweep.runs().unwrap().remove(0);
    assert!(run.scene_text.contains("wall_model = \"penalty\""));
    let solve = |scene: &Scene, obs: &mut dyn Observer| -> Result<(), SolverError> {
        let mesh = rbc_solver::mesh::sphere(2, 3.6);
        let c0 = Vector3::new(0.0, run.y_init_um, run.z_init_um);
        let mut x: Vec<Vector3<f64>> = mesh.vertices.iter().map(|p| p + c0).collect();
        let n_cell = x.len();
        x.extend(vec![Vector3::zeros(); TAIL]);
        let mut tap = Tap { inner: obs, after, action: action.clone(), seen: 0, first_t: None };
        let mut cell = CellOutput { inner: &mut tap, n_cell };
        Runner::new(run_config(scene)).run(&mut RigidWithWalls { cell: Rigid { c0 }, n_cell }, &mut BogackiShampine::new(), &mesh.triangles, &mut x, &mut cell).map(|_| ())
    };
    execute_run(&solve, CheckpointPolicy::default(), sweep, &run, out).unwrap();
}

/// A run with penalty walls (the state: the cell's vertices, then the walls' displacements)
/// suspended at a checkpoint reports its progress from the cell's part, and resumes from it bit
/// for bit: the frames, the last shape and the progress read the cell's vertices, the
/// checkpoint the whole state. (Until session 23 the sweep took every state entry for a vertex
/// of the cell and refused to resume such a run; `study.sh status` refused to read it.)
#[test]
fn a_penalty_wall_run_suspended_at_a_checkpoint_resumes_bit_for_bit() {
    use rbc::sweep::solver_exec::suspend_path;
    let dir = tempfile::tempdir().unwrap();
    let sweep_path = write_sweep(dir.path(), SWEEP_FAST);
    let base = std::fs::read_to_string(dir.path().join("base.toml")).unwrap();
    std::fs::write(dir.path().join("base.toml"), base.replace("[time]", "wall_model = \"penalty\"\nkappa_w_n_m3 = 1.9e7\n[time]")).unwrap();
    let sweep = Sweep::read(&sweep_path).unwrap();
    let run = sweep.runs().unwrap().remove(0);
    assert!(run.scene_text.contains("wall_model = \"penalty\""));
    let id = run.run_id.clone();
    let go = |out: &std::path::Path, after: usize, action: Action| run_with_walls(&sweep, out, after, action);
    let (a, b) = (dir.path().join("a.h5"), dir.path().join("b.h5"));
    go(&a, usize::MAX, Action::Dies);
    let suspend = suspend_path(&b);
    go(&b, 9, Action::RequestsSuspend(suspend.clone()));
    let rec = read_runs(&b).unwrap().remove(0);
    assert_eq!((rec.status, rec.n_samples), (RunStatus::Running, 9));
    let ck = rbc_schema::checkpoint::read(&b.with_file_name(format!("b.h5.{id}.ckpt"))).unwrap();
    let n_cell = rbc_solver::mesh::sphere(2, 3.6).vertices.len();
    assert_eq!(ck.fields["runner.vertices_um"].len(), 3 * (n_cell + TAIL), "the checkpoint holds the whole state");
    let rows_a = read_timeseries(&a, &id).unwrap();
    let p = rbc::sweep::study::run_progress(&b, &id, &rbc_solver::classify::ClassifyConfig::default(), None).unwrap();
    assert_eq!((p.status.as_str(), p.t_s), ("running", rows_a[8].t_s));
    assert!((p.y_um - rows_a[8].centroid_um[1]).abs() < 1e-9 && (p.velocity_mm_s - U_UM_S * 1e-3).abs() < 1e-6, "{p:?}");
    std::fs::remove_file(&suspend).unwrap();
    go(&b, usize::MAX, Action::Dies);
    assert_eq!(read_timeseries(&a, &id).unwrap(), read_timeseries(&b, &id).unwrap());
    let snaps = read_snapshots(&b, &id).unwrap();
    assert_eq!(read_snapshots(&a, &id).unwrap(), snaps);
    assert!(snaps.vertices_um.iter().all(|v| v.len() == n_cell), "snapshots hold the cell only");
}

/// A run that ends keeps the checkpoint of its end state, and `reopen` continues it from there:
/// with penalty walls too (the state: the cell's vertices, then the walls' displacements, which
/// the results do not hold), reopened under a longer window it ends exactly as the run that had
/// the longer window from the start, bit for bit (rows, snapshots, label). A checkpoint that is
/// not of the run's end (another run's, or one before its last sample) is refused, naming it, and
/// nothing is changed.
#[test]
fn an_ended_penalty_wall_run_reopens_at_its_end_checkpoint_bit_for_bit() {
    use rbc::sweep::reopen::reopen_ended;
    let dir = tempfile::tempdir().unwrap();
    let short_path = write_sweep(dir.path(), SWEEP_FAST);
    let base = std::fs::read_to_string(dir.path().join("base.toml")).unwrap();
    std::fs::write(dir.path().join("base.toml"), base.replace("[time]", "wall_model = \"penalty\"\nkappa_w_n_m3 = 1.9e7\n[time]")).unwrap();
    let short = Sweep::read(&short_path).unwrap();
    let long_path = dir.path().join("long.toml");
    std::fs::write(&long_path, SWEEP_FAST.replace("window_s = 0.03", "window_s = 0.06")).unwrap();
    let long = Sweep::read(&long_path).unwrap();
    let id = short.runs().unwrap()[0].run_id.clone();
    let go = |sweep: &Sweep, out: &std::path::Path| run_with_walls(sweep, out, usize::MAX, Action::Dies);
    let (a, b) = (dir.path().join("a.h5"), dir.path().join("b.h5"));
    go(&long, &a);
    go(&short, &b);
    assert_eq!(read_runs(&b).unwrap()[0].status, RunStatus::Steady);
    let rows_ended = read_timeseries(&b, &id).unwrap();
    let ck_path = b.with_file_name(format!("b.h5.{id}.ckpt"));
    let ck = rbc_schema::checkpoint::read(&ck_path).expect("the end checkpoint is kept");
    let n_cell = rbc_solver::mesh::sphere(2, 3.6).vertices.len();
    assert_eq!(ck.fields["runner.vertices_um"].len(), 3 * (n_cell + TAIL), "it holds the walls' displacements too");
    assert_eq!((ck.t_s, ck.n_samples), (rows_ended.last().unwrap().t_s, rows_ended.len()));
    // the progress table reads an ended run from its results, not from the checkpoint beside it
    let p = rbc::sweep::study::run_progress(&b, &id, &rbc_solver::classify::ClassifyConfig::default(), None).unwrap();
    assert_eq!(p.status, "steady");

    // a checkpoint that is not of the end: refused, nothing changed
    let good = std::fs::read(&ck_path).unwrap();
    let mut early = ck.clone();
    early.n_samples -= 1;
    rbc_schema::checkpoint::write(&ck_path, &early).unwrap();
    let before = read_runs(&b).unwrap();
    let e = reopen_ended(&b, &id, long.snapshot_every).unwrap_err().to_string();
    assert!(e.contains(&format!("b.h5.{id}.ckpt")) && e.contains("not the end checkpoint"), "{e}");
    assert_eq!(read_runs(&b).unwrap(), before);
    std::fs::write(&ck_path, &good).unwrap();

    let t = reopen_ended(&b, &id, long.snapshot_every).unwrap();
    assert_eq!(t, rows_ended.last().unwrap().t_s);
    assert_eq!(read_runs(&b).unwrap()[0].status, RunStatus::Running);
    go(&long, &b);
    let (ra, rb) = (read_runs(&a).unwrap().remove(0), read_runs(&b).unwrap().remove(0));
    assert_eq!(read_timeseries(&a, &id).unwrap(), read_timeseries(&b, &id).unwrap(), "the same rows, bit for bit");
    assert_eq!(read_snapshots(&a, &id).unwrap(), read_snapshots(&b, &id).unwrap());
    let strip = |r: RunRecord| {
        let mut s = r.summary.unwrap();
        s.evidence.remove("wall_s");
        s
    };
    assert_eq!(strip(ra), strip(rb));
}
