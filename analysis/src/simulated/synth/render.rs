//! Rendering of synthetic bright-field frames: illumination, walls, dust, cells with rim and halo, motion blur, shot and read noise.

use super::shape::Polygon;
use super::spec::{OpticsSpec, SynthSpec};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Smoothed unit step `S(u) = (1 + erf(u / (sqrt 2 w))) / 2`.
#[inline]
fn step(u: f64, w: f64) -> f64 {
    0.5 * (1.0 + statrs::function::erf::erf(u / (std::f64::consts::SQRT_2 * w)))
}

#[inline]
fn gauss(u: f64, w: f64) -> f64 {
    (-0.5 * (u / w) * (u / w)).exp()
}

/// Relative contrast of a cell at signed distance `d` (um) from its outline (see [`OpticsSpec`]).
pub fn edge_profile(o: &OpticsSpec, d: f64) -> f64 {
    o.interior * step(-d, o.edge_um) + o.inner * step(-(d + o.inner_depth_um), 3.0 * o.edge_um) - o.rim * gauss(d + o.rim_offset_um, o.rim_width_um)
        + o.halo * gauss(d - o.halo_offset_um, o.halo_width_um)
}

/// Distance beyond the outline, um, where [`edge_profile`] is negligible.
pub fn profile_reach_um(o: &OpticsSpec) -> f64 {
    (o.halo_offset_um + 4.0 * o.halo_width_um).max(4.0 * o.edge_um).max(4.0 * o.rim_width_um - o.rim_offset_um)
}

/// Relative brightness of the walls and the PDMS beyond them at `e` um outside the wall
/// (`e = |y| - width/2`): a dark line on the wall, a bright line 0.9 um outside, `pdms` times the
/// channel's brightness beyond (0.85 by default: 15 % darker).
pub fn wall_factor(e: f64, pdms: f64) -> f64 {
    (1.0 - (1.0 - pdms) * step(e, 0.15)) * (1.0 - 0.35 * gauss(e, 0.25) + 0.2 * gauss(e - 0.9, 0.35))
}

/// Static part of every frame (illumination x walls x dust), intensity in [0, 1] of full scale.
pub fn static_background(spec: &SynthSpec, seed: u64) -> Vec<f64> {
    let (w, h) = (spec.width_px, spec.height_px);
    let il = &spec.illumination;
    let um = spec.um_per_px;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xD05D_05D0);
    let half = 0.5 * spec.channel.width_um;
    let dust: Vec<(f64, f64)> = (0..il.dust_spots)
        .map(|_| (rng.random::<f64>() * w as f64 * um, (rng.random::<f64>() * 2.0 - 1.0) * half * 0.9))
        .collect();
    let mut out = vec![0.0; w * h];
    for r in 0..h {
        let y = (r as f64 - spec.channel.axis_row_px) * um;
        let wall = wall_factor(y.abs() - half, il.wall_brightness);
        for c in 0..w {
            let (xn, yn) = (c as f64 / w as f64 - 0.5, r as f64 / h as f64 - 0.5);
            let illum = 1.0 + il.gradient_x * xn + il.gradient_y * yn - il.vignette * 2.0 * (xn * xn + yn * yn);
            let x = (c as f64 + 0.5) * um;
            let mut d = 1.0;
            for &(dx, dy) in &dust {
                d -= 0.12 * gauss(((x - dx).powi(2) + (y - dy).powi(2)).sqrt(), 0.4);
            }
            out[r * w + c] = il.level * illum * wall * d;
        }
    }
    out
}

/// One cell in one frame: its outline and the centroid positions (um, image frame) over the exposure.
pub struct CellInFrame<'a> {
    pub poly: &'a Polygon,
    /// Centroid x at each sub-exposure, um from the image's left edge.
    pub xs_um: Vec<f64>,
    /// Centroid row position in um from the top of the image's first pixel centre row (y from row 0).
    pub y_um: f64,
}

/// Add the relative contrast of `cell` into `contrast` (w x h).
pub fn add_cell(contrast: &mut [f64], w: usize, h: usize, um: f64, o: &OpticsSpec, cell: &CellInFrame) {
    let bb = cell.poly.bbox();
    let reach = profile_reach_um(o);
    let xmin = cell.xs_um.iter().copied().fold(f64::MAX, f64::min) + bb[0] - reach;
    let xmax = cell.xs_um.iter().copied().fold(f64::MIN, f64::max) + bb[1] + reach;
    let (ymin, ymax) = (cell.y_um + bb[2] - reach, cell.y_um + bb[3] + reach);
    // pixel (c, r) centre: x = (c + 0.5) um, y = r um (rows measured from row 0's centre)
    let c0 = ((xmin / um - 0.5).floor().max(0.0)) as usize;
    let c1 = ((xmax / um - 0.5).ceil().max(-1.0) + 1.0).min(w as f64) as usize;
    let r0 = ((ymin / um).floor().max(0.0)) as usize;
    let r1 = ((ymax / um).ceil().max(-1.0) + 1.0).min(h as f64) as usize;
    let inv = 1.0 / cell.xs_um.len() as f64;
    for r in r0..r1 {
        let y = r as f64 * um - cell.y_um;
        for c in c0..c1 {
            let xp = (c as f64 + 0.5) * um;
            let mut acc = 0.0;
            for &xc in &cell.xs_um {
                acc += edge_profile(o, cell.poly.signed_distance(xp - xc, y));
            }
            contrast[r * w + c] += acc * inv;
        }
    }
}

/// Add the relative contrast of a debris particle, a Gaussian spot of standard deviation
/// `radius_um` and peak `contrast`, at the centre positions `xs_um` (motion blur) and row position `y_um`.
pub fn add_debris(contrast: &mut [f64], w: usize, h: usize, um: f64, xs_um: &[f64], y_um: f64, radius_um: f64, peak: f64) {
    let reach = 4.0 * radius_um;
    let xmin = xs_um.iter().copied().fold(f64::MAX, f64::min) - reach;
    let xmax = xs_um.iter().copied().fold(f64::MIN, f64::max) + reach;
    let c0 = ((xmin / um - 0.5).floor().max(0.0)) as usize;
    let c1 = ((xmax / um - 0.5).ceil().max(-1.0) + 1.0).min(w as f64) as usize;
    let r0 = (((y_um - reach) / um).floor().max(0.0)) as usize;
    let r1 = (((y_um + reach) / um).ceil().max(-1.0) + 1.0).min(h as f64) as usize;
    let inv = 1.0 / xs_um.len() as f64;
    for r in r0..r1 {
        let dy = r as f64 * um - y_um;
        for c in c0..c1 {
            let xp = (c as f64 + 0.5) * um;
            let acc: f64 = xs_um.iter().map(|&xc| gauss(((xp - xc).powi(2) + dy * dy).sqrt(), radius_um)).sum();
            contrast[r * w + c] += peak * acc * inv;
        }
    }
}

