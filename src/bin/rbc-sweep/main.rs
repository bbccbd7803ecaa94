//! `rbc-sweep`: run a grid of simulations (velocity x initial offset x start shape) locally or on a Slurm cluster, merge the parts, draw the figures.
//!
//! ```text
//! rbc-sweep run SWEEP.toml [--out results.h5] [--jobs N] [--retry-failed]  # local pool, resumable
//! rbc-sweep list SWEEP.toml                                               # the runs, without running
//! rbc-sweep slurm SWEEP.toml DIR                                          # Slurm array + merge scripts
//! rbc-sweep task SWEEP.toml I --out DIR/parts/I.h5                        # one run (an array task)
//! rbc-sweep merge DIR/parts/*.h5 --out results.h5                         # gather parts
//! rbc-sweep start-shape results.h5 RUN --as NAME --out starts.h5          # an ended run's last shape as a start shape
//! rbc-sweep figures results.h5 [--out DIR]                                # Figs. 5, 6 and shape views
//! rbc-sweep trajectories a.h5 b.h5 [--out DIR]                            # y, z, asphericity vs t of every run
//! rbc-sweep offsets a/state/*.h5 b/state/*.h5 [--velocity-mm-s 6.5] [--mark-um 0.7] [--out DIR]  # steady radial position vs r_init
//! rbc-sweep phase a/state/*.h5 b/state/*.h5 [--start discocyte] [--velocity-tol 0.05] [--out DIR]  # phase diagram, one panel per study
//! rbc-sweep steady a/state/*.h5 b/state/*.h5 [--start discocyte] [--velocity-tol 0.05] [--out DIR]  # steady radial position, slipper extents and tank-treading vs velocity
//! rbc-sweep status FILES [--sweep SWEEP.toml] [--run ID [--field a,b]]    # progress of (running) runs
//! rbc-sweep events FILES [--run ID] [--fraction 0.82]                     # turn-overs and folds (CSV)
//! rbc-sweep xdmf results.h5 [--run ID]                                    # results.<run>.xmf for ParaView
//! rbc-sweep reopen results.h5 RUN --sweep SWEEP.toml                       # let an ended run continue
//! rbc-sweep relabel results.h5... --sweep SWEEP.toml                       # labels again from the stored evidence
//! ```
//!
//! The old flag spelling (`rbc-sweep SWEEP.toml [--list|--slurm DIR|--task I --out F]`,
//! `--merge PARTS --out F`, `--figures`, `--trajectories`, `[SWEEP.toml] --study-status FILES`,
//! `--xdmf`) still works: it is read when the first argument is no subcommand (`legacy`).
//!
//! A run of a local sweep or a task stops at its next checkpoint, unfinished and resumable, when
//! the file `<out>.suspend` appears beside its results file (`scripts/study.sh save`).
//!
//! The sweep file is described in `rbc_schema::sweep`; every expanded scene is
//! validated before anything runs. A local sweep runs `--jobs` runs at a time
//! (default: cores / threads_per_run), one per worker thread, each into its own
//! part file, and copies each finished run into `--out`; run it again after a
//! kill and it continues (finished runs are skipped). Exit codes: 0 success,
//! 1 some runs could not be executed (listed; they are retried next time),
//! 2 bad input.

mod cli;
mod legacy;
mod parse;

use anyhow::{anyhow, Context, Result};
use cli::{Cmd, StudiesFigure};
use parse::Stop;
use rbc::progress::Progress;
use rbc::sweep::local::{run_local, LocalOptions};
use rbc::sweep::solver_exec::SolverExecutor;
use rbc::sweep::task::{run_task, TaskOutcome};
use rbc::sweep::{slurm, RunExecutor};
use rbc_schema::scene::Scene;
use rbc_schema::sweep::{Sweep, SweepRun};
use rbc_solver::run::Observer;
use rbc_solver::SolverError;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Bad input (exit 2) or a failed run (exit 1).
enum Failure {
    Input(anyhow::Error),
    Runs(anyhow::Error),
}

