//! `rbc-bench solver`: TODO(owner).

/// Run the benchmark with the remaining command-line arguments.
pub fn run(_args: &[String]) -> anyhow::Result<()> {
    anyhow::bail!("not implemented yet")
}
