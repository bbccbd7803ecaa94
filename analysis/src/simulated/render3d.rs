//! Bright-field frames of a simulated 3D cell (closed triangle mesh) seen along z, written as a synthetic recording: the closed loop solver -> frames -> rbc-analyze.
//!
//! # Image model
//!
//! The camera looks along z onto the x-y plane (x along the flow, y across the
//! channel, the channel axis at `y = z = 0` as in the solver). For every point
//! `(x, y)` of a fine grid (spacing `grid_um`, 0.05 um by default) the vertical
//! ray is cast through the mesh; its crossings, sorted in z and counted with the
//! sign of the face normal (winding number, robust to nested or touching parts),
//! give the intervals `[a_i, b_i]` where the ray is inside the cell. From them:
//!
//! - **optical thickness** `T(x, y) = sum_i (b_i - a_i)` (um); the optical path
//!   difference is `(n_cell - n_medium) T`, and the absorption of haemoglobin gives
//!   the Beer-Lambert contrast `c_abs = (1 + interior)^(T / T_ref) - 1`, i.e.
//!   `exp(-mu T) - 1` with `mu` chosen so that a layer of `T_ref` (2 um, the
//!   thickness of a red cell's rim) has the synthesiser's interior contrast
//!   ([`OpticsSpec::interior`]). `T` is blurred laterally by the optics' edge
//!   width ([`OpticsSpec::edge_um`]). Parts of the cell above or below the focal
//!   plane appear only through this faint term.
//! - **in-focus occupancy** with a depth of field: the slices of the cell at
//!   heights `z` weighted by a Gaussian `N(z; z_f, sigma)` (`sigma = dof_sigma_um`,
//!   0.5 um by default, i.e. a depth of field of ~1 um), integrated exactly over
//!   the intervals: `f(x, y) = sum_i [Phi((b_i - z_f)/sigma) - Phi((a_i - z_f)/sigma)]`
//!   with `Phi` the standard normal CDF. The **in-focus contour** is `f = 1/2`;
//!   for a thin slab this is where the cell is thicker than ~1.35 sigma around
//!   the focal plane. `z_f` defaults to the z of the volume centroid (the
//!   mid-plane cross-section).
//! - the synthesiser's **bright-field edge** (dark rim, bright halo, lighter
//!   inner region; [`crate::simulated::synth::render::edge_profile`] with its interior
//!   term replaced by `c_abs`) evaluated at the signed distance `d` to the
//!   in-focus contour (negative inside). `d` is the distance to the contour's
//!   crossing points on the grid edges (linear interpolation of `f`), which
//!   lie at most `grid_um` apart: the error of `d` is below `grid_um / 2`
//!   (0.025 um), far below the edge width 0.15 um.
//!
//! The relative contrast `c = c_abs + edge(d)` multiplies the synthesiser's
//! static background (uneven illumination, walls, dust) and frame flicker, and
//! the synthesiser's shot and read noise are added
//! ([`crate::simulated::synth::render`]): `I = B g (1 + c)`.
//!
//! # Recording
//!
//! [`write_recording_3d`] moves the cell along +x at constant velocity (with the
//! synthesiser's motion blur) and writes the frames, `recording.toml`,
//! `spec.toml` (the [`SynthSpec`] with an empty cell list) and `truth.csv` in
//! the synthesiser's format ([`crate::simulated::synthetic_recording::TruthRow`]): the truth centroid,
//! area, length and width are those of the in-focus region `f > 1/2`, and the
//! `shape` column is the label given by the caller (the solver's label).

use crate::error::AnalysisError;
use crate::simulated::camera;
use crate::simulated::synth::random::FPS;
use crate::simulated::synth::render;
use crate::simulated::synth::spec::{ChannelSpec, FrameFormat, IlluminationSpec, NoiseSpec, OpticsSpec, SynthSpec};
use crate::simulated::synthetic_recording::{box_distance, debris_on_cell, write_frames_and_truth, Truth, TruthRow, SPEC_FILE};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rbc_schema::SchemaError;
use std::path::{Path, PathBuf};

