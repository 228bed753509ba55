//! `host-sim qemu [SCENE] [--model MODEL] [--json]`: run the firmware's QEMU image on a scene and
//! check every prediction it makes.
//!
//! 1. Simulate the exact stick-slip truth of the scene ([`crate::truth`]) and measure it with the
//!    seeded sensor model ([`crate::sensors`]); write the sensor log
//!    ([`qemu_runner::write_sensor_log`]). The estimator model is chosen from the simulated truth
//!    like `host-sim run` does ([`crate::model::choose`]), or given with `--model`.
//! 2. Build the QEMU image (and the board image, for its sizes) for the scene and the model
//!    ([`qemu_runner::build_for_scene_model`]: `SSVR_SCENE`, `SSVR_MODEL`; cargo rebuilds only
//!    when the scene's firmware parameters or the model change).
//! 3. Run it under `qemu-system-arm -icount shift=0` and decode its defmt stream.
//! 4. Compare every sample's prediction
//!    * with the same core code on the host on the same f32 inputs ([`HostPipeline`]: the
//!      firmware's per-sample step, i.e. `ReversalDetector` + the model's estimator, mirrored
//!      line by line): must be equal to ≤ 1e-6·gμ (it is bit-identical in practice), as must the
//!      detected events, the flags and the identified μ;
//!    * with a full-precision reference on the events the firmware detected (at sample k, the
//!      events detected up to k: what the estimator knew then), which measures the firmware's
//!      f32 arithmetic: for the rectangular model the closed form (`DuhamelClosedForm`, f64) of
//!      the detected train, event times t = (k − age)/rate in f64; for the stick-slip and
//!      fixed-base models the stick-slip estimator in f64 (libm transcendentals, same history and
//!      settings) fed the same events (same clamped ages) and the same measured accelerations;
//!    * with the exact truth (information: detection latency, and the rectangular model's stick
//!      phases, show there).
//! 5. Report instruction counts (SysTick under `-icount`), flash and static RAM of both images.
//!
//! The command fails (non-zero exit) when the firmware and the host differ by more than
//! [`HOST_TOLERANCE_GMU`], when their events, flags or μ̂ differ, or when frames are missing.

use crate::model::{self, stick_slip_config, Model};
use crate::qemu_runner::{
    self, event_kind, frame_flags as ff, FrameEvent, LogHeader, LogSample, SampleFrame,
};
use crate::scene::Scene;
use crate::sensors::{self, FLAG_ACCEL_SATURATED, FLAG_DISP_SATURATED};
use crate::truth::{self, TruthInput};
use anyhow::{anyhow, bail, Context, Result};
use serde::Serialize;
use ssvr_core::closed_form::duhamel::{DuhamelClosedForm, Reversal, ReversalTrain};
use ssvr_core::detect::acceleration::{PhaseDetector, PhaseDetectorConfig};
use ssvr_core::detect::displacement::{DetectorConfig, ReversalDetector, SlipEvent};
use ssvr_core::math::{F32Poly, Libm};
use ssvr_core::recursion::Estimator32;
use ssvr_core::stick_slip::{history_for_age, MuEstimate, StickSlipEstimator};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Largest accepted |firmware − host| prediction difference, in gμ.
pub const HOST_TOLERANCE_GMU: f64 = 1e-6;
/// Goal: instructions of a steady-state estimator sample on the M4F (rectangular model).
pub const GOAL_INSTRUCTIONS_PER_SAMPLE: f64 = 20.0;
/// Goal: instructions of a steady-state sample of the stick-slip estimator (sliding, μ identified
/// on every block of samples) and of the fixed-base model (stuck) on the M4F.
pub const GOAL_INSTRUCTIONS_PER_SAMPLE_STICK_SLIP: f64 = 40.0;
/// Storage of the host's stick-slip estimators (samples); the firmware's history is at most this
/// (firmware/build.rs checks it).
pub const HOST_HISTORY_CAPACITY: usize = 2048;

/// The instruction goal of a model's steady-state sample.
pub fn instructions_goal(model: Model) -> f64 {
    match model {
        Model::Rectangular => GOAL_INSTRUCTIONS_PER_SAMPLE,
        Model::StickSlip | Model::FixedBase => GOAL_INSTRUCTIONS_PER_SAMPLE_STICK_SLIP,
    }
}
/// Goal: board image flash (bytes).
pub const GOAL_BOARD_FLASH_BYTES: u64 = 32 * 1024;
/// Goal: board image static RAM, `.data` + `.bss` (+ `.uninit`), bytes.
pub const GOAL_BOARD_RAM_BYTES: u64 = 8 * 1024;

/// The detector of a scene as the firmware builds it (see `firmware/build.rs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectorSetup {
    /// The scene's sample rate (Hz).
    pub rate_hz: f64,
    /// `DetectorConfig::for_noise(disp_noise_rms_m, rate_hz)?.with_friction(μs, μ)` (the
    /// settings of `host-sim run` too): the rectangular and fixed-base models' detector.
    pub config: DetectorConfig,
    /// The stick-slip model's detector on the slip acceleration:
    /// `PhaseDetectorConfig::for_noise(accel_noise_rms_m_s2)?.with_friction(μs, μ)`.
    pub phase: Option<PhaseDetectorConfig>,
    /// Ring buffer length: `config.min_ring()` (the power of two ≥ 2·fit_half + 2), or the
    /// phase detector's `min_ring()`.
    pub ring: usize,
    /// Displacement full scale (m) in f32: a sample at or beyond it is unusable.
    pub disp_range_m: f32,
    /// The detector's longest back-dating with this ring
    /// (`config.max_age_samples(ring)`): the stick-slip model clamps older events to it.
    pub max_age: usize,
    /// The stick-slip estimator's history (samples): `max_age + 2`.
    pub history: usize,
}

impl DetectorSetup {
    /// The setup for a scene and the rectangular model (the firmware's default).
    pub fn for_scene(scene: &Scene) -> Result<Self> {
        Self::for_scene_model(scene, Model::Rectangular)
    }

    /// The setup for a scene and a model.
    pub fn for_scene_model(scene: &Scene, model: Model) -> Result<Self> {
        let config = DetectorConfig::for_noise(scene.sensors.disp_noise_rms_m, scene.rate_hz)
            .map_err(|e| anyhow!("no reversal detector for the scene: {e:?}"))?
            .with_friction(
                scene.static_friction_coefficient,
                scene.structure.params().friction_coefficient,
            );
        let phase = (model::Detector::kind_for(model) == model::DetectorKind::SlipAcceleration)
            .then(|| {
                PhaseDetectorConfig::for_noise(scene.sensors.accel_noise_rms_m_s2).map(|c| {
                    c.with_friction(
                        scene.static_friction_coefficient,
                        scene.structure.params().friction_coefficient,
                    )
                })
            })
            .transpose()
            .map_err(|e| anyhow!("no phase detector for the scene: {e:?}"))?;
        let (ring, max_age) = match &phase {
            Some(c) => (c.min_ring(), c.max_age_samples()),
            None => (config.min_ring(), config.max_age_samples(config.min_ring())),
        };
        let history = history_for_age(max_age);
        if history > HOST_HISTORY_CAPACITY {
            bail!(
                "the stick-slip history of {history} samples at {} Hz exceeds {HOST_HISTORY_CAPACITY}",
                scene.rate_hz
            );
        }
        Ok(Self {
            rate_hz: scene.rate_hz,
            config,
            phase,
            ring,
            disp_range_m: scene.sensors.disp_range_m as f32,
            max_age,
            history,
        })
    }

