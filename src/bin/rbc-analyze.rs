//! `rbc-analyze`: bright-field recordings -> detections, tracks, group statistics and figures.
//!
//! `rbc-analyze FRAMES_DIR [--out DIR] [--jobs N] [--no-figures]` (contract:
//! ../shared/spec/interfaces.md). Parses and validates the arguments, finds the
//! recordings, runs [`rbc_analysis::experiment::pipeline`] on a rayon pool of `--jobs` threads with a
//! progress bar (terminal) or log lines (otherwise), and writes every output atomically.
//! Any error is one line naming the file, with exit code 1; usage errors exit with 2.

use anyhow::{bail, Context};
use clap::Parser;
use rbc_analysis::experiment::pipeline::{self, StageConfig};
use std::path::PathBuf;
use std::process::ExitCode;

/// Analyse bright-field recordings of red blood cells in a microchannel.
#[derive(Debug, Parser)]
#[command(name = "rbc-analyze", version, about)]
struct Args {
    /// A recording (folder of frames + recording.toml) or a folder whose sub-folders are recordings.
    frames_dir: PathBuf,
    /// Output folder (created if needed).
    #[arg(long, default_value = "rbc-analysis")]
    out: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Write the tables only, no figures (an existing figures/ folder is left as it is).
    #[arg(long)]
    no_figures: bool,
}

/// Validated settings of one run.
struct Settings {
    root: PathBuf,
    out: PathBuf,
    jobs: Option<usize>,
    figures: bool,
}

impl Settings {
    fn from_args(a: Args) -> anyhow::Result<Settings> {
        if !a.frames_dir.exists() {
            bail!("{}: no such file or folder", a.frames_dir.display());
        }
        if !a.frames_dir.is_dir() {
            bail!(
                "{}: not a folder (give a recording folder or a folder of recordings)",
                a.frames_dir.display()
            );
        }
        if a.jobs == Some(0) {
            bail!("--jobs: must be at least 1");
        }
        if a.out.exists() && !a.out.is_dir() {
            bail!("{}: --out exists and is not a folder", a.out.display());
        }
        Ok(Settings {
            root: a.frames_dir,
            out: a.out,
            jobs: a.jobs,
            figures: !a.no_figures,
        })
    }
}

fn run(s: Settings) -> anyhow::Result<()> {
    if let Some(n) = s.jobs {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("--jobs: cannot start the thread pool")?;
    }
    let recordings = pipeline::find_recordings(&s.root)?;
    let progress = rbc::progress::Progress::new("recordings", recordings.len());
    let started = std::time::Instant::now();
    let (outputs, reports) = pipeline::analyse_all(
        &recordings,
        |dir| pipeline::detect_dir(dir, &s.root),
        &StageConfig::default(),
        |r| {
            progress.step(&format!(
                "{}: {} frames, {} objects, {} tracks, {} isolated ({:.1} s)",
                r.name, r.n_frames, r.n_detections, r.n_tracks, r.n_isolated, r.seconds
            ));
            for w in &r.warnings {
                progress.message(&format!("warning: {w}"));
            }
        },
    )?;
    progress.finish();
    for n in &outputs.notes {
        eprintln!("note: {n}");
    }
    let written = pipeline::write_outputs(&s.out, &outputs, s.figures)?;
    let frames: usize = reports.iter().map(|r| r.n_frames).sum();
    let secs = started.elapsed().as_secs_f64();
    eprintln!(
        "rbc-analyze: {} recordings, {} frames ({:.0} frames/s), {} tracks, {} isolated cells in {} groups -> {} ({} files)",
        reports.len(),
        frames,
        frames as f64 / secs.max(1e-9),
        outputs.tracks.len(),
        outputs.tracks.iter().filter(|t| t.isolated).count(),
        outputs.summary.len(),
        s.out.display(),
        written.len()
    );
    Ok(())
}

fn main() -> ExitCode {
    if !rbc::build_cpu::check("rbc-analyze") {
        return ExitCode::from(2);
    }
    let args = Args::parse();
    match Settings::from_args(args).and_then(run) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // `{:#}` joins the context chain on one line.
            eprintln!("rbc-analyze: {}", format!("{e:#}").replace('\n', " "));
            ExitCode::FAILURE
        }
    }
}
