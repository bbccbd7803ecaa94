//! A second bright-field renderer, from wave optics: cells as thin phase-and-amplitude objects imaged through an objective, sharing no image-formation code with the synthesiser's edge profiles.
//!
//! The synthesiser ([`crate::simulated::synth::render`]) draws a cell as a contrast profile of the
//! distance to its outline (dark rim, bright halo, lighter centre), with shapes read off bright-field
//! images; the classifier and the segmentation were tuned on it. This renderer computes the image
//! from the optics instead, so that the pipeline can be tested on images it was not tuned on:
//!
//! 1. **the object**: the cell's thickness along the viewing axis `T(x, y)` ([`thickness`]: from the
//!    synthesiser's truth outlines with a rounded rim holding a red cell's volume, or from the
//!    solver's 3D mesh), a thin object of refractive index `n_cell` (haemoglobin solution, ~1.40)
//!    in a medium of `n_medium` (~1.335) that absorbs `absorption_per_um` of the light per um
//!    (haemoglobin in the green);
//! 2. **the microscope** ([`image`]): the transmitted field propagated by the angular spectrum to the
//!    plane the objective is focused on and cut by its pupil (NA), summed incoherently over the
//!    condenser's illumination directions (Köhler illumination, condenser NA);
//! 3. **the channel**: the PDMS walls as a phase step of `(n_pdms - n_medium)` over the channel
//!    height, imaged through the same optics (one-dimensional, [`image::bright_field_1d`]);
//! 4. **the frame**: the cells' images moved along the flow (motion blur over the exposure),
//!    integrated over each camera pixel, on an uneven, flickering illumination with out-of-focus
//!    dust; the camera ([`crate::simulated::camera`]: motion blur, flicker, shot and read noise,
//!    quantisation) is every renderer's, and the ground truth the synthesiser's
//!    ([`crate::simulated::synth::truth_rows`]: the truth of the shapes, not of an image).
//!
//! A [`SynthSpec`] with a `[wave]` table ([`WaveOptics`]) is rendered by this renderer
//! (`write_recording` dispatches); its `optics` table then only gives the exposure time.
//!
//! Sign of the defocus: as for the synthesiser, `defocus_um > 0` puts the focal plane above the
//! cell's mid-plane. On an inverted microscope (the usual for microfluidics: condenser above,
//! objective below) the light travels downwards, so the imaged plane lies upstream of the
//! object: the field is propagated by `-defocus_um` ([`WaveOptics::propagation_um`]); a cell
//! then shows a dark rim inside a bright halo above focus and the reverse below, like a
//! phase object in the transport-of-intensity picture (`I = 1 - dz / k Laplacian(phi)`).

pub mod image;
pub mod optics;
pub mod thickness;

pub use optics::WaveOptics;

use crate::error::AnalysisError;
use crate::simulated::render3d::CellMesh;
use crate::simulated::camera;
use crate::simulated::synth::spec::SynthSpec;
use crate::simulated::synthetic_recording::{box_distance, debris_on_cell, write_frames_and_truth, Truth, TruthRow, SPEC_FILE};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rustfft::num_complex::Complex64;
use std::path::Path;
use thickness::ThicknessMap;

/// The bright-field image of one object around its reference point: relative contrast `I - 1` on a
/// fine grid (spacing `s` um, `nx` x `ny`, sample `(0, 0)` at `(x0, y0)` um from the reference point).
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectImage {
    pub nx: usize,
    pub ny: usize,
    pub s: f64,
    pub x0: f64,
    pub y0: f64,
    pub contrast: Vec<f64>,
}

impl ObjectImage {
    /// Image a thickness map of an object of refractive index `n_object` and intensity
    /// absorption `mu` (1/um) under `o` (the map must carry [`image::margin_um`] of empty border).
    pub fn of(th: &ThicknessMap, n_object: f64, mu: f64, o: &WaveOptics) -> ObjectImage {
        let k0 = std::f64::consts::TAU / o.wavelength_um;
        let t: Vec<Complex64> = th.t_um.iter().map(|&t| Complex64::from_polar((-0.5 * mu * t).exp(), k0 * (n_object - o.n_medium) * t)).collect();
        let im = image::bright_field(&t, th.nx, th.ny, th.s, o);
        ObjectImage { nx: th.nx, ny: th.ny, s: th.s, x0: th.x0, y0: th.y0, contrast: im.into_iter().map(|v| v - 1.0).collect() }
    }