    /// Check the firmware's `scene ...` and `detector ...` messages against this setup and
    /// `rate_hz`: rate, ring length, displacement range, and the detector settings in their
    /// `Debug` form (every field, round-trip exact numbers).
    pub fn check_firmware(&self, frames: &[qemu_runner::DecodedFrame], rate_hz: f64) -> Result<()> {
        let m = frames
            .iter()
            .find(|f| f.kind() == "scene")
            .ok_or_else(|| anyhow!("the firmware reported no `scene` message"))?;
        let get = |k: &str| -> Result<&str> {
            m.field(k)
                .ok_or_else(|| anyhow!("no `{k}` in the firmware's `{}`", m.message))
        };
        let checks = [
            ("rate_hz", get("rate_hz")?.parse::<f64>()?, rate_hz),
            ("ring", get("ring")?.parse::<f64>()?, self.ring as f64),
            (
                "disp_range_m",
                f64::from(get("disp_range_m")?.parse::<f32>()?),
                f64::from(self.disp_range_m),
            ),
        ];
        for (name, fw, host) in checks {
            if fw != host {
                bail!("the firmware was built with {name} = {fw}, the host expects {host}");
            }
        }
        let d = frames
            .iter()
            .find(|f| f.kind() == "detector")
            .ok_or_else(|| anyhow!("the firmware reported no `detector` message"))?;
        let want = match &self.phase {
            Some(c) => format!("detector {c:?}"),
            None => format!("detector {:?}", self.config),
        };
        if d.message != want {
            bail!(
                "the firmware's detector differs from the host's: `{}` vs `{want}`",
                d.message
            );
        }
        Ok(())
    }

    /// Check the firmware's `model name=.. history=.. max_age=.. config=..` message: the model,
    /// the stick-slip history and settings ([`stick_slip_config`], `Debug` form).
    pub fn check_model(&self, frames: &[qemu_runner::DecodedFrame], model: Model) -> Result<()> {
        let m = frames
            .iter()
            .find(|f| f.kind() == "model")
            .ok_or_else(|| anyhow!("the firmware reported no `model` message"))?;
        let name = m.field("name").unwrap_or("?");
        if name != model.name() {
            bail!(
                "the firmware was built with the {name} model, the host expects {}",
                model.name()
            );
        }
        for (key, want) in [("history", self.history), ("max_age", self.max_age)] {
            let fw: Option<usize> = m.field(key).and_then(|v| v.parse().ok());
            if fw != Some(want) {
                bail!("the firmware's stick-slip {key} is {fw:?}, the host expects {want}");
            }
        }
        let cfg = m.message.split_once("config=").map(|(_, c)| c.trim());
        let want = format!("{:?}", stick_slip_config(model, self.rate_hz));
        if cfg != Some(want.as_str()) {
            bail!("the firmware's stick-slip settings `{cfg:?}` differ from the host's `{want}`");
        }
        Ok(())
    }
}

/// One sample of the host's run of the firmware pipeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostFrame {
    /// The flags the firmware must stream (bits of `qemu_runner::frame_flags`; no `OVERRUN`).
    pub flags: u8,
    /// The friction event of the sample.
    pub event: Option<FrameEvent>,
    /// The prediction (m/s²).
    pub prediction_m_s2: f32,
}

/// The firmware's estimator of a model (`firmware/src/app/model.rs`), on the host.
#[derive(Debug, Clone)]
pub enum HostEstimator {
    /// `Estimator32`.
    Rectangular(Box<Estimator32>),
    /// `StickSlipEstimator<f32, F32Poly, _>` with the firmware's history; `events` false: the
    /// fixed-base model.
    StickSlip {
        /// The estimator (storage [`HOST_HISTORY_CAPACITY`], history as the firmware's).
        est: Box<StickSlipEstimator<f32, F32Poly, HOST_HISTORY_CAPACITY>>,
        /// Events are pushed (stick-slip) or not (fixed-base).
        events: bool,
        /// Largest age pushed (samples, f32 as in the firmware).
        max_age: f32,
    },
}

/// What the model did with an event (`firmware/src/app/model.rs`, `Pushed`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pushed {
    /// Not used by the model.
    No,
    /// Pushed.
    Yes,
    /// Pushed with its age clamped to the history.
    Clamped,
}

impl HostEstimator {
    /// The firmware's estimator of `model` for the scene.
    pub fn new(scene: &Scene, setup: &DetectorSetup, model: Model) -> Result<Self> {
        Ok(match model {
            Model::Rectangular => HostEstimator::Rectangular(Box::new(
                Estimator32::new(&scene.structure, scene.rate_hz)
                    .map_err(|e| anyhow!("the estimator rejects the scene: {e:?}"))?,
            )),
            Model::StickSlip | Model::FixedBase => HostEstimator::StickSlip {
                est: Box::new(
                    StickSlipEstimator::with_history(
                        &scene.structure,
                        scene.rate_hz,
                        stick_slip_config(model, scene.rate_hz),
                        setup.history,
                    )
                    .map_err(|e| anyhow!("the stick-slip estimator rejects the scene: {e:?}"))?,
                ),
                events: model == Model::StickSlip,
                max_age: setup.max_age as f32,
            },
        })
    }

    /// `model::push`: give a friction event to the estimator.
    pub fn push(&mut self, e: &FrameEvent) -> std::result::Result<Pushed, ssvr_core::Error> {
        match self {
            HostEstimator::Rectangular(est) => {
                if !e.pushes() {
                    return Ok(Pushed::No);
                }
                est.push_reversal(f32::from(e.level), e.age_samples)?;
                Ok(Pushed::Yes)
            }
            HostEstimator::StickSlip { events: false, .. } => Ok(Pushed::No),
            HostEstimator::StickSlip { est, max_age, .. } => {
                let phase = if e.kind == event_kind::STICK {
                    0
                } else {
                    e.level
                };
                if e.age_samples > *max_age {
                    est.push_event(phase, *max_age)?;
                    Ok(Pushed::Clamped)
                } else {
                    est.push_event(phase, e.age_samples)?;
                    Ok(Pushed::Yes)
                }
            }
        }
    }

