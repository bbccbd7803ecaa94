//! Detections of a whole recording: background, channel, then segmentation and measurement of every frame (in parallel).

use super::Recording;
use crate::experiment::channel::{self, ChannelGeometry};
use crate::error::AnalysisError;
use crate::experiment::deblur::{deblurred_y_px, BlurLength};
use crate::experiment::measure::measure_refined;
use crate::experiment::segment::polarity::{self, Polarity};
use crate::experiment::segment::ring::RingProfile;
use crate::experiment::segment::{background, segment, SegmentParams};
use crate::experiment::segment::{Blob, Segmentation};
use crate::types::{ContrastPatch, Detection, Frame, MaskPatch};
use rayon::prelude::*;

/// Most frames used for the temporal-median background.
pub const BACKGROUND_FRAMES: usize = 41;

/// Frames (of the background's samples) segmented both ways to read the rim polarity ([`polarity::estimate`]).
pub const POLARITY_FRAMES: usize = 6;

/// Everything found in one recording.
#[derive(Debug, Clone)]
pub struct RecordingDetections {
    /// The channel: axis row, wall rows, um per pixel.
    pub channel: ChannelGeometry,
    /// Objects of all frames, frame by frame (border-touching ones included, flagged).
    pub detections: Vec<Detection>,
    pub n_frames: usize,
    /// Frame size, pixels.
    pub width: usize,
    pub height: usize,
    /// Non-fatal problems (e.g. no cell found), one line each, naming the recording.
    pub warnings: Vec<String>,
    /// The rim polarity read from the recording (bright below focus), used for every frame.
    pub polarity: Polarity,
    /// Motion blur along the flow read from the recording (zero lags when not read: a bright rim,
    /// a halo outline, no cell in the polarity frames).
    pub blur: BlurLength,
    /// The blur length undone before each detection's y is measured, px (`None`: y from the
    /// blurred outline, [`BlurLength::to_undo_px`]).
    pub undo_blur_px: Option<f64>,
}

/// How far beyond an object's bounding box its contrast is kept for the registration of its
/// track ([`crate::experiment::register`]), um: the outline's edge, rim and halo (the halo lies
/// 0.5-1 um outside the outline at the NAs of `simulated::synth::conditions`) with the
/// segmentation's smoothing.
pub const REGISTRATION_MARGIN_UM: f64 = 1.2;

/// The frame's relative contrast before the smoothing ([`Segmentation::relative_contrast`]; 0
/// outside the searched `rows`) over blob `b`'s bounding box grown by `margin_px` on every side
/// (cut to the frame). Unsmoothed: registered on the smoothed contrast the combined row of
/// `simulated::synth::conditions` (0.35 um/px, 2 % noise) kept a median y error of 0.0111 um
/// against 0.0096 on the frames themselves (a prototype on the same detections).
fn contrast_around(b: &Blob, seg: &Segmentation, frame: &Frame, background: &Frame, rows: &std::ops::Range<usize>, margin_px: usize) -> ContrastPatch {
    let w = frame.width;
    let (c0, r0) = (b.col_range.0.saturating_sub(margin_px), b.row_range.0.saturating_sub(margin_px));
    let c1 = (b.col_range.1 + margin_px).min(w - 1);
    let r1 = (b.row_range.1 + margin_px).min(frame.height - 1);
    let (width, height) = (c1 - c0 + 1, r1 - r0 + 1);
    let mut values = Vec::with_capacity(width * height);
    for r in r0..=r1 {
        let i = r * w;
        if rows.contains(&r) {
            values.extend((c0..=c1).map(|c| seg.relative_contrast(frame.data[i + c], background.data[i + c])));
        } else {
            values.extend(std::iter::repeat_n(0.0, width));
        }
    }
    ContrastPatch { col0: c0, row0: r0, width, height, values }
}

/// Smallest area, um^2, of a stationary object reported by [`stationary_objects`] (a red cell projects to 25-60 um^2).
pub const STATIONARY_MIN_AREA_UM2: f64 = 15.0;

/// Number of cell-sized dark objects in a temporal-median background, found
/// against its own separable row x column model ([`background::row_background`]):
/// cells that did not move during the recording, which the median keeps and
/// the segmentation then cannot see.
pub fn stationary_objects(bg: &Frame, rows: std::ops::Range<usize>, um_per_px: f64, params: &SegmentParams) -> usize {
    let model = background::row_background(bg);
    let seg = segment(bg, &model, rows, um_per_px, params);
    seg.blobs.iter().filter(|b| b.pixels.len() as f64 * um_per_px * um_per_px >= STATIONARY_MIN_AREA_UM2).count()
}

/// Run background, channel, segmentation and measurement over all frames of `rec` with default parameters.
///
/// `t_s = frame / fps`; `x_um` from the image's left edge, i.e. `(x_px + 0.5) um_per_px`;
/// `y_um = (y_px - axis_row_px) um_per_px`.
pub fn detect_recording(rec: &Recording) -> Result<RecordingDetections, AnalysisError> {
    detect_recording_with(rec, &SegmentParams::default())
}

