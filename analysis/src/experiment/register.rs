//! A track's per-frame positions refined by registering each frame on the track's own image.
//!
//! A detection's centroid comes from its frame's outline alone, so pixel noise on the outline
//! moves it from frame to frame (at 0.35 um/px and 2 % noise, 0.009-0.027 um rms in y per cell).
//! A cell keeps its shape while it crosses the field, so every frame of a track shows the same
//! image at another position: the track's template `T`, the per-pixel median of the frames'
//! contrast patches ([`ContrastPatch`]; at most [`TEMPLATE_FRAMES`] of them) sampled at their
//! centroids `p_k` plus integer offsets `u` (bilinear, px), and each frame's offset against it
//! follow from all of its pixels instead of its outline (Lucas-Kanade):
//!
//! `delta_k = argmin sum_u (P_k(p_k + u) - T(u) - grad T(u) . delta)^2`,
//! `(sum g g^T) delta_k = sum g (P_k(p_k + u) - T(u))`, `p_k <- p_k - delta_k`,
//!
//! then the offsets are re-centred to a zero mean, so the track keeps the mean of its frames'
//! centroids (the registration takes out the frame-to-frame scatter, not the outline's bias),
//! and each frame is resampled at its new position for the next round (at most [`ITERATIONS`]
//! rounds, until no offset moves by more than [`CONVERGED_PX`]; a track whose last round still
//! moves an offset by more than [`STILL_MOVING_PX`] keeps its centroids). The template is drawn
//! once: drawn again at the registered positions each round it gave the same y errors to 1e-4 um
//! (the centroids' scatter, ~0.05 px, hardly blurs it). Pixels a frame does not share with the
//! template (residual beyond [`OUTLIER_SIGMAS`] robust sigmas) are left out of its offset.
//! Frames whose offset would exceed [`MAX_SHIFT_PX`] do not show the same image as the others
//! (a neighbour touching, debris joining, a changing shape): the track then keeps its centroids.

use crate::stats::median::median;
use crate::types::ContrastPatch;

/// Register rounds (each frame resampled at its offset and its offset solved again).
pub const ITERATIONS: usize = 3;

/// The rounds stop early once no frame's offset moves by more than this, px. The rounds settle
/// at updates of 0.003-0.015 px, not at zero (resampled at a new sub-pixel phase a frame's noise
/// interpolates differently; measured on `examples/frames` and the grid's noisiest row): the
/// first round moves the offsets by 0.04-0.18 px, the second by 0.009-0.024.
pub const CONVERGED_PX: f64 = 0.01;

/// A last round that still moves an offset by more than this, px, has not found the frame's
/// image near its centroid (a shift beyond the template's linear range, a changing shape): the
/// track keeps its centroids.
pub const STILL_MOVING_PX: f64 = 0.1;

/// Largest offset of a frame from its centroid that the registration accepts, px. The outline's
/// noise moves a centroid by a few hundredths of a pixel; half a pixel is a different image.
pub const MAX_SHIFT_PX: f64 = 0.5;

/// A pixel whose residual against the template exceeds this many robust standard deviations
/// of the frame's residuals is not the cell the other frames show (a neighbour, debris, a
/// reflection in this frame only) and does not pull the frame's offset.
pub const OUTLIER_SIGMAS: f64 = 4.0;

/// Most frames the template is drawn from (spread evenly over a longer track): its noise is then
/// a quarter of one frame's, and the per-pixel medians cost no more for a slow cell's long track.
pub const TEMPLATE_FRAMES: usize = 15;

/// Fewest frames a track is registered with (with two, the median template is their mean and each
/// frame's offset is half their difference: no better than the centroids).
pub const MIN_FRAMES: usize = 3;

/// Offsets `(dx, dy)` (px, zero mean) to add to the positions `p` of a track's frames, whose
/// contrast patches are `patches`, or `None` when the frames are too few, an offset exceeds
/// [`MAX_SHIFT_PX`], the rounds do not settle ([`STILL_MOVING_PX`]) or a frame has no contrast
/// to register on.
pub fn register(patches: &[&ContrastPatch], p: &[(f64, f64)]) -> Option<Vec<(f64, f64)>> {
    Registrar::default().register(patches, p)
}

