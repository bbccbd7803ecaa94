//! The channel in the image: its two walls (horizontal lines) and its axis, from `recording.toml` or detected in the background.
//!
//! The channel runs along the image rows (flow along +x = increasing column).
//! In bright field each wall shows as a thin dark line (with a bright line
//! beside it) that does not move, so it is found in the per-recording
//! background (temporal median, see [`crate::experiment::segment::background`]): the row
//! profile (median over columns, robust to cells and dust) is high-pass
//! filtered, its dark local minima are candidate walls, and the pair with the
//! largest summed depth whose separation fits the channel width (within 25 %
//! when `channel.width_um` is known, else at least 30 % of the image height)
//! is taken. Each minimum is refined to sub-pixel by a parabola through three
//! rows. The axis is the centre of mirror symmetry of the log row profile
//! ([`axis`]), within 1 px of the mid-line between the two minima; the width is
//! the minima's distance.
//!
//! Pixel convention: the centre of pixel row `r` is at `y_px = r`; the signed
//! position across the channel is `y_um = (y_px - axis_row_px) * um_per_px`.

use crate::error::AnalysisError;
use crate::types::Frame;
use rbc_schema::recording::RecordingConfig;
use std::path::Path;

pub mod axis;

/// Where the channel geometry came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChannelSource {
    /// `channel.axis_row_px` (and `channel.width_um`) in `recording.toml`.
    Config,
    /// Detected from the wall lines in the background image.
    Detected,
}

/// The channel in one recording's image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelGeometry {
    /// Image row (pixel centres at integer rows) of the channel centre line.
    pub axis_row_px: f64,
    /// Rows of the two walls, `[top, bottom]` with `top < bottom`.
    pub wall_rows_px: [f64; 2],
    /// Pixel size, um per pixel.
    pub um_per_px: f64,
    pub source: ChannelSource,
}

impl ChannelGeometry {
    /// Signed distance from the axis, um, of an image row position (px).
    #[inline]
    pub fn y_um(&self, y_px: f64) -> f64 {
        (y_px - self.axis_row_px) * self.um_per_px
    }

    /// Wall-to-wall distance, um.
    pub fn width_um(&self) -> f64 {
        (self.wall_rows_px[1] - self.wall_rows_px[0]) * self.um_per_px
    }

    /// Image rows strictly between the walls (where cells can be), clamped to `0..height`.
    pub fn interior_rows(&self, height: usize) -> std::ops::Range<usize> {
        let lo = (self.wall_rows_px[0].floor() + 1.0).max(0.0) as usize;
        let hi = (self.wall_rows_px[1].ceil()).max(0.0) as usize;
        let hi = hi.min(height);
        lo.min(hi)..hi
    }
}

/// Channel geometry of a recording: from `recording.toml` when it gives
/// `channel.axis_row_px`, else detected from the background image.
/// `toml_path` names the file in errors.
pub fn locate(background: &Frame, cfg: &RecordingConfig, toml_path: &Path) -> Result<ChannelGeometry, AnalysisError> {
    let um = cfg.um_per_px;
    if let Some(ch) = &cfg.channel {
        if let Some(axis) = ch.axis_row_px {
            // the axis lies on the image: one off it would find no cell in the channel and write
            // empty tables over good ones
            let rows = background.height as f64;
            if !(0.0..=rows - 1.0).contains(&axis) {
                return Err(AnalysisError::Input { path: toml_path.to_path_buf(), message: format!("field `channel.axis_row_px`: {axis} lies off the frames' rows 0..{}", background.height - 1) });
            }
            let half = 0.5 * ch.width_um / um;
            return Ok(ChannelGeometry { axis_row_px: axis, wall_rows_px: [axis - half, axis + half], um_per_px: um, source: ChannelSource::Config });
        }
    }
    let expected_px = cfg.channel.as_ref().map(|c| c.width_um / um);
    match detect_walls(background, expected_px) {
        Some([a, b]) => Ok(ChannelGeometry { axis_row_px: 0.5 * (a + b), wall_rows_px: [a, b], um_per_px: um, source: ChannelSource::Detected }),
        None => Err(AnalysisError::Input {
            path: toml_path.to_path_buf(),
            message: "channel walls not found in the frames; give field `channel.axis_row_px` (and `channel.width_um`)".into(),
        }),
    }
}

/// Row profile of an image: the median of each row over its columns.
pub fn row_profile(img: &Frame) -> Vec<f64> {
    let mut buf = vec![0f32; img.width];
    (0..img.height)
        .map(|r| {
            buf.copy_from_slice(&img.data[r * img.width..(r + 1) * img.width]);
            let mid = buf.len() / 2;
            let (_, m, _) = buf.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
            *m as f64
        })
        .collect()
}

