//! Slurm array job for a sweep: one task per run index, a merge job, a submit script and the index of runs.
//!
//! `write_slurm` writes into `DIR`:
//! - `rbc-sweep.sbatch`: `#SBATCH --array=0-(N-1)[%max]`, each task runs
//!   `rbc-sweep task SWEEP $SLURM_ARRAY_TASK_ID --out DIR/parts/$SLURM_ARRAY_TASK_ID.h5`
//!   (a resubmitted task whose part already holds its run finished returns at once; a killed
//!   one continues from its last checkpoint). Near the time limit (`--signal=B:USR1@S`, S =
//!   [`stop_before_limit_s`]) the task's shell creates `<part>.suspend`: the run stops at its
//!   next output sample with a checkpoint, and the task requeues itself (`--requeue`,
//!   `scontrol requeue ARRAYID_TASK`) to continue from it; its log grows across attempts
//!   (`--open-mode=append`);
//! - `merge.sbatch`: `rbc-sweep merge DIR/parts/*.h5 --out DIR/results.h5`;
//! - `submit.sh`: submits the array, then the merge with `--dependency=afterany:<array job>`;
//! - `runs.tsv`: `index, run_id, start_shape, velocity_mm_s, r_init_um`, one line per task;
//! - the folders `parts/` and `logs/`.
//!
//! All paths in the scripts are absolute, so the scripts run from any folder.

use super::SweepError;
use rbc_schema::sweep::{Sweep, SweepRun};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Default wall-clock limit per task: the paper's runs took 1 to 29 days on 28 cores.
pub const DEFAULT_TIME: &str = "7-00:00:00";

/// Seconds before the time limit at which a task is told to stop at a checkpoint and requeue:
/// the sweep's `slurm.stop_before_limit_s`, else 600 s but at most a quarter of the limit
/// (`None` without a time limit). Slurm may send the signal up to a minute earlier.
pub fn stop_before_limit_s(sweep: &Sweep) -> Option<u64> {
    let s = &sweep.slurm;
    let limit = rbc_schema::sweep::slurm_time_s(s.time.as_deref().unwrap_or(DEFAULT_TIME)).flatten()?;
    Some(s.stop_before_limit_s.unwrap_or((limit / 4).clamp(1, 600)))
}

/// Quote for a POSIX shell (single quotes; an embedded `'` becomes `'\''`).
pub fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

fn io(path: &Path, e: impl std::fmt::Display) -> SweepError {
    SweepError::Io {
        path: path.into(),
        message: e.to_string(),
    }
}

fn absolute(p: &Path) -> Result<PathBuf, SweepError> {
    std::path::absolute(p).map_err(|e| io(p, e))
}

/// The array script's text.
pub fn array_script(
    sweep: &Sweep,
    n_runs: usize,
    dir: &Path,
    exe: &Path,
    sweep_path: &Path,
) -> String {
    let s = &sweep.slurm;
    let mut t = String::from("#!/bin/bash\n");
    let _ = writeln!(t, "#SBATCH --job-name=rbc-sweep");
    let max = s
        .max_concurrent
        .map(|m| format!("%{m}"))
        .unwrap_or_default();
    let _ = writeln!(t, "#SBATCH --array=0-{}{max}", n_runs.saturating_sub(1));
    let _ = writeln!(t, "#SBATCH --ntasks=1");
    let _ = writeln!(t, "#SBATCH --cpus-per-task={}", sweep.threads_per_run);
    let _ = writeln!(
        t,
        "#SBATCH --time={}",
        s.time.as_deref().unwrap_or(DEFAULT_TIME)
    );
    if let Some(m) = &s.mem {
        let _ = writeln!(t, "#SBATCH --mem={m}");
    }
    if let Some(p) = &s.partition {
        let _ = writeln!(t, "#SBATCH --partition={p}");
    }
    if let Some(a) = &s.account {
        let _ = writeln!(t, "#SBATCH --account={a}");
    }
    let _ = writeln!(
        t,
        "#SBATCH --output={}",
        dir.join("logs/run-%a.out").display()
    );
    t.push_str("#SBATCH --open-mode=append\n#SBATCH --requeue\n");
    let stop = stop_before_limit_s(sweep);
    if let Some(before) = stop {
        let _ = writeln!(t, "#SBATCH --signal=B:USR1@{before}");
    }
    for line in &s.extra {
        let _ = writeln!(t, "{line}");
    }
    t.push_str("set -euo pipefail\n");
    t.push_str("export RAYON_NUM_THREADS=\"${SLURM_CPUS_PER_TASK:-1}\"\n");
    let parts = dir.join("parts");
    let _ = writeln!(t, "part={}/\"$SLURM_ARRAY_TASK_ID\".h5", shell_quote(&parts.to_string_lossy()));
    t.push_str("echo \"rbc-sweep task $SLURM_ARRAY_TASK_ID: job ${SLURM_JOB_ID:-none}, attempt $((${SLURM_RESTART_COUNT:-0} + 1)), $(date -u +%FT%TZ)\"\n");
    if let Some(before) = stop {
        let _ = writeln!(
            t,
            "# {before} s before the time limit Slurm sends USR1 to this shell: the run stops at its next\n\
             # output sample with a checkpoint and the task requeues itself to continue from there\n\
             rm -f \"$part.suspend\"\n\
             stop=0\n\
             trap 'stop=1; touch \"$part.suspend\"' USR1"
        );
    }
    let _ = writeln!(
        t,
        "{} task {} \"$SLURM_ARRAY_TASK_ID\" --out \"$part\" &",
        shell_quote(&exe.to_string_lossy()),
        shell_quote(&sweep_path.to_string_lossy()),
    );
    t.push_str("run=$!\nrc=0\nwait \"$run\" || rc=$?\n");
    if stop.is_some() {
        // `wait` returns early (> 128) when the trap runs: wait again for the run's own exit status.
        // The task is requeued as ARRAY_TASK: its own job id is also the whole array's id for
        // one of the tasks, and `scontrol requeue <that id>` would requeue every task.
        t.push_str(
            "if [ \"$stop\" = 1 ]; then\n  \
               if [ \"$rc\" -gt 128 ]; then rc=0; wait \"$run\" || rc=$?; fi\n  \
               rm -f \"$part.suspend\"\n  \
               if [ \"$rc\" = 0 ]; then\n    \
                 echo \"rbc-sweep task $SLURM_ARRAY_TASK_ID: stopped at a checkpoint before the time limit, requeued\"\n    \
                 scontrol requeue \"${SLURM_ARRAY_JOB_ID}_${SLURM_ARRAY_TASK_ID}\"\n  \
               fi\n\
             fi\n",
        );
    }
    t.push_str("exit \"$rc\"\n");
    t
}

