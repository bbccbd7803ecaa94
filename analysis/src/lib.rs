//! rbc-analysis: from bright-field frames to the paper's tables and figures, and the prediction of the croissant fraction.
//!
//! Data flows one way: frames -> detections -> tracks -> summaries -> figures.
//! One module per stage:
//! - [`recording`]: find recordings, read PNG/TIFF frames (8/16 bit) in file-name order.
//! - [`channel`]: the two walls and the channel axis.
//! - [`segment`]: background, threshold, morphology, connected components.
//! - [`measure`]: sub-pixel centroid, area, length, width, shape descriptors.
//! - [`track`]: frame-to-frame linking along +x, velocities.
//! - [`concavity`]: notch and waist of an outline (touching cells merged into one object).
//! - [`isolate`]: the paper's 40 um isolation criterion.
//! - [`classify`]: croissant / slipper / other from the projected shape.
//! - [`kde`]: MATLAB `ksdensity` with bounded support.
//! - [`groups`]: per (pressure, position) counts, fractions, confidence intervals, velocities.
//! - [`plot`]: figures (PNG + SVG).
//! - [`pipeline`]: runs the stages over a folder and writes every output atomically.
//! - [`synth`]: the frame synthesiser with ground truth.
//! - [`render3d`]: bright-field frames of a simulated 3D cell (closed loop solver -> analysis).
//! - [`closedloop`]: render every labelled cell of a results.h5, analyse it, compare the labels.
//! - [`predict`]: the croissant fraction predicted from simulations (rbc-predict).

pub mod channel;
pub mod classify;
pub mod closedloop;
pub mod concavity;
pub mod error;
pub mod groups;
pub mod isolate;
pub mod kde;
pub mod measure;
pub mod pipeline;
pub mod plot;
pub mod predict;
pub mod recording;
pub mod render3d;
pub mod segment;
pub mod synth;
pub mod track;
pub mod types;

pub use error::AnalysisError;