    /// `model::update`: the prediction of the sample (`top_valid`: the top acceleration may be
    /// used for the friction identification).
    pub fn update(&mut self, s: &LogSample, top_valid: bool) -> f32 {
        match self {
            HostEstimator::Rectangular(est) => est.update(),
            HostEstimator::StickSlip { est, .. } => {
                let top = if top_valid {
                    s.top_accel_m_s2
                } else {
                    f32::NAN
                };
                est.update(s.table_accel_m_s2, top)
            }
        }
    }

    /// The identified μ (stick-slip and fixed-base models).
    pub fn mu_estimate(&self) -> Option<MuEstimate> {
        match self {
            HostEstimator::Rectangular(_) => None,
            HostEstimator::StickSlip { est, .. } => est.mu_estimate(),
        }
    }
}

/// The firmware's detector of a model (`scene::Detector`), on the host.
#[derive(Debug, Clone)]
enum HostDetector<const N: usize> {
    /// On the displacement (rectangular, fixed-base).
    Displacement(ReversalDetector<N>),
    /// On the slip acceleration (stick-slip).
    Acceleration(PhaseDetector<N>),
}

/// The firmware's per-sample step (`firmware/src/app/pipeline.rs`), on the host, with the same
/// ssvr-core code: flags, `ReversalDetector` on the displacement (NaN when unusable), the event
/// to the model's estimator (`model::push`), its update (`model::update`).
#[derive(Debug, Clone)]
pub struct HostPipeline<const N: usize> {
    estimator: HostEstimator,
    detector: HostDetector<N>,
    disp_range_m: f32,
    log_reversals: bool,
    /// Events pushed with a clamped age.
    pub clamped: usize,
}

impl<const N: usize> HostPipeline<N> {
    /// A pipeline at sample 0 with the rectangular model; `log_reversals`: the test hook (events
    /// from the log records).
    pub fn new(scene: &Scene, setup: &DetectorSetup, log_reversals: bool) -> Result<Self> {
        Self::with_model(scene, setup, Model::Rectangular, log_reversals)
    }

    /// A pipeline at sample 0 with the estimator of `model`.
    pub fn with_model(
        scene: &Scene,
        setup: &DetectorSetup,
        model: Model,
        log_reversals: bool,
    ) -> Result<Self> {
        Ok(Self {
            estimator: HostEstimator::new(scene, setup, model)?,
            detector: match setup.phase {
                Some(c) => HostDetector::Acceleration(
                    PhaseDetector::new(c)
                        .map_err(|e| anyhow!("the detector rejects its settings: {e:?}"))?,
                ),
                None => HostDetector::Displacement(
                    ReversalDetector::new(setup.config)
                        .map_err(|e| anyhow!("the detector rejects its settings: {e:?}"))?,
                ),
            },
            disp_range_m: setup.disp_range_m,
            log_reversals,
            clamped: 0,
        })
    }

    /// The estimator.
    pub fn estimator(&self) -> &HostEstimator {
        &self.estimator
    }

    /// One sample.
    pub fn step(&mut self, s: &LogSample) -> HostFrame {
        let ch = [
            s.table_accel_m_s2,
            s.base_accel_m_s2,
            s.top_accel_m_s2,
            s.displacement_m,
        ];
        let mut f = 0u8;
        if s.saturated || s.disp_saturated {
            f |= ff::SATURATED;
        }
        if s.disp_saturated {
            f |= ff::DISP_INVALID;
        }
        if s.missing {
            f |= ff::MISSING;
        }
        if ch.iter().any(|c| !c.is_finite()) {
            f |= ff::NOT_FINITE;
        }
        let disp = s.displacement_m;
        if s.missing || !disp.is_finite() || disp.abs() >= self.disp_range_m {
            f |= ff::DISP_INVALID;
        }
        // `pipeline::detector_input`.
        let detected = match &mut self.detector {
            HostDetector::Displacement(d) => d.process(if f & ff::DISP_INVALID != 0 {
                f32::NAN
            } else {
                disp
            }),
            HostDetector::Acceleration(d) => {
                d.process(if f & (ff::MISSING | ff::NOT_FINITE | ff::SATURATED) != 0 {
                    f32::NAN
                } else {
                    s.base_accel_m_s2 - s.table_accel_m_s2
                })
            }
        };
        let event = if self.log_reversals {
            s.reversal.map(|r| FrameEvent {
                kind: event_kind::LOG,
                level: r.level,
                age_samples: r.age_samples,
            })
        } else {
            detected.map(|e| FrameEvent {
                kind: match e {
                    SlipEvent::SlipStart { .. } => event_kind::SLIP_START,
                    SlipEvent::Reversal { .. } => event_kind::REVERSAL,
                    SlipEvent::Stick { .. } => event_kind::STICK,
                },
                level: e.friction_level() as i8,
                age_samples: e.age_samples(),
            })
        };
        if let Some(e) = &event {
            match self.estimator.push(e) {
                Ok(Pushed::No) => {}
                Ok(p) => {
                    f |= ff::REVERSAL;
                    if p == Pushed::Clamped {
                        self.clamped += 1;
                    }
                }
                Err(_) => f |= ff::REVERSAL_REJECTED,
            }
        }
        let top_valid = f & (ff::SATURATED | ff::MISSING) == 0;
        HostFrame {
            flags: f,
            event,
            prediction_m_s2: self.estimator.update(s, top_valid),
        }
    }
}

/// The host's run of the firmware pipeline over a log.
#[derive(Debug, Clone)]
pub struct HostRun {
    /// One frame per sample.
    pub frames: Vec<HostFrame>,
    /// The identified μ at the end (stick-slip and fixed-base models).
    pub mu: Option<MuEstimate>,
    /// Events pushed with a clamped age.
    pub clamped: usize,
}

/// Run [`HostPipeline`] with `model` over `samples` with the ring length of `setup` (a power of
/// two, 8..=1024).
pub fn host_run(
    scene: &Scene,
    setup: &DetectorSetup,
    model: Model,
    samples: &[LogSample],
    log_reversals: bool,
) -> Result<HostRun> {
    fn run<const N: usize>(
        scene: &Scene,
        setup: &DetectorSetup,
        model: Model,
        samples: &[LogSample],
        log_reversals: bool,
    ) -> Result<HostRun> {
        let mut p = HostPipeline::<N>::with_model(scene, setup, model, log_reversals)?;
        let frames = samples.iter().map(|s| p.step(s)).collect();
        Ok(HostRun {
            frames,
            mu: p.estimator.mu_estimate(),
            clamped: p.clamped,
        })
    }
    match setup.ring {
        8 => run::<8>(scene, setup, model, samples, log_reversals),
        16 => run::<16>(scene, setup, model, samples, log_reversals),
        32 => run::<32>(scene, setup, model, samples, log_reversals),
        64 => run::<64>(scene, setup, model, samples, log_reversals),
        128 => run::<128>(scene, setup, model, samples, log_reversals),
        256 => run::<256>(scene, setup, model, samples, log_reversals),
        512 => run::<512>(scene, setup, model, samples, log_reversals),
        1024 => run::<1024>(scene, setup, model, samples, log_reversals),
        n => bail!("no host detector with a ring of {n} samples"),
    }
}

