//! Benchmarks run by the `rbc-bench` binary; each prints a table to stdout.

pub mod analyze;
pub mod periodic;
pub mod precision;
pub mod precision_cell;
pub mod solver;
