//! Figures of the simulations from results.h5: phase diagrams (paper Fig. 5), steady radial position and slipper extents vs velocity (Fig. 6), 3D shape views and mid-plane cross-sections (Fig. 1 c, d, f, g).
//!
//! - Phase diagram per start shape: [`PhaseDiagramFigure`] of the prediction's figures (one
//!   symbol per run, r_trans line), fed with the phase points and thresholds of the results
//!   file alone ([`crate::simulated`]).
//! - [`RadialFigure`] (Fig. 6a): per start shape and per class (non-tank-treading
//!   croissant, tank-treading croissant, slipper) and velocity column, the mean
//!   steady radial position weighted by the observation time in the steady
//!   state (`evidence_steady_duration_s`, as in the paper; weight 1 when absent);
//!   vertical bars: overall min and max radial position (`evidence_radial_min_um`,
//!   `evidence_radial_max_um`), horizontal bars: min and max velocity.
//! - [`ExtentsFigure`] (Fig. 6b): slippers' bounding-box extents along x, y, z
//!   (`evidence_extent_<axis>_{mean,min,max}_um`), weighted the same way.
//! - [`ShapeFigure`] (Fig. 1 c, d, f, g): the last snapshot of one run, as an
//!   oblique orthographic view and a view along z (the camera's), both with
//!   Lambert shading and painter's ordering, and the cross-section with the
//!   channel mid-plane `z = 0` (the experiment's focal plane) with the walls.
//!
//! [`write_figures`] draws all of them into a folder.

use super::prediction::PhaseDiagramFigure;
use super::{chart_xy, draw_legend, draw_x_error_bar, draw_y_error_bar, shape_colour, DrawResult, Figure, FONT_FAMILY};
use crate::error::AnalysisError;
use crate::simulated::phase::{bin_velocities, phase_points, start_shapes, DEFAULT_VELOCITY_REL_TOL};
use crate::simulated::threshold::thresholds;
use plotters::coord::Shift;
use plotters::prelude::*;
use rbc_schema::results::{read_runs, read_snapshots, FinalShape, RunRecord};
use std::path::{Path, PathBuf};

/// Class of a steady state in Fig. 6a.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum SteadyClass {
    Croissant,
    TankTreadingCroissant,
    Slipper,
}

impl SteadyClass {
    pub fn label(self) -> &'static str {
        match self {
            SteadyClass::Croissant => "croissant",
            SteadyClass::TankTreadingCroissant => "TT croissant",
            SteadyClass::Slipper => "slipper",
        }
    }
}

/// One point of Fig. 6: a velocity column of one start shape and class, weighted over its runs.
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnMean {
    pub start_shape: String,
    pub class: SteadyClass,
    pub n_runs: usize,
    /// Weighted mean velocity and the overall min/max (mm/s).
    pub velocity_mm_s: f64,
    pub velocity_min_mm_s: f64,
    pub velocity_max_mm_s: f64,
    /// Weighted mean of the quantity and its overall min/max.
    pub value: f64,
    pub min: f64,
    pub max: f64,
}

/// A per-run quantity `(mean, min, max)`, `None` when the run does not carry it.
pub type Quantity = dyn Fn(&RunRecord) -> Option<(f64, f64, f64)>;