/// [`host_run`] with the rectangular model (the firmware's default): the frames.
pub fn host_frames(
    scene: &Scene,
    setup: &DetectorSetup,
    samples: &[LogSample],
    log_reversals: bool,
) -> Result<Vec<HostFrame>> {
    Ok(host_run(scene, setup, Model::Rectangular, samples, log_reversals)?.frames)
}

/// The friction train the estimator was given, as the firmware's frames report it, for the
/// closed form: events pushed and accepted (flag `REVERSAL`), at t = (k − age)/rate (f64). Kept
/// sorted by time with levels re-accumulated from the pushed jumps, so that the closed form sums
/// exactly the steps the estimator superposed even if a detection back-dates an event before an
/// earlier-pushed one.
#[derive(Debug, Clone, Default)]
pub struct DetectedTrain {
    /// (time, jump) in time order; jumps at equal times merged.
    steps: Vec<(f64, f64)>,
    /// The train for `DuhamelClosedForm` (levels = running sums of the jumps).
    reversals: Vec<Reversal>,
    /// Level after the last push (push order: what the estimator's `level` is).
    level: f64,
    /// Events pushed whose time is before an earlier-pushed event's time.
    pub out_of_order: usize,
    /// Pushed events that changed the level.
    pub level_changes: usize,
}

impl DetectedTrain {
    /// Add the event of sample `k` (if the frame pushed one).
    pub fn push_frame(&mut self, k: u64, f: &SampleFrame, rate_hz: f64) {
        let Some(e) = f.event.filter(FrameEvent::pushes) else {
            return;
        };
        if f.flags & ff::REVERSAL == 0 {
            return;
        }
        let level = f64::from(e.level);
        let jump = level - self.level;
        self.level = level;
        if jump == 0.0 {
            return;
        }
        self.level_changes += 1;
        let t = (k as f64 - f64::from(e.age_samples)) / rate_hz;
        let i = self.steps.partition_point(|&(ts, _)| ts < t);
        if i < self.steps.len() {
            self.out_of_order += 1;
        }
        match self.steps.get_mut(i) {
            Some(s) if s.0 == t => s.1 += jump,
            _ => self.steps.insert(i, (t, jump)),
        }
        self.reversals.truncate(i);
        let mut acc = self.reversals.last().map_or(0.0, |r| r.level);
        for &(time_s, d) in &self.steps[i..] {
            acc += d;
            self.reversals.push(Reversal { time_s, level: acc });
        }
    }

    /// The train so far.
    pub fn train(&self) -> ReversalTrain<'_> {
        ReversalTrain::Explicit(&self.reversals)
    }
}

/// Wall times of the steps (s).
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Timings {
    /// Truth simulation and sensor model.
    pub simulate_s: f64,
    /// Firmware builds (cargo; near zero when up to date).
    pub build_s: f64,
    /// The QEMU run.
    pub qemu_s: f64,
    /// Decoding and the comparisons (host pipeline, closed form, truth).
    pub compare_s: f64,
}

/// The estimator's steady-state instructions per sample as the pipeline runs it: in blocks
/// (`update_block`) for the stick-slip estimator, the larger of its sliding and stuck samples;
/// per sample for the rectangular recursion.
fn steady_sample_instructions(ic: &qemu_runner::InstructionCounts) -> f64 {
    match (
        ic.instructions_per_sample_in_blocks,
        ic.instructions_per_sample_stuck_in_blocks,
    ) {
        (Some(a), Some(b)) => a.max(b),
        (None, Some(b)) => b,
        (Some(a), None) => a,
        (None, None) => ic.instructions_per_sample,
    }
}

/// The goals and whether they are met.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Goals {
    /// Firmware = host to ≤ 1e-6·gμ on every sample, same events, flags and μ̂, no frame missing.
    pub firmware_equals_host: bool,
    /// ≤ 20 instructions per steady-state estimator sample (the rectangular model's goal).
    pub instructions_per_sample_le_20: bool,
    /// The model's goal of instructions per steady-state sample (rectangular 20, stick-slip and
    /// fixed-base 40).
    pub instructions_per_sample_goal: f64,
    /// `instructions_per_steady_sample` ≤ that goal.
    pub instructions_per_sample_le_goal: bool,
    /// Board image flash ≤ 32 KiB (false when the board image was not built).
    pub board_flash_le_32k: bool,
    /// Board image static RAM ≤ 8 KiB (false when the board image was not built).
    pub board_ram_le_8k: bool,
}

