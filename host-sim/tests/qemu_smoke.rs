//! End-to-end smoke tests of the firmware's QEMU image on hand-made sensor logs: build `firmware/`
//! (its own workspace, thumbv7em) for the built-in default scene, run it under
//! `qemu-system-arm -icount shift=0`, decode the defmt stream and check it sample by sample
//! against the host's run of the same pipeline (`host_sim::qemu_cmd::host_frames`).
//!
//! * the detector path (the firmware's default): a piecewise-parabolic slip with sub-sample
//!   reversals, NaN / missing / saturated samples inside;
//! * the log-reversal test hook (header option `LOG_REVERSALS`): given reversals;
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
use host_sim::qemu_cmd::{host_frames, host_run, DetectorSetup, HostFrame};
use host_sim::qemu::image::{
    self, event_kind, frame_flags as ff, LogHeader, LogReversal, LogSample, SampleFrame,
    OPTION_LOG_REVERSALS,
};
use host_sim::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Build the image for the default scene into `dir`; returns the ELF.
fn build(dir: &Path) -> PathBuf {
    qemu_runner::build_for_scene(
        &qemu_runner::default_firmware_dir(),
        &Scene::default_scene(),
        dir,
        false,
    )
    .unwrap()
    .qemu_elf
}

fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Run `input` through the image and return the decoded frames and all messages.
fn run(
    dir: &Path,
    elf: &Path,
    name: &str,
    header: &LogHeader,
    input: &[LogSample],
) -> (Vec<SampleFrame>, Vec<qemu_runner::DecodedFrame>) {
    let log = dir.join(name);
    qemu_runner::write_sensor_log(&log, header, input).unwrap();
    let bytes = qemu_runner::run_qemu(elf, &log, Duration::from_secs(120)).unwrap();
    let frames = qemu_runner::decode_frames(elf, &bytes).unwrap();
    for f in frames.iter().filter(|f| f.kind() != "sample") {
        eprintln!("firmware: {f}");
    }
    (qemu_runner::sample_frames(&frames), frames)
}

