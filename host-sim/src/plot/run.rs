//! The `run --plot` figure (plotters): SVG or PNG by the file's extension.
//!
//! Two panels over the plot window: top, the top-mass acceleration ü1 (m/s²) measured, predicted
//! by the estimator and true (thin); bottom, the slip (mm), measured and true, with the detected
//! slip starts/reversals (at their back-dated times), the detected sticks and the true events.
//! PNG text is drawn with an embedded subset of DejaVu Sans (`assets/`), so no system font is read.

use super::style::register_font;
use crate::run::{EventMark, PlotData, Series};
use anyhow::{anyhow, bail, Context, Result};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Figure size in pixels (width, height).
pub const SIZE: (u32, u32) = (1600, 1000);

/// The output format, from the file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// `.svg`
    Svg,
    /// `.png`
    Png,
}

/// The format of a plot file: `.svg` or `.png` (case-insensitive); anything else is an error.
pub fn format_of(path: &Path) -> Result<Format> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("svg") => Ok(Format::Svg),
        Some("png") => Ok(Format::Png),
        _ => bail!(
            "--plot {}: unsupported file type, expected a .svg or .png file",
            path.display()
        ),
    }
}

/// Render the figure to `path` (.svg or .png). Errors name the file.
pub fn render(data: &PlotData, path: &Path) -> Result<()> {
    let format = format_of(path)?;
    register_font()?;
    let ctx = || format!("drawing the plot {}", path.display());
    match format {
        Format::Svg => {
            let root = SVGBackend::new(path, SIZE).into_drawing_area();
            draw(&root, data, false)
                .map_err(|e| anyhow!("{e}"))
                .with_context(ctx)?;
            root.present()
                .map_err(|e| anyhow!("{e}"))
                .with_context(ctx)?;
        }
        Format::Png => {
            let root = BitMapBackend::new(path, SIZE).into_drawing_area();
            draw(&root, data, true)
                .map_err(|e| anyhow!("{e}"))
                .with_context(ctx)?;
            root.present()
                .map_err(|e| anyhow!("{e}"))
                .with_context(ctx)?;
        }
    }
    // plotters reports some write failures only on drop; make sure the file is there.
    if !path.is_file() {
        bail!("the plot {} was not written", path.display());
    }
    Ok(())
}

/// (min, max) of the values of some series, widened by 5 % below and `top` (a fraction of the
/// span) above, for the legend (a flat or empty range gets ±1).
fn y_range<'a>(series: impl IntoIterator<Item = &'a Series>, top: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for s in series {
        for &(_, v) in s {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    if hi - lo <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
        return (lo - 1.0, hi + 1.0);
    }
    let span = hi - lo;
    (lo - 0.05 * span, hi + top * span)
}

/// Tick labels with as many decimals as the axis span needs, and no "-0".
fn tick_label(v: f64, span: f64) -> String {
    let decimals = if span > 0.0 && span.is_finite() {
        (1.0 - span.log10().floor()).clamp(0.0, 9.0) as usize
    } else {
        1
    };
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// A line series: one polyline, or (for the bitmap backend and widths > 1) one element per segment,
/// because plotters' thick polylines overshoot at sharp turns (plotters issue #549).
fn line<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    data: &Series,
    style: ShapeStyle,
    segmented: bool,
    label: &str,
) -> DrawResult<DB> {
    let legend = move |(x, y): (i32, i32)| PathElement::new([(x, y), (x + 28, y)], style);
    // An empty series (a replay has no truth) gets no legend entry.
    if data.is_empty() {
        return Ok(());
    }
    if segmented && style.stroke_width > 1 {
        chart
            .draw_series(
                data.windows(2)
                    .map(|w| PathElement::new([w[0], w[1]], style)),
            )?
            .label(label)
            .legend(legend);
    } else {
        chart
            .draw_series(LineSeries::new(data.iter().copied(), style))?
            .label(label)
            .legend(legend);
    }
    Ok(())
}

