//! Motion blur along the flow: its length read from the recording, and the y centroid of a cell measured on its contrast with the blur taken out.
//!
//! A cell moving along x during the exposure is imaged as the mean of its image over a track of
//! length `L` (px): each row is convolved with a box of width `L`. A threshold on that image
//! widens the rows by an amount that grows with the row's contrast (the thick dark rim on a
//! slipper's wide side) and dilutes the pointed tips below the threshold, which moves the centroid
//! towards the wide side (+0.013 to +0.022 um for slippers 1.8-2.4 um off the axis at `L` = 2.5 um;
//! analysis/README.md). The box is undone exactly, row by row: with `b` the blurred contrast and
//! `c` the sharp one, `b'(x) = (c(x + L/2) - c(x - L/2)) / L`, so
//! `c(x) = L b'(x - L/2) + c(x - L)` from the left and `c(x) = -L b'(x + L/2) + c(x + L)` from the
//! right, starting from the background (`c = 0`) on either side ([`deblur_rows`]).
//!
//! The blur length comes from the recording itself ([`BlurLength`]): the second x derivative of a
//! blurred row is the difference of two copies of the sharp row's first derivative `L` apart,
//! `b'' = (c'(x + L/2) - c'(x - L/2)) / L`, so its autocorrelation along x,
//! `(2 R(t) - R(t - L) - R(t + L)) / L^2` with `R` that of `c'`, has its minimum at lag `L` where
//! `R`'s peak at 0 stands apart from its own structure; that structure's minimum is read along y
//! (`lag_y`), which the blur does not touch (3.4 px wave, 4.2 px synthesiser at 0.2 um/px; read
//! along x in sharp recordings, 3.4 and 4.1-4.4). Measured on the 6 recordings of each blurred
//! grid row: `lag_x` 12.0-12.7 px (wave) and 11.4-12.8 px (synthesiser) for the true 12.5 px of
//! 250 us at 10 mm/s, 4.9-5.5 px for the true 5 px of 100 us.

use crate::experiment::measure::measure_refined;
use crate::experiment::segment::{close_3x3, components_8, fill_holes, Blob, Outline, Segmentation};
use crate::stats::median::upper_median;
use image::{GrayImage, Luma};

/// The blur is taken out only when the x lag is at least this many times the edges' own lag along
/// y (`lag_y`, 3.4-4.3 px at 0.2 um/px): below it the minimum at `L` merges with the edges' own, and
/// a short blur costs less than the noise that undoing it adds (measured at 1 um of blur, 5 px,
/// with the true length: the synthesiser's 100 us row 0.0031 -> 0.0049 um median y error).
pub const MIN_BLUR_OVER_EDGE_LAG: f64 = 2.0;

/// Passes of the `[1, 2, 1] / 4` filter along x over the deblurred rows (sigma = sqrt(passes / 2)
/// px): undoing the box multiplies the derivative's noise by `L`.
pub const SMOOTHING_PASSES: usize = 4;

/// The blur length of a recording, px, from the autocorrelation lags of its cells' contrast.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BlurLength {
    /// Median over the cells of the lag of the minimum of the second x derivative's autocorrelation, px.
    pub lag_x_px: f64,
    /// The same along y, px: the edges' own scale.
    pub lag_y_px: f64,
    /// Cells the medians are over.
    pub cells: usize,
}

impl BlurLength {
    /// Read from the objects of `segs` of at least `min_px` pixels that touch no border.
    pub fn from_segmentations(segs: &[Segmentation], min_px: usize) -> BlurLength {
        let (mut lx, mut ly) = (Vec::new(), Vec::new());
        for seg in segs {
            for b in seg.blobs.iter().filter(|b| !b.touches_border && b.pixels.len() >= min_px) {
                lx.push(autocorrelation_minimum(seg, b, true));
                ly.push(autocorrelation_minimum(seg, b, false));
            }
        }
        if lx.is_empty() {
            return BlurLength::default();
        }
        let cells = lx.len();
        let upper = |v: &mut [f64]| upper_median(v).expect("lx, ly non-empty");
        BlurLength { lag_x_px: upper(&mut lx), lag_y_px: upper(&mut ly), cells }
    }

