//! `rbc-bench compare`: runs of the same scene made by different binaries or settings, against a reference run: cost and the science observables side by side.
//!
//! ```text
//! rbc-bench compare REF.h5@CPU_S NAME=RUN.h5@CPU_S [NAME=RUN.h5@CPU_S ...]
//! ```
//!
//! Each file holds one run (the last one is read); `CPU_S` is the process CPU time it took
//! (user + system, s; `scripts/bench_speed.sh` measures it). The observables are those the phase
//! diagram reads: the centroid's y and z (um), the asphericity and the centroid velocity along x
//! (mm/s, the backward difference between outputs as stored in the timeseries); the table gives
//! their largest deviation from the reference over the output times both runs share, the
//! core-seconds per simulated ms and the ratio of each run's cost to the first run's.

use anyhow::{bail, Context, Result};
use rbc_schema::results::{ResultsFile, TimeSample};
use std::path::PathBuf;

/// One run to compare: label, file, CPU seconds.
struct Entry {
    label: String,
    path: PathBuf,
    cpu_s: f64,
}

fn parse(arg: &str, label: Option<&str>) -> Result<Entry> {
    let (spec, label) = match (label, arg.split_once('=')) {
        (Some(l), _) => (arg, l.to_string()),
        (None, Some((l, rest))) => (rest, l.to_string()),
        (None, None) => bail!("`{arg}`: expected NAME=FILE.h5@CPU_S"),
    };
    let (file, cpu) = spec.rsplit_once('@').with_context(|| format!("`{arg}`: expected FILE.h5@CPU_S"))?;
    let cpu_s: f64 = cpu.parse().with_context(|| format!("`{arg}`: CPU seconds `{cpu}` is not a number"))?;
    if !(cpu_s >= 0.0 && cpu_s.is_finite()) {
        bail!("`{arg}`: CPU seconds must be finite and >= 0");
    }
    Ok(Entry { label, path: PathBuf::from(file), cpu_s })
}

fn rows(e: &Entry) -> Result<Vec<TimeSample>> {
    let f = ResultsFile::open(&e.path)?;
    let id = f.run_ids()?.pop().with_context(|| format!("{}: no run", e.path.display()))?;
    let rows = f.timeseries(&id)?;
    if rows.len() < 2 {
        bail!("{}: run {id} has {} rows", e.path.display(), rows.len());
    }
    Ok(rows)
}

/// Largest deviations (y, z, asphericity, x-velocity) of `a` from `reference` at shared output times.
pub fn deviations(a: &[TimeSample], reference: &[TimeSample]) -> Option<[f64; 4]> {
    let mut d = [0.0f64; 4];
    let mut shared = 0;
    for r in a {
        let Some(q) = reference.iter().find(|q| (q.t_s - r.t_s).abs() <= 1e-9 * r.t_s.abs().max(1e-6)) else { continue };
        shared += 1;
        d[0] = d[0].max((r.centroid_um[1] - q.centroid_um[1]).abs());
        d[1] = d[1].max((r.centroid_um[2] - q.centroid_um[2]).abs());
        d[2] = d[2].max((r.asphericity - q.asphericity).abs());
        d[3] = d[3].max((r.velocity_mm_s[0] - q.velocity_mm_s[0]).abs());
    }
    (shared > 1).then_some(d)
}

pub fn run(args: &[String]) -> Result<()> {
    let Some((first, rest)) = args.split_first() else {
        bail!("usage: rbc-bench compare REF.h5@CPU_S NAME=RUN.h5@CPU_S [...]");
    };
    let reference = parse(first, Some("reference"))?;
    let entries: Vec<Entry> = rest.iter().map(|a| parse(a, None)).collect::<Result<_>>()?;
    let ref_rows = rows(&reference)?;
    println!("| run | core-s | simulated ms | core-s per simulated ms | cost vs first | max dy (um) | max dz (um) | max d asphericity | max d u_x (mm/s) |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let span = |r: &[TimeSample]| (r[r.len() - 1].t_s - r[0].t_s) * 1e3;
    let ms = span(&ref_rows);
    println!("| {} | {:.0} | {:.2} | {:.1} | | 0 | 0 | 0 | 0 |", reference.label, reference.cpu_s, ms, reference.cpu_s / ms);
    let mut first_rate = None;
    for e in &entries {
        let r = rows(e)?;
        let ms = span(&r);
        let rate = e.cpu_s / ms;
        let ratio = rate / *first_rate.get_or_insert(rate);
        let d = deviations(&r, &ref_rows).with_context(|| format!("{}: no output time shared with the reference", e.path.display()))?;
        println!(
            "| {} | {:.0} | {:.2} | {:.1} | {:.2} | {:.1e} | {:.1e} | {:.1e} | {:.1e} |",
            e.label, e.cpu_s, ms, rate, ratio, d[0], d[1], d[2], d[3]
        );
    }
    Ok(())
}
