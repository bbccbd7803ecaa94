//! Benchmarks run by the `rbc-bench` binary; each prints a table to stdout.

pub mod analyze;
pub mod channel;
pub mod channel_cost;
pub mod channel_lambda;
pub mod channel_profile;
pub mod channel_tol;
pub mod compare;
pub mod controller;
pub mod near_field;
pub mod periodic;
pub mod precision;
pub mod precision_cell;
pub mod solver;
