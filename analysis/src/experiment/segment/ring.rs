//! Where a dark-voted recording's outline lies: on its threshold crossing, or on the dark ring inside it (the halo of a cell below focus whose bright rim is too weak to vote).
//!
//! Below focus a red cell shows a bright rim inside a dark halo ([`super::polarity`]). A little
//! below focus (wave optics at -0.5 and -1 um, the synthesiser at -0.5 um) the bright rim is too
//! weak to be segmented (+0.02 at most), so the recording votes dark and the object segmented is
//! the dark halo with the interior: an outline 0.5-0.8 um outside the cell's (area +12 to
//! +21 um^2), and a slipper's centroid pulled away from the axis (median y error 0.011-0.018 um).
//! The mean contrast against the distance from the segmented outline tells this apart from a
//! dark rim read right (analysis/README.md, "What still fails"):
//! - the outline is right (above focus, in focus): a bright ring lies just outside the dark one
//!   (+0.13 to +0.16 at +1 um), or the dark object has no ring inside (absorption only);
//! - the outline is the halo's: the dark ring is the outermost ring, nothing outside is brighter
//!   than a fraction ([`OUTSIDE_BRIGHT_MAX`]) of its depth, and inside it the contrast rises back
//!   by most of its depth ([`RECOVERY`]: the bright rim between the halo and the absorbing
//!   interior).
//!
//! [`RingProfile`] accumulates that profile over the frames the polarity vote segmented (pixel
//! layers: the chessboard distance to the outline, inside and out); [`RingProfile::reads_halo`]
//! applies the test. Such a recording's objects are then peeled back to the halo's darkest ring
//! ([`super::peel`]), as an open bright rim is ([`super::halo`]).

use super::{Blob, Segmentation};
use std::collections::VecDeque;

/// Outside the outline, the profile is read this far, um (the bright halo of a dark rim lies
/// within ~1 um of it).
pub const OUTSIDE_UM: f64 = 1.5;

/// The brightest outside layer must stay below this fraction of the dark ring's depth for the
/// outline to be read as a halo's. Measured (`rbc-bench robustness`, seeds 1-3): halos 0.02-0.05
/// (wave -1, -0.5 um, synthesiser -0.5 um); a dark rim read right 0.09-0.11 in focus (wave) and
/// 0.25-0.5 above focus or at NA 0.4.
pub const OUTSIDE_BRIGHT_MAX: f64 = 0.07;

/// Inside the dark ring the contrast must rise back by this fraction of its depth: a bright rim
/// between the halo and the absorbing interior. Measured: 0.98-1.46 where the rim is seen (wave
/// -1 um, synthesiser -0.5 um); 0.69-0.81 where it is weak (wave -0.5 um and the combined row);
/// 0.26-0.67 in focus and above, where the outside test rejects the ring. It was 0.9 until the
/// peeled outline was read on the ring's ridge to sub-pixel precision ([`crate::experiment::measure::ridge_weights`]):
/// with the whole-pixel peel, peeling the weak-rim rows moved y by more than it corrected;
/// read on the ridge, it takes wave -0.5 um from 0.0086 to 0.0040 um and the combined row from
/// 0.0173 to 0.0077 (six seeds, session 19, analysis/README.md).
pub const RECOVERY: f64 = 0.6;

/// Mean polarity-signed contrast (the rim negative) per pixel layer around the outlines of the
/// objects added: layer `k` inside is the pixels at chessboard distance `k + 1` from the nearest
/// pixel outside the object, layer `k` outside at distance `k + 1` from the nearest inside.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RingProfile {
    /// (sum of contrast, pixel count) per inside layer, outermost first.
    pub inside: Vec<(f64, usize)>,
    /// (sum of contrast, pixel count) per outside layer, nearest first.
    pub outside: Vec<(f64, usize)>,
}

