//! rbc-analysis: from bright-field frames to the paper's tables and figures, and the prediction of the croissant fraction.
//!
//! Four parts, each a folder, and the data they pass on:
//! - [`experiment`]: the experiment's pipeline, frames -> detections -> tracks -> summaries
//!   (recording, channel, segment, measure, track, isolate, classify, groups, kde; `rbc-analyze`).
//! - [`simulated`]: the simulation side: the phase diagram of `results.h5` and its r_trans
//!   columns, the frame synthesiser, 3D rendering of simulated cells and the closed loop (`rbc-synth`).
//! - [`predict`]: the croissant fraction predicted from the simulations and the measured
//!   entrance distribution (`rbc-predict`).
//! - [`plot`]: the figures (PNG + SVG) of all three; it draws data and computes nothing the
//!   others need. `plot` and `predict` do not import each other: what both use is in
//!   [`types`] and [`simulated`].
//! - [`types`]: data passed between the stages (frames, detections, the prediction's results).
//! - [`stats`]: statistics of samples more than one part uses (medians).

pub mod error;
pub mod experiment;
pub mod plot;
pub mod predict;
pub mod simulated;
pub mod stats;
pub mod types;

pub use error::AnalysisError;
