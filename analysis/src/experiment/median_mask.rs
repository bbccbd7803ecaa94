//! A track's median mask: the masks of its frames aligned at their sub-pixel centroids and
//! combined pixel by pixel by their median, and the mirror asymmetry of that mask, which the
//! classifier judges a cell's symmetry on.
//!
//! The classifier assumes a steady shape over the track (a croissant or a slipper keeps its
//! outline while it crosses the field). A single frame's outline is ragged by pixel noise, which
//! reads as asymmetry when the cell's contrast is only a few times the noise: near focus the
//! synthesiser's rim vanishes and the interior's -8.5 % absorption is 2.6 x a 1.8 % read noise,
//! and such croissants measure 0.118-0.127 per frame (median over the track) against the
//! classifier's 0.11. The median over the frames keeps the outline's steady part (a slipper's
//! asymmetry) and outvotes what noise puts in or out of the outline in fewer than half of the
//! frames; unlike a mean it also outvotes the odd frame that differs altogether (a particle of
//! debris joining the outline, a neighbour touching, a rim broken by noise), as the median of
//! the frames' own asymmetries did.
//!
//! **Alignment.** Mask `k` (pixel squares centred on integer coordinates, its centroid
//! `(x_k, y_k)` the mean of its pixel centres, px) is sampled at `(x_k + u, y_k + v)` for integer
//! offsets `(u, v)` by bilinear interpolation (0 outside the mask's box):
//! `M(u, v) = median_k M_k(x_k + u, y_k + v)`, an occupancy in [0, 1] (the mean of the two
//! middle values for an even number of frames). Linear interpolation keeps each aligned mask's
//! sum and first moments, so every one has its centroid at `(0, 0)`, and the mirror image about
//! the horizontal line through the frames' common centroid is the row flip `v -> -v`, with no
//! interpolation of its own (the median mask's own centroid lies there too when the frames agree;
//! it is the frames' line that a croissant is symmetric about).
//!
//! **Asymmetry.** The fuzzy (Ruzicka) form of `1 - IoU`,
//! `A = 1 - sum min(M(u, v), M(u, -v)) / sum max(M(u, v), M(u, -v))`,
//! which for one frame whose centroid lies on a pixel centre is the per-frame
//! [`crate::experiment::measure::mirror_asymmetry`] (0 = mirror-symmetric, 1 = disjoint from its
//! mirror image).

use crate::stats::median::median;
use crate::types::MaskPatch;

/// Centroid of a mask's pixel centres in the mask's own box, px (`None` for an empty mask).
pub fn centroid(m: &MaskPatch) -> Option<(f64, f64)> {
    let (mut n, mut sx, mut sy) = (0usize, 0usize, 0usize);
    for r in 0..m.height {
        for c in 0..m.width {
            if m.get(c, r) {
                n += 1;
                sx += c;
                sy += r;
            }
        }
    }
    (n > 0).then(|| (sx as f64 / n as f64, sy as f64 / n as f64))
}

/// Bilinear sample of a mask at `(x, y)` in its box, px (pixel centres on integers; 0 outside).
fn sample(m: &MaskPatch, x: f64, y: f64) -> f64 {
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let at = |c: i64, r: i64| -> f64 {
        if c >= 0 && r >= 0 && m.get(c as usize, r as usize) {
            1.0
        } else {
            0.0
        }
    };
    (1.0 - fy) * ((1.0 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1.0 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1))
}

/// The masks of a track aligned at their centroids and combined by their per-pixel median:
/// `values[(v + half_height) * width() + (u + half_width)] = M(u, v)` for `|u| <= half_width`,
/// `|v| <= half_height` (px), the frames' centroids at `(0, 0)`.
#[derive(Debug, Clone, PartialEq)]
pub struct MedianMask {
    /// Half extents of the grid, px.
    pub half_width: usize,
    pub half_height: usize,
    /// Occupancy in [0, 1], row-major over `width() x height()`.
    pub values: Vec<f64>,
    /// Masks combined (empty ones left out).
    pub frames: usize,
}

