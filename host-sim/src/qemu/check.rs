//! `host-sim qemu [SCENE] [--model MODEL] [--json]`: run the firmware's QEMU image on a scene and
//! check every prediction it makes.
//!
//! 1. Simulate the exact stick-slip truth of the scene ([`crate::truth`]) and measure it with the
//!    seeded sensor model ([`crate::sensors`]); write the sensor log ([`super::log`]). The
//!    estimator model is chosen from the simulated truth like `host-sim run` does
//!    ([`crate::model::choose`]), or given with `--model`.
//! 2. Build the QEMU image (and the board image, for its sizes) for the scene and the model
//!    ([`super::image::build_for_scene_model`]: `SSVR_SCENE`, `SSVR_MODEL`; cargo rebuilds only
//!    when the scene's firmware parameters or the model change). The image reports the digest of
//!    the plan it was built with; it must be the host's plan for the scene and model.
//! 3. Run it under `qemu-system-arm -icount shift=0` and decode its defmt stream by type.
//! 4. Compare every sample's prediction
//!    * with the host's run of the same pipeline (`ssvr_proto::Pipeline` from the same plan, one
//!      sample at a time, as `host-sim run` runs it; the firmware runs it in batches): must be
//!      equal to ≤ 1e-6·gμ (it is bit-identical), as must the detected events, the flags and the
//!      identified μ;
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
//! The command fails (non-zero exit) unless every goal is met ([`Goals`]): firmware = host,
//! the error against the reference, the instructions per steady sample (the estimator's, and the
//! model's as the pipeline runs it with all identification on), the board's flash and RAM.

