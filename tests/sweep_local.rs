//! The local sweep machinery with a fake executor: expansion, a pool of runs gathered into one
//! results.h5, resuming after a kill (finished runs skipped, half-written ones redone, finished
//! parts copied), failed runs kept unless retried, task indexing and the merge of task parts.

mod sweep_common;

use rbc::sweep::local::{parts_dir, plan, run_local, LocalOptions, Planned};
use rbc::sweep::task::{run_task, TaskOutcome};
use rbc::sweep::SweepError;
use rbc_schema::results::*;
use rbc_schema::sweep::Sweep;
use std::collections::BTreeMap;
use sweep_common::*;

fn run_all(
    sweep: &Sweep,
    out: &std::path::Path,
    fake: &Fake,
    jobs: usize,
    retry_failed: bool,
) -> rbc::sweep::local::LocalReport {
    let runs = sweep.runs().unwrap();
    let exec =
        |s: &Sweep, r: &rbc_schema::sweep::SweepRun, o: &std::path::Path| fake.execute(s, r, o);
    let mut seen = Vec::new();
    let report = run_local(
        sweep,
        &runs,
        out,
        &exec,
        &LocalOptions { jobs, retry_failed },
        &mut |id, _| seen.push(id.to_string()),
    )
    .unwrap();
    assert_eq!(
        seen.len(),
        report.done.len() + report.errors.len(),
        "one callback per executed run"
    );
    report
}

#[test]
fn pool_runs_every_run_once_and_a_second_call_skips_them_all() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP)).unwrap();
    let out = dir.path().join("results.h5");
    let fake = Fake::new(|_| Mode::Finish);
    let report = run_all(&sweep, &out, &fake, 3, false);
    assert_eq!(report.done.len(), 24);
    assert!(report.skipped.is_empty() && report.errors.is_empty());
    let ids: Vec<String> = sweep
        .runs()
        .unwrap()
        .iter()
        .map(|r| r.run_id.clone())
        .collect();
    let mut sorted = ids.clone();
    sorted.sort();
    assert_eq!(fake.calls(), sorted, "each run executed exactly once");
    // every run is in the output with its grid attributes and the fake's label
    let recs = read_runs(&out).unwrap();
    assert_eq!(recs.len(), 24);
    for run in sweep.runs().unwrap() {
        let rec = recs.iter().find(|r| r.run_id == run.run_id).unwrap();
        let a = rec.attrs.as_ref().unwrap();
        assert_eq!(
            (
                a.start_shape.as_str(),
                a.r_init_um,
                a.y_init_um,
                a.z_init_um
            ),
            (
                run.start_shape.as_str(),
                run.r_init_um,
                run.y_init_um,
                run.z_init_um
            )
        );
        assert_eq!(a.scene, run.scene_text);
        let s = rec.summary.as_ref().unwrap();
        assert_eq!(s.final_shape, fake_shape(&run));
        assert_eq!(rec.n_samples, 5);
        assert_eq!(rec.n_snapshots, 1);
    }
    assert!(
        !parts_dir(&out).exists(),
        "parts folder removed after a clean sweep"
    );
    // second call: nothing to do
    let fake2 = Fake::new(|_| Mode::Finish);
    let report = run_all(&sweep, &out, &fake2, 3, false);
    assert_eq!((report.skipped.len(), report.done.len()), (24, 0));
    assert!(fake2.calls().is_empty());
}

