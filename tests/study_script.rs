//! `scripts/study.sh` end to end on a small study (capsules in unbounded Poiseuille flow, the
//! real solver): `resume` starts the runs in the background, `save` stops them at a checkpoint
//! and copies their state and a ledger row into the study folder, a second `resume` continues
//! from the saved time (not from 0), and the saved results are one continuous run.

use rbc_schema::results::{read_runs, read_timeseries, RunStatus};
use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn study(cmd: &str, studies: &Path, work: &Path) -> Output {
    study_jobs(cmd, studies, work, 2)
}

fn study_jobs(cmd: &str, studies: &Path, work: &Path, jobs: usize) -> Output {
    let o = study_args(&[cmd, "demo", "--jobs", &jobs.to_string()], studies, work);
    assert!(o.status.success(), "study.sh {cmd}: {}", String::from_utf8_lossy(&o.stderr));
    o
}

/// `study.sh ARGS` on the studies under `studies` (work folder `work`), whatever its exit status.
fn study_args(args: &[&str], studies: &Path, work: &Path) -> Output {
    Command::new("bash")
        .arg(root().join("scripts/study.sh"))
        .args(args)
        .env("RBC_STUDY_ROOT", studies)
        .env("RBC_STUDY_WORK", work)
        .env("RBC_SWEEP_BIN", env!("CARGO_BIN_EXE_rbc-sweep"))
        .output()
        .unwrap()
}

/// Wait until every run has written its first checkpoint (at t = 0), then let them go on a little.
fn wait_for_start(work: &Path, runs: &[&str]) {
    let t0 = Instant::now();
    while !runs.iter().all(|r| rbc_schema::checkpoint::checkpoint_path(&work.join("demo").join(format!("{r}.h5")), r).exists()) {
        assert!(t0.elapsed() < Duration::from_secs(300), "no checkpoint after 5 minutes");
        std::thread::sleep(Duration::from_millis(200));
    }
    std::thread::sleep(Duration::from_secs(2));
}

