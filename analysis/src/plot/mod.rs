//! Figures with plotters, saved as PNG and SVG side by side.
//!
//! Text is drawn with DejaVu Sans embedded in the binary (`assets/DejaVuSans.ttf`,
//! Bitstream Vera licence), so figures render on machines without system fonts.
//! PNGs are encoded through `image` from an RGB buffer (plotters' own encoder
//! would pull a second `image` version). [`Figure::save`] draws the same figure
//! into both backends and moves each file into place only when complete.

pub mod experiment;
pub mod offset;
pub mod phase_studies;
pub mod prediction;
pub mod simulation;
pub mod steady_studies;
pub mod studies;
pub mod trajectory;

use crate::error::AnalysisError;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Font family name to use in every `TextStyle` of our figures.
pub const FONT_FAMILY: &str = "sans-serif";

/// Register the embedded font under [`FONT_FAMILY`] (idempotent).
pub fn register_font() {
    REGISTER.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold, FontStyle::Italic, FontStyle::Oblique] {
            let _ = plotters::style::register_font(FONT_FAMILY, style, FONT);
        }
    });
}

/// Error type of a drawing closure.
pub type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// A figure drawn by a generic function into any plotters backend.
pub trait Figure {
    /// Draw the whole figure onto `root` (already filled white).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static;

    /// Save as `dir/name.png` and `dir/name.svg`, atomically; returns both paths.
    fn save(&self, dir: &Path, name: &str, size: (u32, u32)) -> Result<[PathBuf; 2], AnalysisError> {
        register_font();
        std::fs::create_dir_all(dir).map_err(|e| AnalysisError::Plot { path: dir.into(), message: e.to_string() })?;
        let png = dir.join(format!("{name}.png"));
        let svg = dir.join(format!("{name}.svg"));
        let plot_err = |p: &Path, e: Box<dyn std::error::Error>| AnalysisError::Plot { path: p.into(), message: e.to_string() };

        // SVG
        let mut svg_text = String::new();
        {
            let root = SVGBackend::with_string(&mut svg_text, size).into_drawing_area();
            root.fill(&WHITE).map_err(|e| plot_err(&svg, Box::new(e)))?;
            self.draw(&root).map_err(|e| plot_err(&svg, e))?;
            root.present().map_err(|e| plot_err(&svg, Box::new(e)))?;
        }
        let svg_tmp = rbc_schema::atomic::temp_path(&svg);
        std::fs::write(&svg_tmp, svg_text.as_bytes()).map_err(|e| plot_err(&svg, Box::new(e)))?;

        // PNG via an RGB buffer encoded by `image`.
        let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
            root.fill(&WHITE).map_err(|e| plot_err(&png, Box::new(e)))?;
            self.draw(&root).map_err(|e| plot_err(&png, e))?;
            root.present().map_err(|e| plot_err(&png, Box::new(e)))?;
        }
        let img = image::RgbImage::from_raw(size.0, size.1, buf)
            .ok_or_else(|| AnalysisError::Plot { path: png.clone(), message: "buffer size".into() })?;
        let png_tmp = rbc_schema::atomic::temp_path(&png);
        img.save_with_format(&png_tmp, image::ImageFormat::Png).map_err(|e| plot_err(&png, Box::new(e)))?;
        rbc_schema::atomic::commit(&svg_tmp, &svg)?;
        rbc_schema::atomic::commit(&png_tmp, &png)?;
        Ok([png, svg])
    }
}

/// Save `figure` as `out/name.png` and `.svg` (`size` px), replacing both as one set
/// ([`rbc_schema::output_set`]: other files in `out` are left alone); returns the two paths (PNG
/// first). For a command that draws one figure.
pub fn write_one<F: Figure>(figure: &F, out: &Path, name: &str, size: (u32, u32)) -> Result<[PathBuf; 2], AnalysisError> {
    let owns = |file: &str| file == format!("{name}.png") || file == format!("{name}.svg");
    let ((), _) = rbc_schema::output_set::write_set(out, owns, |dir| figure.save(dir, name, size).map(|_| ()))?;
    Ok([out.join(format!("{name}.png")), out.join(format!("{name}.svg"))])
}