/// What `host-sim qemu` reports (`--json` prints it).
#[derive(Debug, Clone, Serialize)]
pub struct QemuReport {
    /// Scene name.
    pub scene: String,
    /// Scene file (None: the built-in default).
    pub scene_file: Option<PathBuf>,
    /// The estimator model built into the firmware (`fixed-base`, `rectangular`, `stick-slip`).
    pub model: &'static str,
    /// Why this model (chosen from the simulated truth like `host-sim run`, or `--model`).
    pub model_reason: String,
    /// Samples compared (every sample of the scene).
    pub samples: u64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// gμ (m/s²), the unit of the errors.
    pub gmu_m_s2: f64,
    /// Friction events the firmware pushed to its estimator that changed the friction level (a
    /// stick, pushed as level 0 by the stick-slip model, counts): the detected train.
    pub reversals: usize,
    /// Slip starts the firmware's detector reported.
    pub slip_starts: usize,
    /// Direction reversals the firmware's detector reported.
    pub detected_reversals: usize,
    /// Sticks the firmware's detector reported (pushed by the stick-slip model only).
    pub sticks: usize,
    /// Level changes of the exact truth's friction (breakaways, reversals, sticks).
    pub truth_friction_changes: usize,
    /// Frames with a flag other than `REVERSAL` (invalid channel, saturation, overrun, rejected).
    pub frames_flagged: usize,
    /// Events pushed with a time before an earlier-pushed event's.
    pub events_out_of_order: usize,
    /// Stick-slip model: events pushed with their age clamped to the history (older than the
    /// detector's usual longest back-dating).
    pub events_clamped: usize,
    /// Frames whose flags, event or echoed channels differ from the host's.
    pub frame_mismatches: usize,
    /// max |firmware − host| prediction over all samples (gμ).
    pub max_err_vs_host_gmu: f64,
    /// The full-precision reference of `max_err_vs_reference_gmu`.
    pub reference: &'static str,
    /// max |firmware − reference| (gμ): the closed form (f64) on the detected train (rectangular
    /// model), or the stick-slip estimator in f64 on the detected events (stick-slip,
    /// fixed-base).
    pub max_err_vs_reference_gmu: f64,
    /// Time of that maximum (s).
    pub max_err_vs_reference_at_s: f64,
    /// max |firmware − exact truth ü1| (gμ): detection latency and stick phases included.
    pub max_err_vs_truth_gmu: f64,
    /// RMS of the same (gμ).
    pub rms_err_vs_truth_gmu: f64,
    /// The friction coefficient the firmware identified (stick-slip and fixed-base models; null
    /// for the rectangular model or without sliding samples).
    pub mu_estimate: Option<f64>,
    /// Its standard deviation.
    pub mu_std: Option<f64>,
    /// Identification updates it used (one per block of `identify_every` = 32 final sliding
    /// samples).
    pub mu_samples: Option<u32>,
    /// The firmware's μ̂ equals the host's (bit for bit; true when neither has one).
    pub mu_equals_host: bool,
    /// The stick-slip estimator's history (samples; stick-slip and fixed-base models).
    pub history: Option<usize>,
    /// Instructions of a steady-state update of the model's estimator and storing its output
    /// (SysTick under `-icount shift=0`): rectangular `Estimator32::update()` while sliding;
    /// stick-slip `update(table, top)` while sliding, μ identified; fixed-base: stuck.
    pub instructions_per_sample: f64,
    /// Extra instructions of a sample with an event of age 0.5 (`push_reversal` or `push_event`
    /// + update); null for the fixed-base model (no event pushed).
    pub instructions_per_reversal: Option<f64>,
    /// Stick-slip and fixed-base models: instructions of a steady-state stuck update.
    pub instructions_per_sample_stuck: Option<f64>,
    /// The estimator's steady-state cost as the firmware's pipeline runs it, which the goal is
    /// checked on: rectangular `instructions_per_sample`; stick-slip the larger of the sliding
    /// and the stuck sample in blocks; fixed-base the stuck sample in blocks.
    pub instructions_per_steady_sample: f64,
    /// Stick-slip and fixed-base models: the block size of the firmware's estimator
    /// (`update_block`: the pipeline runs the estimator on batches of this many samples).
    pub block_size: Option<u32>,
    /// Stick-slip model: instructions per steady-state sliding sample (μ identified) in blocks
    /// of `block_size` (as the pipeline runs it).
    pub instructions_per_sample_in_blocks: Option<f64>,
    /// Stick-slip and fixed-base models: instructions per steady-state stuck sample in blocks.
    pub instructions_per_sample_stuck_in_blocks: Option<f64>,
    /// Stick-slip model: instructions of a steady-state sliding update without the μ
    /// identification (the prediction alone; the firmware identifies on every block of samples).
    pub instructions_per_sample_without_identification: Option<f64>,
    /// Stick-slip model: extra instructions of a sample with an event `max_event_age` samples old
    /// (the whole history re-simulated).
    pub instructions_per_event_max_age: Option<f64>,
    /// The age of those events (samples).
    pub max_event_age: Option<f64>,
    /// Instructions of the reversal detector per steady sliding sample.
    pub detector_instructions_per_sample: Option<f64>,
    /// Extra instructions of the detector at a detected reversal.
    pub detector_instructions_per_reversal: Option<f64>,
    /// Extra instructions of the detector for a stick and the slip start that ends it (their
    /// kink fits; on the board the sample interrupt that detects a stick runs this long).
    pub detector_instructions_per_stick: Option<f64>,
    /// Instructions per sample of the firmware's whole step in batches of 16 (flags, detector,
    /// estimator, frames; no I/O), steady sliding state.
    pub pipeline_instructions_per_sample: Option<f64>,
    /// Executed instructions per SysTick tick (calibrated; 40 on mps2-an386 at `shift=0`).
    pub instructions_per_tick: f64,
    /// Flash of the QEMU image (bytes).
    pub flash_bytes: u64,
    /// Static RAM of the QEMU image: `.data` + `.bss` (+ `.uninit`), bytes.
    pub ram_bytes: u64,
    /// Stack high-water mark of the QEMU run (bytes).
    pub stack_bytes: Option<u64>,
    /// Flash of the board image built for the scene and model (bytes).
    pub board_flash_bytes: Option<u64>,
    /// Static RAM of the board image (bytes).
    pub board_ram_bytes: Option<u64>,
    /// Why the board image has no sizes (it could not be built for the scene).
    pub board_error: Option<String>,
    /// The goals.
    pub goals: Goals,
    /// firmware = host (the exit status).
    pub passed: bool,
    /// Wall times.
    pub timing: Timings,
}