/// Weighted column means of `value(run) -> (mean, min, max)` for the finished steady/periodic runs.
///
/// Weight = `evidence_steady_duration_s` (the paper weights by the observation time in the
/// steady state), 1 when absent. Columns are velocity bins (relative tolerance `rel_tol`)
/// per start shape and class; runs without the quantity are left out.
pub fn column_means(
    runs: &[RunRecord],
    rel_tol: f64,
    classes: &[SteadyClass],
    value: &Quantity,
) -> Vec<ColumnMean> {
    struct Item<'a> {
        shape: &'a str,
        class: SteadyClass,
        u: f64,
        umin: f64,
        umax: f64,
        w: f64,
        v: (f64, f64, f64),
    }
    let mut items = Vec::new();
    for r in runs {
        let (Some(a), Some(s)) = (&r.attrs, &r.summary) else {
            continue;
        };
        if s.status == rbc_schema::results::RunStatus::Unsteady || s.mean_velocity_mm_s <= 0.0 {
            continue;
        }
        let class = match (s.final_shape, s.tank_treading) {
            (FinalShape::Croissant, false) => SteadyClass::Croissant,
            (FinalShape::Croissant, true) => SteadyClass::TankTreadingCroissant,
            (FinalShape::Slipper, _) => SteadyClass::Slipper,
            (FinalShape::Other, _) => continue,
        };
        if !classes.contains(&class) {
            continue;
        }
        let Some(v) = value(r) else { continue };
        let w = s
            .evidence
            .get("steady_duration_s")
            .copied()
            .filter(|w| *w > 0.0)
            .unwrap_or(1.0);
        items.push(Item {
            shape: &a.start_shape,
            class,
            u: s.mean_velocity_mm_s,
            umin: s.min_velocity_mm_s,
            umax: s.max_velocity_mm_s,
            w,
            v,
        });
    }
    let mut out = Vec::new();
    let mut keys: Vec<(&str, SteadyClass)> = items.iter().map(|i| (i.shape, i.class)).collect();
    keys.sort();
    keys.dedup();
    for (shape, class) in keys {
        let group: Vec<&Item> = items
            .iter()
            .filter(|i| i.shape == shape && i.class == class)
            .collect();
        let u: Vec<f64> = group.iter().map(|i| i.u).collect();
        let bins = bin_velocities(&u, rel_tol);
        for b in 0..=bins.iter().copied().max().unwrap_or(0) {
            let col: Vec<&&Item> = group
                .iter()
                .zip(&bins)
                .filter(|(_, &bb)| bb == b)
                .map(|(i, _)| i)
                .collect();
            if col.is_empty() {
                continue;
            }
            let wsum: f64 = col.iter().map(|i| i.w).sum();
            out.push(ColumnMean {
                start_shape: shape.to_string(),
                class,
                n_runs: col.len(),
                velocity_mm_s: col.iter().map(|i| i.w * i.u).sum::<f64>() / wsum,
                velocity_min_mm_s: col.iter().map(|i| i.umin).fold(f64::INFINITY, f64::min),
                velocity_max_mm_s: col.iter().map(|i| i.umax).fold(f64::NEG_INFINITY, f64::max),
                value: col.iter().map(|i| i.w * i.v.0).sum::<f64>() / wsum,
                min: col.iter().map(|i| i.v.1).fold(f64::INFINITY, f64::min),
                max: col.iter().map(|i| i.v.2).fold(f64::NEG_INFINITY, f64::max),
            });
        }
    }
    out.sort_by(|a, b| {
        (a.start_shape.as_str(), a.class)
            .cmp(&(b.start_shape.as_str(), b.class))
            .then(a.velocity_mm_s.total_cmp(&b.velocity_mm_s))
    });
    out
}

fn evidence(r: &RunRecord, key: &str) -> Option<f64> {
    r.summary.as_ref()?.evidence.get(key).copied()
}

/// Radial position of a run: mean, and min/max from the evidence (mean when absent).
pub fn radial_of(r: &RunRecord) -> Option<(f64, f64, f64)> {
    let m = r.summary.as_ref()?.mean_radial_um;
    Some((
        m,
        evidence(r, "radial_min_um").unwrap_or(m),
        evidence(r, "radial_max_um").unwrap_or(m),
    ))
}

/// The membrane's tank-treading frequency of a run (Hz; mean = min = max), from the evidence its
/// label was decided on (`tt_frequency_hz`: the membrane's circulation relative to the shape over
/// the classifier's window, `rbc_solver::classify`).
pub fn tank_treading_of(r: &RunRecord) -> Option<(f64, f64, f64)> {
    let f = evidence(r, "tt_frequency_hz")?;
    Some((f, f, f))
}

/// The shape's tumbling frequency of a run that tumbles (Hz, the magnitude; mean = min = max),
/// from the evidence its label was decided on (`tumbling_frequency_hz`: the rotation of the
/// shape's orientation in the x-y plane about z over the classifier's window,
/// `rbc_solver::classify`); `None` for a run that does not tumble. The paper's slippers tumble
/// below ~0.7 mm/s, "the cell rotates around the z-axis while approximately preserving its shape".
pub fn tumbling_of(r: &RunRecord) -> Option<(f64, f64, f64)> {
    if !r.summary.as_ref()?.tumbling {
        return None;
    }
    let f = evidence(r, "tumbling_frequency_hz")?.abs();
    Some((f, f, f))
}

