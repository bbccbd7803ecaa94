//! Figures of the prediction (paper Fig. 5-style phase diagram with r_trans, Fig. 7, Fig. 8).
//!
//! - [`PhaseDiagramFigure`]: one symbol per finished run in the (u, r_init)
//!   plane (croissant: filled circle, slipper: triangle, other: cross), the
//!   min-max velocity of each run as a horizontal bar, r_trans(u) as a black
//!   line with its bracket shaded; `inf` (croissant-only) is drawn at the top edge; runs still
//!   going, when given ([`PhaseDiagramFigure::with_running`]), hollow at their recent velocity.
//! - [`PhiFigure`]: predicted phi vs velocity with vertical bars (phi_lo, phi_hi)
//!   and horizontal bars (sigma_u); the observed croissant fractions as a
//!   black dashed line with their own bars both ways.
//! - [`OffsetFigure`]: simulated mean |y| and |z| of tank-treading slippers
//!   (bars: extremes over runs and velocities) and the experiment's `(y_r - y_l) / 2`
//!   (bars: sigma_u and the position uncertainty s_P).
//!
//! [`write_figures`] draws all of them for `rbc-predict`.

use super::studies::RunningRun;
use super::{chart_xy, draw_legend, shape_colour, DrawResult, Figure, FONT_FAMILY};
use crate::error::AnalysisError;
use crate::simulated::phase::{start_shapes, PhasePoint};
use crate::simulated::threshold::Threshold;
use crate::types::prediction::{Prediction, SimulatedOffset};
use rbc_schema::tables::PredictionRow;
use plotters::coord::Shift;
use plotters::prelude::*;
use rbc_schema::results::FinalShape;
use std::path::{Path, PathBuf};

type Chart<'a, 'b, DB> = ChartContext<'a, DB, Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>>;

/// Error bars: a line from `lo` to `hi` with caps `cap` pixels wide, vertical
/// (`(x, lo, hi)`) or horizontal (`(y, lo, hi)`). Our own because plotters'
/// `ErrorBar` needs its `errorbar` feature, which the workspace does not enable.
fn bars<DB: DrawingBackend>(chart: &mut Chart<'_, '_, DB>, items: &[(f64, f64, f64)], vertical: bool, style: ShapeStyle, cap: i32) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let pt = move |k: f64, v: f64| if vertical { (k, v) } else { (v, k) };
    let tick: Vec<(i32, i32)> = if vertical { vec![(-cap, 0), (cap, 0)] } else { vec![(0, -cap), (0, cap)] };
    let finite: Vec<_> = items.iter().filter(|(k, lo, hi)| k.is_finite() && lo.is_finite() && hi.is_finite()).copied().collect();
    chart.draw_series(finite.iter().map(|&(k, lo, hi)| PathElement::new(vec![pt(k, lo), pt(k, hi)], style)))?;
    for end in [1usize, 2] {
        chart.draw_series(finite.iter().map(|it| {
            let v = if end == 1 { it.1 } else { it.2 };
            EmptyElement::at(pt(it.0, v)) + PathElement::new(tick.clone(), style)
        }))?;
    }
    Ok(())
}

const GREY_BAND: RGBColor = RGBColor(0xcc, 0xcc, 0xcc);

/// Colour of a start shape's prediction.
fn start_colour(shape: &str) -> RGBColor {
    match shape {
        "discocyte" => RGBColor(0x2c, 0xa0, 0x2c),
        "croissant" => shape_colour("croissant"),
        "slipper" => shape_colour("slipper"),
        _ => RGBColor(0x94, 0x67, 0xbd),
    }
}

/// Phase diagram of one start shape (paper Fig. 5).
pub struct PhaseDiagramFigure<'a> {
    points: &'a [PhasePoint],
    thresholds: &'a [Threshold],
    shape: String,
    running: &'a [RunningRun],
    caption: Option<String>,
    extent: Option<(f64, f64)>,
}

impl<'a> PhaseDiagramFigure<'a> {
    /// The runs `points` and the r_trans columns `thresholds` of `start_shape` (others are ignored).
    pub fn new(points: &'a [PhasePoint], thresholds: &'a [Threshold], start_shape: &str) -> Self {
        PhaseDiagramFigure { points, thresholds, shape: start_shape.to_string(), running: &[], caption: None, extent: None }
    }

