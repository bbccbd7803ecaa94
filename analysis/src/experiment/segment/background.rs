//! Per-recording background: the per-pixel temporal median of sampled frames (or a separable row x column model for very short recordings).
//!
//! Cells move along the channel while walls, dust and the illumination
//! pattern do not, so the per-pixel median over frames spread through the
//! recording is the empty channel, as long as no pixel is covered by a cell
//! in half or more of the sampled frames (true for any cell that moves more
//! than twice its length during the recording).

use crate::types::Frame;
use rayon::prelude::*;

/// Fewest frames for which the temporal median is used; shorter recordings use [`row_background`].
pub const MIN_FRAMES_FOR_MEDIAN: usize = 5;

/// `k` frame indices spread evenly over `0..n` (all of them when `n <= k`).
pub fn sample_indices(n: usize, k: usize) -> Vec<usize> {
    if n <= k {
        return (0..n).collect();
    }
    let mut v: Vec<usize> = (0..k).map(|i| ((i as f64 + 0.5) * n as f64 / k as f64) as usize).collect();
    v.dedup();
    v
}

/// Per-pixel median of `frames` (all of one size, at least one).
pub fn median_background(frames: &[Frame]) -> Frame {
    let (width, height) = (frames[0].width, frames[0].height);
    let n = frames.len();
    let mut data = vec![0f32; width * height];
    data.par_chunks_mut(width).enumerate().for_each(|(r, out)| {
        let mut buf = vec![0f32; n]; // one scratch buffer per row, reused for every pixel
        for (c, o) in out.iter_mut().enumerate() {
            for (b, f) in buf.iter_mut().zip(frames) {
                *b = f.data[r * width + c];
            }
            *o = median_in_place(&mut buf);
        }
    });
    Frame { width, height, data }
}

/// Background of a single frame, separable model `B(r, c) = m_r f_c`:
/// `m_r` is the median of row `r` (the channel runs along the rows, so walls
/// and the across-channel illumination are kept; cells cover far less than
/// half of a row) and `f_c` the median over rows of `I / m_r` in column `c`,
/// smoothed by a running median over `+-max(w/16, 8)` columns so that cells
/// do not enter it (captures illumination that varies along the channel).
pub fn row_background(frame: &Frame) -> Frame {
    let (w, h) = (frame.width, frame.height);
    let (rowmed, raw) = separable_factors(frame);
    let half = (w / 16).max(8);
    let mut win = Vec::with_capacity(2 * half + 1);
    let colf: Vec<f32> = (0..w)
        .map(|c| {
            win.clear();
            win.extend_from_slice(&raw[c.saturating_sub(half)..(c + half + 1).min(w)]);
            median_in_place(&mut win)
        })
        .collect();
    let mut data = vec![0f32; w * h];
    for (r, out) in data.chunks_mut(w).enumerate() {
        for (o, f) in out.iter_mut().zip(&colf) {
            *o = rowmed[r] * f;
        }
    }
    Frame { width: w, height: h, data }
}

/// The factors of the separable model `I(r, c) = m_r f_c` of [`row_background`], before any
/// smoothing: `m_r` the median of row `r`, `f_c` the median over rows of `I / m_r` in column `c`
/// (1 where every row median is 0).
pub fn separable_factors(frame: &Frame) -> (Vec<f32>, Vec<f32>) {
    let (w, h) = (frame.width, frame.height);
    let mut buf = vec![0f32; w.max(h)];
    let rowmed: Vec<f32> = (0..h)
        .map(|r| {
            buf[..w].copy_from_slice(&frame.data[r * w..(r + 1) * w]);
            median_in_place(&mut buf[..w])
        })
        .collect();
    let colf: Vec<f32> = (0..w)
        .map(|c| {
            let mut k = 0;
            for (r, &m) in rowmed.iter().enumerate() {
                if m > 1e-6 {
                    buf[k] = frame.data[r * w + c] / m;
                    k += 1;
                }
            }
            if k == 0 { 1.0 } else { median_in_place(&mut buf[..k]) }
        })
        .collect();
    (rowmed, colf)
}

/// Median of a non-empty slice (reorders it); mean of the two middle values for even length.
pub fn median_in_place(v: &mut [f32]) -> f32 {
    let n = v.len();
    let mid = n / 2;
    let (lo, m, _) = v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    let m = *m;
    if n % 2 == 1 {
        m
    } else {
        let lo_max = lo.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        0.5 * (lo_max + m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_ignores_a_passing_object() {
        // 7 frames of a flat background 0.5; a dark object covers pixel 3 in 3 of them.
        let frames: Vec<Frame> = (0..7)
            .map(|i| {
                let mut data = vec![0.5f32; 16];
                if i < 3 {
                    data[3] = 0.1;
                }
                Frame { width: 4, height: 4, data }
            })
            .collect();
        let bg = median_background(&frames);
        assert!(bg.data.iter().all(|&v| v == 0.5));
        assert_eq!(median_in_place(&mut [3.0, 1.0, 2.0, 4.0]), 2.5);
        assert_eq!(sample_indices(3, 5), vec![0, 1, 2]);
        assert_eq!(sample_indices(100, 4), vec![12, 37, 62, 87]);
    }
}
