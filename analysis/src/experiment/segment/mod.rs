//! Segmentation of bright-field cells: contrast to the background, hysteresis threshold on darkness, closing, hole filling, connected components.
//!
//! In bright field at 60x a red cell is darker than the background inside a
//! dark rim and is surrounded by a bright halo; its centre can be nearly as
//! bright as the background. The steps, per frame:
//! 1. relative contrast `c = s (I / (g B) - 1)` against the per-recording
//!    background `B` ([`background`]); `g` is the frame's median gain (flicker);
//!    dividing (not subtracting) cancels uneven illumination and the static
//!    wall lines; `s` = [`SegmentParams::polarity`], read per recording by
//!    [`polarity`] (-1 below focus, where the rim is bright inside a dark halo),
//!    so that the rim is always "dark" below;
//! 2. Gaussian smoothing (`smooth_sigma_px`) against pixel noise;
//! 3. noise level `sigma` = 1.4826 MAD of the smoothed contrast between the walls;
//! 4. hysteresis on darkness (Canny's idea applied to regions): pixels with
//!    `c < -t_low` form candidate regions, kept only when they contain a pixel
//!    with `c < -t_high`; `t = max(k sigma, t_min)`. The bright halo is never
//!    foreground, so it cannot merge neighbours or shift the outline outwards;
//! 5. binary closing (3x3) bridges gaps in the dark rim, but not halo pixels (`c > t_low`: the
//!    bright halo between two cells a pixel or two apart keeps them apart), then holes are
//!    filled (a bright cell centre becomes part of the cell);
//! 6. 8-connected components ([`components_8`]), split where the closing joined two cells
//!    ([`split`]); those smaller than
//!    `min_area_um2` are dropped; components touching the image border are
//!    flagged (they are not measured into tracks);
//! 7. where the objects are dark halos around cells below focus
//!    ([`SegmentParams::halo_outline`], read per recording by [`ring`]), each is peeled back to
//!    its darkest ring ([`peel`]).
//!
//! Only rows strictly between the channel walls are searched.

pub mod background;
pub mod halo;
pub mod peel;
pub mod polarity;
pub mod ring;
pub mod split;

use crate::types::Frame;
use image::{GrayImage, ImageBuffer, Luma};
use std::ops::Range;

/// Parameters of [`segment`]; defaults were chosen on the synthesiser and checked on the real RT-DC frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentParams {
    /// Gaussian smoothing of the contrast, pixels.
    pub smooth_sigma_px: f32,
    /// Low (region) threshold in units of the noise sigma, and its floor (relative contrast).
    pub k_low: f32,
    pub t_low_min: f32,
    /// High (seed) threshold in units of the noise sigma, and its floor.
    pub k_high: f32,
    pub t_high_min: f32,
    /// Smallest object kept, um^2 (a red cell projects to ~ 30-60 um^2).
    pub min_area_um2: f64,
    /// Area a red cell projects to at the least, um^2 (the debris bound of the tracks,
    /// `StageConfig::min_cell_area_um2`): two pieces this large that only the closing joined are
    /// two objects ([`split`]).
    pub cell_area_um2: f64,
    /// Sign of the rim: 1 segments dark objects (dark rim, the default), -1 bright ones (bright
    /// rim below focus); the contrast is multiplied by it ([`polarity`]).
    pub polarity: f32,
    /// The objects segmented are dark halos around cells (a dark-voted recording below focus,
    /// [`ring::RingProfile::reads_halo`]): each is peeled back to its darkest ring ([`peel`]).
    pub halo_outline: bool,
}

impl Default for SegmentParams {
    fn default() -> Self {
        SegmentParams { smooth_sigma_px: 1.0, k_low: 4.0, t_low_min: 0.04, k_high: 8.0, t_high_min: 0.08, min_area_um2: 4.0, cell_area_um2: 12.0, polarity: 1.0, halo_outline: false }
    }
}

/// Where an object's outline lies in the contrast, which says how it is refined to sub-pixel
/// precision ([`crate::experiment::measure::measure_refined`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outline {
    /// The iso-contour `c = -t_low` of the contrast: a thresholded rim.
    Threshold,
    /// A dark halo's darkest ring (peeled, [`peel`]): the ridge of `sign * contrast`.
    DarkestRing { sign: f32 },
}

