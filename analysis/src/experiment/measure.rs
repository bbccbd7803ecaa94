//! Measurement of one segmented object: centroid, area, length and width along its principal axes, shape descriptors.
//!
//! Moments are those of the binary mask with each pixel a unit square
//! centred on its integer coordinates (pixel `(col, row)` has centre
//! `(x, y) = (col, row)`): centroid = mean of the pixel centres (exact for
//! the union of squares), second central moments include the 1/12 of a unit
//! square. The principal axis is the eigenvector of the larger eigenvalue of
//! the second-moment matrix, orientation `theta = 1/2 atan2(2 mu11, mu20 - mu02)`
//! (e.g. Jain, Kasturi & Schunck, *Machine Vision*, 1995, sec. 2.2).
//! Length and width are the extents of the mask along and across that axis.
//!
//! [`measure_refined`] replaces the binary centroid and area by those of the
//! iso-contour `c = -t_low` of the smoothed contrast at sub-pixel resolution:
//! each pixel on either side of the mask's outline gets the fraction of its
//! square on the dark side of the contour, from a linear model of the contrast
//! in the pixel, `f = clamp(1/2 - (c - c_iso) / (|dc/dx| + |dc/dy|), 0, 1)`
//! (exact for a straight edge; the area-fraction idea of sub-pixel edge
//! estimation, cf. Trujillo-Pino et al., *Image Vision Comput.* 31, 2013).

use crate::experiment::segment::{Blob, Outline, Segmentation};
use crate::types::ShapeFeatures;
use imageproc::point::Point;

/// Measurement of one object in pixel units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// Centroid, pixels (`x` = column, `y` = row).
    pub x_px: f64,
    pub y_px: f64,
    /// Area, px^2.
    pub area_px: f64,
    /// Extent along / across the principal axis, px.
    pub length_px: f64,
    pub width_px: f64,
    pub features: ShapeFeatures,
}

