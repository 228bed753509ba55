//! The bench's Pareto figures (`pareto-<scene>.png`): error against host cost per sample, one panel
//! per reference (the full closed form, the truth, the double-double sum), with the Pareto front.

use super::figure::{self, Figure, Marker, Panel, Series, Style};
use crate::report::bench::{BenchScene, Report, Row};

/// Floor at which exact zeros are drawn on the log error axis.
const ZERO_FLOOR: f64 = 1e-17;

/// The Pareto figure of one scene: error against cost, one panel per reference.
pub fn pareto_figure(r: &Report, sc: &BenchScene) -> Figure {
    let rows: Vec<&Row> = r.rows.iter().filter(|row| row.scene == sc.id).collect();
    let families: [(&str, &str, Marker, usize); 6] = [
        (
            "rdm-recursion",
            "RDM recursion (estimator)",
            Marker::Circle,
            0,
        ),
        ("rdm-closed", "RDM closed form, full sum", Marker::Square, 6),
        (
            "rdm-truncated",
            "RDM closed form, K newest terms",
            Marker::Triangle,
            1,
        ),
        ("rfm", "RFM, H harmonics", Marker::Ring, 2),
        ("tfm", "TFM, H harmonics", Marker::Cross, 3),
        ("truth", "exact stick-slip truth", Marker::Square, 4),
    ];
    let short = |row: &Row| -> String {
        match row.method.as_str() {
            "rdm-recursion" => match (row.precision.as_str(), row.setting.as_str()) {
                ("f64", _) => "f64".into(),
                (_, s) if s.starts_with("F32Poly") => "f32 poly (fw)".into(),
                (_, s) => format!("f32 {s}"),
            },
            "rdm-closed" => String::new(),
            "truth" => String::new(),
            _ => row.setting.clone(),
        }
    };
    let mut panels = Vec::new();
    type Get = Box<dyn Fn(&Row) -> Option<f64>>;
    let kinds: Vec<(&str, bool, Get)> = vec![
        (
            "numerical: max error against the full f64 closed form",
            false,
            Box::new(|row: &Row| Some(row.max_err_gmu)),
        ),
        (
            "model: max error against the exact stick-slip truth",
            true,
            Box::new(|row: &Row| row.max_err_vs_truth_gmu),
        ),
        (
            "numerical: max error against a double-double evaluation",
            false,
            Box::new(|row: &Row| row.max_err_vs_dd_gmu),
        ),
    ];
    for (title, model, get) in kinds {
        if rows.iter().all(|row| get(row).is_none()) {
            continue;
        }
        let mut p = Panel::new(
            title,
            "host cost (ns per sample, log)",
            "max |error| (gμ, log)",
        );
        p.log_x = true;
        p.log_y = true;
        p.legend = plotters::prelude::SeriesLabelPosition::UpperRight;
        let mut any_zero = false;
        for (method, label, marker, ci) in families {
            let mut pts = Vec::new();
            let mut labels = Vec::new();
            for row in rows.iter().filter(|row| row.method == method) {
                if model && method == "truth" {
                    continue; // the reference of this panel
                }
                if let Some(e) = get(row) {
                    if e == 0.0 {
                        any_zero = true;
                    }
                    pts.push((row.ns_per_sample, e.max(ZERO_FLOOR)));
                    labels.push(short(row));
                }
            }
            if pts.is_empty() {
                continue;
            }
            let style = if pts.len() > 1 && matches!(method, "rdm-truncated" | "rfm" | "tfm") {
                Style::LineMarkers(marker, 6)
            } else {
                Style::Markers(marker, 7)
            };
            merge_close_labels(&pts, &mut labels);
            let mut s = Series::new(label, pts, figure::color(ci), style);
            s.labels = labels;
            p.series.push(s);
        }
        // The Pareto front: the lower-left envelope of every point.
        let mut all: Vec<(f64, f64)> = p.series.iter().flat_map(|s| s.points.clone()).collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut front = Vec::new();
        let mut best = f64::INFINITY;
        for (x, y) in all {
            if y < best {
                best = y;
                front.push((x, y));
            }
        }
        p.series.insert(
            0,
            Series::new("Pareto front", front, figure::color(8), Style::Dashed),
        );
        let ymax = p
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|q| q.1))
            .fold(ZERO_FLOOR, f64::max);
        let (xmin, xmax) = p
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|q| q.0))
            .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
        p.x_range = Some((xmin / 2.0, xmax * 4.0));
        let ymin = p
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|q| q.1))
            .fold(f64::INFINITY, f64::min);
        p.y_range = Some((ymin.max(ZERO_FLOOR) / 5.0, ymax * 20.0));
        p.legend_outside = Some(330);
        if any_zero {
            p.notes.push(format!(
                "error 0 (the reference itself) drawn at {ZERO_FLOOR:.0e}"
            ));
        }
        panels.push(p);
    }
    let cols = panels.len().max(1);
    Figure {
        title: format!("host-sim bench: speed against error, scene \"{}\"", sc.id),
        panels,
        cols,
        panel_size: (1150, 760),
    }
}

/// Join the labels of points drawn close to each other (within a factor 2.5 in x and 2 in y).
fn merge_close_labels(pts: &[(f64, f64)], labels: &mut [String]) {
    for i in 1..pts.len().min(labels.len()) {
        for j in 0..i {
            let close = (pts[i].0 / pts[j].0).ln().abs() < 2.5f64.ln()
                && (pts[i].1 / pts[j].1).log10().abs() < 0.3;
            if close && !labels[j].is_empty() {
                let l = std::mem::take(&mut labels[i]);
                if !l.is_empty() {
                    labels[j] = format!("{}, {l}", labels[j]);
                }
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn close_labels_are_merged() {
        let pts = [(1.3, 1e-7), (1.6, 1.2e-7), (1.5, 1e-13)];
        let mut labels = vec!["a".to_string(), "b".into(), "c".into()];
        merge_close_labels(&pts, &mut labels);
        assert_eq!(labels, ["a, b", "", "c"]);
    }
}