fn scaled(s: &Series, k: f64) -> Series {
    s.iter().map(|&(t, v)| (t, v * k)).collect()
}

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    d: &PlotData,
    segmented: bool,
) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let (from, to) = d.window;
    let t_lo = d
        .truth
        .first()
        .or(d.predicted.first())
        .map_or(from, |p| p.0)
        .min(d.measured.first().map_or(from, |p| p.0));
    let t_hi = d
        .truth
        .last()
        .or(d.measured.last())
        .or(d.predicted.last())
        .map_or(to, |p| p.0)
        .max(t_lo + 1e-9);
    let what = if d.truth.is_empty() {
        "replay"
    } else {
        "estimator run"
    };
    let title = format!("{} — {what}, t = {:.3} … {:.3} s", d.scene, t_lo, t_hi);
    let root = root.titled(&title, ("sans-serif", 26))?;
    let (top, bottom) = root.split_vertically((56).percent_height());

    // Top: ü1.
    let (y0, y1) = y_range([&d.measured, &d.predicted, &d.truth], 0.3);
    let t_span = t_hi - t_lo;
    let fmt_t = move |v: &f64| tick_label(*v, t_span);
    let mut chart = ChartBuilder::on(&top)
        .margin(12)
        .margin_right(24)
        .x_label_area_size(48)
        .y_label_area_size(86)
        .build_cartesian_2d(t_lo..t_hi, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc("time t (s)")
        .y_desc("top-mass acceleration ü1 (m/s²)")
        .x_label_formatter(&fmt_t)
        .y_label_formatter(&|v| tick_label(*v, y1 - y0))
        .label_style(("sans-serif", 18))
        .axis_desc_style(("sans-serif", 20))
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    // Opaque colours: a segmented thick line with alpha would darken at the joints.
    let measured = RGBColor(150, 185, 240);
    let predicted = RGBColor(215, 40, 40);
    let m_style = measured.stroke_width(4);
    let p_style = predicted.stroke_width(2);
    let t_style = BLACK.stroke_width(1);
    let m_label = "measured (top accelerometer)";
    line(&mut chart, &d.measured, m_style, segmented, m_label)?;
    line(
        &mut chart,
        &d.predicted,
        p_style,
        segmented,
        "predicted (estimator, f32)",
    )?;
    line(
        &mut chart,
        &d.truth,
        t_style,
        segmented,
        "truth (exact stick-slip)",
    )?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 18))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.5))
        .draw()?;

    // Bottom: slip in mm with the events.
    let slip_m = scaled(&d.slip_measured, 1e3);
    let slip_t = scaled(&d.slip_truth, 1e3);
    let (s0, s1) = y_range([&slip_m, &slip_t], 0.8);
    let mut chart = ChartBuilder::on(&bottom)
        .margin(12)
        .margin_right(24)
        .x_label_area_size(48)
        .y_label_area_size(86)
        .build_cartesian_2d(t_lo..t_hi, s0..s1)?;
    chart
        .configure_mesh()
        .x_desc("time t (s)")
        .y_desc("slip, base to table (mm)")
        .x_label_formatter(&fmt_t)
        .y_label_formatter(&|v| tick_label(*v, s1 - s0))
        .label_style(("sans-serif", 18))
        .axis_desc_style(("sans-serif", 20))
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    line(&mut chart, &slip_m, m_style, segmented, "measured slip")?;
    line(&mut chart, &slip_t, t_style, segmented, "true slip")?;
    let pts = |v: &[(EventMark, f64)], stick: bool| -> Vec<(f64, f64)> {
        v.iter()
            .filter(|(e, _)| e.stick == stick && e.time_s >= t_lo && e.time_s <= t_hi)
            .map(|(e, x)| (e.time_s, 1e3 * x))
            .collect()
    };
    let green = RGBColor(0, 150, 60);
    // A replay has no truth: no true events in the legend.
    let has_truth = !d.truth.is_empty();
    if has_truth {
        chart
            .draw_series(
                pts(&d.true_events, false)
                    .into_iter()
                    .map(|p| Cross::new(p, 7, BLACK.stroke_width(2))),
            )?
            .label("true slip start / reversal")
            .legend(|(x, y)| Cross::new((x + 14, y), 7, BLACK.stroke_width(2)));
    }
    chart
        .draw_series(
            pts(&d.detected, false)
                .into_iter()
                .map(|p| Circle::new(p, 8, predicted.stroke_width(2))),
        )?
        .label("detected slip start / reversal (back-dated)")
        .legend(move |(x, y)| Circle::new((x + 14, y), 8, predicted.stroke_width(2)));
    let true_sticks = pts(&d.true_events, true);
    let det_sticks = pts(&d.detected, true);
    if !true_sticks.is_empty() || !det_sticks.is_empty() {
        if has_truth {
            chart
                .draw_series(
                    true_sticks
                        .into_iter()
                        .map(|p| TriangleMarker::new(p, 7, BLACK.filled())),
                )?
                .label("true stick")
                .legend(|(x, y)| TriangleMarker::new((x + 14, y), 7, BLACK.filled()));
        }
        chart
            .draw_series(
                det_sticks
                    .into_iter()
                    .map(|p| TriangleMarker::new(p, 9, green.stroke_width(2))),
            )?
            .label("detected stick")
            .legend(move |(x, y)| TriangleMarker::new((x + 14, y), 9, green.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 18))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.5))
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_by_extension() {
        assert_eq!(format_of(Path::new("a.svg")).unwrap(), Format::Svg);
        assert_eq!(format_of(Path::new("a.PNG")).unwrap(), Format::Png);
        let e = format_of(Path::new("dir/a.pdf")).unwrap_err().to_string();
        assert!(e.contains("dir/a.pdf"), "{e}");
        assert!(format_of(Path::new("noext")).is_err());
    }

    #[test]
    fn ranges_are_padded_and_never_flat() {
        let s: Series = vec![(0.0, -1.0), (1.0, 3.0)];
        let (a, b) = y_range([&s], 0.5);
        assert!((a + 1.2).abs() < 1e-12 && (b - 5.0).abs() < 1e-12);
        let flat: Series = vec![(0.0, 2.0)];
        assert_eq!(y_range([&flat], 0.3), (1.0, 3.0));
        assert_eq!(y_range([&Series::new()], 0.3), (-1.0, 1.0));
    }

    #[test]
    fn tick_labels() {
        assert_eq!(tick_label(-0.0001, 2.0), "0.0");
        assert_eq!(tick_label(-0.2, 2.0), "-0.2");
        assert_eq!(tick_label(0.05, 0.5), "0.05");
        assert_eq!(tick_label(4.0, 10.0), "4");
    }
}