    /// Also the runs still going (those of `start_shape`), hollow at their recent velocity.
    pub fn with_running(mut self, running: &'a [RunningRun]) -> Self {
        self.running = running;
        self
    }

    /// Another caption (the default: `"Phase diagram, start shape: <start shape>"`).
    pub fn with_caption(mut self, caption: String) -> Self {
        self.caption = Some(caption);
        self
    }

    /// The axes' upper ends `(u_max mm/s, r_top um)` instead of the figure's own [`Self::extent`]
    /// (panels that share their axes).
    pub fn with_extent(mut self, extent: (f64, f64)) -> Self {
        self.extent = Some(extent);
        self
    }

    /// The axes' upper ends this figure's runs ask for: 5 % beyond the fastest run's velocity (at
    /// least 1.05 mm/s), and 40 % above the largest r_init (at least 0.7 um), headroom for the
    /// legend (upper right), which must hide no point.
    pub fn extent(&self) -> (f64, f64) {
        let pts = self.points.iter().filter(|p| p.start_shape == self.shape);
        let going = self.running.iter().filter(|p| p.start_shape == self.shape);
        let u_max = pts.clone().map(|p| p.max_velocity_mm_s.max(p.velocity_mm_s)).chain(going.clone().map(|p| p.tail.velocity_mm_s)).fold(1.0, f64::max) * 1.05;
        let r_data = pts.map(|p| p.r_init_um).chain(going.map(|p| p.r_init_um)).fold(0.5, f64::max);
        (u_max, r_data * 1.4)
    }
}

impl Figure for PhaseDiagramFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let pts: Vec<_> = self.points.iter().filter(|p| p.start_shape == self.shape).collect();
        let nodes: Vec<&Threshold> = self.thresholds.iter().filter(|t| t.start_shape == self.shape).collect();
        let (u_max, r_top) = self.extent.unwrap_or_else(|| self.extent());
        let clip = |r: f64| if r.is_finite() { r.min(r_top) } else { r_top };

        let caption = self.caption.clone().unwrap_or_else(|| format!("Phase diagram, start shape: {}", self.shape));
        let mut chart = chart_xy(root, &caption, (0f64..u_max, "mean cell velocity u (mm/s)"), (0f64..r_top, "initial offset r_init (um)"))?;

        // bracket band between the interval ends, then the r_trans line
        if nodes.len() >= 2 {
            let mut poly: Vec<(f64, f64)> = nodes.iter().map(|t| (t.velocity_mm_s, clip(t.interval().0))).collect();
            poly.extend(nodes.iter().rev().map(|t| (t.velocity_mm_s, clip(t.interval().1))));
            chart
                .draw_series(std::iter::once(Polygon::new(poly, GREY_BAND.mix(0.6).filled())))?
                .label("r_trans bracket")
                .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], GREY_BAND.filled()));
        }
        chart
            .draw_series(LineSeries::new(nodes.iter().map(|t| (t.velocity_mm_s, clip(t.r_trans_um))), BLACK.stroke_width(2)))?
            .label("r_trans (top edge: inf)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(2)));
        chart.draw_series(nodes.iter().map(|t| Circle::new((t.velocity_mm_s, clip(t.r_trans_um)), 3, BLACK.filled())))?;

        // runs: velocity range bars, then symbols
        for shape in [FinalShape::Croissant, FinalShape::Slipper, FinalShape::Other] {
            let c = shape_colour(shape.as_str());
            let items: Vec<_> = pts.iter().filter(|p| p.final_shape == shape).map(|p| (p.r_init_um, p.min_velocity_mm_s, p.max_velocity_mm_s)).collect();
            bars(&mut chart, &items, false, c.mix(0.7).stroke_width(1), 3)?;
        }
        for (shape, label) in [(FinalShape::Croissant, "croissant"), (FinalShape::Slipper, "slipper"), (FinalShape::Other, "other")] {
            let c = shape_colour(shape.as_str());
            let sel: Vec<(f64, f64)> = pts.iter().filter(|p| p.final_shape == shape).map(|p| (p.velocity_mm_s, p.r_init_um)).collect();
            if sel.is_empty() {
                continue;
            }
            // the legend shows each shape's own marker
            match shape {
                FinalShape::Croissant => {
                    chart.draw_series(sel.iter().map(|&xy| Circle::new(xy, 5, c.filled())))?.label(label).legend(move |(x, y)| Circle::new((x + 8, y), 5, c.filled()));
                }
                FinalShape::Slipper => {
                    chart.draw_series(sel.iter().map(|&xy| TriangleMarker::new(xy, 6, c.filled())))?.label(label).legend(move |(x, y)| TriangleMarker::new((x + 8, y), 6, c.filled()));
                }
                FinalShape::Other => {
                    chart.draw_series(sel.iter().map(|&xy| Cross::new(xy, 5, c.stroke_width(2))))?.label(label).legend(move |(x, y)| Cross::new((x + 8, y), 5, c.stroke_width(2)));
                }
            }
        }
        // runs still going: hollow, at the velocity of their last stretch, with how far each has got
        let going: Vec<&RunningRun> = self.running.iter().filter(|p| p.start_shape == self.shape).collect();
        if !going.is_empty() {
            let grey = RGBColor(0x55, 0x55, 0x55);
            chart
                .draw_series(going.iter().map(|p| Circle::new((p.tail.velocity_mm_s, p.r_init_um), 6, grey.stroke_width(2))))?
                .label("still running")
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, grey.stroke_width(2)));
            let at: Vec<(f64, f64)> = going.iter().map(|p| (p.tail.velocity_mm_s, p.r_init_um)).collect();
            let px_per_mm_s = (chart.backend_coord(&(1.0, 0.0)).0 - chart.backend_coord(&(0.0, 0.0)).0).max(1) as f64;
            let lanes = label_lanes(&at, LABEL_WIDTH_PX / px_per_mm_s);
            chart.draw_series(going.iter().zip(lanes).map(|(p, lane)| {
                let offset = lane_offset_px(lane);
                EmptyElement::at((p.tail.velocity_mm_s, p.r_init_um)) + Text::new(format!("{:.0} ms", p.tail.t_s * 1e3), offset, (FONT_FAMILY, 13).into_font().color(&grey))
            }))?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
    }
}