/// Rows (sub-pixel) of the two wall lines in `background`, or `None` when no pair fits.
///
/// `expected_px`: the channel width in pixels when known.
pub fn detect_walls(background: &Frame, expected_px: Option<f64>) -> Option<[f64; 2]> {
    let p = row_profile(background);
    let n = p.len();
    if n < 8 {
        return None;
    }
    let q = high_pass(&p);
    // Noise of the profile: MAD of its first differences.
    let mut d: Vec<f64> = q.windows(2).map(|x| (x[1] - x[0]).abs()).collect();
    let mid = d.len() / 2;
    let mad = *d.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1;
    let floor = 3.0 * 1.4826 * mad / std::f64::consts::SQRT_2;
    // Candidate wall lines: local minima (depth = -q) above the noise floor.
    let mut cand: Vec<(f64, f64)> = Vec::new(); // (row, depth)
    for r in 1..n - 1 {
        if q[r] < q[r - 1] && q[r] <= q[r + 1] && -q[r] > floor {
            let denom = q[r - 1] - 2.0 * q[r] + q[r + 1];
            let off = if denom > 0.0 { (0.5 * (q[r - 1] - q[r + 1]) / denom).clamp(-0.5, 0.5) } else { 0.0 };
            cand.push((r as f64 + off, -q[r]));
        }
    }
    // Walls are the strongest line features: drop minima shallower than a quarter of the deepest.
    let deepest = cand.iter().map(|c| c.1).fold(0.0, f64::max);
    cand.retain(|c| c.1 >= 0.25 * deepest);
    let mut best: Option<([f64; 2], f64)> = None;
    for i in 0..cand.len() {
        for j in i + 1..cand.len() {
            let sep = cand[j].0 - cand[i].0;
            let ok = match expected_px {
                Some(e) => (sep - e).abs() <= 0.25 * e,
                None => sep >= 0.3 * n as f64,
            };
            if !ok {
                continue;
            }
            // Walls are alike: penalise pairs of very different depth.
            let score = cand[i].1.min(cand[j].1) * 2.0 + 0.1 * (cand[i].1 + cand[j].1);
            if best.is_none_or(|(_, s)| score > s) {
                best = Some(([cand[i].0, cand[j].0], score));
            }
        }
    }
    let [a, b] = best?.0;
    // The axis is the centre of mirror symmetry of the profile around the
    // walls (both walls and what lies between them), which is more precise
    // than the two parabola vertices alone; keep the detected width. The log
    // profile read alike on both sides ([`axis`]); the high-passed profile
    // against its interpolated mirror where it has no logarithm (a row <= 0).
    let half = 0.5 * (b - a);
    let axis = axis::symmetric_centre(&axis::level_profile(background), 0.5 * (a + b), half + axis::BEYOND_WALL_PX)
        .unwrap_or_else(|| mirror_centre(&q, 0.5 * (a + b), half + 3.0));
    Some([axis - half, axis + half])
}

/// The row profile minus its running median over +-w rows (w = n/8, at least 5),
/// so that uneven illumination does not create or hide minima.
pub fn high_pass(p: &[f64]) -> Vec<f64> {
    let n = p.len();
    let w = (n / 8).max(5);
    let mut win = Vec::with_capacity(2 * w + 1);
    (0..n)
        .map(|r| {
            win.clear();
            win.extend_from_slice(&p[r.saturating_sub(w)..(r + w + 1).min(n)]);
            let mid = win.len() / 2;
            let (_, m, _) = win.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
            p[r] - *m
        })
        .collect()
}

/// Centre `c` (within +-1 px of `c0`) that minimises the squared difference
/// between the profile and its mirror image `q(2c - r)` over rows
/// `|r - c0| <= reach`; grid of 0.01 px refined by a parabola. The fallback of
/// [`detect_walls`] for a profile with no logarithm (see [`axis`] for its bias
/// with walls narrower than a pixel).
pub fn mirror_centre(q: &[f64], c0: f64, reach: f64) -> f64 {
    let n = q.len();
    let interp = |y: f64| -> Option<f64> {
        if y < 0.0 || y > (n - 1) as f64 {
            return None;
        }
        let i = (y.floor() as usize).min(n - 2);
        let f = y - i as f64;
        Some(q[i] * (1.0 - f) + q[i + 1] * f)
    };
    let lo = (c0 - reach).ceil().max(0.0) as usize;
    let hi = ((c0 + reach).floor() as usize).min(n - 1);
    let cost = |c: f64| -> f64 {
        let (mut s, mut k) = (0.0, 0usize);
        for (r, &qr) in q.iter().enumerate().take(hi + 1).skip(lo) {
            if let Some(m) = interp(2.0 * c - r as f64) {
                s += (qr - m).powi(2);
                k += 1;
            }
        }
        if k > 0 { s / k as f64 } else { f64::MAX }
    };
    let steps = 200;
    let mut best = (0usize, f64::MAX);
    let costs: Vec<f64> = (0..=steps).map(|i| cost(c0 - 1.0 + 2.0 * i as f64 / steps as f64)).collect();
    for (i, &v) in costs.iter().enumerate() {
        if v < best.1 {
            best = (i, v);
        }
    }
    let h = 2.0 / steps as f64;
    let mut c = c0 - 1.0 + best.0 as f64 * h;
    if best.0 > 0 && best.0 < steps {
        let (a, b, d) = (costs[best.0 - 1], costs[best.0], costs[best.0 + 1]);
        let den = a - 2.0 * b + d;
        if den > 0.0 {
            c += (0.5 * (a - d) / den).clamp(-0.5, 0.5) * h;
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A background with two Gaussian dark lines at known rows and a linear illumination gradient.
    fn lines(height: usize, rows: [f64; 2]) -> Frame {
        let width = 40;
        let mut data = vec![0f32; width * height];
        for r in 0..height {
            let mut v = 0.6 + 0.002 * r as f64;
            for &w in &rows {
                v -= 0.2 * (-0.5 * ((r as f64 - w) / 1.2).powi(2)).exp();
            }
            for c in 0..width {
                data[r * width + c] = v as f32;
            }
        }
        Frame { width, height, data }
    }

    #[test]
    fn finds_two_lines_to_subpixel() {
        let f = lines(100, [20.3, 78.6]);
        let w = detect_walls(&f, None).unwrap();
        assert!((w[0] - 20.3).abs() < 0.15 && (w[1] - 78.6).abs() < 0.15, "{w:?}");
        let w = detect_walls(&f, Some(58.0)).unwrap();
        assert!((w[0] - 20.3).abs() < 0.15, "{w:?}");
        assert!(detect_walls(&f, Some(20.0)).is_none());
    }
}