impl RingProfile {
    /// Add the layers of every object of `seg` (pixels of `um_per_px` um) that touches no border
    /// and covers at least `cell_area_um2` (the least area of a red cell: smaller objects are
    /// debris or noise); outside layers are read to [`OUTSIDE_UM`].
    pub fn add_segmentation(&mut self, seg: &Segmentation, um_per_px: f64, cell_area_um2: f64) {
        let out_layers = ((OUTSIDE_UM / um_per_px).ceil() as usize).max(1);
        let min_px = cell_area_um2 / (um_per_px * um_per_px);
        for b in seg.blobs.iter().filter(|b| !b.touches_border && b.pixels.len() as f64 >= min_px) {
            self.add_blob(b, seg, out_layers);
        }
    }

    fn add_blob(&mut self, b: &Blob, seg: &Segmentation, out_layers: usize) {
        let (w, h) = (seg.width, seg.height);
        // local box: the blob's bounding box and out_layers of outside around it (clipped to the image)
        let c0 = b.col_range.0.saturating_sub(out_layers);
        let r0 = b.row_range.0.saturating_sub(out_layers);
        let c1 = (b.col_range.1 + out_layers).min(w - 1);
        let r1 = (b.row_range.1 + out_layers).min(h - 1);
        let (lw, lh) = (c1 - c0 + 1, r1 - r0 + 1);
        let mut inside = vec![false; lw * lh];
        for &i in &b.pixels {
            inside[(i as usize / w - r0) * lw + (i as usize % w - c0)] = true;
        }
        let dist_in = chessboard_distance(&inside, lw, lh, true);
        let dist_out = chessboard_distance(&inside, lw, lh, false);
        for k in 0..lw * lh {
            let ci = seg.contrast[(k / lw + r0) * w + (k % lw + c0)] as f64;
            let (layers, d) = if inside[k] { (&mut self.inside, dist_in[k]) } else { (&mut self.outside, dist_out[k]) };
            if d == 0 || (!inside[k] && d > out_layers) {
                continue;
            }
            if layers.len() < d {
                layers.resize(d, (0.0, 0));
            }
            layers[d - 1].0 += ci;
            layers[d - 1].1 += 1;
        }
    }

    /// Mean contrast of each inside layer (outermost first).
    pub fn inside_means(&self) -> Vec<f64> {
        self.inside.iter().map(|&(s, n)| if n > 0 { s / n as f64 } else { 0.0 }).collect()
    }

    /// Mean contrast of each outside layer (nearest first).
    pub fn outside_means(&self) -> Vec<f64> {
        self.outside.iter().map(|&(s, n)| if n > 0 { s / n as f64 } else { 0.0 }).collect()
    }

    /// The outline segmented is a dark halo's, not the cell's: the outermost dark ring (the
    /// first inside layer darker than the next one in) is followed inwards by a layer that
    /// recovers by [`RECOVERY`] of its depth, and no outside layer is brighter than
    /// [`OUTSIDE_BRIGHT_MAX`] of its depth. False without any object.
    pub fn reads_halo(&self) -> bool {
        let inside = self.inside_means();
        let Some(k) = (0..inside.len()).find(|&k| inside.get(k + 1).is_some_and(|&next| next > inside[k])) else {
            return false;
        };
        let depth = -inside[k];
        if depth <= 0.0 {
            return false;
        }
        let recovers = inside[k + 1..].iter().any(|&v| v > -(1.0 - RECOVERY) * depth);
        let dark_outside = self.outside_means().iter().all(|&v| v < OUTSIDE_BRIGHT_MAX * depth);
        recovers && dark_outside
    }
}

