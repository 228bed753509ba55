//! End-to-end smoke tests of the firmware's QEMU image on hand-made sensor logs: build `firmware/`
//! (its own workspace, thumbv7em) for the built-in default scene, run it under
//! `qemu-system-arm -icount shift=0`, decode the defmt stream by type and check it sample by
//! sample against the host's run of the same pipeline (`host_sim::pipeline::build` from the same
//! plan, `ssvr_proto::Pipeline`): the firmware replays the log in batches of
//! `ssvr_proto::BATCH`, the host one sample at a time, and every frame must be bit-identical.
//!
//! * the detector path (the firmware's default): a piecewise-parabolic slip with sub-sample
//!   reversals, NaN / missing / saturated samples inside;
//! * the log-reversal test hook (header option `LOG_REVERSALS`): given reversals, with the
//!   rectangular and the stick-slip model;
//! * exit statuses of bad logs (header not matching the compiled-in scene: 7).
//!
//! Needs `qemu-system-arm` (or `$QEMU_SYSTEM_ARM`) and the `thumbv7em-none-eabihf` target; CI
//! installs both. Without them the tests fail; `SSVR_SKIP_QEMU=1` skips them explicitly (each
//! prints "SKIPPED"). The first run builds the firmware (a minute or so).
//!
//! Run: `cargo test -p host-sim --test qemu_smoke -- --nocapture` (prints instruction counts and
//! sizes).

mod common;
use common::qemu_tests_run;
use host_sim::model::Model;
use host_sim::pipeline::{self, Options};
use host_sim::qemu::decode::{self, Message, Value};
use host_sim::qemu::icount::instruction_counts;
use host_sim::qemu::image;
use host_sim::qemu::log as slog;
use host_sim::scene::Scene;
use ssvr_proto::log::{options::LOG_REVERSALS, Header, LogReversal};
use ssvr_proto::stream::{FRAME, PLAN, STATS, STATS_FIELDS};
use ssvr_proto::{flags, Channel, EventKind, EventSource, Frame, Sample, Stats, Step, CHANNELS};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Build the image for the default scene and `model` into `dir`; returns the ELF.
fn build(dir: &Path, model: Model) -> PathBuf {
    image::build_for_scene_model(
        &image::default_firmware_dir(),
        &Scene::default_scene(),
        model,
        dir,
        false,
    )
    .unwrap()
    .qemu_elf
}

fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// A valid sample with these channels (table, base, top accelerations, displacement).
fn sample(channels: [f32; CHANNELS]) -> Sample {
    Sample {
        channels,
        flags: 0,
        reversal: None,
    }
}

/// A missing sample (every channel NaN).
fn missing() -> Sample {
    Sample::missing(0)
}

/// What the image produced for a log.
struct FirmwareRun {
    /// The sample frames, in order.
    frames: Vec<Frame>,
    /// Every decoded message.
    messages: Vec<Message>,
}

/// Run `input` through the image and return the decoded frames and all messages.
fn run(dir: &Path, elf: &Path, name: &str, header: &Header, input: &[Sample]) -> FirmwareRun {
    let log = dir.join(name);
    slog::write(&log, header, input).unwrap();
    let bytes = image::run_qemu(elf, &log, Duration::from_secs(120)).unwrap();
    let messages = decode::decode(elf, &bytes).unwrap();
    for m in messages.iter().filter(|m| m.name != FRAME) {
        eprintln!("firmware: {m}");
    }
    FirmwareRun {
        frames: decode::frames(&messages).unwrap(),
        messages,
    }
}

/// The host's pipeline for the default scene and `model`, events from `source`, run one sample
/// at a time: its frames and the pipeline (for its counters and μ̂).
fn host_run(model: Model, source: EventSource, input: &[Sample]) -> (Vec<Frame>, Box<dyn Step>) {
    let plan = pipeline::plan_for(&Scene::default_scene(), model).unwrap();
    let mut p = pipeline::build(
        &plan,
        Options {
            source,
            zero_at_stick: false,
        },
    )
    .unwrap();
    let frames = input.iter().map(|s| p.step(s)).collect();
    (frames, p)
}

