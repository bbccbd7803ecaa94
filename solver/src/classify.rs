//! Shape classification of a simulated cell over a window of its steady state: croissant / slipper / other, tank-treading and tumbling flags, with the evidence.
//!
//! The paper ("Numerical results") distinguishes a *croissant*, which moves as
//! a rigid body, centred, and is "not perfectly rotationally symmetric" (a
//! parachute folded in the rectangular channel: mirror-symmetric about at least
//! one of the x-z and x-y planes through its centroid, not necessarily both),
//! from a *slipper*, which is off-centre, breaks that symmetry and tank-treads
//! (its membrane circulates around a steady or periodic shape); slow slippers
//! *tumble* (the whole shape rotates about z) and are still slippers. [`classify`] decides this from the vertex positions of a
//! few closely spaced frames (the labelled vertices give the membrane motion)
//! and returns the label with its [`Evidence`].
//!
//! # Measures
//!
//! - **Offset**: volume centroid `c = sum_t V_t (a + b + c)_t / 4 / V` (signed
//!   tetrahedra with the origin), averaged over the frames; `r = sqrt(y^2 + z^2)`
//!   relative to the channel axis.
//! - **Mirror asymmetry** about the plane `y = c_y` (the x-z plane through the
//!   centroid) and `z = c_z` (the x-y plane): the root mean square, over the
//!   vertices, of the distance from each mirrored vertex to the (polyhedral)
//!   surface. It is exactly 0 for a surface that is symmetric and meshed
//!   symmetrically and O(h^2) for a symmetric surface meshed asymmetrically (the
//!   distance is to the surface, not to the nearest vertex). Reported in um and
//!   relative to `R_eff = sqrt(A / 4 pi)`. Evaluated on the first, middle and
//!   last frame and averaged (brute force `O(nv nt)` per frame, pruned by a
//!   bounding-sphere test).
//! - **Fold plane**: the same asymmetry about every plane through the centroid
//!   that contains the flow direction x, its normal `(0, cos a, sin a)` at the
//!   angle `a` from y towards z (`a` = 0: the x-z plane, 90 degrees: the x-y
//!   plane); the least of them and its angle ([`FOLD_COARSE_DEG`] steps, then
//!   [`FOLD_FINE_DEG`] steps around the best). A fold need not lie along a
//!   wall: at ~2.5 mm/s the study's centred r_init = 0.4 um cell
//!   (`discocyte_u1.5_r0.4`) is most nearly symmetric about a plane 16 degrees
//!   from the x-y plane (its steady state: 0.0506 R_eff there, 0.067 and 0.072
//!   about the x-y and x-z planes).
//! - **Membrane circulation** (tank-treading): the circulation axis `n` is the
//!   mean rotation vector of the best rigid rotation (Kabsch) between
//!   successive frames of the centred, labelled vertices (`z` if negligible).
//!   Each vertex's angle `psi_i(t)` about `n` through the centroid is unwrapped
//!   and fitted by a line; the mean slope over vertices away from the axis
//!   (mean projected distance >= 0.3 times the median) is the labels' rotation
//!   rate (the mean, because the phase average of a point's varying rate along a
//!   closed orbit is the circulation rate, also over less than one turn).
//!   The shape's own rotation rate about `n` is the slope of the unwrapped
//!   orientation of the surface's area-weighted gyration tensor in the plane
//!   normal to `n` (label-free: `(1/2) atan2(2 G_12, G_11 - G_22)`, unwrapped
//!   modulo pi; zero when the in-plane anisotropy is below 5 %). The
//!   tank-treading frequency is `|labels rate - shape rate| / 2 pi`.
//!   Frames must be close enough that a vertex turns by less than half a turn
//!   between them (`f_TT dt < 1/2`; use `< 1/10`).
//! - **Tumbling**: the same orientation angle in the x-y plane (rotation about
//!   z); its net change over the window and its rate. A disc tilted far out of
//!   the x-y plane projects nearly round, so its angle is then ill-defined (and
//!   zeroed below 5 % anisotropy). Over every window of 25 shapes 60 ms apart of
//!   the penalty study's slow slippers (~0.26, ~0.32, ~0.37 and ~0.5 mm/s, session 54)
//!   this measure agrees, to the 0.25 turn that flags tumbling, with the net
//!   turn of the azimuth of the disc's normal (the axis of least extent); the
//!   two differ only over the ~0.32 and ~0.37 mm/s cells' one overturn at
//!   0.5-0.73 s, their normals 45-46 degrees out of the plane, where neither is
//!   a rotation about z.
//! - **Non-rigid speed**: the root mean square residual of the Kabsch fits per
//!   unit time (um/s), i.e. membrane motion that is not a rigid-body motion;
//!   also relative to the centroid speed.
//!
//! # Decision ([`ClassifyConfig`])
//!
//! `centred`: `r <= centred_um`; `folded` (mirror-symmetric about one plane):
//! the fold plane's asymmetry `<= symmetric_rel * R_eff` (never more than the
//! smaller of the x-z and x-y planes', which are two of the planes searched);
//! `symmetric` (about both planes): the larger one `<= symmetric_rel * R_eff`;
//! `tank_treading`: the membrane turns at least `min_tt_turns` turns relative
//! to the shape over the window; `tumbling`: the shape's orientation about z
//! changes by at least `min_tumble_turns` turns.
//! `rigid` (moves as a rigid body): the non-rigid vertex speed is at most
//! `rigid_rel` of the centroid speed, and the cell neither tank-treads nor
//! tumbles.
//! Croissant = centred and (mirror-symmetric about at least one plane, or
//! rigid); a tank-treading croissant keeps the label with `tank_treading =
//! true`, as in the paper; slipper = off-centre, not symmetric about both
//! planes and (tank-treading or tumbling); anything else is `other`.
//!
//! Rigid, not only folded: the paper defines its simulated croissant as the
//! centred shape "which moves as a rigid body" ("Numerical results"); the
//! mirror test is this classifier's addition, which recognises the folded
//! parachutes that tank-tread a little (the study's ~6.4 mm/s croissants: their
//! membrane moves at 0.006 of their speed, circulating at 2.3-2.8 Hz, and carries
//! the `tank_treading` flag since `min_tt_turns` is 0.1 turn). A centred cell whose membrane does
//! not move at all is the paper's croissant whatever its mirror asymmetry: the
//! study's ~2.5 mm/s r_init = 0.4 um cell settles so (non-rigid speed 6e-5 of
//! its speed, 0.0506 R_eff about its best plane, just past the mirror bound,
//! and a croissant for the image classifier of `rbc-analysis` when rendered).
//!
//! One plane, not both: in the 12 x 10 um channel the paper's croissants are
//! folded parachutes (its Fig. 1(c, d)), whose cross-section is a U symmetric
//! about the plane through the fold only; their centroid sits a little off the
//! axis along the fold ("minor deviations away from zero", "minuscule periodic
//! shape deformations"). The study's r_init = 0.4 um run ends exactly so:
//! rigid (non-rigid motion 0.6 % of its speed), centred at r = 0.31 um,
//! symmetric about the x-z plane (0.014 R_eff) and folded across the x-y plane
//! (0.28 R_eff). A slipper is symmetric about at most the x-y plane (its
//! offset is along y), so the two labels stay apart by the offset and the
//! membrane motion.

