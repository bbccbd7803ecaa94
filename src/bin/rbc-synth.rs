//! `rbc-synth`: render synthetic bright-field recordings (frames + recording.toml + truth.csv) from a spec, at random, or the shipped examples.
//!
//! ```text
//! rbc-synth SPEC.toml --out DIR [--seed N]
//! rbc-synth --random --out DIR [--seed N] [--um-per-px 0.2] [--noise 0.01] [--velocity 1.0]
//! rbc-synth --examples examples/frames
//! rbc-synth --from-results results.h5 --run RUN_ID --out DIR [--snapshot K] [--um-per-px 0.2] [--noise 0.01]
//!           [--velocity MM_S] [--focal-z UM] [--dof-sigma 0.5] [--seed N]
//! rbc-synth --closed-loop results.h5 --out DIR [--um-per-px 0.2] [--noise 0.01] [--dof-sigma 0.5] [--seed N]
//! ```
//!
//! `--from-results` renders a simulated cell (snapshot `K`, default the last, of run
//! `RUN_ID`) in bright field with `rbc_analysis::simulated::render3d` and moves it along +x at the
//! run's mean velocity (or `--velocity`); `truth.csv` carries the solver's label.
//!
//! `--closed-loop` does this for every finished run of the file (its last snapshot, the
//! run's label; recordings in `DIR/<run_id>/`), analyses each recording like `rbc-analyze`,
//! writes `DIR/closed_loop.csv` (solver, pipeline and classifier-alone labels with the
//! shape measures, [`rbc_analysis::simulated::closedloop`]) and prints the agreement tables.

use anyhow::bail;
use clap::Parser;
use rbc_analysis::simulated::synth;
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(name = "rbc-synth", about = "Render synthetic bright-field recordings of red blood cells with ground truth")]
struct Args {
    /// Spec file (TOML, see `rbc_analysis::simulated::synth::SynthSpec`).
    spec: Option<PathBuf>,
    /// Output recording folder (must not hold frames yet).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Noise seed (and, with --random, the seed of the spec).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Render a random plausible recording instead of a spec file.
    #[arg(long)]
    random: bool,
    #[arg(long, default_value_t = 0.2)]
    um_per_px: f64,
    /// Read noise, fraction of full scale.
    #[arg(long, default_value_t = 0.01)]
    noise: f64,
    /// Cell velocity, mm/s (default 1 with --random; the run's mean velocity with --from-results).
    #[arg(long)]
    velocity: Option<f64>,
    /// (Re)generate the shipped example recordings into this folder.
    #[arg(long, value_name = "DIR")]
    examples: Option<PathBuf>,
    /// Render a simulated cell from this results.h5 (with --run).
    #[arg(long, value_name = "RESULTS_H5")]
    from_results: Option<PathBuf>,
    /// Run id inside the results file.
    #[arg(long, value_name = "RUN_ID")]
    run: Option<String>,
    /// Snapshot index of the run (default: the last).
    #[arg(long)]
    snapshot: Option<usize>,
    /// Focal plane height, um (default: the cell's volume centroid).
    #[arg(long)]
    focal_z: Option<f64>,
    /// Closed loop: render every finished run of this results.h5, analyse it, compare labels.
    #[arg(long, value_name = "RESULTS_H5")]
    closed_loop: Option<PathBuf>,
    /// Depth-of-field Gaussian sigma, um.
    #[arg(long, default_value_t = 0.5)]
    dof_sigma: f64,
}

fn from_results(args: &Args, path: &std::path::Path, out: &std::path::Path) -> anyhow::Result<()> {
    use rbc_analysis::simulated::render3d;
    let Some(run) = &args.run else { bail!("--from-results needs --run RUN_ID") };
    if !(args.um_per_px.is_finite() && args.um_per_px > 0.0) {
        bail!("--um-per-px must be > 0, got {}", args.um_per_px);
    }
    let cell = render3d::cell_from_results(path, run, args.snapshot)?;
    let velocity = args.velocity.unwrap_or(cell.velocity_mm_s);
    if !(velocity.is_finite() && velocity > 0.0) {
        bail!("{}: run {run}: velocity {velocity} mm/s is not > 0; give --velocity", path.display());
    }
    let params = render3d::Render3dParams { focal_z_um: args.focal_z, dof_sigma_um: args.dof_sigma, ..Default::default() };
    let img = render3d::cell_image(&cell.mesh, &synth::OpticsSpec::default(), &params)?;
    let (spec, x0) = render3d::single_cell_spec(args.um_per_px, args.noise, velocity, img.bbox_um[1] - img.bbox_um[0]);
    let motion = render3d::CellMotion { x0_um: x0, velocity_mm_s: velocity };
    let truth = render3d::write_recording_3d(out, &spec, &img, &motion, &cell.label, args.seed)?;
    println!(
        "{}: run {run} snapshot at t = {:.4} s ({}), {} frames at {velocity:.3} mm/s; in-focus area {:.1} um^2, y {:+.2} um",
        out.display(),
        cell.t_s,
        cell.label,
        truth.rows.len(),
        img.area_um2,
        img.centroid_um[1]
    );
    Ok(())
}

