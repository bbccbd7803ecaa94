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

/// The `--help` paragraph on `RBC_MAX_MEMORY_GB`, for the commands that build channel scenes
/// (`rbc-simulate`, `rbc-sweep run` and `task`); the check is `rbc_solver::scene::build`'s.
pub const MEMORY_HELP: &str = "Environment: RBC_MAX_MEMORY_GB=G sets the memory (GB) a channel scene may plan for (default: \
this machine's MemTotal from /proc/meminfo). A scene whose dense wall operator and its LU (2 (3 N_wall)^2 doubles) would \
need more is refused before any allocation, in one line naming walls.wall_edge_um and the estimate; raise it for a \
machine with swap or a job with more memory.";