/// Extent of a run along axis `x`, `y` or `z` (mean, min, max), from the evidence.
pub fn extent_of(r: &RunRecord, axis: &str) -> Option<(f64, f64, f64)> {
    let m = evidence(r, &format!("extent_{axis}_mean_um"))?;
    Some((
        m,
        evidence(r, &format!("extent_{axis}_min_um")).unwrap_or(m),
        evidence(r, &format!("extent_{axis}_max_um")).unwrap_or(m),
    ))
}

fn start_colour(shape: &str) -> RGBColor {
    match shape {
        "discocyte" => RGBColor(0x2c, 0xa0, 0x2c),
        "croissant" => shape_colour("croissant"),
        "slipper" => shape_colour("slipper"),
        _ => RGBColor(0x94, 0x67, 0xbd),
    }
}

/// A marker of Fig. 6: a filled or hollow circle, a triangle or a square.
#[derive(Debug, Clone, Copy)]
pub(super) enum Marker {
    Circle { filled: bool },
    Triangle,
    Square,
}

impl SteadyClass {
    /// Its marker: filled circle (croissant), hollow circle (tank-treading croissant), triangle
    /// (slipper).
    pub(super) fn marker(self) -> Marker {
        match self {
            SteadyClass::Croissant => Marker::Circle { filled: true },
            SteadyClass::TankTreadingCroissant => Marker::Circle { filled: false },
            SteadyClass::Slipper => Marker::Triangle,
        }
    }
}

/// One series of a chart of column means: its legend, colour, marker and points.
pub(super) struct Series<'a> {
    pub label: String,
    pub colour: RGBColor,
    pub marker: Marker,
    pub points: &'a [ColumnMean],
}

/// A chart of column means with bars both ways, each series joined by a faint line, on axes
/// reaching `u_max` (mm/s) and `y_max`.
pub(super) fn draw_panel<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, caption: &str, y_desc: &str, (u_max, y_max): (f64, f64), series: &[Series]) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let mut chart = chart_xy(root, caption, (0f64..u_max, "mean cell velocity u (mm/s)"), (0f64..y_max, y_desc))?;
    for s in series.iter().filter(|s| !s.points.is_empty()) {
        let c = s.colour;
        for p in s.points {
            draw_y_error_bar(&mut chart, p.velocity_mm_s, (p.min, p.max), c.stroke_width(1), 4)?;
            draw_x_error_bar(&mut chart, (p.velocity_min_mm_s, p.velocity_max_mm_s), p.value, c.stroke_width(1), 4)?;
        }
        chart.draw_series(LineSeries::new(s.points.iter().map(|p| (p.velocity_mm_s, p.value)), c.mix(0.5)))?;
        let xy = s.points.iter().map(|p| (p.velocity_mm_s, p.value));
        let drawn = match s.marker {
            Marker::Circle { filled } => chart.draw_series(xy.map(|p| Circle::new(p, 5, if filled { c.filled() } else { c.stroke_width(2) })))?,
            Marker::Triangle => chart.draw_series(xy.map(|p| TriangleMarker::new(p, 6, c.filled())))?,
            Marker::Square => chart.draw_series(xy.map(|p| EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], c.filled())))?,
        };
        let marker = s.marker;
        drawn.label(s.label.clone()).legend(move |(x, y)| match marker {
            Marker::Circle { filled } => Circle::new((x + 8, y), 4, if filled { c.filled() } else { c.stroke_width(2) }).into_dyn(),
            Marker::Triangle => TriangleMarker::new((x + 8, y), 5, c.filled()).into_dyn(),
            Marker::Square => Rectangle::new([(x + 4, y - 4), (x + 12, y + 4)], c.filled()).into_dyn(),
        });
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

/// [`draw_panel`] of `series` = (label, colour, class, points), each with its class's marker, on
/// axes reaching 1.08 x the largest velocity (at least 1 mm/s) and 1.2 x the largest value (at
/// least 0.5).
fn draw_columns<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    caption: &str,
    y_desc: &str,
    series: &[(String, RGBColor, SteadyClass, Vec<ColumnMean>)],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let all: Vec<&ColumnMean> = series.iter().flat_map(|s| s.3.iter()).collect();
    let u_max = all
        .iter()
        .map(|c| c.velocity_max_mm_s.max(c.velocity_mm_s))
        .fold(1.0, f64::max)
        * 1.08;
    let y_max = all.iter().map(|c| c.max.max(c.value)).fold(0.5, f64::max) * 1.2;
    let series: Vec<Series> = series.iter().map(|(label, colour, class, points)| Series { label: label.clone(), colour: *colour, marker: class.marker(), points }).collect();
    draw_panel(root, caption, y_desc, (u_max, y_max), &series)
}