/// The image runs the host's plan for the default scene and `model`: same digest and the same
/// model, rate, ring, back-dating, history and storage in its `plan` message.
fn assert_plan_is_the_hosts(messages: &[Message], model: Model) {
    let plan = pipeline::plan_for(&Scene::default_scene(), model).unwrap();
    assert_eq!(decode::plan_digest(messages), Some(plan.digest()), "digest");
    let m = messages.iter().find(|m| m.name == PLAN).expect("plan");
    assert_eq!(m.uint("model"), Some(u64::from(model as u8)), "model");
    assert_eq!(m.f64("rate_hz"), Some(plan.specimen.sample_rate_hz));
    for (key, want) in [
        ("ring", plan.ring),
        ("max_age", plan.max_age),
        ("history", plan.history),
        ("storage", plan.storage),
    ] {
        assert_eq!(m.uint(key), Some(want as u64), "plan {key}");
    }
}

/// The firmware's `stats` message.
fn firmware_stats(messages: &[Message]) -> Stats {
    let m = messages.iter().find(|m| m.name == STATS).expect("stats");
    let v: Vec<u32> = STATS_FIELDS
        .iter()
        .map(|k| {
            m.u32(k)
                .unwrap_or_else(|| panic!("no stats field {k}: {m}"))
        })
        .collect();
    Stats {
        samples: v[0],
        invalid: v[1],
        dropped: v[2],
        events: v[3],
        pushed: v[4],
        rejected: v[5],
        sticks: v[6],
        clamped: v[7],
    }
}

/// Every frame equals the host's: index, channels echoed bit for bit, flags, event (age bits),
/// prediction bits; and the counters are the host's.
fn assert_matches_host(fw: &FirmwareRun, input: &[Sample], host: &[Frame], host_stats: Stats) {
    let out = &fw.frames;
    assert_eq!(out.len(), input.len(), "sample frames");
    assert_eq!(host.len(), input.len(), "host frames");
    for (k, ((f, s), h)) in out.iter().zip(input).zip(host).enumerate() {
        assert_eq!(f.index as usize, k, "index @{k}");
        assert_eq!(h.index as usize, k, "host index @{k}");
        for c in Channel::ALL {
            let i = c.index();
            assert!(
                same(f.channels[i], s.channels[i]) && same(h.channels[i], s.channels[i]),
                "{} @{k}: firmware {} host {} log {}",
                c.name(),
                f.channels[i],
                h.channels[i],
                s.channels[i]
            );
        }
        assert_eq!(f.flags, h.flags, "flags @{k}: firmware {f:?} host {h:?}");
        let ev = |f: &Frame| f.event.map(|e| (e.kind, e.level, e.age_samples.to_bits()));
        assert_eq!(ev(f), ev(h), "event @{k}: firmware {f:?} host {h:?}");
        assert_eq!(
            f.prediction.to_bits(),
            h.prediction.to_bits(),
            "prediction @{k}: firmware {} host {}",
            f.prediction,
            h.prediction
        );
    }
    assert_eq!(firmware_stats(&fw.messages), host_stats, "stats");
}

/// Start of sliding (s).
const T0: f64 = 0.002;
/// Half length of an arc (s): vertices (reversals) at T0 + HALF + j·2·HALF.
const HALF: f64 = 0.0137;

/// A slip with reversals at sub-sample times: stuck at 0 until `T0`, then parabolic humps
/// x(t) = ±½·a·(HALF² − (t − t_v)²) of alternating sign, which join with equal slopes (the slip
/// velocity is continuous; it changes sign only at the vertices t_v).
fn slip(t: f64) -> f64 {
    let a = 40.0;
    let (t0, half) = (T0, HALF);
    if t < t0 {
        return 0.0;
    }
    // Arc j spans [t0 + j·2h, t0 + (j+1)·2h), vertex in its middle, 0 at both ends.
    let j = ((t - t0) / (2.0 * half)).floor();
    let tv = t0 + j * 2.0 * half + half;
    let sign = if (j as i64) % 2 == 0 { 1.0 } else { -1.0 };
    sign * 0.5 * a * (half * half - (t - tv) * (t - tv))
}

