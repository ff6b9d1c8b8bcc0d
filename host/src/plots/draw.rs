//! Rendering with plotters into an in-memory SVG document: one function per figure,
//! and the colours every figure shares.

use std::io;
use std::panic::{self, AssertUnwindSafe};
use std::path::Path;

use plotters::backend::SVGBackend;
use plotters::chart::{ChartBuilder, ChartContext, SeriesLabelPosition, SeriesLabelStyle};
use plotters::coord::cartesian::Cartesian2d;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::CoordTranslate;
use plotters::coord::Shift;
use plotters::drawing::{DrawingArea, DrawingAreaErrorKind, IntoDrawingArea};
use plotters::element::{PathElement, Rectangle, Text};
use plotters::series::{DashedLineSeries, LineSeries};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{
    Color, IntoFont, RGBColor, ShapeStyle, TextStyle, BLACK, TRANSPARENT, WHITE,
};

use super::stats::{PrCurve, ScoreHist};
use super::PlotError;
use crate::metrics::CalibrationBin;
use mlmap_core::{Gaussian, Histogram, Libm};

/// A series colour.
pub(super) type Colour = RGBColor;

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type DrawResult = Result<(), DrawingAreaErrorKind<io::Error>>;
type UnitChart<'a> = ChartContext<'a, SVGBackend<'a>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The legend box every plot draws: white, framed, at `position`.
trait LegendBox {
    fn legend_box(self, position: SeriesLabelPosition, margin: u32, font: u32) -> DrawResult;
}

impl<'a, 'b, CT: CoordTranslate> LegendBox for SeriesLabelStyle<'a, 'b, SVGBackend<'a>, CT> {
    fn legend_box(mut self, position: SeriesLabelPosition, margin: u32, font: u32) -> DrawResult {
        self.position(position)
            .margin(margin)
            .label_font(("sans-serif", font))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()
    }
}

/// Renders an SVG document in memory with `draw`.
///
/// The renderer is a third-party crate: should it panic on some input, the panic is
/// caught here and reported as [`PlotError::Render`], so an evaluation still reports
/// its metrics.
fn render_svg(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&Area<'_>) -> DrawResult,
) -> Result<String, PlotError> {
    let mut buf = String::new();
    let outcome = panic::catch_unwind(AssertUnwindSafe(|| -> DrawResult {
        let root = SVGBackend::with_string(&mut buf, size).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()
    }));
    let reason = match outcome {
        Ok(Ok(())) => return Ok(buf),
        Ok(Err(e)) => e.to_string(),
        Err(_) => "the SVG renderer panicked".to_string(),
    };
    Err(PlotError::Render {
        path: path.to_path_buf(),
        reason,
    })
}

/// The reliability diagram: accuracy bars over the diagonal, rows per bin below.
pub(super) fn reliability_svg(
    path: &Path,
    title: &str,
    stats: &[CalibrationBin],
    color: RGBColor,
) -> Result<String, PlotError> {
    render_svg(path, (760, 820), |root| {
        draw_reliability(root, title, stats, color)
    })
}

/// True positives left, false positives right.
pub(super) fn scores_svg(
    path: &Path,
    title: &str,
    tp: &ScoreHist,
    fp: &ScoreHist,
    color: RGBColor,
) -> Result<String, PlotError> {
    render_svg(path, (1100, 500), |root| {
        let body = root.titled(title, ("sans-serif", 24))?;
        let (left, right) = body.split_horizontally(body.dim_in_pixel().0 / 2);
        draw_score_panel(&left, "true positives", tp, color.filled())?;
        draw_score_panel(&right, "false positives", fp, color.mix(0.45).filled())
    })
}

/// Precision-recall curves, each `(legend name, colour, curve)`.
pub(super) fn pr_svg(
    path: &Path,
    title: &str,
    curves: &[(String, RGBColor, PrCurve)],
) -> Result<String, PlotError> {
    render_svg(path, (760, 640), |root| draw_pr(root, title, curves))
}

