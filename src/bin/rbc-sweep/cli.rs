//! The command line of `rbc-sweep`: one subcommand per mode (`run`, `list`, `task`, `slurm`,
//! `merge`, `figures`, `trajectories`, `xdmf`, `reopen`, `relabel`, `status`), and the old flag spelling
//! (`rbc-sweep SWEEP.toml --slurm DIR`, `--merge`, ...) when the first argument is no subcommand.

use crate::legacy::LegacyArgs;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// Run a sweep of simulations (the phase diagram of the paper) locally or as a Slurm array, merge
/// the parts, draw the figures, follow the progress of running runs.
#[derive(Parser, Debug)]
#[command(
    name = "rbc-sweep",
    version,
    after_help = "The old flag spelling still works: `rbc-sweep SWEEP.toml [--out F] [--jobs N] [--list] \
                  [--task I] [--slurm DIR]`, `rbc-sweep --merge PARTS --out F`, `--figures R --out DIR`, \
                  `--trajectories FILES --out DIR`, `[SWEEP.toml] --study-status FILES [--run ID --field a,b]`, \
                  `--xdmf R [--run ID]`.\n\n\
                  Environment: RBC_MAX_MEMORY_GB=G, the memory (GB) a channel scene may plan for (default: this \
                  machine's MemTotal; see `rbc-sweep run --help`)."
)]
pub struct Cli {
    #[command(subcommand)]
    pub cmd: Cmd,
}

/// What `rbc-sweep` does; both spellings parse into one of these.
#[derive(Subcommand, Debug, PartialEq)]
pub enum Cmd {
    /// Run every run of a sweep on this machine, `--jobs` at a time, into one results file.
    ///
    /// Resumable: run it again after a kill and finished runs are skipped, a killed run resumes
    /// from its checkpoint. A run stops at its next checkpoint, unfinished and resumable, when the
    /// file `<out>.suspend` appears. Exit codes: 0 success, 1 some runs could not be executed
    /// (listed; retried next time), 2 bad input.
    #[command(after_help = rbc::MEMORY_HELP)]
    Run {
        /// The sweep file (TOML).
        sweep: PathBuf,
        /// The results file.
        #[arg(long, default_value = "results.h5")]
        out: PathBuf,
        /// Runs at a time (default: available cores / threads_per_run).
        #[arg(long)]
        jobs: Option<usize>,
        /// Execute again runs that failed in an earlier attempt.
        #[arg(long)]
        retry_failed: bool,
    },
    /// Print the expanded runs of a sweep (index, run_id, start shape, velocity, offset, status,
    /// note) as a tab-separated table, after validating every scene: status `overlaps-wall` (the
    /// note says where) for a run whose cell would start in, or within 0.1 um of, the channel
    /// wall (`run` and `task` record it so and never run it), `to-run` otherwise.
    List {
        /// The sweep file (TOML).
        sweep: PathBuf,
    },
    /// Execute one run of a sweep (a Slurm array task) into its own results file.
    #[command(after_help = rbc::MEMORY_HELP)]
    Task {
        /// The sweep file (TOML).
        sweep: PathBuf,
        /// The run's index (0-based, as printed by `list`).
        index: usize,
        /// The results file of this run.
        #[arg(long)]
        out: PathBuf,
    },
    /// Write a Slurm array job (one task per run), a merge job, submit.sh and runs.tsv into DIR.
    Slurm {
        /// The sweep file (TOML).
        sweep: PathBuf,
        /// The folder for the scripts (parts/ and results.h5 go there too).
        dir: PathBuf,
    },
    /// Merge results files (e.g. the parts of a Slurm array) into one; a run in two files is refused.
    Merge {
        /// The results files to gather.
        #[arg(required = true, value_name = "PARTS")]
        parts: Vec<PathBuf>,
        /// The merged results file.
        #[arg(long)]
        out: PathBuf,
    },
    /// Draw the figures of a results file (Figs. 5, 6 and shape views) as PNG + SVG into a folder.
    Figures {
        /// The results file.
        results: PathBuf,
        /// The folder of the figures.
        #[arg(long, default_value = "figures")]
        out: PathBuf,
    },
    /// Draw the lateral position and asphericity against time of every run (any status) of
    /// results files, e.g. a study's state: OUT/trajectories.png and .svg.
    Trajectories {
        /// The results files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// The folder of the figure.
        #[arg(long, default_value = "figures")]
        out: PathBuf,
    },
    /// Write `<stem>.<run_id>.xmf` beside a results file for every run with snapshots: a time
    /// series of the run's triangle meshes that ParaView opens, pointing into the HDF5 file.
    Xdmf {
        /// The results file.
        results: PathBuf,
        /// Only this run.
        #[arg(long, value_name = "ID")]
        run: Option<String>,
    },
    /// Reopen a run that ended (steady, periodic or unsteady) at its last state, so that `task`
    /// or `run` continues it (e.g. after the sweep's [steady] criterion was made stricter): a
    /// checkpoint is written from its last snapshot and its summary is removed; its samples,
    /// snapshots and transit records stay.
    Reopen {
        /// The results file holding the run.
        results: PathBuf,
        /// The run.
        run: String,
        /// The sweep file the run belongs to (for its snapshot cadence).
        #[arg(long, value_name = "SWEEP.toml")]
        sweep: PathBuf,
    },
    /// Decide the labels (croissant / slipper / other, tank-treading, tumbling) of the ended runs
    /// again from their stored evidence under the sweep's [classify] thresholds and today's rule,
    /// e.g. after the classification rule changed; nothing is simulated again. Prints every ended
    /// run's label before and after.
    Relabel {
        /// The results files.
        #[arg(required = true)]
        results: Vec<PathBuf>,
        /// The sweep file (for its [classify] thresholds).
        #[arg(long, value_name = "SWEEP.toml")]
        sweep: PathBuf,
    },
    /// Print the progress of every run of results files (read from the checkpoints of unfinished
    /// runs, which may be running) as a Markdown table, or single fields of one run (for scripts).
    Status {
        /// The results files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Label the shapes with this sweep file's classifier settings (default: the defaults).
        #[arg(long, value_name = "SWEEP.toml")]
        sweep: Option<PathBuf>,
        /// Only this run (of exactly one results file).
        #[arg(long, value_name = "ID")]
        run: Option<String>,
        /// With --run: print only these fields, space-separated (run_id, status, t_s, y_um,
        /// z_um, asphericity, sharpest_fold_deg, velocity_mm_s, shape, steps).
        #[arg(long, value_name = "a,b", requires = "run")]
        field: Option<String>,
    },
}