#[test]
fn qemu_image_runs_the_detector_like_the_host() {
    if !qemu_tests_run() {
        return;
    }
    let scene = Scene::default_scene();
    let dir = tempfile::tempdir().unwrap();
    let elf = build(dir.path(), Model::Rectangular);
    let n = 2000;
    let input: Vec<Sample> = (0..n)
        .map(|k| {
            let t = k as f64 / scene.rate_hz;
            let mut s = sample([
                (2.0 * (40.0 * t).sin()) as f32,
                0.5,
                -0.25,
                (slip(t) + 1e-6 * ((k * 7919) % 13) as f64 / 13.0) as f32,
            ]);
            match k {
                300 => s.channels[Channel::Displacement.index()] = f32::NAN,
                301 => s.channels[Channel::TopAccel.index()] = f32::INFINITY,
                302 => s.flags = flags::SATURATED,
                303 => s = missing(),
                // A saturated displacement channel (the log's DISP_SATURATED).
                304 => s.flags = flags::SATURATED | flags::DISP_INVALID,
                // Beyond the 50 mm full scale.
                305 => s.channels[Channel::Displacement.index()] = 0.06,
                _ => {}
            }
            s
        })
        .collect();
    let fw = run(
        dir.path(),
        &elf,
        "detector.ssvrlog",
        &slog::header_for(&scene, 0, input.len()).unwrap(),
        &input,
    );
    assert_plan_is_the_hosts(&fw.messages, Model::Rectangular);
    let (host, pipe) = host_run(Model::Rectangular, EventSource::Detector, &input);
    assert_matches_host(&fw, &input, &host, pipe.stats());
    let out = &fw.frames;

    // The flags of the invalid samples.
    let fl = |k: usize| out[k].flags & !flags::EVENT_PUSHED;
    assert_eq!(fl(300), flags::NOT_FINITE | flags::DISP_INVALID);
    assert_eq!(fl(301), flags::NOT_FINITE);
    assert_eq!(fl(302), flags::SATURATED);
    assert_eq!(
        fl(303),
        flags::MISSING | flags::NOT_FINITE | flags::DISP_INVALID
    );
    assert_eq!(fl(304), flags::SATURATED | flags::DISP_INVALID);
    assert_eq!(fl(305), flags::DISP_INVALID);

    // The detector saw the slip start and the reversals (vertices every 27.4 ms), each pushed.
    let events: Vec<(usize, EventKind, i8, f32)> = out
        .iter()
        .enumerate()
        .filter_map(|(k, f)| f.event.map(|e| (k, e.kind, e.level, e.age_samples)))
        .collect();
    eprintln!("events (sample, kind, level, age): {events:?}");
    assert_eq!(events[0].1, EventKind::SlipStart);
    let reversals: Vec<_> = events
        .iter()
        .filter(|e| e.1 == EventKind::Reversal)
        .collect();
    assert!(reversals.len() >= 4, "{events:?}");
    for &&(k, _, _, age) in &reversals {
        assert_ne!(out[k].flags & flags::EVENT_PUSHED, 0, "flags @{k}");
        let t = (k as f64 - f64::from(age)) / scene.rate_hz;
        let j = ((t - T0 - HALF) / (2.0 * HALF)).round();
        let tv = T0 + HALF + j * 2.0 * HALF;
        // The arcs are exact parabolas, so the vertex fits locate them closely.
        assert!(
            (t - tv).abs() < 1.0 / scene.rate_hz,
            "reversal at {t} vs {tv}"
        );
    }
    let stats = firmware_stats(&fw.messages);
    assert_eq!(stats.samples, 2000);
    assert_eq!(stats.dropped, 0);
    assert_eq!(stats.rejected, 0);
    assert_eq!(stats.invalid, 6);
    assert_eq!(stats.events as usize, events.len());

    let ic = instruction_counts(&fw.messages).unwrap();
    assert_eq!(ic.reversal_errors, 0);
    // One tick per 40 instructions; the calibration reads the counter at an arbitrary phase of
    // its 40-instruction period, so each of its two readings is exact to ±1 tick.
    assert!(
        (ic.instructions_per_tick - 40.0).abs() < 40.0 * 1e-4,
        "instructions per SysTick tick: {}",
        ic.instructions_per_tick
    );
    let (flash, ram) = image::elf_sizes(&elf).unwrap();
    let stack = fw
        .messages
        .iter()
        .find(|m| m.name == "stack")
        .and_then(|m| m.uint("used_bytes"));
    eprintln!(
        "qemu image: estimator {:.2} instructions/sample, +{:?}/reversal; detector {:?}/sample, \
         +{:?}/reversal, +{:?}/stick; whole step {:?}/sample (batches of {}); flash={flash} B \
         ram={ram} B stack={stack:?} B",
        ic.instructions_per_sample,
        ic.instructions_per_reversal,
        ic.detector_instructions_per_sample,
        ic.detector_instructions_per_reversal,
        ic.detector_instructions_per_stick,
        ic.pipeline_instructions_per_sample,
        ssvr_proto::BATCH
    );
    assert!(ic.instructions_per_sample > 0.0);
    assert!(ic.instructions_per_reversal.unwrap() > 0.0);
    assert!(ic.detector_instructions_per_sample.unwrap() > 0.0);
    assert!(ic.detector_instructions_per_reversal.unwrap() > 0.0);
    assert!(ic.pipeline_instructions_per_sample.unwrap() > 0.0);
    assert!(flash > 0 && ram > 0);
    assert!(stack.is_some_and(|s| s > 0), "stack high-water mark");
    assert!(fw.messages.iter().any(|m| m.name == "done"));
}

