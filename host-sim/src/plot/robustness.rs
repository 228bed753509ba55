//! The robustness scorecard's figure (`robustness.png`): a horizontal bar chart of the RMS error
//! (% of the peak, log axis) per perturbation, one colour per scene, one panel per mode, with the
//! mode's RMS goal as a dashed line.

use super::style::{color, register_font};
use crate::report::robustness::{Row, GOAL_FUSE_RMS_PCT, GOAL_PREDICT_RMS_PCT};
use anyhow::{anyhow, bail, Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor;
use std::path::Path;

/// Errors below this are drawn at it (the log axis's left end, % of the peak).
const FLOOR: f64 = 1e-3;
/// Errors above this are drawn at it, with a `>` (% of the peak).
const CEIL: f64 = 1e3;
/// Height of one perturbation's band (px).
const BAND: u32 = 30;
/// Empty bands above the first perturbation, for the legend.
const HEAD: f64 = 2.6;

/// Render the figure of the rows to `path` (PNG). Errors name the file.
pub fn figure(rows: &[Row], path: &Path) -> Result<()> {
    register_font()?;
    let mut ids: Vec<&str> = Vec::new();
    let mut scenes: Vec<&str> = Vec::new();
    let mut modes: Vec<&str> = Vec::new();
    for r in rows {
        if !ids.contains(&r.perturbation) {
            ids.push(r.perturbation);
        }
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
        if !modes.contains(&r.mode) {
            modes.push(r.mode);
        }
    }
    if ids.is_empty() {
        bail!("internal: no rows for {}", path.display());
    }
    let title_h = 50u32;
    let panel_w = 820u32;
    let panel_h = BAND * ids.len() as u32 + 250;
    let size = (panel_w * modes.len() as u32, panel_h + title_h);
    let ctx = || format!("drawing the figure {}", path.display());
    {
        let root = BitMapBackend::new(path, size).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| anyhow!("{e}"))
            .with_context(ctx)?;
        let (top, body) = root.split_vertically(title_h);
        top.titled(
            "host-sim robustness: RMS error against perturbation",
            ("sans-serif", 28).into_font().color(&BLACK),
        )
        .map_err(|e| anyhow!("{e}"))
        .with_context(ctx)?;
        let areas = body.split_evenly((1, modes.len()));
        for (mode, area) in modes.iter().zip(areas.iter()) {
            panel(area, rows, mode, &ids, &scenes)
                .map_err(|e| anyhow!("{e}"))
                .with_context(ctx)?;
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

/// One mode's panel: perturbations top to bottom in their order, one bar per scene.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    rows: &[Row],
    mode: &str,
    ids: &[&str],
    scenes: &[&str],
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let n = ids.len() as f64;
    let hi = rows
        .iter()
        .filter(|r| r.mode == mode)
        .map(|r| r.rms_pct_of_peak.clamp(FLOOR, CEIL))
        .fold(1.0, f64::max)
        * 3.0;
    let goal = if mode == "fuse" {
        GOAL_FUSE_RMS_PCT
    } else {
        GOAL_PREDICT_RMS_PCT
    };
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("{mode} (dashed: the goal, RMS ≤ {goal} %)"),
            ("sans-serif", 22),
        )
        .margin(12)
        .x_label_area_size(55)
        .y_label_area_size(190)
        .build_cartesian_2d((FLOOR..hi).log_scale(), 0.0..n + HEAD)?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(0)
        .x_desc("RMS error (% of the peak)")
        .axis_desc_style(("sans-serif", 19))
        .label_style(("sans-serif", 16))
        .x_label_formatter(&|v| format!("{v}"))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(205, 205, 205))
        .draw()?;
    // Band i (from the top) spans y in [n − i − 1, n − i]; the scenes' bars split it.
    let k = scenes.len() as f64;
    let bar = 0.8 / k;
    for (j, scene) in scenes.iter().enumerate() {
        let c = color(j);
        let bars: Vec<Rectangle<(f64, f64)>> = rows
            .iter()
            .filter(|r| r.mode == mode && r.scene == *scene)
            .filter_map(|r| {
                let i = ids.iter().position(|id| *id == r.perturbation)? as f64;
                let y1 = n - i - 0.1 - j as f64 * bar;
                let v = r.rms_pct_of_peak;
                let v = if v.is_finite() {
                    v.clamp(FLOOR, CEIL)
                } else {
                    CEIL
                };
                Some(Rectangle::new([(FLOOR, y1 - bar), (v, y1)], c.filled()))
            })
            .collect();
        chart
            .draw_series(bars)?
            .label(*scene)
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 16, y + 6)], c.filled()));
    }
    let over: Vec<Text<(f64, f64), String>> = rows
        .iter()
        .filter(|r| r.mode == mode && (!r.rms_pct_of_peak.is_finite() || r.rms_pct_of_peak > CEIL))
        .filter_map(|r| {
            let i = ids.iter().position(|id| *id == r.perturbation)? as f64;
            let j = scenes.iter().position(|s| *s == r.scene)? as f64;
            Some(Text::new(
                ">".to_string(),
                (CEIL * 1.1, n - i - 0.1 - j * bar),
                ("sans-serif", 12).into_font(),
            ))
        })
        .collect();
    chart.draw_series(over)?;
    chart.draw_series(DashedLineSeries::new(
        [(goal, 0.0), (goal, n + HEAD)],
        6,
        4,
        BLACK.stroke_width(2),
    ))?;
    // The perturbations' ids, right-aligned left of the axis, centred on their band.
    let label = ("sans-serif", 15)
        .into_font()
        .color(&BLACK)
        .pos(text_anchor::Pos::new(
            text_anchor::HPos::Right,
            text_anchor::VPos::Center,
        ));
    for (i, id) in ids.iter().enumerate() {
        let (x, y) = chart.backend_coord(&(FLOOR, n - i as f64 - 0.5));
        let (x0, y0) = area.get_base_pixel();
        area.draw(&Text::new(
            id.to_string(),
            (x - x0 - 8, y - y0),
            label.clone(),
        ))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 16))
        .draw()?;
    Ok(())
}
