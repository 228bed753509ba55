//! The plan: what a specimen (as the controller is told it) and a model turn into for the
//! pipeline: the detector's settings, ring and longest back-dating, the stick-slip estimator's
//! settings, history and coefficients. Made once on the host ([`Plan::new`], by the scene's
//! users: `host-sim` and the firmware's build script), embedded in the firmware as words
//! ([`Plan::to_words`], restored by [`Plan::from_words`]: no f64 start-up code), and identified
//! by a digest ([`Plan::digest`]) the firmware reports so the host can check the image runs
//! the plan it expects.

use crate::model::{Mode, ModelKind};
pub use crate::planned_start::{planned_start, PlannedStart};
use ssvr_core::detect::acceleration::PhaseDetectorConfig;
use ssvr_core::detect::displacement::DetectorConfig;
use ssvr_core::recursion::Estimator32;
use ssvr_core::stick_slip::{history_for_age, storage_for, StickSlipCoefficients, StickSlipConfig};
use ssvr_core::{Error, FrictionLaw, Structure, StructureParams};

/// The fixed-base model's history (samples). It pushes no event, so its estimator back-dates
/// none: the history only sets how often the ring wraps, and each wrap costs two general
/// updates (~400 M4F instructions) where the steady run stops. Measured under QEMU against the
/// detector's `max_age + 2` (~190 samples at 10 kHz, ~160 at 1 kHz, 20 B a sample): 2 saved
/// 3.2 KB of the board image's static RAM and cost +10.4 instructions per steady sample at
/// 10 kHz; 66 saves ~1.9 KB and costs about 2 (docs/PERFORMANCE.md).
pub const FIXED_BASE_HISTORY: usize = 66;

/// The longest stick-slip history (samples) a plan may ask for: the host's storage.
pub const MAX_HISTORY: usize = 2048;

/// Number of stick-slip coefficient words.
pub const COEFFICIENT_WORDS: usize = StickSlipCoefficients::<f32>::BITS;

/// What the controller is told about the specimen and its sensors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Specimen {
    /// Structure parameters.
    pub structure: StructureParams,
    /// Static (breakaway) friction coefficient (≥ kinetic).
    pub static_friction_coefficient: f64,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Displacement sensor noise RMS (m): the displacement detector's settings.
    pub disp_noise_rms_m: f64,
    /// Accelerometer noise RMS (m/s²): the slip-acceleration detector's settings.
    pub accel_noise_rms_m_s2: f64,
    /// Displacement full scale ± (m): a sample at or beyond it is unusable.
    pub disp_range_m: f64,
    /// The friction law of the interface (its μ_fast is the structure's friction coefficient):
    /// a velocity-dependent one makes the stick-slip model follow μ(v) from the slip speed.
    pub friction: FrictionLaw,
}

/// The friction-event detector of a plan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DetectorPlan {
    /// `ReversalDetector` on the displacement (rectangular, fixed-base).
    Displacement(DetectorConfig),
    /// `PhaseDetector` on the slip acceleration (stick-slip).
    SlipAcceleration(PhaseDetectorConfig),
}

/// Why a plan cannot be made or restored.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlanError {
    /// A parameter is rejected by the library (structure, rate, detector or estimator settings).
    Core(Error),
    /// The stick-slip history needed (samples) exceeds [`MAX_HISTORY`] or the storage.
    History(usize),
    /// The plan's words are malformed (wrong length, version, or a value out of range).
    Words,
    /// The detector type does not match the plan's detector or ring.
    Detector,
    /// The model type does not match the plan's model.
    Model,
}

impl From<Error> for PlanError {
    fn from(e: Error) -> Self {
        PlanError::Core(e)
    }
}

impl core::fmt::Display for PlanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            PlanError::Core(e) => write!(f, "{e}"),
            PlanError::History(h) => write!(
                f,
                "the stick-slip history of {h} samples (the detector's longest back-dating) \
                 exceeds {MAX_HISTORY}"
            ),
            PlanError::Words => f.write_str("malformed plan words"),
            PlanError::Detector => f.write_str("the detector does not match the plan"),
            PlanError::Model => f.write_str("the model does not match the plan"),
        }
    }
}

