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
use crate::groups::{wilson_interval, Y_SUPPORT_UM, Z_95};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
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
pub fn write_figures(dir: &Path, summary: &[SummaryRow], kde: &[KdeRow], tracks: &[TrackRow]) -> Result<Vec<PathBuf>, AnalysisError> {
    let mut written = Vec::new();
    for position in positions(summary) {
        let tag = position_tag(position);
        let rows: Vec<SummaryRow> = summary.iter().filter(|r| r.position_mm == position).cloned().collect();
        let fig = FractionsFigure::new(position, &rows);
        written.extend(fig.save(dir, &format!("fractions_vs_velocity_{tag}"), (900, 640))?);

        let stack = DensityStack::new(position, &rows, kde, tracks);
        if stack.curves.is_empty() {
            continue;
        }
        let height = stack_height(stack.curves.len());
        written.extend(stack.save(dir, &format!("y_density_{tag}"), (760, height))?);
        let by_shape = DensityStack { by_shape: true, ..stack };
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
        format!("{position_mm} mm downstream of the entrance")
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
            let (lo, hi) = ci.unwrap_or_else(|| wilson_interval((frac * r.n_cells as f64).round() as u64, r.n_cells, Z_95));
            FractionPoint { velocity: r.velocity_mean_mm_s, velocity_std: r.velocity_std_mm_s, frac, lo, hi }
        };
        let both = |lo: Option<f64>, hi: Option<f64>| lo.zip(hi);
        let series = vec![
            ("croissant", rows.iter().map(|r| point(r, r.frac_croissant, both(r.frac_croissant_lo, r.frac_croissant_hi))).collect()),
            ("slipper", rows.iter().map(|r| point(r, r.frac_slipper, both(r.frac_slipper_lo, r.frac_slipper_hi))).collect()),
            ("other", rows.iter().map(|r| point(r, r.frac_other, None)).collect()),
        ];
        let pressures = rows.iter().map(|r| (r.velocity_mean_mm_s, r.pressure_mbar)).collect();
        FractionsFigure { title: format!("Cell shapes, {}", position_title(position_mm)), series, pressures }
    }

    /// Velocity range including the error bars; log scale when it spans more than a decade.
    fn x_range(&self) -> (f64, f64, bool) {
        let pts = self.series.iter().flat_map(|(_, p)| p.iter());
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut min_pos = f64::INFINITY;
        for p in pts {
            lo = lo.min(p.velocity - p.velocity_std);
            hi = hi.max(p.velocity + p.velocity_std);
            if p.velocity > 0.0 {
                min_pos = min_pos.min(p.velocity);
            }
        }
        if !lo.is_finite() || !hi.is_finite() {
            return (0.0, 1.0, false);
        }
        let log = min_pos.is_finite() && hi / min_pos > 10.0;
        if log {
            let lo = if lo > 0.0 { lo } else { min_pos * 0.5 };
            (lo / 1.4, hi * 1.4, true)
        } else {
            let pad = 0.08 * (hi - lo).max(1e-3);
            ((lo - pad).max(if lo >= 0.0 { 0.0 } else { f64::NEG_INFINITY }), hi + pad, false)
        }
    }

    fn draw_on<DB: DrawingBackend, X>(&self, root: &DrawingArea<DB, Shift>, x_spec: X, x_lo: f64) -> DrawResult
    where
        DB::ErrorType: 'static,
        X: AsRangedCoord<Value = f64>,
        X::CoordDescType: ValueFormatter<f64>,
    {
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, (FONT_FAMILY, CAPTION_PX))
            .margin(12)
            .margin_top(44)
            .x_label_area_size(58)
            .y_label_area_size(78)
            .build_cartesian_2d(x_spec, -0.02f64..1.02f64)?;
        chart
            .configure_mesh()
            .x_desc("mean cell velocity (mm/s)")
            .y_desc("fraction of cells")
            .axis_desc_style((FONT_FAMILY, AXIS_DESC_PX))
            .label_style((FONT_FAMILY, TICK_PX))
            .x_label_formatter(&|v| short(*v))
            .y_label_formatter(&|v| format!("{v:.1}"))
            .light_line_style(WHITE.mix(0.0))
            .bold_line_style(BLACK.mix(0.08))
            .draw()?;

        for (i, (shape, points)) in self.series.iter().enumerate() {
            let colour = shape_colour(shape);
            let line = colour.mix(0.45).stroke_width(2);
            chart.draw_series(LineSeries::new(points.iter().map(|p| (p.velocity, p.frac)), line))?;
            for p in points {
                let xl = (p.velocity - p.velocity_std).max(x_lo);
                let xh = p.velocity + p.velocity_std;
                draw_x_error_bar(&mut chart, (xl, xh), p.frac, colour.stroke_width(1), 4)?;
                draw_y_error_bar(&mut chart, p.velocity, (p.lo, p.hi), colour.stroke_width(2), 5)?;
            }
            let style = colour.filled();
            let label = format!("{shape}");
            let anno = match i {
                0 => chart.draw_series(points.iter().map(|p| Circle::new((p.velocity, p.frac), 6, style)))?,
                1 => chart.draw_series(points.iter().map(|p| TriangleMarker::new((p.velocity, p.frac), 7, style)))?,
                _ => chart.draw_series(points.iter().map(|p| Cross::new((p.velocity, p.frac), 6, colour.stroke_width(3))))?,
            };
            anno.label(label).legend(move |(x, y)| {
                EmptyElement::at((x, y)) + Circle::new((10, 0), 6, style) + PathElement::new(vec![(0, 0), (20, 0)], colour.stroke_width(2))
            });
        }
        chart
            .configure_series_labels()
            .label_font((FONT_FAMILY, LEGEND_PX))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .position(SeriesLabelPosition::UpperLeft)
            .draw()?;

        // pressure drops along the top of the plot area (the paper's top axis)
        let area = chart.plotting_area();
        let mut last_px: Option<i32> = None;
        for &(v, p) in &self.pressures {
            let (px, py) = area.map_coordinate(&(v, 1.02));
            if last_px.is_some_and(|l| px - l < 34) {
                continue; // keep labels apart
            }
            last_px = Some(px);
            root.draw(&Text::new(short(p), (px - 10, py - 24), (FONT_FAMILY, LABEL_PX).into_font().color(&BLACK.mix(0.75))))?;
        }
        if let Some(&(v, _)) = self.pressures.last() {
            let (px, py) = area.map_coordinate(&(v, 1.02));
            root.draw(&Text::new("mbar", (px + 18, py - 24), (FONT_FAMILY, LABEL_PX).into_font().color(&BLACK.mix(0.75))))?;
        }
        Ok(())
    }
}

