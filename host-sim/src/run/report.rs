//! The report of a run (`--json` prints it: [`RunReport`] with the truth's, the estimator's and
//! the detector's figures) and its human summary ([`summary_text`]); the scene's name in messages
//! ([`scene_label`]) and the check that `run` can simulate a scene ([`check_runnable`]).

use super::events::{count, DetectionStats, EventMark};
use crate::scene::{Input, Scene};
use crate::truth::{self, EventKind, Truth};
use anyhow::{bail, Result};
use serde::Serialize;
use ssvr_proto::{DetectorPlan, Plan};

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

impl TruthStats {
    /// The figures of `truth` whose events up to the last sample `last_t_s` are `true_events`.
    pub(super) fn of(truth: &Truth, last_t_s: f64, true_events: &[EventMark]) -> Self {
        let events: &[truth::Event] = truth.events();
        Self {
            peak_top_accel_m_s2: truth.peak_top_accel_m_s2(),
            peak_top_accel_time_s: truth.peak_top_accel_time_s(),
            max_abs_slip_m: truth.max_abs_slip_m(),
            final_slip_m: truth.final_slip_m(),
            slip_phases: truth.slip_phases(),
            slip_starts: events
                .iter()
                .filter(|e| e.time_s <= last_t_s && matches!(e.kind, EventKind::SlipStart { .. }))
                .count(),
            reversals: events
                .iter()
                .filter(|e| e.time_s <= last_t_s && matches!(e.kind, EventKind::Reversal { .. }))
                .count(),
            sticks: count(true_events, true),
        }
    }
}

/// The specimen's parameters and the accelerometers' offsets as the estimator ends the run
/// (`estimator.identified` in `run --json`). The natural frequency and the damping ratio are the
/// online estimates when the model identifies them (stick-slip and fixed-base models, fuse mode),
/// else the prior's; the static friction coefficient is the mean breakaway coefficient of the
/// detected slip starts (stick-slip model; else the prior's); the friction
/// coefficient is μ̂ when the model identified it, else the prior's; the offsets are those the
/// pipeline removed: table and top from the rest before the input (zero without one), the base
/// from the rest plus the slip acceleration's offset its detector tracks (the base against the
/// table), stick-slip model only; plus those the stick-slip model identified from the sliding
/// phases and removes from its inputs (the table's, which the base channel also reads, and in
/// fuse mode the top's).
#[derive(Debug, Clone, Serialize)]
pub struct Identified {
    /// Natural frequency (Hz).
    pub natural_frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Kinetic friction coefficient.
    pub friction_coefficient: f64,
    /// Static friction coefficient.
    pub static_friction_coefficient: f64,
    /// Offsets of the table, base and top accelerometers (m/s²).
    pub accel_bias_m_s2: [f64; 3],
    /// Standard deviation of the identified natural frequency (Hz; absent: not identified).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub natural_frequency_std_hz: Option<f64>,
    /// Standard deviation of the identified damping ratio (absent: not identified).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damping_ratio_std: Option<f64>,
    /// The natural frequency (Hz) and damping ratio the model used at the end, and how many
    /// times it adopted identified ones (absent: the model does not identify them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub in_use: Option<InUse>,
    /// Standard deviation of one slip start's breakaway coefficient (absent: not identified).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub static_friction_coefficient_std: Option<f64>,
    /// Slip starts the static friction coefficient was identified from (absent: not
    /// identified).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub static_friction_slip_starts: Option<u32>,
    /// The base accelerometer's gain relative to the table's, minus 1, as the slip-acceleration
    /// detector tracks and removes it (absent: the displacement detector).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub base_vs_table_gain_error: Option<f64>,
    /// The velocity-dependent friction law the model used at the end (absent: the model uses
    /// none, i.e. Coulomb friction).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<FrictionLawJson>,
    /// The table accelerometer's gain error identified against the displacement sensor over
    /// the sliding episodes (absent: fewer than eight episodes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub table_gain_error: Option<TableGainJson>,
}

/// `estimator.identified.table_gain_error`: the table accelerometer's gain error e (measured =
/// (1 + e)·true) against the displacement sensor; every accelerometer is divided by 1 + the one
/// in use.
#[derive(Debug, Clone, Serialize)]
pub struct TableGainJson {
    /// The estimate of e.
    pub estimate: f64,
    /// Its standard deviation.
    pub std: f64,
    /// Sliding episodes it rests on.
    pub episodes: u32,
    /// The e in use at the end (0 until an adoption).
    pub in_use: f64,
}

