//! The experiment's pipeline, one stage per module, in the order the data flows:
//! frames -> detections -> tracks -> summaries.
//!
//! - [`recording`]: find recordings, read PNG/TIFF frames (8/16 bit) in file-name order.
//! - [`channel`]: the two walls and the channel axis.
//! - [`segment`]: background, threshold, morphology, connected components.
//! - [`deblur`]: motion blur along the flow, its length read from the recording, undone for y.
//! - [`measure`]: sub-pixel centroid, area, length, width, shape descriptors
//!   ([`concavity`]: notch and waist of an outline, touching cells merged into one object).
//! - [`track`]: frame-to-frame linking along +x, velocities.
//! - [`register`]: a track's per-frame positions refined by registering each frame's contrast on
//!   the track's median image.
//! - [`median_mask`]: a track's masks aligned at their centroids and combined by their per-pixel
//!   median, and that mask's mirror asymmetry (the classifier's symmetry cue).
//! - [`isolate`]: the paper's 40 um isolation criterion.
//! - [`classify`]: croissant / slipper / other from the projected shape, with the calibrated
//!   probability of a croissant ([`calibration`]: Platt's sigmoid, its fit, reliability, ECE, Brier).
//! - [`groups`]: per (pressure, position) counts, fractions, confidence intervals, velocities.
//! - [`kde`]: MATLAB `ksdensity` with bounded support (the y-densities of the groups).
//! - [`pipeline`]: runs the stages over a folder and writes every output atomically
//!   (figures by [`crate::plot::experiment`]).

pub mod calibration;
pub mod channel;
pub mod classify;
pub mod concavity;
pub mod deblur;
pub mod groups;
pub mod isolate;
pub mod kde;
pub mod measure;
pub mod median_mask;
pub mod pipeline;
pub mod recording;
pub mod register;
pub mod segment;
pub mod track;