impl<E: Into<anyhow::Error>> From<E> for Failure {
    fn from(e: E) -> Self {
        Failure::Input(e.into())
    }
}

fn main() -> ExitCode {
    if !rbc::build_cpu::check("rbc-sweep") {
        return ExitCode::from(2);
    }
    rbc::alloc::keep_freed_memory();
    // a libhdf5 call that hangs on a damaged file ends the command with one line (exit 2)
    rbc_schema::hdf5_watch::enable_from_env("rbc-sweep");
    let argv: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let result = match parse::parse(&argv) {
        Ok(cmd) => run(cmd),
        Err(Stop::Printed(help)) => {
            let _ = help.print();
            return ExitCode::SUCCESS;
        }
        Err(Stop::Input(line)) => Err(Failure::Input(anyhow!(line))),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(e)) => {
            eprintln!("rbc-sweep: {}", format!("{e:#}").replace('\n', " "));
            ExitCode::from(2)
        }
        Err(Failure::Runs(e)) => {
            eprintln!("rbc-sweep: {}", format!("{e:#}").replace('\n', " "));
            ExitCode::FAILURE
        }
    }
}

/// The solver's scene runner: build exactly what the scene needs and run it
/// (`rbc_solver::scene`); a scene the solver cannot assemble yet (e.g. the periodic
/// channel before the periodic Green's functions are wired in) is refused with the
/// solver's diagnosis and recorded nowhere, so a later build retries it.
fn solve(scene: &Scene, observer: &mut dyn Observer) -> Result<(), SolverError> {
    rbc_solver::scene::build(scene)?.run(observer).map(|_| ())
}