/// One panel per class, at most three per row.
pub(super) fn likelihood_svg(
    path: &Path,
    title: &str,
    panels: &[LikelihoodPanel<'_>],
) -> Result<String, PlotError> {
    let cols = panels.len().clamp(1, 3);
    let rows = panels.len().div_ceil(cols).max(1);
    let width = u32::try_from(cols * 500).unwrap_or(u32::MAX);
    let height = u32::try_from(rows * 380 + 50).unwrap_or(u32::MAX);
    render_svg(path, (width, height), |root| {
        let body = root.titled(title, ("sans-serif", 22))?;
        for (panel, area) in panels.iter().zip(body.split_evenly((rows, cols))) {
            draw_likelihood_panel(&area, panel)?;
        }
        Ok(())
    })
}

/// Okabe–Ito colours, readable by colour-blind viewers.
pub(super) fn method_color(method: &str) -> RGBColor {
    match method {
        "sigmoid" => RGBColor(230, 159, 0),
        "softmax" => RGBColor(213, 94, 0),
        "temperature" => RGBColor(204, 121, 167),
        "ml" => RGBColor(0, 114, 178),
        "map" => RGBColor(0, 158, 115),
        "bayes" => RGBColor(0, 0, 0),
        "open" => RGBColor(86, 180, 233),
        other => {
            const OTHERS: [RGBColor; 3] = [
                RGBColor(86, 180, 233),
                RGBColor(120, 120, 120),
                RGBColor(40, 40, 40),
            ];
            let h = other.bytes().fold(0usize, |h, b| {
                h.wrapping_mul(31).wrapping_add(usize::from(b))
            });
            OTHERS.get(h % OTHERS.len()).copied().unwrap_or(BLACK)
        }
    }
}

/// The colour of class `c`, by index.
pub(super) fn class_color(c: usize) -> RGBColor {
    const CLASSES: [RGBColor; 10] = [
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
    CLASSES.get(c % CLASSES.len()).copied().unwrap_or(BLACK)
}

/// Numbers on axes and in captions: at most three decimals without trailing zeros, or
/// scientific notation for very large or very small values.
pub(super) fn axis_number(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        return format!("{v:.2e}");
    }
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

fn unit_tick(v: &f64) -> String {
    format!("{v:.1}")
}

fn legend_box(color: ShapeStyle) -> impl Fn((i32, i32)) -> Rectangle<(i32, i32)> {
    move |(x, y)| Rectangle::new([(x, y - 6), (x + 16, y + 6)], color)
}

fn legend_line(color: ShapeStyle) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color)
}

fn draw_reliability(
    root: &Area<'_>,
    title: &str,
    stats: &[CalibrationBin],
    color: RGBColor,
) -> DrawResult {
    let body = root.titled(title, ("sans-serif", 24))?;
    let height = body.dim_in_pixel().1 as i32;
    let (top, bottom) = body.split_vertically(height * 3 / 4);
    let bar = color.mix(0.8).filled();
    let gap = RGBColor(244, 165, 165).filled();
    let gap_edge = RGBColor(180, 30, 30).stroke_width(1);

    let mut chart = unit_chart(&top, 12, ("confidence", "accuracy"), 1.0)?;
    // (lo, hi, accuracy, mean confidence) of the bins holding rows.
    let filled: Vec<(f64, f64, f64, f64)> = stats
        .iter()
        .filter_map(|b| Some((b.lo, b.hi, b.accuracy?, b.confidence?)))
        .collect();
    chart
        .draw_series(
            filled
                .iter()
                .map(|&(lo, hi, acc, _)| Rectangle::new([(lo, 0.0), (hi, acc)], bar)),
        )?
        .label("accuracy of the bin")
        .legend(legend_box(bar));
    chart
        .draw_series(
            filled
                .iter()
                .map(|&(lo, hi, acc, conf)| Rectangle::new([(lo, acc), (hi, conf)], gap)),
        )?
        .label("gap |accuracy - mean confidence|")
        .legend(legend_box(gap));
    chart.draw_series(
        filled
            .iter()
            .map(|&(lo, hi, acc, _)| Rectangle::new([(lo, 0.0), (hi, acc)], BLACK.stroke_width(1))),
    )?;
    chart.draw_series(
        filled
            .iter()
            .map(|&(lo, hi, acc, conf)| Rectangle::new([(lo, acc), (hi, conf)], gap_edge)),
    )?;
    chart
        .draw_series(DashedLineSeries::new(
            [(0.0, 0.0), (1.0, 1.0)],
            8,
            5,
            BLACK.stroke_width(2),
        ))?
        .label("perfect calibration")
        .legend(legend_line(BLACK.stroke_width(2)));
    chart
        .configure_series_labels()
        .legend_box(SeriesLabelPosition::UpperLeft, 12, 15)?;

    let max_count = stats.iter().map(|b| b.count).max().unwrap_or(0).max(1) as f64;
    let mut counts = ChartBuilder::on(&bottom)
        .margin(12)
        .margin_top(4)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..1f64, 0f64..max_count * 1.25)?;
    draw_mesh(&mut counts, ("confidence", "rows"), Some(4))?;
    counts.draw_series(stats.iter().map(|b| {
        Rectangle::new(
            [(b.lo, 0.0), (b.hi, b.count as f64)],
            RGBColor(150, 150, 150).filled(),
        )
    }))?;
    if stats.len() <= 20 {
        let style = TextStyle::from(("sans-serif", 12).into_font())
            .pos(Pos::new(HPos::Center, VPos::Bottom));
        counts.draw_series(stats.iter().map(|b| {
            Text::new(
                format!("{}", b.count),
                ((b.lo + b.hi) / 2.0, b.count as f64),
                style.clone(),
            )
        }))?;
    }
    Ok(())
}

