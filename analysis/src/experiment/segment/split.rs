//! Objects that the closing joined: two cells a pixel apart are split again along the bridge.
//!
//! The 3 x 3 closing of [`super::segment`] bridges one-pixel gaps so that a rim with a gap is
//! one object; it also bridges the gap between two cells whose rims come within a pixel of each
//! other (wave optics, neighbours 10 um apart: a croissant and a faster slipper 8 um apart along
//! the flow for three frames). Before the closing each of the two is an object of its own, and
//! each is as large as a cell; the pieces of one broken rim are arcs, each far smaller than a
//! cell. [`split_joined`] takes the pieces of a closed object that were apart before the closing
//! (8-connected) and, when at least two of them cover a cell's area each (holes filled) and
//! neither lies inside the other (below focus a dark halo ring around a dark interior is one
//! cell), gives every pixel of the object to the nearest of them (a breadth-first search inside the
//! object from all of them at once, 8-connected).

use super::{components_8, fill_holes};
use image::{GrayImage, Luma};
use std::collections::VecDeque;

/// The objects `group` (pixel indices `row * width + col` of a closed, hole-filled object) is
/// made of: itself, or one per piece of `raw` (the mask before the closing, non-zero = object)
/// covering at least `cell_px` pixels with its own holes filled, when there are two or more.
pub fn split_joined(group: Vec<u32>, raw: &GrayImage, cell_px: usize) -> Vec<Vec<u32>> {
    let w = raw.width() as usize;
    if group.len() < 2 * cell_px {
        return vec![group];
    }
    let (mut c0, mut c1, mut r0, mut r1) = (usize::MAX, 0, usize::MAX, 0);
    for &i in &group {
        let (r, c) = (i as usize / w, i as usize % w);
        (c0, c1, r0, r1) = (c0.min(c), c1.max(c), r0.min(r), r1.max(r));
    }
    // local grid: the bounding box and one pixel of outside around it
    let (lw, lh) = (c1 - c0 + 3, r1 - r0 + 3);
    let local = |i: u32| (i as usize / w - r0 + 1) * lw + (i as usize % w - c0 + 1);
    let mut in_group = vec![false; lw * lh];
    let mut pieces = GrayImage::new(lw as u32, lh as u32);
    let raw_px: &[u8] = raw.as_raw();
    for &i in &group {
        let k = local(i);
        in_group[k] = true;
        if raw_px[i as usize] != 0 {
            pieces.as_mut()[k] = 255;
        }
    }
    // pieces as large as a cell, holes filled, and not inside a larger one (a dark halo ring
    // around a dark interior is one cell below focus)
    let pieces = components_8(&pieces);
    if pieces.len() < 2 {
        return vec![group];
    }
    // (a piece whose bounding box is smaller than a cell cannot fill to one)
    let mut big: Vec<(Vec<u32>, GrayImage)> = pieces
        .into_iter()
        .filter(|p| bbox_area(p, lw) >= cell_px)
        .map(|p| (filled(&p, lw, lh), p))
        .filter(|(f, _)| area(f) >= cell_px)
        .map(|(f, p)| (p, f))
        .collect();
    big.sort_by_key(|(_, f)| std::cmp::Reverse(area(f)));
    let mut markers: Vec<Vec<u32>> = Vec::new();
    let mut covered = vec![false; lw * lh];
    for (p, f) in big {
        if covered[p[0] as usize] {
            continue;
        }
        for (k, &v) in f.as_raw().iter().enumerate() {
            covered[k] |= v != 0;
        }
        markers.push(p);
    }
    if markers.len() < 2 {
        return vec![group];
    }
    // nearest marker, by a breadth-first search inside the object
    let mut owner = vec![u32::MAX; lw * lh];
    let mut queue: VecDeque<usize> = VecDeque::new();
    for (m, p) in markers.iter().enumerate() {
        for &k in p {
            owner[k as usize] = m as u32;
            queue.push_back(k as usize);
        }
    }
    while let Some(k) = queue.pop_front() {
        let (r, c) = (k / lw, k % lw);
        for rr in r - 1..r + 2 {
            for cc in c - 1..c + 2 {
                let q = rr * lw + cc;
                if in_group[q] && owner[q] == u32::MAX {
                    owner[q] = owner[k];
                    queue.push_back(q);
                }
            }
        }
    }
    let mut out = vec![Vec::new(); markers.len()];
    for &i in &group {
        let m = owner[local(i)];
        if m != u32::MAX {
            out[m as usize].push(i);
        }
    }
    out
}