fn run(cmd: Cmd) -> Result<(), Failure> {
    match cmd {
        Cmd::Merge { parts, out } => {
            let n = rbc_schema::results::merge_files(&parts, &out)?;
            eprintln!("rbc-sweep: merged {n} runs from {} files into {}", parts.len(), out.display());
        }
        Cmd::StartShape { results, run, name, out } => {
            let t = rbc_schema::start_shape::copy_last_shape(&results, &run, &out, &name)?;
            eprintln!("rbc-sweep: {}'s run {run} at t = {t} s -> start shape {name} in {}", results.display(), out.display());
        }
        Cmd::Figures { results, out } => {
            let written = rbc_analysis::plot::simulation::write_figures(&results, &out)?;
            for w in &written.warnings {
                eprintln!("rbc-sweep: warning: {w}");
            }
            eprintln!("rbc-sweep: {} files (PNG + SVG) written to {}", written.files.len(), out.display());
        }
        Cmd::Trajectories { files, out } => {
            let files: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
            let fig = rbc_analysis::plot::trajectory::TrajectoryFigure::read(&files)?;
            let [png, _] = fig.write(&out)?;
            eprintln!("rbc-sweep: {} runs drawn into {} (and .svg)", fig.runs.len(), png.display());
        }
        Cmd::Offsets { files, velocity_mm_s, velocity_tol, start, mark_um, out } => {
            let files: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
            let fig = rbc_analysis::plot::offset::OffsetFigure::read(&files, &start, velocity_mm_s, velocity_tol, mark_um)?;
            for w in &fig.skipped {
                eprintln!("rbc-sweep: {w}");
            }
            let [png, _] = fig.write(&out)?;
            for s in &fig.series {
                let runs: Vec<String> = s.points.iter().map(|p| format!("{} um -> {} at {:.3} um", p.r_init_um, p.final_shape.as_str(), p.mean_radial_um)).collect();
                let going: Vec<String> = s.running.iter().map(|p| format!("{} um still running at {:.1} ms, {:.3} um now", p.r_init_um, p.tail.t_s * 1e3, p.tail.radial_um)).collect();
                eprintln!("rbc-sweep: {}: {}", s.label, runs.iter().chain(&going).cloned().collect::<Vec<_>>().join(", "));
            }
            eprintln!("rbc-sweep: {} series drawn into {} (and .svg)", fig.series.len(), png.display());
        }
        Cmd::Phase(StudiesFigure { files, start, velocity_tol, out }) => {
            let files: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
            let fig = rbc_analysis::plot::phase_studies::PhaseStudiesFigure::read(&files, &start, velocity_tol)?;
            for w in fig.skipped() {
                eprintln!("rbc-sweep: {w}");
            }
            let [png, _] = fig.write(&out)?;
            for s in fig.studies() {
                let ended: Vec<String> = s.points.iter().map(|p| format!("{:.2} mm/s from {} um -> {}", p.velocity_mm_s, p.r_init_um, p.final_shape.as_str())).collect();
                let going: Vec<String> = s.running.iter().map(|p| format!("{:.2} mm/s from {} um still running at {:.1} ms", p.tail.velocity_mm_s, p.r_init_um, p.tail.t_s * 1e3)).collect();
                eprintln!("rbc-sweep: {}: {}", s.label, ended.iter().chain(&going).cloned().collect::<Vec<_>>().join(", "));
            }
            eprintln!("rbc-sweep: {} panels drawn into {} (and .svg)", fig.studies().len(), png.display());
        }
        Cmd::Steady(StudiesFigure { files, start, velocity_tol, out }) => {
            let files: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
            let fig = rbc_analysis::plot::steady_studies::SteadyStudiesFigure::read(&files, &start, velocity_tol)?;
            for w in fig.skipped() {
                eprintln!("rbc-sweep: {w}");
            }
            let [png, _] = fig.write(&out)?;
            for s in fig.studies() {
                let cols: Vec<String> = s.radial.iter().map(|c| format!("{} at {:.2} mm/s: {:.3} um ({:.3}-{:.3}, {} run(s))", c.class.label(), c.velocity_mm_s, c.value, c.min, c.max, c.n_runs)).collect();
                eprintln!("rbc-sweep: {}: {}; {} still running", s.label, cols.join(", "), s.running);
                let tt: Vec<String> = s.tank_treading.iter().map(|c| format!("{} at {:.2} mm/s: {:.2} Hz ({:.2}-{:.2})", c.class.label(), c.velocity_mm_s, c.value, c.min, c.max)).collect();
                eprintln!("rbc-sweep: {}: tank-treading: {}", s.label, tt.join(", "));
                if !s.tumbling.is_empty() {
                    let tu: Vec<String> = s.tumbling.iter().map(|c| format!("slipper at {:.2} mm/s: {:.2} Hz ({:.2}-{:.2}, {} run(s))", c.velocity_mm_s, c.value, c.min, c.max, c.n_runs)).collect();
                    eprintln!("rbc-sweep: {}: tumbling: {}", s.label, tu.join(", "));
                }
            }
            eprintln!("rbc-sweep: {} studies drawn into {} (and .svg)", fig.studies().len(), png.display());
        }
        Cmd::Xdmf { results, run } => {
            let done = rbc_schema::xdmf::export(&results, run.as_deref())?;
            for (id, path, n) in &done.written {
                eprintln!("rbc-sweep: run {id}: {n} snapshots -> {}", path.display());
            }
            if !done.empty.is_empty() {
                eprintln!("rbc-sweep: no snapshot yet (no .xmf): {}", done.empty.join(", "));
            }
        }
        Cmd::Status { files, sweep, run, field } => study_status(&files, sweep.as_deref(), run.as_deref(), field.as_deref())?,
        Cmd::Events { files, run, fraction } => {
            if !(fraction > 0.0 && fraction < 1.0) {
                return Err(Failure::Input(anyhow!("--fraction {fraction}: not between 0 and 1")));
            }
            let paths: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
            let runs = rbc::sweep::events::events(&paths, run.as_deref(), fraction)?;
            for line in rbc::sweep::events::summary(&runs) {
                eprintln!("rbc-sweep: {line}");
            }
            // a reader that stops early (`| head`) is no error
            use std::io::Write as _;
            if let Err(e) = std::io::stdout().lock().write_all(rbc::sweep::events::csv(&runs).as_bytes()) {
                if e.kind() != std::io::ErrorKind::BrokenPipe {
                    return Err(anyhow!("writing to stdout: {e}").into());
                }
            }
        }
        Cmd::Reopen { results, run, sweep } => {
            let (sweep, _) = load(&sweep)?;
            let t = rbc::sweep::reopen::reopen_ended(&results, &run, sweep.snapshot_every)?;
            eprintln!("rbc-sweep: run {run} of {} reopened at t = {t} s: `task` or `run` continues it", results.display());
        }
        Cmd::Relabel { results, sweep } => {
            let (sweep, _) = load(&sweep)?;
            let cfg = rbc::sweep::verdict::classify_config(&sweep.classify);
            for path in &results {
                for r in rbc::sweep::relabel::relabel(path, &cfg)? {
                    let show = |(s, tt, tu): (rbc_schema::results::FinalShape, bool, bool)| {
                        format!("{}{}{}", s.as_str(), if tt { ", tank-treading" } else { "" }, if tu { ", tumbling" } else { "" })
                    };
                    let what = if r.changed() { format!("{} -> {}", show(r.before), show(r.after)) } else { format!("{} (unchanged)", show(r.after)) };
                    let carried = r.transits_mm.iter().map(|d| format!("{d} mm")).collect::<Vec<_>>().join(", ");
                    let carried = if carried.is_empty() { String::new() } else { format!("; its steady state carried to {carried} (transit records)") };
                    eprintln!("rbc-sweep: {} run {}: {what}{carried}", path.display(), r.run_id);
                }
            }
        }
        Cmd::List { sweep } => list(&sweep)?,
        Cmd::Slurm { sweep, dir } => {
            let (sweep, runs) = load(&sweep)?;
            let exe = std::env::current_exe().context("locating the rbc-sweep binary")?;
            let files = slurm::write_slurm(&sweep, &runs, &dir, &exe)?;
            let submit = files.iter().find(|f| f.ends_with("submit.sh")).cloned().unwrap_or_else(|| dir.join("submit.sh"));
            eprintln!("rbc-sweep: {} array tasks; submit with {}", runs.len(), submit.display());
        }
        Cmd::Task { sweep, index, out } => task(&sweep, index, &out)?,
        Cmd::Run { sweep, out, jobs, retry_failed } => local(&sweep, &out, jobs, retry_failed)?,
    }
    Ok(())
}

