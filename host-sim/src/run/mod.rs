//! `host-sim run`: the main job on a scene, sample by sample, as the controller would see it.
//!
//! For every sample t_k = k / rate_hz:
//!
//! 1. the exact stick-slip truth ([`crate::truth`]) at t_k,
//! 2. the sensors ([`crate::sensors`]: seeded noise, ADC, saturation) measure it,
//! 3. the firmware's pipeline step ([`crate::pipeline`]: `ssvr_proto::Pipeline`, built from the
//!    plan the firmware compiles in for this scene and model, so these are the firmware's
//!    predictions) flags the sample and runs the model's friction-event detector on it: for the
//!    rectangular and fixed-base models the reversal detector on the measured base-to-table
//!    displacement (`DetectorConfig::for_noise` of the scene's displacement noise and rate, the
//!    firmware's ring); for the stick-slip model the phase detector on the measured slip
//!    acceleration, base minus table accelerometer (`PhaseDetectorConfig::for_noise` of the
//!    accelerometer noise), whose sticks and slip starts it times to a fraction of a sample,
//! 4. the detected event goes, with its friction level and back-dated age, into the model before
//!    the prediction of t_k: the rectangular recursion ([`Estimator32`], f32) takes slip starts and
//!    reversals (`push_reversal(level, age)`); by default ([`StickPolicy::Keep`]) a detected
//!    **stick does not change it**: the rectangular model (eq 36) only knows the two sliding
//!    levels ±F0, and during a stick the friction is the holding force (unknown to the
//!    estimator), so the last level is kept until the next slip start or reversal.
//!    [`StickPolicy::Zero`] pushes level 0 at a stick instead (the generalised eq 36 with a zero
//!    level while stuck). The stick-slip model takes every event (its age clamped to the plan's
//!    longest back-dating), the fixed-base model none,
//! 5. one CSV row ([`CSV_HEADER`]) is written as soon as it is computed.
//!
//! Next to it a second instance of the model is fed the truth's own events at their exact times
//! (sticks treated the same way): its error ("ideal") is the error of the model itself, without
//! detection errors; and the rectangular recursion runs on the detected events for comparison.
//!
//! Detection statistics: each detected slip start/reversal, at its back-dated time
//! t_est = t_k − age/rate, is matched to the nearest not yet matched true slip start/reversal
//! with the same friction level within ± the match tolerance (detected events in time order).
//! Unmatched detections are false, unmatched true events missed. For matched ones,
//! latency = t_k (the sample at which the estimator first uses the event) − t_true, and the timing
//! error = t_est − t_true. True events after the last sample are not counted.
//!
//! Reversals scenes (a prescribed friction train, no table motion) have no physical truth to
//! simulate and are rejected with an error.
//!
//! [`Estimator32`]: ssvr_core::recursion::Estimator32

mod csv;
mod events;
mod plot;
mod report;
mod runner;
mod stats;
#[cfg(test)]
mod tests;

pub use csv::{default_out_path, Num, CSV_HEADER, FLUSH_EVERY_ROWS};
pub use events::{match_events, DetectionStats, EventMark, DEFAULT_MATCH_TOLERANCE_S};
pub(crate) use plot::{PlotCollector, PlotPoint};
pub use plot::{PlotData, Series, DEFAULT_PLOT_WINDOW_S, PLOT_BUCKETS};
pub use report::{
    check_runnable, scene_label, summary_text, DetectorReport, EstimatorStats, Identified,
    RunReport, TruthStats,
};

use crate::model::{self, Model};
use crate::pipeline;
use crate::scene::Scene;
use crate::truth::{simulate, Truth, TruthInput};
use anyhow::{anyhow, bail, Context, Result};
use csv::CsvWriter;
use events::{count, true_marks};
use runner::Runner;
use serde::Serialize;
use ssvr_proto::{Mode, Plan};
use std::fmt;
use std::io::Write;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

/// What a detected stick does to the estimator (and to the ideal estimator's true sticks).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum StickPolicy {
    /// Nothing: the friction level of the last slip start or reversal is kept.
    #[default]
    Keep,
    /// Push friction level 0 (back-dated to the stick).
    Zero,
}