/// One segmented object: its pixels (linear indices `row * width + col`) and bounding box.
#[derive(Debug, Clone, PartialEq)]
pub struct Blob {
    pub pixels: Vec<u32>,
    /// Bounding box, inclusive, pixels.
    pub col_range: (usize, usize),
    pub row_range: (usize, usize),
    /// The object touches the image border (it may be cut off).
    pub touches_border: bool,
    /// What its outline follows in the contrast.
    pub outline: Outline,
}

/// Result of segmenting one frame.
#[derive(Debug, Clone)]
pub struct Segmentation {
    pub width: usize,
    pub height: usize,
    pub blobs: Vec<Blob>,
    /// Smoothed relative contrast `polarity (I / (g B) - 1)` (0 outside the searched rows): the rim is negative.
    pub contrast: Vec<f32>,
    /// Noise sigma of the smoothed contrast, and the thresholds used.
    pub noise_sigma: f32,
    pub t_low: f32,
    pub t_high: f32,
    /// The frame's gain against the background (the median of their ratio over the searched
    /// rows) and the polarity the contrast was taken with ([`Segmentation::relative_contrast`]).
    pub gain: f32,
    pub polarity: f32,
}

impl Segmentation {
    /// The relative contrast of a frame value `f` over its background value `b`, before the
    /// smoothing: `polarity (f / (gain b) - 1)` (0 where the background is dark).
    #[inline]
    pub fn relative_contrast(&self, f: f32, b: f32) -> f32 {
        relative_contrast(f, b, self.gain, self.polarity)
    }
}

/// `polarity (f / (gain b) - 1)`, 0 where `gain b <= 1e-6`: a frame's contrast against its background.
#[inline]
fn relative_contrast(f: f32, b: f32, gain: f32, polarity: f32) -> f32 {
    let b = b * gain;
    if b > 1e-6 {
        polarity * (f / b - 1.0)
    } else {
        0.0
    }
}

/// Segment the dark objects of `frame` against `background`, searching rows `rows`; with a bright
/// rim (`p.polarity < 0`) an open rim is closed by its halo ([`halo`]).
pub fn segment(frame: &Frame, background: &Frame, rows: Range<usize>, um_per_px: f64, p: &SegmentParams) -> Segmentation {
    segment_with(frame, background, rows, um_per_px, p, p.polarity < 0.0)
}

/// [`segment`] without the halo's closing of open rims: the rim's own objects, as the polarity
/// vote compares them with the halo's ([`polarity::votes`]).
pub fn segment_rims(frame: &Frame, background: &Frame, rows: Range<usize>, um_per_px: f64, p: &SegmentParams) -> Segmentation {
    segment_with(frame, background, rows, um_per_px, p, false)
}