/// Errors of the 3D renderer; each names what is wrong (vertex, triangle, field, file, run).
#[derive(Debug, thiserror::Error)]
pub enum Render3dError {
    #[error("mesh: triangle {triangle} refers to vertex {vertex}, the mesh has {n_vertices} vertices")]
    BadTriangle { triangle: usize, vertex: usize, n_vertices: usize },
    #[error("mesh: vertex {vertex} is not finite")]
    NonFinite { vertex: usize },
    #[error("mesh encloses volume {volume_um3} um^3: not a closed, outward-oriented surface")]
    Degenerate { volume_um3: f64 },
    #[error("render3d parameter {field}: {message}")]
    Param { field: &'static str, message: String },
    #[error("{path}: run {run_id}: {message}")]
    Results { path: PathBuf, run_id: String, message: String },
    #[error(transparent)]
    Analysis(#[from] AnalysisError),
    #[error(transparent)]
    Schema(#[from] SchemaError),
}

/// A closed, outward-oriented triangle mesh, um.
#[derive(Debug, Clone, PartialEq)]
pub struct CellMesh {
    pub vertices: Vec<[f64; 3]>,
    pub triangles: Vec<[usize; 3]>,
}

impl CellMesh {
    /// Check indices, finiteness and a positive enclosed volume.
    pub fn new(vertices: &[[f64; 3]], triangles: &[[usize; 3]]) -> Result<CellMesh, Render3dError> {
        if let Some(v) = vertices.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(Render3dError::NonFinite { vertex: v });
        }
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v >= vertices.len()) {
                return Err(Render3dError::BadTriangle { triangle: t, vertex: v, n_vertices: vertices.len() });
            }
        }
        let m = CellMesh { vertices: vertices.to_vec(), triangles: triangles.to_vec() };
        let (vol, _) = m.volume_centroid();
        if vol.is_nan() || vol <= 0.0 {
            return Err(Render3dError::Degenerate { volume_um3: vol });
        }
        Ok(m)
    }

    /// [`CellMesh::new`] from `u32` triangles (the results.h5 layout).
    pub fn from_u32(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Result<CellMesh, Render3dError> {
        let t: Vec<[usize; 3]> = triangles.iter().map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
        CellMesh::new(vertices, &t)
    }

    /// Enclosed volume (um^3) and volume centroid (um): signed tetrahedra with the origin,
    /// `V = sum a.(b x c)/6`, `C = sum V_t (a + b + c)/4 / V`.
    pub fn volume_centroid(&self) -> (f64, [f64; 3]) {
        let (mut vol, mut c) = (0.0, [0.0; 3]);
        for t in &self.triangles {
            let (a, b, d) = (self.vertices[t[0]], self.vertices[t[1]], self.vertices[t[2]]);
            let cr = [b[1] * d[2] - b[2] * d[1], b[2] * d[0] - b[0] * d[2], b[0] * d[1] - b[1] * d[0]];
            let v = (a[0] * cr[0] + a[1] * cr[1] + a[2] * cr[2]) / 6.0;
            vol += v;
            for k in 0..3 {
                c[k] += v * (a[k] + b[k] + d[k]) / 4.0;
            }
        }
        (vol, c.map(|x| x / vol))
    }
}

/// Parameters of the image model (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Render3dParams {
    /// Focal plane height, um; `None` = z of the volume centroid (mid-plane section).
    pub focal_z_um: Option<f64>,
    /// Standard deviation of the Gaussian depth weighting, um (depth of field ~ 2 sigma).
    pub dof_sigma_um: f64,
    /// Thickness whose absorption equals the synthesiser's interior contrast, um.
    pub thickness_ref_um: f64,
    /// Spacing of the fine grid the cell is rendered on, um.
    pub grid_um: f64,
}

impl Default for Render3dParams {
    fn default() -> Self {
        Render3dParams { focal_z_um: None, dof_sigma_um: 0.5, thickness_ref_um: 2.0, grid_um: 0.05 }
    }
}

