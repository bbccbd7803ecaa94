//! Peeling an object's outer flank back to its darkest ring: an ascent in darkness from the outside, pixel by pixel.
//!
//! From the outside inwards, a pixel of the object joins the flank when it is at least as dark
//! as a flank (or outside) pixel next to it: the ascent stops at the darkest ring wherever that
//! lies, with no width to choose. The ring's own pixels go with the flank. What is left, holes
//! filled, is returned as its 8-connected components. Used for a dark halo around a cell below
//! focus, read from the rim's side ([`super::halo`], an open bright rim) and from the halo's
//! own ([`super::ring`], a dark-voted recording whose outline is the halo's).

use super::{components_8, fill_holes};
use image::{GrayImage, Luma};

/// The components (global pixel lists, sorted, linear indices `row * width + col` of an image
/// `w` wide) left of `group` when its outer flank is peeled to the darkest ring of
/// `darkness = sign * contrast` (`sign` = 1 where the halo is positive in `contrast`, -1 where
/// it is negative).
pub fn peel_to_darkest_ring(group: &[u32], contrast: &[f32], sign: f32, w: usize) -> Vec<Vec<u32>> {
    if group.is_empty() {
        return Vec::new();
    }
    // local grid: the group's bounding box and one pixel of outside around it
    let (mut c0, mut c1, mut r0, mut r1) = (usize::MAX, 0, usize::MAX, 0);
    for &i in group {
        let (r, c) = (i as usize / w, i as usize % w);
        (c0, c1, r0, r1) = (c0.min(c), c1.max(c), r0.min(r), r1.max(r));
    }
    let (lw, lh) = (c1 - c0 + 3, r1 - r0 + 3);
    let local = |i: u32| (i as usize / w - r0 + 1) * lw + (i as usize % w - c0 + 1);
    let global = |k: usize| ((k / lw + r0 - 1) * w + (k % lw + c0 - 1)) as u32;
    let mut c = vec![0f32; lw * lh];
    // 0 outside the group, 1 in it, 2 peeled (the outer flank)
    let mut state = vec![0u8; lw * lh];
    for &i in group {
        c[local(i)] = sign * contrast[i as usize];
        state[local(i)] = 1;
    }
    let mut stack: Vec<usize> = (0..lw * lh).filter(|&k| state[k] == 0).collect();
    while let Some(k) = stack.pop() {
        let (r, col) = (k / lw, k % lw);
        for rr in r.saturating_sub(1)..(r + 2).min(lh) {
            for cc in col.saturating_sub(1)..(col + 2).min(lw) {
                let q = rr * lw + cc;
                if state[q] == 1 && (state[k] == 0 || c[q] >= c[k]) {
                    state[q] = 2;
                    stack.push(q);
                }
            }
        }
    }
    let mut keep = GrayImage::from_fn(lw as u32, lh as u32, |x, y| Luma([if state[y as usize * lw + x as usize] == 1 { 255u8 } else { 0 }]));
    fill_holes(&mut keep);
    components_8(&keep)
        .into_iter()
        .map(|g| {
            let mut px: Vec<u32> = g.into_iter().map(|k| global(k as usize)).collect();
            px.sort_unstable();
            px
        })
        .collect()
}