/// Removes a directory when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new() -> Result<Self> {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0);
        let p = std::env::temp_dir().join(format!("host-sim-qemu-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&p).with_context(|| format!("cannot create {}", p.display()))?;
        Ok(Self(p))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A scene's sensor log and what the host knows of its truth.
#[derive(Debug, Clone)]
pub struct SceneLog {
    /// One record per sample.
    pub samples: Vec<LogSample>,
    /// The truth's ü1 per sample (m/s²).
    pub truth_top: Vec<f64>,
    /// The truth's friction changes.
    pub truth_changes: usize,
    /// The model [`model::choose`] picks from the truth, and why.
    pub model: (Model, String),
}

/// The sensor log of a scene: truth, sensor model, one record per sample; with the truth's ü1
/// per sample, its number of friction changes and the model it calls for.
pub fn scene_log(scene: &Scene) -> Result<SceneLog> {
    let table = scene.table_motion();
    let input = TruthInput::new(&scene.structure, &table, scene.duration_s)
        .with_static_friction(scene.static_friction_coefficient);
    let truth = truth::simulate(&input).map_err(|e| anyhow!("truth simulation: {e}"))?;
    let measured = sensors::measure_all(&scene.sensors, &truth, scene.rate_hz, scene.samples);
    if measured.len() as u64 != scene.samples {
        bail!(
            "the truth covers {} of the scene's {} samples",
            measured.len(),
            scene.samples
        );
    }
    let samples = measured
        .iter()
        .map(|(_, f)| LogSample {
            table_accel_m_s2: f.table_accel_m_s2,
            base_accel_m_s2: f.base_accel_m_s2,
            top_accel_m_s2: f.top_accel_m_s2,
            displacement_m: f.disp_m,
            saturated: f.flags & FLAG_ACCEL_SATURATED != 0,
            missing: false,
            disp_saturated: f.flags & FLAG_DISP_SATURATED != 0,
            reversal: None,
        })
        .collect();
    let truth_top = measured.iter().map(|(t, _)| t.top_accel_m_s2).collect();
    Ok(SceneLog {
        samples,
        truth_top,
        truth_changes: truth.friction_train().len(),
        model: model::choose(&truth, scene.duration_s),
    })
}

fn same_bits(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Run the whole comparison for a scene with the model [`model::choose`] picks (see the module
/// docs).
pub fn run_scene(scene: &Scene, firmware_dir: &Path) -> Result<QemuReport> {
    run_scene_model(scene, firmware_dir, None)
}

/// The firmware's `mu estimate=.. std=.. samples=..` message: (μ̂, std, samples).
pub fn firmware_mu(frames: &[qemu_runner::DecodedFrame]) -> Option<(f64, f64, u32)> {
    let m = frames
        .iter()
        .find(|f| f.kind() == "mu" && f.field("estimate").is_some())?;
    Some((
        m.field("estimate")?.parse().ok()?,
        m.field("std")?.parse().ok()?,
        m.field("samples")?.parse().ok()?,
    ))
}

/// Run the whole comparison for a scene with `model` (None: the one [`model::choose`] picks from
/// the simulated truth, as `host-sim run` does).
pub fn run_scene_model(
    scene: &Scene,
    firmware_dir: &Path,
    model: Option<Model>,
) -> Result<QemuReport> {
    qemu_runner::require_qemu()?;
    let mut timing = Timings::default();
    let gmu = scene.gmu();
    let rate = scene.rate_hz;
    let t0 = Instant::now();
    let SceneLog {
        samples,
        truth_top,
        truth_changes,
        model: chosen,
    } = scene_log(scene)?;
    let (model, model_reason) = match model {
        Some(m) => (m, "chosen with --model".to_string()),
        None => chosen,
    };
    let setup = DetectorSetup::for_scene_model(scene, model)?;
    timing.simulate_s = t0.elapsed().as_secs_f64();

    let dir = TempDir::new()?;
    let log = dir.0.join("scene.ssvrlog");
    qemu_runner::write_sensor_log(&log, &LogHeader::for_scene(scene), &samples)?;
    let images = qemu_runner::build_for_scene_model(firmware_dir, scene, model, &dir.0, true)?;
    timing.build_s = images.build_s;
    let elf = &images.qemu_elf;

    let t0 = Instant::now();
    let timeout = Duration::from_secs(120) + Duration::from_micros(500) * samples.len() as u32;
    let bytes = qemu_runner::run_qemu(elf, &log, timeout)?;
    timing.qemu_s = t0.elapsed().as_secs_f64();

    let t0 = Instant::now();
    let frames = qemu_runner::decode_frames(elf, &bytes)?;
    setup.check_firmware(&frames, rate)?;
    setup.check_model(&frames, model)?;
    let fw = qemu_runner::sample_frames(&frames);
    if fw.len() != samples.len() {
        bail!(
            "the firmware streamed {} sample frames for {} samples",
            fw.len(),
            samples.len()
        );
    }
    if let Some((k, f)) = fw.iter().enumerate().find(|(k, f)| f.index as usize != *k) {
        bail!("frame {k} has index {}", f.index);
    }

    // (a) The same core code on the host, same f32 inputs.
    let host = host_run(scene, &setup, model, &samples, false)?;
    let mut max_host = 0.0f64;
    let mut mismatches = 0usize;
    for ((f, h), s) in fw.iter().zip(&host.frames).zip(&samples) {
        let d = (f64::from(f.prediction_m_s2) - f64::from(h.prediction_m_s2)).abs() / gmu;
        max_host = if d.is_nan() {
            f64::INFINITY
        } else {
            max_host.max(d)
        };
        let echoed = same_bits(f.table_accel_m_s2, s.table_accel_m_s2)
            && same_bits(f.base_accel_m_s2, s.base_accel_m_s2)
            && same_bits(f.top_accel_m_s2, s.top_accel_m_s2)
            && same_bits(f.displacement_m, s.displacement_m);
        let event_same = match (f.event, h.event) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                a.kind == b.kind
                    && a.level == b.level
                    && a.age_samples.to_bits() == b.age_samples.to_bits()
            }
            _ => false,
        };
        if !(echoed && event_same && f.flags & !ff::OVERRUN == h.flags) {
            mismatches += 1;
        }
    }
    let fw_mu = firmware_mu(&frames);
    let host_mu = host.mu.map(|m| (m.mu, m.std, m.blocks));
    let mu_equal = fw_mu == host_mu;

    // (b) The full-precision reference on the detected events; (c) the truth.
    let (mut max_ref, mut max_ref_at) = (0.0f64, 0.0f64);
    let (mut max_truth, mut sq_truth) = (0.0f64, 0.0f64);
    let (mut slip_starts, mut detected_reversals, mut sticks, mut flagged) = (0, 0, 0, 0);
    let mut reference = Reference::new(scene, &setup, model)?;
    for (k, ((f, top), s)) in fw.iter().zip(&truth_top).zip(&samples).enumerate() {
        match f.event.map(|e| e.kind) {
            Some(event_kind::SLIP_START) => slip_starts += 1,
            Some(event_kind::REVERSAL) => detected_reversals += 1,
            Some(event_kind::STICK) => sticks += 1,
            _ => {}
        }
        if f.flags & !ff::REVERSAL != 0 {
            flagged += 1;
        }
        let t = k as f64 / rate;
        let pred = f64::from(f.prediction_m_s2);
        let r = reference.step(k as u64, f, s, rate)?;
        let e = (pred - r).abs() / gmu;
        if e > max_ref || e.is_nan() {
            max_ref = if e.is_nan() { f64::INFINITY } else { e };
            max_ref_at = t;
        }
        let et = (pred - top).abs() / gmu;
        max_truth = max_truth.max(et);
        sq_truth += et * et;
    }
    timing.compare_s = t0.elapsed().as_secs_f64();

    let ic = qemu_runner::instruction_counts(&frames)
        .ok_or_else(|| anyhow!("the firmware reported no instruction counts"))?;
    let (flash, ram) = qemu_runner::elf_sizes(elf)?;
    let (board, board_error) = match &images.board_elf {
        Ok(b) => (Some(qemu_runner::elf_sizes(b)?), None),
        Err(e) => (None, Some(e.clone())),
    };
    let stack_bytes = frames
        .iter()
        .find(|f| f.kind() == "stack")
        .and_then(|f| f.field("used_bytes"))
        .and_then(|v| v.parse().ok());

    let equal = max_host <= HOST_TOLERANCE_GMU && mismatches == 0 && mu_equal;
    let goal = instructions_goal(model);
    let steady = steady_sample_instructions(&ic);
    let goals = Goals {
        firmware_equals_host: equal,
        instructions_per_sample_le_20: ic.instructions_per_sample <= GOAL_INSTRUCTIONS_PER_SAMPLE,
        instructions_per_sample_goal: goal,
        instructions_per_sample_le_goal: steady <= goal,
        board_flash_le_32k: board.is_some_and(|b| b.0 <= GOAL_BOARD_FLASH_BYTES),
        board_ram_le_8k: board.is_some_and(|b| b.1 <= GOAL_BOARD_RAM_BYTES),
    };
    let stick_slip = model != Model::Rectangular;
    Ok(QemuReport {
        scene: scene.name.clone(),
        scene_file: scene.source.clone(),
        model: model.name(),
        model_reason,
        samples: samples.len() as u64,
        rate_hz: rate,
        gmu_m_s2: gmu,
        reversals: reference.level_changes_and_order().0,
        slip_starts,
        detected_reversals,
        sticks,
        truth_friction_changes: truth_changes,
        frames_flagged: flagged,
        events_out_of_order: reference.level_changes_and_order().1,
        events_clamped: host.clamped,
        frame_mismatches: mismatches,
        max_err_vs_host_gmu: max_host,
        reference: reference.name(),
        max_err_vs_reference_gmu: max_ref,
        max_err_vs_reference_at_s: max_ref_at,
        max_err_vs_truth_gmu: max_truth,
        rms_err_vs_truth_gmu: (sq_truth / samples.len().max(1) as f64).sqrt(),
        mu_estimate: fw_mu.map(|m| m.0),
        mu_std: fw_mu.map(|m| m.1),
        mu_samples: fw_mu.map(|m| m.2),
        mu_equals_host: mu_equal,
        history: stick_slip.then_some(setup.history),
        instructions_per_sample: ic.instructions_per_sample,
        instructions_per_reversal: ic.instructions_per_reversal,
        instructions_per_sample_stuck: ic.instructions_per_sample_stuck,
        instructions_per_steady_sample: steady,
        block_size: ic.block_size,
        instructions_per_sample_in_blocks: ic.instructions_per_sample_in_blocks,
        instructions_per_sample_stuck_in_blocks: ic.instructions_per_sample_stuck_in_blocks,
        instructions_per_sample_without_identification: ic
            .instructions_per_sample_without_identification,
        instructions_per_event_max_age: ic.instructions_per_event_max_age,
        max_event_age: ic.max_event_age,
        detector_instructions_per_sample: ic.detector_instructions_per_sample,
        detector_instructions_per_reversal: ic.detector_instructions_per_reversal,
        detector_instructions_per_stick: ic.detector_instructions_per_stick,
        pipeline_instructions_per_sample: ic.pipeline_instructions_per_sample,
        instructions_per_tick: ic.instructions_per_tick,
        flash_bytes: flash,
        ram_bytes: ram,
        stack_bytes,
        board_flash_bytes: board.map(|b| b.0),
        board_ram_bytes: board.map(|b| b.1),
        board_error,
        goals,
        passed: equal,
        timing,
    })
}

/// The full-precision reference of a model, fed the firmware's frames one by one.
enum Reference {
    /// The closed form on the detected train (rectangular model).
    ClosedForm {
        cf: DuhamelClosedForm,
        train: Box<DetectedTrain>,
    },
    /// The stick-slip estimator in f64 on the detected events (stick-slip, fixed-base).
    StickSlip {
        est: Box<StickSlipEstimator<f64, Libm, HOST_HISTORY_CAPACITY>>,
        max_age: f32,
        /// Last pushed phase, latest pushed event time.
        last: (i8, f64),
        level_changes: usize,
        out_of_order: usize,
    },
}

impl Reference {
    fn new(scene: &Scene, setup: &DetectorSetup, model: Model) -> Result<Self> {
        Ok(match model {
            Model::Rectangular => Reference::ClosedForm {
                cf: DuhamelClosedForm::new(&scene.structure),
                train: Box::default(),
            },
            Model::StickSlip | Model::FixedBase => Reference::StickSlip {
                est: Box::new(
                    StickSlipEstimator::with_history(
                        &scene.structure,
                        scene.rate_hz,
                        stick_slip_config(model, scene.rate_hz),
                        setup.history,
                    )
                    .map_err(|e| {
                        anyhow!("the f64 stick-slip estimator rejects the scene: {e:?}")
                    })?,
                ),
                max_age: setup.max_age as f32,
                last: (0, f64::NEG_INFINITY),
                level_changes: 0,
                out_of_order: 0,
            },
        })
    }

    fn name(&self) -> &'static str {
        match self {
            Reference::ClosedForm { .. } => "closed form (f64) on the detected train",
            Reference::StickSlip { .. } => {
                "stick-slip estimator in f64 (libm) on the detected events and measured inputs"
            }
        }
    }

    /// The reference's ü1 at sample k of frame `f` (log sample `s`).
    fn step(&mut self, k: u64, f: &SampleFrame, s: &LogSample, rate: f64) -> Result<f64> {
        match self {
            Reference::ClosedForm { cf, train } => {
                train.push_frame(k, f, rate);
                let t = k as f64 / rate;
                Ok(cf.evaluate(&train.train(), t, usize::MAX).accel_m_s2)
            }
            Reference::StickSlip {
                est,
                max_age,
                last,
                level_changes,
                out_of_order,
            } => {
                if let Some(e) = f.event.filter(|_| f.flags & ff::REVERSAL != 0) {
                    let phase = if e.kind == event_kind::STICK {
                        0
                    } else {
                        e.level
                    };
                    let age = e.age_samples.min(*max_age);
                    est.push_event(phase, f64::from(age)).map_err(|err| {
                        anyhow!("the f64 reference rejects the event of sample {k}: {err:?}")
                    })?;
                    let t = (k as f64 - f64::from(age)) / rate;
                    if t < last.1 {
                        *out_of_order += 1;
                    }
                    if phase != last.0 {
                        *level_changes += 1;
                    }
                    *last = (phase, last.1.max(t));
                }
                let top_valid = f.flags & (ff::SATURATED | ff::MISSING) == 0;
                let top = if top_valid {
                    f64::from(s.top_accel_m_s2)
                } else {
                    f64::NAN
                };
                Ok(est.update(f64::from(s.table_accel_m_s2), top))
            }
        }
    }

    fn level_changes_and_order(&self) -> (usize, usize) {
        match self {
            Reference::ClosedForm { train, .. } => (train.level_changes, train.out_of_order),
            Reference::StickSlip {
                level_changes,
                out_of_order,
                ..
            } => (*level_changes, *out_of_order),
        }
    }
}

fn ok(b: bool) -> &'static str {
    if b {
        "ok"
    } else {
        "NOT MET"
    }
}