impl Figure for FractionsFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (lo, hi, log) = self.x_range();
        if log {
            self.draw_on(root, (lo..hi).log_scale(), lo)
        } else {
            self.draw_on(root, lo..hi, lo)
        }
    }
}

/// One stacked curve: a pressure group's densities.
struct StackCurve {
    pressure_mbar: f64,
    /// (y_um, density) of shape `all`.
    all: Vec<(f64, f64)>,
    /// (shape, fraction of the group, curve) for croissant, slipper, other (those with a density).
    shapes: Vec<(&'static str, f64, Vec<(f64, f64)>)>,
    /// y of the individual isolated cells, um.
    cells: Vec<f64>,
}

/// Paper Fig. 3b / Fig. 4: y-densities per pressure drop, offset vertically.
struct DensityStack {
    title: String,
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
                .filter(|k| k.pressure_mbar == p && k.position_mm == position_mm && k.shape == shape)
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
            let shapes = [("croissant", r.frac_croissant), ("slipper", r.frac_slipper), ("other", r.frac_other)]
                .into_iter()
                .map(|(s, f)| (s, f, curve_of(r.pressure_mbar, s)))
                .filter(|(_, _, c)| !c.is_empty())
                .collect();
            let cells = tracks
                .iter()
                .filter(|t| t.isolated && t.pressure_mbar == r.pressure_mbar && t.position_mm == position_mm && t.y_mean_um.is_finite())
                .map(|t| t.y_mean_um)
                .collect();
            curves.push(StackCurve { pressure_mbar: r.pressure_mbar, all, shapes, cells });
        }
        let peak = curves.iter().flat_map(|c| c.all.iter().map(|p| p.1)).fold(0.0f64, f64::max);
        let step = if peak > 0.0 { 0.85 * peak } else { 1.0 };
        DensityStack { title: format!("Cell position y, {}", position_title(position_mm)), curves, step, by_shape: false }
    }
}

