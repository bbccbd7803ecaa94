//! The old flag spelling of `rbc-sweep` (`rbc-sweep SWEEP.toml --slurm DIR`, `--merge PARTS --out F`,
//! ...), still used by scripts, generated Slurm jobs and notes: parsed as before and translated
//! into the subcommand it means, with the same precedence and the same refusals.

use crate::cli::Cmd;
use anyhow::{anyhow, Result};
use clap::Parser;
use std::path::PathBuf;

/// The old spelling: one flag per mode.
#[derive(Parser, Debug)]
#[command(name = "rbc-sweep", version)]
pub struct LegacyArgs {
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
    /// Draw y, z and asphericity against time of every run of these results files into --out.
    #[arg(long, num_args = 1.., value_name = "FILES")]
    trajectories: Vec<PathBuf>,
    /// Print the progress of every run in these results files as a Markdown table.
    #[arg(long, num_args = 1.., value_name = "FILES")]
    study_status: Vec<PathBuf>,
    /// Write `<stem>.<run_id>.xmf` beside this results file for every run with snapshots.
    #[arg(long, value_name = "RESULTS")]
    xdmf: Option<PathBuf>,
    /// With --study-status and one file, or with --xdmf: only this run.
    #[arg(long, value_name = "ID")]
    run: Option<String>,
    /// With --study-status and --run: print only these fields, space-separated.
    #[arg(long, value_name = "a,b", requires = "run")]
    field: Option<String>,
}

impl LegacyArgs {
    /// The subcommand these flags mean: the first of merge, figures, trajectories, xdmf,
    /// study-status, list, slurm, task, run that is given; flags another mode owns are refused
    /// as before.
    pub fn into_cmd(self) -> Result<Cmd> {
        let a = self;
        let sweep_mode = a.sweep.is_some() || a.task.is_some() || a.slurm.is_some();
        if !a.merge.is_empty() {
            if sweep_mode || a.figures.is_some() {
                return Err(anyhow!("--merge takes only --out"));
            }
            let out = a.out.ok_or_else(|| anyhow!("--merge needs --out FILE"))?;
            return Ok(Cmd::Merge { parts: a.merge, out });
        }
        let figures_out = || a.out.clone().unwrap_or_else(|| PathBuf::from("figures"));
        if let Some(results) = a.figures.clone() {
            if sweep_mode {
                return Err(anyhow!("--figures takes only --out"));
            }
            return Ok(Cmd::Figures { results, out: figures_out() });
        }
        if !a.trajectories.is_empty() {
            if sweep_mode {
                return Err(anyhow!("--trajectories takes only --out"));
            }
            return Ok(Cmd::Trajectories { out: figures_out(), files: a.trajectories });
        }
        if let Some(results) = a.xdmf {
            if sweep_mode || a.out.is_some() {
                return Err(anyhow!(
                    "--xdmf takes only --run (the .xmf files go beside the results file)"
                ));
            }
            return Ok(Cmd::Xdmf { results, run: a.run });
        }
        if !a.study_status.is_empty() {
            return Ok(Cmd::Status { files: a.study_status, sweep: a.sweep, run: a.run, field: a.field });
        }
        if a.run.is_some() {
            return Err(anyhow!("--run needs --study-status or --xdmf"));
        }
        let sweep = a.sweep.ok_or_else(|| {
            anyhow!("missing the sweep file (or --merge / --figures / --study-status)")
        })?;
        if a.list {
            return Ok(Cmd::List { sweep });
        }
        if let Some(dir) = a.slurm {
            return Ok(Cmd::Slurm { sweep, dir });
        }
        if let Some(index) = a.task {
            let out = a.out.ok_or_else(|| anyhow!("--task needs --out FILE"))?;
            return Ok(Cmd::Task { sweep, index, out });
        }
        Ok(Cmd::Run {
            sweep,
            out: a.out.unwrap_or_else(|| PathBuf::from("results.h5")),
            jobs: a.jobs,
            retry_failed: a.retry_failed,
        })
    }
}
