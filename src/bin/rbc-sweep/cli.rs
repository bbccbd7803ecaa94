//! The command line of `rbc-sweep`: one subcommand per mode (`run`, `list`, `task`, `slurm`,
//! `merge`, `start-shape`, `figures`, `trajectories`, `offsets`, `phase`, `steady`, `xdmf`, `reopen`, `relabel`, `status`, `events`); `parse` reads
//! the old flag spelling (`legacy`) when the first argument is no subcommand.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

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
    /// Copy the last shape of an ended run into a file of start shapes under a new run id, with
    /// the run's scene, label and source (the paper's croissant and slipper starts of Fig. 5 b, c:
    /// "obtained from previous simulations that started with the discocyte form"). A sweep reads
    /// it in a `[start_shape.NAME]` table: `shape = "mesh-from-results"`, `results`, `run = NAME`.
    StartShape {
        /// The results file holding the ended run.
        results: PathBuf,
        /// The run whose last snapshot is the start shape.
        run: String,
        /// The new run id (e.g. croissant-start).
        #[arg(long = "as", value_name = "NAME")]
        name: String,
        /// The file of start shapes (created when missing; a name it holds is refused).
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
    /// Draw the steady radial position against the initial offset r_init of the ended runs in one
    /// velocity column (the paper's Fig. 4 at ~6.5 mm/s), and where the runs still going were last
    /// saved, one series per folder of files (a study's state/ is named by its study):
    /// OUT/radial_offset.png and .svg.
    Offsets {
        /// The results files (e.g. the state files of two studies of the same grid).
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// The column: runs whose mean velocity lies within --velocity-tol of this, mm/s.
        #[arg(long, default_value_t = 6.5)]
        velocity_mm_s: f64,
        /// Relative tolerance of the column.
        #[arg(long, default_value_t = 0.05)]
        velocity_tol: f64,
        /// The start shape.
        #[arg(long, default_value = "discocyte")]
        start: String,
        /// A vertical line at this r_init, um (e.g. 0.7, the paper's transition at ~6.5 mm/s).
        #[arg(long, value_name = "UM")]
        mark_um: Option<f64>,
        /// The folder of the figure.
        #[arg(long, default_value = "figures")]
        out: PathBuf,
    },
    /// Draw the steady states against the cell velocity (the paper's Fig. 6) of one start shape,
    /// one colour or marker per folder of files (a study's state/ is named by its study; a run in
    /// two files of one folder is refused): (a) the steady radial position of the croissants and
    /// slippers, (b) the slippers' extents along x, y and z, (c) the membrane's tank-treading
    /// frequency of each class, each a mean over the column's runs weighted by their time in the
    /// steady state, bars min-max: OUT/steady_studies.png and .svg.
    Steady(StudiesFigure),
    /// Draw the phase diagram (mean cell velocity against r_init, the final shapes, r_trans with
    /// its bracket: the paper's Fig. 5 a) of one start shape, one panel per folder of files (a
    /// study's state/ is named by its study; a run in two files of one folder is refused), its runs
    /// still going hollow at the velocity of their last 50 ms: OUT/phase_studies.png and .svg.
    Phase(StudiesFigure),
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
    /// or `run` continues it (e.g. after the sweep's `[steady]` criterion was made stricter): from
    /// the checkpoint of its end state that it kept (runs that ended since session 28), else from
    /// a checkpoint written from its last snapshot (refused with penalty walls, whose
    /// displacements the results do not hold); its summary is removed, its samples, snapshots and
    /// transit records stay.
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
    /// again from their stored evidence under the sweep's `[classify]` thresholds and today's rule,
    /// e.g. after the classification rule changed; nothing is simulated again. Prints every ended
    /// run's label before and after.
    Relabel {
        /// The results files.
        #[arg(required = true)]
        results: Vec<PathBuf>,
        /// The sweep file (for its `[classify]` thresholds).
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
        /// z_um, asphericity, sharpest_fold_deg, velocity_mm_s, shape, tank_treading_hz,
        /// tumbling_hz, steps, and with --sweep
        /// steady_gap, periodic_gap, orbit_drift_um_s, orbit_drift_before_um_s: `-` where the run
        /// has none).
        #[arg(long, value_name = "a,b", requires = "run")]
        field: Option<String>,
    },
    /// Print, as CSV on stdout, the moments each run's cell stopped lying along the flow: the
    /// stretches where its x extent (its length along the channel axis) fell below --fraction of
    /// its median over the run, as when a slipper turns over about z (tumbling) or folds, with
    /// the time of the least x extent, the largest y extent meanwhile over the median x extent
    /// (`across`: ~1 or more when the cell passes broadside, turning over) and the interval
    /// since the previous one. The start shape and a stretch still open at the last sample are
    /// left out. Runs of any status; a running run's file is locked by its process: read its
    /// saved copy.
    Events {
        /// The results files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Only this run.
        #[arg(long, value_name = "ID")]
        run: Option<String>,
        /// The threshold, a fraction of the run's median x extent (0.82: below the studies'
        /// steady swings, 0.86 and above, above their folds, 0.74-0.78, and turn-overs, 0.55-0.60).
        #[arg(long, default_value_t = rbc_analysis::simulated::orbit_events::DEFAULT_FRACTION)]
        fraction: f64,
    },
}

/// What `phase` and `steady` read: the results files of one or more studies (one per folder), one
/// start shape, the velocity columns' tolerance, and where the figure goes.
#[derive(Args, Debug, PartialEq)]
pub struct StudiesFigure {
    /// The results files (e.g. the state files of two studies of the same grid).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// The start shape.
    #[arg(long, default_value = "discocyte")]
    pub start: String,
    /// Relative tolerance for grouping the runs' mean velocities into one column (as
    /// rbc-predict's).
    #[arg(long, default_value_t = 0.05)]
    pub velocity_tol: f64,
    /// The folder of the figure.
    #[arg(long, default_value = "figures")]
    pub out: PathBuf,
}