fn segment_with(frame: &Frame, background: &Frame, rows: Range<usize>, um_per_px: f64, p: &SegmentParams, close_rims: bool) -> Segmentation {
    let (w, h) = (frame.width, frame.height);
    let rows = rows.start.min(h)..rows.end.min(h);
    // 1. gain from a subsample of the searched rows
    let mut ratios: Vec<f32> = Vec::with_capacity((rows.len() * w) / 7 + 1);
    for i in (rows.start * w..rows.end * w).step_by(7) {
        let b = background.data[i];
        if b > 1e-6 {
            ratios.push(frame.data[i] / b);
        }
    }
    let gain = if ratios.is_empty() { 1.0 } else { background::median_in_place(&mut ratios) };
    let gain = if gain.is_finite() && gain > 1e-6 { gain } else { 1.0 };
    let mut c = vec![0f32; w * h];
    let span = rows.start * w..rows.end * w;
    for ((ci, &f), &b) in c[span.clone()].iter_mut().zip(&frame.data[span.clone()]).zip(&background.data[span]) {
        *ci = relative_contrast(f, b, gain, p.polarity);
    }
    // 2. smoothing
    let contrast = if p.smooth_sigma_px > 0.0 {
        let img: ImageBuffer<Luma<f32>, Vec<f32>> = ImageBuffer::from_raw(w as u32, h as u32, c).expect("buffer size matches");
        let mut s = imageproc::filter::gaussian_blur_f32(&img, p.smooth_sigma_px).into_raw();
        // keep the outside of the searched rows at zero (the blur spreads the first and last rows)
        s[..rows.start * w].fill(0.0);
        s[rows.end * w..].fill(0.0);
        s
    } else {
        c
    };
    // 3. noise
    let mut sample: Vec<f32> = (rows.start * w..rows.end * w).step_by(5).map(|i| contrast[i]).collect();
    let noise_sigma = if sample.is_empty() {
        0.0
    } else {
        let med = background::median_in_place(&mut sample);
        for v in sample.iter_mut() {
            *v = (*v - med).abs();
        }
        1.4826 * background::median_in_place(&mut sample)
    };
    let t_low = (p.k_low * noise_sigma).max(p.t_low_min);
    let t_high = (p.k_high * noise_sigma).max(p.t_high_min).max(t_low);
    // 4-5. low threshold, closing, holes filled
    let mut mask: GrayImage = ImageBuffer::from_fn(w as u32, h as u32, |x, y| {
        let i = y as usize * w + x as usize;
        Luma([if contrast[i] < -t_low { 255u8 } else { 0 }])
    });
    let raw = mask.clone();
    close_3x3(&mut mask);
    // closing must not reach outside the searched rows, nor into a halo: the halo between two
    // cells a pixel or two apart is what keeps them two objects
    for r in (0..rows.start).chain(rows.end..h) {
        for x in 0..w {
            mask.put_pixel(x as u32, r as u32, Luma([0]));
        }
    }
    for (m, &ci) in mask.iter_mut().zip(&contrast) {
        if ci > t_low {
            *m = 0;
        }
    }
    fill_holes(&mut mask);
    // 6. components
    let cell_px = (p.cell_area_um2 / (um_per_px * um_per_px)).max(4.0) as usize;
    let mut groups: Vec<Vec<u32>> = components_8(&mask).into_iter().flat_map(|g| split::split_joined(g, &raw, cell_px)).collect();
    let min_px = (p.min_area_um2 / (um_per_px * um_per_px)).max(4.0) as usize;
    let mut seg = Segmentation { width: w, height: h, blobs: Vec::new(), contrast, noise_sigma, t_low, t_high, gain, polarity: p.polarity };
    // the cells closed by their halo are appended after the rims' own objects
    let closed = if close_rims { halo::close_open_rims(&mut groups, &seg, rows, min_px) } else { 0 };
    let n_groups = groups.len();
    let seeded = |g: &Vec<u32>| g.len() >= min_px && g.iter().any(|&i| seg.contrast[i as usize] < -t_high);
    let cells: Vec<(Vec<u32>, Outline)> = if p.halo_outline {
        // the seed is the halo's darkest ring, peeled with the flank: test it before
        let ring = Outline::DarkestRing { sign: -1.0 };
        groups.into_iter().filter(seeded).flat_map(|g| peel::peel_to_darkest_ring(&g, &seg.contrast, -1.0, w)).filter(|g| g.len() >= min_px).map(|g| (g, ring)).collect()
    } else {
        groups
            .into_iter()
            .enumerate()
            .map(|(k, g)| (g, if k + closed >= n_groups { Outline::DarkestRing { sign: 1.0 } } else { Outline::Threshold }))
            .filter(|(g, _)| seeded(g))
            .collect()
    };
    seg.blobs = cells.into_iter().map(|(pixels, outline)| blob_of(pixels, w, h, outline)).collect();
    seg
}

fn blob_of(pixels: Vec<u32>, w: usize, h: usize, outline: Outline) -> Blob {
    let (mut c0, mut c1, mut r0, mut r1) = (usize::MAX, 0, usize::MAX, 0);
    for &i in &pixels {
        let (r, c) = (i as usize / w, i as usize % w);
        c0 = c0.min(c);
        c1 = c1.max(c);
        r0 = r0.min(r);
        r1 = r1.max(r);
    }
    let touches_border = c0 == 0 || r0 == 0 || c1 + 1 == w || r1 + 1 == h;
    Blob { pixels, col_range: (c0, c1), row_range: (r0, r1), touches_border, outline }
}

