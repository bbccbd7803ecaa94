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

use crate::experiment::segment::{Blob, Segmentation};
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

/// Like [`measure`], with the centroid and area of the sub-pixel iso-contour of the segmentation's contrast.
pub fn measure_refined(blob: &Blob, seg: &Segmentation) -> Measurement {
    let mut m = measure(blob, seg.width);
    let (w, h) = (seg.width, seg.height);
    let (c0, c1) = (blob.col_range.0.saturating_sub(1), (blob.col_range.1 + 1).min(w - 1));
    let (r0, r1) = (blob.row_range.0.saturating_sub(1), (blob.row_range.1 + 1).min(h - 1));
    let bw = c1 - c0 + 1;
    let mut bits = vec![false; bw * (r1 - r0 + 1)];
    for &i in &blob.pixels {
        let (r, c) = (i as usize / w, i as usize % w);
        bits[(r - r0) * bw + (c - c0)] = true;
    }
    let inside = |r: usize, c: usize| -> bool { r >= r0 && r <= r1 && c >= c0 && c <= c1 && bits[(r - r0) * bw + (c - c0)] };
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
