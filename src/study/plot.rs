//! The study's error-versus-time chart, drawn on the CPU with plotters.
//!
//! Text uses a bundled DejaVu Sans through plotters' `ab_glyph` backend, so rendering the chart needs no system
//! font libraries and gives the same pixels everywhere.

use std::collections::BTreeMap;
use std::sync::Once;

use plotters::backend::DrawingBackend;
use plotters::coord::CoordTranslate;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use super::report::{self, Summary, TARGETS};

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Registers the bundled font as plotters' "sans-serif", once per process; every text style here asks for it.
pub(crate) fn ensure_font() {
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        // The font is bundled and known good; a failure here is a build problem, not a runtime condition.
        if register_font("sans-serif", FontStyle::Normal, FONT).is_err() {
            log::error!("the bundled DejaVu Sans font could not be parsed; chart text will be missing");
        }
    });
}

/// What plotters' bitmap backend fails with.
type DrawingError = DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>;

/// Why a chart or a legend could not be drawn, or two images could not be compared (`flip`).
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// [`error_vs_time`] of no configurations.
    #[error("no configurations to plot")]
    NothingToPlot,
    /// [`error_vs_time`] of configurations none of which has a finite frame time and error.
    #[error("no configuration has a finite frame time and error")]
    NothingFinite,
    /// A chart smaller than [`MIN_CHART`] pixels either way.
    #[error("chart size {width}x{height} is too small (at least {MIN_CHART}x{MIN_CHART})")]
    ChartTooSmall {
        /// The width asked for.
        width: u32,
        /// The height asked for.
        height: u32,
    },
    /// An image too small for the legend's panel (`raster::legend_bar`).
    #[error("image {width}x{height} is too small for a legend")]
    LegendTooSmall {
        /// The image's width.
        width: u32,
        /// The image's height.
        height: u32,
    },
    /// An image without a pixel.
    #[error("{image} image is empty ({width}x{height})")]
    EmptyImage {
        /// Which image: "reference", "test".
        image: &'static str,
        /// Its width.
        width: u32,
        /// Its height.
        height: u32,
    },
    /// RGBA8 pixels whose length is not the image's size.
    #[error("{image} image has {bytes} bytes, {width}x{height} RGBA8 needs {expected}")]
    ImageBytes {
        /// Which image: "reference", "test", "legend".
        image: &'static str,
        /// Bytes given.
        bytes: usize,
        /// The width given.
        width: u32,
        /// The height given.
        height: u32,
        /// Bytes of `width` x `height` RGBA8.
        expected: usize,
    },
    /// plotters could not draw.
    #[error(transparent)]
    Drawing(#[from] DrawingError),
}

/// The smallest chart, in pixels each way.
pub const MIN_CHART: u32 = 64;

/// Smallest value drawn on a log axis; zero or negative measurements are clamped up to it.
const LOG_FLOOR: f64 = 1e-6;

/// Ten well-separated colours (the familiar "category 10" set).
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Compact axis tick text: log ticks land on 1, 2, 5 and their decades, which need no padding zeros.
fn tick(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "0" || s == "-0" { format!("{v:.0e}") } else { s.to_string() }
}

/// Labelled ticks of a log axis: 1, 2, 5 times powers of ten, or only the powers when the range spans so
/// many decades that the labels would crowd (plotters' own log ticks give just the decades on short ranges).
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let mantissas: &[f64] = if last - first > 4 { &[1.0] } else { &[1.0, 2.0, 5.0] };
    (first..=last)
        .flat_map(|d| mantissas.iter().map(move |m| m * 10f64.powi(d)))
        .filter(|v| (lo..=hi).contains(v))
        .collect()
}

/// Unlabelled grid lines at every integer multiple within each decade.
fn minor_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (first..=last)
        .flat_map(|d| (1..10).map(move |m| f64::from(m) * 10f64.powi(d)))
        .filter(|v| (lo..=hi).contains(v))
        .collect()
}

/// Error (as a fraction) against median frame time, log-log, one line per (sampler, gather, epsilon) curve,
/// the Pareto front and the error targets. Returns RGBA8 pixels, rows top to bottom.
pub fn error_vs_time(summaries: &[Summary], title: &str, width: u32, height: u32) -> Result<Vec<u8>, PlotError> {
    if summaries.is_empty() {
        return Err(PlotError::NothingToPlot);
    }
    if width < MIN_CHART || height < MIN_CHART {
        return Err(PlotError::ChartTooSmall { width, height });
    }
    ensure_font();
    let drawable: Vec<&Summary> = summaries.iter().filter(|s| s.frame_ms.is_finite() && s.error.is_finite()).collect();
    if drawable.is_empty() {
        return Err(PlotError::NothingFinite);
    }
    let (x, y) = axis_ranges(&drawable);
    let chart = Chart { title, x, y, curves: curves(&drawable), front: pareto_front(&drawable) };
    let mut rgb = vec![255u8; width as usize * height as usize * 3];
    chart.draw(&mut rgb, width, height)?;
    Ok(rgb_to_rgba(&rgb))
}

