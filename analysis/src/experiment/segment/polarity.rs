//! Rim polarity of a recording: a dark rim inside a bright halo (focus above the cell's mid-plane) or a bright rim inside a dark halo (below), read from the recording's own frames.
//!
//! A red cell is a weak phase object: out of focus its edge shows two rings of opposite
//! contrast whose signs swap with the sign of the defocus (transport of intensity, Teague,
//! *JOSA* 73, 1983: `dI/dz ~ -Laplacian(phi)`), plus the interior darkened by haemoglobin's
//! absorption at any focus. The outline lies between the two rings, and the inner one is the
//! rim: segmenting for the rim's sign and filling holes gives the cell, segmenting for the
//! other sign gives the halo (a ring around it, larger). Near focus the rings fade and the
//! absorption is left: a dark object and no bright ring.
//!
//! [`estimate`] segments sampled frames for dark and for bright objects (holes filled) and
//! looks at every dark object that overlaps a bright one: when the bright object's bounding
//! box is the larger, the dark one is inside (dark rim); otherwise the bright one is. A
//! bounding box (not the pixel count) is compared so that a halo ring left open by noise
//! still counts as the outer one. The majority of these pairs decides; without any pair
//! (near focus, no cell in the samples) the rim is dark, the pipeline's original assumption.

use super::{segment, Blob, SegmentParams};
use crate::types::Frame;
use std::ops::Range;

/// Sign of the rim's contrast against the background.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Polarity {
    /// Dark rim, bright halo (focus above the mid-plane, or in focus: absorption only).
    Dark,
    /// Bright rim, dark halo (focus below the mid-plane).
    Bright,
}

impl Polarity {
    /// The factor applied to the relative contrast so that the rim is negative.
    pub fn sign(self) -> f32 {
        match self {
            Polarity::Dark => 1.0,
            Polarity::Bright => -1.0,
        }
    }
}

/// Votes of [`estimate`]: object pairs whose inner ring is dark / bright.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PolarityVotes {
    pub dark_inside: usize,
    pub bright_inside: usize,
}

impl PolarityVotes {
    /// The majority; a tie (also no pair) is [`Polarity::Dark`].
    pub fn polarity(&self) -> Polarity {
        if self.bright_inside > self.dark_inside {
            Polarity::Bright
        } else {
            Polarity::Dark
        }
    }
}

fn bbox_area(b: &Blob) -> usize {
    (b.col_range.1 - b.col_range.0 + 1) * (b.row_range.1 - b.row_range.0 + 1)
}

/// Count, over `frames`, the dark/bright object pairs that overlap, by which of the two lies inside.
pub fn votes(frames: &[&Frame], background: &Frame, rows: Range<usize>, um_per_px: f64, params: &SegmentParams) -> PolarityVotes {
    let mut v = PolarityVotes::default();
    for f in frames {
        let dark = segment(f, background, rows.clone(), um_per_px, &SegmentParams { polarity: 1.0, ..*params });
        let bright = segment(f, background, rows.clone(), um_per_px, &SegmentParams { polarity: -1.0, ..*params });
        if dark.blobs.is_empty() || bright.blobs.is_empty() {
            continue;
        }
        // label image of the bright objects
        let mut label = vec![u32::MAX; f.width * f.height];
        for (k, b) in bright.blobs.iter().enumerate() {
            for &p in &b.pixels {
                label[p as usize] = k as u32;
            }
        }
        for d in &dark.blobs {
            let mut hit: Vec<u32> = d.pixels.iter().map(|&p| label[p as usize]).filter(|&l| l != u32::MAX).collect();
            hit.sort_unstable();
            hit.dedup();
            // the largest bright object overlapping this dark one
            let Some(b) = hit.iter().map(|&k| &bright.blobs[k as usize]).max_by_key(|b| bbox_area(b)) else { continue };
            if bbox_area(b) > bbox_area(d) {
                v.dark_inside += 1;
            } else {
                v.bright_inside += 1;
            }
        }
    }
    v
}

/// Lead of one side at which [`estimate`] stops reading more frames.
pub const DECISIVE_LEAD: usize = 3;

/// The rim polarity of a recording from `frames` (a few spread over it) and its background:
/// frames are read one at a time until one side leads by [`DECISIVE_LEAD`] pairs (usually one
/// or two frames, two segmentations each), or all have voted.
pub fn estimate(frames: &[&Frame], background: &Frame, rows: Range<usize>, um_per_px: f64, params: &SegmentParams) -> Polarity {
    let mut total = PolarityVotes::default();
    for f in frames {
        let v = votes(&[*f], background, rows.clone(), um_per_px, params);
        total.dark_inside += v.dark_inside;
        total.bright_inside += v.bright_inside;
        if total.dark_inside.abs_diff(total.bright_inside) >= DECISIVE_LEAD {
            break;
        }
    }
    total.polarity()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::segment::ring_disc;

    #[test]
    fn the_inner_ring_gives_the_polarity() {
        // the halo of the opposite sign outside the rim
        let (dark_rim, bg) = ring_disc(-0.4, 0.28);
        let (bright_rim, _) = ring_disc(0.4, -0.28);
        let p = SegmentParams::default();
        assert_eq!(estimate(&[&dark_rim], &bg, 0..40, 0.2, &p), Polarity::Dark);
        assert_eq!(estimate(&[&bright_rim], &bg, 0..40, 0.2, &p), Polarity::Bright);
        // nothing in the frame: the original assumption
        assert_eq!(estimate(&[&bg], &bg, 0..40, 0.2, &p), Polarity::Dark);
        // segmented with its own polarity, the bright-rim cell is one object of the disc's size (~ pi 8^2 = 201 px)
        let s = segment(&bright_rim, &bg, 0..40, 0.2, &SegmentParams { polarity: -1.0, ..p });
        assert_eq!(s.blobs.len(), 1);
        let a = s.blobs[0].pixels.len() as f64;
        assert!(a > 150.0 && a < 230.0, "{a}");
    }
}
