//! `rbc-predict`: the croissant fraction predicted from simulated phase diagrams and the measured entrance positions (paper Figs. 5, 7, 8).
//!
//! ```text
//! rbc-predict --sims results.h5 [--sims more.h5 ...] --entry entry.csv
//!             [--observed summary.csv] [--kde kde.csv] [--out DIR]
//!             [--velocity-tol 0.05] [--position-uncertainty-um 0.1]
//! ```
//!
//! Writes `DIR/thresholds.csv`, `DIR/prediction.csv` and `DIR/figures/`
//! (default `DIR` = `rbc-prediction/`) after everything has been computed, as one
//! set: all staged beside `DIR`, then moved into place (a failure leaves the
//! previous outputs as they were). Failed and unfinished runs are skipped with a warning.
//! Without `--kde`, `kde.csv` beside `entry.csv` is used when present, else the
//! slipper-only densities are computed from `tracks.csv` beside `entry.csv`
//! (MATLAB-compatible ksdensity); their two peaks give the experiment's slipper
//! off-centre positions.

use anyhow::{bail, Context, Result};
use clap::Parser;
use rbc_analysis::predict::{self, PredictInputs};
use rbc_analysis::simulated::phase::DEFAULT_VELOCITY_REL_TOL;
use rbc_analysis::types::prediction::{NextRun, PredictConfig, VelocitySource, POSITION_UNCERTAINTY_UM};
use rbc_schema::results::read_runs;
use rbc_schema::tables::{self, KdeRow, TrackRow};
use std::path::PathBuf;
use std::process::ExitCode;

/// Predict the fraction of croissants from simulations (results.h5) and the entrance y-distribution (entry.csv).
#[derive(Parser, Debug)]
#[command(name = "rbc-predict", version)]
struct Args {
    /// Simulation results (results.h5); repeat to combine several files.
    #[arg(long, required = true)]
    sims: Vec<PathBuf>,
    /// Entering cells (entry.csv of rbc-analyze: pressure_mbar, y_um, velocity_mm_s).
    #[arg(long)]
    entry: PathBuf,
    /// Observed fractions and velocities (summary.csv of rbc-analyze); the row closest to 10 mm per pressure is used.
    #[arg(long)]
    observed: Option<PathBuf>,
    /// Experiment's y-densities (kde.csv of rbc-analyze); default: kde.csv beside the entry file, if present.
    #[arg(long)]
    kde: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "rbc-prediction")]
    out: PathBuf,
    /// Relative tolerance for grouping simulated mean velocities into one column.
    #[arg(long, default_value_t = DEFAULT_VELOCITY_REL_TOL)]
    velocity_tol: f64,
    /// Position uncertainty s_P of the measured y, um.
    #[arg(long, default_value_t = POSITION_UNCERTAINTY_UM)]
    position_uncertainty_um: f64,
    /// Also predict phi from the runs as they were after travelling D mm (their transit records,
    /// e.g. 10 for the experiment's 10 mm window) instead of their steady states:
    /// `prediction_transit_<D>mm.csv` and `thresholds_transit_<D>mm.csv` beside the others.
    #[arg(long, value_name = "D")]
    transit_mm: Option<f64>,
}

fn main() -> ExitCode {
    if !rbc::build_cpu::check("rbc-predict") {
        return ExitCode::from(2);
    }
    let args = Args::parse();
    // a libhdf5 call that hangs on a damaged file ends the command with one line (exit 2)
    rbc_schema::hdf5_watch::enable_from_env("rbc-predict");
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("rbc-predict: {}", format!("{e:#}").replace('\n', " "));
            ExitCode::FAILURE
        }
    }
}