/// The merge script's text.
pub fn merge_script(dir: &Path, exe: &Path) -> String {
    let mut t = String::from("#!/bin/bash\n#SBATCH --job-name=rbc-sweep-merge\n#SBATCH --ntasks=1\n#SBATCH --time=02:00:00\n");
    let _ = writeln!(
        t,
        "#SBATCH --output={}",
        dir.join("logs/merge.out").display()
    );
    t.push_str("set -euo pipefail\n");
    let _ = writeln!(
        t,
        "exec {} merge {}/*.h5 --out {}",
        shell_quote(&exe.to_string_lossy()),
        shell_quote(&dir.join("parts").to_string_lossy()),
        shell_quote(&dir.join("results.h5").to_string_lossy())
    );
    t
}

/// The submit script's text: the array job, then the merge after it (whatever its tasks' exit codes).
pub fn submit_script(dir: &Path) -> String {
    let d = shell_quote(&dir.to_string_lossy());
    format!(
        "#!/bin/bash\nset -euo pipefail\ncd {d}\njid=$(sbatch --parsable rbc-sweep.sbatch)\njid=${{jid%%;*}}\necho \"array job $jid\"\nsbatch --dependency=afterany:\"$jid\" merge.sbatch\n"
    )
}

/// Write the scripts and folders into `dir` (the four files as one set, [`rbc_schema::output_set`]);
/// returns the files written.
/// `exe` is the `rbc-sweep` binary to call (normally the running one).
pub fn write_slurm(
    sweep: &Sweep,
    runs: &[SweepRun],
    dir: &Path,
    exe: &Path,
) -> Result<Vec<PathBuf>, SweepError> {
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let dir = absolute(dir)?;
    let exe = absolute(exe)?;
    let sweep_path = absolute(&sweep.path)?;
    for sub in ["parts", "logs"] {
        std::fs::create_dir_all(dir.join(sub)).map_err(|e| io(&dir.join(sub), e))?;
    }
    let mut tsv = String::from("index\trun_id\tstart_shape\tvelocity_mm_s\tr_init_um\n");
    for r in runs {
        let _ = writeln!(
            tsv,
            "{}\t{}\t{}\t{}\t{}",
            r.index, r.run_id, r.start_shape, r.velocity_mm_s, r.r_init_um
        );
    }
    let files = [
        (
            "rbc-sweep.sbatch",
            array_script(sweep, runs.len(), &dir, &exe, &sweep_path),
            true,
        ),
        ("merge.sbatch", merge_script(&dir, &exe), true),
        ("submit.sh", submit_script(&dir), true),
        ("runs.tsv", tsv, false),
    ];
    // the four files replace those of an earlier call as one set (parts/ and logs/ stay)
    let names: Vec<&str> = files.iter().map(|(name, _, _)| *name).collect();
    let ((), written) = rbc_schema::output_set::write_set(&dir, |n| names.contains(&n), |staging| -> Result<(), SweepError> {
        for (name, text, executable) in &files {
            let path = staging.join(name);
            std::fs::write(&path, text.as_bytes()).map_err(|e| io(&path, e))?;
            #[cfg(unix)]
            if *executable {
                use std::os::unix::fs::PermissionsExt;
                std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).map_err(|e| io(&path, e))?;
            }
            #[cfg(not(unix))]
            let _ = executable;
        }
        Ok(())
    })?;
    Ok(written)
}