/// Read a sweep file and expand its runs, validating every run's scene before anything runs; runs
/// whose cell overlaps the channel wall are marked (`rbc::sweep::expand`) and said on stderr.
fn load(path: &Path) -> Result<(Sweep, Vec<SweepRun>)> {
    let sweep = Sweep::read(path)?;
    let (runs, notes) = rbc::sweep::expand(&sweep)?;
    for n in &notes {
        eprintln!("rbc-sweep: note: {n}");
    }
    let overlapping: Vec<&SweepRun> = runs.iter().filter(|r| r.overlaps_wall.is_some()).collect();
    if let Some(first) = overlapping.first() {
        eprintln!(
            "rbc-sweep: {} of {} runs overlap the channel wall and are not run (status overlaps-wall), e.g. {}: {}",
            overlapping.len(),
            runs.len(),
            first.run_id,
            first.overlaps_wall.as_deref().unwrap_or_default()
        );
    }
    Ok((sweep, runs))
}

/// `list`: the expanded runs as a tab-separated table on stdout (`status`: `to-run`, or
/// `overlaps-wall` with the overlap in `note`). A reader that closes the pipe early (`| head`)
/// ends the listing quietly.
fn list(path: &Path) -> Result<()> {
    use std::io::Write;
    let (_, runs) = load(path)?;
    let mut out = std::io::stdout().lock();
    let mut write = || -> std::io::Result<()> {
        writeln!(out, "index\trun_id\tstart_shape\tvelocity_mm_s\tr_init_um\ty_init_um\tz_init_um\tstatus\tnote")?;
        for r in &runs {
            let (status, note) = match &r.overlaps_wall {
                Some(why) => ("overlaps-wall", why.as_str()),
                None => ("to-run", ""),
            };
            writeln!(
                out,
                "{}\t{}\t{}\t{}\t{}\t{:.4}\t{:.4}\t{status}\t{note}",
                r.index, r.run_id, r.start_shape, r.velocity_mm_s, r.r_init_um, r.y_init_um, r.z_init_um
            )?;
        }
        out.flush()
    };
    match write() {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => Ok(r?),
    }
}