/// The rendered appearance of one cell on a fine grid in the mesh's own x-y coordinates.
#[derive(Debug, Clone)]
pub struct CellImage {
    /// Grid spacing, um; node `(i, j)` is at `(x0_um + i h, y0_um + j h)`.
    pub h_um: f64,
    pub x0_um: f64,
    pub y0_um: f64,
    pub nx: usize,
    pub ny: usize,
    /// Row-major (`j * nx + i`): thickness (um), in-focus occupancy (0..1), relative contrast.
    pub thickness_um: Vec<f64>,
    pub occupancy: Vec<f64>,
    pub contrast: Vec<f64>,
    pub focal_z_um: f64,
    /// In-focus region `f > 1/2`: centroid (mesh x, y; um), area (um^2), length / width along
    /// and across its principal axis (um) and the axis angle to +x (rad).
    pub centroid_um: [f64; 2],
    pub area_um2: f64,
    pub length_um: f64,
    pub width_um: f64,
    pub orientation_rad: f64,
    /// Bounding box of the in-focus region `[xmin, xmax, ymin, ymax]`, mesh coordinates, um.
    pub bbox_um: [f64; 4],
}

/// A triangle projected onto x-y with its z values and twice its signed projected area.
struct Tri2 {
    p: [[f64; 3]; 3],
    d: f64,
}

/// Uniform bucket grid of the projected triangles (each in every bucket its 2D box touches).
struct ZRays {
    tris: Vec<Tri2>,
    x0: f64,
    y0: f64,
    bs: f64,
    nbx: usize,
    nby: usize,
    buckets: Vec<Vec<u32>>,
}

impl ZRays {
    fn new(mesh: &CellMesh) -> ZRays {
        let tris: Vec<Tri2> = mesh
            .triangles
            .iter()
            .map(|t| {
                let p = [mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]];
                let d = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
                Tri2 { p, d }
            })
            .collect();
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for v in &mesh.vertices {
            x0 = x0.min(v[0]);
            x1 = x1.max(v[0]);
            y0 = y0.min(v[1]);
            y1 = y1.max(v[1]);
        }
        let bs = 0.5;
        let nbx = (((x1 - x0) / bs).floor() as usize + 1).max(1);
        let nby = (((y1 - y0) / bs).floor() as usize + 1).max(1);
        let mut buckets = vec![Vec::new(); nbx * nby];
        for (k, t) in tris.iter().enumerate() {
            if t.d == 0.0 {
                continue; // seen edge-on: a vertical ray never crosses it transversally
            }
            let bx = |x: f64| (((x - x0) / bs).floor().max(0.0) as usize).min(nbx - 1);
            let by = |y: f64| (((y - y0) / bs).floor().max(0.0) as usize).min(nby - 1);
            let xs = t.p.map(|p| p[0]);
            let ys = t.p.map(|p| p[1]);
            let (i0, i1) = (bx(xs.iter().copied().fold(f64::MAX, f64::min)), bx(xs.iter().copied().fold(f64::MIN, f64::max)));
            let (j0, j1) = (by(ys.iter().copied().fold(f64::MAX, f64::min)), by(ys.iter().copied().fold(f64::MIN, f64::max)));
            for j in j0..=j1 {
                for i in i0..=i1 {
                    buckets[j * nbx + i].push(k as u32);
                }
            }
        }
        ZRays { tris, x0, y0, bs, nbx, nby, buckets }
    }

    /// Inside intervals `[a, b]` (um) of the vertical line through `(x, y)`, by the winding number:
    /// a crossing of a face whose outward normal points down (`d < 0`) enters the cell.
    fn intervals(&self, x: f64, y: f64, out: &mut Vec<[f64; 2]>) {
        out.clear();
        let (fi, fj) = ((x - self.x0) / self.bs, (y - self.y0) / self.bs);
        if fi < 0.0 || fj < 0.0 || fi >= self.nbx as f64 || fj >= self.nby as f64 {
            return;
        }
        let mut hits: Vec<(f64, i32)> = Vec::new();
        for &k in &self.buckets[fj as usize * self.nbx + fi as usize] {
            let t = &self.tris[k as usize];
            let [a, b, c] = t.p;
            let l0 = ((b[0] - x) * (c[1] - y) - (b[1] - y) * (c[0] - x)) / t.d;
            let l1 = ((c[0] - x) * (a[1] - y) - (c[1] - y) * (a[0] - x)) / t.d;
            let l2 = 1.0 - l0 - l1;
            if l0 >= 0.0 && l1 >= 0.0 && l2 >= 0.0 {
                hits.push((l0 * a[2] + l1 * b[2] + l2 * c[2], if t.d < 0.0 { 1 } else { -1 }));
            }
        }
        hits.sort_by(|p, q| p.0.total_cmp(&q.0));
        let mut w = 0;
        let mut start = 0.0;
        for (z, s) in hits {
            let before = w;
            w += s;
            if before <= 0 && w > 0 {
                start = z;
            } else if before > 0 && w <= 0 {
                out.push([start, z]);
            }
        }
    }
}