/// Width of a "1234 ms" label at 13 px (px), with a margin.
const LABEL_WIDTH_PX: f64 = 56.0;

/// Where the "t ms" labels of runs still going sit, as lanes around their marker: 0 below it, 1
/// above, 2 further below, 3 further above, and so on. Along each `r_init` (velocity order) a
/// label takes the first lane whose last label starts at least `min_gap_mm_s` to its left, so
/// that no two labels overlap however many neighbours crowd a stretch of velocity (`points`:
/// velocity (mm/s), r_init (um), in any order; the answer is in the same order).
fn label_lanes(points: &[(f64, f64)], min_gap_mm_s: f64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| points[a].1.total_cmp(&points[b].1).then(points[a].0.total_cmp(&points[b].0)));
    let mut lane = vec![0; points.len()];
    // the velocity of each lane's last label along the current r_init
    let mut last: Vec<f64> = Vec::new();
    for (k, &i) in order.iter().enumerate() {
        if k == 0 || points[order[k - 1]].1 != points[i].1 {
            last.clear();
        }
        let free = last.iter().position(|&v| points[i].0 - v >= min_gap_mm_s).unwrap_or(last.len());
        if free == last.len() {
            last.push(points[i].0);
        } else {
            last[free] = points[i].0;
        }
        lane[i] = free;
    }
    lane
}

/// The pixel offset of a label in `lane` (see [`label_lanes`]) from its marker: below for even
/// lanes, above for odd ones, 14 px further out for each pair.
fn lane_offset_px(lane: usize) -> (i32, i32) {
    let out = 14 * (lane / 2) as i32;
    if lane.is_multiple_of(2) {
        (-18, 9 + out)
    } else {
        (-18, -22 - out)
    }
}

/// Predicted and observed croissant fraction vs velocity for one start shape (paper Fig. 7).
pub struct PhiFigure<'a> {
    pred: &'a Prediction,
    shape: String,
}