#[test]
fn a_killed_sweep_continues_without_redoing_finished_runs() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP)).unwrap();
    let out = dir.path().join("results.h5");
    // first attempt: the 6.5 mm/s runs are "killed" half-way (left running in their part files)
    let first = Fake::new(|r| {
        if r.velocity_mm_s == 6.5 {
            Mode::Crash
        } else {
            Mode::Finish
        }
    });
    let report = run_all(&sweep, &out, &first, 2, false);
    assert_eq!((report.done.len(), report.errors.len()), (16, 8));
    assert_eq!(
        statuses(&out).len(),
        16,
        "only complete runs reach the output"
    );
    let parts = parts_dir(&out);
    assert_eq!(
        std::fs::read_dir(&parts).unwrap().count(),
        8,
        "the killed runs' parts remain"
    );

    // a finished part that was not copied yet (killed between execution and copy): copied, not rerun
    let runs = sweep.runs().unwrap();
    let pending = runs
        .iter()
        .find(|r| r.velocity_mm_s == 6.5 && r.start_shape == "discocyte")
        .unwrap();
    Fake::new(|_| Mode::Finish)
        .execute(
            &sweep,
            pending,
            &parts.join(format!("{}.h5", pending.run_id)),
        )
        .unwrap();
    // a run half-copied into the output (status running): redone
    {
        let mut f = ResultsFile::create_or_open(&out).unwrap();
        let victim = runs
            .iter()
            .find(|r| r.velocity_mm_s == 1.0 && r.r_init_um == 0.0 && r.start_shape == "slipper")
            .unwrap();
        f.remove_run(&victim.run_id).unwrap();
        let mut w = f
            .begin_run(&victim.run_id, &rbc::sweep::run_attrs(victim, 5.0), &TETRA)
            .unwrap();
        w.flush().unwrap();
    }
    assert_eq!(
        statuses(&out)
            .values()
            .filter(|s| **s == RunStatus::Running)
            .count(),
        1
    );

    let second = Fake::new(|_| Mode::Finish);
    let report = run_all(&sweep, &out, &second, 2, false);
    assert_eq!(report.skipped.len(), 15);
    assert_eq!(report.done.len(), 9);
    // executed: the 7 killed runs without a finished part + the half-copied one; not the copied part
    let calls = second.calls();
    assert_eq!(calls.len(), 8, "{calls:?}");
    assert!(!calls.contains(&pending.run_id));
    assert!(calls.contains(&"slipper_u1_r0".to_string()));
    let st = statuses(&out);
    assert_eq!(st.len(), 24);
    assert!(st.values().all(|s| s.is_finished()), "{st:?}");
    assert!(!parts.exists());
}

#[test]
fn failed_runs_are_kept_unless_retried() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP)).unwrap();
    let out = dir.path().join("results.h5");
    let first = Fake::new(|r| {
        if r.r_init_um == 1.2 {
            Mode::Fail
        } else {
            Mode::Finish
        }
    });
    let report = run_all(&sweep, &out, &first, 4, false);
    assert_eq!(
        report
            .done
            .iter()
            .filter(|(_, s)| *s == RunStatus::Failed)
            .count(),
        6
    );
    let failed = read_runs(&out)
        .unwrap()
        .into_iter()
        .find(|r| r.status == RunStatus::Failed)
        .unwrap();
    assert_eq!(
        failed.failure.as_deref(),
        Some("fake blow-up at t = 0.04 s")
    );
    // without --retry-failed nothing runs; with it only the failed ones
    let again = Fake::new(|_| Mode::Finish);
    assert_eq!(run_all(&sweep, &out, &again, 4, false).done.len(), 0);
    let retry = Fake::new(|_| Mode::Finish);
    assert_eq!(run_all(&sweep, &out, &retry, 4, true).done.len(), 6);
    assert!(retry.calls().iter().all(|id| id.ends_with("_r1.2")));
    assert!(statuses(&out).values().all(|s| s.is_finished()));
}