/// Binary closing with a 3 x 3 square (dilation then erosion, each a separable
/// max / min over rows then columns; the image is treated as padded with background).
///
/// Written here because `imageproc::morphology::close_mut` (a distance
/// transform) took 12 ms of the 14 ms per frame in our profile (test build,
/// 413 x 110 px); this takes well under 1 ms.
pub fn close_3x3(mask: &mut GrayImage) {
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    // pad by one pixel of background so that the dilation can grow past the
    // image border and the erosion take it back (closing of the padded image, cropped)
    let (pw, ph) = (w + 2, h + 2);
    let mut pad = vec![0u8; pw * ph];
    for r in 0..h {
        pad[(r + 1) * pw + 1..(r + 1) * pw + 1 + w].copy_from_slice(&mask.as_raw()[r * w..(r + 1) * w]);
    }
    let mut tmp = vec![0u8; pw * ph];
    pass_3x3(&mut pad, &mut tmp, pw, ph, u8::max);
    pass_3x3(&mut pad, &mut tmp, pw, ph, u8::min);
    let data: &mut [u8] = mask;
    for r in 0..h {
        data[r * w..(r + 1) * w].copy_from_slice(&pad[(r + 1) * pw + 1..(r + 1) * pw + 1 + w]);
    }
}

/// One separable 3 x 3 max or min filter of `data` in place (`tmp` is scratch of the same size).
fn pass_3x3(data: &mut [u8], tmp: &mut [u8], w: usize, h: usize, op: fn(u8, u8) -> u8) {
    for r in 0..h {
        let row = &data[r * w..(r + 1) * w];
        let out = &mut tmp[r * w..(r + 1) * w];
        for c in 0..w {
            let mut v = row[c];
            if c > 0 {
                v = op(v, row[c - 1]);
            }
            if c + 1 < w {
                v = op(v, row[c + 1]);
            }
            out[c] = v;
        }
    }
    for r in 0..h {
        for c in 0..w {
            let mut v = tmp[r * w + c];
            if r > 0 {
                v = op(v, tmp[(r - 1) * w + c]);
            }
            if r + 1 < h {
                v = op(v, tmp[(r + 1) * w + c]);
            }
            data[r * w + c] = v;
        }
    }
}