/// The plan of a specimen and a model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plan {
    /// The model.
    pub model: ModelKind,
    /// The specimen it was made for.
    pub specimen: Specimen,
    /// The detector's settings: `for_noise` of the specimen's sensors,
    /// `with_friction(static, kinetic)`.
    pub detector: DetectorPlan,
    /// The detector's ring (a power of two holding its fit windows: its `min_ring`).
    pub ring: usize,
    /// The detector's longest back-dating with this ring (samples); the stick-slip model clamps
    /// older events to it.
    pub max_age: usize,
    /// The stick-slip estimator's history: `max_age + 2`; at most [`FIXED_BASE_HISTORY`] for
    /// the fixed-base model, which pushes no event.
    pub history: usize,
    /// The stick-slip estimator's storage that makes its steady state cheapest
    /// (`storage_for(history, identify_every)`).
    pub storage: usize,
    /// The stick-slip estimator's settings ([`ModelKind::stick_slip_config`]).
    pub stick_slip: StickSlipConfig,
    /// The stick-slip estimator's coefficients in f32 (`StickSlipCoefficients::to_bits`).
    pub coefficients: [u32; COEFFICIENT_WORDS],
    /// What the model may read ([`Plan::with_mode`]).
    pub mode: Mode,
    /// Samples of rest before the input (the planned input's start): the accelerometers are
    /// zeroed on them ([`crate::zeroing`]).
    pub rest_samples: u32,
    /// The planned table acceleration's line at the input's start ([`PlannedStart`]): a plan
    /// without a rest (either mode) takes the table accelerometer's offset as the measured
    /// line's intercept less its. `None`: not planned (a replay), or not used (a rest).
    pub planned_start: Option<PlannedStart>,
}

/// Version of the word layout ([`Plan::to_words`]).
pub const WORDS_VERSION: u32 = 8;
/// Length of a plan's words.
pub const WORDS: usize = 52 + COEFFICIENT_WORDS;

impl Plan {
    /// The plan of `specimen` and `model`: every setting validated by the library.
    pub fn new(specimen: Specimen, model: ModelKind) -> Result<Self, PlanError> {
        let s = &specimen;
        let structure = Structure::new(s.structure)?;
        let mu = s.structure.friction_coefficient;
        let rate = s.sample_rate_hz;
        if let FrictionLaw::VelocityDependent { mu_slow, rate_s_m } = s.friction {
            FrictionLaw::velocity_dependent(mu_slow, rate_s_m, mu)?;
        }
        Estimator32::new(&structure, rate)?;
        let (detector, ring, max_age) = if model.detects_on_acceleration() {
            // The kinetic friction a slide starts with: μ_slow under a velocity-dependent law.
            // (Strong ramp breakaways confirmed at their second sample, in either mode: the
            // slide's friction then comes from the breakaway, corrected a sample later from
            // the sliding side in predict mode.)
            let d = PhaseDetectorConfig::for_noise(s.accel_noise_rms_m_s2)?
                .with_friction(s.static_friction_coefficient, s.friction.at_rest(mu))
                .with_early_ramp_starts(true);
            (
                DetectorPlan::SlipAcceleration(d),
                d.min_ring(),
                d.max_age_samples(),
            )
        } else {
            let d = DetectorConfig::for_noise(s.disp_noise_rms_m, rate)?
                .with_friction(s.static_friction_coefficient, s.friction.at_rest(mu));
            let ring = d.min_ring();
            (DetectorPlan::Displacement(d), ring, d.max_age_samples(ring))
        };
        let history = if model == ModelKind::FixedBase {
            history_for_age(max_age).min(FIXED_BASE_HISTORY)
        } else {
            history_for_age(max_age)
        };
        if history > MAX_HISTORY {
            return Err(PlanError::History(history));
        }
        let mut stick_slip = model.stick_slip_config(rate);
        // A velocity-dependent law sets μ every sliding sample: the constant μ̂ of an episode is
        // not adopted (measured: with it, a wrong prior law left 0.20 % RMS on the default PTFE
        // scene, without it 0.087 %).
        if let FrictionLaw::VelocityDependent { mu_slow, .. } = s.friction {
            if mu_slow != mu {
                stick_slip.use_identified_mu = false;
            }
        }
        let coefficients = StickSlipCoefficients::<f32>::new(&structure, rate)?;
        let plan = Self {
            model,
            specimen,
            detector,
            ring,
            max_age,
            history,
            storage: storage_for(history, stick_slip.identify_every),
            stick_slip,
            coefficients: coefficients.to_bits(),
            mode: Mode::Fuse,
            rest_samples: 0,
            planned_start: None,
        };
        // (What a mode sets, set in one place.)
        Ok(plan.with_mode(Mode::Fuse))
    }