/// Standard normal CDF `Phi(u) = (1 + erf(u / sqrt 2)) / 2`.
fn phi(u: f64) -> f64 {
    0.5 * (1.0 + statrs::function::erf::erf(u / std::f64::consts::SQRT_2))
}

/// Render `mesh` on a fine grid: thickness, in-focus occupancy, relative contrast and the
/// in-focus region's truth (see the module documentation for the equations).
pub fn cell_image(mesh: &CellMesh, optics: &OpticsSpec, p: &Render3dParams) -> Result<CellImage, Render3dError> {
    let pos = |field: &'static str, v: f64| if v.is_finite() && v > 0.0 { Ok(()) } else { Err(Render3dError::Param { field, message: format!("must be > 0, got {v}") }) };
    pos("dof_sigma_um", p.dof_sigma_um)?;
    pos("thickness_ref_um", p.thickness_ref_um)?;
    pos("grid_um", p.grid_um)?;
    if p.grid_um > 0.2 {
        return Err(Render3dError::Param { field: "grid_um", message: format!("must be <= 0.2 um (finer than the edge), got {}", p.grid_um) });
    }
    let (_, c3) = mesh.volume_centroid();
    let zf = p.focal_z_um.unwrap_or(c3[2]);
    if !zf.is_finite() {
        return Err(Render3dError::Param { field: "focal_z_um", message: "must be finite".into() });
    }
    let rays = ZRays::new(mesh);
    let h = p.grid_um;
    // far enough out that the halo, the edge blur and the inner term have all decayed
    let margin = render::profile_reach_um(optics) + 4.0 * optics.edge_um + 0.5;
    let (mut bx0, mut bx1, mut by0, mut by1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for v in &mesh.vertices {
        bx0 = bx0.min(v[0]);
        bx1 = bx1.max(v[0]);
        by0 = by0.min(v[1]);
        by1 = by1.max(v[1]);
    }
    // an irrational fraction of h keeps the nodes off mesh edges lying on round coordinates
    let jitter = std::f64::consts::FRAC_1_PI * h;
    let (x0, y0) = (bx0 - margin + jitter, by0 - margin + jitter);
    let nx = ((bx1 - bx0 + 2.0 * margin) / h).ceil() as usize + 1;
    let ny = ((by1 - by0 + 2.0 * margin) / h).ceil() as usize + 1;
    let s = p.dof_sigma_um;
    let rows: Vec<(Vec<f64>, Vec<f64>)> = (0..ny)
        .into_par_iter()
        .map(|j| {
            let y = y0 + j as f64 * h;
            let mut iv = Vec::new();
            let (mut t, mut f) = (vec![0.0; nx], vec![0.0; nx]);
            for i in 0..nx {
                rays.intervals(x0 + i as f64 * h, y, &mut iv);
                for &[a, b] in &iv {
                    t[i] += b - a;
                    f[i] += phi((b - zf) / s) - phi((a - zf) / s);
                }
            }
            (t, f)
        })
        .collect();
    let mut thickness = Vec::with_capacity(nx * ny);
    let mut occ = Vec::with_capacity(nx * ny);
    for (t, f) in rows {
        thickness.extend(t);
        occ.extend(f);
    }
    // in-focus region and its moments
    let inside = |k: usize| occ[k] > 0.5;
    let (mut n, mut sx, mut sy) = (0usize, 0.0, 0.0);
    let mut bb = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
    for j in 0..ny {
        for i in 0..nx {
            if inside(j * nx + i) {
                let (x, y) = (x0 + i as f64 * h, y0 + j as f64 * h);
                n += 1;
                sx += x;
                sy += y;
                bb = [bb[0].min(x), bb[1].max(x), bb[2].min(y), bb[3].max(y)];
            }
        }
    }
    if n < 4 {
        return Err(Render3dError::Param { field: "focal_z_um", message: format!("the focal plane z = {zf:.3} um misses the cell (in-focus area {:.4} um^2)", n as f64 * h * h) });
    }
    let (cx, cy) = (sx / n as f64, sy / n as f64);
    let (mut m20, mut m02, mut m11) = (0.0, 0.0, 0.0);
    for j in 0..ny {
        for i in 0..nx {
            if inside(j * nx + i) {
                let (dx, dy) = (x0 + i as f64 * h - cx, y0 + j as f64 * h - cy);
                m20 += dx * dx;
                m02 += dy * dy;
                m11 += dx * dy;
            }
        }
    }
    let theta = crate::experiment::measure::principal_angle(m20, m02, m11);
    let (ct, st) = (theta.cos(), theta.sin());
    let (mut a0, mut a1, mut b0, mut b1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for j in 0..ny {
        for i in 0..nx {
            if inside(j * nx + i) {
                let (dx, dy) = (x0 + i as f64 * h - cx, y0 + j as f64 * h - cy);
                let (u, v) = (dx * ct + dy * st, -dx * st + dy * ct);
                a0 = a0.min(u);
                a1 = a1.max(u);
                b0 = b0.min(v);
                b1 = b1.max(v);
            }
        }
    }
    // contour crossing points of f = 1/2 on the grid edges (linear interpolation)
    let mut pts: Vec<[f64; 2]> = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let g0 = occ[j * nx + i] - 0.5;
            let (x, y) = (x0 + i as f64 * h, y0 + j as f64 * h);
            if i + 1 < nx {
                let g1 = occ[j * nx + i + 1] - 0.5;
                if (g0 > 0.0) != (g1 > 0.0) {
                    pts.push([x + h * (g0 / (g0 - g1)).clamp(0.0, 1.0), y]);
                }
            }
            if j + 1 < ny {
                let g1 = occ[(j + 1) * nx + i] - 0.5;
                if (g0 > 0.0) != (g1 > 0.0) {
                    pts.push([x, y + h * (g0 / (g0 - g1)).clamp(0.0, 1.0)]);
                }
            }
        }
    }
    // thickness blurred by the lateral optical resolution (edge width), in grid units
    let timg = image::ImageBuffer::<image::Luma<f32>, Vec<f32>>::from_raw(nx as u32, ny as u32, thickness.iter().map(|&v| v as f32).collect()).expect("grid size");
    let tblur = imageproc::filter::gaussian_blur_f32(&timg, (optics.edge_um / h) as f32);
    let edge_optics = OpticsSpec { interior: 0.0, ..*optics };
    let mu_ratio = (1.0 + optics.interior).max(1e-6);
    let dmax: f64 = 4.0; // um: beyond this every term of the edge profile is saturated or zero
    let contrast: Vec<f64> = (0..nx * ny)
        .into_par_iter()
        .map(|k| {
            let (x, y) = (x0 + (k % nx) as f64 * h, y0 + (k / nx) as f64 * h);
            // brute force over the crossing points (~1e3), once per cell: simpler than a
            // distance transform and exact to the crossing-point spacing
            let mut d2 = dmax * dmax;
            for q in &pts {
                let (dx, dy) = (q[0] - x, q[1] - y);
                d2 = d2.min(dx * dx + dy * dy);
            }
            let d = if inside(k) { -d2.sqrt() } else { d2.sqrt() };
            let t = tblur.as_raw()[k] as f64;
            mu_ratio.powf(t / p.thickness_ref_um) - 1.0 + render::edge_profile(&edge_optics, d)
        })
        .collect();
    Ok(CellImage {
        h_um: h,
        x0_um: x0,
        y0_um: y0,
        nx,
        ny,
        thickness_um: thickness,
        occupancy: occ,
        contrast,
        focal_z_um: zf,
        centroid_um: [cx, cy],
        area_um2: n as f64 * h * h,
        length_um: a1 - a0 + h,
        width_um: b1 - b0 + h,
        orientation_rad: theta,
        bbox_um: bb,
    })
}

