//! Slurm output of `rbc-sweep --slurm`: script content, and the scripts executed by bash with a
//! stand-in `rbc-sweep` and `sbatch` that record their arguments (task indexing, part names,
//! merge glob, job dependency). Also the binary's --list, --slurm, --merge and input errors.

mod sweep_common;

use rbc::sweep::slurm::{shell_quote, write_slurm};
use rbc_schema::sweep::Sweep;
use std::path::Path;
use std::process::Command;
use sweep_common::*;

/// A stand-in executable that appends its arguments (one per line, then `--`) to `log`.
fn recorder(dir: &Path, name: &str, log: &Path, stdout: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, format!("#!/bin/bash\nfor a in \"$@\"; do echo \"$a\" >> {}; done\necho -- >> {}\necho '{stdout}'\n", shell_quote(&log.to_string_lossy()), shell_quote(&log.to_string_lossy()))).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
    p
}

#[test]
fn array_and_merge_scripts_call_the_right_tasks() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP)).unwrap();
    let runs = sweep.runs().unwrap();
    let bin = dir.path().join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let log = dir.path().join("calls.log");
    let exe = recorder(&bin, "rbc-sweep", &log, "");
    let slurm = dir.path().join("slurm dir"); // a space in the path must survive quoting
    let files = write_slurm(&sweep, &runs, &slurm, &exe).unwrap();
    assert_eq!(files.len(), 4);
    // written as one set (staged beside the folder): the scripts keep their executable bit
    {
        use std::os::unix::fs::PermissionsExt;
        for (name, mode) in [("submit.sh", 0o755), ("merge.sbatch", 0o755), ("rbc-sweep.sbatch", 0o755)] {
            assert_eq!(std::fs::metadata(slurm.join(name)).unwrap().permissions().mode() & 0o777, mode, "{name}");
        }
    }
    let array = std::fs::read_to_string(slurm.join("rbc-sweep.sbatch")).unwrap();
    for line in [
        "#SBATCH --array=0-23%4",
        "#SBATCH --cpus-per-task=2",
        "#SBATCH --time=2-00:00:00",
        "#SBATCH --partition=compute",
        "#SBATCH --constraint=avx2",
        "#SBATCH --open-mode=append",
        "#SBATCH --requeue",
        "#SBATCH --signal=B:USR1@600",
    ] {
        assert!(
            array.lines().any(|l| l == line),
            "missing `{line}` in\n{array}"
        );
    }
    let tsv = std::fs::read_to_string(slurm.join("runs.tsv")).unwrap();
    assert_eq!(tsv.lines().count(), 25);
    assert_eq!(
        tsv.lines().nth(6).unwrap(),
        format!("5\t{}\tdiscocyte\t2.5\t0.4", runs[5].run_id)
    );
    assert!(slurm.join("parts").is_dir() && slurm.join("logs").is_dir());

    // run task 5 of the array script as Slurm would
    let st = Command::new("bash")
        .arg(slurm.join("rbc-sweep.sbatch"))
        .env("SLURM_ARRAY_TASK_ID", "5")
        .status()
        .unwrap();
    assert!(st.success());
    let sweep_abs = std::path::absolute(&sweep.path).unwrap();
    let calls = std::fs::read_to_string(&log).unwrap();
    let expected = format!(
        "task\n{}\n5\n--out\n{}\n--\n",
        sweep_abs.display(),
        slurm.join("parts/5.h5").display()
    );
    assert_eq!(calls, expected);

    // merge: the glob expands to the parts present
    std::fs::remove_file(&log).unwrap();
    for i in [0, 3] {
        std::fs::write(slurm.join(format!("parts/{i}.h5")), b"").unwrap();
    }
    assert!(Command::new("bash")
        .arg(slurm.join("merge.sbatch"))
        .status()
        .unwrap()
        .success());
    let calls = std::fs::read_to_string(&log).unwrap();
    let expected = format!(
        "merge\n{}\n{}\n--out\n{}\n--\n",
        slurm.join("parts/0.h5").display(),
        slurm.join("parts/3.h5").display(),
        slurm.join("results.h5").display()
    );
    assert_eq!(calls, expected);

    // submit: the merge waits for the array job (sbatch --parsable prints "jobid;cluster")
    std::fs::remove_file(&log).unwrap();
    recorder(&bin, "sbatch", &log, "4242;cluster1");
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    assert!(Command::new("bash")
        .arg(slurm.join("submit.sh"))
        .env("PATH", path)
        .status()
        .unwrap()
        .success());
    let calls = std::fs::read_to_string(&log).unwrap();
    assert_eq!(
        calls,
        "--parsable\nrbc-sweep.sbatch\n--\n--dependency=afterany:4242\nmerge.sbatch\n--\n"
    );
}