/// `task`: run number `i` of the sweep into `out` (a Slurm array task).
fn task(path: &Path, i: usize, out: &Path) -> Result<(), Failure> {
    let (sweep, runs) = load(path)?;
    // the run gets the sweep's threads_per_run, not one rayon thread per core
    if let Some(n) = rbc::sweep::task::task_threads(&sweep, std::env::var_os("RAYON_NUM_THREADS").as_deref()) {
        let _ = rayon::ThreadPoolBuilder::new().num_threads(n).build_global();
    }
    let exec = SolverExecutor { solve };
    match run_task(&sweep, &runs, i, out, &exec as &dyn RunExecutor) {
        Ok(TaskOutcome::AlreadyDone { run_id, status }) => {
            eprintln!("rbc-sweep: task {i}: run {run_id} already {status} in {}", out.display());
            Ok(())
        }
        Ok(TaskOutcome::Ran { run_id, status }) => {
            eprintln!("rbc-sweep: task {i}: run {run_id} {status}, written to {}", out.display());
            Ok(())
        }
        Err(e @ rbc::sweep::SweepError::TaskIndex { .. }) => Err(Failure::Input(e.into())),
        Err(e) => Err(Failure::Runs(e.into())),
    }
}

/// `run`: every run of the sweep on this machine, `jobs` at a time, into `out`.
fn local(path: &Path, out: &Path, jobs: Option<usize>, retry_failed: bool) -> Result<(), Failure> {
    if jobs == Some(0) {
        return Err(Failure::Input(anyhow::anyhow!("--jobs 0: give at least 1 run at a time")));
    }
    let (sweep, runs) = load(path)?;
    let exec = SolverExecutor { solve };
    let out = out.to_path_buf();
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let jobs = jobs.unwrap_or((cores / sweep.threads_per_run).max(1));
    // what this call has to do: finished runs are kept, the others run (a killed one resumes from
    // its checkpoint and says so); an unreadable output is reported by run_local below
    if out.exists() {
        if let Ok(existing) = rbc_schema::results::read_runs(&out) {
            let finished = runs.iter().filter(|r| existing.iter().any(|e| e.run_id == r.run_id && e.status.is_finished())).count();
            eprintln!("rbc-sweep: {} of {} runs already finished in {}, {} to run", finished, runs.len(), out.display(), runs.len() - finished);
        }
    }
    let progress = Progress::new("runs", runs.len());
    let mut on_done = |id: &str, r: &Result<rbc_schema::results::RunStatus, String>| match r {
        Ok(s) => progress.step(&format!("{id}: {}", s.as_str())),
        Err(e) => progress.step(&format!("{id}: not run: {e}")),
    };
    let report = run_local(
        &sweep,
        &runs,
        &out,
        &exec,
        &LocalOptions {
            jobs,
            retry_failed,
        },
        &mut on_done,
    )?;
    progress.finish();
    if report.restored {
        eprintln!(
            "rbc-sweep: {} was unreadable (killed while writing?): restored from its backup, the damaged file is kept as {}",
            out.display(),
            rbc::sweep::local::backup_path(&out).with_extension("damaged").display()
        );
    }
    let recorded = report.done.iter().filter(|(_, s)| *s == rbc_schema::results::RunStatus::OverlapsWall).count();
    eprintln!(
        "rbc-sweep: {} runs already in {}, {} done now ({recorded} of them recorded as overlapping the wall, not run), {} not run ({jobs} at a time)",
        report.skipped.len(),
        out.display(),
        report.done.len(),
        report.errors.len()
    );
    if let Some((id, e)) = report.errors.first() {
        return Err(Failure::Runs(anyhow!(
            "{} runs could not be executed; first: {id}: {e}",
            report.errors.len()
        )));
    }
    Ok(())
}