fn closed_loop(args: &Args, path: &std::path::Path, out: &std::path::Path) -> anyhow::Result<()> {
    use rbc_analysis::simulated::closedloop::{self, Agreement, LoopConfig, LOOP_COLUMNS};
    if !(args.um_per_px.is_finite() && args.um_per_px > 0.0) {
        bail!("--um-per-px must be > 0, got {}", args.um_per_px);
    }
    if !(args.dof_sigma.is_finite() && args.dof_sigma > 0.0) {
        bail!("--dof-sigma must be > 0, got {}", args.dof_sigma);
    }
    let cfg = LoopConfig {
        um_per_px: args.um_per_px,
        noise: args.noise,
        render: rbc_analysis::simulated::render3d::Render3dParams { focal_z_um: args.focal_z, dof_sigma_um: args.dof_sigma, ..Default::default() },
        seed: args.seed,
        ..Default::default()
    };
    // the rendered recordings and closed_loop.csv replace those of an earlier run as one set
    let ids: Vec<String> = rbc_schema::results::read_runs(path)?.into_iter().map(|r| r.run_id).collect();
    let owns = |n: &str| n == "closed_loop.csv" || ids.iter().any(|id| id == n);
    let ((rows, skipped), _) = rbc_schema::output_set::write_set(out, owns, |staging| -> anyhow::Result<_> {
        let (rows, skipped) = closedloop::closed_loop(path, staging, &cfg)?;
        if rows.is_empty() {
            bail!("{}: no finished run to render ({} unfinished)", path.display(), skipped.len());
        }
        rbc_schema::tables::write_table(&staging.join("closed_loop.csv"), &rows, &LOOP_COLUMNS)?;
        Ok((rows, skipped))
    })?;
    for r in &rows {
        println!("{:28} solver {:9} pipeline {:9} classifier {:9} cluster {:5} y {:+.2} um asymmetry {:.3} solidity {:.3} notch {:.3}", r.run_id, r.solver, r.pipeline, r.classifier, r.cluster, r.y_um, r.asymmetry, r.solidity, r.notch);
    }
    if !skipped.is_empty() {
        println!("skipped (unfinished): {}", skipped.join(", "));
    }
    let csv = out.join("closed_loop.csv");
    print!("{}", Agreement::pipeline(&rows).render("rbc-analyze pipeline vs solver"));
    print!("{}", Agreement::classifier(&rows).render("shape classifier alone vs solver"));
    println!("{}", csv.display());
    Ok(())
}

fn run(args: Args) -> anyhow::Result<()> {
    if let Some(root) = &args.examples {
        // the example folders replace those of an earlier run as one set; other files (README) stay
        let examples = synth::examples::examples();
        let names: Vec<&str> = examples.iter().map(|ex| ex.name.as_str()).collect();
        rbc_schema::output_set::write_set(root, |n| names.contains(&n), |staging| -> anyhow::Result<()> {
            for ex in &examples {
                let truth = synth::write_recording(&staging.join(&ex.name), &ex.spec, ex.seed)?;
                println!("{}: {} frames, {} cells", root.join(&ex.name).display(), ex.spec.n_frames, truth.spec.cells.len());
            }
            Ok(())
        })?;
        return Ok(());
    }
    let Some(out) = &args.out else { bail!("--out DIR is required (or use --examples DIR)") };
    if let Some(path) = &args.from_results {
        return from_results(&args, path, out);
    }
    if let Some(path) = &args.closed_loop {
        return closed_loop(&args, path, out);
    }
    let spec = if args.random {
        if !(args.um_per_px.is_finite() && args.um_per_px > 0.0) {
            bail!("--um-per-px must be > 0, got {}", args.um_per_px);
        }
        synth::random_spec(args.seed, args.um_per_px, args.noise, args.velocity.unwrap_or(1.0))
    } else {
        let Some(path) = &args.spec else { bail!("give a SPEC.toml, --random or --examples DIR") };
        synth::read_spec(path)?
    };
    let truth = synth::write_recording(out, &spec, args.seed)?;
    println!("{}: {} frames, {} cells, {} truth rows", out.display(), spec.n_frames, spec.cells.len(), truth.rows.len());
    Ok(())
}

fn main() -> std::process::ExitCode {
    match run(Args::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("rbc-synth: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