/// The piece `p` (local indices on an `lw x lh` grid) with its holes filled.
fn filled(p: &[u32], lw: usize, lh: usize) -> GrayImage {
    let mut m = GrayImage::new(lw as u32, lh as u32);
    for &k in p {
        m.put_pixel((k as usize % lw) as u32, (k as usize / lw) as u32, Luma([255]));
    }
    fill_holes(&mut m);
    m
}

/// Pixels of the bounding box of the piece `p` (local indices on a grid `lw` wide).
fn bbox_area(p: &[u32], lw: usize) -> usize {
    let (mut c0, mut c1, mut r0, mut r1) = (usize::MAX, 0, usize::MAX, 0);
    for &k in p {
        let (r, c) = (k as usize / lw, k as usize % lw);
        (c0, c1, r0, r1) = (c0.min(c), c1.max(c), r0.min(r), r1.max(r));
    }
    (c1 - c0 + 1) * (r1 - r0 + 1)
}

fn area(m: &GrayImage) -> usize {
    m.as_raw().iter().filter(|&&v| v != 0).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask(rows: &[&str]) -> GrayImage {
        GrayImage::from_fn(rows[0].len() as u32, rows.len() as u32, |x, y| Luma([if rows[y as usize].as_bytes()[x as usize] == b'#' { 255 } else { 0 }]))
    }

    fn pixels(m: &GrayImage) -> Vec<u32> {
        m.as_raw().iter().enumerate().filter(|(_, &v)| v != 0).map(|(i, _)| i as u32).collect()
    }

    #[test]
    fn two_cells_a_pixel_apart_are_split_and_a_broken_ring_is_not() {
        // two 4 x 4 "cells" one pixel apart, joined by the closing (the bridge column filled)
        let raw = mask(&["...........", ".####.####.", ".####.####.", ".####.####.", ".####.####.", "..........."]);
        let closed = mask(&["...........", ".#########.", ".#########.", ".#########.", ".#########.", "..........."]);
        let mut parts = split_joined(pixels(&closed), &raw, 12);
        parts.sort();
        assert_eq!(parts.len(), 2);
        assert_eq!(parts[0].len() + parts[1].len(), 36);
        assert!(parts.iter().all(|p| p.len() >= 16), "{:?}", parts.iter().map(|p| p.len()).collect::<Vec<_>>());
        // a ring broken into two arcs: each arc far smaller than a cell, one object
        let raw = mask(&["........", ".###.##.", ".#....#.", ".#....#.", ".##.###.", "........"]);
        let closed = mask(&["........", ".######.", ".######.", ".######.", ".######.", "........"]);
        assert_eq!(split_joined(pixels(&closed), &raw, 12).len(), 1);
        // a closed ring around an interior of its own, one pixel apart: one cell
        let raw = mask(&["..........", ".########.", ".#......#.", ".#.####.#.", ".#.####.#.", ".#.####.#.", ".#.####.#.", ".#......#.", ".########.", ".........."]);
        let closed = mask(&["..........", ".########.", ".########.", ".########.", ".########.", ".########.", ".########.", ".########.", ".########.", ".........."]);
        assert_eq!(split_joined(pixels(&closed), &raw, 12).len(), 1);
    }
}