fn draw_score_panel(area: &Area<'_>, what: &str, hist: &ScoreHist, bar: ShapeStyle) -> DrawResult {
    let max = hist.counts.iter().copied().max().unwrap_or(0).max(1) as f64;
    let mut chart = ChartBuilder::on(area)
        .caption(what, ("sans-serif", 20))
        .margin(14)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..1f64, 0f64..max * 1.15)?;
    draw_mesh(&mut chart, ("score (largest of the row)", "rows"), Some(6))?;
    let m = hist.counts.len().max(1) as f64;
    chart
        .draw_series(hist.counts.iter().enumerate().map(|(k, &n)| {
            Rectangle::new([(k as f64 / m, 0.0), ((k + 1) as f64 / m, n as f64)], bar)
        }))?
        .label(format!("{what} (n = {})", hist.n))
        .legend(legend_box(bar));
    chart.draw_series(hist.counts.iter().enumerate().map(|(k, &n)| {
        Rectangle::new(
            [(k as f64 / m, 0.0), ((k + 1) as f64 / m, n as f64)],
            BLACK.stroke_width(1),
        )
    }))?;
    let mean_style = BLACK.stroke_width(2);
    match hist.mean {
        Some(mean) => {
            chart
                .draw_series(DashedLineSeries::new(
                    [(mean, 0.0), (mean, max * 1.15)],
                    6,
                    4,
                    mean_style,
                ))?
                .label(format!("mean = {mean:.3}"))
                .legend(legend_line(mean_style));
        }
        None => {
            chart
                .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())?
                .label("mean = n/a")
                .legend(legend_line(mean_style));
        }
    }
    // The legend goes where the scores are not.
    let position = if hist.mean.unwrap_or(0.0) > 0.5 {
        SeriesLabelPosition::UpperLeft
    } else {
        SeriesLabelPosition::UpperRight
    };
    chart.configure_series_labels().legend_box(position, 10, 15)
}

/// A chart of `[0, 1] x [0, y_max]` with both axes ticked every tenth, its axes
/// described by `desc` (x, y).
fn unit_chart<'a>(
    area: &Area<'a>,
    margin: u32,
    desc: (&str, &str),
    y_max: f64,
) -> Result<UnitChart<'a>, DrawingAreaErrorKind<io::Error>> {
    let mut chart = ChartBuilder::on(area)
        .margin(margin)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..1f64, 0f64..y_max)?;
    draw_mesh(&mut chart, desc, None)?;
    Ok(chart)
}

/// The axes of a chart over `[0, 1]` on x: both ticked every tenth, or with
/// `counts = Some(n)` whole numbers in `n` ticks on y (and no vertical grid lines).
fn draw_mesh(chart: &mut UnitChart<'_>, desc: (&str, &str), counts: Option<usize>) -> DrawResult {
    let count_tick = |v: &f64| format!("{v:.0}");
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(desc.0)
        .y_desc(desc.1)
        .x_labels(11)
        .x_label_formatter(&unit_tick)
        .light_line_style(TRANSPARENT)
        .axis_desc_style(("sans-serif", 16))
        .label_style(("sans-serif", 13));
    match counts {
        Some(n) => mesh
            .y_labels(n)
            .y_label_formatter(&count_tick)
            .disable_x_mesh()
            .draw(),
        None => mesh.y_labels(11).y_label_formatter(&unit_tick).draw(),
    }
}

fn draw_pr(root: &Area<'_>, title: &str, curves: &[(String, RGBColor, PrCurve)]) -> DrawResult {
    let body = root.titled(title, ("sans-serif", 22))?;
    let mut chart = unit_chart(&body, 14, ("recall", "precision"), 1.02)?;
    for (name, color, curve) in curves {
        let style = color.stroke_width(2);
        let label = match curve.ap {
            Some(ap) => format!("{name} (AP = {ap:.4})"),
            None => format!("{name} (no positives)"),
        };
        chart
            .draw_series(LineSeries::new(curve.points.iter().copied(), style))?
            .label(label)
            .legend(legend_line(style));
    }
    chart
        .configure_series_labels()
        .legend_box(SeriesLabelPosition::LowerLeft, 12, 15)
}

/// One class of [`fitted_histograms`].
pub(super) struct LikelihoodPanel<'a> {
    pub(super) name: &'a str,
    /// Training rows of the class.
    pub(super) rows: u64,
    pub(super) hist: &'a Histogram<Vec<f32>>,
    pub(super) prior: &'a Gaussian,
    pub(super) color: RGBColor,
}