    /// This plan in `mode`: [`Mode::Predict`] never reads the top accelerometer, so the
    /// stick-slip estimator neither identifies μ from it nor corrects its stuck state (no stuck
    /// observer); the model's base tuning identifies f, ξ and μ from the sliding base and feeds
    /// the sliding observer the momentum balance's top acceleration
    /// ([`BaseTuning`](crate::model::BaseTuning), docs/ROBUSTNESS.md).
    pub fn with_mode(mut self, mode: Mode) -> Self {
        self.mode = mode;
        if mode == Mode::Predict {
            self.stick_slip.identify_mu = false;
            self.stick_slip.use_identified_mu = false;
            self.stick_slip.observer_bandwidth = 0.0;
            self.stick_slip.cap_sliding_observer = false;
        }
        let planned = self.planned_start;
        self.with_planned_start(planned)
    }

    /// This plan with a rest of `seconds` before the input (whole samples of it).
    pub fn with_rest(mut self, seconds: f64) -> Self {
        let n = libm::floor(seconds * self.specimen.sample_rate_hz);
        self.rest_samples = if n.is_finite() && n > 0.0 {
            if n < u32::MAX as f64 {
                n as u32
            } else {
                u32::MAX
            }
        } else {
            0
        };
        let planned = self.planned_start;
        self.with_planned_start(planned)
    }

    /// This plan with its planned table acceleration `accel(t)` (m/s², t in s from the input's
    /// start): [`Self::planned_start`] ([`planned_start`]) for a plan without a rest, the only
    /// one that uses it (none for the others, whose digests and images then do not depend on
    /// the input). Call it after [`Self::with_mode`] and [`Self::with_rest`].
    pub fn with_planned_input(self, accel: impl Fn(f64) -> f64) -> Self {
        let planned = if self.uses_planned_start() {
            planned_start(
                &self.specimen.structure,
                self.specimen.sample_rate_hz,
                accel,
            )
        } else {
            None
        };
        self.with_planned_start(planned)
    }

    /// This plan with the planned start `planned` (as [`Self::with_planned_input`] computes
    /// it; the firmware's build gets it so from the host): kept for a plan without a rest only,
    /// and when finite. [`Self::with_mode`] and [`Self::with_rest`] drop it when
    /// the plan no longer uses it.
    pub fn with_planned_start(mut self, planned: Option<PlannedStart>) -> Self {
        let uses = self.uses_planned_start();
        self.planned_start = planned
            .filter(|p| uses && p.accel_m_s2.is_finite() && p.rise_per_sample_m_s2.is_finite());
        self
    }

    /// Whether the plan uses a planned start: without a rest, either mode (fuse mode had none
    /// before the fifteenth session: its table offset then stayed in the model as b_t/35 until
    /// the sliding phases, docs/ROBUSTNESS.md).
    fn uses_planned_start(&self) -> bool {
        self.rest_samples == 0
    }

    /// Whether the pipeline identifies the table accelerometer's gain against the displacement
    /// sensor ([`crate::table_gain`]): for the stick-slip model, the one that reads the
    /// accelerometers' values (the rectangular model reads only the events; the fixed-base
    /// model's base never slides, and its board's 8 KiB of RAM have no room for it).
    pub fn identifies_table_gain(&self) -> bool {
        self.model == ModelKind::StickSlip
    }

    /// Whether the stick-slip model follows a velocity-dependent friction law: the specimen has
    /// one with μ_slow < μ_fast (the firmware's build, the host's pipeline and the f64 reference
    /// all decide by this).
    pub const fn follows_law(&self) -> bool {
        match self.specimen.friction {
            FrictionLaw::Coulomb => false,
            FrictionLaw::VelocityDependent { mu_slow, .. } => {
                mu_slow != self.specimen.structure.friction_coefficient
            }
        }
    }

    /// The displacement full scale in f32.
    pub fn disp_range_m(&self) -> f32 {
        self.specimen.disp_range_m as f32
    }