impl<'a> PhiFigure<'a> {
    pub fn new(pred: &'a Prediction, start_shape: &str) -> Self {
        PhiFigure { pred, shape: start_shape.to_string() }
    }
}

impl Figure for PhiFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let rows: Vec<_> = self.pred.rows.iter().filter(|r| r.start_shape == self.shape).collect();
        let mut u_max = rows.iter().map(|r| r.velocity_mm_s + r.velocity_std_mm_s).fold(1.0, f64::max);
        for g in &self.pred.groups {
            if let Some(o) = &g.observed {
                u_max = u_max.max(o.velocity_mean_mm_s + o.velocity_std_mm_s);
            }
        }
        let u_max = u_max * 1.08;
        let colour = start_colour(&self.shape);
        let mut chart = ChartBuilder::on(root)
            .caption(format!("Croissant fraction, simulations started as {}", self.shape), (FONT_FAMILY, 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(55)
            .build_cartesian_2d(0f64..u_max, 0f64..1.05f64)?;
        chart
            .configure_mesh()
            .x_desc("cell velocity u (mm/s)")
            .y_desc("fraction of croissants")
            .label_style((FONT_FAMILY, 15))
            .light_line_style(WHITE)
            .draw()?;

        // observed: black dashed line, bars both ways
        let mut obs: Vec<_> = self.pred.groups.iter().filter_map(|g| g.observed.as_ref()).collect();
        obs.sort_by(|a, b| a.velocity_mean_mm_s.total_cmp(&b.velocity_mean_mm_s));
        if !obs.is_empty() {
            let v: Vec<_> = obs.iter().map(|o| (o.velocity_mean_mm_s, o.frac_croissant_lo, o.frac_croissant_hi)).collect();
            bars(&mut chart, &v, true, BLACK.stroke_width(1), 4)?;
            let h: Vec<_> = obs.iter().map(|o| (o.frac_croissant, o.velocity_mean_mm_s - o.velocity_std_mm_s, o.velocity_mean_mm_s + o.velocity_std_mm_s)).collect();
            bars(&mut chart, &h, false, BLACK.stroke_width(1), 4)?;
            chart
                .draw_series(DashedLineSeries::new(
                    obs.iter().map(|o| (o.velocity_mean_mm_s, o.frac_croissant)).collect::<Vec<_>>(),
                    8,
                    5,
                    BLACK.stroke_width(2),
                ))?
                .label("observed (experiment)")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.stroke_width(2)));
            chart.draw_series(obs.iter().map(|o| Circle::new((o.velocity_mean_mm_s, o.frac_croissant), 4, BLACK.filled())))?;
        }

        // the simulated velocity columns of this start shape: where the runs are
        let columns: Vec<f64> = self.pred.thresholds.iter().filter(|t| t.start_shape == self.shape).map(|t| t.velocity_mm_s).collect();
        for (i, &u) in columns.iter().enumerate() {
            let line = chart.draw_series(DashedLineSeries::new(vec![(u, 0.0), (u, 1.05)], 6, 5, colour.mix(0.8).stroke_width(2)))?;
            if i == 0 {
                line.label("simulated velocity").legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], colour.mix(0.8).stroke_width(2)));
            }
        }

        // predicted: coloured symbols with bars both ways, joined by a thin line; filled where the
        // runs bracket r_trans at the group's velocities, hollow where the nearest column was used
        // (`extrapolated`), grey crosses where phi says nothing (`unbracketed`)
        let mut pr: Vec<(&PredictionRow, &str)> = self.pred.rows.iter().zip(&self.pred.phis).filter(|(r, _)| r.start_shape == self.shape).map(|(r, p)| (r, p.status())).collect();
        pr.sort_by(|a, b| a.0.velocity_mm_s.total_cmp(&b.0.velocity_mm_s));
        let v: Vec<_> = pr.iter().map(|(r, _)| (r.velocity_mm_s, r.phi_lo, r.phi_hi)).collect();
        bars(&mut chart, &v, true, colour.stroke_width(2), 5)?;
        let h: Vec<_> = pr.iter().map(|(r, _)| (r.phi, r.velocity_mm_s - r.velocity_std_mm_s, r.velocity_mm_s + r.velocity_std_mm_s)).collect();
        bars(&mut chart, &h, false, colour.stroke_width(1), 4)?;
        chart.draw_series(LineSeries::new(pr.iter().map(|(r, _)| (r.velocity_mm_s, r.phi)), colour.mix(0.5)))?;
        let of = |status: &'static str| pr.iter().filter(move |(_, s)| *s == status).map(|(r, _)| (r.velocity_mm_s, r.phi)).collect::<Vec<_>>();
        let (bracketed, extrapolated, unbracketed) = (of("bracketed"), of("extrapolated"), of("unbracketed"));
        if !bracketed.is_empty() {
            chart
                .draw_series(bracketed.iter().map(|&xy| TriangleMarker::new(xy, 7, colour.filled())))?
                .label("predicted phi (simulations)")
                .legend(move |(x, y)| TriangleMarker::new((x + 8, y), 6, colour.filled()));
        }
        if !extrapolated.is_empty() {
            // hollow: the coloured triangle with a white one inside (plotters fills every triangle marker)
            chart
                .draw_series(extrapolated.iter().map(|&xy| EmptyElement::at(xy) + TriangleMarker::new((0, 0), 8, colour.filled()) + TriangleMarker::new((0, 1), 4, WHITE.filled())))?
                .label("predicted phi, extrapolated (nearest column)")
                .legend(move |(x, y)| EmptyElement::at((x + 8, y)) + TriangleMarker::new((0, 0), 7, colour.filled()) + TriangleMarker::new((0, 1), 3, WHITE.filled()));
        }
        if !unbracketed.is_empty() {
            chart
                .draw_series(unbracketed.iter().map(|&xy| Cross::new(xy, 6, RGBColor(128, 128, 128).stroke_width(2))))?
                .label("phi not decided by the runs")
                .legend(|(x, y)| Cross::new((x + 8, y), 5, RGBColor(128, 128, 128).stroke_width(2)));
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
    }
}

