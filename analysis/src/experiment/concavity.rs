//! Concavity of a segmented object's outline: its deepest notch and its deepest two-sided constriction (waist), relative to its width; the evidence that separates two touching cells merged into one object from a single bent cell.
//!
//! In the frame of the principal axes (`u` along the long axis, `v` across it,
//! origin at the centroid) the mask's outline is two envelopes over `u`: the
//! top `t(u) = max v + 1/2` and the bottom `b(u) = min v - 1/2` over the pixel
//! centres of the column bin `[u, u + 1)` px (the `1/2` is the pixel square's
//! half-width). Their notch depths below the convex hull are
//! `d_t(u) = T(u) - t(u)`, where `T` is the least concave majorant of `t`
//! (upper hull), and `d_b(u) = b(u) - B(u)` with `B` the greatest convex
//! minorant of `b` (lower hull); both are >= 0 and vanish on a convex outline.
//! With `w` the extent across the long axis (so that both measures are
//! dimensionless and do not depend on the pixel size):
//!
//! - **notch** `N = max_u max(d_t, d_b) / w`: the deepest concavity on either side.
//!   A single cell bent into a banana (a slipper, a curved croissant) is
//!   concave on the inside of the bend, but shallowly: the analytic bent
//!   slippers of the closed loop have `N <= 0.28`, 23 of 24 rendered solver
//!   shapes `N <= 0.29`; the gap between two touching bodies is deeper (the
//!   real RT-DC clusters, `analysis/tests/tracks_rtdc.rs`: `N = 0.38-0.42`).
//! - **waist** `W = max_u min( max_{|u' - u| <= k} d_t(u'), max_{|u' - u| <= k} d_b(u') ) / w`,
//!   `k = w / 2`: a constriction concave on *both* sides at once (the notches of an
//!   oblique junction may be offset along `u` by up to about `k`). A bend is
//!   concave on one side only, so `W` stays near the pixel quantisation (< 0.08 on
//!   the real single cells, <= 0.14 on 23 of 24 rendered solver shapes); two
//!   cells side by side give `W ~ 0.25`, two
//!   equal disks touching at a point `W -> 1/2`.
//!
use crate::experiment::segment::Blob;

/// Upper concave envelope (least concave majorant) of the points `(x_i, y_i)`, `x` increasing,
/// evaluated at every `x_i`. Andrew's monotone chain (upper hull), then linear interpolation.
fn upper_envelope(x: &[f64], y: &[f64]) -> Vec<f64> {
    let mut hull: Vec<usize> = Vec::with_capacity(x.len());
    for i in 0..x.len() {
        while hull.len() >= 2 {
            let (a, b) = (hull[hull.len() - 2], hull[hull.len() - 1]);
            // drop b when it lies on or below the chord a -> i
            let cross = (x[b] - x[a]) * (y[i] - y[a]) - (y[b] - y[a]) * (x[i] - x[a]);
            if cross >= 0.0 {
                hull.pop();
            } else {
                break;
            }
        }
        hull.push(i);
    }
    let mut out = Vec::with_capacity(x.len());
    let mut s = 0;
    for i in 0..x.len() {
        while s + 1 < hull.len() - 1 && x[hull[s + 1]] < x[i] {
            s += 1;
        }
        let (a, b) = (hull[s], hull[(s + 1).min(hull.len() - 1)]);
        out.push(if b == a || x[b] == x[a] { y[a] } else { y[a] + (y[b] - y[a]) * (x[i] - x[a]) / (x[b] - x[a]) });
    }
    out
}

/// Notch and waist of an outline (see the module documentation), both relative to the width.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Concavity {
    pub notch: f64,
    pub waist: f64,
}