/// Every frame equals the host's: channels echoed bit for bit, flags, event, prediction bits.
fn assert_matches_host(out: &[SampleFrame], input: &[LogSample], host: &[HostFrame]) {
    assert_eq!(out.len(), input.len(), "sample frames");
    for (k, ((f, s), h)) in out.iter().zip(input).zip(host).enumerate() {
        assert_eq!(f.index as usize, k);
        assert!(same(f.table_accel_m_s2, s.table_accel_m_s2), "table @{k}");
        assert!(same(f.base_accel_m_s2, s.base_accel_m_s2), "base @{k}");
        assert!(same(f.top_accel_m_s2, s.top_accel_m_s2), "top @{k}");
        assert!(same(f.displacement_m, s.displacement_m), "disp @{k}");
        assert_eq!(f.flags, h.flags, "flags @{k}");
        assert_eq!(f.event, h.event, "event @{k}");
        assert_eq!(
            f.prediction_m_s2.to_bits(),
            h.prediction_m_s2.to_bits(),
            "prediction @{k}: firmware {} host {}",
            f.prediction_m_s2,
            h.prediction_m_s2
        );
    }
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
    let elf = build(dir.path());
    let n = 2000;
    let input: Vec<LogSample> = (0..n)
        .map(|k| {
            let t = k as f64 / scene.rate_hz;
            let mut s = LogSample {
                table_accel_m_s2: (2.0 * (40.0 * t).sin()) as f32,
                base_accel_m_s2: 0.5,
                top_accel_m_s2: -0.25,
                displacement_m: (slip(t) + 1e-6 * ((k * 7919) % 13) as f64 / 13.0) as f32,
                ..LogSample::default()
            };
            match k {
                300 => s.displacement_m = f32::NAN,
                301 => s.top_accel_m_s2 = f32::INFINITY,
                302 => s.saturated = true,
                303 => {
                    s.missing = true;
                    s.table_accel_m_s2 = f32::NAN;
                    s.base_accel_m_s2 = f32::NAN;
                    s.top_accel_m_s2 = f32::NAN;
                    s.displacement_m = f32::NAN;
                }
                304 => s.disp_saturated = true,
                305 => s.displacement_m = 0.06, // beyond the 50 mm full scale
                _ => {}
            }
            s
        })
        .collect();
    let (out, frames) = run(
        dir.path(),
        &elf,
        "detector.ssvrlog",
        &LogHeader::for_scene(&scene),
        &input,
    );
    let setup = DetectorSetup::for_scene(&scene).unwrap();
    setup.check_firmware(&frames, scene.rate_hz).unwrap();
    let host = host_frames(&scene, &setup, &input, false).unwrap();
    assert_matches_host(&out, &input, &host);

    // The flags of the invalid samples.
    assert_eq!(
        out[300].flags & !ff::REVERSAL,
        ff::NOT_FINITE | ff::DISP_INVALID
    );
    assert_eq!(out[301].flags & !ff::REVERSAL, ff::NOT_FINITE);
    assert_eq!(out[302].flags & !ff::REVERSAL, ff::SATURATED);
    assert_eq!(
        out[303].flags & !ff::REVERSAL,
        ff::MISSING | ff::NOT_FINITE | ff::DISP_INVALID
    );
    assert_eq!(
        out[304].flags & !ff::REVERSAL,
        ff::SATURATED | ff::DISP_INVALID
    );
    assert_eq!(out[305].flags & !ff::REVERSAL, ff::DISP_INVALID);

    // The detector saw the slip start and the reversals (vertices every 27.4 ms), each pushed.
    let events: Vec<(usize, u8, i8, f32)> = out
        .iter()
        .enumerate()
        .filter_map(|(k, f)| f.event.map(|e| (k, e.kind, e.level, e.age_samples)))
        .collect();
    eprintln!("events (sample, kind, level, age): {events:?}");
    assert_eq!(events[0].1, event_kind::SLIP_START);
    let reversals: Vec<_> = events
        .iter()
        .filter(|e| e.1 == event_kind::REVERSAL)
        .collect();
    assert!(reversals.len() >= 4, "{events:?}");
    for &&(k, _, _, age) in &reversals {
        assert_ne!(out[k].flags & ff::REVERSAL, 0);
        let t = (k as f64 - f64::from(age)) / scene.rate_hz;
        let j = ((t - T0 - HALF) / (2.0 * HALF)).round();
        let tv = T0 + HALF + j * 2.0 * HALF;
        // The arcs are exact parabolas, so the vertex fits locate them closely.
        assert!(
            (t - tv).abs() < 1.0 / scene.rate_hz,
            "reversal at {t} vs {tv}"
        );
    }
    let stats = frames.iter().find(|f| f.kind() == "stats").unwrap();
    assert_eq!(stats.field("samples"), Some("2000"));
    assert_eq!(stats.field("dropped"), Some("0"));
    assert_eq!(stats.field("rejected"), Some("0"));
    assert_eq!(stats.field("invalid"), Some("6"));

    let ic = qemu_runner::instruction_counts(&frames).unwrap();
    assert_eq!(ic.reversal_errors, 0);
    // One tick per 40 instructions; the calibration reads the counter at an arbitrary phase of
    // its 40-instruction period, so each of its two readings is exact to ±1 tick.
    assert!(
        (ic.instructions_per_tick - 40.0).abs() < 40.0 * 1e-4,
        "instructions per SysTick tick: {}",
        ic.instructions_per_tick
    );
    let (flash, ram) = qemu_runner::elf_sizes(&elf).unwrap();
    eprintln!(
        "qemu image: estimator {:.2} instructions/sample, +{:?}/reversal; detector {:?}/sample, \
         +{:?}/reversal; whole step {:?}/sample; flash={flash} B ram={ram} B",
        ic.instructions_per_sample,
        ic.instructions_per_reversal,
        ic.detector_instructions_per_sample,
        ic.detector_instructions_per_reversal,
        ic.pipeline_instructions_per_sample
    );
    assert!(ic.instructions_per_sample > 0.0);
    assert!(ic.instructions_per_reversal.unwrap() > 0.0);
    assert!(ic.detector_instructions_per_sample.unwrap() > 0.0);
    assert!(ic.detector_instructions_per_reversal.unwrap() > 0.0);
}

const N: usize = 200;

