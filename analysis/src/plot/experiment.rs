//! Figures of the experiment (paper Fig. 3a, 3b, 4 and per-shape densities).
//!
//! [`write_figures`] writes, for every measured position (10 mm is the paper's
//! Fig. 3, 0 mm the entrance of Fig. 4):
//! - `fractions_vs_velocity_<pos>mm`: fractions of croissants, slippers and
//!   others against the mean cell velocity of each pressure group (Fig. 3a);
//!   horizontal error bars = velocity standard deviation, vertical error bars =
//!   Wilson 95 % interval of the fraction; pressure drops labelled along the top.
//! - `y_density_<pos>mm`: the y-density of all isolated cells, one curve per
//!   pressure drop, stacked with a vertical offset (Fig. 3b at 10 mm, Fig. 4 at
//!   0 mm); dashed lines at the walls (y = +-6 um), ticks below each curve at the
//!   individual cells' y.
//! - `y_density_by_shape_<pos>mm`: the same stack with each shape's contribution
//!   (fraction x shape density) drawn in its colour under the total.
//!
//! Each figure is saved as PNG and SVG through [`Figure::save`].

use super::{draw_x_error_bar, draw_y_error_bar, shape_colour, DrawResult, Figure, FONT_FAMILY};
use crate::error::AnalysisError;
use crate::experiment::groups::{wilson_interval, Y_SUPPORT_UM, Z_95};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use rbc_schema::tables::{KdeRow, SummaryRow, TrackRow};
use std::path::{Path, PathBuf};

/// Font sizes in pixels (at the default figure sizes below, readable when printed at column width).
const CAPTION_PX: u32 = 26;
const AXIS_DESC_PX: u32 = 22;
const TICK_PX: u32 = 18;
const LEGEND_PX: u32 = 18;
const LABEL_PX: u32 = 17;

/// Write every experiment figure into `dir` (PNG + SVG each); returns the written paths.
///
/// `summary` and `kde` are the rows of `summary.csv` and `kde.csv`; `tracks`
/// supplies the individual y of the isolated cells (ticks under the densities).
/// Positions without summary rows get no figure; an empty summary writes nothing.
pub fn write_figures(
    dir: &Path,
    summary: &[SummaryRow],
    kde: &[KdeRow],
    tracks: &[TrackRow],
) -> Result<Vec<PathBuf>, AnalysisError> {
    let mut written = Vec::new();
    for position in positions(summary) {
        let tag = position_tag(position);
        let rows: Vec<SummaryRow> = summary
            .iter()
            .filter(|r| r.position_mm == position)
            .cloned()
            .collect();
        let fig = FractionsFigure::new(position, &rows);
        written.extend(fig.save(dir, &format!("fractions_vs_velocity_{tag}"), (900, 640))?);

        let stack = DensityStack::new(position, &rows, kde, tracks);
        if stack.curves.is_empty() {
            continue;
        }
        let height = stack_height(stack.curves.len());
        written.extend(stack.save(dir, &format!("y_density_{tag}"), (760, height))?);
        let by_shape = DensityStack {
            by_shape: true,
            ..stack
        };
        written.extend(by_shape.save(dir, &format!("y_density_by_shape_{tag}"), (760, height))?);
    }
    Ok(written)
}

/// Distinct positions of the summary, increasing.
fn positions(summary: &[SummaryRow]) -> Vec<f64> {
    let mut p: Vec<f64> = summary.iter().map(|r| r.position_mm).collect();
    p.sort_by(f64::total_cmp);
    p.dedup();
    p
}

/// File-name tag of a position: `10mm`, `0mm`, `2.5mm`.
fn position_tag(position_mm: f64) -> String {
    format!("{position_mm}mm")
}

/// Title of a position as in the paper.
fn position_title(position_mm: f64) -> String {
    if position_mm == 0.0 {
        "channel entrance (0 mm)".to_string()
    } else {
        format!("{position_mm} mm from the entrance")
    }
}

/// Figure height for `n` stacked curves, pixels.
fn stack_height(n: usize) -> u32 {
    (220 + 95 * n as u32).clamp(480, 1400)
}

