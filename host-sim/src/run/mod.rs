//! `host-sim run`: the main job on a scene, sample by sample, as the controller would see it.
//!
//! For every sample t_k = k / rate_hz:
//!
//! 1. the exact stick-slip truth ([`crate::truth`]) at t_k,
//! 2. the sensors ([`crate::sensors`]: seeded noise, ADC, saturation) measure it,
//! 3. the model's friction-event detector ([`model::Detector`]) processes the measurement: for the
//!    rectangular and fixed-base models the reversal detector (`ReversalDetector`, configured by
//!    `DetectorConfig::for_noise` from the scene's displacement noise and rate) on the measured
//!    base-to-table displacement; for the stick-slip model the phase detector (`PhaseDetector`,
//!    `PhaseDetectorConfig::for_noise` from the accelerometer noise) on the measured slip
//!    acceleration, base minus table accelerometer, whose sticks and slip starts it times to a
//!    fraction of a sample,
//! 4. a detected slip start or reversal is pushed into the firmware's estimator ([`Estimator32`]: f32,
//!    the same code as the firmware) with its friction level and back-dated age,
//!    `push_reversal(event.friction_level(), event.age_samples())`, before the `update()` that
//!    predicts ü1 at t_k. By default ([`StickPolicy::Keep`]) a detected **stick does not change the
//!    estimator**: the rectangular model (eq 36) only knows the two sliding levels ±F0, and during
//!    a stick the friction is the holding force (unknown to the estimator), so the last level is
//!    kept until the next slip start or reversal (a slip start in the same direction as before the
//!    stick is then a no-op). [`StickPolicy::Zero`] pushes level 0 at a stick instead (the
//!    generalised eq 36 with a zero level while stuck),
//! 5. one CSV row ([`CSV_HEADER`]) is written as soon as it is computed.
//!
//! Next to it a second `Estimator32` is fed the truth's own slip starts and reversals at their exact
//! times (sticks ignored the same way): its error ("ideal") is the error of the rectangular model
//! itself, without detection errors.
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

use crate::model::{self, Model};
use crate::pipeline::{self, sample_of};
use crate::scene::{Input, Scene};
use crate::sensors::SensorModel;
use crate::truth::{simulate, EventKind, Phase, TruthInput};
use anyhow::{anyhow, bail, Context, Result};
use serde::Serialize;
use ssvr_core::recursion::Estimator32;
use ssvr_proto::{flags, DetectorPlan, Event, EventKind as FrameEventKind, Plan};
use std::fmt;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// The CSV header of `run` (one row per sample follows).
///
/// * `t_s`: t_k = k / rate_hz;
/// * `table_accel_m_s2`, `base_accel_m_s2`, `measured_top_accel_m_s2`: the accelerometers;
/// * `rel_disp_m`: the measured base-to-table displacement (the slip seen by the detector);
/// * `reversal`: the friction level (F/F0, −1 or 1) of a slip start or reversal detected at this
///   sample and pushed into the estimator before this sample's prediction, 0 otherwise (a stick
///   is 0 here whatever the stick policy, see `detected_event`);
/// * `predicted_top_accel_m_s2`: the estimator's ü1 (f32);
/// * `truth_top_accel_m_s2`: the exact ü1;
/// * extras: `ideal_predicted_top_accel_m_s2` (the estimator fed the true events),
///   `truth_slip_m`, `truth_slip_dir` (+1 / −1 sliding, 0 stuck), `detected_event`
///   (`slip_start`, `reversal`, `stick` or empty), `event_age_samples` (the detector's
///   back-dating, empty without an event), `flags` (the sensor `FLAG_*` bits).
pub const CSV_HEADER: &str = "t_s,table_accel_m_s2,base_accel_m_s2,measured_top_accel_m_s2,rel_disp_m,reversal,predicted_top_accel_m_s2,truth_top_accel_m_s2,ideal_predicted_top_accel_m_s2,truth_slip_m,truth_slip_dir,detected_event,event_age_samples,flags";

/// The CSV is flushed every this many rows (an interrupted run keeps what was produced).
pub const FLUSH_EVERY_ROWS: u64 = 4096;

/// Default half-width of the window in which a detected event is matched to a true one (s).
pub const DEFAULT_MATCH_TOLERANCE_S: f64 = 0.02;

/// Number of min/max buckets of a decimated plot series (each bucket gives at most two points).
pub const PLOT_BUCKETS: u64 = 2500;

/// Default length of the plot window (s).
pub const DEFAULT_PLOT_WINDOW_S: f64 = 2.0;

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
    /// The estimator model; `None` chooses it from the simulated run ([`model::choose`]).
    pub model: Option<Model>,
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

/// The truth's figures.
#[derive(Debug, Clone, Serialize)]
pub struct TruthStats {
    /// Peak |ü1| of the exact response (continuous in time, not only at samples) (m/s²).
    pub peak_top_accel_m_s2: f64,
    /// Time of that peak (s).
    pub peak_top_accel_time_s: f64,
    /// Largest |slip| (m).
    pub max_abs_slip_m: f64,
    /// Slip at the end (m).
    pub final_slip_m: f64,
    /// Slip phases: slip starts + reversals over the whole simulation.
    pub slip_phases: usize,
    /// Slip starts up to the last sample.
    pub slip_starts: usize,
    /// Reversals up to the last sample.
    pub reversals: usize,
    /// Sticks up to the last sample.
    pub sticks: usize,
}

