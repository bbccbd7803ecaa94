//! Imaging conditions that change between labs and days (focus, objective, lamp, camera, channel, sample), as parameters of a synthetic recording, with a grid and a random draw for robustness studies.
//!
//! [`Conditions`] names what a lab's microscope and sample do to a recording; [`condition_spec`]
//! turns it into a [`SynthSpec`] of three cells (croissants and slippers, one in five irregular)
//! with the synthesiser's ground truth, and [`condition_grid`] varies one condition at a time
//! around [`Conditions::default`] (the conditions `rbc-analyze` was built on).
//!
//! The bright-field appearance ([`microscope_optics`]) follows the weak phase-object picture of a
//! red cell (e.g. the transport-of-intensity equation, Teague, *JOSA* 73, 1983: `I(dz) ~ I0 (1 -
//! dz lambda/(2 pi) Laplacian(phi))`): the rim and halo contrast grows linearly with the defocus
//! `dz` and changes sign with it (a bright rim inside a dark halo below focus), haemoglobin's
//! absorption darkens the interior at any focus, and the point spread (Gaussian sigma `0.21
//! lambda / NA` of the Airy disc) widened by the defocus blur sets the width of every edge.

use super::random::{random_cell, FPS};
use super::shape::CellShape;
use super::spec::{ChannelSpec, DebrisSpec, FrameFormat, IlluminationSpec, NoiseSpec, OpticsSpec, SynthSpec};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Wavelength of the illumination, um (green filter).
pub const WAVELENGTH_UM: f64 = 0.55;

/// Imaging conditions of one synthetic recording (units in the names; see [`Conditions::default`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conditions {
    /// Focal plane above (+) or below (-) the cell's mid-plane, um; the sign of the rim contrast.
    pub defocus_um: f64,
    /// Numerical aperture of the objective.
    pub na: f64,
    /// Relative illumination change across the image width.
    pub gradient: f64,
    /// Relative standard deviation of the frame-to-frame brightness.
    pub flicker: f64,
    /// Exposure time, s (motion blur = velocity x exposure).
    pub exposure_s: f64,
    /// Cell velocity, mm/s.
    pub velocity_mm_s: f64,
    /// Read noise, fraction of full scale.
    pub noise_sigma: f64,
    /// 16-bit frames (else 8-bit).
    pub sixteen_bit: bool,
    /// Pixel size in the object plane, um.
    pub um_per_px: f64,
    /// PDMS brightness beyond the walls relative to the channel.
    pub wall_brightness: f64,
    /// Debris particles flowing through the field (per recording).
    pub debris: usize,
    /// Centre-to-centre distance of consecutive cells along x, um (50: isolated).
    pub spacing_um: f64,
}

impl Default for Conditions {
    /// The nominal conditions: in focus 1 um above the mid-plane, NA 0.8, 0.2 um/px, 1 % read noise,
    /// 8 bit, 3 mm/s with a 20 us exposure, 15 % illumination gradient, 1 % flicker, cells 50 um apart.
    fn default() -> Self {
        Conditions {
            defocus_um: 1.0,
            na: 0.8,
            gradient: 0.15,
            flicker: 0.01,
            exposure_s: 20e-6,
            velocity_mm_s: 3.0,
            noise_sigma: 0.01,
            sixteen_bit: false,
            um_per_px: 0.2,
            wall_brightness: 0.85,
            debris: 0,
            spacing_um: 50.0,
        }
    }
}

/// Edge profile of a red cell imaged at defocus `defocus_um` through an objective of numerical aperture `na`.
///
/// Point spread `psf = 0.21 lambda / NA`, defocus blur `0.12 NA |dz|`, edge width
/// `e = sqrt(psf^2 + blur^2)`; phase contrast `a = dz (psf_0.8 / e)` (linear in `dz`, diluted
/// by the blur); rim `0.40 a`, halo `0.28 a`, lighter dimple `0.08 a`; absorption of the interior
/// `-0.12` at any focus; rim and halo widths `2 e`, the halo `0.2 um + e` outside the outline.
pub fn microscope_optics(defocus_um: f64, na: f64) -> OpticsSpec {
    let psf = 0.21 * WAVELENGTH_UM / na.max(0.05);
    let blur = 0.12 * na * defocus_um.abs();
    let edge = (psf * psf + blur * blur).sqrt();
    let psf_nominal = 0.21 * WAVELENGTH_UM / 0.8;
    let a = defocus_um * psf_nominal / edge;
    OpticsSpec {
        interior: -0.12,
        inner: 0.08 * a,
        inner_depth_um: 1.2,
        rim: 0.40 * a,
        rim_offset_um: 0.4,
        rim_width_um: 2.0 * edge,
        halo: 0.28 * a,
        halo_offset_um: 0.2 + edge,
        halo_width_um: 2.0 * edge,
        edge_um: edge,
        exposure_s: 20e-6,
    }
}

