//! `rbc-sweep`: run a grid of simulations (velocity x initial offset x start shape) locally or on a Slurm cluster, merge the parts, draw the figures.
//!
//! ```text
//! rbc-sweep SWEEP.toml [--out results.h5] [--jobs N] [--retry-failed]   # local pool, resumable
//! rbc-sweep SWEEP.toml --list                                          # the runs, without running
//! rbc-sweep SWEEP.toml --slurm DIR                                     # Slurm array + merge scripts
//! rbc-sweep SWEEP.toml --task I --out DIR/parts/I.h5                   # one run (an array task)
//! rbc-sweep --merge DIR/parts/*.h5 --out results.h5                    # gather parts
//! rbc-sweep --figures results.h5 --out DIR                             # Figs. 5, 6 and shape views
//! rbc-sweep --trajectories a.h5 b.h5 --out DIR                         # y, z, asphericity vs t of every run
//! rbc-sweep [SWEEP.toml] --study-status FILES [--run ID --field a,b]   # progress of (running) runs
//! rbc-sweep --xdmf results.h5 [--run ID]                                # results.<run>.xmf for ParaView
//! ```
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

use anyhow::{anyhow, Context, Result};
use clap::Parser;
use rbc::progress::Progress;
use rbc::sweep::local::{run_local, LocalOptions};
use rbc::sweep::solver_exec::SolverExecutor;
use rbc::sweep::task::{run_task, TaskOutcome};
use rbc::sweep::{slurm, RunExecutor};
use rbc_schema::scene::Scene;
use rbc_schema::sweep::Sweep;
use rbc_solver::run::Observer;
use rbc_solver::SolverError;
use std::path::PathBuf;
use std::process::ExitCode;

