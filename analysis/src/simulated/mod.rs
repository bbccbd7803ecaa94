//! The simulation side: what the analysis does with the solver's output (`results.h5`).
//!
//! - [`orbit_events`]: the moments a cell stops lying along the flow (turn-overs, folds) and
//!   their intervals.
//! - [`phase`]: finished runs as points of the phase diagram (mean velocity u, r_init), velocity columns.
//! - [`threshold`]: r_trans per start shape and velocity column, with its bracket.
//! - [`synth`]: the frame synthesiser with ground truth (`rbc-synth`).
//! - [`render3d`]: bright-field frames of a simulated 3D cell.
//! - [`camera`]: what every renderer's camera adds (motion blur over the exposure, flicker, noise, quantisation).
//! - [`synthetic_recording`]: the files of a synthetic recording (frames, truth, spec), written and read back.
//! - [`wave`]: a second renderer from wave optics (thin phase-and-amplitude cells, angular
//!   spectrum, pupil, partially coherent illumination) that shares no image formation with the
//!   synthesiser's.
//! - [`robustness`]: accuracy of the experiment pipeline per imaging condition (defocus, NA, blur,
//!   noise, pixel size, walls, debris, neighbours) against the synthesiser's truth.
//! - [`labelled`]: synthetic tracks with their truth shape over pixel sizes, noise and
//!   velocities, on which the shape classifier is tuned and its probability calibrated.
//! - [`closedloop`]: render every labelled cell of a results.h5, analyse it with the experiment's
//!   pipeline ([`crate::experiment`]), compare the labels.

pub mod camera;
pub mod closedloop;
pub mod labelled;
pub mod orbit_events;
pub mod phase;
pub mod render3d;
pub mod robustness;
pub mod synth;
pub mod synthetic_recording;
pub mod threshold;
pub mod wave;