impl CellImage {
    /// Bilinear interpolation of the contrast at mesh coordinates `(x, y)`, 0 outside the grid.
    pub fn contrast_at(&self, x: f64, y: f64) -> f64 {
        let (u, v) = ((x - self.x0_um) / self.h_um, (y - self.y0_um) / self.h_um);
        if !(u >= 0.0 && v >= 0.0 && u < (self.nx - 1) as f64 && v < (self.ny - 1) as f64) {
            return 0.0;
        }
        let (i, j) = (u as usize, v as usize);
        let (fu, fv) = (u - i as f64, v - j as f64);
        let c = |i: usize, j: usize| self.contrast[j * self.nx + i];
        (1.0 - fv) * ((1.0 - fu) * c(i, j) + fu * c(i + 1, j)) + fv * ((1.0 - fu) * c(i, j + 1) + fu * c(i + 1, j + 1))
    }
}

/// How the cell moves through the field: in-focus centroid at `x0_um + v t` (um from the
/// image's left edge), at the mesh's own y (um from the channel axis).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellMotion {
    pub x0_um: f64,
    pub velocity_mm_s: f64,
}

impl CellMotion {
    fn x_at(&self, t: f64) -> f64 {
        self.x0_um + self.velocity_mm_s * 1000.0 * t
    }
}