/// A summary's point in plot units: milliseconds and percent, clamped for the log axes.
fn point(s: &Summary) -> (f64, f64) {
    (s.frame_ms.max(LOG_FLOOR), (100.0 * s.error).max(100.0 * LOG_FLOOR))
}

/// The time and error axes' ranges: the points' with a margin, the error axis always spanning
/// the targets (they are the point of the chart).
fn axis_ranges(drawable: &[&Summary]) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for &s in drawable {
        let (x, y) = point(s);
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    for t in TARGETS {
        (y0, y1) = (y0.min(100.0 * t), y1.max(100.0 * t));
    }
    ((x0 / 1.3, x1 * 1.3), (y0 / 1.5, y1 * 1.5))
}

/// The summaries by curve (`Summary::curve`), each in order of sample count.
fn curves<'a>(drawable: &[&'a Summary]) -> BTreeMap<String, Vec<&'a Summary>> {
    let mut curves: BTreeMap<String, Vec<&Summary>> = BTreeMap::new();
    for &s in drawable {
        curves.entry(s.curve()).or_default().push(s);
    }
    for points in curves.values_mut() {
        points.sort_by_key(|s| s.samples);
    }
    curves
}

/// The points on the Pareto front (`report::pareto`), in order of time.
fn pareto_front(drawable: &[&Summary]) -> Vec<(f64, f64)> {
    let all: Vec<(f64, f64)> = drawable.iter().map(|s| point(s)).collect();
    let mut front: Vec<(f64, f64)> =
        report::pareto(&all).into_iter().zip(&all).filter(|(on, _)| *on).map(|(_, p)| *p).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    front
}

/// What the chart shows, in plot units.
struct Chart<'a> {
    title: &'a str,
    /// Time axis range, ms.
    x: (f64, f64),
    /// Error axis range, %.
    y: (f64, f64),
    curves: BTreeMap<String, Vec<&'a Summary>>,
    front: Vec<(f64, f64)>,
}

