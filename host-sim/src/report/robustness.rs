//! The robustness scorecard (`host-sim robustness`): `host-sim run` on perturbed copies of three
//! scenes, one perturbation at a time and combined, in both modes. A perturbation changes what
//! the controller is told (`[estimator]`) or what the sensors do (`[sensors]`, a rest before the
//! input); never the specimen's truth (`[structure]`).

use crate::run::{run, RunOptions};
use crate::scene::Scene;
use anyhow::{anyhow, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;
use ssvr_proto::Mode;
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// 0.05 g (m/s²).
const G005: f64 = 0.05 * 9.80665;

/// Goal of the fuse mode: RMS error ≤ 0.3 % of the peak.
pub const GOAL_FUSE_RMS_PCT: f64 = 0.3;
/// Goal of the fuse mode: max error ≤ 2 % of the peak.
pub const GOAL_FUSE_MAX_PCT: f64 = 2.0;
/// Goal of the predict mode: RMS error ≤ 1 % of the peak.
pub const GOAL_PREDICT_RMS_PCT: f64 = 1.0;

/// A perturbation: its id and what it does to a scene.
#[derive(Debug, Clone, Copy)]
pub struct Perturbation {
    /// A short stable id (`none`, `f+5%`, `base_offset_0.05g`, ..., `_rest` with a 0.5 s rest).
    pub id: &'static str,
    /// The prior's natural frequency, damping ratio, friction coefficients and m1 scaled by these.
    pub prior: [f64; 4],
    /// Accelerometer offsets (table, base, top; m/s²).
    pub bias: [f64; 3],
    /// Accelerometer gain errors (table, base, top).
    pub gain: [f64; 3],
    /// Dropped frames (probability).
    pub dropout: f64,
    /// Rest before the input (s).
    pub rest_s: f64,
    /// How late the table follows the planned input (s; the truth's alone: `table_lag_s`).
    pub table_lag_s: f64,
}

const NONE: Perturbation = Perturbation {
    id: "none",
    prior: [1.0; 4],
    bias: [0.0; 3],
    gain: [0.0; 3],
    dropout: 0.0,
    rest_s: 0.0,
    table_lag_s: 0.0,
};

/// Every perturbation of the full scorecard.
pub fn perturbations() -> Vec<Perturbation> {
    let p = |id, prior| Perturbation { id, prior, ..NONE };
    let b = |id, bias, rest_s| Perturbation {
        id,
        bias,
        rest_s,
        ..NONE
    };
    let all = Perturbation {
        id: "all_combined",
        prior: [1.08, 2.0, 1.25, 1.05],
        bias: [G005, -G005, G005],
        gain: [0.01, -0.01, 0.01],
        dropout: 0.01,
        rest_s: 0.0,
        table_lag_s: 0.0,
    };
    vec![
        NONE,
        Perturbation {
            id: "rest",
            rest_s: 0.5,
            ..NONE
        },
        p("f+5%", [1.05, 1.0, 1.0, 1.0]),
        p("f-5%", [0.95, 1.0, 1.0, 1.0]),
        p("f+8%", [1.08, 1.0, 1.0, 1.0]),
        p("f-8%", [0.92, 1.0, 1.0, 1.0]),
        p("xi*2", [1.0, 2.0, 1.0, 1.0]),
        p("xi*0.5", [1.0, 0.5, 1.0, 1.0]),
        p("mu+10%", [1.0, 1.0, 1.1, 1.0]),
        p("mu-10%", [1.0, 1.0, 0.9, 1.0]),
        p("mu+25%", [1.0, 1.0, 1.25, 1.0]),
        p("mu-25%", [1.0, 1.0, 0.75, 1.0]),
        p("m1+5%", [1.0, 1.0, 1.0, 1.05]),
        p("m1-5%", [1.0, 1.0, 1.0, 0.95]),
        b("base_offset_0.01", [0.0, 0.01, 0.0], 0.0),
        b("base_offset_0.01_rest", [0.0, 0.01, 0.0], 0.5),
        b("base_offset_0.05", [0.0, 0.05, 0.0], 0.0),
        b("base_offset_0.05_rest", [0.0, 0.05, 0.0], 0.5),
        b("base_offset_0.05g", [0.0, G005, 0.0], 0.0),
        b("base_offset_0.05g_rest", [0.0, G005, 0.0], 0.5),
        b("table_offset_0.05", [0.05, 0.0, 0.0], 0.0),
        b("table_offset_0.05_rest", [0.05, 0.0, 0.0], 0.5),
        b("top_offset_0.05", [0.0, 0.0, 0.05], 0.0),
        b("top_offset_0.05_rest", [0.0, 0.0, 0.05], 0.5),
        b("all_offsets_0.05g", [G005, -G005, G005], 0.0),
        b("all_offsets_0.05g_rest", [G005, -G005, G005], 0.5),
        Perturbation {
            id: "gains_1%",
            gain: [0.01, -0.01, 0.01],
            ..NONE
        },
        Perturbation {
            id: "top_gain+2%",
            gain: [0.0, 0.0, 0.02],
            ..NONE
        },
        Perturbation {
            id: "dropout_1%",
            dropout: 0.01,
            ..NONE
        },
        all,
        Perturbation {
            id: "all_combined_rest",
            rest_s: 0.5,
            ..all
        },
        Perturbation {
            id: "table_lag_2ms",
            table_lag_s: 2e-3,
            ..NONE
        },
        Perturbation {
            id: "all_offsets_0.05g_lag_2ms",
            bias: [G005, -G005, G005],
            table_lag_s: 2e-3,
            ..NONE
        },
    ]
}

/// The perturbations of `--quick`.
pub fn quick_perturbations() -> Vec<Perturbation> {
    let keep = [
        "none",
        "f+8%",
        "mu+25%",
        "base_offset_0.05g",
        "all_combined_rest",
    ];
    perturbations()
        .into_iter()
        .filter(|p| keep.contains(&p.id))
        .collect()
}

impl Perturbation {
    /// Whether the perturbation is within the range the issue sets the goals for (a prior off
    /// by up to f ±8 %, ξ ×2 or ×0.5, μ ±25 %, m1 ±5 %; offsets up to 0.05 g per channel; gains
    /// ±1 %; 1 % dropped frames): `top_gain+2%` is a stress row beyond it, and a table that
    /// follows its plan late (`table_lag_2ms`, the servo's lag: not one of the issue's
    /// perturbations) is another; shown, not counted.
    pub fn in_goal_range(&self) -> bool {
        let [f, xi, mu, m1] = self.prior;
        let within = |x: f64, lo: f64, hi: f64| x >= lo - 1e-12 && x <= hi + 1e-12;
        within(f, 0.92, 1.08)
            && within(xi, 0.5, 2.0)
            && within(mu, 0.75, 1.25)
            && within(m1, 0.95, 1.05)
            && self.bias.iter().all(|b| b.abs() <= G005 + 1e-12)
            && self.gain.iter().all(|g| g.abs() <= 0.01 + 1e-12)
            && self.dropout <= 0.01 + 1e-12
            && self.table_lag_s == 0.0
    }

    /// `scene` perturbed (a rest lengthens the run by its length, so the motion keeps its own).
    pub fn apply(&self, scene: &Scene) -> Scene {
        let mut s = scene.clone();
        let [f, xi, mu, m1] = self.prior;
        let e = &mut s.estimator;
        e.params.natural_frequency_hz *= f;
        e.params.damping_ratio = (e.params.damping_ratio * xi).min(0.99);
        e.params.friction_coefficient *= mu;
        e.static_friction_coefficient =
            (e.static_friction_coefficient * mu).max(e.params.friction_coefficient);
        e.params.m1_kg *= m1;
        s.sensors.accel_bias_m_s2 = self.bias;
        s.sensors.accel_gain_error = self.gain;
        s.sensors.dropout_probability = self.dropout;
        s.table_lag_s = self.table_lag_s;
        if self.rest_s > 0.0 {
            s.start_s = self.rest_s;
            s.duration_s += self.rest_s;
            s.samples = (s.duration_s * s.rate_hz).round() as u64;
        }
        s
    }
}

/// One run of the scorecard.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Scene name.
    pub scene: String,
    /// The scene's sample rate (Hz; `--rate-hz` sets every scene's).
    pub rate_hz: f64,
    /// `fuse` or `predict`.
    pub mode: &'static str,
    /// The perturbation's id.
    pub perturbation: &'static str,
    /// The model chosen (from a simulation of the prior).
    pub model: &'static str,
    /// RMS error against the truth (% of the peak).
    pub rms_pct_of_peak: f64,
    /// Max error against the truth (% of the peak).
    pub max_pct_of_peak: f64,
    /// Detected slip starts and reversals matched to true ones.
    pub matched: usize,
    /// True ones missed.
    pub missed: usize,
    /// Detected ones with no true one.
    pub false_events: usize,
    /// The identified μ (stick-slip model, fuse mode).
    pub mu_estimate: Option<f64>,
    /// The offsets removed (table, base, top; m/s²).
    pub accel_bias_m_s2: [f64; 3],
    /// With accelerometer offsets: no event missed or invented beyond the unperturbed run of the
    /// same scene and mode (`None` without offsets).
    pub events_ok: Option<bool>,
    /// The mode's goals met (fuse: RMS ≤ 0.3 %, max ≤ 2 %; predict: RMS ≤ 1 %; and `events_ok`).
    pub goal_met: bool,
    /// The perturbation is within the goals' range ([`Perturbation::in_goal_range`]); a row
    /// beyond it is a stress row, not counted in the scorecard's total.
    pub in_goal_range: bool,
}

