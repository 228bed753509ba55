//! "Model only what a scene needs": the estimator model for a scene, and one interface over them.
//!
//! * **fixed-base**: the base never slides: the top mass is a fixed-base oscillator driven by the
//!   measured table acceleration (the stick-slip estimator held in its stuck phase, events ignored,
//!   no identification: [`FIXED_BASE_CONFIG`]);
//! * **rectangular**: the base reciprocates continuously (after the start-up): the paper's
//!   rectangular friction, the O(1) Duhamel recursion (`Estimator32`);
//! * **stick-slip**: the base sticks and slides in turn: the stick-slip aware estimator
//!   (`StickSlipEstimator`, f32 + `F32Poly`), with online friction identification.
//!
//! [`choose`] picks the smallest model that serves the scene from the pre-test simulation (the exact
//! truth): no slip phase → fixed-base; no stick after the first fifth of the run → rectangular;
//! otherwise stick-slip. The firmware compiles in one model (`SSVR_MODEL`, [`Model::name`]) with
//! the same settings; `host-sim qemu` chooses it the same way.

use crate::sensors::{SensorFrame, FLAG_ACCEL_SATURATED};
use crate::truth::{EventKind, Truth};
use ssvr_core::detect::acceleration::{PhaseDetector, PhaseDetectorConfig};
use ssvr_core::detect::displacement::{DetectorConfig, ReversalDetector, SlipEvent};
use ssvr_core::math::F32Poly;
use ssvr_core::recursion::Estimator32;
use ssvr_core::stick_slip::{MuEstimate, StickSlipConfig, StickSlipEstimator};
use ssvr_core::{Error, Structure};

/// History of the stick-slip estimator on the host (samples): the longest back-dating.
pub const HISTORY: usize = 2048;

/// The stick-slip estimator's settings (`run`, and the firmware's: `firmware/build.rs` builds
/// the same, `host-sim qemu` checks the firmware's `model` message against it): μ identified and
/// adopted at the start of each sliding episode.
pub const STICK_SLIP_CONFIG: StickSlipConfig = StickSlipConfig {
    use_identified_mu: true,
    ..StickSlipConfig::DEFAULT
};

/// The fixed-base model's settings: the stick-slip estimator without identification (it never
/// leaves its stuck phase, so identifying μ would change nothing but the cost).
pub const FIXED_BASE_CONFIG: StickSlipConfig = StickSlipConfig {
    identify_mu: false,
    observer_bandwidth: 0.0,
    ..STICK_SLIP_CONFIG
};

/// The stick-slip estimator's settings of a model at a sample rate (rectangular: unused, the
/// stick-slip ones), with identification blocks of ~3.2 ms ([`StickSlipConfig::for_rate`]).
pub fn stick_slip_config(model: Model, rate_hz: f64) -> StickSlipConfig {
    match model {
        Model::FixedBase => FIXED_BASE_CONFIG,
        Model::Rectangular | Model::StickSlip => STICK_SLIP_CONFIG,
    }
    .for_rate(rate_hz)
}

/// An estimator model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Model {
    /// Fixed-base oscillator (no sliding).
    FixedBase,
    /// Rectangular friction, O(1) Duhamel recursion (continuous reciprocation).
    Rectangular,
    /// Stick-slip aware estimator (stick and slide in turn).
    StickSlip,
}

impl Model {
    /// Every model.
    pub const ALL: [Model; 3] = [Model::FixedBase, Model::Rectangular, Model::StickSlip];

    /// The model's name as printed, in JSON and in the firmware's `SSVR_MODEL`.
    pub fn name(self) -> &'static str {
        match self {
            Model::FixedBase => "fixed-base",
            Model::Rectangular => "rectangular",
            Model::StickSlip => "stick-slip",
        }
    }
}

/// The smallest model that serves the simulated run, with the reason in words.
pub fn choose(truth: &Truth, duration_s: f64) -> (Model, String) {
    let events = truth.events();
    let slips = events
        .iter()
        .filter(|e| matches!(e.kind, EventKind::SlipStart { .. }))
        .count();
    if slips == 0 {
        return (
            Model::FixedBase,
            "the base never slides in the simulated run".into(),
        );
    }
    let settle = 0.2 * duration_s;
    let late_sticks = events
        .iter()
        .filter(|e| e.time_s > settle && matches!(e.kind, EventKind::Stick))
        .count();
    if late_sticks == 0 {
        (
            Model::Rectangular,
            format!("the base slides continuously after t = {settle:.3} s"),
        )
    } else {
        (
            Model::StickSlip,
            format!("the base sticks {late_sticks} time(s) after t = {settle:.3} s"),
        )
    }
}

/// One of the models, driven sample by sample.
#[derive(Debug, Clone)]
pub enum ModelEstimator {
    /// Rectangular friction; `zero_at_stick` pushes level 0 at a stick (else the level is kept).
    Rectangular {
        /// The recursion.
        est: Box<Estimator32>,
        /// Push level 0 at a stick.
        zero_at_stick: bool,
    },
    /// Stick-slip aware (also the fixed-base model, with `events` false).
    StickSlip {
        /// The estimator.
        est: Box<StickSlipEstimator<f32, F32Poly, HISTORY>>,
        /// Whether detected events are applied (false: fixed-base).
        events: bool,
    },
}