fn opt(v: Option<f64>, prec: usize) -> String {
    v.map_or_else(|| "-".to_string(), |x| format!("{x:.prec$}"))
}

/// The human-readable report.
pub fn print_report(r: &QemuReport, out: &mut impl Write) -> std::io::Result<()> {
    let g = &r.goals;
    let file = r.scene_file.as_ref().map_or_else(
        || "built-in default".to_string(),
        |p| p.display().to_string(),
    );
    writeln!(
        out,
        "host-sim qemu: scene \"{}\" ({file}), {} samples at {} Hz, gμ = {} m/s²",
        r.scene, r.samples, r.rate_hz, r.gmu_m_s2
    )?;
    let history = r
        .history
        .map_or_else(String::new, |h| format!(", history {h} samples"));
    writeln!(out, "  model: {} ({}){history}", r.model, r.model_reason)?;
    writeln!(
        out,
        "  detector: {} slip starts, {} reversals, {} sticks -> {} level changes pushed (truth: {} friction changes); {} frames flagged, {} events clamped",
        r.slip_starts,
        r.detected_reversals,
        r.sticks,
        r.reversals,
        r.truth_friction_changes,
        r.frames_flagged,
        r.events_clamped
    )?;
    writeln!(
        out,
        "  firmware vs host (same f32 detector + {} estimator): max |diff| = {:.3e} gμ, {} frames differ, mu {} [goal <= {:e} gμ: {}]",
        r.model,
        r.max_err_vs_host_gmu,
        r.frame_mismatches,
        if r.mu_equals_host { "equal" } else { "DIFFERS" },
        HOST_TOLERANCE_GMU,
        ok(g.firmware_equals_host)
    )?;
    writeln!(
        out,
        "  firmware vs {}: max |error| = {:.3e} gμ at t = {:.4} s",
        r.reference, r.max_err_vs_reference_gmu, r.max_err_vs_reference_at_s
    )?;
    writeln!(
        out,
        "  firmware vs exact truth: max |error| = {:.3} gμ, rms {:.3} gμ ({})",
        r.max_err_vs_truth_gmu,
        r.rms_err_vs_truth_gmu,
        match r.model {
            "rectangular" => "detection latency, stick phases",
            "fixed-base" => "the fixed-base model ignores any sliding",
            _ => "detection latency",
        }
    )?;
    if let (Some(mu), Some(sd), Some(n)) = (r.mu_estimate, r.mu_std, r.mu_samples) {
        writeln!(
            out,
            "  identified friction coefficient (firmware): mu = {mu:.5} ± {sd:.5} ({n} identification updates, one per block of sliding samples)"
        )?;
    }
    writeln!(
        out,
        "  instructions (QEMU Cortex-M4F, SysTick, -icount shift=0): estimator {:.2}/sample [goal <= {}: {}]{}, +{}/event (age 0.5){}; detector {}/sample, +{}/reversal, +{}/stick and slip start; whole step {}/sample",
        r.instructions_per_steady_sample,
        g.instructions_per_sample_goal,
        ok(g.instructions_per_sample_le_goal),
        match (
            r.block_size,
            r.instructions_per_sample_in_blocks,
            r.instructions_per_sample_stuck_in_blocks,
        ) {
            (Some(n), Some(a), Some(b)) => format!(
                " (blocks of {n}: {a:.2} sliding, {b:.2} stuck; one update() at a time: {:.2} sliding, {} stuck, {} sliding without the mu identification)",
                r.instructions_per_sample,
                opt(r.instructions_per_sample_stuck, 2),
                opt(r.instructions_per_sample_without_identification, 2)
            ),
            (Some(n), None, Some(_)) => format!(
                " (stuck, blocks of {n}; one update() at a time: {:.2})",
                r.instructions_per_sample
            ),
            _ => String::new(),
        },
        opt(r.instructions_per_reversal, 1),
        match (r.instructions_per_event_max_age, r.max_event_age) {
            (Some(i), Some(a)) => format!(", +{i:.0}/event (age {a})"),
            _ => String::new(),
        },
        opt(r.detector_instructions_per_sample, 1),
        opt(r.detector_instructions_per_reversal, 0),
        opt(r.detector_instructions_per_stick, 0),
        opt(r.pipeline_instructions_per_sample, 1)
    )?;
    let board = match (r.board_flash_bytes, r.board_ram_bytes) {
        (Some(f), Some(m)) => format!(
            "ssvr-board flash {f} B [<= 32 KiB: {}], static RAM {m} B [<= 8 KiB: {}]",
            ok(g.board_flash_le_32k),
            ok(g.board_ram_le_8k)
        ),
        _ => format!(
            "ssvr-board not built: {}",
            r.board_error.as_deref().unwrap_or("?")
        ),
    };
    writeln!(
        out,
        "  sizes ({} model): ssvr-qemu flash {} B, static RAM {} B, stack {} B; {board}",
        r.model,
        r.flash_bytes,
        r.ram_bytes,
        r.stack_bytes.map_or_else(|| "-".into(), |s| s.to_string())
    )?;
    writeln!(
        out,
        "  time: simulate {:.1} s, build {:.1} s, qemu {:.1} s, compare {:.1} s",
        r.timing.simulate_s, r.timing.build_s, r.timing.qemu_s, r.timing.compare_s
    )?;
    writeln!(
        out,
        "  result: {}",
        if r.passed {
            "firmware = host on every sample"
        } else {
            "FIRMWARE DIFFERS FROM THE HOST"
        }
    )
}