use nalgebra::{Matrix3, Rotation3, Vector3};
use rbc_schema::results::FinalShape;
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// Errors of the classifier (unusable input).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClassifyError {
    #[error("need at least 3 frames to classify, got {0}")]
    TooFewFrames(usize),
    #[error("frame {frame} has {found} vertices, frame 0 has {expected}")]
    VertexCount {
        frame: usize,
        expected: usize,
        found: usize,
    },
    #[error("frame {frame}: time {t_s} s is not after the previous frame")]
    TimeOrder { frame: usize, t_s: f64 },
    #[error("frame {frame}: time {t_s} s is not a finite number")]
    NonFiniteTime { frame: usize, t_s: f64 },
    #[error("frame {frame}: vertex {vertex} is not finite")]
    NonFinite { frame: usize, vertex: usize },
    #[error("triangle {triangle} refers to vertex {vertex}, the frames have {n_vertices}")]
    BadTriangle {
        triangle: usize,
        vertex: usize,
        n_vertices: usize,
    },
    #[error("the surface encloses no volume (volume {volume_um3} um^3 in frame {frame})")]
    Degenerate { frame: usize, volume_um3: f64 },
}

/// Step (degrees) of the coarse search for the fold plane (it includes 0 and 90: the x-z and x-y planes).
pub const FOLD_COARSE_DEG: f64 = 10.0;
/// Step (degrees) of the fine search within one coarse step either side of the coarse minimum.
pub const FOLD_FINE_DEG: f64 = 1.0;

/// One frame: time (s) and vertex positions (um), vertices labelled consistently across frames.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    pub t_s: f64,
    pub vertices: &'a [[f64; 3]],
}

