//! `rbc-bench channel-profile`: where the time of one viscosity-contrast channel solve goes (each kind of Ewald sum, real and Fourier parts, real-space pair counts).
//!
//! Usage: `rbc-bench channel-profile [--level 3] [--lambda 5] [--edge 2.0] [--tol 1e-4] [--threads 1] [--repeats 2] [--cutoffs 0,4,5,6]`.
//! The last table repeats the solve with the real-space parts of the sums inside GMRES frozen
//! into block-sparse matrices at each real-space cutoff (um; 0: the cost model's choice), against the plain solve.
//! Times are CPU seconds of the process (`/proc/self/task/*/schedstat`), best of the repeats.

use anyhow::{bail, Context};

/// Run the benchmark with the remaining command-line arguments.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let (mut level, mut lambda, mut edge, mut tol, mut threads, mut repeats) = (3usize, 5.0, 2.0, 1e-4, 1usize, 2usize);
    let mut cutoffs = vec![0.0, 4.0, 5.0, 6.0];
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("rbc-bench channel-profile: {a} needs a value"));
        match a.as_str() {
            "--level" => level = val()?.parse().context("--level")?,
            "--lambda" => lambda = val()?.parse().context("--lambda")?,
            "--edge" => edge = val()?.parse().context("--edge")?,
            "--tol" => tol = val()?.parse().context("--tol")?,
            "--threads" => threads = val()?.parse().context("--threads")?,
            "--repeats" => repeats = val()?.parse().context("--repeats")?,
            "--cutoffs" => cutoffs = val()?.split(',').map(|s| s.trim().parse()).collect::<Result<_, _>>().context("--cutoffs")?,
            other => bail!("rbc-bench channel-profile: unknown option {other:?} (expected --level, --lambda, --edge, --tol, --threads, --repeats, --cutoffs)"),
        }
    }
    if level > 6 {
        bail!("--level: {level} is above the largest mesh level 6");
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build().context("rayon pool")?;
    let p = pool.install(|| rbc_solver::channel::profile::profile(level, lambda, edge, tol, repeats, &cutoffs)).context("channel profile")?;
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("## One channel solve (no-slip, lambda = {lambda}, wall edge {edge} um, Ewald tol {tol:e}), {threads} thread(s), load {}", load.split_whitespace().take(3).collect::<Vec<_>>().join(" "));
    println!("{}", rbc_solver::channel::profile::profile_table(&p));
    Ok(())
}