/// Number with at most 3 significant digits and no trailing zeros (tick labels, pressures).
fn short(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// One shape's fraction per pressure group, with its interval.
struct FractionPoint {
    velocity: f64,
    velocity_std: f64,
    frac: f64,
    lo: f64,
    hi: f64,
}

/// Paper Fig. 3a: shape fractions vs mean velocity.
struct FractionsFigure {
    title: String,
    /// (shape, points sorted by velocity)
    series: Vec<(&'static str, Vec<FractionPoint>)>,
    /// (velocity, pressure) for the labels along the top.
    pressures: Vec<(f64, f64)>,
}

impl FractionsFigure {
    fn new(position_mm: f64, rows: &[SummaryRow]) -> Self {
        let mut rows: Vec<&SummaryRow> = rows.iter().collect();
        rows.sort_by(|a, b| a.velocity_mean_mm_s.total_cmp(&b.velocity_mean_mm_s));
        let point = |r: &SummaryRow, frac: f64, ci: Option<(f64, f64)>| {
            // rows read from a CSV without the interval columns: recompute Wilson from the counts
            let (lo, hi) = ci.unwrap_or_else(|| {
                wilson_interval((frac * r.n_cells as f64).round() as u64, r.n_cells, Z_95)
            });
            FractionPoint {
                velocity: r.velocity_mean_mm_s,
                velocity_std: r.velocity_std_mm_s,
                frac,
                lo,
                hi,
            }
        };
        let both = |lo: Option<f64>, hi: Option<f64>| lo.zip(hi);
        let series = vec![
            (
                "croissant",
                rows.iter()
                    .map(|r| {
                        point(
                            r,
                            r.frac_croissant,
                            both(r.frac_croissant_lo, r.frac_croissant_hi),
                        )
                    })
                    .collect(),
            ),
            (
                "slipper",
                rows.iter()
                    .map(|r| {
                        point(
                            r,
                            r.frac_slipper,
                            both(r.frac_slipper_lo, r.frac_slipper_hi),
                        )
                    })
                    .collect(),
            ),
            (
                "other",
                rows.iter().map(|r| point(r, r.frac_other, None)).collect(),
            ),
        ];
        let pressures = rows
            .iter()
            .map(|r| (r.velocity_mean_mm_s, r.pressure_mbar))
            .collect();
        FractionsFigure {
            title: format!("Cell shapes, {}", position_title(position_mm)),
            series,
            pressures,
        }
    }

    /// Velocity axis: log scale when the mean velocities span more than a decade (the paper's
    /// 20-1000 mbar give 0.14-10.6 mm/s), else linear. Error bars reaching 0 on a log axis are cut at the axis.
    fn axis(&self) -> VelocityAxis {
        let pts = || self.series.iter().flat_map(|(_, p)| p.iter());
        let lo = pts()
            .map(|p| p.velocity - p.velocity_std)
            .fold(f64::INFINITY, f64::min);
        let hi = pts()
            .map(|p| p.velocity + p.velocity_std)
            .fold(f64::NEG_INFINITY, f64::max);
        let min_pos = pts()
            .map(|p| p.velocity)
            .filter(|&v| v > 0.0)
            .fold(f64::INFINITY, f64::min);
        let max_v = pts().map(|p| p.velocity).fold(f64::NEG_INFINITY, f64::max);
        if !lo.is_finite() || !hi.is_finite() {
            return VelocityAxis {
                log: false,
                lo: 0.0,
                hi: 1.0,
            };
        }
        if min_pos.is_finite() && max_v / min_pos > 10.0 {
            let lo = if lo > 0.0 {
                lo.min(min_pos)
            } else {
                min_pos / 2.0
            };
            VelocityAxis {
                log: true,
                lo: lo / 1.3,
                hi: hi * 1.3,
            }
        } else {
            let pad = 0.08 * (hi - lo).max(1e-3);
            let lo = if lo >= 0.0 {
                (lo - pad).max(0.0)
            } else {
                lo - pad
            };
            VelocityAxis {
                log: false,
                lo,
                hi: hi + pad,
            }
        }
    }
}

/// The velocity axis of the fraction figure. On a log axis the chart coordinate is log10(v).
#[derive(Debug, Clone, Copy)]
struct VelocityAxis {
    log: bool,
    lo: f64,
    hi: f64,
}

impl VelocityAxis {
    /// Chart coordinate of velocity `v` (clamped to the axis range).
    fn x(&self, v: f64) -> f64 {
        let v = v.clamp(self.lo, self.hi);
        if self.log {
            v.log10()
        } else {
            v
        }
    }

    /// Tick positions (velocities) of a log axis: 1, 2 and 5 times powers of ten inside the range.
    fn log_ticks(&self) -> Vec<f64> {
        let mut t = Vec::new();
        let mut e = self.lo.log10().floor() as i32;
        while 10f64.powi(e) <= self.hi {
            for m in [1.0, 2.0, 5.0] {
                let v = m * 10f64.powi(e);
                if v >= self.lo && v <= self.hi {
                    t.push(v);
                }
            }
            e += 1;
        }
        t
    }
}

impl Figure for FractionsFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let ax = self.axis();
        let body = root.titled(&self.title, (FONT_FAMILY, CAPTION_PX))?;
        let mut chart = ChartBuilder::on(&body)
            .margin(12)
            .margin_top(58)
            .margin_right(175)
            .x_label_area_size(80)
            .y_label_area_size(78)
            .build_cartesian_2d(ax.x(ax.lo)..ax.x(ax.hi), -0.02f64..1.02f64)?;
        let mut mesh = chart.configure_mesh();
        mesh.y_desc("fraction of cells")
            .axis_desc_style((FONT_FAMILY, AXIS_DESC_PX))
            .label_style((FONT_FAMILY, TICK_PX))
            .y_label_formatter(&|v| format!("{v:.1}"))
            .light_line_style(WHITE.mix(0.0))
            .bold_line_style(BLACK.mix(0.08));
        let fmt = |v: &f64| short(*v);
        if ax.log {
            mesh.disable_x_mesh().x_labels(0);
        } else {
            mesh.x_label_formatter(&fmt)
                .x_desc("mean cell velocity (mm/s)");
        }
        mesh.draw()?;
        let area = chart.plotting_area().clone();
        if ax.log {
            // our own ticks: plotters' log axis labels only start at the first full decade
            let (y0, y1) = (-0.02, 1.02);
            for v in ax.log_ticks() {
                let x = v.log10();
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(x, y0), (x, y1)],
                    BLACK.mix(0.08),
                )))?;
                let (px, py) = area.map_coordinate(&(x, y0));
                body.draw(&PathElement::new(vec![(px, py), (px, py + 6)], BLACK))?;
                body.draw(&Text::new(
                    short(v),
                    (px, py + 10),
                    (FONT_FAMILY, TICK_PX)
                        .into_font()
                        .color(&BLACK)
                        .pos(Pos::new(HPos::Center, VPos::Top)),
                ))?;
            }
            let (x0, yb) = area.map_coordinate(&(ax.x(ax.lo), -0.02));
            let (x1, _) = area.map_coordinate(&(ax.x(ax.hi), -0.02));
            body.draw(&Text::new(
                "mean cell velocity (mm/s)",
                ((x0 + x1) / 2, yb + 36),
                (FONT_FAMILY, AXIS_DESC_PX)
                    .into_font()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Center, VPos::Top)),
            ))?;
        }

        for (i, (shape, points)) in self.series.iter().enumerate() {
            let colour = shape_colour(shape);
            chart.draw_series(LineSeries::new(
                points.iter().map(|p| (ax.x(p.velocity), p.frac)),
                colour.mix(0.45).stroke_width(2),
            ))?;
            for p in points {
                let xl = ax.x(p.velocity - p.velocity_std);
                let xh = ax.x(p.velocity + p.velocity_std);
                draw_x_error_bar(&mut chart, (xl, xh), p.frac, colour.stroke_width(1), 4)?;
                draw_y_error_bar(
                    &mut chart,
                    ax.x(p.velocity),
                    (p.lo, p.hi),
                    colour.stroke_width(2),
                    5,
                )?;
            }
            let filled = colour.filled();
            let cross = colour.stroke_width(3);
            let at = |p: &FractionPoint| (ax.x(p.velocity), p.frac);
            match i {
                0 => chart.draw_series(points.iter().map(|p| Circle::new(at(p), 6, filled)))?,
                1 => chart
                    .draw_series(points.iter().map(|p| TriangleMarker::new(at(p), 8, filled)))?,
                _ => chart.draw_series(points.iter().map(|p| Cross::new(at(p), 6, cross)))?,
            };
        }
        // legend to the right of the plot area (inside it would hide points or pressure labels)
        let (right_px, top_px) = area.map_coordinate(&(ax.x(ax.hi), 1.02));
        for (i, (shape, _)) in self.series.iter().enumerate() {
            let colour = shape_colour(shape);
            let (x, y) = (right_px + 18, top_px + 24 + 30 * i as i32);
            body.draw(&PathElement::new(
                vec![(x, y), (x + 28, y)],
                colour.stroke_width(2),
            ))?;
            match i {
                0 => body.draw(&Circle::new((x + 14, y), 6, colour.filled()))?,
                1 => body.draw(&TriangleMarker::new((x + 14, y), 8, colour.filled()))?,
                _ => body.draw(&Cross::new((x + 14, y), 6, colour.stroke_width(3)))?,
            }
            body.draw(&Text::new(
                shape.to_string(),
                (x + 36, y),
                (FONT_FAMILY, LEGEND_PX)
                    .into_font()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
        }
        let note = (FONT_FAMILY, LABEL_PX - 3)
            .into_font()
            .color(&BLACK.mix(0.6))
            .pos(Pos::new(HPos::Left, VPos::Center));
        let y_note = top_px + 24 + 30 * self.series.len() as i32 + 8;
        body.draw(&Text::new(
            "bars: velocity s.d.,",
            (right_px + 18, y_note),
            note.clone(),
        ))?;
        body.draw(&Text::new(
            "Wilson 95 % CI",
            (right_px + 18, y_note + 18),
            note,
        ))?;

        // pressure drops along the top of the plot area (the paper's top axis)
        let grey = BLACK.mix(0.75);
        let label_font = (FONT_FAMILY, LABEL_PX)
            .into_font()
            .color(&grey)
            .pos(Pos::new(HPos::Center, VPos::Bottom));
        let mut last_px: Option<i32> = None;
        for &(v, p) in &self.pressures {
            let (px, py) = area.map_coordinate(&(ax.x(v), 1.02));
            if last_px.is_some_and(|l| px - l < 36) {
                continue; // keep labels apart
            }
            last_px = Some(px);
            body.draw(&PathElement::new(vec![(px, py), (px, py - 5)], grey))?;
            body.draw(&Text::new(short(p), (px, py - 7), label_font.clone()))?;
        }
        let (x0, y_top) = area.map_coordinate(&(ax.x(ax.lo), 1.02));
        let (x1, _) = area.map_coordinate(&(ax.x(ax.hi), 1.02));
        body.draw(&Text::new(
            "pressure drop (mbar)",
            ((x0 + x1) / 2, y_top - 30),
            (FONT_FAMILY, AXIS_DESC_PX)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Bottom)),
        ))?;
        Ok(())
    }
}