/// Steady radial position vs velocity (paper Fig. 6a).
pub struct RadialFigure {
    pub columns: Vec<ColumnMean>,
}

impl RadialFigure {
    pub fn new(runs: &[RunRecord]) -> Self {
        let classes = [
            SteadyClass::Croissant,
            SteadyClass::TankTreadingCroissant,
            SteadyClass::Slipper,
        ];
        RadialFigure {
            columns: column_means(
                runs,
                DEFAULT_VELOCITY_REL_TOL,
                &classes,
                &radial_of,
            ),
        }
    }
}

impl Figure for RadialFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let mut keys: Vec<(String, SteadyClass)> = self
            .columns
            .iter()
            .map(|c| (c.start_shape.clone(), c.class))
            .collect();
        keys.dedup();
        let series: Vec<_> = keys
            .into_iter()
            .map(|(shape, class)| {
                let pts = self
                    .columns
                    .iter()
                    .filter(|c| c.start_shape == shape && c.class == class)
                    .cloned()
                    .collect();
                (
                    format!("{} (start: {shape})", class.label()),
                    start_colour(&shape),
                    class,
                    pts,
                )
            })
            .collect();
        draw_columns(
            root,
            "Steady radial position",
            "radial centroid position (um)",
            &series,
        )
    }
}

/// Extents of the slippers along x, y, z vs velocity (paper Fig. 6b).
pub struct ExtentsFigure {
    /// Columns for x, y and z (all start shapes together, as in the paper).
    pub axes: [Vec<ColumnMean>; 3],
}

impl ExtentsFigure {
    pub fn new(runs: &[RunRecord]) -> Self {
        // all start shapes in one column: the paper shows the slippers of Fig. 6a together
        let merged: Vec<RunRecord> = runs
            .iter()
            .map(|r| {
                let mut r = r.clone();
                if let Some(a) = r.attrs.as_mut() {
                    a.start_shape = "all".into();
                }
                r
            })
            .collect();
        let tol = DEFAULT_VELOCITY_REL_TOL;
        let f = |axis: &'static str| {
            column_means(&merged, tol, &[SteadyClass::Slipper], &move |r| {
                extent_of(r, axis)
            })
        };
        ExtentsFigure {
            axes: [f("x"), f("y"), f("z")],
        }
    }
}

impl Figure for ExtentsFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let colours = [
            RGBColor(0xd6, 0x27, 0x28),
            RGBColor(0x1f, 0x77, 0xb4),
            RGBColor(0x2c, 0xa0, 0x2c),
        ];
        let names = ["length (x)", "extent y (width)", "extent z (height)"];
        let series: Vec<_> = (0..3)
            .map(|k| {
                (
                    names[k].to_string(),
                    colours[k],
                    SteadyClass::Slipper,
                    self.axes[k].clone(),
                )
            })
            .collect();
        draw_columns(root, "Slipper extents", "bounding-box extent (um)", &series)
    }
}

/// One run's final shape: oblique view, view along z, mid-plane cross-section (paper Fig. 1 c, d, f, g).
pub struct ShapeFigure {
    pub title: String,
    /// Vertices (um) relative to nothing: the channel frame.
    pub vertices: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Channel width and height (um), for the walls.
    pub width_y_um: f64,
    pub height_z_um: f64,
    /// Colour of the surface.
    pub colour: RGBColor,
}

/// Segments of the intersection of a triangle mesh with the plane `z = z0` (in x, y).
pub fn cross_section(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    z0: f64,
) -> Vec<[(f64, f64); 2]> {
    let mut out = Vec::new();
    for t in triangles {
        let p: Vec<[f64; 3]> = t.iter().map(|&i| vertices[i as usize]).collect();
        let mut pts = Vec::with_capacity(2);
        for k in 0..3 {
            let (a, b) = (p[k], p[(k + 1) % 3]);
            let (da, db) = (a[2] - z0, b[2] - z0);
            // half-open rule so that a vertex exactly on the plane is counted once per edge pair
            if (da < 0.0) != (db < 0.0) {
                let s = da / (da - db);
                pts.push((a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])));
            }
        }
        if pts.len() == 2 {
            out.push([pts[0], pts[1]]);
        }
    }
    out
}

