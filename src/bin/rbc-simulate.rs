//! `rbc-simulate`: run one scene and append it as a run to `results.h5`.
//!
//! ```text
//! rbc-simulate SCENE.toml [--out results.h5] [--run-id ID] [--snapshot-every N]
//!              [--checkpoint-every K] [--checkpoint-interval SECONDS] [--resume]
//! ```
//!
//! While it runs, a checkpoint (`<out>.<run_id>.ckpt`, see `rbc_schema::checkpoint`)
//! is replaced atomically at the first sample, every K-th output sample and every
//! SECONDS of wall time (default 60 s); `--resume` continues a killed run from it,
//! bit-for-bit as if it had never stopped. To stop a run without losing the work since its last
//! checkpoint, create the file `<out>.suspend` (e.g. `touch results.h5.suspend`): the run takes a
//! checkpoint at its next output sample and exits (0) unfinished, status `running`; remove the
//! file, then `--resume` continues it bit-for-bit (while the file is there, a start is refused).
//! A run that reached its end time keeps the checkpoint of its end state: `--resume` with a
//! scene whose `time.end_s` is later continues it there (status `running` again until the new
//! end; its first step is the one the step control proposed at the old end). `--resume` refuses (exit 2, one line) when
//! `--out` has no such run, when the run ended (failed, or at an end time the scene does not
//! pass), when the scene
//! differs from the one the run was started from, or when its checkpoint is damaged or holds a
//! state no run could continue from (naming the checkpoint and the field; the run and its
//! checkpoint are left as they were); a run killed before its first
//! checkpoint is started again from t = 0; a resumed run keeps the snapshot cadence it was
//! started with (`--snapshot-every` is then ignored). Without `--resume` a new run is appended
//! (`NAME-2`, ...): an existing run or file is never overwritten.
//!
//! The scene is validated first (errors name the file and field; a channel scene whose cell would
//! start in, or closer than 0.1 um to, the wall is refused naming `cell.position_um` and the
//! channel's width and height), then only the
//! operators it needs are assembled, and the run is appended to `--out`
//! (status `running` while it runs, `failed` with the diagnosis if the
//! integration stops on a blow-up, `unsteady` at the end time). Progress is a
//! kdam bar on a terminal, plain log lines otherwise. Exit codes: 0 success,
//! 1 the run failed (diagnosis on stderr and in the file), 2 bad input.

use anyhow::{Context, Result};
use clap::Parser;
use rbc_schema::results::{ResultsFile, RunAttrs, RunStatus};
use rbc_schema::scene::{CellShape, Scene};
use rbc_solver::run::persist::{self, CheckpointPolicy, CheckpointWriter, NotResumable, SuspendRequest};
use rbc_solver::run::progress::Progress;
use rbc_solver::run::results::ResultsObserver;
use rbc_solver::run::step_log::StepLog;
use rbc_solver::run::Fanout;
use std::path::PathBuf;
use std::process::ExitCode;

/// Run one simulation scene (TOML) and append it to a results file (HDF5).
#[derive(Parser, Debug)]
#[command(
    name = "rbc-simulate",
    version,
    after_help = rbc::MEMORY_HELP
)]
struct Args {
    /// The scene file.
    scene: PathBuf,
    /// Results file to append the run to (created if absent).
    #[arg(long, default_value = "results.h5")]
    out: PathBuf,
    /// Run id inside the results file (default: the scene's name, with -2, -3, ... if taken).
    #[arg(long)]
    run_id: Option<String>,
    /// Store all vertices every N-th output sample (and at the end).
    #[arg(long, default_value_t = 10)]
    snapshot_every: usize,
    /// Write a checkpoint every K-th output sample (0: only by wall time).
    #[arg(long, default_value_t = 0)]
    checkpoint_every: usize,
    /// Write a checkpoint when this many seconds of wall time passed since the last one (0: only every K-th output).
    #[arg(long, default_value_t = 60.0)]
    checkpoint_interval: f64,
    /// Continue the run (`--run-id`, else the last run named after the scene) from its last checkpoint.
    #[arg(long)]
    resume: bool,
    /// Write every step attempt (accepted and rejected: step, error norm, where the error sits) to this CSV file.
    #[arg(long)]
    step_log: Option<PathBuf>,
}

enum Failure {
    Input(anyhow::Error),
    Run(anyhow::Error),
}

fn main() -> ExitCode {
    if !rbc::build_cpu::check("rbc-simulate") {
        return ExitCode::from(2);
    }
    rbc::alloc::keep_freed_memory();
    let args = Args::parse();
    // a libhdf5 call that hangs on a damaged file ends the command with one line (exit 2)
    rbc_schema::hdf5_watch::enable_from_env("rbc-simulate");
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(e)) => {
            eprintln!("rbc-simulate: {}", format!("{e:#}").replace('\n', " "));
            ExitCode::from(2)
        }
        Err(Failure::Run(e)) => {
            eprintln!("rbc-simulate: run failed: {}", format!("{e:#}").replace('\n', " "));
            ExitCode::FAILURE
        }
    }
}