/// A recording of three cells under `c` (seeded): shapes croissant, slipper, then one in five
/// irregular, `c.spacing_um` apart, random sizes and offsets ([`random_cell`]); `c.debris` dark
/// particles 0.3-0.6 um in size at random places and speeds within the flow.
pub fn condition_spec(seed: u64, c: &Conditions) -> SynthSpec {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let v = c.velocity_mm_s;
    let disp = v.abs() * 1000.0 / FPS;
    let n_cells = 3;
    let span = c.spacing_um * (n_cells - 1) as f64;
    // the train enters from the left and every cell travels >= 40 um in the field: each pixel is
    // covered by a cell in well under half of the frames (clean median background)
    let n_frames = (((span + 40.0) / disp.max(1e-9)).ceil() as usize).clamp(8, 240);
    let field_um = 60.0 + 3.0 * disp;
    let width_px = (field_um / c.um_per_px).ceil() as usize;
    let height_px = (22.0 / c.um_per_px).ceil() as usize;
    let axis_row_px = 0.5 * (height_px as f64 - 1.0) + rng.random_range(-2.0..2.0) * 0.2 / c.um_per_px;
    let x_first = 10.0;
    let cells = (0..n_cells)
        .map(|i| {
            let shape = if rng.random::<f64>() < 0.2 {
                CellShape::Other
            } else if (i + seed as usize).is_multiple_of(2) {
                CellShape::Croissant
            } else {
                CellShape::Slipper
            };
            // from the front: the first cell is the furthest downstream
            random_cell(&mut rng, shape, x_first - c.spacing_um * i as f64, v)
        })
        .collect();
    let debris = (0..c.debris)
        .map(|_| DebrisSpec {
            x0_um: rng.random_range(-span..field_um),
            y_um: rng.random_range(-5.0..5.0),
            velocity_mm_s: v * rng.random_range(0.3..1.1),
            radius_um: rng.random_range(0.3..0.6),
            contrast: -rng.random_range(0.15..0.4),
        })
        .collect();
    let mut optics = microscope_optics(c.defocus_um, c.na);
    optics.exposure_s = c.exposure_s;
    SynthSpec {
        width_px,
        height_px,
        um_per_px: c.um_per_px,
        fps: FPS,
        n_frames,
        pressure_mbar: v.abs() / 0.0106,
        position_mm: 10.0,
        format: if c.sixteen_bit { FrameFormat::Png16 } else { FrameFormat::Png8 },
        noise: NoiseSpec { gaussian_sigma: c.noise_sigma, full_well: 10000.0 },
        illumination: IlluminationSpec {
            gradient_x: c.gradient * if rng.random::<bool>() { 1.0 } else { -1.0 },
            gradient_y: rng.random_range(-0.08..0.08),
            flicker: c.flicker,
            wall_brightness: c.wall_brightness,
            ..IlluminationSpec::default()
        },
        optics,
        channel: ChannelSpec { width_um: 11.9, height_um: 9.7, axis_row_px, axis_in_toml: false },
        cells,
        debris,
        wave: None,
    }
}

/// The same recording as [`condition_spec`], rendered by the wave-optics renderer
/// ([`crate::simulated::wave`]) under the same defocus and NA (condenser at half the objective's NA,
/// the usual partial coherence of bright field) instead of the edge profiles.
pub fn condition_spec_wave(seed: u64, c: &Conditions) -> SynthSpec {
    let mut spec = condition_spec(seed, c);
    let na = c.na.min(1.25);
    spec.wave = Some(crate::simulated::wave::optics::WaveOptics { defocus_um: c.defocus_um, na, condenser_na: 0.5 * na, wavelength_um: WAVELENGTH_UM, ..Default::default() });
    spec
}

/// Conditions drawn at random from the ranges a lab meets: defocus -2..2 um, NA 0.4-1.2, gradient
/// 0-0.4, flicker 0-5 %, exposure 2-100 us, velocity 0.5-10 mm/s, read noise 0.3-3 %, 8 or 16 bit,
/// 0.1-0.4 um/px, walls 0.5-1.2, 0-10 debris, cells 10-50 um apart.
pub fn random_conditions(seed: u64) -> Conditions {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xC0_4D17_1045);
    Conditions {
        defocus_um: rng.random_range(-2.0..2.0),
        na: rng.random_range(0.4..1.2),
        gradient: rng.random_range(0.0..0.4),
        flicker: rng.random_range(0.0..0.05),
        exposure_s: 10f64.powf(rng.random_range(-5.7..-4.0)),
        velocity_mm_s: rng.random_range(0.5..10.0),
        noise_sigma: 10f64.powf(rng.random_range(-2.5..-1.5)),
        sixteen_bit: rng.random::<bool>(),
        um_per_px: rng.random_range(0.1..0.4),
        wall_brightness: rng.random_range(0.5..1.2),
        debris: rng.random_range(0..=10),
        spacing_um: rng.random_range(10.0..50.0),
    }
}

