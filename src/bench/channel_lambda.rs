//! `rbc-bench periodic` section: cost of the channel solve with viscosity contrast (GMRES iterations, Ewald / wall LU / GMRES split) at 512 and 2048 cell triangles.

use anyhow::Context;

/// Print the viscosity-contrast table (`quick`: 512 triangles and lambda 1, 5 only).
pub fn print(quick: bool, threads: usize) -> anyhow::Result<()> {
    println!();
    println!("## Channel with viscosity contrast (exact no-slip walls, pushed discocyte, mean flow 3 mm/s, GMRES 1e-5), {threads} thread(s)");
    let (levels, lambdas): (&[usize], &[f64]) = if quick { (&[3], &[1.0, 5.0]) } else { (&[3, 4], &[1.0, 5.0, 20.0]) };
    let table = rbc_solver::channel::lambda_bench::lambda_table(levels, lambdas, 5e-5, threads)
        .context("channel viscosity-contrast benchmark")?;
    println!("{table}");
    Ok(())
}