/// The estimator's figures (errors against the truth's ü1 over every sample).
#[derive(Debug, Clone, Serialize)]
pub struct EstimatorStats {
    /// The model ("fixed-base", "rectangular", "stick-slip").
    pub model: &'static str,
    /// Why this model (chosen from the simulated run, or "--model").
    pub model_reason: String,
    /// The identified friction coefficient (stick-slip model; null otherwise).
    pub mu_estimate: Option<f64>,
    /// Its standard deviation.
    pub mu_std: Option<f64>,
    /// Delay after which a prediction is revised by late events (ms; null for the rectangular model).
    pub revision_delay_ms: Option<f64>,
    /// max |revised prediction − truth| (m/s²): the prediction of each sample as revised once its
    /// events are detected (stick-slip model; null otherwise).
    pub revised_max_err_m_s2: Option<f64>,
    /// RMS of revised prediction − truth (m/s²).
    pub revised_rms_err_m_s2: Option<f64>,
    /// `revised_max_err_m_s2` in % of the truth's peak |ü1|.
    pub revised_max_err_pct_of_peak: Option<f64>,
    /// `revised_rms_err_m_s2` in % of the truth's peak |ü1|.
    pub revised_rms_err_pct_of_peak: Option<f64>,
    /// The rectangular model's max |error| on the same detected events (for comparison; m/s²).
    pub rectangular_max_err_m_s2: f64,
    /// The rectangular model's RMS error (m/s²).
    pub rectangular_rms_err_m_s2: f64,
    /// "f32" (as on the firmware).
    pub precision: &'static str,
    /// What a stick does to the estimator ("keep" or "zero").
    pub on_stick: &'static str,
    /// Peak |predicted ü1| over the samples (m/s²).
    pub peak_predicted_m_s2: f64,
    /// Peak |measured ü1| over the samples (m/s²).
    pub peak_measured_m_s2: f64,
    /// Peak |truth ü1| over the samples (m/s²).
    pub peak_truth_sampled_m_s2: f64,
    /// max |predicted − truth| (m/s²).
    pub max_err_m_s2: f64,
    /// Time of the largest error (s).
    pub max_err_at_s: f64,
    /// RMS of predicted − truth (m/s²).
    pub rms_err_m_s2: f64,
    /// `max_err_m_s2` in % of the truth's peak |ü1|.
    pub max_err_pct_of_peak: f64,
    /// `rms_err_m_s2` in % of the truth's peak |ü1|.
    pub rms_err_pct_of_peak: f64,
    /// max |ideal − truth| (m/s²): the estimator fed the true events (model error only).
    pub ideal_max_err_m_s2: f64,
    /// RMS of ideal − truth (m/s²).
    pub ideal_rms_err_m_s2: f64,
    /// max |measured − truth| (m/s²): the top accelerometer's own error, for scale.
    pub measured_max_err_m_s2: f64,
    /// Slip starts + reversals detected (the events pushed into the estimator).
    pub reversals_detected: usize,
    /// Slip starts + reversals of the truth up to the last sample.
    pub reversals_true: usize,
    /// Sticks detected (pushed as level 0 only with `on_stick = zero`).
    pub sticks_detected: usize,
    /// Sticks of the truth up to the last sample.
    pub sticks_true: usize,
}

/// Detection figures (matching: see the module documentation).
#[derive(Debug, Clone, Serialize)]
pub struct DetectionStats {
    /// Detected events matched to a true one.
    pub matched: usize,
    /// True slip starts/reversals with no detection.
    pub missed: usize,
    /// Detections with no true event.
    #[serde(rename = "false")]
    pub false_: usize,
    /// Mean latency (ms): sample of detection − true event time.
    pub latency_mean_ms: Option<f64>,
    /// Largest latency (ms).
    pub latency_max_ms: Option<f64>,
    /// Mean of the back-dated event time − true time (ms).
    pub timing_err_mean_ms: Option<f64>,
    /// RMS of the back-dated event time − true time (ms).
    pub timing_err_rms_ms: Option<f64>,
    /// Largest |back-dated event time − true time| (ms).
    pub timing_err_max_ms: Option<f64>,
    /// Half-width of the matching window (ms).
    pub match_tolerance_ms: f64,
}

/// The report of a run (`--json` prints it).
#[derive(Debug, Clone, Serialize)]
pub struct RunReport {
    /// Scene name.
    pub scene: String,
    /// Scene file, `null` for the built-in default.
    pub scene_file: Option<String>,
    /// Input kind.
    pub input: &'static str,
    /// Samples (= CSV rows).
    pub samples: u64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Duration (s).
    pub duration_s: f64,
    /// The CSV output.
    pub out: String,
    /// Detector settings.
    pub detector: DetectorReport,
    /// The truth.
    pub truth: TruthStats,
    /// The estimator.
    pub estimator: EstimatorStats,
    /// Detection.
    pub detection: DetectionStats,
    /// Wall-clock time of the run (s), filled by the caller (0 until then).
    pub runtime_s: f64,
}