    /// Contrast at `(x, y)` um from the reference point (bilinear; 0 outside the grid).
    pub fn at(&self, x: f64, y: f64) -> f64 {
        let (u, v) = ((x - self.x0) / self.s, (y - self.y0) / self.s);
        if !(u >= 0.0 && v >= 0.0) {
            return 0.0;
        }
        let (i, j) = (u.floor() as usize, v.floor() as usize);
        if i + 1 >= self.nx || j + 1 >= self.ny {
            return 0.0;
        }
        let (fu, fv) = (u - i as f64, v - j as f64);
        let c = |i: usize, j: usize| self.contrast[j * self.nx + i];
        (1.0 - fv) * ((1.0 - fu) * c(i, j) + fu * c(i + 1, j)) + fv * ((1.0 - fu) * c(i, j + 1) + fu * c(i + 1, j + 1))
    }

    /// Extent `[xmin, xmax, ymin, ymax]` um around the reference point.
    pub fn extent(&self) -> [f64; 4] {
        [self.x0, self.x0 + (self.nx - 1) as f64 * self.s, self.y0, self.y0 + (self.ny - 1) as f64 * self.s]
    }
}

/// Refractive index of debris (platelets, cell fragments, beads: protein or polystyrene ~1.45-1.59).
pub const N_DEBRIS: f64 = 1.45;

/// An object crossing the field: its image, its reference point at `t = 0` (x um from the image's
/// left edge, y um from the axis) and its velocity along +x, mm/s.
pub struct Moving {
    pub image: ObjectImage,
    pub x0_um: f64,
    pub y_um: f64,
    pub velocity_mm_s: f64,
}

/// Everything of a spec that does not change from frame to frame.
pub struct WaveScene {
    /// The cells of the spec (reference point: the outline's centroid), then the debris particles.
    pub moving: Vec<Moving>,
    /// Image of the channel walls per image row (relative intensity, 1 far from the walls).
    pub wall_rows: Vec<f64>,
    /// Illumination per pixel (fraction of full scale), with the out-of-focus dust.
    pub illumination: Vec<f64>,
    /// Sub-samples per pixel and direction.
    pub oversampling: usize,
}

/// Precompute the images of `spec` (which must carry `wave`) with illumination seed `seed`.
pub fn scene(spec: &SynthSpec, o: &WaveOptics, seed: u64) -> WaveScene {
    let (s, m) = o.fine_spacing(spec.um_per_px);
    let margin = image::margin_um(o);
    let cells = spec.cells.iter().map(|c| {
        let th = thickness::from_outline(&c.outline(), o.cell_volume_um3, s, margin);
        Moving { image: ObjectImage::of(&th, o.n_cell, o.absorption_per_um, o), x0_um: c.x0_um, y_um: c.y_um, velocity_mm_s: c.velocity_mm_s }
    });
    let debris = spec.debris.iter().map(|d| {
            // a sphere of radius 1.5 sigma; its absorption darkens its centre by `contrast` in focus
            let r = 1.5 * d.radius_um;
            let mut th = ThicknessMap::empty([-r, r, -r, r], margin, s);
            for j in 0..th.ny {
                for i in 0..th.nx {
                    let (x, y) = (th.x0 + i as f64 * s, th.y0 + j as f64 * s);
                    th.t_um[j * th.nx + i] = 2.0 * (r * r - x * x - y * y).max(0.0).sqrt();
                }
            }
            let mu = -(1.0 + d.contrast.clamp(-0.95, 0.0)).ln() / (2.0 * r);
            Moving { image: ObjectImage::of(&th, N_DEBRIS, mu, o), x0_um: d.x0_um, y_um: d.y_um, velocity_mm_s: d.velocity_mm_s }
    });
    WaveScene { moving: cells.chain(debris).collect(), wall_rows: wall_rows(spec, o, s, m), illumination: illumination(spec, seed), oversampling: m }
}

