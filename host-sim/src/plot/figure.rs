//! The generic figure of `bench` and `reproduce` (plotters, PNG): a grid of panels, each with line,
//! dashed and marker series on linear or logarithmic axes, a legend and optional point labels. Text
//! is drawn with the embedded subset of DejaVu Sans (`assets/`), so no system font is read.

use super::style::register_font;
pub use super::style::{color, PALETTE};
use anyhow::{anyhow, bail, Context, Result};
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Marker shapes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Filled circle.
    Circle,
    /// Filled triangle.
    Triangle,
    /// Filled square.
    Square,
    /// Cross (×).
    Cross,
    /// Open circle.
    Ring,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Style {
    /// A solid line of this width (px).
    Line(u32),
    /// A dashed line.
    Dashed,
    /// Markers of this size (px radius).
    Markers(Marker, u32),
    /// A line with markers.
    LineMarkers(Marker, u32),
}

/// One series of a panel.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend entry (empty: no legend entry).
    pub name: String,
    /// The points (x, y).
    pub points: Vec<(f64, f64)>,
    /// Per-point labels drawn next to markers (empty: none).
    pub labels: Vec<String>,
    /// Colour.
    pub color: RGBColor,
    /// Style.
    pub style: Style,
}

impl Series {
    /// A series without point labels.
    pub fn new(
        name: impl Into<String>,
        points: Vec<(f64, f64)>,
        color: RGBColor,
        style: Style,
    ) -> Self {
        Self {
            name: name.into(),
            points,
            labels: Vec::new(),
            color,
            style,
        }
    }
}

/// One panel (a chart).
#[derive(Debug, Clone)]
pub struct Panel {
    /// Caption above the chart.
    pub title: String,
    /// x axis description (with units).
    pub x_label: String,
    /// y axis description (with units).
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// x range (None: from the data).
    pub x_range: Option<(f64, f64)>,
    /// y range (None: from the data).
    pub y_range: Option<(f64, f64)>,
    /// The series, drawn in order.
    pub series: Vec<Series>,
    /// Where the legend goes (inside the plotting area).
    pub legend: SeriesLabelPosition,
    /// Draw the legend in a column of this width (px) right of the chart instead.
    pub legend_outside: Option<u32>,
    /// Free text lines drawn in the upper left of the plotting area.
    pub notes: Vec<String>,
}

impl Panel {
    /// An empty linear-axes panel.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            log_x: false,
            log_y: false,
            x_range: None,
            y_range: None,
            series: Vec::new(),
            legend: SeriesLabelPosition::UpperRight,
            legend_outside: None,
            notes: Vec::new(),
        }
    }
}

/// A figure: a title and a grid of panels, `cols` per row, each `panel_size` pixels.
#[derive(Debug, Clone)]
pub struct Figure {
    /// Title across the top.
    pub title: String,
    /// The panels, row by row.
    pub panels: Vec<Panel>,
    /// Panels per row (≥ 1).
    pub cols: usize,
    /// Size of one panel (px).
    pub panel_size: (u32, u32),
}

/// Render a figure as PNG to `path`. Errors name the file.
pub fn render_png(fig: &Figure, path: &Path) -> Result<()> {
    register_font()?;
    if fig.panels.is_empty() || fig.cols == 0 {
        bail!("internal: empty figure {}", path.display());
    }
    let rows = fig.panels.len().div_ceil(fig.cols);
    let title_h = 50u32;
    let size = (
        fig.panel_size.0 * fig.cols as u32,
        fig.panel_size.1 * rows as u32 + title_h,
    );
    let ctx = || format!("drawing the figure {}", path.display());
    {
        let root = BitMapBackend::new(path, size).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| anyhow!("{e}"))
            .with_context(ctx)?;
        let (top, body) = root.split_vertically(title_h);
        top.titled(&fig.title, ("sans-serif", 28).into_font().color(&BLACK))
            .map_err(|e| anyhow!("{e}"))
            .with_context(ctx)?;
        let areas = body.split_evenly((rows, fig.cols));
        for (panel, area) in fig.panels.iter().zip(areas.iter()) {
            draw_panel(area, panel).with_context(ctx)?;
        }
        root.present()
            .map_err(|e| anyhow!("{e}"))
            .with_context(ctx)?;
    }
    if !path.is_file() {
        bail!("the figure {} was not written", path.display());
    }
    Ok(())
}

