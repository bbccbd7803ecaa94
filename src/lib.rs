//! Shared helpers of the rbc-toolkit command-line front ends (progress display, benchmarks, the sweep machinery of `rbc-sweep`).

pub mod bench;
pub mod progress;
pub mod sweep;