const N: usize = 200;

/// Given reversals: +1 at sample 50 (age 0.25), −1 at 120 (age 0.5). Invalid samples: 10 (NaN
/// top accel), 11 (saturated), 12 (missing).
fn hook_samples() -> Vec<Sample> {
    (0..N)
        .map(|k| {
            let t = k as f32 / 1e4;
            let mut s = sample([
                2.0 * (2.0 * std::f32::consts::PI * 5.0 * t).sin(),
                1.5 * (2.0 * std::f32::consts::PI * 5.0 * t).sin(),
                -0.5 + k as f32 * 1e-3,
                1e-4 * k as f32,
            ]);
            match k {
                10 => s.channels[Channel::TopAccel.index()] = f32::NAN,
                11 => s.flags = flags::SATURATED,
                12 => s = missing(),
                50 => {
                    s.reversal = Some(LogReversal {
                        level: 1,
                        age_samples: 0.25,
                    })
                }
                120 => {
                    s.reversal = Some(LogReversal {
                        level: -1,
                        age_samples: 0.5,
                    })
                }
                _ => {}
            }
            s
        })
        .collect()
}

#[test]
fn qemu_image_log_reversal_hook_feeds_the_estimator() {
    if !qemu_tests_run() {
        return;
    }
    let scene = Scene::default_scene();
    let dir = tempfile::tempdir().unwrap();
    let elf = build(dir.path(), Model::Rectangular);
    let input = hook_samples();
    let header = slog::header_for(&scene, LOG_REVERSALS, input.len()).unwrap();
    let fw = run(dir.path(), &elf, "hook.ssvrlog", &header, &input);
    assert_plan_is_the_hosts(&fw.messages, Model::Rectangular);
    let (host, pipe) = host_run(Model::Rectangular, EventSource::Log, &input);
    assert_matches_host(&fw, &input, &host, pipe.stats());
    let out = &fw.frames;

    assert!(fw.messages.iter().any(|m| m.name == "done"));
    let stats = firmware_stats(&fw.messages);
    assert_eq!(stats.samples, 200);
    assert_eq!(stats.events, 2);
    assert_eq!(stats.pushed, 2);
    assert_eq!(stats.rejected, 0);
    assert_eq!(stats.invalid, 3);
    for (k, f) in out.iter().enumerate() {
        let expected = match k {
            10 => flags::NOT_FINITE,
            11 => flags::SATURATED,
            12 => flags::MISSING | flags::NOT_FINITE | flags::DISP_INVALID,
            50 | 120 => flags::EVENT_PUSHED,
            _ => 0,
        };
        assert_eq!(f.flags, expected, "flags @{k}");
        if k == 50 || k == 120 {
            let e = f.event.unwrap();
            assert_eq!(e.kind, EventKind::Log);
            assert_eq!(e.level, if k == 50 { 1 } else { -1 });
            assert_eq!(e.age_samples, if k == 50 { 0.25 } else { 0.5 });
        } else {
            assert_eq!(f.event, None, "event @{k}");
        }
    }
    // At rest before the first reversal; within a few gμ afterwards.
    let gmu = scene.gmu() as f32;
    for (k, f) in out.iter().enumerate() {
        if k < 50 {
            assert_eq!(f.prediction, 0.0, "prediction @{k}");
        } else {
            assert!(f.prediction.abs() <= 4.0 * gmu, "prediction @{k}");
        }
    }
}