/// The detector's settings in a report.
#[derive(Debug, Clone, Serialize)]
pub struct DetectorReport {
    /// Which detector the model uses: `slip-displacement` or `slip-acceleration`.
    pub kind: &'static str,
    /// Ring length N.
    pub ring: usize,
    /// The longest back-dating of its events (samples).
    pub max_age_samples: usize,
    /// Displacement detector: hysteresis (m).
    pub hysteresis_m: Option<f64>,
    /// Displacement detector: fit half-width (samples).
    pub fit_half: Option<usize>,
    /// Displacement detector: samples to declare a stick.
    pub stick_samples: Option<usize>,
    /// Acceleration detector: |base − table acceleration| threshold (m/s²).
    pub threshold_m_s2: Option<f64>,
    /// Acceleration detector: samples of |s̈| below the threshold to declare a stick without a jump.
    pub stall_samples: Option<usize>,
}

impl DetectorReport {
    fn of(plan: &Plan) -> Self {
        let mut r = Self {
            kind: "",
            ring: plan.ring,
            max_age_samples: plan.max_age,
            hysteresis_m: None,
            fit_half: None,
            stick_samples: None,
            threshold_m_s2: None,
            stall_samples: None,
        };
        match plan.detector {
            DetectorPlan::Displacement(c) => {
                r.kind = "slip-displacement";
                r.hysteresis_m = Some(c.hysteresis_m as f64);
                r.fit_half = Some(c.fit_half);
                r.stick_samples = Some(c.stick_samples);
            }
            DetectorPlan::SlipAcceleration(c) => {
                r.kind = "slip-acceleration";
                r.threshold_m_s2 = Some(c.threshold_m_s2 as f64);
                r.stall_samples = Some(c.stall_samples);
            }
        }
        r
    }
}

/// A slip start or reversal, detected or true.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventMark {
    /// Event time (s): true, or back-dated for a detection.
    pub time_s: f64,
    /// Sample time at which it was detected (s); the true time for a true event.
    pub detected_at_s: f64,
    /// Friction level after it (−1 or 1; 0 for a stick).
    pub level: f64,
    /// A stick (else a slip start or reversal).
    pub stick: bool,
}

/// One decimated series of a plot: (t, value) points in time order.
pub type Series = Vec<(f64, f64)>;

/// The series of the plot window (min/max decimated to at most 2·[`PLOT_BUCKETS`] points each).
#[derive(Debug, Clone, Default)]
pub struct PlotData {
    /// Window (s).
    pub window: (f64, f64),
    /// Measured ü1.
    pub measured: Series,
    /// Predicted ü1.
    pub predicted: Series,
    /// True ü1.
    pub truth: Series,
    /// Measured slip (m).
    pub slip_measured: Series,
    /// True slip (m).
    pub slip_truth: Series,
    /// Detected events in the window, with the true slip at their back-dated time (m).
    pub detected: Vec<(EventMark, f64)>,
    /// True events in the window, with the true slip at their time (m).
    pub true_events: Vec<(EventMark, f64)>,
    /// Scene name.
    pub scene: String,
}

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

/// The default CSV output: `<scene-stem>.run.csv` next to the scene file, or `default.run.csv` in
/// the working directory for the built-in scene.
pub fn default_out_path(scene: &Scene) -> PathBuf {
    match &scene.source {
        Some(p) => {
            let stem = p
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into());
            p.with_file_name(format!("{stem}.run.csv"))
        }
        None => PathBuf::from("default.run.csv"),
    }
}

/// The scene's name for messages: its file, or "the built-in default scene".
pub fn scene_label(scene: &Scene) -> String {
    match &scene.source {
        Some(p) => p.display().to_string(),
        None => "the built-in default scene".into(),
    }
}

/// Reject scenes `run` cannot simulate (a prescribed reversal train has no table motion).
pub fn check_runnable(scene: &Scene) -> Result<()> {
    if let Input::Reversals(_) = scene.input {
        bail!(
            "{}: [input] kind = \"reversals\" prescribes the friction train and has no table motion, \
             so there is no stick-slip truth to measure: `run` needs kind = \"harmonic\" or \"record\" \
             (use `check` or `trace` for a reversals scene)",
            scene_label(scene)
        );
    }
    Ok(())
}

/// A CSV number: the shortest representation that reads back to the same f32/f64, in plain
/// decimal for 1e-5 <= |x| < 1e16 (and 0), in exponent form (`1.5e-48`) otherwise.
#[derive(Debug, Clone, Copy)]
pub struct Num<T>(pub T);

macro_rules! num_display {
    ($t:ty) => {
        impl fmt::Display for Num<$t> {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                let a = self.0.abs();
                if a == 0.0 || !a.is_finite() || (1e-5..1e16).contains(&a) {
                    write!(f, "{}", self.0)
                } else {
                    write!(f, "{:e}", self.0)
                }
            }
        }
    };
}
num_display!(f32);
num_display!(f64);

/// Min/max decimation of one series into fixed buckets of `bucket` samples.
#[derive(Debug, Clone)]
struct Decimator {
    bucket: u64,
    n: u64,
    lo: (f64, f64),
    hi: (f64, f64),
    out: Series,
}

impl Decimator {
    fn new(bucket: u64) -> Self {
        Self {
            bucket: bucket.max(1),
            n: 0,
            lo: (0.0, f64::INFINITY),
            hi: (0.0, f64::NEG_INFINITY),
            out: Vec::new(),
        }
    }

    fn push(&mut self, t: f64, v: f64) {
        if !v.is_finite() {
            return;
        }
        if v < self.lo.1 {
            self.lo = (t, v);
        }
        if v > self.hi.1 {
            self.hi = (t, v);
        }
        self.n += 1;
        if self.n >= self.bucket {
            self.emit();
        }
    }

