//! `rbc-bench periodic`: cost of the periodic-channel parts (membrane forces, spectral Ewald sums, wall operator).
//!
//! Usage: `rbc-bench periodic [--quick]`. Prints three tables: membrane force
//! evaluations on the 2048-triangle discocyte; spectral Ewald Stokeslet and
//! stresslet sums at the paper's tolerance 5e-5 for growing point counts (the
//! smooth part should grow like N log N); the channel wall operator
//! (assembly, LU factorisation, one velocity solve) for several wall resolutions; the channel
//! solve with viscosity contrast ([`super::channel_lambda`]).

use anyhow::{bail, Context};

/// Run the benchmark with the remaining command-line arguments.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let mut quick = false;
    for a in args {
        match a.as_str() {
            "--quick" => quick = true,
            other => bail!("rbc-bench periodic: unknown option {other:?} (expected --quick)"),
        }
    }
    let threads = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1).min(2);

    println!("## Membrane forces, discocyte level 4 (2048 triangles)");
    println!("law | time per evaluation (ms)");
    println!("---|---");
    for t in super::membrane_timing::membrane_timings(4, if quick { 5 } else { 20 }) {
        println!("{} | {:.3}", t.name, t.seconds * 1e3);
    }

    println!();
    println!("## Spectral Ewald, tolerance 5e-5, {threads} thread(s)");
    let points: &[usize] = if quick { &[1026, 3000] } else { &[1026, 3000, 10000, 30000] };
    let table = super::ewald_timing::ewald_table(points, &[5e-5], threads, if quick { 2 } else { 5 })
        .context("spectral Ewald benchmark")?;
    println!("{table}");

    println!();
    println!("## Channel wall operator (exact no-slip), cell level 4, Ewald tolerance 5e-5, {threads} thread(s)");
    let edges: &[f64] = if quick { &[2.0] } else { &[2.0, 1.38, 1.0] };
    let table = super::channel_walls::channel_table(edges, 4, 5e-5, threads).context("channel benchmark")?;
    println!("{table}");
    super::channel_lambda::print(quick, threads)?;
    Ok(())
}