/// `estimator.identified.friction`: the law μ(v) = mu_fast − (mu_fast − mu_slow)·e^{−rate_s_m·|v|}
/// in use at the end of the run (identified online in fuse mode, the prior's in predict mode).
#[derive(Debug, Clone, Serialize)]
pub struct FrictionLawJson {
    /// "velocity-dependent".
    pub law: &'static str,
    /// μ as |v| → 0.
    pub mu_slow: f64,
    /// μ at high speed.
    pub mu_fast: f64,
    /// a (s/m).
    pub rate_s_m: f64,
    /// Times an identified law was adopted (0: the prior's law throughout).
    pub adoptions: u32,
    /// Observations (sliding samples) of the last fit (absent: no fit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub observations: Option<u32>,
    /// RMS residual of the last fit (units of μ; absent: no fit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_rms: Option<f64>,
}

impl From<ssvr_proto::model::FrictionReport> for FrictionLawJson {
    fn from(r: ssvr_proto::model::FrictionReport) -> Self {
        Self {
            law: "velocity-dependent",
            mu_slow: f64::from(r.mu_slow),
            mu_fast: f64::from(r.mu_fast),
            rate_s_m: f64::from(r.rate_s_m),
            adoptions: r.adoptions,
            observations: r.fit.map(|f| f.observations),
            residual_rms: r.fit.map(|f| f64::from(f.residual_rms)),
        }
    }
}

/// The f, ξ and m1 a model used at the end of a run (`estimator.identified.in_use`).
#[derive(Debug, Clone, Serialize)]
pub struct InUse {
    /// Natural frequency (Hz).
    pub natural_frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Adoptions of identified values during the run.
    pub adoptions: u32,
    /// Top mass (kg): the prior's, or the one the mass identification took.
    pub m1_kg: f64,
}

impl Identified {
    /// From the plan (the prior) and what the pipeline identified by the end of the run (the
    /// base's gain against the table's only for the stick-slip model, `stick_slip`).
    pub fn of(plan: &ssvr_proto::Plan, pipe: &dyn ssvr_proto::Step, stick_slip: bool) -> Self {
        let mu = pipe.mu_estimate().map(|m| m.mu);
        let oscillator = pipe.oscillator();
        let static_friction = pipe.static_friction();
        let offsets = crate::run::sum(pipe.offsets(), pipe.model_offsets());
        let gain_mismatch = stick_slip.then(|| pipe.gain_mismatch());
        let p = &plan.specimen.structure;
        let est = oscillator.and_then(|o| o.estimate);
        Self {
            natural_frequency_hz: est.map_or(p.natural_frequency_hz, |e| e.natural_frequency_hz),
            damping_ratio: est.map_or(p.damping_ratio, |e| e.damping_ratio),
            friction_coefficient: mu.unwrap_or(p.friction_coefficient),
            static_friction_coefficient: static_friction
                .map_or(plan.specimen.static_friction_coefficient, |s| s.mu_s),
            accel_bias_m_s2: offsets.map(f64::from),
            natural_frequency_std_hz: est.map(|e| e.natural_frequency_std_hz),
            damping_ratio_std: est.map(|e| e.damping_ratio_std),
            in_use: oscillator.map(|o| InUse {
                natural_frequency_hz: o.natural_frequency_hz,
                damping_ratio: o.damping_ratio,
                adoptions: o.adoptions,
                m1_kg: o.m1_kg,
            }),
            static_friction_coefficient_std: static_friction.map(|s| s.std),
            static_friction_slip_starts: static_friction.map(|s| s.slip_starts),
            base_vs_table_gain_error: gain_mismatch.map(f64::from),
            friction: pipe.friction_law().map(FrictionLawJson::from),
            table_gain_error: pipe.table_gain().map(|g| TableGainJson {
                estimate: g.gain - 1.0,
                std: g.sigma,
                episodes: g.episodes,
                in_use: f64::from(g.in_use) - 1.0,
            }),
        }
    }
}

/// The estimator's figures (errors against the truth's ü1 over every sample).
#[derive(Debug, Clone, Serialize)]
pub struct EstimatorStats {
    /// The model ("fixed-base", "rectangular", "stick-slip").
    pub model: &'static str,
    /// What the model read: "fuse" (every channel) or "predict" (never the top accelerometer).
    pub mode: &'static str,
    /// Why this model (chosen from the simulated run, or "--model").
    pub model_reason: String,
    /// The specimen's parameters and the sensors' offsets as the estimator ends the run.
    pub identified: Identified,
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
    pub(super) fn of(plan: &Plan) -> Self {
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
    if let Some(law) = &e.identified.friction {
        s += &format!(
            "; friction law in use: mu_slow {:.5}, mu_fast {:.5}, a {:.2} s/m ({})",
            law.mu_slow,
            law.mu_fast,
            law.rate_s_m,
            match law.adoptions {
                0 => "the prior's".to_string(),
                n => format!("identified, {n} adoptions"),
            }
        );
    } else if let (Some(mu), Some(sd)) = (e.mu_estimate, e.mu_std) {
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