    fn emit(&mut self) {
        if self.n == 0 {
            return;
        }
        let (a, b) = if self.lo.0 <= self.hi.0 {
            (self.lo, self.hi)
        } else {
            (self.hi, self.lo)
        };
        self.out.push(a);
        if b != a {
            self.out.push(b);
        }
        self.n = 0;
        self.lo = (0.0, f64::INFINITY);
        self.hi = (0.0, f64::NEG_INFINITY);
    }

    fn finish(mut self) -> Series {
        self.emit();
        self.out
    }
}

struct PlotCollector {
    window: (f64, f64),
    measured: Decimator,
    predicted: Decimator,
    truth: Decimator,
    slip_measured: Decimator,
    slip_truth: Decimator,
}

/// Running error statistics of a prediction against the truth.
#[derive(Debug, Clone, Copy, Default)]
struct ErrStats {
    max: f64,
    at: f64,
    sum_sq: f64,
    peak: f64,
}

impl ErrStats {
    fn add(&mut self, t: f64, value: f64, truth: f64) {
        let e = (value - truth).abs();
        if e > self.max || e.is_nan() {
            self.max = e;
            self.at = t;
        }
        self.sum_sq += e * e;
        self.peak = self.peak.max(value.abs());
    }

    fn rms(&self, n: u64) -> f64 {
        if n == 0 {
            0.0
        } else {
            (self.sum_sq / n as f64).sqrt()
        }
    }
}