/// The stick-slip model through the log-reversal hook: events of every kind (a stick is level 0)
/// and age, one older than the history (clamped), invalid samples (a NaN, a saturated and a
/// missing top acceleration are not used for the μ identification), 2000 samples (the
/// identification runs on blocks of samples once they are history − 2 samples old). Every frame,
/// the stats and μ̂ equal the host's.
#[test]
fn qemu_image_stick_slip_model_matches_the_host() {
    if !qemu_tests_run() {
        return;
    }
    let scene = Scene::default_scene();
    let dir = tempfile::tempdir().unwrap();
    let elf = build(dir.path(), Model::StickSlip);
    let plan = pipeline::plan_for(&scene, Model::StickSlip).unwrap();
    let old = plan.max_age as f32 + 30.5;
    // (sample, level, age): slip, stick 20.5 samples back (the history is max_age + 2 = 39
    // samples with the phase detector), slip the other way, an event older than the history, a
    // stick on a sample boundary, a slip.
    assert!(plan.max_age > 21, "max_age {}", plan.max_age);
    assert_eq!(plan.history, plan.max_age + 2);
    let events = [
        (50, 1, 0.25),
        (400, 0, 20.5),
        (420, -1, 3.75),
        (900, 1, old),
        (1300, 0, 12.0),
        (1350, 1, 0.0),
    ];
    let n = 2000;
    let input: Vec<Sample> = (0..n)
        .map(|k| {
            let t = k as f32 / 1e4;
            let mut s = sample([
                2.0 * (2.0 * std::f32::consts::PI * 7.0 * t).sin(),
                1.5 * (2.0 * std::f32::consts::PI * 7.0 * t).sin(),
                1.8 * (2.0 * std::f32::consts::PI * 7.0 * t).cos(),
                1e-6 * k as f32,
            ]);
            match k {
                610 => s.channels[Channel::TopAccel.index()] = f32::NAN,
                611 => s.flags = flags::SATURATED,
                612 => s = missing(),
                _ => {}
            }
            if let Some(&(_, level, age)) = events.iter().find(|e| e.0 == k) {
                s.reversal = Some(LogReversal {
                    level,
                    age_samples: age,
                });
            }
            s
        })
        .collect();
    let header = slog::header_for(&scene, LOG_REVERSALS, input.len()).unwrap();
    let fw = run(dir.path(), &elf, "ss.ssvrlog", &header, &input);
    assert_plan_is_the_hosts(&fw.messages, Model::StickSlip);
    let (host, pipe) = host_run(Model::StickSlip, EventSource::Log, &input);
    assert_matches_host(&fw, &input, &host, pipe.stats());
    let out = &fw.frames;

    let stats = firmware_stats(&fw.messages);
    assert_eq!(stats.events, 6);
    assert_eq!(stats.pushed, 6);
    assert_eq!(stats.rejected, 0);
    assert_eq!(stats.clamped, 1);
    assert_eq!(stats.invalid, 3);
    assert_eq!(pipe.stats().clamped, 1);
    for &(k, _, _) in &events {
        assert_eq!(
            out[k].flags & flags::EVENT_PUSHED,
            flags::EVENT_PUSHED,
            "flags @{k}"
        );
    }
    let mu = decode::mu(&fw.messages).expect("mu estimate");
    let want = pipe.mu_estimate().expect("host mu");
    assert_eq!(mu, (want.mu, want.std, want.blocks));
    eprintln!(
        "stick-slip image: mu {} ± {} from {} blocks",
        mu.0, mu.1, mu.2
    );
    // Identification updates (one per block of `identify_every` sliding samples).
    assert!(want.blocks > 10, "{want:?}");
    let ic = instruction_counts(&fw.messages).unwrap();
    eprintln!(
        "stick-slip image: {:.2} instructions/sliding sample, {:?} stuck, {:?} without the \
         identification, +{:?}/event (age 0.5), +{:?}/event (age {:?}); in blocks of {:?}: \
         {:?} sliding, {:?} stuck; whole step {:?}/sample",
        ic.instructions_per_sample,
        ic.instructions_per_sample_stuck,
        ic.instructions_per_sample_without_identification,
        ic.instructions_per_reversal,
        ic.instructions_per_event_max_age,
        ic.max_event_age,
        ic.block_size,
        ic.instructions_per_sample_in_blocks,
        ic.instructions_per_sample_stuck_in_blocks,
        ic.pipeline_instructions_per_sample
    );
    assert_eq!(ic.reversal_errors, 0);
    // The pipeline's way (blocks): within the goal of 40 per steady-state sample.
    assert_eq!(ic.block_size, Some(ssvr_proto::BATCH as u32));
    for (name, v) in [
        ("sliding", ic.instructions_per_sample_in_blocks),
        ("stuck", ic.instructions_per_sample_stuck_in_blocks),
    ] {
        let v = v.unwrap_or(f64::NAN);
        assert!(v > 15.0 && v <= 40.0, "{name} in blocks: {v}");
    }
}