use super::decode;
pub use super::goals::{
    instructions_goal, Goals, Timings, BOARD_FLASH_32K, GOAL_BOARD_FLASH_BYTES,
    GOAL_BOARD_RAM_BYTES, GOAL_INSTRUCTIONS_PER_SAMPLE, GOAL_INSTRUCTIONS_PER_SAMPLE_STICK_SLIP,
    GOAL_MODEL_INSTRUCTIONS_PER_SAMPLE, GOAL_REFERENCE_GMU, HOST_TOLERANCE_GMU,
};
use super::goals::{steady_model_instructions, steady_sample_instructions};
use super::icount::{instruction_counts, InstructionCounts};
use super::image;
use super::log::{self as slog, scene_log, SceneLog};
use super::reference::Reference;
use crate::model::Model;
use crate::pipeline;
use crate::scene::Scene;
use anyhow::{anyhow, bail, Context, Result};
use serde::Serialize;
use ssvr_proto::{flags, EventKind, Frame, Mode};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// What `host-sim qemu` reports (`--json` prints it).
#[derive(Debug, Clone, Serialize)]
pub struct QemuReport {
    /// Scene name.
    pub scene: String,
    /// Scene file (None: the built-in default).
    pub scene_file: Option<PathBuf>,
    /// The QEMU image that ran (absolute; kept after the run by [`image::keep_image`], so
    /// `host-sim monitor --elf` can decode the stream `--stream-out` saved).
    pub elf: PathBuf,
    /// The estimator model built into the firmware (`fixed-base`, `rectangular`, `stick-slip`).
    pub model: &'static str,
    /// What the model may read: `fuse` (every channel) or `predict` (never the top
    /// accelerometer).
    pub mode: &'static str,
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
    /// The firmware's μ̂ equals the host's (bit for bit; true when neither has one), and so does
    /// the velocity-dependent friction law in use (`law` message) if the model follows one.
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
    /// The model's steady-state cost as the firmware's pipeline runs it with all identification
    /// on, which the goal of 50 is checked on: the plan's model (`FromPlan`; in fuse mode the
    /// stick-slip and fixed-base models identify f and ξ online) fed batches of `block_size`
    /// samples through `note_inputs` and `predict_run` as `Pipeline::step_batch` does without
    /// an event, after a warm-up, on a steady oscillation of the plan's top oscillator: the
    /// larger of `instructions_per_sample_model_sliding` and
    /// `instructions_per_sample_model_stuck` (fixed-base: stuck). It includes the estimator's
    /// `instructions_per_steady_sample` work; null when the image did not measure it.
    pub instructions_per_steady_sample_model: Option<f64>,
    /// Instructions per steady-state stuck sample of the model as the pipeline runs it, all
    /// identification on (`instructions_per_steady_sample_model`).
    pub instructions_per_sample_model_stuck: Option<f64>,
    /// The same sliding after one slip start (stick-slip: μ identified; rectangular: level +1);
    /// null for the fixed-base model, which pushes no event.
    pub instructions_per_sample_model_sliding: Option<f64>,
    /// Whether the model timed for `instructions_per_steady_sample_model` identifies f and ξ
    /// online (fuse mode, stick-slip and fixed-base models).
    pub model_tuning: Option<bool>,
    /// Adoptions of f and ξ while it was timed (0: the steady state, nothing to adopt).
    pub model_adoptions: Option<u32>,
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
    /// Every goal met (the exit status).
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

fn same_bits(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Run the whole comparison for a scene with the model [`crate::model::choose`] picks (see the module
/// docs).
pub fn run_scene(scene: &Scene, firmware_dir: &Path) -> Result<QemuReport> {
    run_scene_model(scene, firmware_dir, None)
}

/// Run the whole comparison for a scene with `model` (None: the one [`crate::model::choose`] picks from
/// the simulated truth, as `host-sim run` does).
pub fn run_scene_model(
    scene: &Scene,
    firmware_dir: &Path,
    model: Option<Model>,
) -> Result<QemuReport> {
    run_scene_mode(scene, firmware_dir, model, Mode::Fuse)
}

/// [`run_scene_model`] in `mode` (the firmware built with `SSVR_MODE`).
pub fn run_scene_mode(
    scene: &Scene,
    firmware_dir: &Path,
    model: Option<Model>,
    mode: Mode,
) -> Result<QemuReport> {
    run_scene_stream(scene, firmware_dir, model, mode, None)
}

/// [`run_scene_mode`], also writing the raw defmt stream QEMU produced (its stdout, before
/// decoding) to `stream_out` when given (`host-sim qemu --stream-out`).
pub fn run_scene_stream(
    scene: &Scene,
    firmware_dir: &Path,
    model: Option<Model>,
    mode: Mode,
    stream_out: Option<&Path>,
) -> Result<QemuReport> {
    image::require_qemu()?;
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
    let plan = pipeline::plan_for_mode(scene, model, mode)?;
    timing.simulate_s = t0.elapsed().as_secs_f64();

    let dir = TempDir::new()?;
    let log = dir.0.join("scene.ssvrlog");
    slog::write(&log, &slog::header_for(scene, 0, samples.len())?, &samples)?;
    let images = image::build_for_scene_mode(firmware_dir, scene, model, mode, &dir.0, true)?;
    timing.build_s = images.build_s;
    let kept = image::keep_image(firmware_dir, &images.qemu_elf)?;
    let elf = &kept;

    let t0 = Instant::now();
    let timeout = Duration::from_secs(120) + Duration::from_micros(500) * samples.len() as u32;
    let bytes = image::run_qemu(elf, &log, timeout)?;
    timing.qemu_s = t0.elapsed().as_secs_f64();
    if let Some(path) = stream_out {
        std::fs::write(path, &bytes)
            .with_context(|| format!("cannot write the stream to {}", path.display()))?;
    }

    let t0 = Instant::now();
    let frames = decode::decode(elf, &bytes)?;
    let fw_digest = decode::plan_digest(&frames)
        .ok_or_else(|| anyhow!("the firmware reported no `plan` message"))?;
    let plan_equal = fw_digest == plan.digest();
    if !plan_equal {
        bail!(
            "the firmware runs another plan than the host's for this scene and the {} model \
             (digest {fw_digest:#010x}, host {:#010x}): rebuild it for the scene",
            model.name(),
            plan.digest()
        );
    }
    let fw = decode::frames(&frames)?;
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

    // (a) The same pipeline on the host, same plan, same f32 inputs, one sample at a time.
    let mut host = pipeline::build(&plan, pipeline::Options::default())?;
    let host_frames: Vec<Frame> = samples.iter().map(|s| host.step(s)).collect();
    let mut max_host = 0.0f64;
    let mut mismatches = 0usize;
    for ((f, h), s) in fw.iter().zip(&host_frames).zip(&samples) {
        let d = (f64::from(f.prediction) - f64::from(h.prediction)).abs() / gmu;
        max_host = if d.is_nan() {
            f64::INFINITY
        } else {
            max_host.max(d)
        };
        let echoed = f
            .channels
            .iter()
            .zip(&s.channels)
            .all(|(&a, &b)| same_bits(a, b));
        let event_same = match (f.event, h.event) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                a.kind == b.kind
                    && a.level == b.level
                    && a.age_samples.to_bits() == b.age_samples.to_bits()
            }
            _ => false,
        };
        if !(echoed && event_same && f.flags & !flags::OVERRUN == h.flags) {
            mismatches += 1;
        }
    }
    let fw_mu = decode::mu(&frames);
    let host_mu = host.mu_estimate().map(|m| (m.mu, m.std, m.blocks));
    let law_equal = decode::law(&frames)
        == host
            .friction_law()
            .map(|l| (l.mu_slow, l.mu_fast, l.rate_s_m, l.adoptions));
    let mu_equal = fw_mu == host_mu && law_equal;

    // (b) The full-precision reference on the detected events; (c) the truth.
    let (mut max_ref, mut max_ref_at) = (0.0f64, 0.0f64);
    let (mut max_truth, mut sq_truth) = (0.0f64, 0.0f64);
    let (mut slip_starts, mut detected_reversals, mut sticks, mut flagged) = (0, 0, 0, 0);
    let mut reference = Reference::new(scene, &plan)?;
    for (k, ((f, top), s)) in fw.iter().zip(&truth_top).zip(&samples).enumerate() {
        match f.event.map(|e| e.kind) {
            Some(EventKind::SlipStart) => slip_starts += 1,
            Some(EventKind::Reversal) => detected_reversals += 1,
            Some(EventKind::Stick) => sticks += 1,
            _ => {}
        }
        if f.flags & !flags::EVENT_PUSHED != 0 {
            flagged += 1;
        }
        let t = k as f64 / rate;
        let pred = f64::from(f.prediction);
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

    let ic = instruction_counts(&frames)
        .ok_or_else(|| anyhow!("the firmware reported no instruction counts"))?;
    let (flash, ram) = image::elf_sizes(elf)?;
    let (board, board_error) = match &images.board_elf {
        Ok(b) => (Some(image::elf_sizes(b)?), None),
        Err(e) => (None, Some(e.clone())),
    };
    let stack_bytes = frames
        .iter()
        .find(|m| m.name == "stack")
        .and_then(|m| m.uint("used_bytes"));

    let equal = max_host <= HOST_TOLERANCE_GMU && mismatches == 0 && mu_equal;
    let goal = instructions_goal(model);
    let steady = steady_sample_instructions(&ic);
    let steady_model = steady_model_instructions(&ic);
    let goals = Goals {
        firmware_equals_host: equal,
        instructions_per_sample_le_20: ic.instructions_per_sample <= GOAL_INSTRUCTIONS_PER_SAMPLE,
        instructions_per_sample_goal: goal,
        instructions_per_sample_le_goal: steady <= goal,
        model_instructions_per_sample_le_50: steady_model
            .is_some_and(|m| m <= GOAL_MODEL_INSTRUCTIONS_PER_SAMPLE),
        board_flash_le_32k: board.is_some_and(|b| b.0 <= BOARD_FLASH_32K),
        board_flash_le_budget: board.is_some_and(|b| b.0 <= GOAL_BOARD_FLASH_BYTES),
        board_flash_budget_bytes: GOAL_BOARD_FLASH_BYTES,
        board_ram_le_8k: board.is_some_and(|b| b.1 <= GOAL_BOARD_RAM_BYTES),
        reference_error_le_goal: max_ref <= GOAL_REFERENCE_GMU,
        plan_equals_host: plan_equal,
    };
    let stick_slip = model != Model::Rectangular;
    Ok(QemuReport {
        scene: scene.name.clone(),
        scene_file: scene.source.clone(),
        elf: kept.clone(),
        model: model.name(),
        mode: mode.name(),
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
        events_clamped: host.stats().clamped as usize,
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
        history: stick_slip.then_some(plan.history),
        instructions_per_sample: ic.instructions_per_sample,
        instructions_per_reversal: ic.instructions_per_reversal,
        instructions_per_sample_stuck: ic.instructions_per_sample_stuck,
        instructions_per_steady_sample: steady,
        instructions_per_steady_sample_model: steady_model,
        instructions_per_sample_model_stuck: ic.model_instructions_per_sample_stuck,
        instructions_per_sample_model_sliding: ic.model_instructions_per_sample_sliding,
        model_tuning: ic.model_tuning,
        model_adoptions: ic.model_adoptions,
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
        passed: equal
            && goals.instructions_per_sample_le_goal
            && goals.board_flash_le_budget
            && goals.board_ram_le_8k
            && goals.reference_error_le_goal,
        goals,
        timing,
    })
}

/// Cortex-M4F instruction counts of a model's estimator, measured once: the QEMU image built
/// for the built-in default scene and `model`, run on the first 0.1 s of its sensor log (the
/// benchmark blocks do not depend on the log). Errors: QEMU missing, build or run failure.
pub fn measure_instruction_counts(model: Model) -> Result<InstructionCounts> {
    image::require_qemu()?;
    let mut scene = Scene::default_scene();
    scene.duration_s = 0.1;
    scene.samples = (scene.duration_s * scene.rate_hz).round() as u64;
    let log_data = scene_log(&scene)?;
    let dir = TempDir::new()?;
    let log = dir.0.join("bench.ssvrlog");
    slog::write(
        &log,
        &slog::header_for(&scene, 0, log_data.samples.len())?,
        &log_data.samples,
    )?;
    let images =
        image::build_for_scene_model(&image::default_firmware_dir(), &scene, model, &dir.0, false)?;
    let bytes = image::run_qemu(&images.qemu_elf, &log, Duration::from_secs(120))?;
    let frames = decode::decode(&images.qemu_elf, &bytes)?;
    instruction_counts(&frames)
        .ok_or_else(|| anyhow!("the firmware reported no instruction counts"))
}