/// `host-sim qemu [SCENE] [--model MODEL] [--json]`: load the scene (None or `default`: the
/// built-in default), run [`run_scene_model`] with `firmware/` next to host-sim, print the
/// report, and fail when the firmware differs from the host.
pub fn command(scene: Option<&Path>, json: bool, model: Option<Model>) -> Result<()> {
    let scene = match scene {
        None => Scene::default_scene(),
        Some(p) if p == Path::new("default") && !p.exists() => Scene::default_scene(),
        Some(p) => Scene::load(p)?,
    };
    let report = run_scene_model(&scene, &qemu_runner::default_firmware_dir(), model)?;
    let mut out = std::io::stdout().lock();
    if json {
        let s = serde_json::to_string_pretty(&report).context("serialising the report")?;
        writeln!(out, "{s}").context("writing the report")?;
    } else {
        print_report(&report, &mut out).context("writing the report")?;
    }
    out.flush().context("writing the report")?;
    if !report.passed {
        bail!(
            "the firmware differs from the host: max |diff| = {:e} gμ (tolerance {:e}), {} frames with other flags/events, mu {}",
            report.max_err_vs_host_gmu,
            HOST_TOLERANCE_GMU,
            report.frame_mismatches,
            if report.mu_equals_host { "equal" } else { "differs" }
        );
    }
    Ok(())
}

/// Cortex-M4F instruction counts of a model's estimator, measured once: the QEMU image built
/// for the built-in default scene and `model`, run on the first 0.1 s of its sensor log (the
/// benchmark blocks do not depend on the log). Errors: QEMU missing, build or run failure.
pub fn measure_instruction_counts(model: Model) -> Result<qemu_runner::InstructionCounts> {
    qemu_runner::require_qemu()?;
    let mut scene = Scene::default_scene();
    scene.duration_s = 0.1;
    scene.samples = (scene.duration_s * scene.rate_hz).round() as u64;
    let log_data = scene_log(&scene)?;
    let dir = TempDir::new()?;
    let log = dir.0.join("bench.ssvrlog");
    qemu_runner::write_sensor_log(&log, &LogHeader::for_scene(&scene), &log_data.samples)?;
    let images = qemu_runner::build_for_scene_model(
        &qemu_runner::default_firmware_dir(),
        &scene,
        model,
        &dir.0,
        false,
    )?;
    let bytes = qemu_runner::run_qemu(&images.qemu_elf, &log, Duration::from_secs(120))?;
    let frames = qemu_runner::decode_frames(&images.qemu_elf, &bytes)?;
    qemu_runner::instruction_counts(&frames)
        .ok_or_else(|| anyhow!("the firmware reported no instruction counts"))
}