    /// The plan as words (version [`WORDS_VERSION`]): every field, floats by their bits.
    pub const fn to_words(&self) -> [u32; WORDS] {
        let mut w = Words([0; WORDS], 0);
        w.u32(WORDS_VERSION);
        w.u32(self.model as u32);
        let s = &self.specimen;
        let p = &s.structure;
        w.f64(p.m1_kg);
        w.f64(p.m2_kg);
        w.f64(p.natural_frequency_hz);
        w.f64(p.damping_ratio);
        w.f64(p.friction_coefficient);
        w.f64(p.gravity_m_s2);
        w.f64(s.static_friction_coefficient);
        w.f64(s.sample_rate_hz);
        w.f64(s.disp_noise_rms_m);
        w.f64(s.accel_noise_rms_m_s2);
        w.f64(s.disp_range_m);
        match s.friction {
            FrictionLaw::Coulomb => {
                w.u32(0);
                w.f64(0.0);
                w.f64(0.0);
            }
            FrictionLaw::VelocityDependent { mu_slow, rate_s_m } => {
                w.u32(1);
                w.f64(mu_slow);
                w.f64(rate_s_m);
            }
        }
        match self.detector {
            DetectorPlan::Displacement(d) => {
                w.u32(0);
                w.u32(d.hysteresis_m.to_bits());
                w.usize(d.fit_half);
                w.usize(d.stick_samples);
                w.u32(0);
                w.u32(d.cubic_breakaway as u32);
            }
            DetectorPlan::SlipAcceleration(d) => {
                w.u32(1);
                w.u32(d.threshold_m_s2.to_bits());
                w.usize(d.confirm_samples);
                w.usize(d.search_samples);
                w.usize(d.stall_samples);
                w.u32(d.jump_breakaway as u32 | (d.early_ramp_starts as u32) << 1);
            }
        }
        w.usize(self.ring);
        w.usize(self.max_age);
        w.usize(self.history);
        w.usize(self.storage);
        let c = &self.stick_slip;
        w.u32(c.identify_mu as u32);
        w.u32(c.use_identified_mu as u32);
        w.f64(c.forgetting);
        w.u32(c.min_blocks);
        w.u32(c.identify_every);
        w.f64(c.observer_bandwidth);
        // (Bit 0: the sliding observer; bit 1: capped.)
        w.u32(c.sliding_observer as u32 | (c.cap_sliding_observer as u32) << 1);
        let mut i = 0;
        while i < COEFFICIENT_WORDS {
            w.u32(self.coefficients[i]);
            i += 1;
        }
        w.u32(self.mode as u32);
        w.u32(self.rest_samples);
        // (Not planned: NaNs.)
        let (a, rise) = match self.planned_start {
            Some(p) => (p.accel_m_s2, p.rise_per_sample_m_s2),
            None => (f32::NAN, f32::NAN),
        };
        w.u32(a.to_bits());
        w.u32(rise.to_bits());
        w.0
    }