/// Thresholds of the decision, with the reasons for the defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClassifyConfig {
    /// A cell is centred when its radial offset is at most this (um). Default 0.6 um
    /// (session 60; 0.4 before): between the largest offset of any croissant the two studies
    /// ended (0.387 um, the paper's-walls croissants at ~6.45 mm/s, tank-treading at 2.7-2.8
    /// Hz) and the smallest slipper offset of the paper (0.8 um; of the studies' ended
    /// slippers 0.944 um), 0.21 um from the one and 0.2 um from the other. At 0.4 those
    /// croissants sat within 0.013 um of the bound, and a faster tank-treading croissant held a
    /// little further out (the paper sees them above ~7 mm/s) would have been labelled a
    /// slipper. No ended run of either study changes its label (`rbc-sweep relabel`).
    pub centred_um: f64,
    /// A shape is mirror-symmetric about a plane when its asymmetry about it is at most this
    /// fraction of `R_eff`. Default 0.05 (0.17 um for the paper's cell): a mesh edge at 2048
    /// triangles is ~0.4 um, so discretisation noise stays below it while a slipper's
    /// asymmetry is of order 1 um.
    pub symmetric_rel: f64,
    /// Tank-treading when the membrane turns at least this many times relative to the
    /// shape over the window. Default 0.1 turn (session 51; 0.25 before): 5x the most a rigid
    /// croissant of the two studies turns over its window (0.02: its fit error and the slow
    /// turn of its shape), and below the least the ~6.45 mm/s croissants turn (0.16-0.23 turns
    /// at 2.3-2.8 Hz over windows of 0.06-0.10 s; slippers 0.36 and more). At 0.25 those
    /// croissants, whose membrane circulates at a third of a slipper's rate, were labelled
    /// rigid; now they are the paper's tank-treading croissants, and its "non-tank-treading
    /// croissants are always almost centered" holds for the rest (within 0.18 um).
    pub min_tt_turns: f64,
    /// Tumbling when the shape's orientation about z changes by at least this many
    /// turns over the window. Default 0.25 turn (90 degrees; periodic contractions of
    /// a slipper wobble its orientation by a few degrees only).
    pub min_tumble_turns: f64,
    /// A cell moves as a rigid body when its RMS non-rigid vertex speed is at most this
    /// fraction of its centroid speed (and it neither tank-treads nor tumbles). Default 1e-3:
    /// the study's settled centred cells at 2.5 and 4 mm/s move at 6e-5 and 1.2e-4, its
    /// slightly tank-treading croissants at 6.4 mm/s at 0.006, its slippers at 0.019-0.023. A
    /// cell whose centroid does not move has no ratio and is not judged rigid.
    pub rigid_rel: f64,
    /// Channel axis position (y, z) in um (the origin in the paper's frame).
    pub axis_yz_um: [f64; 2],
}

impl Default for ClassifyConfig {
    fn default() -> Self {
        ClassifyConfig {
            centred_um: 0.6,
            symmetric_rel: 0.05,
            min_tt_turns: 0.1,
            min_tumble_turns: 0.25,
            rigid_rel: 1e-3,
            axis_yz_um: [0.0, 0.0],
        }
    }
}

/// The measures behind a label (units in the names).
#[derive(Debug, Clone, PartialEq)]
pub struct Evidence {
    /// Mean centroid offset from the channel axis, y and z (um, signed) and radial (um).
    pub offset_y_um: f64,
    pub offset_z_um: f64,
    pub offset_r_um: f64,
    /// `sqrt(A / 4 pi)` of the first frame (um).
    pub r_eff_um: f64,
    /// RMS distance of the vertices mirrored about the x-z plane (y) and the x-y plane (z) through the centroid to the surface (um).
    pub mirror_y_um: f64,
    pub mirror_z_um: f64,
    /// The same divided by `r_eff_um`.
    pub mirror_y_rel: f64,
    pub mirror_z_rel: f64,
    /// The fold plane: the least asymmetry about a plane through the centroid containing x (um,
    /// and relative to `r_eff_um`) and the angle of its normal from y towards z (degrees, [0, 180)).
    pub mirror_fold_um: f64,
    pub mirror_fold_rel: f64,
    pub fold_angle_deg: f64,
    /// Circulation axis (unit vector).
    pub tt_axis: [f64; 3],
    /// Rotation rate of the labelled vertices about the axis (rad/s) and of the shape (rad/s).
    pub label_rate_rad_s: f64,
    pub shape_rate_rad_s: f64,
    /// Membrane circulation relative to the shape, `|label - shape rate| / 2 pi` (Hz).
    pub tt_frequency_hz: f64,
    /// Rotation rate of the shape about z (Hz, signed) and its net turns over the window.
    pub tumbling_frequency_hz: f64,
    pub tumbling_turns: f64,
    /// RMS non-rigid vertex speed (um/s) and its ratio to the centroid speed.
    pub nonrigid_speed_um_s: f64,
    pub nonrigid_ratio: f64,
    /// Window length (s) and number of frames.
    pub window_s: f64,
    pub n_frames: usize,
}