/// A shape's fraction of its group and its density curve `(y_um, density)`.
type ShapeCurve = (&'static str, f64, Vec<(f64, f64)>);

/// One stacked curve: a pressure group's densities.
struct StackCurve {
    pressure_mbar: f64,
    /// (y_um, density) of shape `all`.
    all: Vec<(f64, f64)>,
    /// (shape, fraction of the group, curve) for croissant, slipper, other (those with a density).
    shapes: Vec<ShapeCurve>,
    /// y of the individual isolated cells, um.
    cells: Vec<f64>,
}

/// Paper Fig. 3b / Fig. 4: y-densities per pressure drop, offset vertically.
struct DensityStack {
    title: String,
    /// Where the cells were observed, for titles.
    position: String,
    curves: Vec<StackCurve>,
    /// Vertical offset between neighbouring curves, 1/um.
    step: f64,
    by_shape: bool,
}

impl DensityStack {
    fn new(position_mm: f64, rows: &[SummaryRow], kde: &[KdeRow], tracks: &[TrackRow]) -> Self {
        let mut rows: Vec<&SummaryRow> = rows.iter().collect();
        rows.sort_by(|a, b| a.pressure_mbar.total_cmp(&b.pressure_mbar));
        let curve_of = |p: f64, shape: &str| -> Vec<(f64, f64)> {
            let mut c: Vec<(f64, f64)> = kde
                .iter()
                .filter(|k| {
                    k.pressure_mbar == p && k.position_mm == position_mm && k.shape == shape
                })
                .map(|k| (k.y_um, k.density))
                .collect();
            c.sort_by(|a, b| a.0.total_cmp(&b.0));
            c
        };
        let mut curves = Vec::new();
        for r in rows {
            let all = curve_of(r.pressure_mbar, "all");
            if all.is_empty() {
                continue;
            }
            let shapes = [
                ("croissant", r.frac_croissant),
                ("slipper", r.frac_slipper),
                ("other", r.frac_other),
            ]
            .into_iter()
            .map(|(s, f)| (s, f, curve_of(r.pressure_mbar, s)))
            .filter(|(_, _, c)| !c.is_empty())
            .collect();
            let cells = tracks
                .iter()
                .filter(|t| {
                    t.isolated
                        && t.pressure_mbar == r.pressure_mbar
                        && t.position_mm == position_mm
                        && t.y_mean_um.is_finite()
                })
                .map(|t| t.y_mean_um)
                .collect();
            curves.push(StackCurve {
                pressure_mbar: r.pressure_mbar,
                all,
                shapes,
                cells,
            });
        }
        let peak = curves
            .iter()
            .flat_map(|c| c.all.iter().map(|p| p.1))
            .fold(0.0f64, f64::max);
        let step = if peak > 0.0 { 0.85 * peak } else { 1.0 };
        DensityStack {
            title: format!("y-density, {}", position_title(position_mm)),
            position: position_title(position_mm),
            curves,
            step,
            by_shape: false,
        }
    }
}

impl Figure for DensityStack {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let n = self.curves.len();
        let peak = self
            .curves
            .iter()
            .flat_map(|c| c.all.iter().map(|p| p.1))
            .fold(0.0f64, f64::max);
        let tick = 0.06 * self.step;
        let y_lo = -2.0 * tick;
        // the by-shape figure keeps room above the top curve for its legend
        let headroom = if self.by_shape { 1.1 * self.step } else { 0.0 };
        let y_hi = (n.saturating_sub(1)) as f64 * self.step + peak.max(self.step) * 1.08 + headroom;
        let (wall_lo, wall_hi) = Y_SUPPORT_UM;
        let title = if self.by_shape {
            format!("Shape contributions, {}", self.position)
        } else {
            self.title.clone()
        };
        let mut chart = ChartBuilder::on(root)
            .caption(title, (FONT_FAMILY, CAPTION_PX))
            .margin(12)
            .margin_right(20)
            .x_label_area_size(58)
            .y_label_area_size(112)
            .right_y_label_area_size(0)
            .build_cartesian_2d(wall_lo - 0.5..wall_hi + 0.5, y_lo..y_hi)?;
        chart
            .configure_mesh()
            .x_desc("y (µm)")
            .axis_desc_style((FONT_FAMILY, AXIS_DESC_PX))
            .label_style((FONT_FAMILY, TICK_PX))
            .x_label_formatter(&|v| short(*v))
            .disable_y_mesh()
            .y_labels(0)
            .light_line_style(WHITE.mix(0.0))
            .bold_line_style(BLACK.mix(0.06))
            .draw()?;

        // walls
        for w in [wall_lo, wall_hi] {
            chart.draw_series(DashedLineSeries::new(
                vec![(w, y_lo), (w, y_hi)],
                8,
                6,
                BLACK.mix(0.6).stroke_width(2),
            ))?;
        }

        let area = chart.plotting_area().clone();
        for (i, c) in self.curves.iter().enumerate() {
            let base = i as f64 * self.step;
            chart.draw_series(LineSeries::new(
                vec![(wall_lo, base), (wall_hi, base)],
                BLACK.mix(0.15),
            ))?;
            // individual cells as ticks under the baseline
            chart.draw_series(c.cells.iter().map(|&y| {
                PathElement::new(
                    vec![(y, base - 1.8 * tick), (y, base - 0.2 * tick)],
                    BLACK.mix(0.35),
                )
            }))?;
            if self.by_shape {
                for (shape, frac, curve) in &c.shapes {
                    let colour = shape_colour(shape);
                    chart.draw_series(LineSeries::new(
                        curve.iter().map(|&(y, d)| (y, base + frac * d)),
                        colour.stroke_width(2),
                    ))?;
                }
            }
            chart.draw_series(LineSeries::new(
                c.all.iter().map(|&(y, d)| (y, base + d)),
                BLACK.stroke_width(2),
            ))?;
            // pressure label left of the baseline, in the y label area
            let (px, py) = area.map_coordinate(&(wall_lo - 0.5, base));
            let right = |c: RGBAColor, px_size: u32| {
                (FONT_FAMILY, px_size)
                    .into_font()
                    .color(&c)
                    .pos(Pos::new(HPos::Right, VPos::Bottom))
            };
            root.draw(&Text::new(
                format!("{} mbar", short(c.pressure_mbar)),
                (px - 10, py + 2),
                right(BLACK.to_rgba(), LABEL_PX),
            ))?;
            root.draw(&Text::new(
                format!("n = {}", c.cells.len()),
                (px - 10, py + 20),
                right(BLACK.mix(0.55), LABEL_PX - 3),
            ))?;
        }

        // scale bar of the density axis, upper right
        let bar = nice_below(0.5 * self.step);
        let x_bar = wall_hi + 0.25;
        let top = y_hi - 0.04 * (y_hi - y_lo);
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(x_bar, top - bar), (x_bar, top)],
            BLACK.stroke_width(3),
        )))?;
        let (bx, by) = area.map_coordinate(&(x_bar, top - 0.5 * bar));
        root.draw(&Text::new(
            format!("{} µm⁻¹", short(bar)),
            (bx - 8, by),
            (FONT_FAMILY, LABEL_PX)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Right, VPos::Center)),
        ))?;

        if self.by_shape {
            // legend entries in a fixed order, for the shapes drawn anywhere in the stack
            let drawn = |shape: &str| {
                self.curves
                    .iter()
                    .any(|c| c.shapes.iter().any(|q| q.0 == shape))
            };
            let entries = ["croissant", "slipper", "other"]
                .into_iter()
                .filter(|s| drawn(s))
                .map(|s| (format!("{s} (fraction × density)"), shape_colour(s)))
                .chain(std::iter::once(("all shapes".to_string(), BLACK)));
            for (label, colour) in entries {
                chart
                    .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())?
                    .label(label)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(3))
                    });
            }
            chart
                .configure_series_labels()
                .label_font((FONT_FAMILY, LEGEND_PX))
                .background_style(WHITE.mix(0.9))
                .border_style(BLACK.mix(0.4))
                .position(SeriesLabelPosition::UpperLeft)
                .draw()?;
        }
        Ok(())
    }
}

/// Largest 1, 2 or 5 times a power of ten not above `v` (> 0).
fn nice_below(v: f64) -> f64 {
    let e = 10f64.powf(v.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * e)
        .find(|&c| c <= v)
        .unwrap_or(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_numbers() {
        assert_eq!(short(100.0), "100");
        assert_eq!(short(0.14), "0.14");
        assert_eq!(short(2.5), "2.5");
        assert_eq!(short(1000.0), "1000");
    }

    #[test]
    fn nice_values() {
        assert_eq!(nice_below(0.37), 0.2);
        assert_eq!(nice_below(0.6), 0.5);
        assert_eq!(nice_below(1.0), 1.0);
    }
}