/// Measure a blob of an image `width` pixels wide.
pub fn measure(blob: &Blob, width: usize) -> Measurement {
    let n = blob.pixels.len() as f64;
    let (mut sx, mut sy) = (0.0, 0.0);
    for &i in &blob.pixels {
        sx += (i as usize % width) as f64;
        sy += (i as usize / width) as f64;
    }
    let (xc, yc) = (sx / n, sy / n);
    let (mut m20, mut m02, mut m11, mut m03) = (0.0, 0.0, 0.0, 0.0);
    for &i in &blob.pixels {
        let dx = (i as usize % width) as f64 - xc;
        let dy = (i as usize / width) as f64 - yc;
        m20 += dx * dx;
        m02 += dy * dy;
        m11 += dx * dy;
        m03 += dy * dy * dy;
    }
    // per-pixel averages, with the unit square's own 1/12
    let (mu20, mu02, mu11) = (m20 / n + 1.0 / 12.0, m02 / n + 1.0 / 12.0, m11 / n);
    let theta = principal_angle(mu20, mu02, mu11);
    let (ct, st) = (theta.cos(), theta.sin());
    let (mut a0, mut a1, mut b0, mut b1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &i in &blob.pixels {
        let dx = (i as usize % width) as f64 - xc;
        let dy = (i as usize / width) as f64 - yc;
        let a = dx * ct + dy * st;
        let b = -dx * st + dy * ct;
        a0 = a0.min(a);
        a1 = a1.max(a);
        b0 = b0.min(b);
        b1 = b1.max(b);
    }
    // a unit square's extent along a direction (cos, sin) is |cos| + |sin|
    let pix = ct.abs() + st.abs();
    let skew_y = if m02 > 0.0 { (m03 / n) / (m02 / n).powf(1.5) } else { 0.0 };
    let conc = crate::experiment::concavity::concavity(blob, width, xc, yc, theta);
    let features = ShapeFeatures {
        mirror_asymmetry: mirror_asymmetry(blob, width, yc),
        skew_y,
        orientation_rad: theta,
        solidity: n / hull_area(blob, width),
        notch: conc.notch,
        waist: conc.waist,
    };
    Measurement { x_px: xc, y_px: yc, area_px: n, length_px: a1 - a0 + pix, width_px: b1 - b0 + pix, features }
}

/// Like [`measure`], with the centroid and area of the sub-pixel outline: the iso-contour of the
/// segmentation's contrast for a thresholded rim, the darkest ring's ridge for a peeled halo
/// ([`Outline`], [`ridge_weights`]).
pub fn measure_refined(blob: &Blob, seg: &Segmentation) -> Measurement {
    let mut m = measure(blob, seg.width);
    if let Outline::DarkestRing { sign } = blob.outline {
        let (sw, sx, sy) = ridge_weights(blob, seg, sign);
        if sw > 0.0 {
            (m.x_px, m.y_px, m.area_px) = (sx / sw, sy / sw, sw);
        }
        return m;
    }
    refine_iso(m, blob, seg)
}

/// A blob's pixels as a mask over its bounding box grown by one pixel (clipped to the frame):
/// the outline and the pixels just outside it, which the sub-pixel refinements weigh.
struct PaddedMask {
    rows: (usize, usize),
    cols: (usize, usize),
    bits: Vec<bool>,
}

impl PaddedMask {
    fn new(blob: &Blob, w: usize, h: usize) -> Self {
        let cols = (blob.col_range.0.saturating_sub(1), (blob.col_range.1 + 1).min(w - 1));
        let rows = (blob.row_range.0.saturating_sub(1), (blob.row_range.1 + 1).min(h - 1));
        let bw = cols.1 - cols.0 + 1;
        let mut bits = vec![false; bw * (rows.1 - rows.0 + 1)];
        for &i in &blob.pixels {
            let (r, c) = (i as usize / w, i as usize % w);
            bits[(r - rows.0) * bw + (c - cols.0)] = true;
        }
        Self { rows, cols, bits }
    }

    /// Whether pixel (`r`, `c`) belongs to the blob (false outside the box, also for negative indices).
    fn inside(&self, r: i64, c: i64) -> bool {
        let ((r0, r1), (c0, c1)) = (self.rows, self.cols);
        r >= r0 as i64 && r <= r1 as i64 && c >= c0 as i64 && c <= c1 as i64 && self.bits[(r as usize - r0) * (c1 - c0 + 1) + (c as usize - c0)]
    }
}

fn refine_iso(mut m: Measurement, blob: &Blob, seg: &Segmentation) -> Measurement {
    let (w, h) = (seg.width, seg.height);
    let mask = PaddedMask::new(blob, w, h);
    let ((r0, r1), (c0, c1)) = (mask.rows, mask.cols);
    let inside = |r: usize, c: usize| mask.inside(r as i64, c as i64);
    let iso = -seg.t_low as f64;
    let ct = |r: usize, c: usize| seg.contrast[r * w + c] as f64;
    let (mut sw, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for r in r0..=r1 {
        for c in c0..=c1 {
            let me = inside(r, c);
            let n4 = [(r > 0).then(|| inside(r - 1, c)), (r + 1 < h).then(|| inside(r + 1, c)), (c > 0).then(|| inside(r, c - 1)), (c + 1 < w).then(|| inside(r, c + 1))];
            let edge = n4.iter().any(|n| n.is_some_and(|v| v != me));
            let wgt = if !edge {
                if me { 1.0 } else { 0.0 }
            } else {
                let gx = if c > 0 && c + 1 < w { 0.5 * (ct(r, c + 1) - ct(r, c - 1)) } else { 0.0 };
                let gy = if r > 0 && r + 1 < h { 0.5 * (ct(r + 1, c) - ct(r - 1, c)) } else { 0.0 };
                let g = gx.abs() + gy.abs();
                if g > 1e-6 {
                    let f = (0.5 - (ct(r, c) - iso) / g).clamp(0.0, 1.0);
                    // the pixel's side of the mask decides which half its fraction may take
                    if me { f.max(0.5) } else { f.min(0.5) }
                } else if me {
                    1.0
                } else {
                    0.0
                }
            };
            sw += wgt;
            sx += wgt * c as f64;
            sy += wgt * r as f64;
        }
    }
    if sw > 0.0 {
        m.x_px = sx / sw;
        m.y_px = sy / sw;
        m.area_px = sw;
    }
    m
}

/// Weight sums `(sum w, sum w col, sum w row)` of a peeled halo's cell whose outline is the ridge
/// of the darkness `sign * contrast` (the halo's darkest ring), at sub-pixel precision.
///
/// The peel ([`crate::experiment::segment::peel`]) gives the darkest ring's pixels to the flank,
/// so the mask's outline lies half a pixel inside the ring's pixel centres on average, and by
/// anything from 0 to 1 px where it is: a whole-pixel outline whose phase against the pixel grid
/// differs from one side of a cell to the other (wave optics at -2 um: 0.06-0.18 um inside the
/// truth, top and bottom of one cell up to 0.03 um apart, i.e. up to 0.025 um of y). Every
/// pixel of the mask counts 1; every ring pixel (outside, 4-adjacent to the mask) counts the
/// share of its square inside the ridge: along the mask's inward normal `n` there (the mean
/// direction to its mask neighbours), a parabola through the darkness at `p + n`, `p` and `p - n`
/// (bilinear) puts the ridge at `t = (a - c) / (2 (a - 2b + c))` px outwards, and the share is
/// `clamp(1/2 + t, 0, 1)`; where the darkness has no maximum across the ring, one half.
pub fn ridge_weights(blob: &Blob, seg: &Segmentation, sign: f32) -> (f64, f64, f64) {
    let (w, h) = (seg.width, seg.height);
    let mask = PaddedMask::new(blob, w, h);
    let ((r0, r1), (c0, c1)) = (mask.rows, mask.cols);
    let (mut sw, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for &i in &blob.pixels {
        let (r, c) = (i as usize / w, i as usize % w);
        sw += 1.0;
        sx += c as f64;
        sy += r as f64;
    }
    let inside = |r: i64, c: i64| mask.inside(r, c);
    let dark = |x: f64, y: f64| -> f64 {
        let (x, y) = (x.clamp(0.0, (w - 1) as f64), y.clamp(0.0, (h - 1) as f64));
        let (xi, yi) = ((x.floor() as usize).min(w.saturating_sub(2)), (y.floor() as usize).min(h.saturating_sub(2)));
        let (fx, fy) = (x - xi as f64, y - yi as f64);
        let at = |r: usize, c: usize| sign as f64 * seg.contrast[r.min(h - 1) * w + c.min(w - 1)] as f64;
        (1.0 - fy) * ((1.0 - fx) * at(yi, xi) + fx * at(yi, xi + 1)) + fy * ((1.0 - fx) * at(yi + 1, xi) + fx * at(yi + 1, xi + 1))
    };
    for r in r0..=r1 {
        for c in c0..=c1 {
            let (ri, ci) = (r as i64, c as i64);
            if inside(ri, ci) || !(inside(ri - 1, ci) || inside(ri + 1, ci) || inside(ri, ci - 1) || inside(ri, ci + 1)) {
                continue;
            }
            let (mut nx, mut ny) = (0.0f64, 0.0f64);
            for dr in -1..=1i64 {
                for dc in -1..=1i64 {
                    if inside(ri + dr, ci + dc) {
                        nx += dc as f64;
                        ny += dr as f64;
                    }
                }
            }
            let norm = nx.hypot(ny);
            let share = if norm < 1e-9 {
                0.5
            } else {
                let (nx, ny) = (nx / norm, ny / norm);
                let (x, y) = (c as f64, r as f64);
                let (a, b, cc) = (dark(x + nx, y + ny), dark(x, y), dark(x - nx, y - ny));
                let k = a - 2.0 * b + cc;
                if k < 0.0 {
                    (0.5 + (a - cc) / (2.0 * k)).clamp(0.0, 1.0)
                } else {
                    0.5
                }
            };
            sw += share;
            sx += share * c as f64;
            sy += share * r as f64;
        }
    }
    (sw, sx, sy)
}

/// Principal-axis angle from +x, radians in (-pi/2, pi/2], of central moments `mu20`, `mu02`, `mu11`.
pub fn principal_angle(mu20: f64, mu02: f64, mu11: f64) -> f64 {
    let t = 0.5 * (2.0 * mu11).atan2(mu20 - mu02);
    if t <= -std::f64::consts::FRAC_PI_2 {
        t + std::f64::consts::PI
    } else {
        t
    }
}

/// `1 - IoU(M, M')` where `M'` is the mask mirrored about the horizontal line
/// `y = yc` through its centroid; the mirrored mask is sampled with linear
/// interpolation between rows so that a fractional `yc` does not create asymmetry.
pub fn mirror_asymmetry(blob: &Blob, width: usize, yc: f64) -> f64 {
    let (c0, c1) = blob.col_range;
    let (r0, r1) = blob.row_range;
    let bw = c1 - c0 + 1;
    let bh = r1 - r0 + 1;
    let mut bits = vec![false; bw * bh];
    for &i in &blob.pixels {
        let (r, c) = (i as usize / width, i as usize % width);
        bits[(r - r0) * bw + (c - c0)] = true;
    }
    let at = |r: i64, c: usize| -> f64 {
        if r < r0 as i64 || r > r1 as i64 {
            0.0
        } else if bits[(r as usize - r0) * bw + c] {
            1.0
        } else {
            0.0
        }
    };
    let mut inter = 0.0;
    for &i in &blob.pixels {
        let (r, c) = (i as usize / width, i as usize % width);
        let m = 2.0 * yc - r as f64; // mirrored row, fractional
        let lo = m.floor();
        let f = m - lo;
        inter += (1.0 - f) * at(lo as i64, c - c0) + f * at(lo as i64 + 1, c - c0);
    }
    let n = blob.pixels.len() as f64;
    let union = 2.0 * n - inter;
    if union > 0.0 {
        (1.0 - inter / union).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Area, px^2, of the convex hull of the mask's pixel squares.
fn hull_area(blob: &Blob, width: usize) -> f64 {
    let (r0, r1) = blob.row_range;
    let nr = r1 - r0 + 1;
    let mut lo = vec![i32::MAX; nr];
    let mut hi = vec![i32::MIN; nr];
    for &i in &blob.pixels {
        let (r, c) = (i as usize / width, (i as usize % width) as i32);
        lo[r - r0] = lo[r - r0].min(c);
        hi[r - r0] = hi[r - r0].max(c);
    }
    // corners of the leftmost and rightmost square of each row span the hull
    let mut pts = Vec::with_capacity(4 * nr);
    for k in 0..nr {
        if lo[k] > hi[k] {
            continue;
        }
        let r = (r0 + k) as i32;
        pts.extend_from_slice(&[Point::new(lo[k], r), Point::new(lo[k], r + 1), Point::new(hi[k] + 1, r), Point::new(hi[k] + 1, r + 1)]);
    }
    let hull = imageproc::geometry::convex_hull(pts);
    let mut a = 0.0;
    for k in 0..hull.len() {
        let (p, q) = (hull[k], hull[(k + 1) % hull.len()]);
        a += p.x as f64 * q.y as f64 - q.x as f64 * p.y as f64;
    }
    (0.5 * a.abs()).max(blob.pixels.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blob_from(rows: &[&str]) -> (Blob, usize) {
        let w = rows[0].len();
        let mut pixels = Vec::new();
        for (r, s) in rows.iter().enumerate() {
            for (c, ch) in s.bytes().enumerate() {
                if ch == b'#' {
                    pixels.push((r * w + c) as u32);
                }
            }
        }
        let cols: Vec<usize> = pixels.iter().map(|&i| i as usize % w).collect();
        let rs: Vec<usize> = pixels.iter().map(|&i| i as usize / w).collect();
        let b = Blob {
            pixels,
            col_range: (*cols.iter().min().unwrap(), *cols.iter().max().unwrap()),
            row_range: (*rs.iter().min().unwrap(), *rs.iter().max().unwrap()),
            touches_border: false,
            outline: Outline::Threshold,
        };
        (b, w)
    }

    #[test]
    fn rectangle_is_exact() {
        // 6 x 2 rectangle of pixels: centroid, area, extents, symmetric, convex
        let (b, w) = blob_from(&["..........", "..######..", "..######..", ".........."]);
        let m = measure(&b, w);
        assert_eq!((m.x_px, m.y_px, m.area_px), (4.5, 1.5, 12.0));
        assert!((m.length_px - 6.0).abs() < 1e-12 && (m.width_px - 2.0).abs() < 1e-12);
        assert!(m.features.orientation_rad.abs() < 1e-12);
        assert!(m.features.mirror_asymmetry < 1e-12);
        assert!((m.features.solidity - 1.0).abs() < 1e-12);
    }

    /// The outline of a box 24 x 14 px with corners rounded to 4 px, centred at (30, 20.3): signed
    /// distance, px (negative inside).
    fn rounded_box(c: f64, r: f64) -> f64 {
        let (qx, qy) = ((c - 30.0).abs() - 8.0, (r - 20.3).abs() - 3.0);
        qx.max(0.0).hypot(qy.max(0.0)) + qx.max(qy).min(0.0) - 4.0
    }

    /// A dark ring (the halo of a cell below focus) along [`rounded_box`] on a 60 x 40 frame, as
    /// the polarity-signed contrast `sign * darkness`, and the cell inside it peeled from a region
    /// 3.5 px around it ([`crate::experiment::segment::peel`]).
    fn peeled_ring_box(sign: f32) -> (Blob, Segmentation) {
        let (w, h) = (60usize, 40usize);
        let mut contrast = vec![0f32; w * h];
        let mut region = Vec::new();
        for r in 0..h {
            for c in 0..w {
                let d = rounded_box(c as f64, r as f64);
                contrast[r * w + c] = sign * (0.3 * (-d * d / (2.0 * 1.2 * 1.2)).exp()) as f32;
                if d < 3.5 {
                    region.push((r * w + c) as u32);
                }
            }
        }
        let cells = crate::experiment::segment::peel::peel_to_darkest_ring(&region, &contrast, sign, w);
        assert_eq!(cells.len(), 1);
        let pixels = cells.into_iter().next().unwrap();
        let (rows, cols): (Vec<usize>, Vec<usize>) = pixels.iter().map(|&i| (i as usize / w, i as usize % w)).unzip();
        let blob = Blob {
            col_range: (*cols.iter().min().unwrap(), *cols.iter().max().unwrap()),
            row_range: (*rows.iter().min().unwrap(), *rows.iter().max().unwrap()),
            pixels,
            touches_border: false,
            outline: Outline::DarkestRing { sign },
        };
        let seg = Segmentation { width: w, height: h, blobs: Vec::new(), contrast, noise_sigma: 0.005, t_low: 0.04, t_high: 0.08, gain: 1.0, polarity: 1.0 };
        (blob, seg)
    }

    #[test]
    fn a_peeled_outline_is_read_on_the_ridge_to_sub_pixel_precision() {
        // the box's area with its rounded corners
        let area = 24.0 * 14.0 - (4.0 - std::f64::consts::PI) * 16.0;
        for sign in [1.0, -1.0] {
            let (blob, seg) = peeled_ring_box(sign);
            // the whole-pixel mask: the ring's pixels went with the flank, row 13 at the top (the
            // ridge at 13.3, the mask's edge 0.2 px inside it) and rows 28 and 27 at the bottom
            // (the ridge at 27.3, the edge 0.8 px inside): its centroid is high
            let binary = measure(&blob, seg.width);
            assert!(binary.y_px - 20.3 < -0.1, "binary centroid {}", binary.y_px);
            // on the ridge: the box itself, to 0.05 px (measured 0.047 px high: a fifth of the
            // whole-pixel mask's 0.26 px, whose area is 285 px^2 of 322)
            let m = measure_refined(&blob, &seg);
            assert!((m.y_px - 20.3).abs() < 0.05 && (m.x_px - 30.0).abs() < 0.01, "centroid ({}, {})", m.x_px, m.y_px);
            assert!((m.area_px - area).abs() < 0.02 * area, "area {} against {area}", m.area_px);
        }
    }

    #[test]
    fn asymmetric_shape_scores_asymmetric() {
        // an L shape: not mirror-symmetric about its horizontal centre line, not convex
        let (b, w) = blob_from(&["......", ".#....", ".#....", ".#....", ".####.", "......"]);
        let m = measure(&b, w);
        assert!(m.features.mirror_asymmetry > 0.3, "{:?}", m.features);
        assert!(m.features.solidity < 0.8);
        assert!(m.features.skew_y < 0.0, "mass concentrated at the bottom row: negative skew");
    }
}