impl Evidence {
    /// The evidence as `name -> value` for the results.h5 attributes `evidence_<name>`.
    pub fn to_map(&self) -> BTreeMap<String, f64> {
        let mut m = BTreeMap::new();
        let mut put = |k: &str, v: f64| {
            if v.is_finite() {
                m.insert(k.to_string(), v);
            }
        };
        put("offset_y_um", self.offset_y_um);
        put("offset_z_um", self.offset_z_um);
        put("offset_r_um", self.offset_r_um);
        put("r_eff_um", self.r_eff_um);
        put("mirror_y_um", self.mirror_y_um);
        put("mirror_z_um", self.mirror_z_um);
        put("mirror_y_rel", self.mirror_y_rel);
        put("mirror_z_rel", self.mirror_z_rel);
        put("mirror_fold_um", self.mirror_fold_um);
        put("mirror_fold_rel", self.mirror_fold_rel);
        put("fold_angle_deg", self.fold_angle_deg);
        put("tt_axis_x", self.tt_axis[0]);
        put("tt_axis_y", self.tt_axis[1]);
        put("tt_axis_z", self.tt_axis[2]);
        put("tt_frequency_hz", self.tt_frequency_hz);
        put("tumbling_frequency_hz", self.tumbling_frequency_hz);
        put("tumbling_turns", self.tumbling_turns);
        put("nonrigid_speed_um_s", self.nonrigid_speed_um_s);
        put("nonrigid_ratio", self.nonrigid_ratio);
        put("classify_window_s", self.window_s);
        put("classify_frames", self.n_frames as f64);
        m
    }

    /// Whether `m` holds the classifier's evidence at all ([`Evidence::to_map`] always writes the
    /// frame count): a run that ended with fewer than 3 shapes has none.
    pub fn recorded_in(m: &BTreeMap<String, f64>) -> bool {
        m.contains_key("classify_frames")
    }

    /// The evidence back from [`Evidence::to_map`]'s names (as stored in a results file), or the
    /// first name that is missing. `shape_rate_rad_s` and `label_rate_rad_s` are not stored:
    /// they come back as 0 and `tt_frequency_hz` as stored, which is all [`decide`] reads. Evidence
    /// stored before the fold plane was searched (no `mirror_fold_rel`) gets the better of the x-z
    /// and x-y planes as its fold plane, which is what its label was decided from.
    pub fn from_map(m: &BTreeMap<String, f64>) -> Result<Evidence, String> {
        let get = |k: &str| m.get(k).copied().ok_or_else(|| k.to_string());
        let (my, mz) = (get("mirror_y_um")?, get("mirror_z_um")?);
        let (my_rel, mz_rel) = (get("mirror_y_rel")?, get("mirror_z_rel")?);
        let (fold_um, fold_rel, fold_deg) = match (m.get("mirror_fold_um"), m.get("mirror_fold_rel"), m.get("fold_angle_deg")) {
            (Some(&u), Some(&r), Some(&a)) => (u, r, a),
            _ if my_rel <= mz_rel => (my, my_rel, 0.0),
            _ => (mz, mz_rel, 90.0),
        };
        Ok(Evidence {
            offset_y_um: get("offset_y_um")?,
            offset_z_um: get("offset_z_um")?,
            offset_r_um: get("offset_r_um")?,
            r_eff_um: get("r_eff_um")?,
            mirror_y_um: my,
            mirror_z_um: mz,
            mirror_y_rel: my_rel,
            mirror_z_rel: mz_rel,
            mirror_fold_um: fold_um,
            mirror_fold_rel: fold_rel,
            fold_angle_deg: fold_deg,
            tt_axis: [get("tt_axis_x")?, get("tt_axis_y")?, get("tt_axis_z")?],
            label_rate_rad_s: 0.0,
            shape_rate_rad_s: 0.0,
            tt_frequency_hz: get("tt_frequency_hz")?,
            tumbling_frequency_hz: get("tumbling_frequency_hz")?,
            tumbling_turns: get("tumbling_turns")?,
            nonrigid_speed_um_s: get("nonrigid_speed_um_s")?,
            nonrigid_ratio: get("nonrigid_ratio")?,
            window_s: get("classify_window_s")?,
            n_frames: get("classify_frames")? as usize,
        })
    }
}

/// Label, flags and evidence.
#[derive(Debug, Clone, PartialEq)]
pub struct Classification {
    pub shape: FinalShape,
    pub tank_treading: bool,
    pub tumbling: bool,
    pub evidence: Evidence,
}