/// The walls' image per image row: PDMS beyond `|y| = width / 2` transmits `wall_brightness` of the
/// intensity and delays the light by `(n_pdms - n_medium) h` (the channel height `h`) over a wall
/// edge rounded over 0.3 um, imaged in one dimension and averaged over each pixel's rows.
fn wall_rows(spec: &SynthSpec, o: &WaveOptics, s: f64, m: usize) -> Vec<f64> {
    let um = spec.um_per_px;
    // a whole number of samples of padding above row 0, so that sample `k + row m + q` is the
    // `q`-th sub-sample of the row's pixel (`s = um / m`): the walls stand where the spec puts them
    let k = ((8.0 + image::margin_um(o)) / s).ceil() as usize;
    let y_top = -spec.channel.axis_row_px * um - 0.5 * um - k as f64 * s; // um from the axis
    let n = 2 * k + spec.height_px * m;
    let k0 = std::f64::consts::TAU / o.wavelength_um;
    let half = 0.5 * spec.channel.width_um;
    let t: Vec<Complex64> = (0..n)
        .map(|j| {
            let y = y_top + (j as f64 + 0.5) * s;
            let beyond = 0.5 * (1.0 + ((y.abs() - half) / 0.15).tanh());
            let amplitude = 1.0 + (spec.illumination.wall_brightness.sqrt() - 1.0) * beyond;
            Complex64::from_polar(amplitude, k0 * (o.n_pdms - o.n_medium) * spec.channel.height_um * beyond)
        })
        .collect();
    let im = image::bright_field_1d(&t, s, o);
    (0..spec.height_px)
        .map(|row| {
            let j0 = k + row * m;
            (0..m).map(|q| im[j0 + q]).sum::<f64>() / m as f64
        })
        .collect()
}

/// Uneven illumination (linear ramps, vignette) with out-of-focus dust on the optics (dark blurred
/// spots 1-3 um wide, 3-8 % deep), fraction of full scale per pixel.
fn illumination(spec: &SynthSpec, seed: u64) -> Vec<f64> {
    let (w, h) = (spec.width_px, spec.height_px);
    let il = &spec.illumination;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x57A7E_1C0DE);
    let dust: Vec<(f64, f64, f64, f64)> = (0..il.dust_spots).map(|_| (rng.random_range(0.0..w as f64), rng.random_range(0.0..h as f64), rng.random_range(1.0..3.0) / spec.um_per_px, rng.random_range(0.03..0.08))).collect();
    let mut out = Vec::with_capacity(w * h);
    for row in 0..h {
        for col in 0..w {
            let (u, v) = (col as f64 / w as f64 - 0.5, row as f64 / h as f64 - 0.5);
            let mut b = il.level * (1.0 + il.gradient_x * u) * (1.0 + il.gradient_y * v) * (1.0 - il.vignette * 2.0 * (u * u + v * v));
            for &(x, y, r, depth) in &dust {
                let d2 = ((col as f64 - x).powi(2) + (row as f64 - y).powi(2)) / (r * r);
                b *= 1.0 - depth * (-0.5 * d2).exp();
            }
            out.push(b);
        }
    }
    out
}

/// Add an object's image at `(x, y)` um (reference point, x from the image's left edge, y from the
/// axis) into a per-pixel contrast grid, each pixel the mean of its `m` x `m` sub-samples.
fn add_object(contrast: &mut [f64], spec: &SynthSpec, obj: &ObjectImage, x: f64, y: f64, m: usize, weight: f64) {
    let (w, h, um) = (spec.width_px, spec.height_px, spec.um_per_px);
    let e = obj.extent();
    let col0 = ((x + e[0]) / um - 1.0).floor().max(0.0) as usize;
    let col1 = (((x + e[1]) / um + 1.0).ceil().max(0.0) as usize).min(w);
    let row0 = ((y + e[2]) / um + spec.channel.axis_row_px - 1.0).floor().max(0.0) as usize;
    let row1 = (((y + e[3]) / um + spec.channel.axis_row_px + 1.0).ceil().max(0.0) as usize).min(h);
    let sub = |q: usize| ((q as f64 + 0.5) / m as f64 - 0.5) * um;
    let norm = weight / (m * m) as f64;
    for row in row0..row1 {
        let yc = (row as f64 - spec.channel.axis_row_px) * um;
        for col in col0..col1 {
            let xc = (col as f64 + 0.5) * um;
            let mut acc = 0.0;
            for qy in 0..m {
                for qx in 0..m {
                    acc += obj.at(xc + sub(qx) - x, yc + sub(qy) - y);
                }
            }
            contrast[row * w + col] += acc * norm;
        }
    }
}

