//! Shared helpers of the rbc-toolkit command-line front ends:
//! - [`alloc`]: the C allocator's thresholds for long runs (page faults);
//! - [`bench`](mod@bench): every benchmark of `rbc-bench`, including the timings of the library crates' parts
//!   (the libraries hold no benchmark code);
//! - [`fuzz`]: the input fuzzer of `rbc-bench fuzz`;
//! - [`progress`]: the progress display;
//! - [`sweep`]: the sweep machinery of `rbc-sweep`.

pub mod alloc;
pub mod bench;
pub mod fuzz;
pub mod progress;
pub mod sweep;