/// [`detect_recording`] with explicit segmentation parameters.
pub fn detect_recording_with(rec: &Recording, params: &SegmentParams) -> Result<RecordingDetections, AnalysisError> {
    let n = rec.n_frames();
    let um = rec.config.um_per_px;
    let (median_bg, samples) = if n >= background::MIN_FRAMES_FOR_MEDIAN {
        let idx = background::sample_indices(n, BACKGROUND_FRAMES);
        let frames: Vec<Frame> = idx.par_iter().map(|&i| rec.load_frame(i)).collect::<Result<_, _>>()?;
        (Some(background::median_background(&frames)), frames)
    } else {
        (None, vec![rec.load_frame(0)?])
    };
    let toml = rec.dir.join(rbc_schema::recording::FILE_NAME);
    let channel = match &median_bg {
        Some(bg) => channel::locate(bg, &rec.config, &toml)?,
        None => channel::locate(&background::row_background(&samples[0]), &rec.config, &toml)?,
    };
    let rows = channel.interior_rows(rec.height);
    // the rim's sign, from the recording itself: bright below focus, dark above and in focus
    let polarity = {
        let own_bg;
        let bg = match &median_bg {
            Some(b) => b,
            None => {
                own_bg = background::row_background(&samples[0]);
                &own_bg
            }
        };
        let pick: Vec<&Frame> = background::sample_indices(samples.len(), POLARITY_FRAMES).into_iter().map(|i| &samples[i]).collect();
        let (polarity, dark) = polarity::estimate_keeping_dark(&pick, bg, rows.clone(), um, params);
        // a dark vote below focus segments the dark halo: read where the outline lies, from the
        // frames the vote segmented (no frame is segmented again)
        let halo_outline = polarity == Polarity::Dark && params.polarity > 0.0 && {
            let mut profile = RingProfile::default();
            for seg in &dark {
                profile.add_segmentation(seg, um, params.cell_area_um2);
            }
            profile.reads_halo()
        };
        let halo_outline = halo_outline || params.halo_outline;
        // motion blur along the flow, read from the same segmentations; undone only on dark rims
        // whose outline is the rim's own (a bright rim's open arc and a halo's peel are not)
        let blur = if polarity == Polarity::Dark && !halo_outline {
            BlurLength::from_segmentations(&dark, (params.cell_area_um2 / (um * um)) as usize)
        } else {
            BlurLength::default()
        };
        (polarity, halo_outline, blur)
    };
    let (polarity, halo_outline, blur) = polarity;
    let undo_blur_px = blur.to_undo_px();
    drop(samples);
    let params = &SegmentParams { polarity: polarity.sign() * params.polarity, halo_outline, ..*params };
    let mut warnings = Vec::new();
    if let Some(bg) = &median_bg {
        let n_static = stationary_objects(bg, rows.clone(), um, params);
        if n_static > 0 {
            warnings.push(format!(
                "{}: the background (median of {} frames) holds {n_static} cell-sized stationary object(s); cells that stay in place for half of the recording are not found",
                rec.dir.display(),
                n.min(BACKGROUND_FRAMES)
            ));
        }
    }
    let margin_px = (REGISTRATION_MARGIN_UM / um).ceil() as usize;
    let per_frame: Vec<Vec<Detection>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let frame = rec.load_frame(i)?;
            let own_bg;
            let bg = match &median_bg {
                Some(b) => b,
                None => {
                    own_bg = background::row_background(&frame);
                    &own_bg
                }
            };
            let seg = segment(&frame, bg, rows.clone(), um, params);
            let t_s = rec.time_s(i);
            Ok(seg
                .blobs
                .iter()
                .map(|b| {
                    let mut m = measure_refined(b, &seg);
                    if let Some(y) = undo_blur_px.and_then(|l| deblurred_y_px(b, &seg, l)) {
                        m.y_px = y;
                    }
                    Detection {
                        frame: i,
                        t_s,
                        x_px: m.x_px,
                        y_px: m.y_px,
                        x_um: (m.x_px + 0.5) * um,
                        y_um: channel.y_um(m.y_px),
                        area_um2: m.area_px * um * um,
                        length_um: m.length_px * um,
                        width_um: m.width_px * um,
                        touches_border: b.touches_border,
                        features: m.features,
                        mask: MaskPatch::from_pixels(&b.pixels, seg.width, (b.col_range.0, b.row_range.0), (b.col_range.1 - b.col_range.0 + 1, b.row_range.1 - b.row_range.0 + 1)),
                        contrast: contrast_around(b, &seg, &frame, bg, &rows, margin_px),
                    }
                })
                .collect())
        })
        .collect::<Result<_, AnalysisError>>()?;
    let detections: Vec<Detection> = per_frame.into_iter().flatten().collect();
    if detections.is_empty() {
        warnings.push(format!("{}: no cell found in {n} frames", rec.dir.display()));
    }
    Ok(RecordingDetections { channel, detections, n_frames: n, width: rec.width, height: rec.height, warnings, polarity, blur, undo_blur_px })
}