/// Render frame `k` of `spec` as raw counts (0..=255 or 0..=65535), row-major: the objects at
/// their positions over the exposure (motion blur), `I = B g (W(row) + sum contrast)` with the
/// illumination `B`, the frame's flicker gain `g` and the walls' image `W`, then camera noise.
pub fn render_frame(spec: &SynthSpec, sc: &WaveScene, seed: u64, k: usize) -> Vec<u16> {
    let (w, h, um) = (spec.width_px, spec.height_px, spec.um_per_px);
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0xD1B5_4A32_D192_ED03).wrapping_add(k as u64 + 1));
    let t = k as f64 / spec.fps;
    let mut contrast = vec![0.0; w * h];
    let exposure = spec.optics.exposure_s;
    for m in &sc.moving {
        let xs = camera::exposure_positions(m.x0_um + m.velocity_mm_s * 1000.0 * t, m.velocity_mm_s, exposure, um);
        for &x in &xs {
            add_object(&mut contrast, spec, &m.image, x, m.y_um, sc.oversampling, 1.0 / xs.len() as f64);
        }
    }
    let gain = camera::flicker_gain(spec, &mut rng);
    let intensity: Vec<f64> = (0..w * h).map(|p| sc.illumination[p] * gain * (sc.wall_rows[p / w] + contrast[p])).collect();
    camera::expose(&intensity, spec, &mut rng)
}

/// A simulated cell's mesh (um, the channel axis at `y = z = 0`) as a wave-optics object: its
/// image around the centroid of its silhouette (where the thickness is > 0), and that centroid's
/// `(x, y)`, area (um^2) and extents along x and y (um): the truth of a recording of it.
pub fn mesh_object(mesh: &CellMesh, o: &WaveOptics, um_per_px: f64) -> (ObjectImage, [f64; 2], f64, [f64; 2]) {
    let (s, _) = o.fine_spacing(um_per_px);
    let mut th = thickness::from_mesh(mesh, s, image::margin_um(o));
    let (mut n, mut cx, mut cy) = (0.0, 0.0, 0.0);
    let mut bb = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
    for j in 0..th.ny {
        for i in 0..th.nx {
            if th.t_um[j * th.nx + i] > 0.0 {
                let (x, y) = (th.x0 + i as f64 * s, th.y0 + j as f64 * s);
                n += 1.0;
                cx += x;
                cy += y;
                bb = [bb[0].min(x), bb[1].max(x), bb[2].min(y), bb[3].max(y)];
            }
        }
    }
    let c = [cx / n, cy / n];
    th.x0 -= c[0];
    th.y0 -= c[1];
    (ObjectImage::of(&th, o.n_cell, o.absorption_per_um, o), c, n * s * s, [bb[1] - bb[0] + s, bb[3] - bb[2] + s])
}