impl ShapeFigure {
    /// Projected, shaded triangles seen along `view` (from the viewer towards the scene), drawn far to near.
    /// Returns (2D polygon in the view's (right, up) coordinates, shade in 0..1).
    fn projected(&self, rot: &Rot) -> Vec<([(f64, f64); 3], f64)> {
        let c = centroid(&self.vertices);
        let l = [-0.3, 0.4, 1.0];
        let ln = dot(l, l).sqrt();
        let light = [l[0] / ln, l[1] / ln, l[2] / ln]; // in view coordinates: from upper left, towards the viewer
        let v: Vec<V3> = self
            .vertices
            .iter()
            .map(|p| apply(rot, sub(*p, c)))
            .collect();
        let mut tris: Vec<(f64, Triangle2, f64)> = self
            .triangles
            .iter()
            .map(|t| {
                let (a, b, d) = (v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]);
                let n = cross(sub(b, a), sub(d, a));
                let nn = dot(n, n).sqrt();
                let cos = if nn > 0.0 { dot(n, light) / nn } else { 0.0 };
                let shade = 0.25 + 0.75 * cos.abs();
                let depth = (a[2] + b[2] + d[2]) / 3.0;
                (depth, [(a[0], a[1]), (b[0], b[1]), (d[0], d[1])], shade)
            })
            .collect();
        // view coordinates: z points towards the viewer, so draw increasing z (far first)
        tris.sort_by(|p, q| p.0.total_cmp(&q.0));
        tris.into_iter().map(|(_, p, s)| (p, s)).collect()
    }

    fn draw_view<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        caption: &str,
        rot: &Rot,
        half: f64,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let mut chart = ChartBuilder::on(area)
            .caption(caption, (FONT_FAMILY, 16))
            .margin(8)
            .build_cartesian_2d(-half..half, -half..half)?;
        let base = self.colour;
        let tris = self.projected(rot);
        chart.draw_series(tris.iter().map(|(p, s)| {
            let col = RGBColor(
                (base.0 as f64 * s) as u8,
                (base.1 as f64 * s) as u8,
                (base.2 as f64 * s) as u8,
            );
            Polygon::new(p.to_vec(), col.filled())
        }))?;
        chart.draw_series(
            tris.iter()
                .map(|(p, _)| PathElement::new(vec![p[0], p[1], p[2], p[0]], BLACK.mix(0.15))),
        )?;
        // 2 um scale bar (as in the paper's figure)
        let y = -0.9 * half;
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(0.5 * half, y), (0.5 * half + 2.0, y)],
            BLACK.stroke_width(3),
        )))?;
        chart.draw_series(std::iter::once(Text::new(
            "2 um",
            (0.5 * half, y + 0.08 * half),
            (FONT_FAMILY, 13),
        )))?;
        Ok(())
    }
}