/// Render frame `k` (raw counts, row-major) of `cell` moving with `motion` in the field of `spec`.
pub fn render_frame_3d(spec: &SynthSpec, cell: &CellImage, motion: &CellMotion, background: &[f64], seed: u64, k: usize) -> Vec<u16> {
    let (w, h, um) = (spec.width_px, spec.height_px, spec.um_per_px);
    // same per-frame stream as the synthesiser's frames
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(k as u64 + 1));
    let t = k as f64 / spec.fps;
    // image x of mesh x: X = x - cx + x_c(t); image y (from row 0) of mesh y: Y = axis_row um + y
    let shifts: Vec<f64> = camera::exposure_positions(motion.x_at(t), motion.velocity_mm_s, spec.optics.exposure_s, um).into_iter().map(|x| x - cell.centroid_um[0]).collect();
    let y_axis = spec.channel.axis_row_px * um;
    let xlo = cell.x0_um + shifts.iter().copied().fold(f64::MAX, f64::min);
    let xhi = cell.x0_um + (cell.nx as f64) * cell.h_um + shifts.iter().copied().fold(f64::MIN, f64::max);
    let (ylo, yhi) = (y_axis + cell.y0_um, y_axis + cell.y0_um + cell.ny as f64 * cell.h_um);
    let c0 = ((xlo / um - 0.5).floor().max(0.0) as usize).min(w);
    let c1 = ((xhi / um - 0.5).ceil().max(0.0) as usize + 1).min(w);
    let r0 = ((ylo / um).floor().max(0.0) as usize).min(h);
    let r1 = ((yhi / um).ceil().max(0.0) as usize + 1).min(h);
    let mut contrast = vec![0.0; w * h];
    let inv = 1.0 / shifts.len() as f64;
    for r in r0..r1 {
        let y = r as f64 * um - y_axis;
        for c in c0..c1 {
            let xp = (c as f64 + 0.5) * um;
            contrast[r * w + c] = shifts.iter().map(|s| cell.contrast_at(xp - s, y)).sum::<f64>() * inv;
        }
    }
    let gain = camera::flicker_gain(spec, &mut rng);
    let intensity: Vec<f64> = background.iter().zip(&contrast).map(|(b, c)| b * gain * (1.0 + c)).collect();
    camera::expose(&intensity, spec, &mut rng)
}