/// Slipper off-centre position, simulation vs experiment (paper Fig. 8).
pub struct OffsetFigure<'a> {
    pred: &'a Prediction,
}

impl<'a> OffsetFigure<'a> {
    pub fn new(pred: &'a Prediction) -> Self {
        OffsetFigure { pred }
    }
}

impl Figure for OffsetFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let sim = &self.pred.simulated_offsets;
        let exp = &self.pred.experiment_offsets;
        let s_p = self.pred.config.position_uncertainty_um;
        let u_max = sim
            .iter()
            .map(|s| s.velocity_max_mm_s)
            .chain(exp.iter().map(|e| e.velocity_mm_s + e.velocity_std_mm_s))
            .fold(1.0, f64::max)
            * 1.08;
        let y_max = sim
            .iter()
            .map(|s| s.abs_y_max_um.max(s.abs_z_max_um))
            .chain(exp.iter().map(|e| e.offset_um + s_p))
            .fold(1.0, f64::max)
            * 1.25;
        let mut chart = ChartBuilder::on(root)
            .caption("Slipper off-centre position", (FONT_FAMILY, 22))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(55)
            .build_cartesian_2d(0f64..u_max, 0f64..y_max)?;
        chart
            .configure_mesh()
            .x_desc("cell velocity u (mm/s)")
            .y_desc("off-centre position (um)")
            .label_style((FONT_FAMILY, 15))
            .light_line_style(WHITE)
            .draw()?;
        let red = shape_colour("slipper");
        let blue = shape_colour("croissant");
        for (label, colour, get) in [
            ("simulation |y|", red, (|s: &SimulatedOffset| (s.abs_y_min_um, s.abs_y_um, s.abs_y_max_um)) as fn(&SimulatedOffset) -> (f64, f64, f64)),
            ("simulation |z|", blue, |s| (s.abs_z_min_um, s.abs_z_um, s.abs_z_max_um)),
        ] {
            if sim.is_empty() {
                break;
            }
            let v: Vec<_> = sim.iter().map(|s| { let (lo, _, hi) = get(s); (s.velocity_mm_s, lo, hi) }).collect();
            bars(&mut chart, &v, true, colour.stroke_width(1), 4)?;
            let h: Vec<_> = sim.iter().map(|s| (get(s).1, s.velocity_min_mm_s, s.velocity_max_mm_s)).collect();
            bars(&mut chart, &h, false, colour.stroke_width(1), 4)?;
            chart.draw_series(LineSeries::new(sim.iter().map(|s| (s.velocity_mm_s, get(s).1)), colour.mix(0.6)))?;
            chart
                .draw_series(sim.iter().map(|s| Circle::new((s.velocity_mm_s, get(s).1), 5, colour.filled())))?
                .label(label)
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
        }
        if !exp.is_empty() {
            let v: Vec<_> = exp.iter().map(|e| (e.velocity_mm_s, e.offset_um - s_p, e.offset_um + s_p)).collect();
            bars(&mut chart, &v, true, BLACK.stroke_width(1), 4)?;
            let h: Vec<_> = exp.iter().map(|e| (e.offset_um, e.velocity_mm_s - e.velocity_std_mm_s, e.velocity_mm_s + e.velocity_std_mm_s)).collect();
            bars(&mut chart, &h, false, BLACK.stroke_width(1), 4)?;
            chart
                .draw_series(exp.iter().map(|e| TriangleMarker::new((e.velocity_mm_s, e.offset_um), 7, BLACK.filled())))?
                .label("experiment (y_r - y_l)/2")
                .legend(|(x, y)| TriangleMarker::new((x + 8, y), 6, BLACK.filled()));
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
    }
}