/// Small 3-vector helpers (plain arrays: this crate does not depend on nalgebra for one figure).
type V3 = [f64; 3];
/// A projected triangle (view coordinates, um).
type Triangle2 = [(f64, f64); 3];
/// A rotation as a row-major 3 x 3 matrix.
type Rot = [[f64; 3]; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn apply(r: &Rot, v: V3) -> V3 {
    [dot(r[0], v), dot(r[1], v), dot(r[2], v)]
}
fn matmul(a: &Rot, b: &Rot) -> Rot {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}
/// Rotation by `angle` (rad) about the coordinate axis `axis` (0 = x, 2 = z).
fn rot_axis(axis: usize, angle: f64) -> Rot {
    let (s, c) = angle.sin_cos();
    match axis {
        0 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
        1 => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
        _ => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
    }
}
const IDENTITY: Rot = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn centroid(v: &[[f64; 3]]) -> V3 {
    let n = v.len().max(1) as f64;
    let s = v
        .iter()
        .fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
    [s[0] / n, s[1] / n, s[2] / n]
}

impl Figure for ShapeFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (title_area, body) = root.split_vertically(36);
        title_area.titled(&self.title, (FONT_FAMILY, 20))?;
        let panels = body.split_evenly((1, 3));
        let half = 0.5 * self.width_y_um.max(self.height_z_um) + 0.5;
        // oblique: looking from above (+z), from the side (-y) and from upstream (-x)
        let oblique = matmul(&rot_axis(0, -0.9), &rot_axis(2, -0.5));
        self.draw_view(&panels[0], "3D view (oblique)", &oblique, half)?;
        self.draw_view(&panels[1], "view along z (camera)", &IDENTITY, half)?;

        // cross-section with the channel mid-plane z = 0, x relative to the centroid
        let c = centroid(&self.vertices);
        let hw = 0.5 * self.width_y_um;
        let mut chart = ChartBuilder::on(&panels[2])
            .caption("mid-plane cross-section z = 0", (FONT_FAMILY, 16))
            .margin(8)
            .x_label_area_size(25)
            .y_label_area_size(30)
            .build_cartesian_2d(-half..half, -half..half)?;
        chart
            .configure_mesh()
            .x_desc("x - x_c (um)")
            .y_desc("y (um)")
            .label_style((FONT_FAMILY, 11))
            .light_line_style(WHITE)
            .draw()?;
        for y in [-hw, hw] {
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(-half, y), (half, y)],
                BLACK.stroke_width(2),
            )))?;
        }
        let seg = cross_section(&self.vertices, &self.triangles, 0.0);
        chart.draw_series(seg.iter().map(|s| {
            PathElement::new(
                vec![(s[0].0 - c[0], s[0].1), (s[1].0 - c[0], s[1].1)],
                self.colour.stroke_width(2),
            )
        }))?;
        Ok(())
    }
}

/// What [`write_figures`] wrote.
#[derive(Debug, Clone, Default)]
pub struct FiguresWritten {
    pub files: Vec<PathBuf>,
    pub warnings: Vec<String>,
}

/// Channel width and height from a run's scene text (`walls.width_y_um`, `walls.height_z_um`); the paper's 12 x 10 um otherwise.
pub fn channel_size(scene: &str) -> (f64, f64) {
    let t: Option<toml::Table> = scene.parse().ok();
    let get = |k: &str| {
        t.as_ref()
            .and_then(|t| t.get("walls"))
            .and_then(|w| w.get(k))
            .and_then(|v| v.as_float())
    };
    (
        get("width_y_um").unwrap_or(12.0),
        get("height_z_um").unwrap_or(10.0),
    )
}

/// The figure names [`write_figures`] draws (without `.png` / `.svg`): `phase_diagram_<start>`,
/// `radial_position`, `slipper_extents`, `shape_croissant`, `shape_slipper`.
pub fn is_figure_name(name: &str) -> bool {
    let Some(stem) = name.strip_suffix(".png").or_else(|| name.strip_suffix(".svg")) else {
        return false;
    };
    stem.starts_with("phase_diagram_")
        || matches!(stem, "radial_position" | "slipper_extents" | "shape_croissant" | "shape_slipper")
}

/// Draw every figure of `results` into the folder `out`: `phase_diagram_<start>`,
/// `radial_position`, `slipper_extents`, `shape_croissant`, `shape_slipper` (each PNG + SVG),
/// replacing the figures of an earlier call as one set ([`rbc_schema::output_set`]: a failure
/// leaves them as they were; a figure not drawn this time is removed). Other files in `out`
/// are left alone.
///
/// The shape views show, for each final shape, the steady or periodic run whose mean
/// velocity is closest to the paper's examples (croissant 1.1 mm/s, slipper 5.2 mm/s).
pub fn write_figures(results: &Path, out: &Path) -> Result<FiguresWritten, AnalysisError> {
    let (mut w, files) = rbc_schema::output_set::write_set(out, is_figure_name, |dir| draw_figures(results, dir))?;
    w.files = files;
    Ok(w)
}