impl ModelEstimator {
    /// The estimator of `model` for a structure and sample rate.
    pub fn new(
        model: Model,
        structure: &Structure,
        rate_hz: f64,
        zero_at_stick: bool,
    ) -> Result<Self, Error> {
        Ok(match model {
            Model::Rectangular => ModelEstimator::Rectangular {
                est: Box::new(Estimator32::new(structure, rate_hz)?),
                zero_at_stick,
            },
            Model::StickSlip | Model::FixedBase => ModelEstimator::StickSlip {
                est: Box::new(StickSlipEstimator::new(
                    structure,
                    rate_hz,
                    stick_slip_config(model, rate_hz),
                )?),
                events: model == Model::StickSlip,
            },
        })
    }

    /// A detected event: `level` is the friction level after it (±1 for a slip start or reversal,
    /// 0 for a stick), `age` its age in samples. Returns whether the model used it.
    pub fn push(&mut self, level: f32, stick: bool, age: f32) -> Result<bool, Error> {
        match self {
            ModelEstimator::Rectangular { est, zero_at_stick } => {
                if stick && !*zero_at_stick {
                    return Ok(false);
                }
                est.push_reversal(if stick { 0.0 } else { level }, age)?;
                Ok(true)
            }
            ModelEstimator::StickSlip { est, events } => {
                if !*events {
                    return Ok(false);
                }
                let phase = if stick { 0 } else { level as i8 };
                est.push_event(phase, age)?;
                Ok(true)
            }
        }
    }

    /// The prediction of ü1 at this sample from the measured table and top accelerations.
    pub fn update(&mut self, table_accel: f32, measured_top: f32) -> f32 {
        match self {
            ModelEstimator::Rectangular { est, .. } => est.update(),
            ModelEstimator::StickSlip { est, .. } => est.update(table_accel, measured_top),
        }
    }

    /// The prediction of an earlier sample revised by later (back-dated) events: the stick-slip
    /// model re-simulates its history; the rectangular one cannot revise (`None`).
    pub fn revised(&self, sample: u64) -> Option<f32> {
        match self {
            ModelEstimator::Rectangular { .. } => None,
            ModelEstimator::StickSlip { est, .. } => est.prediction_at(sample),
        }
    }

    /// The identified friction coefficient (stick-slip model).
    pub fn mu_estimate(&self) -> Option<MuEstimate> {
        match self {
            ModelEstimator::Rectangular { .. } => None,
            ModelEstimator::StickSlip { est, .. } => est.mu_estimate(),
        }
    }
}

/// Ring of the slip-acceleration detector (power of two ≥ its fit window of 38 samples).
pub const PHASE_DETECTOR_RING: usize = 64;

/// Ring of the slip-displacement detector (≥ 2·fit_half + 2 = 130 at any rate; holds a stick's
/// fit window at 10 kHz).
pub const DISPLACEMENT_DETECTOR_RING: usize = 256;

/// Which detector a model uses ([`Detector::for_model`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum DetectorKind {
    /// [`ReversalDetector`] on the base-to-table displacement (rectangular, fixed-base).
    SlipDisplacement,
    /// [`PhaseDetector`] on the slip acceleration, base minus table accelerometer
    /// (stick-slip: its stick and slip start times must be right to a fraction of a sample).
    SlipAcceleration,
}

/// The friction-event detector of a run (the firmware compiles in the same per model).
#[derive(Debug, Clone)]
pub enum Detector {
    /// On the displacement.
    Displacement(Box<ReversalDetector<DISPLACEMENT_DETECTOR_RING>>),
    /// On the slip acceleration.
    Acceleration(Box<PhaseDetector<PHASE_DETECTOR_RING>>),
}

impl Detector {
    /// The detector kind of a model.
    pub fn kind_for(model: Model) -> DetectorKind {
        match model {
            Model::StickSlip => DetectorKind::SlipAcceleration,
            Model::FixedBase | Model::Rectangular => DetectorKind::SlipDisplacement,
        }
    }

    /// The detector of `model` for a scene's sensors, sample rate and friction.
    pub fn for_model(
        model: Model,
        sensors: &crate::scene::Sensors,
        rate_hz: f64,
        (mu_static, mu): (f64, f64),
    ) -> Result<Self, Error> {
        Ok(match Self::kind_for(model) {
            DetectorKind::SlipDisplacement => {
                let cfg = DetectorConfig::for_noise(sensors.disp_noise_rms_m, rate_hz)?
                    .with_friction(mu_static, mu);
                Detector::Displacement(Box::new(ReversalDetector::new(cfg)?))
            }
            DetectorKind::SlipAcceleration => {
                let cfg = PhaseDetectorConfig::for_noise(sensors.accel_noise_rms_m_s2)?
                    .with_friction(mu_static, mu);
                Detector::Acceleration(Box::new(PhaseDetector::new(cfg)?))
            }
        })
    }

    /// Its kind.
    pub fn kind(&self) -> DetectorKind {
        match self {
            Detector::Displacement(_) => DetectorKind::SlipDisplacement,
            Detector::Acceleration(_) => DetectorKind::SlipAcceleration,
        }
    }

    /// Process one measured frame: the displacement, or the base minus table acceleration (NaN
    /// when an accelerometer saturated: the detector repeats its last value).
    pub fn process(&mut self, f: &SensorFrame) -> Option<SlipEvent> {
        match self {
            Detector::Displacement(d) => d.process(f.disp_m),
            Detector::Acceleration(d) => d.process(if f.flags & FLAG_ACCEL_SATURATED != 0 {
                f32::NAN
            } else {
                f.base_accel_m_s2 - f.table_accel_m_s2
            }),
        }
    }

    /// The longest back-dating of its events (samples).
    pub fn max_age_samples(&self) -> usize {
        match self {
            Detector::Displacement(d) => d.config().max_age_samples(DISPLACEMENT_DETECTOR_RING),
            Detector::Acceleration(d) => d.config().max_age_samples(),
        }
    }
}