    /// The plan of its words ([`Self::to_words`]). A `const fn`: the firmware restores its plan
    /// at compile time, so the plan's numbers are constants in its code.
    pub const fn from_words(words: &[u32; WORDS]) -> Result<Self, PlanError> {
        let mut r = Reader { w: words, i: 0 };
        if r.u32() != WORDS_VERSION {
            return Err(PlanError::Words);
        }
        let Some(model) = (match byte(r.u32()) {
            Some(c) => ModelKind::from_code(c),
            None => None,
        }) else {
            return Err(PlanError::Words);
        };
        let structure = StructureParams {
            m1_kg: r.f64(),
            m2_kg: r.f64(),
            natural_frequency_hz: r.f64(),
            damping_ratio: r.f64(),
            friction_coefficient: r.f64(),
            gravity_m_s2: r.f64(),
        };
        let specimen = Specimen {
            structure,
            static_friction_coefficient: r.f64(),
            sample_rate_hz: r.f64(),
            disp_noise_rms_m: r.f64(),
            accel_noise_rms_m_s2: r.f64(),
            disp_range_m: r.f64(),
            friction: match (r.u32(), r.f64(), r.f64()) {
                (0, _, _) => FrictionLaw::Coulomb,
                (1, mu_slow, rate_s_m) => FrictionLaw::VelocityDependent { mu_slow, rate_s_m },
                _ => return Err(PlanError::Words),
            },
        };
        let kind = r.u32();
        let x = r.u32();
        let a = r.usize();
        let b = r.usize();
        let c = r.usize();
        let flags = r.u32();
        let flag = flags & 1 != 0;
        let detector = match kind {
            0 => DetectorPlan::Displacement(DetectorConfig {
                hysteresis_m: f32::from_bits(x),
                fit_half: a,
                stick_samples: b,
                cubic_breakaway: flag,
            }),
            1 => DetectorPlan::SlipAcceleration(PhaseDetectorConfig {
                threshold_m_s2: f32::from_bits(x),
                confirm_samples: a,
                search_samples: b,
                stall_samples: c,
                jump_breakaway: flag,
                early_ramp_starts: flags & 2 != 0,
            }),
            _ => return Err(PlanError::Words),
        };
        let ring = r.usize();
        let max_age = r.usize();
        let history = r.usize();
        let storage = r.usize();
        let (identify_mu, use_identified_mu) = (r.u32() != 0, r.u32() != 0);
        let (forgetting, min_blocks, identify_every) = (r.f64(), r.u32(), r.u32());
        let (observer_bandwidth, sliding) = (r.f64(), r.u32());
        let stick_slip = StickSlipConfig {
            identify_mu,
            use_identified_mu,
            forgetting,
            min_blocks,
            identify_every,
            observer_bandwidth,
            sliding_observer: sliding & 1 != 0,
            cap_sliding_observer: sliding & 2 != 0,
        };
        let mut coefficients = [0u32; COEFFICIENT_WORDS];
        let mut i = 0;
        while i < COEFFICIENT_WORDS {
            coefficients[i] = r.u32();
            i += 1;
        }
        let Some(mode) = (match byte(r.u32()) {
            Some(c) => Mode::from_code(c),
            None => None,
        }) else {
            return Err(PlanError::Words);
        };
        let rest_samples = r.u32();
        let (a, rise) = (f32::from_bits(r.u32()), f32::from_bits(r.u32()));
        let planned_start = if a.is_finite() && rise.is_finite() {
            Some(PlannedStart {
                accel_m_s2: a,
                rise_per_sample_m_s2: rise,
            })
        } else {
            None
        };
        if r.i != WORDS {
            return Err(PlanError::Words);
        }
        Ok(Self {
            model,
            specimen,
            detector,
            ring,
            max_age,
            history,
            storage,
            stick_slip,
            coefficients,
            mode,
            rest_samples,
            planned_start,
        })
    }

    /// FNV-1a (32 bit) of the plan's words: the firmware reports it, the host compares it.
    pub const fn digest(&self) -> u32 {
        let words = self.to_words();
        let mut h: u32 = 0x811c_9dc5;
        let mut i = 0;
        while i < WORDS {
            let bytes = words[i].to_le_bytes();
            let mut j = 0;
            while j < 4 {
                h ^= bytes[j] as u32;
                h = h.wrapping_mul(0x0100_0193);
                j += 1;
            }
            i += 1;
        }
        h
    }
}

/// A word that holds a byte (an enum's code).
const fn byte(w: u32) -> Option<u8> {
    if w <= u8::MAX as u32 {
        Some(w as u8)
    } else {
        None
    }
}

/// Writes words in order.
struct Words([u32; WORDS], usize);

impl Words {
    const fn u32(&mut self, v: u32) {
        if self.1 < WORDS {
            self.0[self.1] = v;
        }
        self.1 += 1;
    }
    const fn usize(&mut self, v: usize) {
        self.u32(if v > u32::MAX as usize {
            u32::MAX
        } else {
            v as u32
        });
    }
    const fn f64(&mut self, v: f64) {
        let b = v.to_bits();
        self.u32(b as u32);
        self.u32((b >> 32) as u32);
    }
}

/// Reads words in order (zero past the end; the caller checks the count).
struct Reader<'a> {
    w: &'a [u32; WORDS],
    i: usize,
}

impl Reader<'_> {
    const fn u32(&mut self) -> u32 {
        let v = if self.i < WORDS { self.w[self.i] } else { 0 };
        self.i += 1;
        v
    }
    const fn usize(&mut self) -> usize {
        self.u32() as usize
    }
    const fn f64(&mut self) -> f64 {
        let lo = self.u32() as u64;
        let hi = self.u32() as u64;
        f64::from_bits(lo | (hi << 32))
    }
}

#[cfg(test)]
mod tests;
