//! Shared helpers of the rbc-toolkit command-line front ends:
//! - [`alloc`]: the C allocator's thresholds for long runs (page faults);
//! - [`build_cpu`]: whether the binary was built for the CPU it runs on;
//! - [`bench`](mod@bench): every benchmark of `rbc-bench`, including the timings of the library crates' parts
//!   (the libraries hold no benchmark code);
//! - [`fuzz`]: the input fuzzer of `rbc-bench fuzz`;
//! - [`progress`]: the progress display;
//! - [`sweep`]: the sweep machinery of `rbc-sweep`.

pub mod alloc;
pub mod build_cpu;
pub mod bench;
pub mod fuzz;
pub mod progress;
pub mod sweep;

/// An error of a binary's output set (`rbc_schema::output_set::write_set_with`) naming the output
/// folder `out` where it named the staging folder or a file in it: the user asked for `out`.
pub fn unstaged(e: anyhow::Error, staging: &std::path::Path, out: &std::path::Path) -> anyhow::Error {
    anyhow::anyhow!("{}", rbc_schema::unstage::renamed_in(&format!("{e:#}"), staging, out))
}

/// The `--help` paragraph on `RBC_MAX_MEMORY_GB`, for the commands that build channel scenes
/// (`rbc-simulate`, `rbc-sweep run` and `task`); the check is `rbc_solver::scene::build`'s.
pub const MEMORY_HELP: &str = "Environment: RBC_MAX_MEMORY_GB=G sets the memory (GB) a channel scene may plan for (default: \
this machine's MemTotal from /proc/meminfo). A scene whose dense wall operator and its LU (2 (3 N_wall)^2 doubles) would \
need more is refused before any allocation, in one line naming walls.wall_edge_um and the estimate; raise it for a \
machine with swap or a job with more memory.";

#[cfg(test)]
mod tests {
    /// A binary's error, context included, names the output folder where it named the staging one.
    #[test]
    fn unstaged_names_the_output_folder_in_every_line_of_context() {
        use anyhow::Context;
        let (staging, out) = (std::path::Path::new("/r/.pred.staging-9"), std::path::Path::new("/r/pred"));
        let e = Err::<(), _>(anyhow::anyhow!("{}: disk full", staging.join("thresholds.csv").display())).context(format!("writing {}", staging.display())).unwrap_err();
        assert_eq!(super::unstaged(e, staging, out).to_string(), "writing /r/pred: /r/pred/thresholds.csv: disk full");
    }
}
