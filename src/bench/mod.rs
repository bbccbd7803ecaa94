//! Benchmarks run by the `rbc-bench` binary; each prints a table to stdout. The measurements of
//! the library crates' parts live here too (never in the libraries), each beside the subcommand
//! that prints it.

pub mod analyze;
pub mod bending_relaxation;
pub mod bim_timing;
pub mod centroid_bias;
pub mod channel;
pub mod channel_cost;
pub mod channel_lambda;
pub mod channel_profile;
pub mod channel_tol;
pub mod channel_walls;
pub mod classifier_features;
pub mod clock;
pub mod compare;
pub mod controller;
pub mod ewald_timing;
pub mod frame_stages;
pub mod membrane_timing;
pub mod near_field;
pub mod periodic;
pub mod precision;
pub mod precision_cell;
pub mod robustness;
pub mod shape_calibration;
pub mod solver;
pub mod steady_detector;