/// One condition varied at a time around the nominal [`Conditions::default`]: name and conditions.
///
/// Defocus -2..+2 um (the rim inverts below focus), NA 0.4-1.2, illumination gradient and flicker,
/// motion blur at 10 mm/s and 400 fps (exposure 20-250 us: 0.2-2.5 um of travel), read noise and
/// bit depth, pixel size 0.1-0.4 um, PDMS wall brightness, debris, neighbours 10-40 um away.
pub fn condition_grid() -> Vec<(String, Conditions)> {
    let n = Conditions::default();
    let mut g: Vec<(String, Conditions)> = vec![("nominal".into(), n)];
    for dz in [-2.0, -1.0, -0.5, 0.0, 0.5, 2.0] {
        g.push((format!("defocus {dz:+.1} um"), Conditions { defocus_um: dz, ..n }));
    }
    for na in [0.4, 0.6, 1.2] {
        g.push((format!("NA {na}"), Conditions { na, ..n }));
    }
    g.push(("gradient 0.4".into(), Conditions { gradient: 0.4, ..n }));
    g.push(("flicker 5 %".into(), Conditions { flicker: 0.05, ..n }));
    for (ex, label) in [(20e-6, "20 us"), (100e-6, "100 us"), (250e-6, "250 us")] {
        g.push((format!("10 mm/s, exposure {label}"), Conditions { velocity_mm_s: 10.0, exposure_s: ex, ..n }));
    }
    g.push(("0.5 mm/s".into(), Conditions { velocity_mm_s: 0.5, ..n }));
    g.push(("noise 0.3 %, 16 bit".into(), Conditions { noise_sigma: 0.003, sixteen_bit: true, ..n }));
    g.push(("noise 3 %".into(), Conditions { noise_sigma: 0.03, ..n }));
    for px in [0.1, 0.3, 0.4] {
        g.push((format!("{px} um/px"), Conditions { um_per_px: px, ..n }));
    }
    g.push(("walls 0.5".into(), Conditions { wall_brightness: 0.5, ..n }));
    g.push(("walls 1.2".into(), Conditions { wall_brightness: 1.2, ..n }));
    g.push(("10 debris".into(), Conditions { debris: 10, ..n }));
    for s in [10.0, 20.0, 40.0] {
        g.push((format!("neighbours {s} um"), Conditions { spacing_um: s, ..n }));
    }
    g.push(("defocus -1.5, NA 0.5, 0.35 um/px, noise 2 %".into(), Conditions { defocus_um: -1.5, na: 0.5, um_per_px: 0.35, noise_sigma: 0.02, ..n }));
    g
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulated::synth::render::edge_profile;

    #[test]
    fn defocus_inverts_the_rim_and_focus_leaves_absorption() {
        let above = microscope_optics(1.0, 0.8);
        let below = microscope_optics(-1.0, 0.8);
        // rim at d = -0.4 um: dark above focus, bright below; the halo outside the other way round
        assert!(edge_profile(&above, -0.4) < -0.2 && edge_profile(&below, -0.4) > 0.05);
        assert!(edge_profile(&above, 0.2 + above.edge_um) > 0.1 && edge_profile(&below, 0.2 + below.edge_um) < -0.1);
        // in focus only the absorption is left: the interior darker by 12 %, nothing outside
        let focus = microscope_optics(0.0, 0.8);
        assert!((edge_profile(&focus, -3.0) + 0.12).abs() < 1e-9 && edge_profile(&focus, 2.0).abs() < 1e-9);
        // half the NA doubles the in-focus edge width (the Airy disc scales with lambda / NA); out of focus the defocus blur adds in quadrature
        assert!((microscope_optics(0.0, 0.4).edge_um - 2.0 * microscope_optics(0.0, 0.8).edge_um).abs() < 1e-12);
        assert!(microscope_optics(1.0, 0.4).edge_um > 1.5 * microscope_optics(1.0, 0.8).edge_um);
    }

    #[test]
    fn condition_specs_are_valid_and_hold_their_conditions() {
        for (name, c) in condition_grid().into_iter().chain((0..20).map(|s| ("random".to_string(), random_conditions(s)))) {
            let spec = condition_spec(3, &c);
            spec.validate(std::path::Path::new("spec.toml")).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(spec.cells.len(), 3);
            assert_eq!(spec.debris.len(), c.debris);
            let dx = spec.cells[0].x0_um - spec.cells[1].x0_um;
            assert!((dx - c.spacing_um).abs() <= 3.0, "{name}: spacing {dx}");
            // every cell travels at least 40 um after it entered the field
            assert!(spec.n_frames as f64 * c.velocity_mm_s * 1000.0 / spec.fps >= c.spacing_um * 2.0 + 40.0 - 1e-9);
            assert_eq!(spec.um_per_px, c.um_per_px);
        }
    }
}