/// Points of the prior's curve across `[x0, x1]`, the mean included.
const PDF_SAMPLES: usize = 400;

fn draw_likelihood_panel(area: &Area<'_>, panel: &LikelihoodPanel<'_>) -> DrawResult {
    let hist = panel.hist;
    let mean = f64::from(panel.prior.mean());
    let variance = f64::from(panel.prior.variance());
    let (lo, hi) = (f64::from(hist.lo()), f64::from(hist.hi()));
    let sd = variance.sqrt();
    let mut x0 = lo.min(mean - 3.0 * sd);
    let mut x1 = hi.max(mean + 3.0 * sd);
    let pad = (x1 - x0) * 0.03;
    x0 -= pad;
    x1 += pad;
    if !(x0.is_finite() && x1.is_finite() && x1 > x0) {
        (x0, x1) = (lo - 1.0, hi + 1.0);
    }

    let mut xs: Vec<f64> = (0..=PDF_SAMPLES)
        .map(|i| x0 + (x1 - x0) * i as f64 / PDF_SAMPLES as f64)
        .collect();
    xs.push(mean);
    xs.sort_by(f64::total_cmp);
    let curve: Vec<(f64, f64)> = xs
        .iter()
        .map(|&x| (x, f64::from(panel.prior.pdf::<Libm>(x as f32))))
        .collect();
    let pdf_max = curve.iter().map(|p| p.1).fold(0.0, f64::max);
    let freq_max = hist
        .frequencies()
        .iter()
        .map(|&f| f64::from(f))
        .fold(0.0, f64::max);
    let y_top = if freq_max > 0.0 { freq_max * 1.4 } else { 1.0 };
    let p_top = if pdf_max > 0.0 && pdf_max.is_finite() {
        pdf_max * 1.4
    } else {
        1.0
    };

    let caption = format!(
        "{} (n = {}): μ = {}, σ² = {}",
        panel.name,
        panel.rows,
        axis_number(mean),
        axis_number(variance)
    );
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 17))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .right_y_label_area_size(62)
        .build_cartesian_2d(x0..x1, 0f64..y_top)?
        .set_secondary_coord(x0..x1, 0f64..p_top);
    chart
        .configure_mesh()
        .x_desc("logit")
        .y_desc("frequency")
        .x_labels(7)
        .y_labels(6)
        .x_label_formatter(&|v| axis_number(*v))
        .y_label_formatter(&|v| axis_number(*v))
        .disable_x_mesh()
        .light_line_style(TRANSPARENT)
        .axis_desc_style(("sans-serif", 14))
        .label_style(("sans-serif", 12))
        .draw()?;
    chart
        .configure_secondary_axes()
        .y_desc("prior density")
        .y_labels(6)
        .y_label_formatter(&|v| axis_number(*v))
        .axis_desc_style(("sans-serif", 14))
        .label_style(("sans-serif", 12))
        .draw()?;
    let bar = panel.color.mix(0.7).filled();
    let bars: Vec<(f64, f64, f64)> = hist
        .frequencies()
        .iter()
        .enumerate()
        .map(|(k, &f)| {
            (
                f64::from(hist.edge(k)),
                f64::from(hist.edge(k + 1)),
                f64::from(f),
            )
        })
        .collect();
    chart
        .draw_series(
            bars.iter()
                .map(|&(a, b, f)| Rectangle::new([(a, 0.0), (b, f)], bar)),
        )?
        .label(format!("histogram ({} bins)", hist.bins()))
        .legend(legend_box(bar));
    chart.draw_series(
        bars.iter()
            .map(|&(a, b, f)| Rectangle::new([(a, 0.0), (b, f)], panel.color.stroke_width(1))),
    )?;
    let line = BLACK.stroke_width(2);
    chart
        .draw_secondary_series(LineSeries::new(curve, line))?
        .label("prior N(μ, σ²), right axis")
        .legend(legend_line(line));
    chart
        .configure_series_labels()
        .legend_box(SeriesLabelPosition::UpperRight, 8, 13)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_numbers_are_short() {
        const VECTORS: &[(f64, &str)] = &[
            (0.0, "0"),
            (-0.0, "0"),
            (4.0, "4"),
            (-1.25, "-1.25"),
            (0.123_456, "0.123"),
            (1.5e-12, "1.50e-12"),
            (4.0e5, "4.00e5"),
        ];
        for &(v, want) in VECTORS {
            assert_eq!(axis_number(v), want, "{v}");
        }
    }

    #[test]
    fn colours_are_stable() {
        assert_eq!(method_color("ml"), RGBColor(0, 114, 178));
        assert_eq!(method_color("custom"), method_color("custom"));
        assert_ne!(class_color(0), class_color(1));
        assert_eq!(class_color(0), class_color(10));
    }
}
