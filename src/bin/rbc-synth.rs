//! `rbc-synth`: render synthetic bright-field recordings (frames + recording.toml + truth.csv) from a spec, at random, or the shipped examples.
//!
//! ```text
//! rbc-synth SPEC.toml --out DIR [--seed N]
//! rbc-synth --random --out DIR [--seed N] [--um-per-px 0.2] [--noise 0.01] [--velocity 1.0]
//! rbc-synth --examples examples/frames
//! ```

use anyhow::{bail, Context};
use clap::Parser;
use rbc_analysis::synth;
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(name = "rbc-synth", about = "Render synthetic bright-field recordings of red blood cells with ground truth")]
struct Args {
    /// Spec file (TOML, see `rbc_analysis::synth::SynthSpec`).
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
    /// Cell velocity, mm/s.
    #[arg(long, default_value_t = 1.0)]
    velocity: f64,
    /// (Re)generate the shipped example recordings into this folder.
    #[arg(long, value_name = "DIR")]
    examples: Option<PathBuf>,
}

fn run(args: Args) -> anyhow::Result<()> {
    if let Some(root) = &args.examples {
        for ex in synth::examples::examples() {
            let dir = root.join(&ex.name);
            // remove only what an earlier run of this mode wrote
            if dir.join(synth::TRUTH_FILE).exists() {
                std::fs::remove_dir_all(&dir).with_context(|| format!("{}: cannot remove the old example", dir.display()))?;
            }
            let truth = synth::write_recording(&dir, &ex.spec, ex.seed)?;
            println!("{}: {} frames, {} cells", dir.display(), ex.spec.n_frames, truth.spec.cells.len());
        }
        return Ok(());
    }
    let Some(out) = &args.out else { bail!("--out DIR is required (or use --examples DIR)") };
    let spec = if args.random {
        if !(args.um_per_px.is_finite() && args.um_per_px > 0.0) {
            bail!("--um-per-px must be > 0, got {}", args.um_per_px);
        }
        synth::random_spec(args.seed, args.um_per_px, args.noise, args.velocity)
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