    /// The length to undo, px: the x lag when it is at least [`MIN_BLUR_OVER_EDGE_LAG`] times the
    /// y lag (the minimum at `L` stands apart from the edges' own), else `None` (no correction).
    pub fn to_undo_px(&self) -> Option<f64> {
        let l = self.lag_x_px;
        (self.cells > 0 && l >= 1.0 && l >= MIN_BLUR_OVER_EDGE_LAG * self.lag_y_px).then_some(l)
    }
}

/// Lag, px (sub-pixel by a parabola), of the minimum from lag 2 of the autocorrelation of the
/// contrast's second difference along x (`along_x`) or y, summed over the rows (or columns) of
/// `blob` (4 px beyond it each way), lags up to 0.6 of its extent.
pub fn autocorrelation_minimum(seg: &Segmentation, blob: &Blob, along_x: bool) -> f64 {
    let (w, h) = (seg.width, seg.height);
    let ((a0, a1), (s0, s1), n_along) = if along_x { (blob.col_range, blob.row_range, w) } else { (blob.row_range, blob.col_range, h) };
    let tmax = ((a1 - a0 + 1) * 6 / 10).max(4);
    let (lo, hi) = (a0.saturating_sub(4).max(1), (a1 + 4).min(n_along - 2));
    let at = |along: usize, across: usize| if along_x { seg.contrast[across * w + along] } else { seg.contrast[along * w + across] } as f64;
    let mut acf = vec![0.0f64; tmax + 1];
    let mut d = Vec::with_capacity(hi + 1 - lo);
    for s in s0..=s1 {
        d.clear();
        d.extend((lo..=hi).map(|k| at(k + 1, s) - 2.0 * at(k, s) + at(k - 1, s)));
        for (t, a) in acf.iter_mut().enumerate() {
            *a += d.iter().zip(d.iter().skip(t)).map(|(p, q)| p * q).sum::<f64>();
        }
    }
    let k = (2..tmax).min_by(|&i, &j| acf[i].total_cmp(&acf[j])).unwrap_or(2);
    let (a, b, c) = (acf[k - 1], acf[k], acf[k + 1]);
    let den = a - 2.0 * b + c;
    if den > 0.0 { k as f64 + 0.5 * (a - c) / den } else { k as f64 }
}

/// The rows `rows` x columns `cols` of `seg`'s contrast with a box blur of `l` px (>= 1) along x
/// undone: the recursion from the left and the one from the right, weighted linearly across the
/// patch (each exact, each accumulating noise away from its start), then
/// [`SMOOTHING_PASSES`] of `[1, 2, 1] / 4` along x. Row-major, `cols.len()` wide.
pub fn deblur_rows(seg: &Segmentation, rows: std::ops::RangeInclusive<usize>, cols: std::ops::RangeInclusive<usize>, l: f64) -> Vec<f32> {
    let w = seg.width;
    let (c0, c1) = (*cols.start(), *cols.end());
    let pw = c1 - c0 + 1;
    let mut out = Vec::with_capacity(pw * rows.clone().count());
    let (mut from_left, mut from_right, mut d) = (vec![0.0; pw], vec![0.0; pw], vec![0.0; pw]);
    // linear interpolation of the values computed so far (0 before the start: the background)
    let earlier = |v: &[f64], x: f64| -> f64 {
        if x < 0.0 {
            return 0.0;
        }
        let i = x.floor() as usize;
        let f = x - i as f64;
        v[i] * (1.0 - f) + if f > 0.0 { v[i + 1] * f } else { 0.0 }
    };
    for r in rows {
        let row = &seg.contrast[r * w..(r + 1) * w];
        let at = |x: f64| -> f64 {
            let x = x.clamp(0.0, (w - 1) as f64);
            let i = (x.floor() as usize).min(w - 2);
            let f = x - i as f64;
            row[i] as f64 * (1.0 - f) + row[i + 1] as f64 * f
        };
        for k in 0..pw {
            let x = (c0 + k) as f64;
            from_left[k] = l * (at(x - 0.5 * l + 0.5) - at(x - 0.5 * l - 0.5)) + earlier(&from_left, k as f64 - l);
        }
        for j in 0..pw {
            let x = (c1 - j) as f64;
            from_right[j] = -l * (at(x + 0.5 * l + 0.5) - at(x + 0.5 * l - 0.5)) + earlier(&from_right, j as f64 - l);
        }
        for (k, v) in d.iter_mut().enumerate() {
            let wt = k as f64 / (pw - 1).max(1) as f64;
            *v = (1.0 - wt) * from_left[k] + wt * from_right[pw - 1 - k];
        }
        for _ in 0..SMOOTHING_PASSES {
            let mut prev = d[0];
            for k in 1..pw.saturating_sub(1) {
                let cur = d[k];
                d[k] = 0.25 * (prev + 2.0 * cur + d[k + 1]);
                prev = cur;
            }
        }
        out.extend(d.iter().map(|&v| v as f32));
    }
    out
}

