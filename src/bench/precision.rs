//! `rbc-bench precision`: error of the flow validation cases against wall time, per mesh level and integrator (work-precision table and plot).
//!
//! ```text
//! rbc-bench precision [--levels 2,3,4] [--schemes bs23,ros2] [--cases capsule,drop]
//!                     [--atol 4e-5] [--out rbc-bench-precision] [--paper-cell MS]
//!                     [--paper-configs plain,bending,stiff] [--paper-atols 4e-5,1e-5]
//!                     [--reference bs23] [--reference-factor 100]
//! ```
//!
//! For each case (capsule Ca = 0.01, C = 1; drop Ca = 0.01; lambda = 1, see
//! `rbc_solver::validation`), mesh level (`8 * 4^level` triangles:
//! 2 -> 128, 3 -> 512, 4 -> 2048, 5 -> 8192) and integrator, runs 30 relaxation
//! times and prints the Taylor deformation error against the small-deformation
//! reference with the wall time; draws `work_precision.png/.svg` in `--out`.
//! `--paper-cell MS` also times the paper's cell (2048-triangle discocyte,
//! lambda = 5, Krueger Skalak kappa_S = 5e-6, kappa_A = 100 kappa_S, shear
//! 100 1/s; with and without bending, and a stiff kappa_A = 1000 kappa_S at Ca 0.01)
//! for MS simulated milliseconds with each integrator, at equal error against a
//! tight-tolerance reference ([`super::precision_cell`]). Schemes: bs23, ros2,
//! ros34pw2, ros34pw2-plain, ros34pw2-local (the last two for the paper cell only).

use anyhow::{bail, Context, Result};
use plotters::prelude::*;
use rbc_analysis::plot::{Figure, FONT_FAMILY};
use rbc_solver::validation::{run_case, Case};
use std::path::PathBuf;
use std::time::Instant;

/// One row of the work-precision table.
#[derive(Debug, Clone)]
struct Row {
    case: &'static str,
    triangles: usize,
    scheme: String,
    d: f64,
    d_ref: f64,
    steps: usize,
    h_mean_s: f64,
    wall_s: f64,
}

impl Row {
    fn error(&self) -> f64 {
        (self.d / self.d_ref - 1.0).abs()
    }
}

struct Options {
    levels: Vec<u32>,
    schemes: Vec<String>,
    cases: Vec<String>,
    atol_um: f64,
    out: PathBuf,
    paper_cell_ms: Option<f64>,
    paper_configs: Vec<String>,
    paper_atols: Vec<f64>,
    reference: String,
    reference_factor: f64,
}

fn parse(args: &[String]) -> Result<Options> {
    let mut o = Options {
        levels: vec![2, 3, 4],
        schemes: vec!["bs23".into(), "ros2".into()],
        cases: vec!["capsule".into(), "drop".into()],
        atol_um: 4e-5,
        out: PathBuf::from("rbc-bench-precision"),
        paper_cell_ms: None,
        paper_configs: vec!["plain".into(), "bending".into(), "stiff".into()],
        paper_atols: Vec::new(),
        reference: "bs23".into(),
        reference_factor: 100.0,
    };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a} needs a value"));
        let list = |s: &str| s.split(',').map(str::trim).filter(|s| !s.is_empty()).map(String::from).collect::<Vec<_>>();
        match a.as_str() {
            "--levels" => o.levels = list(val()?).iter().map(|s| s.parse().with_context(|| format!("--levels: `{s}` is not a level"))).collect::<Result<_>>()?,
            "--schemes" => o.schemes = list(val()?),
            "--cases" => o.cases = list(val()?),
            "--atol" => o.atol_um = val()?.parse().context("--atol")?,
            "--out" => o.out = PathBuf::from(val()?),
            "--paper-cell" => o.paper_cell_ms = Some(val()?.parse().context("--paper-cell")?),
            "--paper-configs" => o.paper_configs = list(val()?),
            "--paper-atols" => o.paper_atols = list(val()?).iter().map(|s| s.parse().with_context(|| format!("--paper-atols: `{s}`"))).collect::<Result<_>>()?,
            "--reference" => o.reference = val()?.clone(),
            "--reference-factor" => o.reference_factor = val()?.parse().context("--reference-factor")?,
            other => bail!("unknown option {other} (see the doc comment of src/bench/precision.rs)"),
        }
    }
    if let Some(l) = o.levels.iter().find(|&&l| !(1..=6).contains(&l)) {
        bail!("--levels: {l} is outside 1..=6");
    }
    Ok(o)
}

