//! `host-sim qemu [SCENE] [--json]`: run the firmware's QEMU image on a scene and check every
//! prediction it makes.
//!
//! 1. Simulate the exact stick-slip truth of the scene ([`crate::truth`]) and measure it with the
//!    seeded sensor model ([`crate::sensors`]); write the sensor log
//!    ([`qemu_runner::write_sensor_log`]).
//! 2. Build the QEMU image (and the board image, for its sizes) for the scene
//!    ([`qemu_runner::build_for_scene`]: `SSVR_SCENE`, cargo rebuilds only when the scene's
//!    firmware parameters change).
//! 3. Run it under `qemu-system-arm -icount shift=0` and decode its defmt stream.
//! 4. Compare every sample's prediction
//!    * with the same core code on the host on the same f32 inputs ([`HostPipeline`]: the
//!      firmware's per-sample step, i.e. `ReversalDetector` + `Estimator32`): must be equal to
//!      ≤ 1e-6·gμ (it is bit-identical in practice), as must the detected events;
//!    * with the full-precision closed form (`DuhamelClosedForm`, f64) on the train of events
//!      the firmware detected, event times t = (k − age)/rate in f64; at sample k the train holds
//!      the events detected up to k (what the estimator knew then);
//!    * with the exact truth (information: detection latency and the rectangular model's
//!      stick phases show there).
//! 5. Report instruction counts (SysTick under `-icount`), flash and static RAM of both images.
//!
//! The command fails (non-zero exit) when the firmware and the host differ by more than
//! [`HOST_TOLERANCE_GMU`], when their events or flags differ, or when frames are missing.

use crate::qemu_runner::{
    self, event_kind, frame_flags as ff, FrameEvent, LogHeader, LogSample, SampleFrame,
};
use crate::scene::Scene;
use crate::sensors::{self, FLAG_ACCEL_SATURATED, FLAG_DISP_SATURATED};
use crate::truth::{self, TruthInput};
use anyhow::{anyhow, bail, Context, Result};
use serde::Serialize;
use ssvr_core::duhamel_closed_form::{DuhamelClosedForm, Reversal, ReversalTrain};
use ssvr_core::duhamel_recursion::Estimator32;
use ssvr_core::reversal_detector::{DetectorConfig, ReversalDetector, SlipEvent};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Largest accepted |firmware − host| prediction difference, in gμ.
pub const HOST_TOLERANCE_GMU: f64 = 1e-6;
/// Goal: instructions of a steady-state estimator sample on the M4F.
pub const GOAL_INSTRUCTIONS_PER_SAMPLE: f64 = 20.0;
/// Goal: board image flash (bytes).
pub const GOAL_BOARD_FLASH_BYTES: u64 = 32 * 1024;
/// Goal: board image static RAM, `.data` + `.bss` (+ `.uninit`), bytes.
pub const GOAL_BOARD_RAM_BYTES: u64 = 8 * 1024;

/// The detector of a scene as the firmware builds it (see `firmware/build.rs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectorSetup {
    /// `DetectorConfig::for_noise(disp_noise_rms_m, rate_hz)?.with_friction(μs, μ)` (the
    /// settings of `host-sim run` too).
    pub config: DetectorConfig,
    /// Ring buffer length: the power of two ≥ 2·fit_half + 2.
    pub ring: usize,
    /// Displacement full scale (m) in f32: a sample at or beyond it is unusable.
    pub disp_range_m: f32,
}