/// Near the time limit Slurm sends USR1 to the task's shell (`--signal=B:USR1@S`): the shell asks
/// the run to stop at a checkpoint (`<part>.suspend`), waits for it, removes the request and
/// requeues the task with `scontrol requeue ${SLURM_ARRAY_JOB_ID}_${SLURM_ARRAY_TASK_ID}` (not its
/// job id: one task's job id is the array's, which would requeue every task); a task not signalled
/// is not requeued.
/// Stand-ins: an `rbc-sweep` that runs until the request appears, and a recording `scontrol`.
#[test]
fn a_signalled_task_stops_at_a_checkpoint_and_requeues_itself() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = Sweep::read(&write_sweep(dir.path(), SWEEP)).unwrap();
    let runs = sweep.runs().unwrap();
    let bin = dir.path().join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let log = dir.path().join("run.log");
    let exe = bin.join("rbc-sweep");
    // args: SWEEP --task I --out PART; runs (at most 3 s) until PART.suspend exists
    std::fs::write(&exe, format!("#!/bin/bash\necho started >> {log}\nfor i in $(seq 30); do\n  if [ -e \"$5.suspend\" ]; then echo \"stopped at a checkpoint\" >> {log}; exit 0; fi\n  sleep 0.1\ndone\necho finished >> {log}\n", log = shell_quote(&log.to_string_lossy()))).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&exe, std::fs::Permissions::from_mode(0o755)).unwrap();
    let scontrol_log = dir.path().join("scontrol.log");
    recorder(&bin, "scontrol", &scontrol_log, "");
    let slurm = dir.path().join("slurm");
    write_slurm(&sweep, &runs, &slurm, &exe).unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let task = |signal: bool| {
        let _ = std::fs::remove_file(&log);
        let child = Command::new("bash")
            .arg(slurm.join("rbc-sweep.sbatch"))
            .env("SLURM_ARRAY_TASK_ID", "3")
            .env("SLURM_JOB_ID", "4711")
            .env("SLURM_ARRAY_JOB_ID", "4708")
            .env("PATH", &path)
            .stdout(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        if signal {
            while !std::fs::read_to_string(&log).unwrap_or_default().contains("started") {
                std::thread::sleep(std::time::Duration::from_millis(20));
            }
            assert!(Command::new("kill").args(["-USR1", &child.id().to_string()]).status().unwrap().success());
        }
        let out = child.wait_with_output().unwrap();
        assert!(out.status.success());
        String::from_utf8(out.stdout).unwrap()
    };
    let stdout = task(true);
    assert_eq!(std::fs::read_to_string(&log).unwrap(), "started\nstopped at a checkpoint\n");
    assert_eq!(std::fs::read_to_string(&scontrol_log).unwrap(), "requeue\n4708_3\n--\n");
    assert!(!slurm.join("parts/3.h5.suspend").exists(), "the request is removed for the next attempt");
    assert!(stdout.starts_with("rbc-sweep task 3: job 4711, attempt 1, "), "{stdout}");
    assert!(stdout.trim_end().ends_with("rbc-sweep task 3: stopped at a checkpoint before the time limit, requeued"), "{stdout}");

    // not signalled: the run ends by itself, no requeue
    std::fs::remove_file(&scontrol_log).unwrap();
    task(false);
    assert_eq!(std::fs::read_to_string(&log).unwrap(), "started\nfinished\n");
    assert!(!scontrol_log.exists());
}