impl Chart<'_> {
    /// Draw it into `rgb` (RGB8, `width` x `height`): axes and grid, targets, front, curves, legend.
    fn draw(&self, rgb: &mut [u8], width: u32, height: u32) -> Result<(), PlotError> {
        let ((x0, x1), (y0, y1)) = (self.x, self.y);
        let root = BitMapBackend::with_buffer(rgb, (width, height)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(self.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(65)
            .build_cartesian_2d(
                (x0..x1).log_scale().with_key_points(ticks(x0, x1)).with_light_points(minor_ticks(x0, x1)),
                (y0..y1).log_scale().with_key_points(ticks(y0, y1)).with_light_points(minor_ticks(y0, y1)),
            )?;
        chart
            .configure_mesh()
            .x_desc("frame time, ms (median GPU time)")
            .y_desc("error, % (per-vertex relative RMS, mean of r g b)")
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .light_line_style(RGBColor(242, 242, 242))
            .draw()?;
        self.draw_targets(&mut chart)?;
        self.draw_front(&mut chart)?;
        self.draw_curves(&mut chart)?;
        chart.draw_series(self.front.iter().map(|&p| Cross::new(p, 6, BLACK.stroke_width(2))))?;
        chart
            .configure_series_labels()
            .position(self.legend_corner())
            .label_font(("sans-serif", 12))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
        Ok(root.present()?)
    }

    /// Where the legend covers no point: the upper right, as error falls with time, unless the
    /// points lie in the chart's upper half (error against the light, which the model bounds),
    /// then the lower right.
    fn legend_corner(&self) -> SeriesLabelPosition {
        let (y0, y1) = self.y;
        let middle = (y0 * y1).sqrt();
        let points = self.curves.values().flatten().map(|s| point(s).1);
        let (above, all) = points.fold((0, 0), |(a, n), y| (a + usize::from(y > middle), n + 1));
        if 2 * above > all { SeriesLabelPosition::LowerRight } else { SeriesLabelPosition::UpperRight }
    }

    /// Each error target as a dashed line across the chart, labelled at its left end.
    fn draw_targets<CT: CoordTranslate<From = (f64, f64)>>(
        &self,
        chart: &mut ChartContext<'_, BitMapBackend<'_>, CT>,
    ) -> Result<(), PlotError> {
        let (x0, x1) = self.x;
        let guide = RGBColor(150, 150, 150);
        for t in TARGETS {
            let y = 100.0 * t;
            chart.draw_series(DashedLineSeries::new([(x0, y), (x1, y)], 6, 4, guide.stroke_width(1)))?;
            let label = Text::new(
                format!("{} %", tick(y)),
                (x0 * 1.05, y * 1.04),
                ("sans-serif", 12).into_font().color(&guide),
            );
            chart.draw_series(std::iter::once(label))?;
        }
        Ok(())
    }

    /// A staircase through the front: the best error reachable within each time budget.
    fn draw_front<CT: CoordTranslate<From = (f64, f64)>>(
        &self,
        chart: &mut ChartContext<'_, BitMapBackend<'_>, CT>,
    ) -> Result<(), PlotError> {
        let mut steps = Vec::new();
        for (i, &(x, y)) in self.front.iter().enumerate() {
            if i > 0 {
                steps.push((x, steps.last().map_or(y, |p: &(f64, f64)| p.1)));
            }
            steps.push((x, y));
        }
        let grey = RGBColor(120, 120, 120).mix(0.6);
        chart
            .draw_series(LineSeries::new(steps, grey.stroke_width(5)))?
            .label("Pareto front")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], grey.stroke_width(5)));
        Ok(())
    }

    /// Each curve as a line with markers, in the legend by name.
    fn draw_curves<CT: CoordTranslate<From = (f64, f64)>>(
        &self,
        chart: &mut ChartContext<'_, BitMapBackend<'_>, CT>,
    ) -> Result<(), PlotError> {
        for (i, (name, points)) in self.curves.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            let line: Vec<(f64, f64)> = points.iter().map(|s| point(s)).collect();
            chart
                .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2)));
            // Past ten curves the colours repeat, so the marker shape tells them apart.
            match (i / PALETTE.len()) % 3 {
                0 => chart.draw_series(line.iter().map(|&p| Circle::new(p, 4, colour.filled()))),
                1 => chart.draw_series(line.iter().map(|&p| TriangleMarker::new(p, 5, colour.filled()))),
                _ => chart.draw_series(line.iter().map(|&p| Circle::new(p, 4, colour.stroke_width(2)))),
            }?;
        }
        Ok(())
    }
}

/// Widens tightly packed RGB8 to opaque RGBA8.
pub(crate) fn rgb_to_rgba(rgb: &[u8]) -> Vec<u8> {
    rgb.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(sampler: &str, samples: usize, gather: &str, frame_ms: f64, error: f64) -> Summary {
        Summary {
            model: String::new(),
            total: f64::NAN,
            precompute_s: 0.0,
            sampler: sampler.into(),
            samples,
            gather: gather.into(),
            epsilon: None,
            seeds: 2,
            frame_ms,
            error,
            error_spread: error / 10.0,
            flip_mean: 0.01,
            image_rel_rmse: error / 2.0,
            sampling_ms: 1.0,
            predicted: f64::NAN,
            predicted_worst: f64::NAN,
            error_worst: f64::NAN,
        }
    }

    #[test]
    fn renders_a_chart() {
        let s = vec![
            summary("random", 1000, "vertex", 1.0, 0.2),
            summary("random", 4000, "vertex", 2.5, 0.08),
            summary("random", 16000, "vertex", 7.0, 0.03),
            summary("turk", 1000, "tree", 1.5, 0.05),
            summary("turk", 4000, "tree", 3.0, 0.012),
            summary("turk", 16000, "tree", 6.0, 0.0),
        ];
        let (w, h) = (640, 480);
        let pixels = error_vs_time(&s, "test chart", w, h).unwrap();
        assert_eq!(pixels.len(), (w * h * 4) as usize);
        assert!(pixels.chunks_exact(4).any(|p| p[..3] != [255, 255, 255]));
        assert!(pixels.chunks_exact(4).all(|p| p[3] == 255));
        assert!(error_vs_time(&[], "empty", w, h).is_err());
    }

    #[test]
    fn compact_ticks() {
        assert_eq!(tick(10.0), "10");
        assert_eq!(tick(0.3), "0.3");
        assert_eq!(tick(2.5), "2.5");
        assert_eq!(tick(0.0001), "1e-4");
        assert_eq!(ticks(0.15, 30.0), vec![0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0]);
        assert_eq!(ticks(1e-3, 1e3), vec![1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0, 1000.0]);
    }
}
