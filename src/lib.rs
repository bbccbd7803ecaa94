//! Shared helpers of the rbc-toolkit command-line front ends (progress display, benchmarks).

pub mod bench;
pub mod progress;