struct Plot<'a>(&'a [Row]);

impl Figure for Plot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, plotters::coord::Shift>) -> rbc_analysis::plot::DrawResult
    where
        DB::ErrorType: 'static,
    {
        let rows = self.0;
        let (tmin, tmax) = rows.iter().fold((f64::MAX, 0.0f64), |(a, b), r| (a.min(r.wall_s), b.max(r.wall_s)));
        let (emin, emax) = rows.iter().fold((f64::MAX, 0.0f64), |(a, b), r| (a.min(r.error().max(1e-6)), b.max(r.error())));
        let mut chart = ChartBuilder::on(root)
            .caption("Work-precision: Taylor deformation error vs wall time", (FONT_FAMILY, 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d((tmin / 2.0..tmax * 2.0).log_scale(), (emin / 2.0..emax * 2.0).log_scale())?;
        chart.configure_mesh().x_desc("wall time (s)").y_desc("|D / D_ref - 1|").label_style((FONT_FAMILY, 14)).draw()?;
        let colours = [RED, BLUE, GREEN, MAGENTA];
        let mut k = 0;
        for case in ["capsule", "drop"] {
            for scheme in ["bs23", "ros2", "ros34pw2"] {
                let mut pts: Vec<(f64, f64)> = rows.iter().filter(|r| r.case == case && r.scheme == scheme).map(|r| (r.wall_s, r.error().max(1e-6))).collect();
                if pts.is_empty() {
                    continue;
                }
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                let c = colours[k % colours.len()];
                k += 1;
                chart.draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?.label(format!("{case} {scheme}")).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
                chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
            }
        }
        chart.configure_series_labels().label_font((FONT_FAMILY, 14)).background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
        Ok(())
    }
}

/// Run the benchmark with the remaining command-line arguments.
pub fn run(args: &[String]) -> Result<()> {
    let o = parse(args)?;
    let threads = rayon::current_num_threads();
    let mut rows = Vec::new();
    println!("| case | triangles | integrator | D | D_ref | error | steps | mean h (s) | wall (s) | core-s |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for case_name in &o.cases {
        let (name, case): (&'static str, Case) = match case_name.as_str() {
            "capsule" => ("capsule", Case::Capsule { ca: 0.01, c: 1.0, lambda: 1.0 }),
            "drop" => ("drop", Case::Drop { ca: 0.01, lambda: 1.0 }),
            other => bail!("--cases: unknown case {other} (capsule, drop)"),
        };
        for &level in &o.levels {
            for scheme in &o.schemes {
                let t0 = Instant::now();
                let cpu0 = super::clock::process_cpu_ticks_s();
                let r = run_case(case, level, scheme, o.atol_um, 30.0).with_context(|| format!("{name} level {level} {scheme}"))?;
                let row = Row {
                    case: name,
                    triangles: 8 * 4usize.pow(level),
                    scheme: scheme.clone(),
                    d: r.d,
                    d_ref: r.d_ref,
                    steps: r.summary.accepted,
                    h_mean_s: r.summary.h_mean_s(0.0),
                    wall_s: t0.elapsed().as_secs_f64(),
                };
                // process CPU time where available (a shared machine inflates wall x threads)
                let core_s = match (cpu0, super::clock::process_cpu_ticks_s()) {
                    (Some(a), Some(b)) => b - a,
                    _ => row.wall_s * threads as f64,
                };
                println!(
                    "| {} | {} | {} | {:.5e} | {:.5e} | {:.2e} | {} | {:.2e} | {:.2} | {:.2} |",
                    row.case, row.triangles, row.scheme, row.d, row.d_ref, row.error(), row.steps, row.h_mean_s, row.wall_s, core_s
                );
                rows.push(row);
            }
        }
    }
    if !rows.is_empty() {
        let paths = Plot(&rows).save(&o.out, "work_precision", (900, 600))?;
        println!("\nplot: {}", paths[0].display());
    }
    if let Some(ms) = o.paper_cell_ms {
        let atols = if o.paper_atols.is_empty() { vec![o.atol_um] } else { o.paper_atols.clone() };
        super::precision_cell::run(&o.paper_configs, &o.schemes, ms, o.atol_um, &atols, &o.reference, o.reference_factor)?;
    }
    Ok(())
}