/// Data range of a panel's axis, padded (linear: 5 %; log: a factor 1.5), positive for log axes.
fn range(panel: &Panel, x: bool, log: bool) -> (f64, f64) {
    if let Some(r) = if x { panel.x_range } else { panel.y_range } {
        return r;
    }
    let vals = panel
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| if x { p.0 } else { p.1 }))
        .filter(|v| v.is_finite() && (!log || *v > 0.0));
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (0.1, 10.0) } else { (-1.0, 1.0) };
    }
    if log {
        (lo / 1.5, hi * 1.5)
    } else if hi - lo <= 0.0 {
        (lo - 1.0, hi + 1.0)
    } else {
        let pad = 0.05 * (hi - lo);
        (lo - pad, hi + pad)
    }
}

/// Tick label: plain for moderate magnitudes, else `1e-9` style.
fn tick(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.0e}")
    }
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> Result<()> {
    if let Some(w) = p.legend_outside {
        let (aw, _) = area.dim_in_pixel();
        let (left, right) = area.split_horizontally(aw.saturating_sub(w));
        draw_panel_inner(&left, p, false)?;
        return draw_side_legend(&right, p);
    }
    draw_panel_inner(area, p, true)
}

fn draw_side_legend<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> Result<()> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{e}");
    let font = ("sans-serif", 16).into_font().color(&BLACK);
    let mut y = 70;
    for s in p.series.iter().filter(|s| !s.name.is_empty()) {
        let c = s.color;
        match s.style {
            Style::Line(w) => area
                .draw(&PathElement::new(
                    vec![(8, y), (40, y)],
                    c.stroke_width(w.max(2)),
                ))
                .map_err(e)?,
            Style::Dashed => {
                area.draw(&PathElement::new(vec![(8, y), (18, y)], c.stroke_width(2)))
                    .map_err(e)?;
                area.draw(&PathElement::new(vec![(24, y), (34, y)], c.stroke_width(2)))
                    .map_err(e)?;
            }
            Style::Markers(m, r) => draw_marker_px(area, (24, y), m, r as i32, c)?,
            Style::LineMarkers(m, r) => {
                area.draw(&PathElement::new(vec![(8, y), (40, y)], c.stroke_width(2)))
                    .map_err(e)?;
                draw_marker_px(area, (24, y), m, r as i32, c)?;
            }
        }
        area.draw(&Text::new(s.name.clone(), (48, y - 9), font.clone()))
            .map_err(e)?;
        y += 28;
    }
    Ok(())
}

fn draw_marker_px<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    at: (i32, i32),
    m: Marker,
    r: i32,
    c: RGBColor,
) -> Result<()> {
    let base = EmptyElement::at(at);
    match m {
        Marker::Circle => area.draw(&(base + Circle::new((0, 0), r, c.filled()))),
        Marker::Ring => area.draw(&(base + Circle::new((0, 0), r, c.stroke_width(2)))),
        Marker::Triangle => area
            .draw(&(base + Polygon::new(vec![(0, -r - 1), (-r - 1, r), (r + 1, r)], c.filled()))),
        Marker::Square => area.draw(&(base + Rectangle::new([(-r, -r), (r, r)], c.filled()))),
        Marker::Cross => area.draw(
            &(base
                + PathElement::new(
                    vec![(-r, -r), (r, r), (0, 0), (-r, r), (r, -r)],
                    c.stroke_width(3),
                )),
        ),
    }
    .map_err(|e| anyhow!("{e}"))
}

fn draw_panel_inner<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    legend: bool,
) -> Result<()> {
    let (x0, x1) = range(p, true, p.log_x);
    let (y0, y1) = range(p, false, p.log_y);
    match (p.log_x, p.log_y) {
        (false, false) => draw_chart(area, p, legend, x0..x1, y0..y1),
        (true, false) => draw_chart(area, p, legend, (x0..x1).log_scale(), y0..y1),
        (false, true) => draw_chart(area, p, legend, x0..x1, (y0..y1).log_scale()),
        (true, true) => draw_chart(area, p, legend, (x0..x1).log_scale(), (y0..y1).log_scale()),
    }
}

