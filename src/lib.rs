//! Shared helpers of the rbc-toolkit command-line front ends (progress display, benchmarks, the input fuzzer, the sweep machinery of `rbc-sweep`).

pub mod bench;
pub mod fuzz;
pub mod progress;
pub mod sweep;