/// Pixel lists (linear indices, in scan order of their first pixel) of the
/// 8-connected components of a binary mask (non-zero = object).
///
/// A flood fill from each unvisited object pixel: the mask is sparse (cells
/// cover a few per cent of a frame), so this visits each object pixel once and
/// returns the pixel lists directly; `imageproc::region_labelling` labels the
/// whole image in two passes and then needs a third to gather the lists
/// (0.55 ms of 1.3 ms per 413 x 110 frame in our profile).
pub fn components_8(mask: &GrayImage) -> Vec<Vec<u32>> {
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    let data: &[u8] = mask.as_raw();
    let mut seen = vec![false; w * h];
    let mut out = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    for start in 0..w * h {
        if data[start] == 0 || seen[start] {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let mut px = Vec::new();
        while let Some(i) = stack.pop() {
            px.push(i as u32);
            let (r, c) = (i / w, i % w);
            for rr in r.saturating_sub(1)..(r + 2).min(h) {
                for cc in c.saturating_sub(1)..(c + 2).min(w) {
                    let j = rr * w + cc;
                    if data[j] != 0 && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        px.sort_unstable();
        out.push(px);
    }
    out
}

/// Fill the holes of a binary mask (255 = object): background pixels not
/// 4-connected to the image border become object.
///
/// Written here (a flood fill from the border with an explicit stack) because
/// imageproc 0.27 has no hole filling.
pub fn fill_holes(mask: &mut GrayImage) {
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    let data: &mut [u8] = mask;
    // 0 = background not yet reached, 255 = object, 1 = background reached from the border
    let mut stack: Vec<usize> = Vec::new();
    let push = |i: usize, data: &mut [u8], stack: &mut Vec<usize>| {
        if data[i] == 0 {
            data[i] = 1;
            stack.push(i);
        }
    };
    for c in 0..w {
        push(c, data, &mut stack);
        push((h - 1) * w + c, data, &mut stack);
    }
    for r in 0..h {
        push(r * w, data, &mut stack);
        push(r * w + w - 1, data, &mut stack);
    }
    while let Some(i) = stack.pop() {
        let (r, c) = (i / w, i % w);
        if c > 0 {
            push(i - 1, data, &mut stack);
        }
        if c + 1 < w {
            push(i + 1, data, &mut stack);
        }
        if r > 0 {
            push(i - w, data, &mut stack);
        }
        if r + 1 < h {
            push(i + w, data, &mut stack);
        }
    }
    for v in data.iter_mut() {
        *v = if *v == 1 { 0 } else { 255 };
    }
}

/// A 60 x 40 px frame of background 0.5 with a disc of radius 8 px centred at (30, 20): relative
/// contrast `rim` at r = 7 (inside), `halo` at r = 9.5 (outside), centre as bright as the
/// background; and the background frame.
#[cfg(test)]
pub(crate) fn ring_disc(rim: f32, halo: f32) -> (Frame, Frame) {
    let (w, h) = (60usize, 40usize);
    let bg = Frame { width: w, height: h, data: vec![0.5; w * h] };
    let mut f = bg.clone();
    for r in 0..h {
        for c in 0..w {
            let d = (((c as f32 - 30.0).powi(2) + (r as f32 - 20.0).powi(2)).sqrt()) - 8.0;
            let v = rim * (-(d + 1.0).powi(2)).exp() + halo * (-(d - 1.5).powi(2)).exp();
            f.data[r * w + c] = 0.5 * (1.0 + v);
        }
    }
    (f, bg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closing_bridges_a_one_pixel_gap_and_keeps_the_outline() {
        let rows = [".......", ".##.##.", ".##.##.", "......."];
        let mut m = GrayImage::from_fn(7, 4, |x, y| Luma([if rows[y as usize].as_bytes()[x as usize] == b'#' { 255 } else { 0 }]));
        close_3x3(&mut m);
        let got: Vec<String> = (0..4).map(|y| (0..7).map(|x| if m.get_pixel(x, y)[0] > 0 { '#' } else { '.' }).collect()).collect();
        assert_eq!(got, vec![".......", ".#####.", ".#####.", "......."]);
    }

    #[test]
    fn components_are_eight_connected() {
        // two pixels touching at a corner are one component; a separate pixel is another
        let rows = ["#...", ".#..", "...#"];
        let m = GrayImage::from_fn(4, 3, |x, y| Luma([if rows[y as usize].as_bytes()[x as usize] == b'#' { 255 } else { 0 }]));
        assert_eq!(components_8(&m), vec![vec![0, 5], vec![11]]);
    }

    #[test]
    fn fill_holes_fills_enclosed_only() {
        // a ring (enclosing one hole) and a C shape open to the outside
        let rows = ["........", ".###....", ".#.#.##.", ".###.#..", ".....##.", "........"];
        let mut m = GrayImage::from_fn(8, 6, |x, y| Luma([if rows[y as usize].as_bytes()[x as usize] == b'#' { 255 } else { 0 }]));
        fill_holes(&mut m);
        assert_eq!(m.get_pixel(2, 2)[0], 255, "hole of the ring filled");
        assert_eq!(m.get_pixel(6, 3)[0], 0, "mouth of the C is not a hole");
        assert_eq!(m.get_pixel(0, 0)[0], 0);
    }

    #[test]
    fn dark_disc_with_bright_centre_and_halo_is_one_filled_object() {
        let (f, bg) = ring_disc(-0.4, 0.3);
        let s = segment(&f, &bg, 0..40, 0.2, &SegmentParams::default());
        assert_eq!(s.blobs.len(), 1);
        let area = s.blobs[0].pixels.len() as f64;
        // the rim's threshold crossing lies near d = 0: area close to pi 8^2 = 201 px
        assert!(area > 150.0 && area < 230.0, "{area}");
        assert!(!s.blobs[0].touches_border);
    }
}