/// [`register`] with its buffers kept from one track to the next (the tracks of a recording).
#[derive(Debug, Default)]
pub struct Registrar {
    frames: Vec<f64>,
    template: Vec<f64>,
    column: Vec<f64>,
    terms: Vec<(f64, f64, f64)>,
    abs_r: Vec<f64>,
}

impl Registrar {
    /// [`register`].
    pub fn register(&mut self, patches: &[&ContrastPatch], p: &[(f64, f64)]) -> Option<Vec<(f64, f64)>> {
        let Registrar { frames, template, column, terms, abs_r } = self;
        register_with(patches, p, frames, template, column, terms, abs_r)
    }
}

fn register_with(
    patches: &[&ContrastPatch],
    p: &[(f64, f64)],
    frames: &mut Vec<f64>,
    template: &mut Vec<f64>,
    column: &mut Vec<f64>,
    terms: &mut Vec<(f64, f64, f64)>,
    abs_r: &mut Vec<f64>,
) -> Option<Vec<(f64, f64)>> {
    let n = patches.len();
    if n < MIN_FRAMES || p.len() != n {
        return None;
    }
    // the grid of offsets: on each side as far as half of the frames' patches reach from their
    // positions (the template needs half of the frames at a pixel)
    let side = |f: &dyn Fn(&ContrastPatch, (f64, f64)) -> f64| {
        let mut r: Vec<f64> = patches.iter().zip(p).map(|(q, &at)| f(q, at)).collect();
        median(&mut r).unwrap_or(0.0).floor() as i64
    };
    let left = side(&|q, (x, _)| x - q.col0 as f64);
    let right = side(&|q, (x, _)| (q.col0 + q.width) as f64 - 1.0 - x);
    let up = side(&|q, (_, y)| y - q.row0 as f64);
    let down = side(&|q, (_, y)| (q.row0 + q.height) as f64 - 1.0 - y);
    if left.min(right).min(up).min(down) < 2 {
        return None;
    }
    let (gw, gh) = ((left + right + 1) as usize, (up + down + 1) as usize);
    let mut shift = vec![(0.0f64, 0.0f64); n];
    let mut cuts = vec![f64::INFINITY; n];
    frames.clear();
    frames.resize(n * gw * gh, f64::NAN);
    template.clear();
    template.resize(gw * gh, f64::NAN);
    // the frames the template is drawn from: all, or TEMPLATE_FRAMES spread evenly over a long track
    let chosen: Vec<usize> = if n <= TEMPLATE_FRAMES { (0..n).collect() } else { (0..TEMPLATE_FRAMES).map(|j| j * (n - 1) / (TEMPLATE_FRAMES - 1)).collect() };
    let mut largest = f64::INFINITY;
    for round in 0..ITERATIONS {
        largest = 0.0;
        // each frame sampled at its position plus the grid's offsets
        for k in 0..n {
            let at = (p[k].0 + shift[k].0, p[k].1 + shift[k].1);
            patches[k].resample(at, (-left, -up), (gw, gh), &mut frames[k * gw * gh..(k + 1) * gw * gh]);
        }
        // the template, once, at the frames' centroids: the per-pixel median over the template's
        // frames that cover the pixel (at least half of them)
        for (i, t) in template.iter_mut().enumerate().take_while(|_| round == 0) {
            column.clear();
            column.extend(chosen.iter().map(|&k| frames[k * gw * gh + i]).filter(|s| s.is_finite()));
            *t = if 2 * column.len() >= chosen.len() { median(column).unwrap_or(f64::NAN) } else { f64::NAN };
        }
        // each frame's offset against it
        for k in 0..n {
            let f = &frames[k * gw * gh..(k + 1) * gw * gh];
            terms.clear();
            for v in 1..gh - 1 {
                for u in 1..gw - 1 {
                    let i = v * gw + u;
                    let gx = 0.5 * (template[i + 1] - template[i - 1]);
                    let gy = 0.5 * (template[i + gw] - template[i - gw]);
                    let r = f[i] - template[i];
                    if gx.is_finite() && gy.is_finite() && r.is_finite() {
                        terms.push((gx, gy, r));
                    }
                }
            }
            // pixels the template does not explain (a neighbour or debris in this frame only)
            // left out: residuals beyond OUTLIER_SIGMAS robust sigmas (1.4826 x their median |r|)
            // (read in the first round, at the centroids, on every 4th pixel: ~1000 of a cell's
            // residuals at 0.15 um/px, the scale to a few per cent; kept for the later rounds)
            if round == 0 {
                abs_r.clear();
                abs_r.extend(terms.iter().step_by(4).map(|t| t.2.abs()));
                cuts[k] = OUTLIER_SIGMAS * 1.4826 * median(abs_r).unwrap_or(f64::INFINITY);
            }
            let cut = cuts[k];
            let (mut a, mut b) = ([0.0f64; 3], [0.0f64; 2]);
            for &(gx, gy, r) in terms.iter().filter(|t| t.2.abs() <= cut) {
                a[0] += gx * gx;
                a[1] += gx * gy;
                a[2] += gy * gy;
                b[0] += gx * r;
                b[1] += gy * r;
            }
            let det = a[0] * a[2] - a[1] * a[1];
            if !(det > 1e-12 * (a[0] * a[2]).max(f64::MIN_POSITIVE)) {
                return None;
            }
            let dx = (a[2] * b[0] - a[1] * b[1]) / det;
            let dy = (a[0] * b[1] - a[1] * b[0]) / det;
            shift[k].0 -= dx;
            shift[k].1 -= dy;
            largest = largest.max(dx.hypot(dy));
        }
        let mean = shift.iter().fold((0.0, 0.0), |m, s| (m.0 + s.0, m.1 + s.1));
        let mean = (mean.0 / n as f64, mean.1 / n as f64);
        for s in &mut shift {
            s.0 -= mean.0;
            s.1 -= mean.1;
        }
        if largest <= CONVERGED_PX {
            break;
        }
    }
    let settled = largest <= STILL_MOVING_PX;
    (settled && shift.iter().all(|s| s.0.hypot(s.1) <= MAX_SHIFT_PX && s.0.is_finite() && s.1.is_finite())).then_some(shift)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, Normal};

    /// An asymmetric dark cell (a ring of radius 9 px with a denser lobe), smoothed, at `(x, y)`.
    fn cell(x: f64, y: f64, xi: f64, yi: f64) -> f64 {
        let (dx, dy) = (xi - x, yi - y);
        let r = dx.hypot(dy);
        let ring = -(-(r - 9.0).powi(2) / 4.0).exp();
        let lobe = -0.5 * (-((dx - 3.0).powi(2) + (dy + 2.0).powi(2)) / 10.0).exp();
        ring + lobe
    }

    /// Frames of one cell at known sub-pixel positions with pixel noise, and centroids off by
    /// noise of their own: the registration brings the positions to within a fraction of the
    /// centroids' scatter of the truth and keeps their mean exactly.
    #[test]
    fn noisy_centroids_are_registered_to_the_frames_true_offsets() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let pixel = Normal::new(0.0, 0.02).unwrap();
        let centroid = Normal::new(0.0, 0.08).unwrap();
        let n = 9;
        let truth: Vec<(f64, f64)> = (0..n).map(|k| (30.0 + 17.3 * k as f64 + 0.13 * k as f64, 25.0 + 0.037 * k as f64)).collect();
        let (w, h) = (240usize, 50usize);
        let mut patches = Vec::new();
        let mut p = Vec::new();
        for &(x, y) in &truth {
            let img: Vec<f32> = (0..w * h).map(|i| (cell(x, y, (i % w) as f64, (i / w) as f64) + pixel.sample(&mut rng)) as f32).collect();
            let (c0, r0) = ((x - 14.0).floor() as usize, (y - 14.0).floor() as usize);
            patches.push(ContrastPatch::cut(&img, w, (c0, r0), (29, 29)));
            p.push((x + centroid.sample(&mut rng), y + centroid.sample(&mut rng)));
        }
        let refs: Vec<&ContrastPatch> = patches.iter().collect();
        let shift = register(&refs, &p).expect("registered");
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let sx: Vec<f64> = shift.iter().map(|s| s.0).collect();
        let sy: Vec<f64> = shift.iter().map(|s| s.1).collect();
        assert!(mean(&sx).abs() < 1e-12 && mean(&sy).abs() < 1e-12, "zero mean: {shift:?}");
        // the error of a position about the track's mean error (the part registration can see)
        let rms = |pos: &dyn Fn(usize) -> (f64, f64)| {
            let e: Vec<(f64, f64)> = (0..n).map(|k| (pos(k).0 - truth[k].0, pos(k).1 - truth[k].1)).collect();
            let m = (mean(&e.iter().map(|e| e.0).collect::<Vec<_>>()), mean(&e.iter().map(|e| e.1).collect::<Vec<_>>()));
            (e.iter().map(|e| (e.0 - m.0).powi(2) + (e.1 - m.1).powi(2)).sum::<f64>() / n as f64).sqrt()
        };
        let before = rms(&|k| p[k]);
        let after = rms(&|k| (p[k].0 + shift[k].0, p[k].1 + shift[k].1));
        assert!(before > 0.07, "the centroids scatter: {before}");
        assert!(after < 0.2 * before, "registered {after:.4} px against the centroids' {before:.4} px");
    }

    /// The grid resampling is the bilinear interpolation of the box, NaN where a neighbour is
    /// missing (every sub-pixel phase and every edge).
    #[test]
    fn a_patch_resampled_on_a_grid_is_its_bilinear_interpolation() {
        let values: Vec<f32> = (0..7 * 5).map(|i| ((i * 37) % 11) as f32 - 3.0).collect();
        let q = ContrastPatch { col0: 10, row0: 20, width: 7, height: 5, values };
        let at = |c: i64, r: i64| -> Option<f64> {
            let (c, r) = (c - 10, r - 20);
            (c >= 0 && r >= 0 && c < 7 && r < 5).then(|| f64::from(q.values[(r * 7 + c) as usize]))
        };
        for (x, y) in [(13.0, 22.0), (13.25, 22.75), (9.6, 19.1), (16.5, 24.5), (12.999, 21.0001)] {
            let mut out = vec![0.0; 9 * 7];
            q.resample((x, y), (-4, -3), (9, 7), &mut out);
            for v in 0..7 {
                for u in 0..9 {
                    let (xs, ys) = (x + u as f64 - 4.0, y + v as f64 - 3.0);
                    let (c, r) = (xs.floor() as i64, ys.floor() as i64);
                    let (fx, fy) = (xs - xs.floor(), ys - ys.floor());
                    let want = match (at(c, r), at(c + 1, r), at(c, r + 1), at(c + 1, r + 1)) {
                        (Some(a), Some(b), Some(cc), Some(d)) => (1.0 - fy) * ((1.0 - fx) * a + fx * b) + fy * ((1.0 - fx) * cc + fx * d),
                        _ => f64::NAN,
                    };
                    let got = out[v * 9 + u];
                    assert!(got == want || (got.is_nan() && want.is_nan()) || (got - want).abs() < 1e-12, "({xs}, {ys}): {got} against {want}");
                }
            }
        }
    }

    /// A frame whose centroid lies 1.5 px from its cell (pulled by something joined to its
    /// outline) moves more than half a pixel: the track keeps its centroids. A frame with a
    /// second cell beside it is registered on the cell the others show; too few frames are not
    /// registered.
    #[test]
    fn a_centroid_far_from_its_image_or_too_few_frames_leave_the_centroids() {
        let (w, h) = (60usize, 50usize);
        let mut patches = Vec::new();
        for k in 0..5 {
            let intruder = if k == 3 { 1.0 } else { 0.0 };
            let img: Vec<f32> = (0..w * h)
                .map(|i| {
                    let (xi, yi) = ((i % w) as f64, (i / w) as f64);
                    (cell(30.0, 25.0, xi, yi) + intruder * cell(48.0, 25.0, xi, yi)) as f32
                })
                .collect();
            patches.push(ContrastPatch::cut(&img, w, (10, 5), (41, 41)));
        }
        let refs: Vec<&ContrastPatch> = patches.iter().collect();
        let mut p = vec![(30.0, 25.0); 5];
        let shift = register(&refs, &p).expect("registered");
        assert!(shift.iter().all(|s| s.0.hypot(s.1) < 0.02), "{shift:?}");
        p[1].1 += 1.5;
        let r = register(&refs, &p);
        assert!(r.is_none(), "{r:?}");
        assert!(register(&refs[..2], &p[..2]).is_none());
    }
}