impl StickPolicy {
    /// "keep" or "zero".
    pub fn name(self) -> &'static str {
        match self {
            StickPolicy::Keep => "keep",
            StickPolicy::Zero => "zero",
        }
    }
}

/// Options of [`run`].
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// What a stick does to the estimator.
    pub on_stick: StickPolicy,
    /// Name of the CSV output in messages and in the report.
    pub out_name: String,
    /// Half-width of the event-matching window (s).
    pub match_tolerance_s: f64,
    /// Keep the series of this time window `[from_s, to_s]` for a plot.
    pub plot_window: Option<(f64, f64)>,
    /// The estimator model; `None` chooses it from a simulation of the prior ([`model::choose_for`]).
    pub model: Option<Model>,
    /// What the model may read (`fuse`: every channel; `predict`: never the top accelerometer).
    pub mode: Mode,
}

impl RunOptions {
    /// Defaults: the given output name, the default tolerance, no plot.
    pub fn new(out_name: impl Into<String>) -> Self {
        Self {
            out_name: out_name.into(),
            on_stick: StickPolicy::Keep,
            match_tolerance_s: DEFAULT_MATCH_TOLERANCE_S,
            plot_window: None,
            model: None,
            mode: Mode::Fuse,
        }
    }
}

/// The run was stopped (Ctrl-C) before the end; the CSV holds the rows written so far.
#[derive(Debug, Clone, PartialEq)]
pub struct Interrupted {
    /// The output.
    pub out: String,
    /// Rows written (and flushed).
    pub rows: u64,
}

impl fmt::Display for Interrupted {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "interrupted: {} holds the first {} rows (flushed)",
            self.out, self.rows
        )
    }
}

impl std::error::Error for Interrupted {}

/// What [`run`] returns.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// The report.
    pub report: RunReport,
    /// The plot series (when a window was asked for).
    pub plot: Option<PlotData>,
    /// Detected slip starts, reversals and sticks, in order.
    pub detected: Vec<EventMark>,
    /// True slip starts, reversals and sticks up to the last sample, in order.
    pub true_events: Vec<EventMark>,
}

/// Run the scene, streaming the CSV to `w` (buffered; flushed every [`FLUSH_EVERY_ROWS`] rows, at
/// the end and before returning any error). `stop` is polled every few thousand samples; when set,
/// the rows so far are flushed and an [`Interrupted`] error is returned.
pub fn run<W: Write>(
    scene: &Scene,
    w: W,
    opts: &RunOptions,
    stop: &AtomicBool,
) -> Result<RunOutcome> {
    check_runnable(scene)?;
    let label = scene_label(scene);
    let tol = opts.match_tolerance_s;
    if !(tol.is_finite() && tol > 0.0) {
        bail!("the match tolerance must be > 0 (got {tol} s)");
    }
    let table = scene.table_motion();
    let input = TruthInput::new(&scene.structure, &table, scene.duration_s)
        .with_static_friction(scene.static_friction_coefficient)
        .with_friction(scene.friction);
    let truth =
        simulate(&input).map_err(|e| anyhow!("{label}: the truth simulation failed: {e}"))?;

    let (model, model_reason) = match opts.model {
        Some(m) => (m, "chosen with --model".to_string()),
        None => model::choose_for(scene).map_err(|e| anyhow!("{label}: {e}"))?,
    };
    let plan =
        pipeline::plan_for_mode(scene, model, opts.mode).map_err(|e| anyhow!("{label}: {e}"))?;
    let mut runner = Runner::new(
        scene,
        &label,
        &truth,
        &plan,
        opts.on_stick,
        opts.plot_window,
    )?;

    let mut csv = CsvWriter::new(w, &opts.out_name);
    csv.header()?;
    let result = samples(scene, &mut runner, &mut csv, stop);
    let flushed = csv.flush();
    result?;
    flushed?;
    runner.finish();

    Ok(outcome(
        scene,
        opts,
        &truth,
        &plan,
        (model, model_reason),
        runner,
    ))
}

