//! Cells whose bright rim is open, closed by the dark halo around them (below focus in wave optics).
//!
//! Below focus a red cell shows a bright rim inside a dark halo, and its interior is darkened by
//! haemoglobin's absorption. The absorption works against the rim: where the rim's phase signal
//! is weak (the concave side of a croissant, the flat sides of an irregular cell, the lower edge
//! of a slipper) the dark interior runs into the dark halo and the rim is an open arc, so
//! segmenting the rim and filling its holes gives the arc, not the cell (wave optics at -2 um:
//! 4-9 um^2 of a 28-30 um^2 cell). The halo stays closed all around (`simulated::wave`). Above
//! focus the two add (a dark rim around a dark interior) and the rim closes; this is only needed
//! when the polarity vote says bright ([`super::polarity`]).
//!
//! Where is the outline? Not at the zero crossing between halo and rim: in the wave-optics
//! images at -2 um that lies 0.4-0.5 um inside the cell (the absorbing interior lifts the rim's
//! inner side), and the area read there is 10 um^2 short. The truth outline lies near the halo's
//! darkest ring (the mean contrast against the distance from the outside peaks 0.85-1.0 um in,
//! the truth area's outline is 0.85-1.05 um in), as it does at -1 um where the dark halo is
//! segmented as the cell (analysis/README.md). [`cells_inside_halo`], per frame:
//! 1. the halo-signed pixels (`c > t_low` in the polarity-signed contrast, where the rim is
//!    negative) are closed (3 x 3) and their holes filled: each component is a cell with its
//!    halo (or touching cells with theirs);
//! 2. the halo's outer flank is peeled off ([`super::peel`]): from the outside inwards, a pixel
//!    joins the flank when it is at least as dark as a flank pixel next to it (an ascent, so it
//!    stops at the halo's darkest ring wherever that lies, pixel by pixel, with no width to
//!    choose). The ring's own pixels go with the flank: the outline is then about 0.15 um
//!    inside the truth's (area 3 um^2 short at -2 um, seeds 1-3) and the median y error
//!    0.009 um; keeping them put it 0.1 um outside and the y error at 0.014 um (the ring is two
//!    pixels wide in places);
//! 3. what is left, holes filled, in components holding a rim seed (`c < -t_high`) of at least
//!    `min_px` pixels, are the cells.

use super::peel::peel_to_darkest_ring;
use super::{close_3x3, components_8, fill_holes, Segmentation};
use image::{GrayImage, Luma};
use std::ops::Range;

/// Cells found inside the closed halos of a frame: pixel lists (linear indices `row * width + col`).
///
/// `seg` holds the smoothed, polarity-signed contrast of [`super::segment`] (the rim negative)
/// and its thresholds; `rows` are the searched rows; objects smaller than `min_px` pixels are
/// dropped.
pub fn cells_inside_halo(seg: &Segmentation, rows: Range<usize>, min_px: usize) -> Vec<Vec<u32>> {
    let (w, h, contrast, t_low, t_high) = (seg.width, seg.height, &seg.contrast[..], seg.t_low, seg.t_high);
    let mut halo = GrayImage::from_fn(w as u32, h as u32, |x, y| {
        let (r, i) = (y as usize, y as usize * w + x as usize);
        Luma([if rows.contains(&r) && contrast[i] > t_low { 255u8 } else { 0 }])
    });
    close_3x3(&mut halo);
    for r in (0..rows.start).chain(rows.end..h) {
        for x in 0..w {
            halo.put_pixel(x as u32, r as u32, Luma([0]));
        }
    }
    fill_holes(&mut halo);
    let mut cells = Vec::new();
    for group in components_8(&halo) {
        if group.len() < min_px || !group.iter().any(|&i| contrast[i as usize] < -t_high) {
            continue;
        }
        cells.extend(peel(&group, contrast, w, t_high, min_px));
    }
    cells
}

/// Share of a cell that its rim's own objects must cover for the rim to count as closed: an open
/// rim with its holes left unfilled covers a band of the cell (0.15-0.3 of it in wave optics at
/// -2 um), a closed one all of it.
pub const CLOSED_RIM_COVER: f64 = 0.5;

