//! Shared helpers of the rbc-toolkit command-line front ends (progress display, exit codes).

pub mod progress;