/// Centroid row, px, of `blob` measured on its patch of `seg` with a blur of `l` px undone
/// ([`deblur_rows`]): the patch (the blob's box, 2 rows and `l` + 4 columns wider on each side)
/// is thresholded at `-t_low`, closed, its holes filled, and the largest object's sub-pixel
/// centroid taken ([`measure_refined`]). `None` when nothing in the patch passes the threshold.
pub fn deblurred_y_px(blob: &Blob, seg: &Segmentation, l: f64) -> Option<f64> {
    let (w, h) = (seg.width, seg.height);
    let pad = l.ceil() as usize + 4;
    let (c0, c1) = (blob.col_range.0.saturating_sub(pad), (blob.col_range.1 + pad).min(w - 1));
    let (r0, r1) = (blob.row_range.0.saturating_sub(2), (blob.row_range.1 + 2).min(h - 1));
    let (pw, ph) = (c1 - c0 + 1, r1 - r0 + 1);
    let contrast = deblur_rows(seg, r0..=r1, c0..=c1, l);
    let mut mask = GrayImage::from_fn(pw as u32, ph as u32, |x, y| Luma([if contrast[y as usize * pw + x as usize] < -seg.t_low { 255u8 } else { 0 }]));
    close_3x3(&mut mask);
    fill_holes(&mut mask);
    let pixels = components_8(&mask).into_iter().max_by_key(Vec::len)?;
    let patch = Segmentation { width: pw, height: ph, blobs: Vec::new(), contrast, noise_sigma: seg.noise_sigma, t_low: seg.t_low, gain: seg.gain, polarity: seg.polarity, t_high: seg.t_high };
    let (mut a0, mut a1, mut b0, mut b1) = (usize::MAX, 0, usize::MAX, 0);
    for &i in &pixels {
        let (r, c) = (i as usize / pw, i as usize % pw);
        (a0, a1, b0, b1) = (a0.min(c), a1.max(c), b0.min(r), b1.max(r));
    }
    let nb = Blob { pixels, col_range: (a0, a1), row_range: (b0, b1), touches_border: false, outline: Outline::Threshold };
    Some(measure_refined(&nb, &patch).y_px + r0 as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::segment::{segment, SegmentParams};
    use crate::types::Frame;

    /// Contrast of a cell at (x, y) px: a "D" (flat side down, round side up: its area centroid
    /// lies 4 r / (3 pi) above the flat side) of radius `r` centred at (`cx`, `cy`), a dark rim
    /// (-0.35) just inside its outline over an absorbing interior (-0.1) and a bright halo (+0.08)
    /// outside, edges 1 px wide.
    fn d_cell(x: f64, y: f64, cx: f64, cy: f64, r: f64) -> f64 {
        let (dx, dy) = (x - cx, cy - y); // dy up
        // signed distance (approx.) to the D: the half-disc dy >= 0, radius r, closed by dy = 0
        let round = (dx * dx + dy * dy).sqrt() - r;
        let s = round.max(-dy);
        let edge = |t: f64| 1.0 / (1.0 + (t / 0.5).exp());
        let inside = edge(s);
        -0.1 * inside - 0.25 * (-((s + 1.0) / 0.8).powi(2)).exp() + 0.08 * (-((s - 1.5) / 1.0).powi(2)).exp()
    }

    /// Frames (w x h) of the D cell blurred along x by a box of `l` px (mean over 64 positions),
    /// with the background frame; and the D's exact area centroid row, px.
    fn blurred_d(l: f64) -> (Frame, Frame, f64) {
        let (w, h, cx, cy, r) = (120usize, 60usize, 60.0, 34.3, 14.0);
        let bg = Frame { width: w, height: h, data: vec![0.5; w * h] };
        let mut f = bg.clone();
        let n = 64;
        for row in 0..h {
            for col in 0..w {
                let mut acc = 0.0;
                for j in 0..n {
                    let sx = if l > 0.0 { l * ((j as f64 + 0.5) / n as f64 - 0.5) } else { 0.0 };
                    acc += d_cell(col as f64 - sx, row as f64, cx, cy, r);
                }
                f.data[row * w + col] = (0.5 * (1.0 + acc / n as f64)) as f32;
            }
        }
        (f, bg, cy - 4.0 * r / (3.0 * std::f64::consts::PI))
    }

    #[test]
    fn undoing_a_box_blur_gives_the_sharp_row_back() {
        // one row: a 30 px plateau of -0.3 with edges 1.5 px wide; blurred by 10 px exactly
        // (the mean of the sharp row over 400 sub-positions), then undone
        let (w, l) = (100usize, 10.0);
        let sharp = |x: f64| -0.3 / (1.0 + ((x - 65.0) / 1.5).exp()) / (1.0 + ((35.0 - x) / 1.5).exp());
        let blurred: Vec<f32> = (0..w).map(|c| ((0..400).map(|j| sharp(c as f64 + l * ((j as f64 + 0.5) / 400.0 - 0.5))).sum::<f64>() / 400.0) as f32).collect();
        let seg = Segmentation { width: w, height: 1, blobs: Vec::new(), contrast: blurred, noise_sigma: 0.0, t_low: 0.04, t_high: 0.08, gain: 1.0, polarity: 1.0 };
        let got = deblur_rows(&seg, 0..=0, 10..=89, l);
        // the sharp row through the same smoothing passes
        let mut want: Vec<f64> = (10..90).map(|c| sharp(c as f64)).collect();
        for _ in 0..SMOOTHING_PASSES {
            let e = want.clone();
            for k in 1..want.len() - 1 {
                want[k] = 0.25 * (e[k - 1] + 2.0 * e[k] + e[k + 1]);
            }
        }
        let worst = got.iter().zip(&want).map(|(g, w)| (*g as f64 - w).abs()).fold(0.0, f64::max);
        assert!(worst < 0.003, "largest difference {worst} (plateau 0.3)");
        // the blurred row itself is far from it: its edges are ramps 10 px wide (measured 0.025)
        let far = seg.contrast[10..90].iter().zip(&want).map(|(g, w)| (*g as f64 - w).abs()).fold(0.0, f64::max);
        assert!(far > 10.0 * worst, "{far} (worst {worst})");
    }

    #[test]
    fn the_blur_length_is_read_from_the_cells_and_a_sharp_recording_has_none() {
        let p = SegmentParams::default();
        for l in [10.0, 14.0] {
            let (f, bg, _) = blurred_d(l);
            let seg = segment(&f, &bg, 0..60, 0.2, &p);
            let b = BlurLength::from_segmentations(&[seg], 100);
            assert_eq!(b.cells, 1);
            assert!((b.lag_x_px - l).abs() < 1.0, "blur {l} px read as {b:?}");
            assert_eq!(b.to_undo_px(), Some(b.lag_x_px));
        }
        let (f, bg, _) = blurred_d(0.0);
        let b = BlurLength::from_segmentations(&[segment(&f, &bg, 0..60, 0.2, &p)], 100);
        assert_eq!(b.cells, 1);
        assert_eq!(b.to_undo_px(), None, "{b:?}");
    }

    #[test]
    fn the_blurred_cells_centroid_row_comes_back_with_the_blur_undone() {
        let p = SegmentParams::default();
        let (f, bg, truth) = blurred_d(0.0);
        let seg = segment(&f, &bg, 0..60, 0.2, &p);
        let sharp = measure_refined(&seg.blobs[0], &seg).y_px - truth;
        let (f, bg, _) = blurred_d(12.0);
        let seg = segment(&f, &bg, 0..60, 0.2, &p);
        assert_eq!(seg.blobs.len(), 1);
        let blurred = measure_refined(&seg.blobs[0], &seg).y_px - truth;
        let undone = deblurred_y_px(&seg.blobs[0], &seg, 12.0).unwrap() - truth;
        // px from the D's area centroid
        println!("sharp {sharp:+.4}, blurred {blurred:+.4}, undone {undone:+.4}");
        assert!((blurred - sharp).abs() > 0.05, "sharp {sharp:+.4}, blurred {blurred:+.4}");
        assert!((undone - sharp).abs() < 0.3 * (blurred - sharp).abs(), "sharp {sharp:+.4}, blurred {blurred:+.4}, undone {undone:+.4}");
    }
}