/// A finished run is kept only while the sweep still asks for it: after the base scene changed
/// its physics (here the mesh level) a second call is refused with one line naming the output and
/// a run, and changes nothing; a change of the step method or the end time alone keeps every run
/// (as `rbc-simulate --resume` continues such a run).
#[test]
fn a_kept_run_from_another_scene_is_refused_and_a_stepping_change_keeps_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_sweep(dir.path(), SWEEP);
    let sweep = Sweep::read(&path).unwrap();
    let out = dir.path().join("results.h5");
    assert_eq!(run_all(&sweep, &out, &Fake::new(|_| Mode::Finish), 3, false).done.len(), 24);
    let before = std::fs::read(&out).unwrap();
    let base = dir.path().join("base.toml");
    std::fs::write(&base, BASE_SCENE.replace("level = 2", "level = 3")).unwrap();
    let changed = Sweep::read(&path).unwrap();
    let runs = changed.runs().unwrap();
    let fake = Fake::new(|_| Mode::Finish);
    let exec = |s: &Sweep, r: &rbc_schema::sweep::SweepRun, o: &std::path::Path| fake.execute(s, r, o);
    let e = run_local(&changed, &runs, &out, &exec, &LocalOptions { jobs: 2, retry_failed: false }, &mut |_, _| {}).unwrap_err().to_string();
    assert!(e.contains("results.h5") && e.contains("was run from another scene") && e.contains(&runs[0].run_id) && !e.contains('\n'), "{e}");
    assert!(fake.calls().is_empty());
    assert_eq!(std::fs::read(&out).unwrap(), before, "the output untouched");
    // the step method and the end time alone: every run kept
    std::fs::write(&base, BASE_SCENE.replace("end_s = 40.0", "end_s = 60.0") + "[integrator]\natol_um = 1e-3\n").unwrap();
    let stepping = Sweep::read(&path).unwrap();
    let report = run_all(&stepping, &out, &Fake::new(|_| Mode::Finish), 2, false);
    assert_eq!((report.done.len(), report.skipped.len()), (0, 24));
}

#[test]
fn plan_follows_the_statuses() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP)).unwrap();
    let runs = sweep.runs().unwrap();
    let mut existing = BTreeMap::new();
    existing.insert(runs[0].run_id.clone(), RunStatus::Steady);
    existing.insert(runs[1].run_id.clone(), RunStatus::Unsteady);
    existing.insert(runs[2].run_id.clone(), RunStatus::Failed);
    existing.insert(runs[3].run_id.clone(), RunStatus::Running);
    existing.insert("not-in-the-sweep".into(), RunStatus::Steady);
    let p = plan(&existing, &runs, false);
    assert_eq!(
        &p[..5],
        [
            Planned::Skip(RunStatus::Steady),
            Planned::Skip(RunStatus::Unsteady),
            Planned::Skip(RunStatus::Failed),
            Planned::Execute,
            Planned::Execute
        ]
    );
    assert_eq!(plan(&existing, &runs, true)[2], Planned::Execute);
}

#[test]
fn tasks_by_index_then_merge_equal_the_local_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP)).unwrap();
    let runs = sweep.runs().unwrap();
    let fake = Fake::new(|_| Mode::Finish);
    let exec =
        |s: &Sweep, r: &rbc_schema::sweep::SweepRun, o: &std::path::Path| fake.execute(s, r, o);
    let parts = dir.path().join("parts");
    let mut files = Vec::new();
    for i in 0..runs.len() {
        let out = parts.join(format!("{i}.h5"));
        let o = run_task(&sweep, &runs, i, &out, &exec).unwrap();
        assert_eq!(
            o,
            TaskOutcome::Ran {
                run_id: runs[i].run_id.clone(),
                status: if fake_shape(&runs[i]) == FinalShape::Slipper {
                    "periodic".into()
                } else {
                    "steady".into()
                }
            }
        );
        // task i holds exactly run i
        assert_eq!(
            read_runs(&out)
                .unwrap()
                .iter()
                .map(|r| r.run_id.clone())
                .collect::<Vec<_>>(),
            vec![runs[i].run_id.clone()]
        );
        files.push(out);
    }
    // a resubmitted task does nothing
    assert!(matches!(
        run_task(&sweep, &runs, 7, &files[7], &exec).unwrap(),
        TaskOutcome::AlreadyDone { .. }
    ));
    assert_eq!(fake.calls().len(), runs.len());
    assert!(matches!(
        run_task(&sweep, &runs, 24, &parts.join("24.h5"), &exec),
        Err(SweepError::TaskIndex { index: 24, len: 24 })
    ));

    let merged = dir.path().join("merged.h5");
    assert_eq!(merge_files(&files, &merged).unwrap(), 24);
    let local = dir.path().join("local.h5");
    run_all(&sweep, &local, &Fake::new(|_| Mode::Finish), 3, false);
    let strip = |p: &std::path::Path| -> Vec<(String, Option<RunAttrs>, Option<RunSummary>)> {
        read_runs(p)
            .unwrap()
            .into_iter()
            .map(|r| (r.run_id, r.attrs, r.summary))
            .collect()
    };
    assert_eq!(
        strip(&merged),
        strip(&local),
        "cluster parts merged == local sweep"
    );
}

