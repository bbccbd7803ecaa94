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
//! groups the objects that overlap into clusters (one per cell): the outermost object of a
//! cluster (the largest bounding box) is the halo, so the rim has the other sign. A cell whose
//! interior is darkened by absorption inside a bright rim inside a dark halo (below focus, seen
//! by wave optics: `rbc_analysis::simulated::wave`) thus votes for a bright rim, as the ring
//! just inside its halo is. A bounding box (not the pixel count) is compared so that a halo ring
//! left open by noise still counts as the outer one. The majority of the clusters decides;
//! without any (near focus, no cell in the samples) the rim is dark, the pipeline's original
//! assumption.

use super::{segment_rims, Blob, SegmentParams, Segmentation};
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
        let (fv, _) = frame_votes(f, background, rows.clone(), um_per_px, params);
        v.dark_inside += fv.dark_inside;
        v.bright_inside += fv.bright_inside;
    }
    v
}

/// The votes of one frame, and its segmentation for dark objects (the rim's own objects, as
/// [`super::segment`] finds them for a dark rim).
fn frame_votes(f: &Frame, background: &Frame, rows: Range<usize>, um_per_px: f64, params: &SegmentParams) -> (PolarityVotes, Segmentation) {
    let mut v = PolarityVotes::default();
    let dark = segment_rims(f, background, rows.clone(), um_per_px, &SegmentParams { polarity: 1.0, halo_outline: false, ..*params });
    let bright = segment_rims(f, background, rows, um_per_px, &SegmentParams { polarity: -1.0, halo_outline: false, ..*params });
    if dark.blobs.is_empty() || bright.blobs.is_empty() {
        return (v, dark);
    }
    // label image of the bright objects
    let mut label = vec![u32::MAX; f.width * f.height];
    for (k, b) in bright.blobs.iter().enumerate() {
        for &p in &b.pixels {
            label[p as usize] = k as u32;
        }
    }
    // clusters of overlapping dark and bright objects (union-find over dark 0..nd, bright nd..)
    let nd = dark.blobs.len();
    let mut parent: Vec<usize> = (0..nd + bright.blobs.len()).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    let mut paired = vec![false; parent.len()];
    for (i, d) in dark.blobs.iter().enumerate() {
        for &p in &d.pixels {
            let l = label[p as usize];
            if l != u32::MAX {
                let (a, b) = (root(&mut parent, i), root(&mut parent, nd + l as usize));
                parent[a] = b;
                paired[i] = true;
                paired[nd + l as usize] = true;
            }
        }
    }
    // the outermost object of each cluster (largest bounding box) is the halo: the rim has the other sign
    let mut outer: std::collections::HashMap<usize, (usize, bool)> = std::collections::HashMap::new();
    for k in (0..parent.len()).filter(|&k| paired[k]) {
        let (area, is_bright) = if k < nd { (bbox_area(&dark.blobs[k]), false) } else { (bbox_area(&bright.blobs[k - nd]), true) };
        let r = root(&mut parent, k);
        let e = outer.entry(r).or_insert((area, is_bright));
        if area > e.0 {
            *e = (area, is_bright);
        }
    }
    for (_, is_bright) in outer.values() {
        if *is_bright {
            v.dark_inside += 1;
        } else {
            v.bright_inside += 1;
        }
    }
    (v, dark)
}

/// Lead of one side at which [`estimate`] stops reading more frames.
pub const DECISIVE_LEAD: usize = 3;

/// The rim polarity of a recording from `frames` (a few spread over it) and its background:
/// frames are read one at a time until one side leads by [`DECISIVE_LEAD`] pairs (usually one
/// or two frames, two segmentations each), or all have voted.
pub fn estimate(frames: &[&Frame], background: &Frame, rows: Range<usize>, um_per_px: f64, params: &SegmentParams) -> Polarity {
    estimate_keeping_dark(frames, background, rows, um_per_px, params).0
}

/// [`estimate`], and the segmentations for dark objects of the frames read (for
/// [`super::ring::RingProfile`], which reads a dark-voted recording's outline from them).
pub fn estimate_keeping_dark(frames: &[&Frame], background: &Frame, rows: Range<usize>, um_per_px: f64, params: &SegmentParams) -> (Polarity, Vec<Segmentation>) {
    let mut total = PolarityVotes::default();
    let mut dark = Vec::new();
    for f in frames {
        let (v, seg) = frame_votes(f, background, rows.clone(), um_per_px, params);
        dark.push(seg);
        total.dark_inside += v.dark_inside;
        total.bright_inside += v.bright_inside;
        if total.dark_inside.abs_diff(total.bright_inside) >= DECISIVE_LEAD {
            break;
        }
    }
    (total.polarity(), dark)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::segment::{ring_disc, segment};

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