impl Figure for DensityStack {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let n = self.curves.len();
        let peak = self.curves.iter().flat_map(|c| c.all.iter().map(|p| p.1)).fold(0.0f64, f64::max);
        let tick = 0.06 * self.step;
        let y_lo = -2.0 * tick;
        let y_hi = (n.saturating_sub(1)) as f64 * self.step + peak.max(self.step) * 1.08;
        let (wall_lo, wall_hi) = Y_SUPPORT_UM;
        let title = if self.by_shape { format!("{} by shape", self.title) } else { self.title.clone() };
        let mut chart = ChartBuilder::on(root)
            .caption(title, (FONT_FAMILY, CAPTION_PX))
            .margin(12)
            .margin_right(20)
            .x_label_area_size(58)
            .y_label_area_size(96)
            .right_y_label_area_size(0)
            .build_cartesian_2d(wall_lo - 0.5..wall_hi + 0.5, y_lo..y_hi)?;
        chart
            .configure_mesh()
            .x_desc("y (µm)")
            .y_desc("pressure drop (mbar)")
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
            chart.draw_series(DashedLineSeries::new(vec![(w, y_lo), (w, y_hi)], 8, 6, BLACK.mix(0.6).stroke_width(2)))?;
        }

        let area = chart.plotting_area().clone();
        for (i, c) in self.curves.iter().enumerate() {
            let base = i as f64 * self.step;
            chart.draw_series(LineSeries::new(vec![(wall_lo, base), (wall_hi, base)], BLACK.mix(0.15)))?;
            // individual cells as ticks under the baseline
            chart.draw_series(c.cells.iter().map(|&y| PathElement::new(vec![(y, base - 1.8 * tick), (y, base - 0.2 * tick)], BLACK.mix(0.35))))?;
            if self.by_shape {
                for (k, (shape, frac, curve)) in c.shapes.iter().enumerate() {
                    let colour = shape_colour(shape);
                    let s = chart.draw_series(LineSeries::new(curve.iter().map(|&(y, d)| (y, base + frac * d)), colour.stroke_width(2)))?;
                    if i == 0 || !self.curves[..i].iter().any(|p| p.shapes.iter().any(|q| q.0 == *shape)) {
                        let _ = k;
                        s.label(format!("{shape} (fraction × density)"))
                            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(3)));
                    }
                }
            }
            let total = chart.draw_series(LineSeries::new(c.all.iter().map(|&(y, d)| (y, base + d)), BLACK.stroke_width(2)))?;
            if self.by_shape && i == 0 {
                total.label("all shapes").legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(3)));
            }
            // pressure label left of the baseline, in the y label area
            let (px, py) = area.map_coordinate(&(wall_lo - 0.5, base));
            root.draw(&Text::new(
                format!("{} ({})", short(c.pressure_mbar), c.cells.len()),
                (px - 90, py - 9),
                (FONT_FAMILY, LABEL_PX).into_font(),
            ))?;
        }

        // scale bar of the density axis, upper right
        let bar = nice_below(0.5 * self.step);
        let x_bar = wall_hi + 0.25;
        let top = y_hi - 0.04 * (y_hi - y_lo);
        chart.draw_series(std::iter::once(PathElement::new(vec![(x_bar, top - bar), (x_bar, top)], BLACK.stroke_width(3))))?;
        let (bx, by) = area.map_coordinate(&(x_bar, top - 0.5 * bar));
        root.draw(&Text::new(
            format!("{} /µm", short(bar)),
            (bx - 80, by - 9),
            (FONT_FAMILY, LABEL_PX).into_font(),
        ))?;

        if self.by_shape {
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
    [5.0, 2.0, 1.0].into_iter().map(|m| m * e).find(|&c| c <= v).unwrap_or(e)
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