fn start_shape(scene: &Scene) -> &'static str {
    match scene.cell.shape {
        CellShape::Sphere { .. } => "sphere",
        CellShape::Discocyte { .. } => "discocyte",
        CellShape::MeshFromResults { .. } => "mesh-from-results",
    }
}

/// Why the step log `p` could not be written, without touching it: a directory, a folder that
/// does not exist, or an existing file that does not open for writing.
fn step_log_writable(p: &std::path::Path) -> Result<(), String> {
    if p.is_dir() {
        return Err("is a directory".into());
    }
    let folder = p.parent().filter(|f| !f.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    if !folder.is_dir() {
        return Err(format!("its folder {} does not exist", folder.display()));
    }
    if p.exists() {
        std::fs::OpenOptions::new().append(true).open(p).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// True when the scene TOML `stored` (from the results file) describes the same run as `scene`
/// ([`Scene::runs_as`]); a stored scene this build does not read is another run.
fn same_scene(scene: &Scene, stored: &str) -> bool {
    scene.runs_as(stored).unwrap_or(false)
}

/// The stored scene's step method when it differs from this scene's.
fn changed_stepping(scene: &Scene, stored: &str) -> Option<String> {
    let old = Scene::parse(stored, &scene.path).ok()?;
    (old.integrator != scene.integrator).then(|| old.stepping_summary())
}

fn input(message: String) -> Failure {
    Failure::Input(anyhow::anyhow!(message))
}

fn run(args: &Args) -> Result<(), Failure> {
    let scene = Scene::read(&args.scene).map_err(|e| Failure::Input(e.into()))?;
    // a cell that starts in (or too close to) the channel wall is refused here, before anything
    // is built or written (the channel solve would refuse it at the first step, after the run was
    // appended)
    let overlap = rbc_solver::scene::wall_overlap(&scene).map_err(|e| Failure::Input(anyhow::Error::new(e).context(args.scene.display().to_string())))?;
    if let Some(o) = overlap {
        return Err(input(format!("{}: field `cell.position_um`: {:?} um: {o}", args.scene.display(), scene.cell.position_um)));
    }
    if !(args.checkpoint_interval >= 0.0 && args.checkpoint_interval.is_finite()) {
        return Err(input(format!("--checkpoint-interval: {} is not a number of seconds >= 0", args.checkpoint_interval)));
    }
    let suspend_request = SuspendRequest::for_results(&args.out);
    let suspend = suspend_request.path().to_path_buf();
    if suspend.exists() {
        return Err(input(format!("{}: a suspend request for {} is in place: remove it to run", suspend.display(), args.out.display())));
    }
    if args.resume && !args.out.exists() {
        return Err(input(format!("{}: nothing to resume (no such file)", args.out.display())));
    }
    let built = rbc_solver::scene::build(&scene).map_err(|e| Failure::Input(anyhow::Error::new(e).context(args.scene.display().to_string())))?;
    for line in &built.assembled {
        eprintln!("rbc-simulate: {line}");
    }
    // a step log it could not write is refused before the results file is created or gains a run;
    // the log itself is written (an earlier one at that path replaced) only once the run starts
    if let Some(p) = &args.step_log {
        step_log_writable(p).map_err(|why| Failure::Input(anyhow::anyhow!("--step-log {}: {why}", p.display())))?;
    }
    let mut file = ResultsFile::create_or_open_by(&args.out, &format!("rbc-simulate {}", env!("CARGO_PKG_VERSION"))).map_err(|e| Failure::Input(e.into()))?;
    let base = args.run_id.clone().unwrap_or_else(|| scene.name.clone());
    let candidates = (1..).map(|k| if k == 1 { base.clone() } else { format!("{base}-{k}") });
    let run_id = match (&args.run_id, args.resume) {
        (Some(id), _) => id.clone(),
        // resume the last run named after the scene
        (None, true) => candidates.take_while(|id| file.has_run(id)).last().unwrap_or(base),
        (None, false) => candidates.into_iter().find(|id| !file.has_run(id)).expect("unbounded"),
    };
    let [_, y, z] = scene.cell.position_um;
    let attrs = RunAttrs {
        start_shape: start_shape(&scene).to_string(),
        r_init_um: (y * y + z * z).sqrt(),
        y_init_um: y,
        z_init_um: z,
        lambda: scene.fluid.lambda,
        scene: scene.source.clone(),
    };
    let policy = CheckpointPolicy { every_outputs: args.checkpoint_every, every_wall_s: args.checkpoint_interval };
    let checkpoints = CheckpointWriter::new(&args.out, &run_id, &scene.source, policy);
    let where_ = format!("run `{run_id}` in {}", args.out.display());
    let triangles: Vec<[u32; 3]> = built.mesh.triangles.iter().map(|t| [t[0] as u32, t[1] as u32, t[2] as u32]).collect();
    let results = if args.resume {
        let same = |stored: &str| same_scene(&scene, stored);
        match persist::reopen_to(&mut file, &run_id, &same, scene.time.end_s).map_err(|e| Failure::Input(anyhow::Error::new(e).context(where_.clone())))? {
            Ok(r) => {
                eprintln!("rbc-simulate: resuming {where_} at t = {:e} s (sample {})", r.state.t_s, r.rows.len());
                if let Some(was) = changed_stepping(&scene, &r.scene) {
                    eprintln!("rbc-simulate: the step method changed: was {was}, now {}", scene.stepping_summary());
                }
                ResultsObserver::resumed(r, checkpoints).map_err(|e| Failure::Input(anyhow::Error::new(e).context(where_.clone())))?
            }
            Err(NotResumable::NoRun) => return Err(input(format!("{}: nothing to resume (no run `{run_id}`)", args.out.display()))),
            Err(NotResumable::AtEnd(t)) => {
                return Err(input(format!("{where_}: nothing to resume (the run reached its end time {t:e} s: set time.end_s later to continue it)")))
            }
            Err(NotResumable::Ended(status)) => {
                let kept = if status == RunStatus::Unsteady { " and kept no checkpoint of its end" } else { "" };
                return Err(input(format!("{where_}: nothing to resume (the run ended with status {}{kept})", status.as_str())));
            }
            Err(NotResumable::Mismatch(why)) => return Err(input(format!("cannot resume {where_}: {why}"))),
            Err(NotResumable::OtherScene) => return Err(input(format!("cannot resume {where_}: the scene differs from the one the run was started from (beyond the step method and end time)"))),
            Err(NotResumable::NoCheckpoint) => {
                // killed before its first checkpoint: nothing was computed worth keeping
                // (a run killed while it was being created may lack its attributes: nothing to compare)
                let stored = file.run(&run_id).ok().and_then(|r| r.attrs).map(|a| a.scene);
                if stored.is_some_and(|s| !same_scene(&scene, &s)) {
                    return Err(input(format!("cannot resume {where_}: the scene differs from the one the run was started from")));
                }
                eprintln!("rbc-simulate: {where_} has no checkpoint; starting it again from t = 0");
                file.remove_run(&run_id).map_err(|e| Failure::Input(e.into()))?;
                let writer = file.begin_run(&run_id, &attrs, &triangles).map_err(|e| Failure::Input(e.into()))?;
                ResultsObserver::new(writer, args.snapshot_every).with_checkpoints(checkpoints)
            }
        }
    } else {
        let writer = file.begin_run(&run_id, &attrs, &triangles).map_err(|e| Failure::Input(e.into()))?;
        ResultsObserver::new(writer, args.snapshot_every).with_checkpoints(checkpoints)
    };
    let mut results = results.with_suspend(suspend_request);
    let mut progress = Progress::new(&run_id, scene.time.end_s, scene.time.output_interval_s);
    let mut step_log = match &args.step_log {
        Some(p) => Some(StepLog::create(p, &built.mesh.triangles).map_err(|e| Failure::Input(e.into()))?),
        None => None,
    };
    let mut observers = Fanout(vec![&mut results, &mut progress]);
    if let Some(l) = step_log.as_mut() {
        observers.0.push(l);
    }
    let run_start = std::time::Instant::now();
    let ran = built.run(&mut observers);
    drop(observers);
    if results.suspended() {
        eprintln!(
            "rbc-simulate: {where_} suspended at its checkpoint ({} exists): remove it, then continue with --resume",
            suspend.display()
        );
        return Ok(());
    }
    let (summary, _) = ran.map_err(|e| {
        // a checkpoint the run cannot continue from is bad input: the run is kept
        let input = matches!(e, rbc_solver::SolverError::Resume(_));
        let e = anyhow::Error::new(e).context(format!("{}, {where_}", args.scene.display()));
        if input { Failure::Input(e) } else { Failure::Run(e) }
    })?;
    eprintln!(
        "rbc-simulate: run {run_id} written to {} ({} steps, mean step {:.3e} s)",
        args.out.display(),
        summary.accepted,
        summary.h_mean_s(0.0)
    );
    if let Some(ch) = built.channel() {
        let (solves, iterations, _) = ch.gmres_totals();
        if solves > 0 {
            eprintln!("rbc-simulate: {solves} viscosity-contrast solves, {iterations} GMRES iterations ({:.2} per solve)", iterations as f64 / solves as f64);
        }
        let t = ch.solve_times();
        if t.solves > 0 {
            eprintln!(
                "rbc-simulate: velocity solves {:.1} s of this run's {:.1} s wall: GMRES {:.1} (of it the wall's back-substitutions {:.1}), the double layer's build {:.1}, the single layer {:.1}, near field {:.1}, the rest {:.1}",
                t.total_s,
                run_start.elapsed().as_secs_f64(),
                t.gmres_s,
                t.wall_solve_s,
                t.double_layer_build_s,
                t.single_layer_s,
                t.near_field_s,
                t.rest_s()
            );
        }
    }
    file.flush().context("flush").map_err(Failure::Run)?;
    Ok(())
}