/// The scenes: the built-in default, El Centro and Table 2 test 2 (`--quick`: 2 s of each).
pub fn scenes(quick: bool) -> Result<Vec<Scene>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut out = vec![Scene::default_scene()];
    for f in ["elcentro.toml", "table2-test2.toml"] {
        out.push(Scene::load(dir.join(f)).with_context(|| format!("loading {f}"))?);
    }
    if quick {
        for s in &mut out {
            s.duration_s = s.duration_s.min(2.0);
            s.samples = (s.duration_s * s.rate_hz).round() as u64;
        }
    }
    Ok(out)
}

/// Run every (scene, mode, perturbation) case, in parallel (a progress bar on standard error with
/// `progress`); rows in that order.
pub fn scorecard(
    scenes: &[Scene],
    modes: &[Mode],
    perturbations: &[Perturbation],
    progress: bool,
) -> Result<Vec<Row>> {
    let mut cases = Vec::new();
    for s in scenes {
        for &m in modes {
            for p in perturbations {
                cases.push((s, m, *p));
            }
        }
    }
    let pb = if progress {
        let pb = ProgressBar::new(cases.len() as u64);
        if let Ok(style) = ProgressStyle::with_template(
            "{msg:<12} [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta})",
        ) {
            pb.set_style(style.progress_chars("=> "));
        }
        pb.set_message("robustness");
        pb
    } else {
        ProgressBar::hidden()
    };
    let mut rows = cases
        .par_iter()
        .map(|(s, mode, p)| {
            let scene = p.apply(s);
            let mut opts = RunOptions::new("robustness");
            opts.mode = *mode;
            let out = run(&scene, std::io::sink(), &opts, &AtomicBool::new(false))
                .map_err(|e| anyhow!("{} / {} / {}: {e:#}", s.name, mode.name(), p.id))?;
            pb.inc(1);
            let e = &out.report.estimator;
            let d = &out.report.detection;
            let goal_met = match mode {
                Mode::Fuse => {
                    e.rms_err_pct_of_peak <= GOAL_FUSE_RMS_PCT
                        && e.max_err_pct_of_peak <= GOAL_FUSE_MAX_PCT
                }
                Mode::Predict => e.rms_err_pct_of_peak <= GOAL_PREDICT_RMS_PCT,
            };
            Ok(Row {
                scene: s.name.clone(),
                rate_hz: s.rate_hz,
                mode: mode.name(),
                perturbation: p.id,
                model: e.model,
                rms_pct_of_peak: e.rms_err_pct_of_peak,
                max_pct_of_peak: e.max_err_pct_of_peak,
                matched: d.matched,
                missed: d.missed,
                false_events: d.false_,
                mu_estimate: e.mu_estimate,
                accel_bias_m_s2: e.identified.accel_bias_m_s2,
                events_ok: None,
                goal_met,
                in_goal_range: p.in_goal_range(),
            })
        })
        .collect::<Result<Vec<Row>>>()?;
    pb.finish_and_clear();
    // No event missed or invented because of offsets: against the unperturbed run.
    let baseline: Vec<(String, &str, usize, usize)> = rows
        .iter()
        .filter(|r| r.perturbation == NONE.id)
        .map(|r| (r.scene.clone(), r.mode, r.missed, r.false_events))
        .collect();
    for (r, (_, _, p)) in rows.iter_mut().zip(&cases) {
        if p.bias == [0.0; 3] {
            continue;
        }
        let base = baseline
            .iter()
            .find(|(scene, mode, _, _)| *scene == r.scene && *mode == r.mode);
        if let Some((_, _, missed, false_events)) = base {
            let ok = r.missed <= *missed && r.false_events <= *false_events;
            r.events_ok = Some(ok);
            r.goal_met &= ok;
        }
    }
    Ok(rows)
}