/// Write the figures of `pred` into `dir` (each PNG + SVG, atomically): `phase_<start shape>`
/// (Fig. 5 style), `phi_<start shape>` (Fig. 7) when the shape has predictions, and
/// `slipper_offset` (Fig. 8) when there are simulated or measured offsets. Returns the paths written.
pub fn write_figures(pred: &Prediction, dir: &Path) -> Result<Vec<PathBuf>, AnalysisError> {
    let mut written = Vec::new();
    for shape in start_shapes(&pred.points) {
        let safe: String = shape.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect();
        let pd = PhaseDiagramFigure::new(&pred.points, &pred.thresholds, &shape);
        written.extend(pd.save(dir, &format!("phase_{safe}"), (800, 600))?);
        if pred.rows.iter().any(|r| r.start_shape == shape) {
            let pf = PhiFigure::new(pred, &shape);
            written.extend(pf.save(dir, &format!("phi_{safe}"), (800, 600))?);
        }
    }
    if !pred.simulated_offsets.is_empty() || !pred.experiment_offsets.is_empty() {
        written.extend(OffsetFigure::new(pred).save(dir, "slipper_offset", (800, 600))?);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::{label_lanes, lane_offset_px};

    #[test]
    fn neighbouring_labels_at_one_offset_take_free_lanes_and_far_or_other_offsets_stay_below() {
        // the penalty study's runs still going in session 44: 0.5, 2.1 and 2.54 mm/s at 1.2 um, 2.54 at 0.4, 6.46 at 0.6
        let points = [(2.54, 1.2), (0.50, 1.2), (2.09, 1.2), (2.54, 0.4), (6.46, 0.6)];
        assert_eq!(label_lanes(&points, 0.7), vec![1, 0, 0, 0, 0]);
        // three close neighbours, the outer two a gap apart: below, above, below
        assert_eq!(label_lanes(&[(3.0, 1.0), (2.5, 1.0), (2.0, 1.0)], 0.7), vec![0, 1, 0]);
        // three within one gap (session 53: ~0.26, ~0.32 and ~0.37 mm/s at 1.2 um): a third lane,
        // and the next label beyond the gap back below
        assert_eq!(label_lanes(&[(0.24, 1.2), (0.32, 1.2), (0.36, 1.2), (1.25, 1.2)], 0.66), vec![0, 1, 2, 0]);
        // no neighbour within the gap: every label below
        assert_eq!(label_lanes(&[(1.0, 1.0), (2.0, 1.0)], 0.7), vec![0, 0]);
        assert!(label_lanes(&[], 0.7).is_empty());
        // lanes alternate below and above, each pair further out
        assert_eq!((0..4).map(lane_offset_px).collect::<Vec<_>>(), vec![(-18, 9), (-18, -22), (-18, 23), (-18, -36)]);
    }
}