#[test]
fn sensor_log_layout_matches_log_format_md() {
    let scene = Scene::default_scene();
    let header = slog::header_for(&scene, LOG_REVERSALS, 3).unwrap();
    let s = [
        sample([1.0, 0.0, 0.0, 0.0]),
        Sample {
            channels: [0.0; CHANNELS],
            flags: flags::MISSING,
            reversal: Some(LogReversal {
                level: -1,
                age_samples: 0.5,
            }),
        },
        // A saturated displacement channel.
        Sample {
            channels: [0.0; CHANNELS],
            flags: flags::SATURATED | flags::DISP_INVALID,
            reversal: None,
        },
    ];
    let b = slog::encode(&header, &s);
    assert_eq!(b.len(), 80 + 17 + 22 + 17);
    assert_eq!(&b[0..8], b"SSVRLOG1");
    assert_eq!(u16::from_le_bytes([b[8], b[9]]), 1);
    assert_eq!(u16::from_le_bytes([b[10], b[11]]), 80);
    assert_eq!(u16::from_le_bytes([b[12], b[13]]), 4);
    assert_eq!(u16::from_le_bytes([b[14], b[15]]), 1);
    assert_eq!(f64::from_le_bytes(b[16..24].try_into().unwrap()), 10_000.0);
    assert_eq!(f64::from_le_bytes(b[24..32].try_into().unwrap()), 29.5);
    assert_eq!(f64::from_le_bytes(b[64..72].try_into().unwrap()), 9.80665);
    assert_eq!(u32::from_le_bytes(b[72..76].try_into().unwrap()), 3);
    assert_eq!(f32::from_le_bytes(b[80..84].try_into().unwrap()), 1.0);
    assert_eq!(b[96], 0);
    assert_eq!(b[97 + 16], 0x80 | 0x02);
    assert_eq!(b[97 + 17] as i8, -1);
    assert_eq!(f32::from_le_bytes(b[115..119].try_into().unwrap()), 0.5);
    assert_eq!(b[119 + 16], 0x01 | 0x04);
}

#[test]
fn firmware_scene_file_round_trips_the_scene() {
    // The file build.rs reads has host-sim's layout: host-sim reads it back to the same values.
    for scene in [
        Scene::default_scene(),
        Scene::load(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scenes")
                .join("elcentro.toml"),
        )
        .unwrap(),
    ] {
        let text = image::firmware_scene_toml(&scene);
        let back =
            Scene::parse(&format!(
            "duration_s = 1.0\n{text}\n[input]\nkind = \"harmonic\"\namplitude_m_s2 = 1.0\nperiod_s = 1.0\n"
        ), Path::new("fw.toml")).unwrap();
        assert_eq!(back.structure.params(), scene.structure.params());
        assert_eq!(
            back.static_friction_coefficient,
            scene.static_friction_coefficient
        );
        assert_eq!(back.rate_hz, scene.rate_hz);
        assert_eq!(
            back.sensors.disp_noise_rms_m,
            scene.sensors.disp_noise_rms_m
        );
        assert_eq!(back.sensors.disp_range_m, scene.sensors.disp_range_m);
    }
}