/// The truth rows of a rendered cell (one per frame, `cell_id` 0, `shape` = `label`).
pub fn truth_rows_3d(spec: &SynthSpec, cell: &CellImage, motion: &CellMotion, label: &str) -> Vec<TruthRow> {
    let um = spec.um_per_px;
    let (wu, hu) = (spec.width_px as f64 * um, spec.height_px as f64 * um);
    let blur = camera::half_blur_um(motion.velocity_mm_s, spec.optics.exposure_s);
    let bb = cell.bbox_um;
    (0..spec.n_frames)
        .map(|k| {
            let t = k as f64 / spec.fps;
            let x = motion.x_at(t);
            let (xa, xb) = (x + bb[0] - cell.centroid_um[0], x + bb[1] - cell.centroid_um[0]);
            let (ya, yb) = (spec.channel.axis_row_px * um + bb[2] + 0.5 * um, spec.channel.axis_row_px * um + bb[3] + 0.5 * um);
            TruthRow {
                frame: k as u64,
                cell_id: 0,
                t_s: t,
                x_um: x,
                y_um: cell.centroid_um[1],
                shape: label.to_string(),
                velocity_mm_s: motion.velocity_mm_s,
                visible: xa - blur >= 0.5 && xb + blur <= wu - 0.5 && ya >= 0.5 && yb <= hu - 0.5,
                area_um2: cell.area_um2,
                length_um: cell.length_um,
                width_um: cell.width_um,
                // the mesh's image as its bounding box
                debris_on_cell: debris_on_cell(spec, t, |dx, dy| {
                    let (cx, cy) = (0.5 * (xa + xb), 0.5 * (bb[2] + bb[3]));
                    box_distance(dx - cx, dy - cy, [0.5 * (xb - xa), 0.5 * (bb[3] - bb[2])])
                }),
            }
        })
        .collect()
}

/// A field for one cell crossing it: like [`crate::simulated::synth::random_spec`] (400 fps, 22 um high,
/// 11.9 um channel centred, default optics and illumination) with no synthetic cells.
/// The cell moves at least 45 um (12 to 120 frames) and is whole in the field from its
/// start `x0_um` (returned) to its end.
pub fn single_cell_spec(um_per_px: f64, noise_sigma: f64, velocity_mm_s: f64, cell_length_um: f64) -> (SynthSpec, f64) {
    let disp = velocity_mm_s.abs() * 1000.0 / FPS;
    let n_frames = ((45.0 / disp.max(1e-9)).ceil() as usize + 1).clamp(12, 120);
    let margin = 0.5 * cell_length_um + 6.0;
    let field_um = 2.0 * margin + (n_frames - 1) as f64 * disp + 4.0;
    let height_px = (22.0 / um_per_px).ceil() as usize;
    let spec = SynthSpec {
        width_px: (field_um / um_per_px).ceil() as usize,
        height_px,
        um_per_px,
        fps: FPS,
        n_frames,
        pressure_mbar: velocity_mm_s.abs() / 0.0106,
        position_mm: 10.0,
        format: FrameFormat::Png16,
        noise: NoiseSpec { gaussian_sigma: noise_sigma, full_well: 10000.0 },
        illumination: IlluminationSpec::default(),
        optics: OpticsSpec::default(),
        channel: ChannelSpec { width_um: 11.9, height_um: 9.7, axis_row_px: 0.5 * (height_px as f64 - 1.0) + 0.37, axis_in_toml: false },
        cells: Vec::new(),
        debris: Vec::new(),
        wave: None,
    };
    (spec, margin)
}