/// The [`Concavity`] of a blob of an image `width` pixels wide; `(xc, yc)` is the centroid
/// and `theta` the angle of the long axis to +x (rad), pixels.
pub fn concavity(blob: &Blob, width: usize, xc: f64, yc: f64, theta: f64) -> Concavity {
    let (ct, st) = (theta.cos(), theta.sin());
    let uv: Vec<(f64, f64)> = blob
        .pixels
        .iter()
        .map(|&i| {
            let (dx, dy) = ((i as usize % width) as f64 - xc, (i as usize / width) as f64 - yc);
            (dx * ct + dy * st, -dx * st + dy * ct)
        })
        .collect();
    let Some(u0) = uv.iter().map(|p| p.0).min_by(f64::total_cmp) else { return Concavity::default() };
    let nb = uv.iter().map(|p| ((p.0 - u0) as usize) + 1).max().unwrap_or(0);
    let (mut top, mut bot) = (vec![f64::MIN; nb], vec![f64::MAX; nb]);
    for &(u, v) in &uv {
        let k = (u - u0) as usize;
        top[k] = top[k].max(v + 0.5);
        bot[k] = bot[k].min(v - 0.5);
    }
    // bins without a pixel centre (a rotated lattice can skip one) are left out
    let bins: Vec<usize> = (0..nb).filter(|&k| top[k] > f64::MIN).collect();
    if bins.len() < 3 {
        return Concavity::default();
    }
    let x: Vec<f64> = bins.iter().map(|&k| k as f64).collect();
    let t: Vec<f64> = bins.iter().map(|&k| top[k]).collect();
    let nb_neg: Vec<f64> = bins.iter().map(|&k| -bot[k]).collect();
    let (ht, hb) = (upper_envelope(&x, &t), upper_envelope(&x, &nb_neg));
    let dt: Vec<f64> = ht.iter().zip(&t).map(|(h, v)| h - v).collect();
    let db: Vec<f64> = hb.iter().zip(&nb_neg).map(|(h, v)| h - v).collect();
    let w = top.iter().copied().fold(f64::MIN, f64::max) - bot.iter().copied().fold(f64::MAX, f64::min);
    if !(w > 0.0) {
        return Concavity::default();
    }
    let k = 0.5 * w;
    let window_max = |d: &[f64], i: usize| -> f64 {
        (0..x.len()).filter(|&j| (x[j] - x[i]).abs() <= k).map(|j| d[j]).fold(0.0, f64::max)
    };
    let deepest = (0..x.len()).map(|i| window_max(&dt, i).min(window_max(&db, i))).fold(0.0, f64::max);
    let notch = dt.iter().chain(&db).copied().fold(0.0, f64::max);
    Concavity { notch: notch / w, waist: deepest / w }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blob(w: usize, h: usize, inside: impl Fn(f64, f64) -> bool) -> Blob {
        let mut pixels = Vec::new();
        for r in 0..h {
            for c in 0..w {
                if inside(c as f64, r as f64) {
                    pixels.push((r * w + c) as u32);
                }
            }
        }
        let cols: Vec<usize> = pixels.iter().map(|&i| i as usize % w).collect();
        let rows: Vec<usize> = pixels.iter().map(|&i| i as usize / w).collect();
        Blob {
            col_range: (*cols.iter().min().unwrap(), *cols.iter().max().unwrap()),
            row_range: (*rows.iter().min().unwrap(), *rows.iter().max().unwrap()),
            pixels,
            touches_border: false,
            outline: crate::experiment::segment::Outline::Threshold,
        }
    }

    fn centroid(b: &Blob, w: usize) -> (f64, f64) {
        let n = b.pixels.len() as f64;
        let sx: f64 = b.pixels.iter().map(|&i| (i as usize % w) as f64).sum();
        let sy: f64 = b.pixels.iter().map(|&i| (i as usize / w) as f64).sum();
        (sx / n, sy / n)
    }

    #[test]
    fn envelope_is_the_upper_hull() {
        let x = [0.0, 1.0, 2.0, 3.0, 4.0];
        let y = [0.0, 1.0, 0.0, 3.0, 0.0];
        // hull through (0,0), (3,3), (4,0): at x = 1, 2 the chord 0 -> 3 gives 1, 2
        assert_eq!(upper_envelope(&x, &y), vec![0.0, 1.0, 2.0, 3.0, 0.0]);
    }

    #[test]
    fn ellipse_has_no_waist_and_two_touching_disks_have_one() {
        let w = 80;
        // ellipse 30 x 12 px, tilted 20 deg: convex
        let (a, c) = (20f64.to_radians().cos(), 20f64.to_radians().sin());
        let e = blob(w, 60, |x, y| {
            let (dx, dy) = (x - 40.0, y - 30.0);
            let (u, v) = (dx * a + dy * c, -dx * c + dy * a);
            (u / 15.0).powi(2) + (v / 6.0).powi(2) <= 1.0
        });
        let (xc, yc) = centroid(&e, w);
        let ce = concavity(&e, w, xc, yc, 20f64.to_radians());
        // a tilted lattice makes the envelopes jitter by up to a pixel: < 1 px / 12 px
        assert!(ce.notch < 1.0 / 12.0 && ce.waist <= ce.notch, "ellipse: pixel quantisation only, {ce:?}");
        // two disks of radius 8 px whose centres are 15 px apart: the constriction between
        // them is 2 sqrt(8^2 - 7.5^2) = 5.6 px wide, notch depth (16 - 5.6) / 2 = 5.2 px
        // on each side, width 16 px: W = 0.33 (pixel quantisation: +-1/16)
        let d = blob(w, 60, |x, y| (x - 30.0).hypot(y - 30.0) <= 8.0 || (x - 45.0).hypot(y - 30.0) <= 8.0);
        let (xc, yc) = centroid(&d, w);
        let cd = concavity(&d, w, xc, yc, 0.0);
        assert!((cd.waist - 0.33).abs() < 0.07 && (cd.notch - 0.33).abs() < 0.07, "two disks: {cd:?}");
    }

    #[test]
    fn a_banana_bent_to_one_side_has_a_notch_but_no_waist() {
        // annulus sector about (40, 45): radii 14 and 22 px, +-60 deg about the upward
        // vertical. Along the long axis (x) the lower envelope runs from the inner corners at
        // row 45 - 14 cos 60 = 38 up to the inner arc's apex at row 45 - 14 = 31: a
        // notch 7 px deep below their chord; the upper envelope is the convex outer arc
        // (apex row 23). Width 38.5 - 22.5 = 16 px: notch 7/16 (+-1 px), waist ~0.
        let w = 80;
        let b = blob(w, 60, |x, y| {
            let (dx, dy) = (x - 40.0, y - 45.0);
            let r = dx.hypot(dy);
            (14.0..=22.0).contains(&r) && dy < 0.0 && dx.abs() <= 0.866 * r
        });
        let (xc, yc) = centroid(&b, w);
        let cb = concavity(&b, w, xc, yc, 0.0);
        assert!(cb.waist < 1.0 / 16.0, "banana: {cb:?}");
        assert!((cb.notch - 7.0 / 16.0).abs() < 1.0 / 16.0, "banana: {cb:?}");
    }
}
