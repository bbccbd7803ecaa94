//! Random but plausible synthetic recordings for accuracy studies (seeded).

use super::shape::CellShape;
use super::spec::{CellSpec, ChannelSpec, FrameFormat, IlluminationSpec, NoiseSpec, OpticsSpec, SynthSpec};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Frame rate of the paper's camera, frames per second.
pub const FPS: f64 = 400.0;

/// A random cell of kind `shape` near `x_um` (plus 0-3 um), at `velocity_mm_s` +- 3 %: size, tilt, bend,
/// asymmetry and offset drawn from the ranges of the paper's croissants and slippers (croissants
/// within 0.5 um of the axis, slippers 1-2.5 um off it, tilted 5-20 deg towards the axis), kept 0.5 um
/// from the 11.9 um channel's walls.
pub fn random_cell(rng: &mut ChaCha8Rng, shape: CellShape, x_um: f64, velocity_mm_s: f64) -> CellSpec {
    let half = 0.5 * 11.9;
    let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
    let (length_um, width_um, orientation_deg, deform, y_um): (f64, f64, f64, f64, f64) = match shape {
        CellShape::Croissant => (rng.random_range(5.5..7.0), rng.random_range(6.0..7.5), 0.0, rng.random_range(0.25..0.45), rng.random_range(-0.5..0.5)),
        CellShape::Slipper => (rng.random_range(7.0..8.5), rng.random_range(3.5..4.5), sign * rng.random_range(5.0..20.0), rng.random_range(0.05..0.2), -sign * rng.random_range(1.0..2.5)),
        CellShape::Other => (rng.random_range(6.0..7.5), rng.random_range(5.0..6.5), rng.random_range(-90.0..90.0), 0.15, rng.random_range(-1.5..1.5)),
    };
    // keep the cell inside the channel: |y| + half extent across (tilted box) 0.5 um from the wall
    let th = orientation_deg.to_radians();
    let reach = 0.5 * (length_um * th.sin().abs() + width_um * th.cos().abs());
    let y_um = if shape == CellShape::Croissant { y_um } else { y_um.clamp(-(half - 0.5 - reach).max(0.0), (half - 0.5 - reach).max(0.0)) };
    CellSpec {
        shape,
        x0_um: x_um + rng.random_range(0.0..3.0),
        y_um,
        velocity_mm_s: velocity_mm_s * rng.random_range(0.97..1.03),
        length_um,
        width_um,
        orientation_deg,
        deform,
        flip: rng.random::<bool>(),
        asymmetry: rng.random_range(0.15..0.4),
        seed: rng.random(),
    }
}

/// A random recording of two cells (random shapes, sizes, tilts, offsets, ~50 um
/// apart) flowing at `velocity_mm_s` through a 11.9 um channel imaged at
/// `um_per_px`, with read noise `noise_sigma` (fraction of full scale) and shot
/// noise, at 400 fps. The field is long enough for every cell to be seen whole
/// in several frames, and the recording long enough for the cells to move at
/// least 30 um (so the temporal-median background is clean), 6 to 120 frames.
pub fn random_spec(seed: u64, um_per_px: f64, noise_sigma: f64, velocity_mm_s: f64) -> SynthSpec {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let disp = velocity_mm_s.abs() * 1000.0 / FPS; // um per frame
    let n_frames = ((30.0 / disp.max(1e-9)).ceil() as usize).clamp(6, 120);
    let field_um = 75.0 + 3.0 * disp;
    let width_px = (field_um / um_per_px).ceil() as usize;
    let height_px = (22.0 / um_per_px).ceil() as usize;
    let axis_row_px = 0.5 * (height_px as f64 - 1.0) + rng.random_range(-2.0..2.0);
    let x_first = rng.random_range(10.0..14.0);
    let cells = (0..2)
        .map(|i| {
            let shape = match rng.random_range(0..3) {
                0 => CellShape::Croissant,
                1 => CellShape::Slipper,
                _ => CellShape::Other,
            };
            random_cell(&mut rng, shape, x_first + 50.0 * i as f64, velocity_mm_s)
        })
        .collect();
    SynthSpec {
        width_px,
        height_px,
        um_per_px,
        fps: FPS,
        n_frames,
        pressure_mbar: velocity_mm_s.abs() / 0.0106,
        position_mm: 10.0,
        format: if rng.random::<bool>() { FrameFormat::Png8 } else { FrameFormat::Png16 },
        noise: NoiseSpec { gaussian_sigma: noise_sigma, full_well: 10000.0 },
        illumination: IlluminationSpec { gradient_x: rng.random_range(-0.2..0.2), gradient_y: rng.random_range(-0.08..0.08), ..IlluminationSpec::default() },
        optics: OpticsSpec::default(),
        channel: ChannelSpec { width_um: 11.9, height_um: 9.7, axis_row_px, axis_in_toml: false },
        cells,
        debris: Vec::new(),
        wave: None,
    }
}