/// Render a simulated cell (`mesh`, um) crossing the field of `spec` (which must carry `wave` and no
/// synthetic cells) from `x0_um` at `velocity_mm_s` into the recording folder `dir` (created;
/// refused if it holds frames), with truth rows labelled `label`: the wave-optics counterpart of
/// [`crate::simulated::render3d::write_recording_3d`] for the closed loop.
pub fn write_recording_mesh(dir: &Path, spec: &SynthSpec, mesh: &CellMesh, x0_um: f64, velocity_mm_s: f64, label: &str, seed: u64) -> Result<Truth, AnalysisError> {
    let Some(o) = &spec.wave else {
        return Err(AnalysisError::Input { path: dir.join(SPEC_FILE), message: "wave: the spec has no [wave] table".into() });
    };
    spec.validate(&dir.join(SPEC_FILE))?;
    if !(spec.cells.is_empty() && x0_um.is_finite() && velocity_mm_s.is_finite()) {
        return Err(AnalysisError::Input { path: dir.join(SPEC_FILE), message: "cells: must be empty (the mesh is the only cell), x0 and velocity finite".into() });
    }
    let (image, centroid, area_um2, extent) = mesh_object(mesh, o, spec.um_per_px);
    let mut sc = scene(spec, o, seed);
    sc.moving.insert(0, Moving { image, x0_um, y_um: centroid[1], velocity_mm_s });
    let um = spec.um_per_px;
    let (wu, hu) = (spec.width_px as f64 * um, spec.height_px as f64 * um);
    let blur = camera::half_blur_um(velocity_mm_s, spec.optics.exposure_s);
    let half = [0.5 * extent[0], 0.5 * extent[1]];
    let rows: Vec<TruthRow> = (0..spec.n_frames)
        .map(|k| {
            let t = k as f64 / spec.fps;
            let x = x0_um + velocity_mm_s * 1000.0 * t;
            let y_img = spec.channel.axis_row_px * um + centroid[1] + 0.5 * um;
            TruthRow {
                frame: k as u64,
                cell_id: 0,
                t_s: t,
                x_um: x,
                y_um: centroid[1],
                shape: label.to_string(),
                velocity_mm_s,
                visible: x - half[0] - blur >= 0.5 && x + half[0] + blur <= wu - 0.5 && y_img - half[1] >= 0.5 && y_img + half[1] <= hu - 0.5,
                area_um2,
                length_um: extent[0],
                width_um: extent[1],
                // the mesh's image as its bounding box
                debris_on_cell: debris_on_cell(spec, t, |dx, dy| box_distance(dx - x, dy - centroid[1], half)),
            }
        })
        .collect();
    write_frames_and_truth(dir, spec, &rows, |k| render_frame(spec, &sc, seed, k))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulated::synth::shape::Polygon;

    /// The walls are mirror images about the axis, whatever the defocus: the image of the channel
    /// is sampled on the pixels the spec places around the axis (before, a fraction of a fine
    /// sample of padding moved the walls by up to s / 2 = 0.05 um against the cells, at 2 um of
    /// defocus 0.048 um: the whole y error of the wave rows in the session-12 table).
    #[test]
    fn the_walls_image_is_mirror_symmetric_about_the_axis() {
        for (defocus_um, na, um_per_px) in [(2.0, 0.8, 0.2), (0.5, 0.8, 0.2), (1.0, 0.6, 0.2), (-1.5, 0.5, 0.35)] {
            let c = crate::simulated::synth::Conditions { defocus_um, na, um_per_px, ..Default::default() };
            let mut spec = crate::simulated::synth::condition_spec_wave(1, &c);
            let o = spec.wave.expect("a wave spec");
            // the axis on a pixel centre: row a - j mirrors row a + j
            spec.channel.axis_row_px = spec.channel.axis_row_px.round();
            let (s, m) = o.fine_spacing(spec.um_per_px);
            let rows = wall_rows(&spec, &o, s, m);
            let a = spec.channel.axis_row_px as usize;
            let worst = (1..a.min(rows.len() - 1 - a)).map(|j| (rows[a - j] - rows[a + j]).abs()).fold(0.0, f64::max);
            assert!(worst < 1e-9, "defocus {defocus_um}, NA {na}, {um_per_px} um/px: asymmetry {worst}");
        }
    }

    fn disc(r: f64) -> Polygon {
        Polygon { pts: (0..256).map(|k| { let a = std::f64::consts::TAU * k as f64 / 256.0; [r * a.cos(), r * a.sin()] }).collect() }
    }

    /// A red cell seen in focus is darker inside by its haemoglobin's absorption (Beer-Lambert over
    /// its thickness), and out of focus its rim contrast inverts with the sign of the defocus: dark
    /// rim inside a bright halo above focus, bright rim inside a dark halo below.
    #[test]
    fn a_cell_is_dark_in_focus_and_its_rim_inverts_with_the_defocus() {
        let o = WaveOptics { defocus_um: 0.0, ..WaveOptics::default() };
        let (s, _) = o.fine_spacing(0.2);
        let margin = image::margin_um(&WaveOptics { defocus_um: 2.0, ..o });
        // in focus the plateau's phase is flat: far from the edge I = exp(-mu T) (a large flat cell:
        // the edge's diffraction rings decay before its centre)
        let flat = thickness::from_outline(&disc(8.0), 400.0, s, margin);
        let centre_t = flat.t_um[(flat.ny / 2) * flat.nx + flat.nx / 2];
        let focus = ObjectImage::of(&flat, o.n_cell, o.absorption_per_um, &o);
        let expected = (-o.absorption_per_um * centre_t).exp() - 1.0;
        assert!((focus.at(0.0, 0.0) - expected).abs() < 0.01, "{} vs {expected}", focus.at(0.0, 0.0));
        let th = thickness::from_outline(&disc(3.5), 90.0, s, margin);
        let above = ObjectImage::of(&th, o.n_cell, o.absorption_per_um, &WaveOptics { defocus_um: 1.0, ..o });
        let below = ObjectImage::of(&th, o.n_cell, o.absorption_per_um, &WaveOptics { defocus_um: -1.0, ..o });
        // the rim: the rounding zone 0.2-0.8 um inside the outline; the halo: 0.2-0.8 um outside
        let mean = |im: &ObjectImage, r0: f64, r1: f64| {
            let n = 64;
            let mut acc = 0.0;
            for q in 0..n {
                let a = std::f64::consts::TAU * q as f64 / n as f64;
                for k in 0..5 {
                    let r = r0 + (r1 - r0) * k as f64 / 4.0;
                    acc += im.at(r * a.cos(), r * a.sin());
                }
            }
            acc / (5 * n) as f64
        };
        let (rim_above, halo_above) = (mean(&above, 2.7, 3.3), mean(&above, 3.7, 4.3));
        let (rim_below, halo_below) = (mean(&below, 2.7, 3.3), mean(&below, 3.7, 4.3));
        assert!(rim_above < halo_above && rim_below > halo_below, "above rim {rim_above} halo {halo_above}, below rim {rim_below} halo {halo_below}");
    }

    /// A mesh object: its silhouette's centroid is the truth, and its image reaches the centroid's
    /// neighbourhood (an ellipsoid 8 x 6 x 2.4 um centred at (1, -0.5): silhouette area pi 4 3).
    #[test]
    fn a_mesh_object_is_centred_on_its_silhouette() {
        let (a, b) = (4.0, 3.0);
        let mesh = thickness::ellipsoid(1.0, -0.5, a, b, 1.2, 48);
        let (im, centroid, area, extent) = mesh_object(&mesh, &WaveOptics::default(), 0.2);
        assert!((centroid[0] - 1.0).abs() < 0.01 && (centroid[1] + 0.5).abs() < 0.01, "{centroid:?}");
        assert!((area / (std::f64::consts::PI * a * b) - 1.0).abs() < 0.02, "{area}");
        assert!((extent[0] - 2.0 * a).abs() < 0.1 && (extent[1] - 2.0 * b).abs() < 0.1, "{extent:?}");
        // the cell is darker than the field at its centre (absorption, 1 um above focus) and the
        // image is blank far outside it
        assert!(im.at(0.0, 0.0) < -0.05, "{}", im.at(0.0, 0.0));
        assert_eq!(im.at(20.0, 0.0), 0.0);
    }

    /// Fields of the `[wave]` table out of range are refused naming `wave.<field>` and the file.
    #[test]
    fn bad_optics_are_refused_naming_the_field() {
        let p = Path::new("spec.toml");
        WaveOptics::default().validate(p).unwrap();
        for (o, field) in [
            (WaveOptics { na: 1.4, ..WaveOptics::default() }, "wave.na"),
            (WaveOptics { condenser_na: 0.9, ..WaveOptics::default() }, "wave.condenser_na"),
            (WaveOptics { defocus_um: f64::NAN, ..WaveOptics::default() }, "wave.defocus_um"),
            (WaveOptics { wavelength_um: 5.0, ..WaveOptics::default() }, "wave.wavelength_um"),
            (WaveOptics { cell_volume_um3: 0.0, ..WaveOptics::default() }, "wave.cell_volume_um3"),
        ] {
            let e = o.validate(p).unwrap_err().to_string();
            assert!(e.contains(field) && e.contains("spec.toml"), "{e}");
        }
    }
}