fn run(args: &Args) -> Result<()> {
    if !(args.velocity_tol >= 0.0 && args.velocity_tol < 1.0) {
        bail!("--velocity-tol {}: must be in [0, 1)", args.velocity_tol);
    }
    if !(args.position_uncertainty_um >= 0.0 && args.position_uncertainty_um.is_finite()) {
        bail!("--position-uncertainty-um {}: must be a finite value >= 0", args.position_uncertainty_um);
    }
    let config = PredictConfig { velocity_rel_tol: args.velocity_tol, position_uncertainty_um: args.position_uncertainty_um };

    // read everything first
    let mut runs = Vec::new();
    for p in &args.sims {
        let mut r = read_runs(p)?;
        if let Some(dup) = r.iter().find(|x| runs.iter().any(|y: &rbc_schema::results::RunRecord| y.run_id == x.run_id)) {
            bail!("{}: run `{}` also occurs in an earlier --sims file", p.display(), dup.run_id);
        }
        runs.append(&mut r);
    }
    let entry = tables::read_entry(&args.entry)?;
    let observed = match &args.observed {
        Some(p) => Some(tables::read_summary(p)?),
        None => None,
    };
    let kde_path = args.kde.clone().or_else(|| {
        let p = args.entry.parent().map(|d| d.join("kde.csv")).unwrap_or_else(|| PathBuf::from("kde.csv"));
        p.exists().then_some(p)
    });
    let beside_entry = |name: &str| args.entry.parent().map(|d| d.join(name)).unwrap_or_else(|| PathBuf::from(name));
    let kde: Option<Vec<KdeRow>> = match &kde_path {
        Some(p) => Some(tables::read_table(p, tables::columns::KDE)?),
        None => {
            // no kde.csv: compute the slipper-only densities from tracks.csv beside entry.csv, if present
            let tracks = beside_entry("tracks.csv");
            if tracks.exists() {
                let rows: Vec<TrackRow> = tables::read_table(&tracks, tables::columns::TRACKS)?;
                eprintln!("note: slipper densities computed from {} (no kde.csv)", tracks.display());
                Some(predict::offset::slipper_densities(&rows))
            } else {
                None
            }
        }
    };

    let sims_label = args.sims.first().cloned().unwrap_or_default();
    let inputs = PredictInputs {
        runs: &runs,
        sims_path: &sims_label,
        entry: &entry,
        entry_path: &args.entry,
        observed: observed.as_deref().zip(args.observed.as_deref()),
        kde: kde.as_deref(),
    };
    let pred = predict::predict(&inputs, config)?;
    let transit = match args.transit_mm {
        None => None,
        Some(d) => {
            let (seen, missing) = predict::transit::at_transit(&runs, d);
            if seen.is_empty() {
                bail!("--transit-mm {d}: no run of {} has travelled {d} mm yet ({} runs)", sims_label.display(), runs.len());
            }
            for id in &missing {
                eprintln!("warning: run {id} has no transit record at {d} mm: left out of the transit prediction");
            }
            let at = PredictInputs { runs: &seen, ..inputs };
            Some((d, predict::predict(&at, config).with_context(|| format!("--transit-mm {d}"))?))
        }
    };

    for s in &pred.skipped {
        eprintln!("warning: run {} skipped: {}", s.run_id, s.reason);
    }
    for w in pred.warnings.iter().chain(&pred.next_run_notes) {
        eprintln!("warning: {w}");
    }
    if pred.groups.iter().any(|g| g.velocity_source == VelocitySource::Entry) {
        eprintln!("note: groups without an observed row use the mean and std of their entering cells' velocities");
    }
    if kde.is_some() && pred.experiment_offsets.is_empty() {
        eprintln!("note: no slipper-only density with a peak on each side of the axis: no measured slipper offsets");
    }

    if let Some((d, t)) = &transit {
        for w in &t.warnings {
            eprintln!("warning: at {d} mm: {w}");
        }
    }
    // the tables, figures and transit tables replace the previous ones as one set
    let fill = |dir: &std::path::Path| -> Result<()> {
        predict::write_outputs(&pred, dir)?;
        rbc_analysis::plot::prediction::write_figures(&pred, &dir.join("figures"))?;
        if let Some((d, t)) = &transit {
            predict::write_transit_outputs(t, *d, dir)?;
        }
        Ok(())
    };
    let ((), written) = rbc_schema::output_set::write_set_with(&args.out, predict::is_output_name, fill, rbc::unstaged).with_context(|| format!("writing {}", args.out.display()))?;
    eprintln!(
        "rbc-predict: {} runs used ({} skipped), {} thresholds, {} predictions; wrote {} files to {}",
        pred.points.len(),
        pred.skipped.len(),
        pred.thresholds.len(),
        pred.rows.len(),
        written.len(),
        args.out.display()
    );
    print_rows("steady states", &pred.rows);
    if let Some((d, t)) = &transit {
        print_rows(&format!("after {d} mm"), &t.rows);
    }
    print_next_runs(&pred.next_runs);
    Ok(())
}

fn print_next_runs(runs: &[NextRun]) {
    if runs.is_empty() {
        println!("next runs: none (every entering cell is decided by the simulated brackets, or lies beyond the runs' largest start)");
        return;
    }
    println!("next runs (each halves the entering cells its bracket leaves undecided; next_runs.csv):");
    println!("start_shape  pressure_mbar  u_mm_s  mean_flow_mm_s  r_init_um  bracket_um    undecided  column  awaits");
    for r in runs {
        let bracket = format!("[{:.2}, {:.2}]", r.r_lo_um, r.r_hi_um);
        let undecided = format!("{}/{}", r.undecided, r.cells);
        let flow = r.mean_flow_mm_s.map_or_else(|| "-".to_string(), |f| format!("{f:.3}"));
        println!(
            "{:<12} {:>13.1} {:>7.3} {flow:>15} {:>10.2} {bracket:<13} {undecided:>9}  {:<7} {}",
            r.start_shape, r.pressure_mbar, r.velocity_mm_s, r.r_init_um, r.column, r.awaits
        );
    }
}

fn print_rows(title: &str, rows: &[tables::PredictionRow]) {
    println!("{title}:");
    println!("start_shape  pressure_mbar  u_mm_s  sigma_u  r_trans_um  phi    [phi_lo, phi_hi]  observed  status");
    for r in rows {
        let obs = r.phi_observed.map(|v| format!("{v:.3}")).unwrap_or_else(|| "-".into());
        println!(
            "{:<12} {:>13.1} {:>7.3} {:>8.3} {:>11.3} {:>6.3} [{:.3}, {:.3}]    {:<9} {}",
            r.start_shape, r.pressure_mbar, r.velocity_mm_s, r.velocity_std_mm_s, r.r_trans_um, r.phi, r.phi_lo, r.phi_hi, obs, r.status
        );
    }
}