#[test]
fn a_damaged_output_is_rebuilt_from_the_backup_and_the_parts() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP)).unwrap();
    let runs = sweep.runs().unwrap();
    let out = dir.path().join("results.h5");
    // a first complete call: 8 runs (one start shape, two velocities)
    let first: Vec<_> = runs
        .iter()
        .filter(|r| r.start_shape == "discocyte" && r.velocity_mm_s < 6.0)
        .cloned()
        .collect();
    let fake = Fake::new(|_| Mode::Finish);
    let exec =
        |s: &Sweep, r: &rbc_schema::sweep::SweepRun, o: &std::path::Path| fake.execute(s, r, o);
    run_local(
        &sweep,
        &first,
        &out,
        &exec,
        &LocalOptions {
            jobs: 2,
            retry_failed: false,
        },
        &mut |_, _| {},
    )
    .unwrap();
    assert!(
        !rbc::sweep::local::backup_path(&out).exists(),
        "backup removed after a clean call"
    );
    // the second call "dies" after copying 6 runs (a panic in the progress callback stands in for a kill)
    let mut copied = Vec::new();
    let died = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run_local(
            &sweep,
            &runs,
            &out,
            &exec,
            &LocalOptions {
                jobs: 2,
                retry_failed: false,
            },
            &mut |id, _| {
                copied.push(id.to_string());
                if copied.len() == 6 {
                    panic!("killed");
                }
            },
        )
    }));
    assert!(died.is_err());
    assert_eq!(statuses(&out).len(), 14);
    // ... and the kill damaged the HDF5 file
    std::fs::write(&out, b"not an HDF5 file any more").unwrap();
    let again = Fake::new(|_| Mode::Finish);
    let exec2 =
        |s: &Sweep, r: &rbc_schema::sweep::SweepRun, o: &std::path::Path| again.execute(s, r, o);
    let report = run_local(
        &sweep,
        &runs,
        &out,
        &exec2,
        &LocalOptions {
            jobs: 2,
            retry_failed: false,
        },
        &mut |_, _| {},
    )
    .unwrap();
    assert!(report.restored);
    assert_eq!(
        report.skipped.len(),
        8,
        "the first call's runs come back from the backup"
    );
    let st = statuses(&out);
    assert_eq!(st.len(), 24);
    assert!(st.values().all(|s| s.is_finished()));
    // runs finished in the killed call are copied from their parts, not executed again
    let calls = again.calls();
    assert!(
        copied.iter().all(|id| !calls.contains(id)),
        "{copied:?} rerun: {calls:?}"
    );
    assert!(calls.len() <= 24 - 8 - 6, "{} executed again", calls.len());
    assert!(
        rbc::sweep::local::backup_path(&out)
            .with_extension("damaged")
            .exists(),
        "the damaged file is kept aside"
    );
    assert!(!parts_dir(&out).exists());
}