/// `status`: the progress table of `files`, or single fields of one run (for scripts); the shape
/// label uses the sweep file's classifier settings when one is given, and the table's steady gap
/// its steady-state criterion (without a sweep file: `-`).
fn study_status(files: &[PathBuf], sweep: Option<&Path>, run: Option<&str>, fields: Option<&str>) -> Result<(), Failure> {
    use rbc::sweep::study;
    let sweep = sweep.map(Sweep::read).transpose()?;
    let cfg = sweep.as_ref().map_or_else(rbc_solver::classify::ClassifyConfig::default, |s| rbc::sweep::verdict::classify_config(&s.classify));
    // without the sweep's `max_time_s`, an end no run reaches: the gaps do not depend on it, and
    // the detector refuses an infinite one (the periodic gap would be `-` for every run)
    let steady = sweep.as_ref().map(|s| rbc::sweep::verdict::criterion(&s.steady, f64::MAX));
    let Some(id) = run else {
        let paths: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
        print!("{}", study::table(&study::progress(&paths, &cfg, steady.as_ref())?));
        return Ok(());
    };
    let [file] = files else {
        return Err(anyhow!("--run takes exactly one results file").into());
    };
    let p = study::run_progress(file, id, &cfg, steady.as_ref())?;
    let Some(fields) = fields else {
        print!("{}", study::table(&[p]));
        return Ok(());
    };
    let values: Vec<String> = fields
        .split(',')
        .map(|f| match f.trim() {
            "run_id" => Ok(p.run_id.clone()),
            "status" => Ok(p.status.clone()),
            "t_s" => Ok(format!("{:e}", p.t_s)),
            "y_um" => Ok(p.y_um.to_string()),
            "z_um" => Ok(p.z_um.to_string()),
            "asphericity" => Ok(p.asphericity.to_string()),
            "sharpest_fold_deg" => Ok(p.sharpest_fold_deg.to_string()),
            "velocity_mm_s" => Ok(p.velocity_mm_s.to_string()),
            "shape" => Ok(p.shape.clone()),
            "tank_treading_hz" => Ok(p.motion.map_or("-".into(), |m| m.tank_treading_hz.to_string())),
            "tumbling_hz" => Ok(p.motion.map_or("-".into(), |m| m.tumbling_hz.to_string())),
            "steps" => Ok(p.steps.to_string()),
            "steady_gap" => Ok(p.steady_gap.map_or("-".into(), |g| g.0.to_string())),
            "periodic_gap" => Ok(p.periodic_gap.map_or("-".into(), |g| g.gap.to_string())),
            "orbit_drift_um_s" => Ok(p.orbit_drift.map_or("-".into(), |d| d.rate.to_string())),
            "orbit_drift_before_um_s" => Ok(p.orbit_drift.and_then(|d| d.earlier_rate).map_or("-".into(), |r| r.to_string())),
            other => Err(anyhow!("--field: unknown field `{other}`")),
        })
        .collect::<Result<_>>()?;
    println!("{}", values.join(" "));
    Ok(())
}