impl DetectorSetup {
    /// The setup for a scene.
    pub fn for_scene(scene: &Scene) -> Result<Self> {
        let config = DetectorConfig::for_noise(scene.sensors.disp_noise_rms_m, scene.rate_hz)
            .map_err(|e| anyhow!("no reversal detector for the scene: {e:?}"))?
            .with_friction(
                scene.static_friction_coefficient,
                scene.structure.params().friction_coefficient,
            );
        Ok(Self {
            config,
            ring: (2 * config.fit_half + 2).next_power_of_two(),
            disp_range_m: scene.sensors.disp_range_m as f32,
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
        let want = format!("detector {:?}", self.config);
        if d.message != want {
            bail!(
                "the firmware's detector differs from the host's: `{}` vs `{want}`",
                d.message
            );
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

/// The firmware's per-sample step (`firmware/src/app/pipeline.rs`), on the host, with the same
/// ssvr-core code: flags, `ReversalDetector` on the displacement (NaN when unusable),
/// `push_reversal(level, age)` for slip starts and reversals, `update()`.
#[derive(Debug, Clone)]
pub struct HostPipeline<const N: usize> {
    estimator: Estimator32,
    detector: ReversalDetector<N>,
    disp_range_m: f32,
    log_reversals: bool,
}

impl<const N: usize> HostPipeline<N> {
    /// A pipeline at sample 0; `log_reversals`: the test hook (events from the log records).
    pub fn new(scene: &Scene, setup: &DetectorSetup, log_reversals: bool) -> Result<Self> {
        Ok(Self {
            estimator: Estimator32::new(&scene.structure, scene.rate_hz)
                .map_err(|e| anyhow!("the estimator rejects the scene: {e:?}"))?,
            detector: ReversalDetector::new(setup.config)
                .map_err(|e| anyhow!("the detector rejects its settings: {e:?}"))?,
            disp_range_m: setup.disp_range_m,
            log_reversals,
        })
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
        let detected = self.detector.process(if f & ff::DISP_INVALID != 0 {
            f32::NAN
        } else {
            disp
        });
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
        if let Some(e) = event.filter(FrameEvent::pushes) {
            match self
                .estimator
                .push_reversal(f32::from(e.level), e.age_samples)
            {
                Ok(()) => f |= ff::REVERSAL,
                Err(_) => f |= ff::REVERSAL_REJECTED,
            }
        }
        HostFrame {
            flags: f,
            event,
            prediction_m_s2: self.estimator.update(),
        }
    }
}

/// Run [`HostPipeline`] over `samples` with the ring length of `setup` (a power of two, 8..=256).
pub fn host_frames(
    scene: &Scene,
    setup: &DetectorSetup,
    samples: &[LogSample],
    log_reversals: bool,
) -> Result<Vec<HostFrame>> {
    fn run<const N: usize>(
        scene: &Scene,
        setup: &DetectorSetup,
        samples: &[LogSample],
        log_reversals: bool,
    ) -> Result<Vec<HostFrame>> {
        let mut p = HostPipeline::<N>::new(scene, setup, log_reversals)?;
        Ok(samples.iter().map(|s| p.step(s)).collect())
    }
    match setup.ring {
        8 => run::<8>(scene, setup, samples, log_reversals),
        16 => run::<16>(scene, setup, samples, log_reversals),
        32 => run::<32>(scene, setup, samples, log_reversals),
        64 => run::<64>(scene, setup, samples, log_reversals),
        128 => run::<128>(scene, setup, samples, log_reversals),
        256 => run::<256>(scene, setup, samples, log_reversals),
        n => bail!("no host detector with a ring of {n} samples"),
    }
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

/// The goals and whether they are met.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Goals {
    /// Firmware = host to ≤ 1e-6·gμ on every sample, same events and flags, no frame missing.
    pub firmware_equals_host: bool,
    /// ≤ 20 instructions per steady-state estimator sample.
    pub instructions_per_sample_le_20: bool,
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
    /// Samples compared (every sample of the scene).
    pub samples: u64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// gμ (m/s²), the unit of the errors.
    pub gmu_m_s2: f64,
    /// Friction events the firmware pushed to its estimator that changed the level (slip starts
    /// and reversals): the detected reversal train.
    pub reversals: usize,
    /// Slip starts the firmware's detector reported.
    pub slip_starts: usize,
    /// Direction reversals the firmware's detector reported.
    pub detected_reversals: usize,
    /// Sticks the firmware's detector reported (not pushed).
    pub sticks: usize,
    /// Level changes of the exact truth's friction (breakaways, reversals, sticks).
    pub truth_friction_changes: usize,
    /// Frames with a flag other than `REVERSAL` (invalid channel, saturation, overrun, rejected).
    pub frames_flagged: usize,
    /// Events pushed with a time before an earlier-pushed event's.
    pub events_out_of_order: usize,
    /// Frames whose flags, event or echoed channels differ from the host's.
    pub frame_mismatches: usize,
    /// max |firmware − host| prediction over all samples (gμ).
    pub max_err_vs_host_gmu: f64,
    /// max |firmware − closed form (f64) on the detected train| (gμ).
    pub max_err_vs_reference_gmu: f64,
    /// Time of that maximum (s).
    pub max_err_vs_reference_at_s: f64,
    /// max |firmware − exact truth ü1| (gμ): detection latency and stick phases included.
    pub max_err_vs_truth_gmu: f64,
    /// RMS of the same (gμ).
    pub rms_err_vs_truth_gmu: f64,
    /// Instructions of a steady-state `Estimator32::update()` and storing its output (SysTick
    /// under `-icount shift=0`).
    pub instructions_per_sample: f64,
    /// Extra instructions of a sample with a reversal (`push_reversal` + update).
    pub instructions_per_reversal: f64,
    /// Instructions of the reversal detector per steady sliding sample.
    pub detector_instructions_per_sample: Option<f64>,
    /// Extra instructions of the detector at a detected reversal.
    pub detector_instructions_per_reversal: Option<f64>,
    /// Instructions of the firmware's whole per-sample step (flags, detector, estimator, frame;
    /// no I/O), steady sliding state.
    pub pipeline_instructions_per_sample: Option<f64>,
    /// Executed instructions per SysTick tick (calibrated; 40 on mps2-an386 at `shift=0`).
    pub instructions_per_tick: f64,
    /// Flash of the QEMU image (bytes).
    pub flash_bytes: u64,
    /// Static RAM of the QEMU image: `.data` + `.bss` (+ `.uninit`), bytes.
    pub ram_bytes: u64,
    /// Stack high-water mark of the QEMU run (bytes).
    pub stack_bytes: Option<u64>,
    /// Flash of the board image built for the scene (bytes).
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

/// The sensor log of a scene: truth, sensor model, one record per sample. Also returns the
/// truth's ü1 per sample and its number of friction changes.
pub fn scene_log(scene: &Scene) -> Result<(Vec<LogSample>, Vec<f64>, usize)> {
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
    let top = measured.iter().map(|(t, _)| t.top_accel_m_s2).collect();
    Ok((samples, top, truth.friction_train().len()))
}

fn same_bits(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Run the whole comparison for a scene (see the module docs).
pub fn run_scene(scene: &Scene, firmware_dir: &Path) -> Result<QemuReport> {
    qemu_runner::require_qemu()?;
    let mut timing = Timings::default();
    let gmu = scene.gmu();
    let rate = scene.rate_hz;
    let setup = DetectorSetup::for_scene(scene)?;

    let t0 = Instant::now();
    let (samples, truth_top, truth_changes) = scene_log(scene)?;
    timing.simulate_s = t0.elapsed().as_secs_f64();

    let dir = TempDir::new()?;
    let log = dir.0.join("scene.ssvrlog");
    qemu_runner::write_sensor_log(&log, &LogHeader::for_scene(scene), &samples)?;
    let images = qemu_runner::build_for_scene(firmware_dir, scene, &dir.0, true)?;
    timing.build_s = images.build_s;
    let elf = &images.qemu_elf;

    let t0 = Instant::now();
    let timeout = Duration::from_secs(120) + Duration::from_micros(500) * samples.len() as u32;
    let bytes = qemu_runner::run_qemu(elf, &log, timeout)?;
    timing.qemu_s = t0.elapsed().as_secs_f64();

    let t0 = Instant::now();
    let frames = qemu_runner::decode_frames(elf, &bytes)?;
    setup.check_firmware(&frames, rate)?;
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
    let host = host_frames(scene, &setup, &samples, false)?;
    let mut max_host = 0.0f64;
    let mut mismatches = 0usize;
    for ((f, h), s) in fw.iter().zip(&host).zip(&samples) {
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

    // (b) The closed form in f64 on the detected train; (c) the truth.
    let cf = DuhamelClosedForm::new(&scene.structure);
    let mut train = DetectedTrain::default();
    let (mut max_ref, mut max_ref_at) = (0.0f64, 0.0f64);
    let (mut max_truth, mut sq_truth) = (0.0f64, 0.0f64);
    let (mut slip_starts, mut detected_reversals, mut sticks, mut flagged) = (0, 0, 0, 0);
    for (k, (f, top)) in fw.iter().zip(&truth_top).enumerate() {
        train.push_frame(k as u64, f, rate);
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
        let reference = cf.evaluate(&train.train(), t, usize::MAX).accel_m_s2;
        let e = (pred - reference).abs() / gmu;
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

    let equal = max_host <= HOST_TOLERANCE_GMU && mismatches == 0;
    let goals = Goals {
        firmware_equals_host: equal,
        instructions_per_sample_le_20: ic.instructions_per_sample <= GOAL_INSTRUCTIONS_PER_SAMPLE,
        board_flash_le_32k: board.is_some_and(|b| b.0 <= GOAL_BOARD_FLASH_BYTES),
        board_ram_le_8k: board.is_some_and(|b| b.1 <= GOAL_BOARD_RAM_BYTES),
    };
    Ok(QemuReport {
        scene: scene.name.clone(),
        scene_file: scene.source.clone(),
        samples: samples.len() as u64,
        rate_hz: rate,
        gmu_m_s2: gmu,
        reversals: train.level_changes,
        slip_starts,
        detected_reversals,
        sticks,
        truth_friction_changes: truth_changes,
        frames_flagged: flagged,
        events_out_of_order: train.out_of_order,
        frame_mismatches: mismatches,
        max_err_vs_host_gmu: max_host,
        max_err_vs_reference_gmu: max_ref,
        max_err_vs_reference_at_s: max_ref_at,
        max_err_vs_truth_gmu: max_truth,
        rms_err_vs_truth_gmu: (sq_truth / samples.len().max(1) as f64).sqrt(),
        instructions_per_sample: ic.instructions_per_sample,
        instructions_per_reversal: ic.instructions_per_reversal,
        detector_instructions_per_sample: ic.detector_instructions_per_sample,
        detector_instructions_per_reversal: ic.detector_instructions_per_reversal,
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
    writeln!(
        out,
        "  detector: {} slip starts, {} reversals, {} sticks -> {} level changes pushed (truth: {} friction changes); {} frames flagged",
        r.slip_starts,
        r.detected_reversals,
        r.sticks,
        r.reversals,
        r.truth_friction_changes,
        r.frames_flagged
    )?;
    writeln!(
        out,
        "  firmware vs host (same f32 detector + Estimator32): max |diff| = {:.3e} gμ, {} frames differ [goal <= {:e} gμ: {}]",
        r.max_err_vs_host_gmu,
        r.frame_mismatches,
        HOST_TOLERANCE_GMU,
        ok(g.firmware_equals_host)
    )?;
    writeln!(
        out,
        "  firmware vs closed form (f64, detected train): max |error| = {:.3e} gμ at t = {:.4} s",
        r.max_err_vs_reference_gmu, r.max_err_vs_reference_at_s
    )?;
    writeln!(
        out,
        "  firmware vs exact truth: max |error| = {:.3} gμ, rms {:.3} gμ (detection latency, stick phases)",
        r.max_err_vs_truth_gmu, r.rms_err_vs_truth_gmu
    )?;
    writeln!(
        out,
        "  instructions (QEMU Cortex-M4F, SysTick, -icount shift=0): estimator {:.2}/sample [goal <= 20: {}], +{:.1}/reversal; detector {}/sample, +{}/reversal; whole step {}/sample",
        r.instructions_per_sample,
        ok(g.instructions_per_sample_le_20),
        r.instructions_per_reversal,
        opt(r.detector_instructions_per_sample, 1),
        opt(r.detector_instructions_per_reversal, 0),
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
        "  sizes: ssvr-qemu flash {} B, static RAM {} B, stack {} B; {board}",
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

/// `host-sim qemu [SCENE] [--json]`: load the scene (None or `default`: the built-in default),
/// run [`run_scene`] with `firmware/` next to host-sim, print the report, and fail when the
/// firmware differs from the host.
pub fn command(scene: Option<&Path>, json: bool) -> Result<()> {
    let scene = match scene {
        None => Scene::default_scene(),
        Some(p) if p == Path::new("default") && !p.exists() => Scene::default_scene(),
        Some(p) => Scene::load(p)?,
    };
    let report = run_scene(&scene, &qemu_runner::default_firmware_dir())?;
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
            "the firmware differs from the host: max |diff| = {:e} gμ (tolerance {:e}), {} frames with other flags/events",
            report.max_err_vs_host_gmu,
            HOST_TOLERANCE_GMU,
            report.frame_mismatches
        );
    }
    Ok(())
}