/// Given reversals: +1 at sample 50 (age 0.25), −1 at 120 (age 0.5). Invalid samples: 10 (NaN
/// top accel), 11 (saturated), 12 (missing).
fn hook_samples() -> Vec<LogSample> {
    (0..N)
        .map(|k| {
            let t = k as f32 / 1e4;
            let mut s = LogSample {
                table_accel_m_s2: 2.0 * (2.0 * std::f32::consts::PI * 5.0 * t).sin(),
                base_accel_m_s2: 1.5 * (2.0 * std::f32::consts::PI * 5.0 * t).sin(),
                top_accel_m_s2: -0.5 + k as f32 * 1e-3,
                displacement_m: 1e-4 * k as f32,
                ..LogSample::default()
            };
            match k {
                10 => s.top_accel_m_s2 = f32::NAN,
                11 => s.saturated = true,
                12 => {
                    s.missing = true;
                    s.table_accel_m_s2 = f32::NAN;
                    s.base_accel_m_s2 = f32::NAN;
                    s.top_accel_m_s2 = f32::NAN;
                    s.displacement_m = f32::NAN;
                }
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
    let elf = build(dir.path());
    let input = hook_samples();
    let header = LogHeader {
        options: OPTION_LOG_REVERSALS,
        ..LogHeader::for_scene(&scene)
    };
    let (out, frames) = run(dir.path(), &elf, "hook.ssvrlog", &header, &input);
    let setup = DetectorSetup::for_scene(&scene).unwrap();
    let host = host_frames(&scene, &setup, &input, true).unwrap();
    assert_matches_host(&out, &input, &host);

    assert!(frames.iter().any(|f| f.kind() == "done"));
    let stats = frames.iter().find(|f| f.kind() == "stats").unwrap();
    assert_eq!(stats.field("samples"), Some("200"));
    assert_eq!(stats.field("reversals"), Some("2"));
    assert_eq!(stats.field("invalid"), Some("3"));
    for (k, f) in out.iter().enumerate() {
        let expected = match k {
            10 => ff::NOT_FINITE,
            11 => ff::SATURATED,
            12 => ff::MISSING | ff::NOT_FINITE | ff::DISP_INVALID,
            50 | 120 => ff::REVERSAL,
            _ => 0,
        };
        assert_eq!(f.flags, expected, "flags @{k}");
        if k == 50 || k == 120 {
            let e = f.event.unwrap();
            assert_eq!(e.kind, event_kind::LOG);
            assert_eq!(e.level, if k == 50 { 1 } else { -1 });
        } else {
            assert_eq!(f.event, None, "event @{k}");
        }
    }
    // At rest before the first reversal; within a few gμ afterwards.
    let gmu = scene.gmu() as f32;
    for (k, f) in out.iter().enumerate() {
        if k < 50 {
            assert_eq!(f.prediction_m_s2, 0.0, "prediction @{k}");
        } else {
            assert!(f.prediction_m_s2.abs() <= 4.0 * gmu, "prediction @{k}");
        }
    }
}

/// The stick-slip model through the log-reversal hook: events of every kind (a stick is level 0)
/// and age, one older than the history (clamped), invalid samples (a NaN, a saturated and a
/// missing top acceleration are not used for the μ identification), 2000 samples (the
/// identification runs on blocks of samples once they are history − 2 samples old). Every frame, the stats and μ̂ equal the
/// host's.
#[test]
fn qemu_image_stick_slip_model_matches_the_host() {
    if !qemu_tests_run() {
        return;
    }
    let scene = Scene::default_scene();
    let dir = tempfile::tempdir().unwrap();
    let elf = qemu_runner::build_for_scene_model(
        &qemu_runner::default_firmware_dir(),
        &scene,
        Model::StickSlip,
        dir.path(),
        false,
    )
    .unwrap()
    .qemu_elf;
    let setup = DetectorSetup::for_scene_model(&scene, Model::StickSlip).unwrap();
    let old = setup.max_age as f32 + 30.5;
    // (sample, level, age): slip, stick 20.5 samples back (the history is max_age + 2 = 39
    // samples with the phase detector), slip the other way, an event older than the history, a
    // stick on a sample boundary, a slip.
    assert!(setup.max_age > 21);
    let events = [
        (50, 1, 0.25),
        (400, 0, 20.5),
        (420, -1, 3.75),
        (900, 1, old),
        (1300, 0, 12.0),
        (1350, 1, 0.0),
    ];
    let n = 2000;
    let input: Vec<LogSample> = (0..n)
        .map(|k| {
            let t = k as f32 / 1e4;
            let mut s = LogSample {
                table_accel_m_s2: 2.0 * (2.0 * std::f32::consts::PI * 7.0 * t).sin(),
                base_accel_m_s2: 1.5 * (2.0 * std::f32::consts::PI * 7.0 * t).sin(),
                top_accel_m_s2: 1.8 * (2.0 * std::f32::consts::PI * 7.0 * t).cos(),
                displacement_m: 1e-6 * k as f32,
                ..LogSample::default()
            };
            match k {
                610 => s.top_accel_m_s2 = f32::NAN,
                611 => s.saturated = true,
                612 => {
                    s.missing = true;
                    s.table_accel_m_s2 = f32::NAN;
                    s.base_accel_m_s2 = f32::NAN;
                    s.top_accel_m_s2 = f32::NAN;
                    s.displacement_m = f32::NAN;
                }
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
    let header = LogHeader {
        options: OPTION_LOG_REVERSALS,
        ..LogHeader::for_scene(&scene)
    };
    let (out, frames) = run(dir.path(), &elf, "ss.ssvrlog", &header, &input);
    let host = host_run(&scene, &setup, Model::StickSlip, &input, true).unwrap();
    assert_matches_host(&out, &input, &host.frames);
    setup.check_model(&frames, Model::StickSlip).unwrap();

    let stats = frames.iter().find(|f| f.kind() == "stats").unwrap();
    assert_eq!(stats.field("reversals"), Some("6"));
    assert_eq!(stats.field("rejected"), Some("0"));
    assert_eq!(stats.field("clamped"), Some("1"));
    assert_eq!(host.clamped, 1);
    for &(k, _, _) in &events {
        assert_eq!(out[k].flags & ff::REVERSAL, ff::REVERSAL, "flags @{k}");
    }
    let mu = host_sim::qemu_cmd::firmware_mu(&frames).expect("mu estimate");
    let want = host.mu.expect("host mu");
    assert_eq!(mu, (want.mu, want.std, want.blocks));
    // Identification updates (one per block of `identify_every` sliding samples).
    assert!(want.blocks > 10, "{want:?}");
    let ic = qemu_runner::instruction_counts(&frames).unwrap();
    eprintln!(
        "stick-slip image: {:.2} instructions/sliding sample, {:?} stuck, {:?} without the \
         identification, +{:?}/event (age 0.5), +{:?}/event (age {:?})",
        ic.instructions_per_sample,
        ic.instructions_per_sample_stuck,
        ic.instructions_per_sample_without_identification,
        ic.instructions_per_reversal,
        ic.instructions_per_event_max_age,
        ic.max_event_age
    );
    assert_eq!(ic.reversal_errors, 0);
    // The pipeline's way (blocks): within the goal of 40 per steady-state sample.
    assert!(ic.block_size.is_some());
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
    let header = LogHeader {
        options: OPTION_LOG_REVERSALS,
        ..LogHeader::for_scene(&scene)
    };
    let s = [
        LogSample {
            table_accel_m_s2: 1.0,
            ..LogSample::default()
        },
        LogSample {
            missing: true,
            reversal: Some(LogReversal {
                level: -1,
                age_samples: 0.5,
            }),
            ..LogSample::default()
        },
        LogSample {
            disp_saturated: true,
            ..LogSample::default()
        },
    ];
    let b = qemu_runner::encode_sensor_log(&header, &s).unwrap();
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
        let text = qemu_runner::firmware_scene_toml(&scene);
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
    let elf = build(dir.path());
    let header = LogHeader {
        options: OPTION_LOG_REVERSALS,
        ..LogHeader::for_scene(&scene)
    };
    let good = qemu_runner::encode_sensor_log(&header, &hook_samples()).unwrap();
    let run = |name: &str, bytes: &[u8]| {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = qemu_runner::run_qemu_output(&elf, &path, Duration::from_secs(60)).unwrap();
        assert!(!out.timed_out, "{name} timed out");
        let frames = qemu_runner::decode_frames(&elf, &out.stdout).unwrap();
        (out.status, frames)
    };

    // sample_count = 0xFFFFFFFF: read to the end of the file.
    let mut until_eof = good.clone();
    until_eof[72..76].copy_from_slice(&u32::MAX.to_le_bytes());
    let (status, frames) = run("eof.ssvrlog", &until_eof);
    assert_eq!(status, Some(0));
    assert_eq!(qemu_runner::sample_frames(&frames).len(), N);

    // Bad magic: status 3.
    let mut bad_magic = good.clone();
    bad_magic[0] = b'X';
    assert_eq!(run("magic.ssvrlog", &bad_magic).0, Some(3));

    // A structure or rate other than the compiled-in scene's: status 7, the field named.
    let mut other_damping = good.clone();
    other_damping[48..56].copy_from_slice(&0.06f64.to_le_bytes());
    let (status, frames) = run("damping.ssvrlog", &other_damping);
    assert_eq!(status, Some(7));
    assert!(frames
        .iter()
        .any(|f| f.level.as_deref() == Some("error") && f.message.contains("damping_ratio")));
    let mut other_rate = good.clone();
    other_rate[16..24].copy_from_slice(&1000.0f64.to_le_bytes());
    assert_eq!(run("rate.ssvrlog", &other_rate).0, Some(7));

    // Truncated inside record 100 (header, 100 records, the reversal event of record 50, 3 bytes):
    // status 5, the first 100 frames were streamed.
    let cut = 80 + 100 * 17 + 5 + 3;
    let (status, frames) = run("cut.ssvrlog", &good[..cut]);
    assert_eq!(status, Some(5));
    assert_eq!(qemu_runner::sample_frames(&frames).len(), 100);
}