/// The rows as a markdown table.
pub fn markdown(rows: &[Row]) -> String {
    use std::fmt::Write as _;
    let mut s = String::from(
        "| scene | rate (Hz) | mode | perturbation | model | RMS % of peak | max % | events matched / missed / false | μ̂ | offsets removed (table, base, top; m/s²) | goal |\n|---|---:|---|---|---|---:|---:|---|---:|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {:.3} | {:.2} | {} / {} / {}{} | {} | {:.3}, {:.3}, {:.3} | {} |",
            r.scene,
            r.rate_hz,
            r.mode,
            r.perturbation,
            r.model,
            r.rms_pct_of_peak,
            r.max_pct_of_peak,
            r.matched,
            r.missed,
            r.false_events,
            if r.events_ok == Some(false) {
                " (events changed)"
            } else {
                ""
            },
            r.mu_estimate
                .map_or_else(|| "–".to_string(), |m| format!("{m:.4}")),
            r.accel_bias_m_s2[0],
            r.accel_bias_m_s2[1],
            r.accel_bias_m_s2[2],
            match (r.goal_met, r.in_goal_range) {
                (true, true) => "ok",
                (false, true) => "NOT MET",
                (true, false) => "ok (beyond the goals' range)",
                (false, false) => "not met (beyond the goals' range)",
            }
        );
    }
    let (met, counted) = tally(rows);
    let _ = writeln!(
        s,
        "\n{met} of {counted} rows meet their goal (fuse: RMS ≤ {GOAL_FUSE_RMS_PCT} %, max ≤ {GOAL_FUSE_MAX_PCT} % of the peak; predict: RMS ≤ {GOAL_PREDICT_RMS_PCT} %; with offsets, no event missed or invented against the unperturbed run).",
    );
    let beyond = rows.len() - counted;
    if beyond > 0 {
        let met_beyond = rows
            .iter()
            .filter(|r| !r.in_goal_range && r.goal_met)
            .count();
        let mut ids: Vec<&str> = rows
            .iter()
            .filter(|r| !r.in_goal_range)
            .map(|r| r.perturbation)
            .collect();
        ids.sort_unstable();
        ids.dedup();
        let _ = writeln!(
            s,
            "{beyond} more rows are beyond the goals' range ({}; the goals are for a prior off by up to f ±8 %, ξ ×2 or ×0.5, μ ±25 %, m1 ±5 %, offsets up to 0.05 g, gains ±1 %, 1 % dropped frames, a table that follows its plan at once), shown, not counted: {met_beyond} of them would meet it.",
            ids.join(", ")
        );
    }
    s
}

/// (Rows within the goals' range that meet their goal, rows within it.)
pub fn tally(rows: &[Row]) -> (usize, usize) {
    let counted = rows.iter().filter(|r| r.in_goal_range);
    let n = counted.clone().count();
    (counted.filter(|r| r.goal_met).count(), n)
}