impl MedianMask {
    /// Grid width, px.
    pub fn width(&self) -> usize {
        2 * self.half_width + 1
    }

    /// Grid height, px.
    pub fn height(&self) -> usize {
        2 * self.half_height + 1
    }

    /// The median of `masks` aligned at their centroids (`None` when every mask is empty).
    pub fn of<'a>(masks: impl IntoIterator<Item = &'a MaskPatch>) -> Option<MedianMask> {
        let aligned: Vec<(&MaskPatch, (f64, f64))> = masks.into_iter().filter_map(|m| centroid(m).map(|c| (m, c))).collect();
        if aligned.is_empty() {
            return None;
        }
        // the grid reaches one pixel beyond every mask's box around its centroid
        let reach = |lo: f64, hi: f64| lo.max(hi).ceil() as usize + 1;
        let half_width = aligned.iter().map(|(m, (cx, _))| reach(*cx, m.width as f64 - 1.0 - cx)).max().unwrap_or(0);
        let half_height = aligned.iter().map(|(m, (_, cy))| reach(*cy, m.height as f64 - 1.0 - cy)).max().unwrap_or(0);
        let (w, h, n) = (2 * half_width + 1, 2 * half_height + 1, aligned.len());
        let mut values = Vec::with_capacity(w * h);
        let mut at = vec![0.0; n];
        for j in 0..h {
            let v = j as f64 - half_height as f64;
            for i in 0..w {
                let u = i as f64 - half_width as f64;
                for (s, (m, (cx, cy))) in at.iter_mut().zip(&aligned) {
                    *s = sample(m, cx + u, cy + v);
                }
                values.push(median(&mut at).expect("at least one mask"));
            }
        }
        Some(MedianMask { half_width, half_height, values, frames: n })
    }

    /// `1 - sum min(M, M') / sum max(M, M')` with `M'` the mirror image about the horizontal line
    /// through the frames' centroid, `v = 0` (module documentation; 0 = symmetric). 0 for an
    /// empty grid.
    pub fn mirror_asymmetry(&self) -> f64 {
        let (w, h) = (self.width(), self.height());
        let (mut lo, mut hi) = (0.0, 0.0);
        for j in 0..h {
            let mirrored = h - 1 - j;
            for i in 0..w {
                let (a, b) = (self.values[j * w + i], self.values[mirrored * w + i]);
                lo += a.min(b);
                hi += a.max(b);
            }
        }
        if hi > 0.0 {
            (1.0 - lo / hi).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// Mirror asymmetry of the median of `masks` aligned at their centroids ([`MedianMask`]); `None`
/// when every mask is empty.
pub fn track_asymmetry<'a>(masks: impl IntoIterator<Item = &'a MaskPatch>) -> Option<f64> {
    MedianMask::of(masks).map(|m| m.mirror_asymmetry())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::measure::mirror_asymmetry;
    use crate::experiment::segment::{Blob, Outline};

    /// A mask of `w x h` px at `(col0, row0)` holding the pixels where `inside(col, row)`.
    fn mask(col0: usize, row0: usize, w: usize, h: usize, inside: impl Fn(usize, usize) -> bool) -> MaskPatch {
        MaskPatch::from_fn(col0, row0, w, h, inside)
    }

    /// An ellipse with semi-axes 9 and 5 px about the box's centre pixel (10, 6): mirror-symmetric.
    fn ellipse(c: usize, r: usize) -> bool {
        let (x, y) = (c as f64 - 10.0, r as f64 - 6.0);
        (x / 9.0).powi(2) + (y / 5.0).powi(2) <= 1.0
    }

    /// One frame whose centroid lies on a pixel centre: the median mask is the mask itself and its
    /// asymmetry is the per-frame one of `measure::mirror_asymmetry`, to rounding.
    #[test]
    fn one_frame_gives_the_per_frame_asymmetry() {
        // a teardrop: wider below its centre row than above
        let m = mask(0, 0, 21, 13, |c, r| ellipse(c, r) && (r >= 6 || (c as f64 - 10.0).abs() <= 6.0));
        let (cx, cy) = centroid(&m).unwrap();
        let width = 21;
        let pixels: Vec<u32> = (0..13 * width).filter(|&i| m.get(i % width, i / width)).map(|i| i as u32).collect();
        // the blob's pixels give the mask back (as `detect_recording` keeps it with a detection)
        assert_eq!(MaskPatch::from_pixels(&pixels, width, (0, 0), (21, 13)), m);
        let blob = Blob { pixels, col_range: (0, 20), row_range: (0, 12), touches_border: false, outline: Outline::Threshold };
        let per_frame = mirror_asymmetry(&blob, width, cy);
        let mm = MedianMask::of([&m]).unwrap();
        assert!(per_frame > 0.05, "a teardrop is asymmetric: {per_frame}");
        // the teardrop's centroid row is not on a pixel centre: both read the mirror by linear
        // interpolation between rows, the per-frame function of the mirrored mask, this one of the mask
        assert!(cy.fract() != 0.0 && cx == 10.0, "({cx}, {cy})");
        assert!((mm.mirror_asymmetry() - per_frame).abs() < 0.01, "{} against {per_frame}", mm.mirror_asymmetry());
        // the symmetric ellipse, centroid on a pixel centre: exactly 0 for both
        let e = mask(3, 4, 21, 13, ellipse);
        assert_eq!(centroid(&e), Some((10.0, 6.0)));
        assert_eq!(MedianMask::of([&e]).unwrap().mirror_asymmetry(), 0.0);
    }

    /// Pixels that noise flips on a symmetric cell's outline in fewer than half of the frames, and
    /// a frame with a particle of debris on the outline, are outvoted: the median mask is
    /// symmetric although every frame is not. The frames sit at different places in the frame.
    #[test]
    fn noise_and_an_odd_frame_are_outvoted() {
        let flips: [&[(usize, usize)]; 5] = [&[(10, 1), (4, 2)], &[(16, 10), (10, 11)], &[(2, 5)], &[(17, 3), (12, 11)], &[]];
        let mut frames: Vec<MaskPatch> = flips
            .iter()
            .enumerate()
            .map(|(k, f)| mask(7 * k, 3 + k, 21, 13, |c, r| ellipse(c, r) != f.contains(&(c, r))))
            .collect();
        // a 2 x 2 particle stuck to the lower edge
        frames.push(mask(40, 2, 21, 13, |c, r| ellipse(c, r) || ((9..=10).contains(&c) && (11..=12).contains(&r))));
        let per_frame: Vec<f64> = frames.iter().map(|m| MedianMask::of([m]).unwrap().mirror_asymmetry()).collect();
        assert!(per_frame.iter().filter(|&&a| a > 0.0).count() == 5, "{per_frame:?}");
        let mm = MedianMask::of(&frames).unwrap();
        assert_eq!(mm.frames, 6);
        let a = mm.mirror_asymmetry();
        // the flips and the particle move the centroids by up to 0.1 px: what is left of them
        let worst = per_frame.iter().copied().fold(0.0, f64::max);
        assert!(a < 0.01 && a < worst / 4.0, "median mask {a}, frames {per_frame:?}");
    }

    /// A steady asymmetric shape keeps its asymmetry, whatever its sub-pixel phase in each frame.
    #[test]
    fn a_steady_asymmetric_shape_keeps_its_asymmetry() {
        let tear = |c: usize, r: usize| ellipse(c, r) && (r >= 6 || (c as f64 - 10.0).abs() <= 6.0);
        let one = MedianMask::of([&mask(0, 0, 21, 13, tear)]).unwrap().mirror_asymmetry();
        let frames: Vec<MaskPatch> = (0..7).map(|k| mask(5 * k, k, 21, 13, tear)).collect();
        let all = MedianMask::of(&frames).unwrap().mirror_asymmetry();
        assert!(one > 0.05 && (all - one).abs() < 1e-12, "{all} against {one}");
        assert!(MedianMask::of(&[MaskPatch::default()]).is_none());
    }
}