#[test]
fn qemu_image_exit_status_names_bad_logs() {
    if !qemu_tests_run() {
        return;
    }
    let scene = Scene::default_scene();
    let dir = tempfile::tempdir().unwrap();
    let elf = build(dir.path(), Model::Rectangular);
    let header = slog::header_for(&scene, LOG_REVERSALS, N).unwrap();
    let good = slog::encode(&header, &hook_samples());
    let run = |name: &str, bytes: &[u8]| {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = image::run_qemu_output(&elf, &path, Duration::from_secs(60)).unwrap();
        assert!(!out.timed_out, "{name} timed out");
        let messages = decode::decode(&elf, &out.stdout).unwrap();
        (out.status, messages)
    };
    let errors = |messages: &[Message]| -> Vec<Message> {
        messages
            .iter()
            .filter(|m| m.level.as_deref() == Some("error"))
            .cloned()
            .collect()
    };

    // sample_count = 0xFFFFFFFF: read to the end of the file.
    let mut until_eof = good.clone();
    until_eof[72..76].copy_from_slice(&u32::MAX.to_le_bytes());
    let (status, messages) = run("eof.ssvrlog", &until_eof);
    assert_eq!(status, Some(0));
    assert_eq!(decode::frames(&messages).unwrap().len(), N);
    assert!(errors(&messages).is_empty(), "{:?}", errors(&messages));

    // Bad magic: status 3.
    let mut bad_magic = good.clone();
    bad_magic[0] = b'X';
    let (status, messages) = run("magic.ssvrlog", &bad_magic);
    assert_eq!(status, Some(3));
    assert!(decode::frames(&messages).unwrap().is_empty());

    // A structure or rate other than the compiled-in scene's: status 7, the field named with
    // the log's and the firmware's values.
    let named = |messages: &[Message], field: &str, log: f64, firmware: f64| {
        errors(messages).iter().any(|m| {
            m.fields.first().map(|(_, v)| v) == Some(&Value::Text(field.to_string()))
                && m.f64("log") == Some(log)
                && m.f64("firmware") == Some(firmware)
        })
    };
    let mut other_damping = good.clone();
    other_damping[48..56].copy_from_slice(&0.06f64.to_le_bytes());
    let (status, messages) = run("damping.ssvrlog", &other_damping);
    assert_eq!(status, Some(7));
    assert!(
        named(&messages, "damping_ratio", 0.06, 0.05),
        "{:?}",
        errors(&messages)
    );
    assert!(decode::frames(&messages).unwrap().is_empty());
    let mut other_rate = good.clone();
    other_rate[16..24].copy_from_slice(&1000.0f64.to_le_bytes());
    let (status, messages) = run("rate.ssvrlog", &other_rate);
    assert_eq!(status, Some(7));
    assert!(
        named(&messages, "sample_rate_hz", 1000.0, 10_000.0),
        "{:?}",
        errors(&messages)
    );

    // Truncated inside record 100 (header, 100 records, the reversal event of record 50, 3 bytes):
    // status 5, the first 100 frames were streamed (the last, partial batch of the replay
    // included), then the error after 100 samples.
    let cut = 80 + 100 * 17 + 5 + 3;
    let (status, messages) = run("cut.ssvrlog", &good[..cut]);
    assert_eq!(status, Some(5));
    let frames = decode::frames(&messages).unwrap();
    assert_eq!(frames.len(), 100);
    assert!(frames
        .iter()
        .enumerate()
        .all(|(k, f)| f.index as usize == k));
    assert!(
        errors(&messages)
            .iter()
            .any(|m| m.fields.first().map(|(_, v)| v) == Some(&Value::Uint(100))),
        "{:?}",
        errors(&messages)
    );
}

/// A reader that falls behind loses no frame. Under `-nographic` QEMU made its stdout
/// non-blocking, a semihosting write that met a full pipe failed, and defmt-semihosting drops
/// what it could not write: CI on a loaded machine once got 317 890 frames for 320 000. Here
/// the pipe is left unread for 2 s while the image streams a few hundred KB.
#[test]
fn a_slow_reader_loses_no_frames() {
    use std::io::Read;
    use std::process::Stdio;
    if !qemu_tests_run() {
        return;
    }
    let scene = Scene::default_scene();
    let dir = tempfile::tempdir().unwrap();
    let elf = build(dir.path(), Model::Rectangular);
    let n = 100_000;
    let input = vec![sample([0.0; CHANNELS]); n];
    let log = dir.path().join("slow.ssvrlog");
    slog::write(&log, &slog::header_for(&scene, 0, n).unwrap(), &input).unwrap();
    let mut child = image::qemu_command(&elf, "slow.ssvrlog")
        .current_dir(dir.path())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs(2));
    let mut bytes = Vec::new();
    child
        .stdout
        .take()
        .unwrap()
        .read_to_end(&mut bytes)
        .unwrap();
    assert_eq!(child.wait().unwrap().code(), Some(0));
    assert!(bytes.len() > 256 * 1024, "{} bytes", bytes.len());
    let frames = decode::frames(&decode::decode(&elf, &bytes).unwrap()).unwrap();
    assert_eq!(frames.len(), n);
    assert!(frames
        .iter()
        .enumerate()
        .all(|(k, f)| f.index as usize == k));
}
