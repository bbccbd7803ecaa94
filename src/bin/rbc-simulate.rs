//! `rbc-simulate`: run one scene and append it as a run to `results.h5`.
//!
//! ```text
//! rbc-simulate SCENE.toml [--out results.h5] [--run-id ID] [--snapshot-every N]
//! ```
//!
//! The scene is validated first (errors name the file and field), then only the
//! operators it needs are assembled, and the run is appended to `--out`
//! (status `running` while it runs, `failed` with the diagnosis if the
//! integration stops on a blow-up, `unsteady` at the end time). Progress is a
//! kdam bar on a terminal, plain log lines otherwise. Exit codes: 0 success,
//! 1 the run failed (diagnosis on stderr and in the file), 2 bad input.

use anyhow::{Context, Result};
use clap::Parser;
use rbc_schema::results::{ResultsFile, RunAttrs};
use rbc_schema::scene::{CellShape, Scene};
use rbc_solver::run::progress::Progress;
use rbc_solver::run::results::ResultsObserver;
use rbc_solver::run::Fanout;
use std::path::PathBuf;
use std::process::ExitCode;

/// Run one simulation scene (TOML) and append it to a results file (HDF5).
#[derive(Parser, Debug)]
#[command(name = "rbc-simulate", version)]
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
}

enum Failure {
    Input(anyhow::Error),
    Run(anyhow::Error),
}

fn main() -> ExitCode {
    let args = Args::parse();
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

fn run(args: &Args) -> Result<(), Failure> {
    let scene = Scene::read(&args.scene).map_err(|e| Failure::Input(e.into()))?;
    let built = rbc_solver::scene::build(&scene).map_err(|e| Failure::Input(anyhow::Error::new(e).context(args.scene.display().to_string())))?;
    for line in &built.assembled {
        eprintln!("rbc-simulate: {line}");
    }
    let mut file = ResultsFile::create_or_open_by(&args.out, &format!("rbc-simulate {}", env!("CARGO_PKG_VERSION"))).map_err(|e| Failure::Input(e.into()))?;
    let base = args.run_id.clone().unwrap_or_else(|| scene.name.clone());
    let run_id = if args.run_id.is_some() {
        base
    } else {
        (1..).map(|k| if k == 1 { base.clone() } else { format!("{base}-{k}") }).find(|id| !file.has_run(id)).expect("unbounded")
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
    let triangles: Vec<[u32; 3]> = built.mesh.triangles.iter().map(|t| [t[0] as u32, t[1] as u32, t[2] as u32]).collect();
    let writer = file.begin_run(&run_id, &attrs, &triangles).map_err(|e| Failure::Input(e.into()))?;
    let mut results = ResultsObserver::new(writer, args.snapshot_every);
    let mut progress = Progress::new(&run_id, scene.time.end_s, scene.time.output_interval_s);
    let mut observers = Fanout(vec![&mut results, &mut progress]);
    let (summary, _) = built
        .run(&mut observers)
        .map_err(|e| Failure::Run(anyhow::Error::new(e).context(format!("{}, run {run_id} in {}", args.scene.display(), args.out.display()))))?;
    eprintln!(
        "rbc-simulate: run {run_id} written to {} ({} steps, mean step {:.3e} s)",
        args.out.display(),
        summary.accepted,
        summary.h_mean_s(0.0)
    );
    file.flush().context("flush").map_err(Failure::Run)?;
    Ok(())
}
