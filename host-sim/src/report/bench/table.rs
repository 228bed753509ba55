//! The bench's results: one [`Row`] per method and setting on a scene, the scenes' descriptions
//! ([`SceneInfo`]), the whole [`Report`] (`bench.json`, `--json`) and its [`markdown`] tables
//! (`bench.md`, standard output).

use serde::Serialize;
use std::fmt::Write as _;

/// One row of the bench: a method with one setting on one scene.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Row {
    /// `rdm-recursion`, `rdm-closed`, `rdm-truncated`, `rfm`, `tfm` or `truth`.
    pub method: String,
    /// `f32` or `f64` (of the per-sample arithmetic).
    pub precision: String,
    /// The setting: transcendentals of the recursion, `K=…` terms, `H=…` harmonics, ….
    pub setting: String,
    /// Scene id: `harmonic`, `long-train` or `earthquake`.
    pub scene: String,
    /// Host nanoseconds per sample (median of the repetitions).
    pub ns_per_sample: f64,
    /// Largest |method − full f64 closed form| / gμ over the compared samples.
    pub max_err_gmu: f64,
    /// RMS of (method − full f64 closed form) / gμ.
    pub rms_err_gmu: f64,
    /// Cortex-M4F instructions per sample under QEMU (null: not measured).
    pub m4f_instructions_per_sample: Option<f64>,
    /// Largest |method − exact stick-slip truth| / gμ (null: no truth for the scene).
    pub max_err_vs_truth_gmu: Option<f64>,
    /// RMS of (method − truth) / gμ (null: no truth for the scene).
    pub rms_err_vs_truth_gmu: Option<f64>,
    /// Largest |method − double-double evaluation of the undamped sum| / gμ (`long-train` only).
    pub max_err_vs_dd_gmu: Option<f64>,
    /// Samples of the scene.
    pub samples: u64,
    /// Samples evaluated per timed run.
    pub timed_samples: u64,
    /// Samples compared.
    pub compared_samples: u64,
}

/// Description of a bench scene (in the JSON report).
#[derive(Debug, Clone, Serialize)]
pub struct SceneInfo {
    /// Scene id.
    pub id: String,
    /// What it is.
    pub description: String,
    /// Samples.
    pub samples: u64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Reversals (friction level changes) of the RDM train.
    pub reversals: usize,
    /// Samples compared.
    pub compared_samples: u64,
    /// gμ (m/s²).
    pub gmu_m_s2: f64,
}

/// The bench report (`--json`).
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The rows.
    pub rows: Vec<Row>,
    /// The scenes.
    pub scenes: Vec<SceneInfo>,
    /// Rows not run and why, and other remarks.
    pub notes: Vec<String>,
    /// Whether `--quick` was given.
    pub quick: bool,
    /// Full closed form ns/sample over firmware-default recursion ns/sample on `long-train`.
    pub long_train_speedup: Option<f64>,
}

/// A value in short scientific notation (`0` for zero).
fn sci(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:.1e}")
    }
}

/// Nanoseconds per sample, with the digits that matter.
fn ns(v: f64) -> String {
    if v >= 1000.0 {
        format!("{:.3e}", v)
    } else if v >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// The markdown tables of a report.
pub fn markdown(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| scene | method | precision | setting | ns/sample | max err vs closed form (gμ) | rms | max err vs truth (gμ) | rms vs truth | M4F instr/sample |"
    );
    let _ = writeln!(s, "|---|---|---|---|---:|---:|---:|---:|---:|---:|");
    for row in &r.rows {
        let opt = |v: Option<f64>| v.map_or("–".to_string(), sci);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            row.scene,
            row.method,
            row.precision,
            row.setting,
            ns(row.ns_per_sample),
            sci(row.max_err_gmu),
            sci(row.rms_err_gmu),
            opt(row.max_err_vs_truth_gmu),
            opt(row.rms_err_vs_truth_gmu),
            row.m4f_instructions_per_sample
                .map_or("–".to_string(), |v| format!("{v:.1}")),
        );
    }
    let dd: Vec<&Row> = r
        .rows
        .iter()
        .filter(|row| row.max_err_vs_dd_gmu.is_some())
        .collect();
    if !dd.is_empty() {
        let _ = writeln!(
            s,
            "\nlong-train against a double-double evaluation of the undamped sum (the closed form's own rounding):\n"
        );
        let _ = writeln!(
            s,
            "| method | precision | setting | max err vs double-double (gμ) |"
        );
        let _ = writeln!(s, "|---|---|---|---:|");
        for row in dd {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} |",
                row.method,
                row.precision,
                row.setting,
                sci(row.max_err_vs_dd_gmu.unwrap_or(f64::NAN))
            );
        }
    }
    if let Some(x) = r.long_train_speedup {
        let _ = writeln!(
            s,
            "\nlong-train: the recursion (f32, F32Poly) is {x:.3e}× faster per sample than the full closed-form sum."
        );
    }
    if !r.scenes.is_empty() {
        let _ = writeln!(s, "\nScenes:\n");
        for sc in &r.scenes {
            let _ = writeln!(
                s,
                "- `{}`: {} ({} samples, {} reversals in the RDM train, {} compared; gμ = {:.4} m/s²)",
                sc.id, sc.description, sc.samples, sc.reversals, sc.compared_samples, sc.gmu_m_s2
            );
        }
    }
    if !r.notes.is_empty() {
        let _ = writeln!(s, "\nNotes:\n");
        for n in &r.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    s
}