fn v3(p: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

/// Enclosed volume (um^3) and volume centroid (um) of a closed outward-oriented surface.
pub fn volume_centroid(vertices: &[[f64; 3]], triangles: &[[usize; 3]]) -> (f64, [f64; 3]) {
    let mut vol = 0.0;
    let mut c = Vector3::zeros();
    for t in triangles {
        let (a, b, d) = (
            v3(&vertices[t[0]]),
            v3(&vertices[t[1]]),
            v3(&vertices[t[2]]),
        );
        let v = a.dot(&b.cross(&d)) / 6.0;
        vol += v;
        c += v * (a + b + d) / 4.0;
    }
    let c = if vol != 0.0 { c / vol } else { c };
    (vol, [c.x, c.y, c.z])
}

/// Surface area (um^2).
pub fn surface_area(vertices: &[[f64; 3]], triangles: &[[usize; 3]]) -> f64 {
    triangles
        .iter()
        .map(|t| {
            let (a, b, d) = (
                v3(&vertices[t[0]]),
                v3(&vertices[t[1]]),
                v3(&vertices[t[2]]),
            );
            0.5 * (b - a).cross(&(d - a)).norm()
        })
        .sum()
}

/// Closest point of triangle `abc` to `p` (Ericson, "Real-Time Collision Detection", sec. 5.1.5).
fn closest_on_triangle(
    p: Vector3<f64>,
    a: Vector3<f64>,
    b: Vector3<f64>,
    c: Vector3<f64>,
) -> Vector3<f64> {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Distance queries to a fixed triangulated surface (brute force with bounding-sphere pruning).
struct Surface {
    verts: Vec<Vector3<f64>>,
    tris: Vec<[usize; 3]>,
    centre: Vec<Vector3<f64>>,
    radius: Vec<f64>,
}

impl Surface {
    fn new(vertices: &[[f64; 3]], triangles: &[[usize; 3]]) -> Self {
        let verts: Vec<Vector3<f64>> = vertices.iter().map(v3).collect();
        let centre: Vec<Vector3<f64>> = triangles
            .iter()
            .map(|t| (verts[t[0]] + verts[t[1]] + verts[t[2]]) / 3.0)
            .collect();
        let radius = triangles
            .iter()
            .zip(&centre)
            .map(|(t, c)| t.iter().map(|&i| (verts[i] - c).norm()).fold(0.0, f64::max))
            .collect();
        Surface {
            verts,
            tris: triangles.to_vec(),
            centre,
            radius,
        }
    }

    /// Distance (um) from `q` to the surface.
    fn distance(&self, q: Vector3<f64>) -> f64 {
        // the nearest vertex bounds the distance from above
        let mut best = self
            .verts
            .iter()
            .map(|v| (v - q).norm())
            .fold(f64::INFINITY, f64::min);
        for (k, t) in self.tris.iter().enumerate() {
            if (self.centre[k] - q).norm() - self.radius[k] >= best {
                continue;
            }
            let c = closest_on_triangle(q, self.verts[t[0]], self.verts[t[1]], self.verts[t[2]]);
            best = best.min((c - q).norm());
        }
        best
    }
}

/// RMS distance (um) from the vertices mirrored about the plane `x_axis = plane` (axis 0, 1 or 2) to the surface.
pub fn mirror_asymmetry(
    vertices: &[[f64; 3]],
    triangles: &[[usize; 3]],
    axis: usize,
    plane: f64,
) -> f64 {
    let mut normal = Vector3::zeros();
    normal[axis] = 1.0;
    let mut point = Vector3::zeros();
    point[axis] = plane;
    mirror_rms(&Surface::new(vertices, triangles), vertices, point, normal)
}

/// RMS distance (um) from `vertices` mirrored about the plane through `point` with unit `normal` to the surface `s`.
fn mirror_rms(s: &Surface, vertices: &[[f64; 3]], point: Vector3<f64>, normal: Vector3<f64>) -> f64 {
    let sum: f64 = vertices
        .iter()
        .map(|p| {
            let p = v3(p);
            let q = p - normal * (2.0 * (p - point).dot(&normal));
            s.distance(q).powi(2)
        })
        .sum();
    (sum / vertices.len().max(1) as f64).sqrt()
}

/// The fold plane of [`measure`]: the least mean asymmetry (um) over `frames` (each with its
/// centroid) about a plane through the centroid containing x, and its normal's angle from y
/// towards z (degrees): [`FOLD_COARSE_DEG`] steps over [0, 180), then [`FOLD_FINE_DEG`] steps
/// within one coarse step either side of the coarse minimum. Also the mean asymmetries about the
/// x-z and x-y planes through the centroid (the coarse scan's 0 and 90 degrees).
fn fold_plane(frames: &[(&[[f64; 3]], Vector3<f64>)], triangles: &[[usize; 3]]) -> FoldPlane {
    const _: () = assert!(90.0 % FOLD_COARSE_DEG == 0.0, "the coarse scan holds the x-y plane");
    let surfaces: Vec<Surface> = frames.iter().map(|(v, _)| Surface::new(v, triangles)).collect();
    let asymmetry = |deg: f64| {
        let a = deg.to_radians();
        // (exact axes at 0 and 90 degrees: cos(pi/2) is 6e-17, not 0)
        let normal = if deg == 90.0 { Vector3::z() } else { Vector3::new(0.0, a.cos(), a.sin()) };
        frames.iter().zip(&surfaces).map(|((v, c), s)| mirror_rms(s, v, *c, normal)).sum::<f64>() / frames.len() as f64
    };
    let best = |scan: &[(f64, f64)]| scan.iter().copied().fold((f64::INFINITY, 0.0), |b, x| if x.0 < b.0 { x } else { b });
    let coarse_steps = (180.0 / FOLD_COARSE_DEG).round() as usize;
    let coarse: Vec<(f64, f64)> = (0..coarse_steps).map(|k| k as f64 * FOLD_COARSE_DEG).map(|a| (asymmetry(a), a)).collect();
    let (_, a0) = best(&coarse);
    let fine_steps = (FOLD_COARSE_DEG / FOLD_FINE_DEG).round() as i64;
    let fine: Vec<(f64, f64)> = (-fine_steps..=fine_steps).map(|k| a0 + k as f64 * FOLD_FINE_DEG).map(|a| (asymmetry(a), a)).collect();
    let (m, a) = best(&fine);
    let at = |deg: f64| coarse.iter().find(|c| c.1 == deg).map_or(f64::NAN, |c| c.0);
    FoldPlane { asymmetry_um: m, angle_deg: a.rem_euclid(180.0), xz_um: at(0.0), xy_um: at(90.0) }
}

/// What [`fold_plane`] finds (um, degrees).
struct FoldPlane {
    asymmetry_um: f64,
    angle_deg: f64,
    /// Mean asymmetry about the x-z plane (`y = c_y`) and the x-y plane (`z = c_z`) through the centroid.
    xz_um: f64,
    xy_um: f64,
}

/// Area-weighted second moment of the surface about `c`: `int (x - c)(x - c)^T dA`
/// (exact for flat triangles: `A/12 (sum v_i v_i^T + (sum v_i)(sum v_i)^T)`, vertices relative to `c`).
fn surface_gyration(
    vertices: &[[f64; 3]],
    triangles: &[[usize; 3]],
    c: Vector3<f64>,
) -> Matrix3<f64> {
    let mut g = Matrix3::zeros();
    for t in triangles {
        let (a, b, d) = (
            v3(&vertices[t[0]]) - c,
            v3(&vertices[t[1]]) - c,
            v3(&vertices[t[2]]) - c,
        );
        let area = 0.5 * (b - a).cross(&(d - a)).norm();
        let s = a + b + d;
        g += area / 12.0
            * (a * a.transpose() + b * b.transpose() + d * d.transpose() + s * s.transpose());
    }
    g
}

/// Orientation (rad, modulo pi) of the principal axis of `g` in the plane spanned by `e1`, `e2`,
/// and the in-plane anisotropy `(l1 - l2) / (l1 + l2)`.
fn in_plane_orientation(g: &Matrix3<f64>, e1: &Vector3<f64>, e2: &Vector3<f64>) -> (f64, f64) {
    let (g11, g22, g12) = ((g * e1).dot(e1), (g * e2).dot(e2), (g * e2).dot(e1));
    let diff = ((g11 - g22).powi(2) + 4.0 * g12 * g12).sqrt();
    let aniso = if g11 + g22 > 0.0 {
        diff / (g11 + g22)
    } else {
        0.0
    };
    (0.5 * (2.0 * g12).atan2(g11 - g22), aniso)
}

/// Unwrap a sequence of angles with period `period` (successive jumps brought into `[-period/2, period/2]`,
/// a jump of exactly half a period rounded away from zero: `f64::round`).
fn unwrap(angles: &[f64], period: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(angles.len());
    let mut offset = 0.0;
    for (k, &a) in angles.iter().enumerate() {
        if k > 0 {
            let prev = angles[k - 1];
            let d = a - prev;
            offset -= period * (d / period).round();
        }
        out.push(a + offset);
    }
    out
}

/// Least-squares slope of `y(t)`.
fn slope(t: &[f64], y: &[f64]) -> f64 {
    let n = t.len() as f64;
    let (mt, my) = (t.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (a, b) in t.iter().zip(y) {
        sxy += (a - mt) * (b - my);
        sxx += (a - mt).powi(2);
    }
    if sxx > 0.0 {
        sxy / sxx
    } else {
        0.0
    }
}

/// Best rotation `R` (Kabsch) with `R p_i ~ q_i` for centred point sets; returns `R` and the RMS residual.
fn kabsch(p: &[Vector3<f64>], q: &[Vector3<f64>]) -> (Rotation3<f64>, f64) {
    let h: Matrix3<f64> = p.iter().zip(q).map(|(a, b)| b * a.transpose()).sum();
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.expect("u"), svd.v_t.expect("v_t"));
    let d = (u * vt).determinant().signum();
    let r = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * vt;
    let rot = Rotation3::from_matrix_unchecked(r);
    let res = (p
        .iter()
        .zip(q)
        .map(|(a, b)| (rot * a - b).norm_squared())
        .sum::<f64>()
        / p.len().max(1) as f64)
        .sqrt();
    (rot, res)
}

/// Median of a non-empty slice (copied).
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    s[s.len() / 2]
}

/// Validate frames and triangles.
fn check(frames: &[Frame<'_>], triangles: &[[usize; 3]]) -> Result<(), ClassifyError> {
    if frames.len() < 3 {
        return Err(ClassifyError::TooFewFrames(frames.len()));
    }
    let nv = frames[0].vertices.len();
    for (k, f) in frames.iter().enumerate() {
        if f.vertices.len() != nv {
            return Err(ClassifyError::VertexCount {
                frame: k,
                expected: nv,
                found: f.vertices.len(),
            });
        }
        if !f.t_s.is_finite() {
            return Err(ClassifyError::NonFiniteTime { frame: k, t_s: f.t_s });
        }
        if k > 0 && f.t_s <= frames[k - 1].t_s {
            return Err(ClassifyError::TimeOrder {
                frame: k,
                t_s: f.t_s,
            });
        }
        if let Some(vertex) = f
            .vertices
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            return Err(ClassifyError::NonFinite { frame: k, vertex });
        }
    }
    for (i, t) in triangles.iter().enumerate() {
        if let Some(&v) = t.iter().find(|&&v| v >= nv) {
            return Err(ClassifyError::BadTriangle {
                triangle: i,
                vertex: v,
                n_vertices: nv,
            });
        }
    }
    Ok(())
}

/// Measure the evidence over `frames` (time-ordered, at least 3, same vertex labelling).
pub fn measure(
    frames: &[Frame<'_>],
    triangles: &[[usize; 3]],
    cfg: &ClassifyConfig,
) -> Result<Evidence, ClassifyError> {
    check(frames, triangles)?;
    let m = frames.len();
    let times: Vec<f64> = frames.iter().map(|f| f.t_s).collect();
    let window_s = times[m - 1] - times[0];

    // centroids and offsets
    let mut centroids = Vec::with_capacity(m);
    for (k, f) in frames.iter().enumerate() {
        let (vol, c) = volume_centroid(f.vertices, triangles);
        if vol.is_nan() || vol == 0.0 {
            return Err(ClassifyError::Degenerate {
                frame: k,
                volume_um3: vol,
            });
        }
        centroids.push(v3(&c));
    }
    let mean_c: Vector3<f64> = centroids.iter().sum::<Vector3<f64>>() / m as f64;
    let (oy, oz) = (mean_c.y - cfg.axis_yz_um[0], mean_c.z - cfg.axis_yz_um[1]);
    let r_eff_um = (surface_area(frames[0].vertices, triangles) / (4.0 * PI)).sqrt();

    // mirror asymmetry on the first, middle and last frame
    let picks = [0, m / 2, m - 1];
    let picked: Vec<(&[[f64; 3]], Vector3<f64>)> = picks.iter().map(|&k| (frames[k].vertices, centroids[k])).collect();
    let FoldPlane { asymmetry_um: mf, angle_deg: fold_deg, xz_um: my, xy_um: mz } = fold_plane(&picked, triangles);
    // (the planes at 0 and 90 degrees are the x-z and x-y planes: the fold plane is never worse)
    let (mf, fold_deg) = if my.min(mz) < mf { if my <= mz { (my, 0.0) } else { (mz, 90.0) } } else { (mf, fold_deg) };

    // labelled motion: Kabsch between successive centred frames
    let centred: Vec<Vec<Vector3<f64>>> = frames
        .iter()
        .zip(&centroids)
        .map(|(f, c)| f.vertices.iter().map(|p| v3(p) - c).collect())
        .collect();
    let mut rot_sum = Vector3::zeros();
    let mut residual_speed2 = 0.0;
    for k in 0..m - 1 {
        let (rot, res) = kabsch(&centred[k], &centred[k + 1]);
        rot_sum += rot.scaled_axis();
        let dt = times[k + 1] - times[k];
        residual_speed2 += (res / dt).powi(2);
    }
    let nonrigid_speed_um_s = (residual_speed2 / (m - 1) as f64).sqrt();
    let centroid_speed = if window_s > 0.0 {
        (centroids[m - 1] - centroids[0]).norm() / window_s
    } else {
        0.0
    };
    let nonrigid_ratio = if centroid_speed > 0.0 {
        nonrigid_speed_um_s / centroid_speed
    } else {
        f64::NAN
    };
    // circulation axis: mean rotation vector, oriented with positive z (z when negligible)
    let mut n = if rot_sum.norm() > 1e-9 {
        rot_sum.normalize()
    } else {
        Vector3::z()
    };
    if n.z < 0.0 || (n.z == 0.0 && n.y + n.x < 0.0) {
        n = -n;
    }
    let helper = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = (helper - n * n.dot(&helper)).normalize();
    let e2 = n.cross(&e1);

    // labels' rotation rate about n: mean over vertices away from the axis
    let nv = frames[0].vertices.len();
    let rho: Vec<f64> = (0..nv)
        .map(|i| {
            centred
                .iter()
                .map(|f| (f[i].dot(&e1)).hypot(f[i].dot(&e2)))
                .sum::<f64>()
                / m as f64
        })
        .collect();
    let rho_cut = 0.3 * median(&rho);
    let mut rates = Vec::new();
    for i in 0..nv {
        if rho[i] < rho_cut || rho[i] <= 0.0 {
            continue;
        }
        let psi: Vec<f64> = centred
            .iter()
            .map(|f| f[i].dot(&e2).atan2(f[i].dot(&e1)))
            .collect();
        rates.push(slope(&times, &unwrap(&psi, 2.0 * PI)));
    }
    // the mean (not the median): for points circulating on a closed orbit at a uniformly
    // distributed phase, the mean of the instantaneous angular rates is exactly the circulation
    // rate even when each point's rate varies along its orbit (int psi'(phi) dphi = 2 pi), so
    // windows shorter than a turn are not biased
    let label_rate_rad_s = if rates.is_empty() {
        0.0
    } else {
        rates.iter().sum::<f64>() / rates.len() as f64
    };

    // shape orientation about n and about z (label-free)
    let gyr: Vec<Matrix3<f64>> = frames
        .iter()
        .zip(&centroids)
        .map(|(f, c)| surface_gyration(f.vertices, triangles, *c))
        .collect();
    let orientation_rate = |a: &Vector3<f64>, b: &Vector3<f64>| -> (f64, f64) {
        let mut th = Vec::with_capacity(m);
        let mut aniso_min = f64::INFINITY;
        for g in &gyr {
            let (t, an) = in_plane_orientation(g, a, b);
            th.push(t);
            aniso_min = aniso_min.min(an);
        }
        if aniso_min < 0.05 {
            return (0.0, 0.0); // (nearly) axisymmetric about the normal: rotation invisible
        }
        let th = unwrap(&th, PI);
        (slope(&times, &th), th[m - 1] - th[0])
    };
    let (shape_rate_rad_s, _) = orientation_rate(&e1, &e2);
    let (tumble_rate, tumble_angle) = orientation_rate(&Vector3::x(), &Vector3::y());

    Ok(Evidence {
        offset_y_um: oy,
        offset_z_um: oz,
        offset_r_um: oy.hypot(oz),
        r_eff_um,
        mirror_y_um: my,
        mirror_z_um: mz,
        mirror_y_rel: my / r_eff_um,
        mirror_z_rel: mz / r_eff_um,
        mirror_fold_um: mf,
        mirror_fold_rel: mf / r_eff_um,
        fold_angle_deg: fold_deg,
        tt_axis: [n.x, n.y, n.z],
        label_rate_rad_s,
        shape_rate_rad_s,
        tt_frequency_hz: (label_rate_rad_s - shape_rate_rad_s).abs() / (2.0 * PI),
        tumbling_frequency_hz: tumble_rate / (2.0 * PI),
        tumbling_turns: tumble_angle / (2.0 * PI),
        nonrigid_speed_um_s,
        nonrigid_ratio,
        window_s,
        n_frames: m,
    })
}

/// Decide the label and flags from measured evidence (the table in the module docs).
pub fn decide(e: &Evidence, cfg: &ClassifyConfig) -> Classification {
    let centred = e.offset_r_um <= cfg.centred_um;
    let folded = e.mirror_fold_rel <= cfg.symmetric_rel;
    let symmetric = e.mirror_y_rel.max(e.mirror_z_rel) <= cfg.symmetric_rel;
    let tank_treading = e.tt_frequency_hz * e.window_s >= cfg.min_tt_turns;
    let tumbling = e.tumbling_turns.abs() >= cfg.min_tumble_turns;
    let rigid = e.nonrigid_ratio <= cfg.rigid_rel && !tank_treading && !tumbling;
    let shape = if centred && (folded || rigid) {
        FinalShape::Croissant
    } else if !centred && !symmetric && (tank_treading || tumbling) {
        FinalShape::Slipper
    } else {
        FinalShape::Other
    };
    Classification {
        shape,
        tank_treading,
        tumbling,
        evidence: e.clone(),
    }
}

/// Measure and decide: the label of the cell over `frames`.
pub fn classify(
    frames: &[Frame<'_>],
    triangles: &[[usize; 3]],
    cfg: &ClassifyConfig,
) -> Result<Classification, ClassifyError> {
    Ok(decide(&measure(frames, triangles, cfg)?, cfg))
}