fn level_of(kind: EventKind) -> (f64, bool) {
    match kind {
        EventKind::SlipStart { direction } => (-direction.sign(), false),
        EventKind::Reversal { new_direction } => (-new_direction.sign(), false),
        EventKind::Stick => (0.0, true),
    }
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
    let structure = &scene.structure;
    let rate = scene.rate_hz;
    let table = scene.table_motion();
    let input = TruthInput::new(structure, &table, scene.duration_s)
        .with_static_friction(scene.static_friction_coefficient);
    let truth =
        simulate(&input).map_err(|e| anyhow!("{label}: the truth simulation failed: {e}"))?;

    let (model, model_reason) = match opts.model {
        Some(m) => (m, "chosen with --model".to_string()),
        None => model::choose(&truth, scene.duration_s),
    };
    // The firmware's pipeline for this scene and model: the same plan, detector, model and step.
    let plan = pipeline::plan_for(scene, model).map_err(|e| anyhow!("{label}: {e}"))?;
    let zero_at_stick = opts.on_stick == StickPolicy::Zero;
    let pipe_opts = pipeline::Options {
        zero_at_stick,
        ..pipeline::Options::default()
    };
    let mut pipe = pipeline::build(&plan, pipe_opts).map_err(|e| anyhow!("{label}: {e}"))?;
    let mut ideal = pipeline::model(&plan, pipe_opts).map_err(|e| anyhow!("{label}: {e}"))?;
    // The rectangular model on the same detected events, for comparison.
    let mut rect =
        Estimator32::new(structure, rate).map_err(|e| anyhow!("{label}: estimator: {e}"))?;
    let mut sensors = SensorModel::new(&scene.sensors);
    let mut sampler = truth.sampler();
    let events = truth.events();
    let last_t = scene.time(scene.samples.saturating_sub(1));

    let mut plot = opts.plot_window.map(|(from, to)| {
        let first = (from * rate).ceil().max(0.0);
        let last = (to * rate)
            .floor()
            .min(scene.samples.saturating_sub(1) as f64);
        let n = (last - first + 1.0).max(1.0) as u64;
        let bucket = n.div_ceil(PLOT_BUCKETS).max(1);
        let bucket = if bucket <= 2 { 1 } else { bucket };
        PlotCollector {
            window: (from, to),
            measured: Decimator::new(bucket),
            predicted: Decimator::new(bucket),
            truth: Decimator::new(bucket),
            slip_measured: Decimator::new(bucket),
            slip_truth: Decimator::new(bucket),
        }
    });

    let mut out = BufWriter::with_capacity(1 << 16, w);
    let name = opts.out_name.as_str();
    let write_err = |e: std::io::Error| anyhow!(e).context(format!("writing {name}"));
    writeln!(out, "{CSV_HEADER}").map_err(write_err)?;

    let mut pred_err = ErrStats::default();
    let mut rect_err = ErrStats::default();
    // Revised predictions: each sample once every event that can reach back to it is known (the
    // detector's stick window plus its fits), compared with the truth kept for that long.
    // The oldest sample the stick-slip model keeps is `history − 1` back; an event is back-dated
    // by at most `max_age` = history − 2 samples, so that sample is final.
    let revision_delay = plan.history.saturating_sub(1) as u64;
    let mut rev_err = ErrStats::default();
    let mut rev_missing = 0u64;
    let mut truth_ring: std::collections::VecDeque<f64> = std::collections::VecDeque::new();
    let mut ideal_err = ErrStats::default();
    let mut meas_err = ErrStats::default();
    let mut truth_peak = 0.0f64;
    let mut detected: Vec<EventMark> = Vec::new();
    let mut next_true = 0usize;
    let mut rows = 0u64;

    let result = (|| -> Result<()> {
        for k in 0..scene.samples {
            if k % FLUSH_EVERY_ROWS == 0 && k > 0 {
                out.flush().map_err(write_err)?;
                if stop.load(Ordering::Relaxed) {
                    return Err(Interrupted {
                        out: name.to_string(),
                        rows,
                    }
                    .into());
                }
            }
            let t = scene.time(k);
            let s = sampler
                .sample(t)
                .ok_or_else(|| anyhow!("{label}: no truth sample at t = {t} s (sample {k})"))?;
            let f = sensors.measure(k, &s);

            // The pipeline's step: detector, its event to the model, the prediction.
            let sample = sample_of(&f);
            let frame = pipe.step(&sample);
            let event = frame.event;
            let mut pushed = 0i32;
            if let Some(e) = event {
                let age = e.age_samples;
                let stick = e.is_stick();
                let mark = EventMark {
                    time_s: t - age as f64 / rate,
                    detected_at_s: t,
                    level: f64::from(e.level),
                    stick,
                };
                if frame.flags & flags::EVENT_REJECTED != 0 {
                    bail!("{label}: the estimator rejected the event {e:?} at t = {t} s");
                }
                if frame.flags & flags::EVENT_PUSHED != 0 && !stick {
                    pushed = i32::from(e.level);
                }
                if !stick || zero_at_stick {
                    let level = if stick { 0.0 } else { f32::from(e.level) };
                    rect.push_reversal(level, age).map_err(|err| {
                        anyhow!("{label}: estimator rejected the event {e:?} at t = {t} s: {err}")
                    })?;
                }
                detected.push(mark);
            }
            let pred = frame.prediction;
            // The ideal estimator: the truth's own slip starts, reversals and sticks, exact ages.
            while let Some(ev) = events.get(next_true).filter(|ev| ev.time_s <= t) {
                let (level, stick) = level_of(ev.kind);
                let e = Event {
                    kind: if stick {
                        FrameEventKind::Stick
                    } else {
                        FrameEventKind::Reversal
                    },
                    level: level as i8,
                    age_samples: ((t - ev.time_s) * rate) as f32,
                };
                ideal.push(&e).map_err(|err| {
                    anyhow!(
                        "{label}: ideal estimator rejected the true event at t = {} s: {err}",
                        ev.time_s
                    )
                })?;
                next_true += 1;
            }
            let (ideal_pred, _) = pipeline::model_step(ideal.as_mut(), None, &sample)
                .map_err(|err| anyhow!("{label}: ideal estimator at t = {t} s: {err}"))?;
            let rect_pred = rect.update();

            let truth_top = s.top_accel_m_s2;
            pred_err.add(t, pred as f64, truth_top);
            rect_err.add(t, rect_pred as f64, truth_top);
            truth_ring.push_back(truth_top);
            if k >= revision_delay {
                let d = k - revision_delay;
                let want = truth_ring.pop_front().unwrap_or(f64::NAN);
                match pipe.revised(d) {
                    Some(r) => rev_err.add(scene.time(d), r as f64, want),
                    None => rev_missing += 1,
                }
            }
            ideal_err.add(t, ideal_pred as f64, truth_top);
            meas_err.add(t, f.top_accel_m_s2 as f64, truth_top);
            truth_peak = truth_peak.max(truth_top.abs());

            let dir = match s.phase {
                Phase::Stuck => 0,
                Phase::SlidingPos => 1,
                Phase::SlidingNeg => -1,
            };
            let (ev_name, age) = match event {
                None => ("", None),
                Some(e) => (e.kind.name(), Some(e.age_samples)),
            };
            write!(
                out,
                "{},{},{},{},{},{pushed},{},{},{},{},{dir},{ev_name},",
                Num(t),
                Num(f.table_accel_m_s2),
                Num(f.base_accel_m_s2),
                Num(f.top_accel_m_s2),
                Num(f.disp_m),
                Num(pred),
                Num(truth_top),
                Num(ideal_pred),
                Num(s.slip_m)
            )
            .map_err(write_err)?;
            if let Some(a) = age {
                write!(out, "{a}").map_err(write_err)?;
            }
            writeln!(out, ",{}", f.flags).map_err(write_err)?;
            rows += 1;

            if let Some(p) = plot.as_mut() {
                if t >= p.window.0 && t <= p.window.1 {
                    p.measured.push(t, f.top_accel_m_s2 as f64);
                    p.predicted.push(t, pred as f64);
                    p.truth.push(t, truth_top);
                    p.slip_measured.push(t, f.disp_m as f64);
                    p.slip_truth.push(t, s.slip_m);
                }
            }
        }
        Ok(())
    })();
    let flushed = out.flush().map_err(write_err);
    result?;
    flushed?;
    // The last samples: revised by everything seen.
    let first = scene.samples.saturating_sub(truth_ring.len() as u64);
    for (i, want) in truth_ring.iter().enumerate() {
        let d = first + i as u64;
        match pipe.revised(d) {
            Some(r) => rev_err.add(scene.time(d), r as f64, *want),
            None => rev_missing += 1,
        }
    }
    // Every sample revised, or no revised figures (never a figure over part of the run).
    let revised = model != Model::Rectangular && rev_missing == 0;

    // True events up to the last sample.
    let true_events: Vec<EventMark> = events
        .iter()
        .filter(|e| e.time_s <= last_t)
        .map(|e| {
            let (level, stick) = level_of(e.kind);
            EventMark {
                time_s: e.time_s,
                detected_at_s: e.time_s,
                level,
                stick,
            }
        })
        .collect();
    let count = |v: &[EventMark], stick: bool| v.iter().filter(|e| e.stick == stick).count();
    let detection = match_events(&detected, &true_events, tol);
    let n = scene.samples;
    let peak = truth.peak_top_accel_m_s2();
    let pct = |x: f64| if peak > 0.0 { 100.0 * x / peak } else { 0.0 };
    let truth_stats = TruthStats {
        peak_top_accel_m_s2: peak,
        peak_top_accel_time_s: truth.peak_top_accel_time_s(),
        max_abs_slip_m: truth.max_abs_slip_m(),
        final_slip_m: truth.final_slip_m(),
        slip_phases: truth.slip_phases(),
        slip_starts: events
            .iter()
            .filter(|e| e.time_s <= last_t && matches!(e.kind, EventKind::SlipStart { .. }))
            .count(),
        reversals: events
            .iter()
            .filter(|e| e.time_s <= last_t && matches!(e.kind, EventKind::Reversal { .. }))
            .count(),
        sticks: count(&true_events, true),
    };
    let mu = pipe.mu_estimate();
    let estimator = EstimatorStats {
        model: model.name(),
        model_reason,
        mu_estimate: mu.map(|m| m.mu),
        mu_std: mu.map(|m| m.std),
        revision_delay_ms: revised.then(|| 1e3 * revision_delay as f64 / rate),
        revised_max_err_m_s2: revised.then_some(rev_err.max),
        revised_rms_err_m_s2: revised.then(|| rev_err.rms(n)),
        revised_max_err_pct_of_peak: revised.then(|| pct(rev_err.max)),
        revised_rms_err_pct_of_peak: revised.then(|| pct(rev_err.rms(n))),
        rectangular_max_err_m_s2: rect_err.max,
        rectangular_rms_err_m_s2: rect_err.rms(n),
        precision: "f32",
        on_stick: opts.on_stick.name(),
        peak_predicted_m_s2: pred_err.peak,
        peak_measured_m_s2: meas_err.peak,
        peak_truth_sampled_m_s2: truth_peak,
        max_err_m_s2: pred_err.max,
        max_err_at_s: pred_err.at,
        rms_err_m_s2: pred_err.rms(n),
        max_err_pct_of_peak: pct(pred_err.max),
        rms_err_pct_of_peak: pct(pred_err.rms(n)),
        ideal_max_err_m_s2: ideal_err.max,
        ideal_rms_err_m_s2: ideal_err.rms(n),
        measured_max_err_m_s2: meas_err.max,
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
        detector: DetectorReport::of(&plan),
        truth: truth_stats,
        estimator,
        detection,
        runtime_s: 0.0,
    };
    let plot = plot.map(|p| {
        let (from, to) = p.window;
        let slip_at = |t: f64| truth.sample(t).map_or(0.0, |s| s.slip_m);
        let in_window = |v: &[EventMark]| {
            v.iter()
                .filter(|e| e.time_s >= from && e.time_s <= to)
                .map(|e| (*e, slip_at(e.time_s.max(0.0))))
                .collect::<Vec<_>>()
        };
        PlotData {
            window: p.window,
            measured: p.measured.finish(),
            predicted: p.predicted.finish(),
            truth: p.truth.finish(),
            slip_measured: p.slip_measured.finish(),
            slip_truth: p.slip_truth.finish(),
            detected: in_window(&detected),
            true_events: in_window(&true_events),
            scene: scene.name.clone(),
        }
    });
    Ok(RunOutcome {
        report,
        plot,
        detected,
        true_events,
    })
}