/// The rows of the demo study's ledger (its header checked, nine columns a row).
fn ledger(studies: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(studies.join("demo/ledger.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("saved_utc,commit,run_id,t_from_s,t_to_s,cpu_s,core_s_per_sim_ms,status,cpu"));
    let rows: Vec<Vec<String>> = lines.map(|l| l.split(',').map(str::to_string).collect()).collect();
    assert!(rows.iter().all(|r| r.len() == 9), "{rows:?}");
    rows
}

/// This machine's CPU as `/proc/cpuinfo` names it, as the ledger records it (commas as semicolons).
fn cpu_model() -> String {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap();
    let line = info.lines().find(|l| l.starts_with("model name")).expect("a model name in /proc/cpuinfo");
    line.split_once(':').unwrap().1.trim().replace(',', ";")
}

/// A study `demo` under `dir/studies` (work folder `dir/work`): the demo sweep at 1 mm/s up to
/// 100 s, edited by `edit`. Returns the studies root, the work folder, the study folder and the sweep text.
fn demo_study(dir: &Path, edit: impl Fn(String) -> String) -> (std::path::PathBuf, std::path::PathBuf, std::path::PathBuf, String) {
    let (studies, work) = (dir.join("studies"), dir.join("work"));
    let folder = studies.join("demo");
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::copy(root().join("examples/sweeps/demo-capsule.toml"), folder.join("demo-capsule.toml")).unwrap();
    let sweep = std::fs::read_to_string(root().join("examples/sweeps/demo-poiseuille.toml")).unwrap();
    let sweep = edit(sweep.replace("mean_velocity_mm_s = [0.5, 1.0]", "mean_velocity_mm_s = [1.0]").replace("max_time_s = 0.2", "max_time_s = 100.0"));
    std::fs::write(folder.join("sweep.toml"), &sweep).unwrap();
    (studies, work, folder, sweep)
}

/// [`demo_study`] with a steady window no run can fill here (the runs go on until saved), resumed,
/// its two runs past their first checkpoint. Returns the studies root, the work folder, the study
/// folder and the run ids.
fn running_demo(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf, std::path::PathBuf, [&'static str; 2]) {
    let (studies, work, folder, _) = demo_study(dir, |s| s.replace("window_s = 0.05", "window_s = 50.0"));
    let runs = ["capsule_u1_r0", "capsule_u1_r1"];
    study("resume", &studies, &work);
    wait_for_start(&work, &runs);
    (studies, work, folder, runs)
}

#[test]
fn resume_save_resume_continues_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let (studies, work, folder, runs) = running_demo(dir.path());
    study("save", &studies, &work);
    let first = ledger(&studies);
    let svg = std::fs::read_to_string(folder.join("trajectories.svg")).expect("save draws trajectories.svg");
    assert!(runs.iter().all(|id| svg.contains(id)), "the figure names every run");
    assert_eq!(first.len(), 2, "{first:?}");
    let mut saved_t = Vec::new();
    for (row, id) in first.iter().zip(runs) {
        assert_eq!((row[2].as_str(), row[3].as_str(), row[7].as_str()), (id, "0", "running"), "{row:?}");
        assert!(!row[8].is_empty() && row[8] == cpu_model(), "the CPU that computed the stretch: {row:?}");
        let t: f64 = row[4].parse().unwrap();
        assert!(t > 0.0, "{row:?}");
        let state = folder.join("state").join(format!("{id}.h5"));
        assert_eq!(read_runs(&state).unwrap()[0].status, RunStatus::Running);
        assert!(folder.join("state").join(format!("{id}.h5.{id}.ckpt")).exists());
        assert_eq!(read_timeseries(&state, id).unwrap().last().unwrap().t_s, t, "the state ends at the ledger's time");
        saved_t.push(t);
    }
    // the status table reads the saved state
    let table = String::from_utf8(study("status", &studies, &work).stdout).unwrap();
    for id in runs {
        assert!(table.lines().any(|l| l.starts_with(&format!("| {id} | running | "))), "{table}");
    }

    // a sibling study of the same grid that holds one of the runs: the next save draws that run
    // of both studies into vs-other.svg, each labelled by its study
    let sibling = studies.join("other/state");
    std::fs::create_dir_all(&sibling).unwrap();
    std::fs::copy(folder.join("state").join(format!("{}.h5", runs[0])), sibling.join(format!("{}.h5", runs[0]))).unwrap();
    std::fs::write(folder.join("compare-with"), "other\n").unwrap();

    // a ledger written before the column cpu (session 30): the next save adds the column, empty
    // in the old rows
    let path = folder.join("ledger.csv");
    let old: String = std::fs::read_to_string(&path).unwrap().lines().map(|l| format!("{}\n", l.rsplit_once(',').unwrap().0)).collect();
    assert!(old.starts_with("saved_utc,commit,run_id,t_from_s,t_to_s,cpu_s,core_s_per_sim_ms,status\n"), "{old}");
    std::fs::write(&path, old).unwrap();

    // a fresh work folder (another machine): resumes from the saved time
    let work2 = dir.path().join("work2");
    study("resume", &studies, &work2);
    let starts: Vec<f64> = runs
        .iter()
        .map(|r| std::fs::read_to_string(work2.join("demo").join(format!("{r}.start"))).unwrap().split_whitespace().next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(starts, saved_t, "resumed at the saved times");
    std::thread::sleep(Duration::from_secs(2));
    study("save", &studies, &work2);
    let second = ledger(&studies);
    assert_eq!(second.len(), 4);
    assert!(second[..2].iter().all(|r| r[8].is_empty()) && second[2..].iter().all(|r| r[8] == cpu_model()), "{second:?}");
    assert_eq!(second[..2].iter().map(|r| r[..8].to_vec()).collect::<Vec<_>>(), first.iter().map(|r| r[..8].to_vec()).collect::<Vec<_>>(), "the old rows kept");
    for (k, id) in runs.iter().enumerate() {
        // the run says where it resumed (its log is rbc-sweep's stderr)
        let log = std::fs::read_to_string(work2.join("demo").join(format!("{id}.log"))).unwrap();
        let said = format!("{id}: resumed from its checkpoint at t = {:.6} s", saved_t[k]);
        assert!(log.contains(&said), "{said} not in {log}");
        let row = &second[2 + k];
        assert_eq!(row[3].parse::<f64>().unwrap(), saved_t[k], "the second stretch starts where the first ended: {row:?}");
        assert!(row[4].parse::<f64>().unwrap() >= saved_t[k]);
        // one continuous run: rows from t = 0, strictly increasing, through the first save
        let rows = read_timeseries(&folder.join("state").join(format!("{id}.h5")), id).unwrap();
        assert_eq!(rows[0].t_s, 0.0);
        assert!(rows.windows(2).all(|w| w[1].t_s > w[0].t_s));
        assert!(rows.iter().any(|r| r.t_s == saved_t[k]));
    }
    let vs = std::fs::read_to_string(folder.join("vs-other.svg")).expect("save draws the runs beside the sibling study");
    assert!(vs.contains(&format!("{} (other)", runs[0])) && vs.contains(&format!("{} (demo)", runs[0])), "both studies' run, labelled");
    assert!(!vs.contains(runs[1]), "only the runs both studies hold");
}

/// Wait until run `run` of the study in `work` has ended on its own (its wrapper records its CPU time).
fn wait_for_end(work: &Path, run: &str) {
    let t0 = Instant::now();
    while !work.join("demo").join(format!("{run}.cpu")).exists() {
        assert!(t0.elapsed() < Duration::from_secs(600), "{run} did not end within 10 minutes");
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// Whether run `run` of the demo study is still running (its wrapper's pid is alive).
fn still_running(work: &Path, run: &str) -> bool {
    let pid = std::fs::read_to_string(work.join(format!("demo/{run}.pid"))).unwrap();
    Path::new("/proc").join(pid.trim()).exists()
}

/// The demo study's refill log once it holds `line` (within a minute of the call; as soon as it
/// does, so lines the refill writes later may be missing).
fn refill_log_with(work: &Path, line: &str) -> String {
    let t0 = Instant::now();
    let log = work.join("demo/refill.log");
    loop {
        match std::fs::read_to_string(&log) {
            Ok(l) if l.contains(line) => return l,
            other => assert!(t0.elapsed() < Duration::from_secs(60), "no refill line {line:?}: {other:?}"),
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// A run that ends on its own (steady) between two saves gets one ledger row with the CPU time
/// its wrapper recorded, and no further row at the next save; `reopen` (after the steady window
/// was made longer) sets it back to running at its end with a `reopened` row, and the next
/// `resume` continues it from there to its new steady state: one continuous run.
#[test]
fn an_ended_run_is_ledgered_once_and_reopened_continues_from_its_end() {
    let dir = tempfile::tempdir().unwrap();
    let (studies, work, folder, sweep) = demo_study(dir.path(), |s| s.replace("r_init_um = [0.0, 1.0]", "r_init_um = [0.0]"));
    let (id, state) = ("capsule_u1_r0", folder.join("state/capsule_u1_r0.h5"));

    study("resume", &studies, &work);
    wait_for_end(&work, id);
    study("save", &studies, &work);
    study("save", &studies, &work);
    let rows = ledger(&studies);
    assert_eq!(rows.len(), 1, "one row for the stretch that ended, none for the second save: {rows:?}");
    assert_eq!((rows[0][3].as_str(), rows[0][7].as_str()), ("0", "steady"), "{rows:?}");
    let (t_end, cpu): (f64, f64) = (rows[0][4].parse().unwrap(), rows[0][5].parse().unwrap());
    assert!(t_end >= 0.05 && cpu > 0.0, "{rows:?}");
    assert_eq!(read_runs(&state).unwrap()[0].status, RunStatus::Steady);
    // relabel: the ended run's label decided again from its stored evidence under the same rule
    // (unchanged; its steady state was carried to 10 mm when it ended), the ledger untouched
    let shape = read_runs(&state).unwrap()[0].summary.clone().unwrap().final_shape;
    let o = study("relabel", &studies, &work);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&format!("run {id}: {} (unchanged)\n", shape.as_str())), "{err}");
    assert_eq!(ledger(&studies).len(), 1);

    std::fs::write(folder.join("sweep.toml"), sweep.replace("window_s = 0.05", "window_s = 0.08")).unwrap();
    let o = study_args(&["reopen", "demo", id], &studies, &work);
    assert!(o.status.success(), "study.sh reopen: {}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(read_runs(&state).unwrap()[0].status, RunStatus::Running);
    let rows = ledger(&studies);
    assert_eq!((rows[1][3].parse::<f64>().unwrap(), rows[1][7].as_str(), rows[1][8].as_str()), (t_end, "reopened", cpu_model().as_str()), "{rows:?}");

    study("resume", &studies, &work);
    wait_for_end(&work, id);
    study("save", &studies, &work);
    let rows = ledger(&studies);
    assert_eq!(rows.len(), 3, "{rows:?}");
    assert_eq!((rows[2][3].parse::<f64>().unwrap(), rows[2][7].as_str()), (t_end, "steady"), "{rows:?}");
    let t2: f64 = rows[2][4].parse().unwrap();
    assert!(t2 >= t_end + 0.03 - 1e-9, "the longer window ends later: {rows:?}");
    let log = std::fs::read_to_string(work.join("demo").join(format!("{id}.log"))).unwrap();
    assert!(log.contains(&format!("{id}: resumed from its checkpoint at t = {t_end:.6} s")), "{log}");
    let series = read_timeseries(&state, id).unwrap();
    assert_eq!(series[0].t_s, 0.0);
    assert!(series.windows(2).all(|w| (w[1].t_s - w[0].t_s - 1e-3).abs() < 1e-12), "every output, no gap or repeat");
    assert_eq!(series.last().unwrap().t_s, t2);
}

/// With one job for two runs the second waits; when the first ends on its own the second starts
/// by itself (with the same binary), and a `resume` in between keeps the first's ended work copy
/// for `save` instead of restarting it from the saved state: `save` then ledgers both stretches
/// from t = 0 to their ends.
#[test]
fn a_run_that_ends_frees_its_job_for_the_next() {
    let dir = tempfile::tempdir().unwrap();
    // both runs end within 0.1 s of simulated time (steady, or at the end of their time)
    let (studies, work, folder, _) = demo_study(dir.path(), |s| s.replace("max_time_s = 100.0", "max_time_s = 0.1"));
    let runs = ["capsule_u1_r0", "capsule_u1_r1"];

    let o = study_jobs("resume", &studies, &work, 1);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&format!("study.sh: {} waits (--jobs 1)", runs[1])), "{err}");
    wait_for_end(&work, runs[0]);
    // the first run ended (its stretch unsaved): a resume keeps it, nothing restarts it
    let o = study_jobs("resume", &studies, &work, 1);
    let err = String::from_utf8_lossy(&o.stderr);
    let first = read_runs(&work.join("demo").join(format!("{}.h5", runs[0]))).unwrap()[0].status;
    assert_ne!(first, RunStatus::Running);
    assert!(err.contains(&format!("study.sh: {} ended here ({}) since the last save: kept for save", runs[0], first.as_str())), "{err}");
    wait_for_end(&work, runs[1]);
    let refill = std::fs::read_to_string(work.join("demo/refill.log")).unwrap();
    assert!(refill.contains(&format!("study.sh: {} resumed from t = 0", runs[1])), "{refill}");
    study_jobs("save", &studies, &work, 1);
    let rows = ledger(&studies);
    assert_eq!(rows.len(), 2, "{rows:?}");
    for (row, id) in rows.iter().zip(runs) {
        let state = folder.join("state").join(format!("{id}.h5"));
        let status = read_runs(&state).unwrap()[0].status;
        assert_ne!(status, RunStatus::Running);
        assert_eq!((row[2].as_str(), row[3].as_str(), row[7].as_str()), (id, "0", status.as_str()), "{row:?}");
        assert_eq!(read_timeseries(&state, id).unwrap().last().unwrap().t_s, row[4].parse::<f64>().unwrap());
    }
}

/// A binary given by `RBC_SWEEP_BIN` that is older than the last commit changing the solver is
/// named in a warning (the ledger records HEAD as the runs' commit, session 17's stale resume);
/// the same binary with a fresh time stamp is taken without one.
#[test]
fn a_sweep_binary_older_than_the_solver_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let (studies, work, _, _) = demo_study(dir.path(), |s| s);
    let bin = dir.path().join("rbc-sweep");
    std::fs::copy(env!("CARGO_BIN_EXE_rbc-sweep"), &bin).unwrap();
    let status = |stamp: &str| {
        let touched = Command::new("touch").args(["-d", stamp]).arg(&bin).status().unwrap();
        assert!(touched.success());
        let _ = std::fs::remove_dir_all(&work);
        let o = Command::new("bash")
            .arg(root().join("scripts/study.sh"))
            .args(["status", "demo"])
            .env("RBC_STUDY_ROOT", &studies)
            .env("RBC_STUDY_WORK", &work)
            .env("RBC_SWEEP_BIN", &bin)
            .output()
            .unwrap();
        assert!(o.status.success(), "study.sh status: {}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let old = status("2000-01-01");
    assert!(old.contains("warning: RBC_SWEEP_BIN") && old.contains("is older than the last commit that changed the solver"), "{old}");
    let fresh = status("now");
    assert!(!fresh.contains("warning"), "{fresh}");
}

/// Replace the study's copy of rbc-sweep in `work` by a stand-in that refuses `--list` as a build
/// older than the sweep's settings would, and hands everything else to the real binary.
fn make_study_binary_older_than_its_sweep(work: &Path) {
    use std::os::unix::fs::PermissionsExt;
    let (bin, real) = (work.join("demo/bin/rbc-sweep"), work.join("demo/bin/rbc-sweep.real"));
    std::fs::rename(&bin, &real).unwrap();
    let stand_in = format!(
        "#!/bin/sh\nfor a in \"$@\"; do if [ \"$a\" = --list ]; then echo \"rbc-sweep: sweep.toml: unknown field\" >&2; exit 2; fi; done\nexec '{}' \"$@\"\n",
        real.display()
    );
    std::fs::write(&bin, stand_in).unwrap();
    std::fs::set_permissions(&bin, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// A sweep edited while the runs go on may gain a setting the study's binary does not read
/// (session 21's `classify.frame_travel_um`): `save` then lists the runs with this checkout's
/// binary, says so, and saves them.
#[test]
fn a_sweep_newer_than_the_studys_binary_is_still_saved() {
    let dir = tempfile::tempdir().unwrap();
    let (studies, work, folder, runs) = running_demo(dir.path());
    make_study_binary_older_than_its_sweep(&work);
    let o = study("save", &studies, &work);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("does not read") && err.contains("reading it with this checkout's"), "{err}");
    let rows = ledger(&studies);
    assert_eq!(rows.iter().map(|r| r[2].as_str()).collect::<Vec<_>>(), runs, "{rows:?}");
    for id in runs {
        let state = folder.join("state").join(format!("{id}.h5"));
        assert!(read_timeseries(&state, id).unwrap().last().unwrap().t_s > 0.0, "{id} saved");
        assert!(!work.join(format!("demo/{id}.pid")).exists(), "{id} stopped");
    }
}

/// A run that ends hands its job on by a refill with the study's binary; when that binary no
/// longer reads the sweep (edited since), the refill starts nothing and says why (the waiting run
/// starts at the next resume) instead of failing silently.
#[test]
fn a_refill_with_a_binary_older_than_the_sweep_says_why_it_starts_nothing() {
    let dir = tempfile::tempdir().unwrap();
    // the first run cannot end before 0.4 s of simulated time (its steady window; ~4 s here): the
    // stand-in is in place by then
    let (studies, work, _, _) = demo_study(dir.path(), |s| s.replace("max_time_s = 100.0", "max_time_s = 0.5").replace("window_s = 0.05", "window_s = 0.4"));
    let runs = ["capsule_u1_r0", "capsule_u1_r1"];
    study_jobs("resume", &studies, &work, 1);
    make_study_binary_older_than_its_sweep(&work);
    assert!(still_running(&work, runs[0]), "the first run still runs when the stand-in is in place");
    wait_for_end(&work, runs[0]);
    let refill = refill_log_with(&work, "refill:");
    assert!(refill.contains("does not read") && refill.contains("no run started"), "{refill}");
    assert!(!refill.contains("resumed from") && !work.join(format!("demo/{}.pid", runs[1])).exists(), "the waiting run did not start: {refill}");
}

/// While the study runs, a run with saved state that waits for a job (`--jobs 1` for two) shows as
/// `waiting` in the status table, the one that runs as `running`; saved, with nothing running,
/// both are `running` again (unfinished).
#[test]
fn the_status_table_says_which_unfinished_run_waits_for_a_job() {
    let dir = tempfile::tempdir().unwrap();
    let (studies, work, _, runs) = running_demo(dir.path());
    study("save", &studies, &work);
    let o = study_jobs("resume", &studies, &work, 1);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&format!("study.sh: {} waits (--jobs 1)", runs[1])), "{err}");
    let table = String::from_utf8(study_jobs("status", &studies, &work, 1).stdout).unwrap();
    let status = |table: &str, id: &str| table.lines().find(|l| l.starts_with(&format!("| {id} | "))).map(|l| l.split(" | ").nth(1).unwrap().to_string());
    assert_eq!((status(&table, runs[0]).as_deref(), status(&table, runs[1]).as_deref()), (Some("running"), Some("waiting")), "{table}");
    study_jobs("save", &studies, &work, 1);
    let table = String::from_utf8(study_jobs("status", &studies, &work, 1).stdout).unwrap();
    assert_eq!((status(&table, runs[0]).as_deref(), status(&table, runs[1]).as_deref()), (Some("running"), Some("running")), "{table}");
}

/// `resume --first RUN` gives the named run the job before the sweep's first run (`--jobs 1` for
/// two: the sweep's second runs, its first waits); a name that is no run of the sweep is refused
/// with one line and starts nothing.
#[test]
fn the_runs_named_first_take_the_jobs_first() {
    let dir = tempfile::tempdir().unwrap();
    let (studies, work, _, _) = demo_study(dir.path(), |s| s.replace("window_s = 0.05", "window_s = 50.0"));
    let runs = ["capsule_u1_r0", "capsule_u1_r1"];
    let resume_first = |first: &str| study_args(&["resume", "demo", "--jobs", "1", "--first", first], &studies, &work);
    let o = resume_first("capsule_u1_r9");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("study.sh: --first: no run capsule_u1_r9 in "), "{err}");
    assert!(runs.iter().all(|r| !work.join(format!("demo/{r}.pid")).exists()), "nothing started");
    let o = resume_first(runs[1]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains(&format!("study.sh: {} resumed from t = 0", runs[1])), "{err}");
    assert!(err.contains(&format!("study.sh: {} waits (--jobs 1)", runs[0])), "{err}");
    wait_for_start(&work, &runs[1..]);
    study_jobs("save", &studies, &work, 1);
}

/// Without `--first`, the study's file `first` names the runs that take the jobs first (comments
/// and blank lines skipped); `--first` overrides it, and a name in it that is no run of the sweep
/// is refused as from the flag.
#[test]
fn the_studys_file_first_orders_the_jobs_unless_the_flag_does() {
    let dir = tempfile::tempdir().unwrap();
    let (studies, work, folder, _) = demo_study(dir.path(), |s| s.replace("window_s = 0.05", "window_s = 50.0"));
    let runs = ["capsule_u1_r0", "capsule_u1_r1"];
    let resume = |extra: &[&str]| {
        let o = study_args(&[&["resume", "demo", "--jobs", "1"], extra].concat(), &studies, &work);
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    std::fs::write(folder.join("first"), "# the second run first\n\ncapsule_u1_r9  # no such run\n").unwrap();
    let (ok, err) = resume(&[]);
    assert!(!ok && err.contains("study.sh: --first: no run capsule_u1_r9 in "), "{err}");
    std::fs::write(folder.join("first"), format!("# the second run first\n\n{}  # a comment\n", runs[1])).unwrap();
    let (ok, err) = resume(&[]);
    assert!(ok && err.contains(&format!("study.sh: {} resumed from t = 0", runs[1])) && err.contains(&format!("study.sh: {} waits (--jobs 1)", runs[0])), "{err}");
    wait_for_start(&work, &runs[1..]);
    // the run that has not started is listed too: waiting while the study runs, else not started
    let row = |id: &str| {
        let table = String::from_utf8(study_jobs("status", &studies, &work, 1).stdout).unwrap();
        table.lines().find(|l| l.starts_with(&format!("| {id} | "))).map(|l| l.split(" | ").skip(1).take(2).collect::<Vec<_>>().join(" ")).unwrap_or_else(|| panic!("no row {id} in\n{table}"))
    };
    assert_eq!(row(runs[0]), "waiting 0.00");
    assert!(row(runs[1]).starts_with("running "));
    // with a cell for each of the header's columns
    let table = String::from_utf8(study_jobs("status", &studies, &work, 1).stdout).unwrap();
    let cells = |prefix: &str| table.lines().find(|l| l.starts_with(prefix)).map(|l| l.matches('|').count()).unwrap_or_else(|| panic!("no {prefix} in\n{table}"));
    assert_eq!(cells(&format!("| {} | ", runs[0])), cells("| run | "), "{table}");
    study_jobs("save", &studies, &work, 1);
    assert_eq!(row(runs[0]), "not started 0.00");
    // the flag wins over the file
    let (ok, err) = resume(&["--first", runs[0]]);
    assert!(ok && err.contains(&format!("study.sh: {} resumed from t = ", runs[0])) && err.contains(&format!("study.sh: {} waits (--jobs 1)", runs[1])), "{err}");
    wait_for_start(&work, &runs[..1]);
    study_jobs("save", &studies, &work, 1);
}

/// A refill reads the study's file `first` as it is when a run ends, not as it was at the resume:
/// a run queued there while the study runs takes the next free job (session 49: a run appended to
/// the penalty study and put ahead in `first` lost the freed job to the next run of the old
/// order). Three runs, one job: the resume starts the first; `first` then names the third next,
/// and when the first ends the refill starts the third while the second waits.
#[test]
fn a_refill_takes_the_order_of_the_file_first_as_it_is_then() {
    let dir = tempfile::tempdir().unwrap();
    // the first run cannot end before 0.4 s of simulated time (its steady window; ~4 s here): the
    // file is edited by then
    let (studies, work, folder, _) = demo_study(dir.path(), |s| {
        s.replace("max_time_s = 100.0", "max_time_s = 0.5").replace("window_s = 0.05", "window_s = 0.4").replace("r_init_um = [0.0, 1.0]", "r_init_um = [0.0, 1.0, 2.0]")
    });
    let runs = ["capsule_u1_r0", "capsule_u1_r1", "capsule_u1_r2"];
    std::fs::write(folder.join("first"), format!("{}\n", runs[0])).unwrap();
    let o = study_jobs("resume", &studies, &work, 1);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&format!("study.sh: {} resumed from t = 0", runs[0])) && err.contains(&format!("study.sh: {} waits (--jobs 1)", runs[1])), "{err}");
    std::fs::write(folder.join("first"), format!("{}\n{}  # queued while the study runs\n", runs[0], runs[2])).unwrap();
    assert!(still_running(&work, runs[0]), "the first run still runs when the file is edited");
    wait_for_end(&work, runs[0]);
    // the refill writes the started run's line before the waiting run's: wait for the last one
    // (reading at the first, under load, raced the second, CI of session 52)
    let refill = refill_log_with(&work, &format!("study.sh: {} waits", runs[1]));
    assert!(refill.contains(&format!("study.sh: {} resumed from t = 0", runs[2])) && refill.contains(&format!("study.sh: {} waits (--jobs 1)", runs[1])), "{refill}");
    study_jobs("save", &studies, &work, 1);
}

/// A run that ended says so (`nothing to do`) when the jobs are already taken by runs before it,
/// not that it waits: both demo runs end and are saved, the second is reopened under a window it
/// cannot fill and a later end time, and named `--first` for the one job.
#[test]
fn an_ended_run_behind_the_taken_jobs_has_nothing_to_do() {
    let dir = tempfile::tempdir().unwrap();
    // both runs end within 0.1 s of simulated time (steady, or at the end of their time)
    let (studies, work, folder, sweep) = demo_study(dir.path(), |s| s.replace("max_time_s = 100.0", "max_time_s = 0.1"));
    let runs = ["capsule_u1_r0", "capsule_u1_r1"];
    study("resume", &studies, &work);
    for r in runs {
        wait_for_end(&work, r);
    }
    study("save", &studies, &work);
    std::fs::write(folder.join("sweep.toml"), sweep.replace("window_s = 0.05", "window_s = 50.0").replace("max_time_s = 0.1", "max_time_s = 100.0")).unwrap();
    let script = |args: &[&str]| {
        let o = study_args(args, &studies, &work);
        assert!(o.status.success(), "study.sh {args:?}: {}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    script(&["reopen", "demo", runs[1]]);
    let status = read_runs(&folder.join(format!("state/{}.h5", runs[0]))).unwrap()[0].status;
    assert_ne!(status, RunStatus::Running);
    let err = script(&["resume", "demo", "--jobs", "1", "--first", runs[1]]);
    assert!(err.contains(&format!("study.sh: {} resumed from t = ", runs[1])), "{err}");
    assert!(err.contains(&format!("study.sh: {} is {} at t = ", runs[0], status.as_str())) && err.contains(": nothing to do"), "{err}");
    assert!(!err.contains(&format!("study.sh: {} waits", runs[0])), "{err}");
    wait_for_start(&work, &runs[1..]);
    study_jobs("save", &studies, &work, 1);
}

/// `status` names, on stderr, the runs of the saved state whose cell turned over or folded, with
/// how many times and the intervals (`rbc-sweep events`), and no run whose cell never did: here the
/// paper's-walls study's ~0.32 mm/s slipper (7 folds, the last interval 0.9608 s) beside its
/// ~0.5 mm/s croissant start (none), in a copy of that study.
#[test]
fn status_names_the_runs_whose_cell_turned_over_or_folded() {
    let dir = tempfile::tempdir().unwrap();
    let (studies, work) = (dir.path().join("studies"), dir.path().join("work"));
    let from = root().join("examples/studies/science-6p5-penalty");
    let to = studies.join("fold");
    std::fs::create_dir_all(to.join("state")).unwrap();
    for f in ["sweep.toml", "scene.toml", "starts.h5"] {
        std::fs::copy(from.join(f), to.join(f)).unwrap();
    }
    for run in ["discocyte_u0.2_r1.2", "croissant_u0.31_r0.2"] {
        std::fs::copy(from.join(format!("state/{run}.h5")), to.join(format!("state/{run}.h5"))).unwrap();
    }
    let o = study_args(&["status", "fold"], &studies, &work);
    assert!(o.status.success(), "study.sh status: {}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("study.sh: saved state: ")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(lines[0].contains("discocyte_u0.2_r1.2") && lines[0].contains("7 collapse(s)") && lines[0].contains("the last 0.9608 s"), "{}", lines[0]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("| discocyte_u0.2_r1.2 | periodic |"), "the table is on stdout");
}