/// Run a sweep of simulations (phase diagram of the paper), locally or as a Slurm array.
#[derive(Parser, Debug)]
#[command(name = "rbc-sweep", version)]
struct Args {
    /// The sweep file (TOML).
    sweep: Option<PathBuf>,
    /// Output: results file (local run, task, merge) or folder (figures). Default results.h5 / figures.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Runs at a time on this machine (default: available cores / threads_per_run).
    #[arg(long)]
    jobs: Option<usize>,
    /// Execute again runs that failed in an earlier attempt.
    #[arg(long)]
    retry_failed: bool,
    /// Print the expanded runs (index, id, shape, velocity, offset) and exit.
    #[arg(long)]
    list: bool,
    /// Write a Slurm array job, a merge job and submit.sh into this folder.
    #[arg(long, value_name = "DIR")]
    slurm: Option<PathBuf>,
    /// Execute only run number I (0-based; a Slurm array task) into --out.
    #[arg(long, value_name = "I")]
    task: Option<usize>,
    /// Merge these results files into --out.
    #[arg(long, num_args = 1.., value_name = "FILES")]
    merge: Vec<PathBuf>,
    /// Draw the figures of this results file into --out (a folder).
    #[arg(long, value_name = "RESULTS")]
    figures: Option<PathBuf>,
    /// Draw the lateral position and asphericity against time of every run (any status) of these
    /// results files into --out (a folder: trajectories.png and .svg), e.g. a study's state.
    #[arg(long, num_args = 1.., value_name = "FILES")]
    trajectories: Vec<PathBuf>,
    /// Print the progress of every run in these results files (read from the checkpoints of
    /// unfinished runs, which may be running), as a Markdown table; the shape label uses the
    /// sweep file's classifier settings when one is given.
    #[arg(long, num_args = 1.., value_name = "FILES")]
    study_status: Vec<PathBuf>,
    /// Write `<stem>.<run_id>.xmf` beside this results file for every run with snapshots: each a
    /// time series of the run's triangle meshes that ParaView opens, pointing into the HDF5 file.
    #[arg(long, value_name = "RESULTS")]
    xdmf: Option<PathBuf>,
    /// With --study-status and one file, or with --xdmf: only this run.
    #[arg(long, value_name = "ID")]
    run: Option<String>,
    /// With --study-status and --run: print only these fields, space-separated
    /// (run_id, status, t_s, y_um, z_um, asphericity, sharpest_fold_deg, velocity_mm_s, shape, steps).
    #[arg(long, value_name = "a,b", requires = "run")]
    field: Option<String>,
}

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
    let args = Args::parse();
    match run(&args) {
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

fn run(args: &Args) -> Result<(), Failure> {
    if !args.merge.is_empty() {
        if args.sweep.is_some()
            || args.figures.is_some()
            || args.task.is_some()
            || args.slurm.is_some()
        {
            return Err(anyhow!("--merge takes only --out").into());
        }
        let out = args
            .out
            .clone()
            .ok_or_else(|| anyhow!("--merge needs --out FILE"))?;
        let n = rbc_schema::results::merge_files(&args.merge, &out)?;
        eprintln!(
            "rbc-sweep: merged {n} runs from {} files into {}",
            args.merge.len(),
            out.display()
        );
        return Ok(());
    }
    if let Some(results) = &args.figures {
        if args.sweep.is_some() || args.task.is_some() || args.slurm.is_some() {
            return Err(anyhow!("--figures takes only --out").into());
        }
        let out = args.out.clone().unwrap_or_else(|| PathBuf::from("figures"));
        let written = rbc_analysis::plot::simulation::write_figures(results, &out)?;
        for w in &written.warnings {
            eprintln!("rbc-sweep: warning: {w}");
        }
        eprintln!(
            "rbc-sweep: {} files (PNG + SVG) written to {}",
            written.files.len(),
            out.display()
        );
        return Ok(());
    }
    if !args.trajectories.is_empty() {
        if args.sweep.is_some() || args.task.is_some() || args.slurm.is_some() {
            return Err(anyhow!("--trajectories takes only --out").into());
        }
        let out = args.out.clone().unwrap_or_else(|| PathBuf::from("figures"));
        let files: Vec<&std::path::Path> = args.trajectories.iter().map(PathBuf::as_path).collect();
        let fig = rbc_analysis::plot::trajectory::TrajectoryFigure::read(&files)?;
        let [png, _] = fig.write(&out)?;
        eprintln!("rbc-sweep: {} runs drawn into {} (and .svg)", fig.runs.len(), png.display());
        return Ok(());
    }
    if let Some(results) = &args.xdmf {
        if args.sweep.is_some() || args.out.is_some() || args.task.is_some() || args.slurm.is_some() {
            return Err(anyhow!("--xdmf takes only --run (the .xmf files go beside the results file)").into());
        }
        let done = rbc_schema::xdmf::export(results, args.run.as_deref())?;
        for (id, path, n) in &done.written {
            eprintln!("rbc-sweep: run {id}: {n} snapshots -> {}", path.display());
        }
        if !done.empty.is_empty() {
            eprintln!("rbc-sweep: no snapshot yet (no .xmf): {}", done.empty.join(", "));
        }
        return Ok(());
    }
    if args.run.is_some() && args.study_status.is_empty() {
        return Err(anyhow!("--run needs --study-status or --xdmf").into());
    }
    if !args.study_status.is_empty() {
        return study_status(args);
    }
    let path = args
        .sweep
        .clone()
        .ok_or_else(|| anyhow!("missing the sweep file (or --merge / --figures / --study-status)"))?;
    let sweep = Sweep::read(&path)?;
    let runs = sweep.runs()?;
    for r in &runs {
        Scene::parse(&r.scene_text, &sweep.base_scene)
            .with_context(|| format!("{}: run {}", path.display(), r.run_id))?;
    }
    if args.list {
        println!("index\trun_id\tstart_shape\tvelocity_mm_s\tr_init_um\ty_init_um\tz_init_um");
        for r in &runs {
            println!(
                "{}\t{}\t{}\t{}\t{}\t{:.4}\t{:.4}",
                r.index,
                r.run_id,
                r.start_shape,
                r.velocity_mm_s,
                r.r_init_um,
                r.y_init_um,
                r.z_init_um
            );
        }
        return Ok(());
    }
    let exec = SolverExecutor { solve };
    if let Some(dir) = &args.slurm {
        let exe = std::env::current_exe().context("locating the rbc-sweep binary")?;
        let files = slurm::write_slurm(&sweep, &runs, dir, &exe)?;
        eprintln!(
            "rbc-sweep: {} array tasks; submit with {}",
            runs.len(),
            files[2].display()
        );
        return Ok(());
    }
    if let Some(i) = args.task {
        let out = args
            .out
            .clone()
            .ok_or_else(|| anyhow!("--task needs --out FILE"))?;
        return match run_task(&sweep, &runs, i, &out, &exec as &dyn RunExecutor) {
            Ok(TaskOutcome::AlreadyDone { run_id, status }) => {
                eprintln!(
                    "rbc-sweep: task {i}: run {run_id} already {status} in {}",
                    out.display()
                );
                Ok(())
            }
            Ok(TaskOutcome::Ran { run_id, status }) => {
                eprintln!(
                    "rbc-sweep: task {i}: run {run_id} {status}, written to {}",
                    out.display()
                );
                Ok(())
            }
            Err(e @ rbc::sweep::SweepError::TaskIndex { .. }) => Err(Failure::Input(e.into())),
            Err(e) => Err(Failure::Runs(e.into())),
        };
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("results.h5"));
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let jobs = args.jobs.unwrap_or((cores / sweep.threads_per_run).max(1));
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
            retry_failed: args.retry_failed,
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
    eprintln!(
        "rbc-sweep: {} runs already in {}, {} done now, {} not run ({jobs} at a time)",
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

/// `--study-status`: the progress table, or single fields of one run (for scripts).
fn study_status(args: &Args) -> Result<(), Failure> {
    use rbc::sweep::study;
    let cfg = match &args.sweep {
        Some(p) => rbc::sweep::solver_exec::classify_config(&Sweep::read(p)?.classify),
        None => rbc_solver::classify::ClassifyConfig::default(),
    };
    let Some(id) = &args.run else {
        let paths: Vec<&std::path::Path> = args.study_status.iter().map(PathBuf::as_path).collect();
        print!("{}", study::table(&study::progress(&paths, &cfg)?));
        return Ok(());
    };
    let [file] = args.study_status.as_slice() else {
        return Err(anyhow!("--run takes exactly one results file after --study-status").into());
    };
    let p = study::run_progress(file, id, &cfg)?;
    let Some(fields) = &args.field else {
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
            "steps" => Ok(p.steps.to_string()),
            other => Err(anyhow!("--field: unknown field `{other}`")),
        })
        .collect::<Result<_>>()?;
    println!("{}", values.join(" "));
    Ok(())
}