fn draw_chart<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    p: &Panel,
    legend: bool,
    xs: X,
    ys: Y,
) -> Result<()>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{e}");
    let mut chart = ChartBuilder::on(area)
        .caption(&p.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(55)
        .y_label_area_size(90)
        .build_cartesian_2d(xs, ys)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(p.x_label.as_str())
        .y_desc(p.y_label.as_str())
        .axis_desc_style(("sans-serif", 19))
        .label_style(("sans-serif", 16))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .light_line_style(RGBColor(235, 235, 235))
        .max_light_lines(3)
        .bold_line_style(RGBColor(205, 205, 205))
        .draw()
        .map_err(e)?;
    let mut any_legend = false;
    for s in &p.series {
        let c = s.color;
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        let line_w = match s.style {
            Style::Line(w) => Some(w),
            Style::LineMarkers(..) => Some(2),
            _ => None,
        };
        let mut legend_drawn = false;
        if let Some(w) = line_w {
            let ann = chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(w)))
                .map_err(e)?;
            if !s.name.is_empty() {
                ann.label(s.name.as_str()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(w.max(2)))
                });
                legend_drawn = true;
            }
        }
        if s.style == Style::Dashed {
            let ann = chart
                .draw_series(DashedLineSeries::new(pts.clone(), 8, 5, c.stroke_width(2)))
                .map_err(e)?;
            if !s.name.is_empty() {
                ann.label(s.name.as_str()).legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (8, 0)], c.stroke_width(2))
                        + PathElement::new(vec![(13, 0), (21, 0)], c.stroke_width(2))
                });
                legend_drawn = true;
            }
        }
        if let Style::Markers(m, r) | Style::LineMarkers(m, r) = s.style {
            let r = r as i32;
            let name = (!s.name.is_empty() && !legend_drawn).then_some(s.name.as_str());
            macro_rules! markers {
                ($shape:expr) => {{
                    let shape = $shape;
                    let ann = chart
                        .draw_series(pts.iter().map(|&pt| EmptyElement::at(pt) + shape(r, c)))
                        .map_err(e)?;
                    if let Some(name) = name {
                        ann.label(name)
                            .legend(move |(x, y)| EmptyElement::at((x + 10, y)) + shape(r, c));
                    }
                }};
            }
            match m {
                Marker::Circle => markers!(|r, c: RGBColor| Circle::new((0, 0), r, c.filled())),
                Marker::Ring => {
                    markers!(|r, c: RGBColor| Circle::new((0, 0), r, c.stroke_width(2)))
                }
                Marker::Triangle => markers!(|r: i32, c: RGBColor| Polygon::new(
                    vec![(0, -r - 1), (-r - 1, r), (r + 1, r)],
                    c.filled()
                )),
                Marker::Square => {
                    markers!(|r: i32, c: RGBColor| Rectangle::new([(-r, -r), (r, r)], c.filled()))
                }
                Marker::Cross => markers!(|r: i32, c: RGBColor| PathElement::new(
                    vec![(-r, -r), (r, r), (0, 0), (-r, r), (r, -r)],
                    c.stroke_width(3)
                )),
            }
            legend_drawn |= name.is_some();
            if !s.labels.is_empty() {
                chart
                    .draw_series(pts.iter().zip(&s.labels).map(|(&pt, l)| {
                        EmptyElement::at(pt)
                            + Text::new(
                                l.clone(),
                                (r + 3, -r - 12),
                                ("sans-serif", 14).into_font().color(&c),
                            )
                    }))
                    .map_err(e)?;
            }
        }
        any_legend |= legend_drawn;
    }
    if any_legend && legend {
        chart
            .configure_series_labels()
            .position(p.legend.clone())
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 16))
            .draw()
            .map_err(e)?;
    }
    if !p.notes.is_empty() {
        let area = chart.plotting_area().strip_coord_spec();
        for (i, note) in p.notes.iter().enumerate() {
            area.draw(&Text::new(
                note.clone(),
                (10, 8 + 20 * i as i32),
                ("sans-serif", 15).into_font().color(&RGBColor(60, 60, 60)),
            ))
            .map_err(e)?;
        }
    }
    Ok(())
}