/// Match detected slip starts/reversals to true ones (see the module documentation); sticks in
/// either list are ignored.
pub fn match_events(detected: &[EventMark], truth: &[EventMark], tol_s: f64) -> DetectionStats {
    let truth: Vec<&EventMark> = truth.iter().filter(|e| !e.stick).collect();
    let mut used = vec![false; truth.len()];
    let (mut matched, mut false_) = (0usize, 0usize);
    let (mut lat_sum, mut lat_max) = (0.0f64, f64::NEG_INFINITY);
    let (mut te_sum, mut te_sq, mut te_max) = (0.0f64, 0.0f64, 0.0f64);
    for d in detected.iter().filter(|e| !e.stick) {
        let lo = truth.partition_point(|e| e.time_s < d.time_s - tol_s);
        let hi = truth.partition_point(|e| e.time_s <= d.time_s + tol_s);
        let best = (lo..hi)
            .filter(|&i| !used[i] && truth[i].level == d.level)
            .min_by(|&a, &b| {
                let da = (truth[a].time_s - d.time_s).abs();
                let db = (truth[b].time_s - d.time_s).abs();
                da.total_cmp(&db)
            });
        match best {
            Some(i) => {
                used[i] = true;
                matched += 1;
                let lat = d.detected_at_s - truth[i].time_s;
                lat_sum += lat;
                lat_max = lat_max.max(lat);
                let te = d.time_s - truth[i].time_s;
                te_sum += te;
                te_sq += te * te;
                te_max = te_max.max(te.abs());
            }
            None => false_ += 1,
        }
    }
    let ms = |x: f64| (matched > 0).then_some(1e3 * x);
    let m = matched.max(1) as f64;
    DetectionStats {
        matched,
        missed: truth.len() - matched,
        false_,
        latency_mean_ms: ms(lat_sum / m),
        latency_max_ms: ms(lat_max),
        timing_err_mean_ms: ms(te_sum / m),
        timing_err_rms_ms: ms((te_sq / m).sqrt()),
        timing_err_max_ms: ms(te_max),
        match_tolerance_ms: 1e3 * tol_s,
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

/// The human summary.
pub fn summary_text(r: &RunReport) -> String {
    let mut s = String::new();
    let t = &r.truth;
    let e = &r.estimator;
    let d = &r.detection;
    let opt = |x: Option<f64>, p: usize| x.map_or("n/a".to_string(), |v| format!("{v:.p$}"));
    let file = r
        .scene_file
        .as_deref()
        .map_or("built-in default scene".to_string(), |f| f.to_string());
    s += &format!(
        "host-sim run: \"{}\" ({file}, {} input): {} samples at {} Hz ({} s)\n",
        r.scene, r.input, r.samples, r.rate_hz, r.duration_s
    );
    s += &format!(
        "  truth: peak |ü1| {:.4} m/s² at t = {:.4} s; max |slip| {:.3} mm, final slip {:.3} mm; \
         {} slip start(s), {} reversal(s), {} stick(s)\n",
        t.peak_top_accel_m_s2,
        t.peak_top_accel_time_s,
        1e3 * t.max_abs_slip_m,
        1e3 * t.final_slip_m,
        t.slip_starts,
        t.reversals,
        t.sticks
    );
    s += &format!(
        "  peak |ü1| at the samples: measured {:.4}, predicted {:.4}, truth {:.4} m/s²\n",
        e.peak_measured_m_s2, e.peak_predicted_m_s2, e.peak_truth_sampled_m_s2
    );
    s += &format!("  model: {} ({})", e.model, e.model_reason);
    if let (Some(mu), Some(sd)) = (e.mu_estimate, e.mu_std) {
        s += &format!("; identified mu = {mu:.5} ± {sd:.5}");
    }
    s += "\n";
    s += &format!(
        "  estimator ({}, f32, detected events, on stick: {}) vs truth: max |error| {:.4} m/s² ({:.2} % of peak) at t = {:.4} s, \
         rms {:.4} m/s² ({:.2} %)\n",
        e.model,
        e.on_stick,
        e.max_err_m_s2,
        e.max_err_pct_of_peak,
        e.max_err_at_s,
        e.rms_err_m_s2,
        e.rms_err_pct_of_peak
    );
    if let (Some(m), Some(r), Some(mp), Some(rp), Some(d)) = (
        e.revised_max_err_m_s2,
        e.revised_rms_err_m_s2,
        e.revised_max_err_pct_of_peak,
        e.revised_rms_err_pct_of_peak,
        e.revision_delay_ms,
    ) {
        s += &format!(
            "  revised prediction ({d:.1} ms later, after late events re-simulate the history): max |error| {m:.4} m/s² ({mp:.2} %), rms {r:.4} m/s² ({rp:.2} %)\n"
        );
    }
    if e.model != "rectangular" {
        s += &format!(
            "  rectangular model (the paper's, same events) for comparison: max |error| {:.4} m/s², rms {:.4} m/s²\n",
            e.rectangular_max_err_m_s2, e.rectangular_rms_err_m_s2
        );
    }
    s += &format!(
        "  same estimator fed the true events (model error only): max |error| {:.4} m/s², rms {:.4} m/s²; \
         top accelerometer: max |error| {:.4} m/s²\n",
        e.ideal_max_err_m_s2, e.ideal_rms_err_m_s2, e.measured_max_err_m_s2
    );
    let how = match (r.detector.hysteresis_m, r.detector.threshold_m_s2) {
        (Some(h), _) => format!("slip displacement, hysteresis {:.1} µm", 1e6 * h),
        (_, Some(a)) => format!("slip acceleration, threshold {a:.3} m/s²"),
        _ => String::new(),
    };
    s += &format!(
        "  detection ({how}, ring {}): slip starts + reversals {} detected, {} true; \
         {} matched, {} missed, {} false (±{} ms); sticks {} detected, {} true\n",
        r.detector.ring,
        e.reversals_detected,
        e.reversals_true,
        d.matched,
        d.missed,
        d.false_,
        d.match_tolerance_ms,
        e.sticks_detected,
        e.sticks_true
    );
    s += &format!(
        "  latency mean {} ms, max {} ms; event-time error (back-dated) mean {} ms, rms {} ms, max {} ms\n",
        opt(d.latency_mean_ms, 2),
        opt(d.latency_max_ms, 2),
        opt(d.timing_err_mean_ms, 4),
        opt(d.timing_err_rms_ms, 4),
        opt(d.timing_err_max_ms, 4)
    );
    s += &format!(
        "  out: {} ({} rows); runtime {:.2} s\n",
        r.out, r.samples, r.runtime_s
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mark(t: f64, at: f64, level: f64) -> EventMark {
        EventMark {
            time_s: t,
            detected_at_s: at,
            level,
            stick: false,
        }
    }

    #[test]
    fn matching_counts_missed_false_and_timing() {
        let truth = [
            mark(0.10, 0.10, -1.0),
            mark(0.20, 0.20, 1.0),
            mark(0.30, 0.30, -1.0),
            EventMark {
                time_s: 0.35,
                detected_at_s: 0.35,
                level: 0.0,
                stick: true,
            },
        ];
        let detected = [
            mark(0.1001, 0.103, -1.0), // matched, +0.1 ms, latency 3 ms
            mark(0.1999, 0.205, 1.0),  // matched, −0.1 ms, latency 5 ms
            mark(0.25, 0.26, 1.0),     // false: no true event within 20 ms
            mark(0.301, 0.302, 1.0),   // false: wrong level
        ];
        let d = match_events(&detected, &truth, 0.02);
        assert_eq!((d.matched, d.missed, d.false_), (2, 1, 2));
        assert!((d.latency_mean_ms.unwrap() - 4.0).abs() < 1e-9);
        assert!((d.latency_max_ms.unwrap() - 5.0).abs() < 1e-9);
        assert!((d.timing_err_max_ms.unwrap() - 0.1).abs() < 1e-9);
        assert!(d.timing_err_mean_ms.unwrap().abs() < 1e-9);
        let none = match_events(&[], &truth, 0.02);
        assert_eq!((none.matched, none.missed, none.false_), (0, 3, 0));
        assert_eq!(none.latency_mean_ms, None);
    }

    #[test]
    fn csv_numbers_round_trip_without_long_zero_runs() {
        for x in [
            0.0f64,
            -0.0,
            0.3,
            1e-5,
            2.5e-6,
            -1.65863499991046e-48,
            1e16,
            123.456,
        ] {
            let s = Num(x).to_string();
            assert_eq!(s.parse::<f64>().unwrap(), x, "{s}");
            assert!(s.len() < 24, "{s}");
        }
        assert_eq!(Num(-1.6586e-48f64).to_string(), "-1.6586e-48");
        assert_eq!(Num(0.0002f64).to_string(), "0.0002");
        assert_eq!(Num(-0.0000011267663f32).to_string(), "-1.1267663e-6");
        assert_eq!(Num(1.5f32).to_string(), "1.5");
    }

    #[test]
    fn decimation_keeps_extremes_in_time_order() {
        let mut d = Decimator::new(4);
        for (i, v) in [0.0, 3.0, -2.0, 1.0, 5.0, 4.0, 6.0].iter().enumerate() {
            d.push(i as f64, *v);
        }
        let s = d.finish();
        assert_eq!(s, vec![(1.0, 3.0), (2.0, -2.0), (5.0, 4.0), (6.0, 6.0)]);
        let mut one = Decimator::new(1);
        one.push(0.0, 1.0);
        one.push(1.0, 2.0);
        assert_eq!(one.finish(), vec![(0.0, 1.0), (1.0, 2.0)]);
    }

    fn short_scene(duration_s: f64) -> Scene {
        let mut s = Scene::default_scene();
        s.duration_s = duration_s;
        s.samples = (duration_s * s.rate_hz).round() as u64;
        s
    }

    #[test]
    fn writes_the_header_and_one_row_per_sample() {
        let scene = short_scene(0.5);
        let mut buf = Vec::new();
        let stop = AtomicBool::new(false);
        let o = run(&scene, &mut buf, &RunOptions::new("mem"), &stop).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some(CSV_HEADER));
        let cols = CSV_HEADER.split(',').count();
        let rows: Vec<&str> = lines.collect();
        assert_eq!(rows.len() as u64, scene.samples);
        assert!(rows.iter().all(|r| r.split(',').count() == cols));
        assert_eq!(o.report.samples, 5000);
        // Every pushed level in the CSV is a detected slip start or reversal.
        let pushed = rows
            .iter()
            .filter(|r| r.split(',').nth(5) != Some("0"))
            .count();
        assert_eq!(pushed, o.report.estimator.reversals_detected);
    }

    #[test]
    fn a_set_stop_flag_interrupts_after_flushing() {
        let scene = short_scene(1.0);
        let mut buf = Vec::new();
        let stop = AtomicBool::new(true);
        let err = run(&scene, &mut buf, &RunOptions::new("mem"), &stop).unwrap_err();
        let int = err.downcast_ref::<Interrupted>().unwrap();
        assert_eq!(int.rows, FLUSH_EVERY_ROWS);
        let text = String::from_utf8(buf).unwrap();
        assert_eq!(text.lines().count() as u64, FLUSH_EVERY_ROWS + 1);
    }

    #[test]
    fn reversals_scenes_are_rejected_with_a_message() {
        let text = "duration_s = 1.0\n[structure]\nm1_kg = 29.5\nm2_kg = 1.75\nnatural_frequency_hz = 7.0\n\
                    damping_ratio = 0.05\nfriction_coefficient = 0.2\n[input]\nkind = \"reversals\"\n\
                    half_period_s = 0.0715\n[sampling]\nrate_hz = 1000.0\n";
        let scene = Scene::parse(text, Path::new("r.toml")).unwrap();
        let stop = AtomicBool::new(false);
        let err = run(&scene, Vec::new(), &RunOptions::new("mem"), &stop).unwrap_err();
        let msg = format!("{err:#}");
        assert!(msg.contains("r.toml") && msg.contains("reversals"), "{msg}");
    }

    #[test]
    fn default_out_paths() {
        let mut s = Scene::default_scene();
        assert_eq!(default_out_path(&s), PathBuf::from("default.run.csv"));
        s.source = Some(PathBuf::from("dir/elcentro.toml"));
        assert_eq!(default_out_path(&s), PathBuf::from("dir/elcentro.run.csv"));
    }
}