/// Every sample into the CSV, flushed every [`FLUSH_EVERY_ROWS`] rows, when `stop` is checked.
fn samples<W: Write>(
    scene: &Scene,
    runner: &mut Runner,
    csv: &mut CsvWriter<W>,
    stop: &AtomicBool,
) -> Result<()> {
    for k in 0..scene.samples {
        if k % FLUSH_EVERY_ROWS == 0 && k > 0 {
            csv.flush()?;
            if stop.load(Ordering::Relaxed) {
                return Err(Interrupted {
                    out: csv.name().to_string(),
                    rows: csv.rows(),
                }
                .into());
            }
        }
        runner.sample(k, csv)?;
    }
    Ok(())
}

/// The report, the plot and the events of a finished run.
fn outcome(
    scene: &Scene,
    opts: &RunOptions,
    truth: &Truth,
    plan: &Plan,
    (model, model_reason): (Model, String),
    runner: Runner,
) -> RunOutcome {
    let rate = scene.rate_hz;
    let n = scene.samples;
    let last_t = scene.time(scene.samples.saturating_sub(1));
    let true_events = true_marks(truth.events(), last_t);
    let detected = runner.detected;
    let detection = match_events(&detected, &true_events, opts.match_tolerance_s);
    let peak = truth.peak_top_accel_m_s2();
    let pct = |x: f64| if peak > 0.0 { 100.0 * x / peak } else { 0.0 };
    let err = &runner.errors;
    let rev = &runner.revision;
    // Every sample revised, or no revised figures (never a figure over part of the run).
    let revised = model != Model::Rectangular && rev.missing == 0;
    let mu = runner.pipe.mu_estimate();
    let estimator = EstimatorStats {
        model: model.name(),
        mode: opts.mode.name(),
        model_reason,
        identified: Identified::of(plan, &*runner.pipe, model == Model::StickSlip),
        mu_estimate: mu.map(|m| m.mu),
        mu_std: mu.map(|m| m.std),
        revision_delay_ms: revised.then(|| 1e3 * rev.delay as f64 / rate),
        revised_max_err_m_s2: revised.then_some(rev.err.max),
        revised_rms_err_m_s2: revised.then(|| rev.err.rms(n)),
        revised_max_err_pct_of_peak: revised.then(|| pct(rev.err.max)),
        revised_rms_err_pct_of_peak: revised.then(|| pct(rev.err.rms(n))),
        rectangular_max_err_m_s2: err.rectangular.max,
        rectangular_rms_err_m_s2: err.rectangular.rms(n),
        precision: "f32",
        on_stick: opts.on_stick.name(),
        peak_predicted_m_s2: err.predicted.peak,
        peak_measured_m_s2: err.measured.peak,
        peak_truth_sampled_m_s2: err.truth_peak,
        max_err_m_s2: err.predicted.max,
        max_err_at_s: err.predicted.at,
        rms_err_m_s2: err.predicted.rms(n),
        max_err_pct_of_peak: pct(err.predicted.max),
        rms_err_pct_of_peak: pct(err.predicted.rms(n)),
        ideal_max_err_m_s2: err.ideal.max,
        ideal_rms_err_m_s2: err.ideal.rms(n),
        measured_max_err_m_s2: err.measured.max,
        reversals_detected: count(&detected, false),
        reversals_true: count(&true_events, false),
        sticks_detected: count(&detected, true),
        sticks_true: count(&true_events, true),
    };
    let report = RunReport {
        scene: scene.name.clone(),
        scene_file: scene.source.as_ref().map(|p| p.display().to_string()),
        input: scene.input.kind(),
        samples: n,
        rate_hz: rate,
        duration_s: scene.duration_s,
        out: opts.out_name.clone(),
        detector: DetectorReport::of(plan),
        truth: TruthStats::of(truth, last_t, &true_events),
        estimator,
        detection,
        runtime_s: 0.0,
    };
    let plot = runner
        .plot
        .map(|p| p.finish(truth, &detected, &true_events, &scene.name));
    RunOutcome {
        report,
        plot,
        detected,
        true_events,
    }
}

/// Create the CSV file and run into it. Errors name the file.
pub fn run_to_file(
    scene: &Scene,
    path: &Path,
    opts: &RunOptions,
    stop: &AtomicBool,
) -> Result<RunOutcome> {
    let file = std::fs::File::create(path)
        .with_context(|| format!("cannot create the output file {}", path.display()))?;
    run(scene, file, opts, stop)
}

/// The offsets the pipeline removed and those its model removed besides (table, base, top).
pub fn sum(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