fn rbc_sweep(args: &[&str], cwd: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rbc-sweep"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

#[test]
fn cli_list_slurm_merge_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    write_sweep(dir.path(), SWEEP);
    let d = dir.path();
    let o = rbc_sweep(&["sweep.toml", "--list"], d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    assert_eq!(text.lines().count(), 25);
    assert!(text
        .lines()
        .nth(24)
        .unwrap()
        .starts_with("23\tslipper_u6.5_r1.2\tslipper\t6.5\t1.2\t"));

    let o = rbc_sweep(&["sweep.toml", "--slurm", "cluster"], d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let array = std::fs::read_to_string(d.join("cluster/rbc-sweep.sbatch")).unwrap();
    assert!(
        array.contains(env!("CARGO_BIN_EXE_rbc-sweep")),
        "the script calls this binary:\n{array}"
    );

    // merge of two files written by the fake executor
    let sweep = Sweep::read(&d.join("sweep.toml")).unwrap();
    let runs = sweep.runs().unwrap();
    let fake = Fake::new(|_| Mode::Finish);
    fake.execute(&sweep, &runs[0], &d.join("a.h5")).unwrap();
    fake.execute(&sweep, &runs[1], &d.join("b.h5")).unwrap();
    let o = rbc_sweep(&["--merge", "a.h5", "b.h5", "--out", "all.h5"], d);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(statuses(&d.join("all.h5")).len(), 2);
    // the same run twice is refused, naming both files, and writes nothing
    let o = rbc_sweep(&["--merge", "a.h5", "a.h5", "--out", "dup.h5"], d);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("a.h5") && !d.join("dup.h5").exists());

    // bad input: one line naming the file and the field, exit code 2
    std::fs::write(
        d.join("bad.toml"),
        SWEEP.replace("[1.0, 2.5, 6.5]", "[1.0, -2.5]"),
    )
    .unwrap();
    let o = rbc_sweep(&["bad.toml", "--list"], d);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        err.contains("bad.toml") && err.contains("mean_velocity_mm_s") && err.lines().count() == 1,
        "{err}"
    );
    // an override the scene schema refuses is reported per run before anything runs
    std::fs::write(
        d.join("bad2.toml"),
        format!("{SWEEP}\n[overrides]\n\"fluid.lambda\" = -1.0\n"),
    )
    .unwrap();
    let o = rbc_sweep(&["bad2.toml", "--list"], d);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        err.contains("bad2.toml: run discocyte_u1_r0") && err.contains("fluid.lambda"),
        "{err}"
    );
    let o = rbc_sweep(&["sweep.toml", "--task", "99", "--out", "t.h5"], d);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("task index 99"));
    let o = rbc_sweep(&["--merge", "a.h5"], d);
    assert_eq!(o.status.code(), Some(2));
}

/// `scripts/results_equal.py` (the equality of `scripts/slurm_check.sh`): a merge of a file equals
/// it although `created_by` differs, and so does a copy with another `evidence_wall_s`; one value
/// changed by one ulp, an extra attribute or a missing run make it report the path and exit 1.
#[test]
fn results_equal_script_is_bit_strict_except_provenance() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sweep = Sweep::read(&write_sweep(d, SWEEP)).unwrap();
    let runs = sweep.runs().unwrap();
    let fake = Fake::new(|_| Mode::Finish);
    for r in &runs[..2] {
        fake.execute(&sweep, r, &d.join("a.h5")).unwrap();
    }
    rbc_schema::results::merge_files(&[d.join("a.h5")], &d.join("merged.h5")).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/results_equal.py");
    let equal = |a: &str, b: &str| {
        let o = Command::new("python3").arg(&script).arg(d.join(a)).arg(d.join(b)).output().unwrap();
        (o.status.code(), String::from_utf8_lossy(&o.stdout).into_owned())
    };
    // an edit of a copy of merged.h5 with h5py
    let edited = |name: &str, edit: &str| {
        std::fs::copy(d.join("merged.h5"), d.join(name)).unwrap();
        let code = format!("import h5py, numpy as np\nf = h5py.File({:?}, 'r+')\nrun = f['runs/{}']\n{edit}\nf.close()\n", d.join(name).to_string_lossy(), runs[1].run_id);
        let st = Command::new("python3").arg("-c").arg(code).status().unwrap();
        assert!(st.success(), "h5py (scripts/setup.sh installs it) must edit {name}");
    };
    let (code, out) = equal("a.h5", "merged.h5");
    assert_eq!(code, Some(0), "{out}");
    assert!(out.contains("equal (2 runs, "), "{out}");

    edited("wall.h5", "run.attrs['evidence_wall_s'] = 12.5");
    assert_eq!(equal("merged.h5", "wall.h5").0, Some(0));

    edited("ulp.h5", "d = run['timeseries/centroid_um']\nv = d[()]\nv[3, 1] = np.nextafter(v[3, 1], np.inf)\nd[...] = v");
    let (code, out) = equal("merged.h5", "ulp.h5");
    assert_eq!(code, Some(1), "{out}");
    assert!(out.contains(&format!("/runs/{}/timeseries/centroid_um: 1 of 15 values differ", runs[1].run_id)), "{out}");

    edited("attr.h5", "run.attrs['extra'] = 1.0");
    let (code, out) = equal("merged.h5", "attr.h5");
    assert_eq!(code, Some(1), "{out}");
    assert!(out.contains(&format!("/runs/{} attribute extra: only in B", runs[1].run_id)), "{out}");

    edited("norun.h5", "del f['runs/' + run.name.split('/')[-1]]");
    let (code, out) = equal("merged.h5", "norun.h5");
    assert_eq!(code, Some(1), "{out}");
    assert!(out.contains(&format!("/runs/{}: only in A", runs[1].run_id)), "{out}");
}