/// The paper's largest offsets put the discocyte into the 12 x 10 um channel's wall (its rim spans
/// 8 um across the flow; at r_init = 2.25 um the rim is ~0.09 um beyond the upper wall): the
/// expansion marks those runs, the local sweep records them with status `overlaps-wall` (never
/// executed, never failed) and runs the others, a second call skips them, a task of one records it
/// too and the merge keeps the record. A start shape whose mesh file is not made yet
/// (`starts.h5`) is said once and its runs are left to the solver.
#[test]
fn runs_overlapping_the_wall_are_recorded_not_run_and_the_others_run() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), &SWEEP.replace("r_init_um = [0.0, 0.4, 0.8, 1.2]", "r_init_um = [0.0, 1.2, 2.25]"))).unwrap();
    let (runs, notes) = rbc::sweep::expand(&sweep).unwrap();
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(notes[0].contains("start shape slipper") && notes[0].contains("not checked"), "{notes:?}");
    let over: Vec<&str> = runs.iter().filter(|r| r.overlaps_wall.is_some()).map(|r| r.run_id.as_str()).collect();
    assert_eq!(over, ["discocyte_u1_r2.25", "discocyte_u2.5_r2.25", "discocyte_u6.5_r2.25"]);
    let why = runs[2].overlaps_wall.as_deref().unwrap();
    assert!(why.starts_with("r_init_um = 2.25: the cell reaches 0.09 um into the wall of the 12 x 10 um channel (walls.width_y_um x walls.height_z_um)"), "{why}");

    let out = dir.path().join("results.h5");
    let fake = Fake::new(|_| Mode::Finish);
    let exec = |s: &Sweep, r: &rbc_schema::sweep::SweepRun, o: &std::path::Path| fake.execute(s, r, o);
    let opts = LocalOptions { jobs: 2, retry_failed: true };
    let report = run_local(&sweep, &runs, &out, &exec, &opts, &mut |_, _| {}).unwrap();
    assert_eq!((report.done.len(), report.errors.len()), (18, 0));
    assert_eq!(fake.calls().len(), 15, "the three overlapping runs are not executed");
    assert!(fake.calls().iter().all(|id| !over.contains(&id.as_str())));
    let recs = read_runs(&out).unwrap();
    for r in &recs {
        if over.contains(&r.run_id.as_str()) {
            assert_eq!(r.status, RunStatus::OverlapsWall);
            assert_eq!((r.n_samples, r.n_snapshots, r.summary.is_none(), r.failure.is_none()), (0, 0, true, true));
            assert!(r.not_run.as_deref().unwrap().contains("into the wall"));
            assert_eq!(r.attrs.as_ref().unwrap().r_init_um, 2.25);
            assert!(read_timeseries(&out, &r.run_id).unwrap().is_empty());
            assert!(read_snapshots(&out, &r.run_id).unwrap().times_s.is_empty());
        } else {
            assert!(r.status.is_finished(), "{}: {:?}", r.run_id, r.status);
        }
    }
    // again (also with --retry-failed): nothing to do
    let again = run_local(&sweep, &runs, &out, &exec, &opts, &mut |_, _| {}).unwrap();
    assert_eq!((again.skipped.len(), again.done.len()), (18, 0));
    assert_eq!(fake.calls().len(), 15);
    // the sweep changed so that the cell fits (a narrower offset under the same id is not possible;
    // an unmarked run stands for it): the recorded run is executed
    let mut fits = runs.clone();
    fits[2].overlaps_wall = None;
    let changed = run_local(&sweep, &fits, &out, &exec, &opts, &mut |_, _| {}).unwrap();
    assert_eq!(changed.done.len(), 1, "{changed:?}");
    assert_eq!(changed.done[0].0, "discocyte_u1_r2.25");
    assert!(changed.done[0].1.is_finished(), "{changed:?}");
    // a task of an overlapping run records it; the merge keeps the record
    let part = dir.path().join("part.h5");
    match run_task(&sweep, &runs, 2, &part, &exec).unwrap() {
        TaskOutcome::Ran { run_id, status } => assert_eq!((run_id.as_str(), status.as_str()), ("discocyte_u1_r2.25", "overlaps-wall")),
        other => panic!("{other:?}"),
    }
    assert!(matches!(run_task(&sweep, &runs, 2, &part, &exec).unwrap(), TaskOutcome::AlreadyDone { .. }));
    let merged = dir.path().join("merged.h5");
    merge_files(&[part], &merged).unwrap();
    let rec = &read_runs(&merged).unwrap()[0];
    assert_eq!((rec.status, rec.not_run.is_some()), (RunStatus::OverlapsWall, true));
}