/// Below focus (bright rim): replace the objects `groups` (pixel lists) of an open rim by the
/// cell inside its halo ([`cells_inside_halo`]) where they cover less than [`CLOSED_RIM_COVER`]
/// of it. The cells are appended after the objects kept; returns how many.
pub fn close_open_rims(groups: &mut Vec<Vec<u32>>, seg: &Segmentation, rows: Range<usize>, min_px: usize) -> usize {
    let cells = cells_inside_halo(seg, rows, min_px);
    if cells.is_empty() {
        return 0;
    }
    let mut label = vec![u32::MAX; seg.width * seg.height];
    for (k, g) in groups.iter().enumerate() {
        for &i in g {
            label[i as usize] = k as u32;
        }
    }
    let mut dropped = vec![false; groups.len()];
    let mut added = Vec::new();
    for cell in cells {
        let mut inside: Vec<u32> = cell.iter().map(|&i| label[i as usize]).filter(|&l| l != u32::MAX).collect();
        inside.sort_unstable();
        inside.dedup();
        let covered: usize = inside.iter().map(|&l| groups[l as usize].len()).sum();
        if (covered as f64) < CLOSED_RIM_COVER * cell.len() as f64 {
            for &l in &inside {
                dropped[l as usize] = true;
            }
            added.push(cell);
        }
    }
    let mut k = 0;
    groups.retain(|_| {
        k += 1;
        !dropped[k - 1]
    });
    let n = added.len();
    groups.extend(added);
    n
}

/// The cells of one halo component `group` (steps 2-3 of the module's doc), in global indices.
fn peel(group: &[u32], contrast: &[f32], w: usize, t_high: f32, min_px: usize) -> Vec<Vec<u32>> {
    peel_to_darkest_ring(group, contrast, 1.0, w)
        .into_iter()
        .filter(|g| g.len() >= min_px && g.iter().any(|&i| contrast[i as usize] < -t_high))
        .collect()
}

#[cfg(test)]
mod tests {
    use crate::experiment::segment::{segment, segment_rims, SegmentParams};
    use crate::types::Frame;

    /// A 60 x 40 px frame of background 0.5 with a disc of radius 8 px at (30, 20) as the wave
    /// renderer draws it 2 um below focus: a dark halo (-0.3) all around, darkest on the outline,
    /// a bright rim (+0.4) 3 px inside only on the left of the disc (|angle from -x| < 100 deg),
    /// the interior darkened by absorption (-0.12).
    fn open_rim_disc() -> (Frame, Frame) {
        let (w, h) = (60usize, 40usize);
        let bg = Frame { width: w, height: h, data: vec![0.5; w * h] };
        let mut f = bg.clone();
        for r in 0..h {
            for c in 0..w {
                let (dx, dy) = (c as f32 - 30.0, r as f32 - 20.0);
                let d = (dx * dx + dy * dy).sqrt() - 8.0;
                let rim = if dy.atan2(-dx).abs() < 100f32.to_radians() { 0.4 } else { 0.0 };
                let inside = 1.0 / (1.0 + (2.0 * d).exp());
                let v = rim * (-(d + 3.0).powi(2) / 2.0).exp() - 0.3 * (-d.powi(2) / 2.0).exp() - 0.12 * inside;
                f.data[r * w + c] = 0.5 * (1.0 + v);
            }
        }
        (f, bg)
    }

    #[test]
    fn an_open_bright_rim_is_closed_by_its_halo() {
        let (f, bg) = open_rim_disc();
        let params = SegmentParams { polarity: -1.0, ..SegmentParams::default() };
        let s = segment(&f, &bg, 0..40, 0.2, &params);
        assert_eq!(s.blobs.len(), 1);
        // the disc inside its darkest ring, the ring peeled: pi 7.5^2 = 177 px (165 measured)
        let area = s.blobs[0].pixels.len() as f64;
        assert!(area > 150.0 && area < 210.0, "{area}");
        let n = s.blobs[0].pixels.len() as f64;
        let xc = s.blobs[0].pixels.iter().map(|&i| (i % 60) as f64).sum::<f64>() / n;
        let yc = s.blobs[0].pixels.iter().map(|&i| (i / 60) as f64).sum::<f64>() / n;
        assert!((xc - 30.0).abs() < 0.5 && (yc - 20.0).abs() < 0.1, "centroid ({xc}, {yc})");
        // without the halo's closing the open rim is only its arc
        let arcs: usize = segment_rims(&f, &bg, 0..40, 0.2, &params).blobs.iter().map(|b| b.pixels.len()).sum();
        let arcs = arcs as f64;
        assert!(arcs < 0.5 * area, "arc {arcs} px");
    }
}
