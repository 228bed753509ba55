//! The robustness scorecard's figure (`robustness.png`): RMS error (% of the peak, log axis)
//! against perturbation, one marker series per scene, one panel per mode.

use super::figure::{self, Figure, Marker, Panel, Series, Style};
use crate::report::robustness::Row;

/// Floor at which an error is drawn on the log axis.
const FLOOR: f64 = 1e-3;

/// The figure of the rows (perturbations in their order along x).
pub fn figure(rows: &[Row]) -> Figure {
    let mut ids: Vec<&str> = Vec::new();
    let mut scenes: Vec<&str> = Vec::new();
    for r in rows {
        if !ids.contains(&r.perturbation) {
            ids.push(r.perturbation);
        }
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    let mut panels = Vec::new();
    for mode in ["fuse", "predict"] {
        let mut panel = Panel::new(
            format!("{mode}: RMS error against perturbation"),
            "perturbation (index: see robustness.md)",
            "RMS error (% of the peak)",
        );
        panel.log_y = true;
        for (j, scene) in scenes.iter().enumerate() {
            let points: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.mode == mode && r.scene == *scene)
                .filter_map(|r| {
                    let x = ids.iter().position(|i| *i == r.perturbation)? as f64;
                    Some((x, r.rms_pct_of_peak.max(FLOOR)))
                })
                .collect();
            if !points.is_empty() {
                panel.series.push(Series::new(
                    *scene,
                    points,
                    figure::color(j),
                    Style::Markers(Marker::Circle, 4),
                ));
            }
        }
        panel.notes = ids
            .iter()
            .enumerate()
            .map(|(i, id)| format!("{i}: {id}"))
            .collect();
        if !panel.series.is_empty() {
            panels.push(panel);
        }
    }
    Figure {
        title: "host-sim robustness: error against perturbation".into(),
        panels,
        cols: 2,
        panel_size: (900, 700),
    }
}