/// Render `cell` moving with `motion` through the field of `spec` (which must have no
/// synthetic cells) into the recording folder `dir` (created; refused if it holds frames):
/// frames, `recording.toml`, `spec.toml`, `truth.csv` (synthesiser format).
pub fn write_recording_3d(dir: &Path, spec: &SynthSpec, cell: &CellImage, motion: &CellMotion, label: &str, seed: u64) -> Result<Truth, Render3dError> {
    spec.validate(&dir.join(SPEC_FILE))?;
    if !spec.cells.is_empty() {
        return Err(Render3dError::Param { field: "spec.cells", message: "must be empty: the 3D cell is the only cell".into() });
    }
    if !(motion.x0_um.is_finite() && motion.velocity_mm_s.is_finite()) {
        return Err(Render3dError::Param { field: "motion", message: "x0_um and velocity_mm_s must be finite".into() });
    }
    let background = render::static_background(spec, seed);
    let rows = truth_rows_3d(spec, cell, motion, label);
    Ok(write_frames_and_truth(dir, spec, &rows, |k| render_frame_3d(spec, cell, motion, &background, seed, k))?)
}

/// One simulated cell read from results.h5: a snapshot's mesh, the run's label and velocity.
#[derive(Debug, Clone)]
pub struct SimulatedCell {
    pub mesh: CellMesh,
    /// The solver's `final_shape` (`croissant|slipper|other`), `unlabelled` for an unfinished run.
    pub label: String,
    /// Mean x-velocity of the run (mm/s), or from the last two snapshots' centroids if unfinished.
    pub velocity_mm_s: f64,
    /// Time of the snapshot, s.
    pub t_s: f64,
}

/// Read snapshot `index` (default: the last) of run `run_id` from `path`
/// ([`rbc_schema::results::read_snapshots`], [`rbc_schema::results::read_runs`]).
pub fn cell_from_results(path: &Path, run_id: &str, index: Option<usize>) -> Result<SimulatedCell, Render3dError> {
    let err = |message: String| Render3dError::Results { path: path.to_path_buf(), run_id: run_id.to_string(), message };
    let runs = rbc_schema::results::read_runs(path)?;
    let Some(run) = runs.iter().find(|r| r.run_id == run_id) else {
        let ids: Vec<&str> = runs.iter().map(|r| r.run_id.as_str()).take(10).collect();
        return Err(err(format!("no such run (runs: {})", ids.join(", "))));
    };
    let snaps = rbc_schema::results::read_snapshots(path, run_id)?;
    let n = snaps.vertices_um.len();
    if n == 0 {
        return Err(err("the run has no snapshots".into()));
    }
    let k = index.unwrap_or(n - 1);
    if k >= n {
        return Err(err(format!("snapshot {k} does not exist (the run has {n})")));
    }
    let mesh = CellMesh::from_u32(&snaps.vertices_um[k], &snaps.triangles).map_err(|e| err(format!("snapshot {k}: {e}")))?;
    let (label, velocity) = match &run.summary {
        Some(s) => (s.final_shape.as_str().to_string(), s.mean_velocity_mm_s),
        None => ("unlabelled".to_string(), f64::NAN),
    };
    let velocity = if velocity.is_finite() {
        velocity
    } else if n >= 2 {
        let a = CellMesh::from_u32(&snaps.vertices_um[n - 2], &snaps.triangles).map_err(|e| err(format!("snapshot {}: {e}", n - 2)))?;
        let (_, ca) = a.volume_centroid();
        let (_, cb) = CellMesh::from_u32(&snaps.vertices_um[n - 1], &snaps.triangles).map_err(|e| err(format!("snapshot {}: {e}", n - 1)))?.volume_centroid();
        (cb[0] - ca[0]) / (snaps.times_s[n - 1] - snaps.times_s[n - 2]) / 1000.0
    } else {
        f64::NAN
    };
    if !velocity.is_finite() {
        return Err(err("no velocity (unfinished run with one snapshot): give one explicitly".into()));
    }
    Ok(SimulatedCell { mesh, label, velocity_mm_s: velocity, t_s: snaps.times_s[k] })
}