/// A chart over `x` and `y` with our caption, margins, axis descriptions and light grid: what
/// the phase diagrams and the column figures share.
pub fn chart_xy<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    caption: &str,
    (x, x_desc): (std::ops::Range<f64>, &str),
    (y, y_desc): (std::ops::Range<f64>, &str),
) -> Result<ChartContext<'a, DB, Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>>, Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(root).caption(caption, (FONT_FAMILY, 22)).margin(12).x_label_area_size(45).y_label_area_size(55).build_cartesian_2d(x, y)?;
    chart.configure_mesh().x_desc(x_desc).y_desc(y_desc).label_style((FONT_FAMILY, 15)).light_line_style(WHITE).draw()?;
    Ok(chart)
}

/// Colours of the series of a figure that draws several runs or studies, in order (matplotlib's
/// first six).
pub const SERIES_COLOURS: [RGBColor; 6] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x8c, 0x56, 0x4b),
];

/// Colours of the three shape classes, used by every figure.
pub fn shape_colour(shape: &str) -> RGBColor {
    match shape {
        "croissant" => RGBColor(0x1f, 0x77, 0xb4),
        "slipper" => RGBColor(0xd6, 0x27, 0x28),
        "other" => RGBColor(0x7f, 0x7f, 0x7f),
        _ => RGBColor(0x2c, 0xa0, 0x2c),
    }
}

/// Draw the chart's series legend at `position` in the style of the prediction and simulation
/// figures: 14 px labels on a white, slightly transparent box with a black border.
pub fn draw_legend<'a, DB, X, Y>(chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>, position: SeriesLabelPosition) -> DrawResult
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    X: Ranged,
    Y: Ranged,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT_FAMILY, 14))
        .draw()?;
    Ok(())
}

/// Draw a vertical error bar from `(x, lo)` to `(x, hi)` with caps `cap_px` pixels to each side
/// (plotters' own `ErrorBar` sits behind a feature we do not enable).
pub fn draw_y_error_bar<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    x: f64,
    (lo, hi): (f64, f64),
    style: ShapeStyle,
    cap_px: i32,
) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart.draw_series(std::iter::once(PathElement::new(vec![(x, lo), (x, hi)], style)))?;
    chart.draw_series([lo, hi].into_iter().map(|v| EmptyElement::at((x, v)) + PathElement::new(vec![(-cap_px, 0), (cap_px, 0)], style)))?;
    Ok(())
}

/// Draw a horizontal error bar from `(lo, y)` to `(hi, y)` with caps `cap_px` pixels up and down.
pub fn draw_x_error_bar<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    (lo, hi): (f64, f64),
    y: f64,
    style: ShapeStyle,
    cap_px: i32,
) -> DrawResult
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart.draw_series(std::iter::once(PathElement::new(vec![(lo, y), (hi, y)], style)))?;
    chart.draw_series([lo, hi].into_iter().map(|v| EmptyElement::at((v, y)) + PathElement::new(vec![(0, -cap_px), (0, cap_px)], style)))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Line;
    impl Figure for Line {
        fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
        where
            DB::ErrorType: 'static,
        {
            let mut chart = ChartBuilder::on(root)
                .caption("test", (FONT_FAMILY, 20))
                .x_label_area_size(30)
                .y_label_area_size(30)
                .build_cartesian_2d(0f64..1f64, 0f64..1f64)?;
            chart.configure_mesh().x_desc("x_um").draw()?;
            chart.draw_series(LineSeries::new([(0.0, 0.0), (1.0, 1.0)], &BLACK))?;
            Ok(())
        }
    }

    #[test]
    fn png_and_svg_are_written_with_text() {
        let dir = tempfile::tempdir().unwrap();
        let [png, svg] = Line.save(dir.path(), "line", (320, 240)).unwrap();
        let img = image::open(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (320, 240));
        // the diagonal black line and the caption make some pixels dark
        let dark = img.pixels().filter(|p| p.0[0] < 64).count();
        assert!(dark > 100, "{dark} dark pixels");
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.contains("<svg") && text.contains("x_um"));
    }
}