/// Draw the figures of [`write_figures`] into `out`.
fn draw_figures(results: &Path, out: &Path) -> Result<FiguresWritten, AnalysisError> {
    let runs = read_runs(results)?;
    let mut w = FiguresWritten::default();
    let (points, skipped) = phase_points(&runs);
    let th = thresholds(&points, DEFAULT_VELOCITY_REL_TOL);
    for s in &skipped {
        w.warnings.push(format!(
            "{}: run {} left out: {}",
            results.display(),
            s.run_id,
            s.reason
        ));
    }
    if points.is_empty() {
        return Err(AnalysisError::Input {
            path: results.into(),
            message: format!(
                "no steady or periodic run among {} runs: nothing to draw",
                runs.len()
            ),
        });
    }
    for shape in start_shapes(&points) {
        w.files.extend(PhaseDiagramFigure::new(&points, &th, &shape).save(
            out,
            &format!("phase_diagram_{shape}"),
            (900, 650),
        )?);
    }
    w.files
        .extend(RadialFigure::new(&runs).save(out, "radial_position", (900, 650))?);
    let ext = ExtentsFigure::new(&runs);
    if ext.axes.iter().any(|a| !a.is_empty()) {
        w.files
            .extend(ext.save(out, "slipper_extents", (900, 650))?);
    } else {
        w.warnings
            .push("no slipper with extents evidence: slipper_extents not drawn".into());
    }
    for (shape, u_paper) in [(FinalShape::Croissant, 1.1), (FinalShape::Slipper, 5.2)] {
        let best = points
            .iter()
            .filter(|p| p.final_shape == shape)
            .min_by(|a, b| {
                (a.velocity_mm_s - u_paper)
                    .abs()
                    .total_cmp(&(b.velocity_mm_s - u_paper).abs())
            });
        let Some(p) = best else {
            w.warnings.push(format!(
                "no {} run: shape_{} not drawn",
                shape.as_str(),
                shape.as_str()
            ));
            continue;
        };
        let snaps = read_snapshots(results, &p.run_id)?;
        let Some(last) = snaps.vertices_um.last() else {
            w.warnings.push(format!(
                "run {} has no snapshot: shape_{} not drawn",
                p.run_id,
                shape.as_str()
            ));
            continue;
        };
        let scene = runs
            .iter()
            .find(|r| r.run_id == p.run_id)
            .and_then(|r| r.attrs.as_ref())
            .map(|a| a.scene.clone())
            .unwrap_or_default();
        let (width_y_um, height_z_um) = channel_size(&scene);
        let fig = ShapeFigure {
            title: format!(
                "{} (run {}, u = {:.2} mm/s)",
                shape.as_str(),
                p.run_id,
                p.velocity_mm_s
            ),
            vertices: last.clone(),
            triangles: snaps.triangles.clone(),
            width_y_um,
            height_z_um,
            colour: shape_colour(shape.as_str()),
        };
        w.files
            .extend(fig.save(out, &format!("shape_{}", shape.as_str()), (1500, 560))?);
    }
    Ok(w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rbc_schema::results::{RunAttrs, RunStatus, RunSummary};
    use std::collections::BTreeMap;

    fn record(
        id: &str,
        shape: FinalShape,
        tt: bool,
        u: f64,
        radial: f64,
        weight: f64,
    ) -> RunRecord {
        let mut evidence = BTreeMap::new();
        evidence.insert("steady_duration_s".to_string(), weight);
        evidence.insert("radial_min_um".to_string(), radial - 0.1);
        evidence.insert("radial_max_um".to_string(), radial + 0.1);
        RunRecord {
            run_id: id.into(),
            status: RunStatus::Periodic,
            attrs: Some(RunAttrs {
                start_shape: "discocyte".into(),
                r_init_um: 1.0,
                y_init_um: 0.0,
                z_init_um: 0.0,
                lambda: 5.0,
                scene: String::new(),
            }),
            summary: Some(RunSummary {
                status: RunStatus::Periodic,
                final_shape: shape,
                tank_treading: tt,
                tumbling: false,
                mean_velocity_mm_s: u,
                min_velocity_mm_s: u - 0.1,
                max_velocity_mm_s: u + 0.1,
                mean_radial_um: radial,
                mean_y_um: radial,
                mean_z_um: 0.0,
                evidence,
            }),
            failure: None,
            not_run: None,
            copied_from: None,
            transits: Vec::new(),
            n_samples: 0,
            n_snapshots: 0,
        }
    }

    #[test]
    fn column_means_weight_by_steady_time_and_separate_classes() {
        let runs = vec![
            record("a", FinalShape::Slipper, true, 5.0, 1.0, 1.0),
            record("b", FinalShape::Slipper, true, 5.1, 2.0, 3.0),
            record("c", FinalShape::Slipper, true, 8.0, 1.5, 1.0),
            record("d", FinalShape::Croissant, false, 5.0, 0.05, 1.0),
            record("e", FinalShape::Croissant, true, 5.0, 0.3, 1.0),
            record("f", FinalShape::Other, false, 5.0, 0.7, 1.0),
        ];
        let fig = RadialFigure::new(&runs);
        let slip: Vec<&ColumnMean> = fig
            .columns
            .iter()
            .filter(|c| c.class == SteadyClass::Slipper)
            .collect();
        assert_eq!(slip.len(), 2);
        // (1 * 1.0 + 3 * 2.0) / 4 and (1 * 5.0 + 3 * 5.1) / 4
        assert!(
            (slip[0].value - 1.75).abs() < 1e-12 && (slip[0].velocity_mm_s - 5.075).abs() < 1e-12
        );
        assert_eq!((slip[0].min, slip[0].max, slip[0].n_runs), (0.9, 2.1, 2));
        assert!(
            (slip[0].velocity_min_mm_s - 4.9).abs() < 1e-12
                && (slip[0].velocity_max_mm_s - 5.2).abs() < 1e-12
        );
        assert_eq!(
            fig.columns
                .iter()
                .filter(|c| c.class == SteadyClass::Croissant)
                .count(),
            1
        );
        assert_eq!(
            fig.columns
                .iter()
                .filter(|c| c.class == SteadyClass::TankTreadingCroissant)
                .count(),
            1
        );
        assert_eq!(fig.columns.len(), 4, "`other` is not drawn");
    }

    #[test]
    fn cross_section_of_a_sphere_is_a_closed_circle() {
        // latitude-longitude sphere of radius 2 whose rings avoid z = 0 (no vertex on the plane)
        let n = 16; // latitude-longitude sphere built here to keep this crate free of the solver
        let mut v = vec![[0.0, 0.0, 2.0]];
        for i in 1..n {
            let th = std::f64::consts::PI * (i as f64 - 0.5) / (n as f64 - 1.0);
            for j in 0..2 * n {
                let ph = std::f64::consts::PI * j as f64 / n as f64;
                v.push([
                    2.0 * th.sin() * ph.cos(),
                    2.0 * th.sin() * ph.sin(),
                    2.0 * th.cos(),
                ]);
            }
        }
        v.push([0.0, 0.0, -2.0]);
        let ring = |i: usize, j: usize| (1 + (i - 1) * 2 * n + j % (2 * n)) as u32;
        let mut t = Vec::new();
        for j in 0..2 * n {
            t.push([0, ring(1, j), ring(1, j + 1)]);
            for i in 1..n - 1 {
                t.push([ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)]);
                t.push([ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)]);
            }
            t.push([(v.len() - 1) as u32, ring(n - 1, j + 1), ring(n - 1, j)]);
        }
        let seg = cross_section(&v, &t, 0.0);
        // the equator z = 0 cuts 2n quads (2 triangles each): 4n segments
        assert_eq!(seg.len(), 4 * n);
        let len: f64 = seg
            .iter()
            .map(|s| (s[1].0 - s[0].0).hypot(s[1].1 - s[0].1))
            .sum();
        // inscribed polygon between the two rings next to the equator: perimeter 2 pi r' (1 - O(1/n^2))
        let r_in = 2.0 * (std::f64::consts::PI * 0.5 / (n as f64 - 1.0)).cos();
        assert!(
            len < 2.0 * std::f64::consts::PI * 2.0
                && len > 0.99 * 2.0 * std::f64::consts::PI * r_in,
            "{len}"
        );
        for s in &seg {
            for p in s {
                let r = p.0.hypot(p.1);
                assert!(r <= 2.0 + 1e-12 && r > 0.98 * r_in, "{r}");
            }
        }
    }

    #[test]
    fn channel_size_from_the_scene() {
        assert_eq!(
            channel_size(
                "[walls]\nkind = \"periodic-channel\"\nwidth_y_um = 11.5\nheight_z_um = 9.0\n"
            ),
            (11.5, 9.0)
        );
        assert_eq!(channel_size(""), (12.0, 10.0));
    }
}