/// How parsing ended without a command: help/version printed (exit 0), or an error to report
/// on one line (exit 2).
pub enum Stop {
    Printed(clap::Error),
    Input(String),
}

/// The subcommand names, as the first argument.
fn subcommand_names() -> Vec<String> {
    Cli::command().get_subcommands().map(|c| c.get_name().to_string()).collect()
}

/// Parse the arguments (`argv[0]` is the program): the subcommand spelling when the first
/// argument names a subcommand (or asks for help/version), otherwise the old flag spelling. A
/// bare word that is no subcommand, no file and no path is an unknown subcommand.
pub fn parse(argv: &[OsString]) -> Result<Cmd, Stop> {
    let names = subcommand_names();
    let Some(first) = argv.get(1) else {
        return Err(Stop::Input(format!(
            "missing a subcommand ({}); see rbc-sweep --help",
            names.join(", ")
        )));
    };
    let first_str = first.to_string_lossy();
    let new_spelling = names.iter().any(|n| *n == first_str)
        || matches!(&*first_str, "help" | "--help" | "-h" | "--version" | "-V");
    if new_spelling {
        return Cli::try_parse_from(argv).map(|c| c.cmd).map_err(clap_stop);
    }
    let bare_word = !first_str.starts_with('-') && !first_str.contains(['.', '/']);
    if bare_word && !Path::new(first).exists() {
        return Err(Stop::Input(format!(
            "unknown subcommand `{first_str}` (one of {}; or a sweep file first, the old spelling)",
            names.join(", ")
        )));
    }
    let matches = LegacyArgs::command().try_get_matches_from(argv).map_err(clap_stop)?;
    let args = LegacyArgs::from_arg_matches(&matches).map_err(clap_stop)?;
    args.into_cmd().map_err(|e| Stop::Input(format!("{e:#}")))
}

/// A clap error as a `Stop`: help and version texts are printed as clap formats them, an error
/// becomes one line (its message and tips, without the usage block).
fn clap_stop(e: clap::Error) -> Stop {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
        return Stop::Printed(e);
    }
    let text = e.render().to_string();
    let line = text
        .lines()
        .take_while(|l| !l.starts_with("Usage:"))
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    Stop::Input(line.trim_start_matches("error: ").to_string())
}