/// Chessboard distance of every pixel of a `w` x `h` grid to the nearest pixel of the other kind
/// (`of_inside`: of the inside pixels to the outside, else of the outside pixels to the inside;
/// `usize::MAX` where there is none); 0 for the pixels of the other kind.
fn chessboard_distance(inside: &[bool], w: usize, h: usize, of_inside: bool) -> Vec<usize> {
    let mut d = vec![usize::MAX; w * h];
    let mut queue = VecDeque::new();
    for k in 0..w * h {
        if inside[k] != of_inside {
            d[k] = 0;
            queue.push_back(k);
        }
    }
    while let Some(k) = queue.pop_front() {
        let (r, c) = (k / w, k % w);
        for rr in r.saturating_sub(1)..(r + 2).min(h) {
            for cc in c.saturating_sub(1)..(c + 2).min(w) {
                let q = rr * w + cc;
                if d[q] == usize::MAX {
                    d[q] = d[k] + 1;
                    queue.push_back(q);
                }
            }
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::segment::{ring_disc, segment, SegmentParams};
    use crate::types::Frame;

    /// A 60 x 40 px frame of background 0.5 with a disc of radius 8 px at (30, 20) as a cell a
    /// little below focus: a dark halo (-0.3) on the outline, a bright rim (`rim`) 3 px inside it,
    /// the interior darkened by absorption (-0.15), a bright ring (`outer`) 2.5 px outside; and
    /// the background frame.
    fn halo_disc(rim: f32, outer: f32) -> (Frame, Frame) {
        let (w, h) = (60usize, 40usize);
        let bg = Frame { width: w, height: h, data: vec![0.5; w * h] };
        let mut f = bg.clone();
        for r in 0..h {
            for c in 0..w {
                let d = ((c as f32 - 30.0).powi(2) + (r as f32 - 20.0).powi(2)).sqrt() - 8.0;
                let inside = 1.0 / (1.0 + (2.0 * d).exp());
                let v = rim * (-(d + 3.0).powi(2) / 2.0).exp() - 0.3 * (-d.powi(2) / 2.0).exp() - 0.15 * inside + outer * (-(d - 2.5).powi(2) / 2.0).exp();
                f.data[r * w + c] = 0.5 * (1.0 + v);
            }
        }
        (f, bg)
    }

    fn profile_of(f: &Frame, bg: &Frame) -> RingProfile {
        let mut p = RingProfile::default();
        // the test disc covers 8 um^2 at 0.2 um/px: a smaller cell than the default bound
        p.add_segmentation(&segment(f, bg, 0..40, 0.2, &SegmentParams::default()), 0.2, 4.0);
        p
    }

    #[test]
    fn a_dark_halo_around_a_bright_rim_is_read_as_a_halo() {
        let (f, bg) = halo_disc(0.3, 0.0);
        let p = profile_of(&f, &bg);
        assert!(p.reads_halo(), "in {:?} out {:?}", p.inside_means(), p.outside_means());
        // read as a halo, the object is peeled back to the disc inside its darkest ring
        let whole = segment(&f, &bg, 0..40, 0.2, &SegmentParams::default());
        let peeled = segment(&f, &bg, 0..40, 0.2, &SegmentParams { halo_outline: true, ..SegmentParams::default() });
        assert_eq!((whole.blobs.len(), peeled.blobs.len()), (1, 1));
        let (a_whole, a_peeled) = (whole.blobs[0].pixels.len() as f64, peeled.blobs[0].pixels.len() as f64);
        // pi 8^2 = 201 px inside the ring's centre line; the halo's outer flank reaches ~ 10 px
        assert!(a_whole > 260.0, "{a_whole}");
        assert!(a_peeled > 150.0 && a_peeled < 210.0, "{a_peeled}");
    }

    #[test]
    fn a_dark_rim_with_a_bright_halo_or_without_a_rim_inside_is_the_outline() {
        // above focus: the bright halo outside the dark rim
        let (f, bg) = ring_disc(-0.4, 0.3);
        assert!(!profile_of(&f, &bg).reads_halo());
        // the same rings as a halo's, but a bright ring outside them (a third of their depth)
        let (f, bg) = halo_disc(0.3, 0.1);
        assert!(!profile_of(&f, &bg).reads_halo());
        // no bright rim between the dark ring and the absorbing interior: no recovery
        let (f, bg) = halo_disc(0.0, 0.0);
        assert!(!profile_of(&f, &bg).reads_halo());
        // nothing segmented
        assert!(!profile_of(&bg, &bg).reads_halo());
    }
}
