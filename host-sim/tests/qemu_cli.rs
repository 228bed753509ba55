//! `host-sim qemu [SCENE] [--model MODEL] --json` end to end on short copies of the default scene
//! (1–2 s) and of the El Centro scene (its first 5 s): the firmware's QEMU image built for the
//! scene and the estimator model, every prediction compared with the host and a full-precision
//! reference, and the goals (firmware = host to ≤ 1e-6·gμ; board image ≤ 100 KiB flash and
//! ≤ 8 KiB static RAM; the instruction counts measured; the model as the pipeline runs it, all
//! identification on, ≤ 50 instructions per steady sample).
//!
//! * the rectangular model (`--model rectangular`): ≤ 20 instructions per steady-state sample,
//!   the closed form as the reference;
//! * the stick-slip model, which `model::choose` picks for both scenes (they stick): the f64
//!   stick-slip estimator as the reference, μ̂ from the firmware.
//!
//! Needs `qemu-system-arm` (or `$QEMU_SYSTEM_ARM`) and the `thumbv7em-none-eabihf` target; CI
//! installs both. Without them the tests fail; `SSVR_SKIP_QEMU=1` skips them explicitly (each
//! prints "SKIPPED"). The first run builds the firmware.

mod common;
use assert_cmd::Command;
use common::qemu_tests_run;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// A copy of `scenes/<name>` with `duration_s` replaced and record paths made absolute.
fn short_copy(dir: &Path, name: &str, duration_s: f64) -> PathBuf {
    let text = std::fs::read_to_string(scenes_dir().join(name)).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        let key = line.split('=').next().unwrap_or("").trim();
        match key {
            "duration_s" => out.push_str(&format!("duration_s = {duration_s:?}\n")),
            "file" => {
                let file = line.split('"').nth(1).unwrap();
                let abs = scenes_dir().join(file);
                out.push_str(&format!("file = {:?}\n", abs.to_str().unwrap()));
            }
            _ => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    let path = dir.join(name);
    std::fs::write(&path, out).unwrap();
    path
}

fn run_json(scene: &Path, model: Option<&str>) -> Value {
    run_json_mode(scene, model, None)
}

/// [`run_json`] with `--mode`.
fn run_json_mode(scene: &Path, model: Option<&str>, mode: Option<&str>) -> Value {
    let (ok, v) = run_json_status(scene, model, mode);
    assert!(ok, "host-sim qemu failed");
    v
}

/// The report, and whether the command succeeded (every goal it prints met).
fn run_json_status(scene: &Path, model: Option<&str>, mode: Option<&str>) -> (bool, Value) {
    let mut args = vec!["qemu", scene.to_str().unwrap(), "--json"];
    if let Some(m) = model {
        args.extend(["--model", m]);
    }
    if let Some(m) = mode {
        args.extend(["--mode", m]);
    }
    let out = Command::cargo_bin("host-sim")
        .unwrap()
        .args(&args)
        .timeout(std::time::Duration::from_secs(600))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!("{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    (out.status.success(), serde_json::from_str(&stdout).unwrap())
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("no number `{key}` in {v}"))
}

/// What every model's report must show.
fn check_common(v: &Value, samples: u64) {
    for key in [
        "samples",
        "max_err_vs_host_gmu",
        "max_err_vs_reference_gmu",
        "instructions_per_sample",
        "flash_bytes",
        "ram_bytes",
        "reversals",
        "frames_flagged",
        "board_flash_bytes",
        "board_ram_bytes",
    ] {
        num(v, key);
    }
    assert!(v["scene"].is_string() && v["model"].is_string());
    assert!(v.get("mu_estimate").is_some());
    assert_eq!(v["samples"].as_u64(), Some(samples));
    assert_eq!(v["passed"], Value::Bool(true));
    assert_eq!(v["frame_mismatches"].as_u64(), Some(0));
    assert_eq!(v["mu_equals_host"], Value::Bool(true));
    // Firmware = host: bit-identical in practice, the goal is 1e-6 gμ.
    assert!(num(v, "max_err_vs_host_gmu") <= 1e-6);
    assert_eq!(num(v, "max_err_vs_host_gmu"), 0.0);
    assert!(num(v, "reversals") >= 1.0);
    assert!(num(v, "flash_bytes") > 0.0 && num(v, "ram_bytes") > 0.0);
    assert!(num(v, "board_flash_bytes") <= num(&v["goals"], "board_flash_budget_bytes"));
    // Measured 91 984 B (stick-slip, fuse, Coulomb, with the offsets' identification from the
    // sliding phases and the open-loop starts (the top's, and predict mode's table start against
    // the plan with its state correction: +2.0 KB), the table's gain against the displacement, the
    // top's gain from the stuck phases, f and ξ from the input's start, the first slides'
    // friction from the slip starts and the M of either mode: 51 172 B without them; +1.5 KB in
    // the eleventh session for speed: the open-loop start's runs apart from the steady ones, the
    // least squares' rows written out; +3.7 KB in the twelfth for predict mode's table start
    // allowing for the table's lag, once per run in f64; +1.4 KB in the thirteenth for the top's
    // curved start below ~4.4 kHz and +1.7 KB for the events' steps in the oscillator
    // identification; +4.1 KB in the fourteenth for missing samples at coarse rates (their
    // indices kept, the jump test after a gap, the gap refilled, fills held after a jump) and
    // strong jump breakaways confirmed at their second sample (the sliding side a sample
    // later, through the pipeline to the model); +0.7 KB in the seventeenth for the events'
    // kinks (two samples corrected at an event) and +1.3 KB for the rescaling at the table
    // gain's adoption and the base's offset in the table's units; +0.9 KB in the eighteenth
    // for predict mode's friction from a late sliding side, the slide re-run with it (99 252 B
    // on the default scene); the velocity-dependent law is compiled in only for a scene with
    // one); the budget is 100 KiB, bounded here a little above the measured size so that a
    // regression fails.
    assert!(num(v, "board_flash_bytes") <= 97.2 * 1024.0);
    assert!(num(v, "board_ram_bytes") <= 8.0 * 1024.0);
    // The model as the pipeline runs it, all identification on, against the budget of
    // 50 instructions per steady sample (reported, not met by the stick-slip and fixed-base
    // models): measured 164.3 in fuse mode and 136.7 in predict mode (252.3 and 199.9 before
    // the eleventh session's work on the samples' path: docs/PERFORMANCE.md; 96.8 before the
    // offsets' identification from the sliding phases), fixed-base 93.8, rectangular 22.9. The
    // compiler's inlining and the structures' layout move these by a few (the model's and the
    // base tuning's layouts are fixed, `repr(C)`). Bounded a little above the measured figures,
    // so a regression fails.
    let model = num(v, "instructions_per_steady_sample_model");
    println!(
        "{} model ({} mode) as the pipeline runs it: {model:.2} instructions per steady sample \
         (estimator {:.2})",
        v["model"],
        v["mode"],
        num(v, "instructions_per_steady_sample")
    );
    let bound = match (v["model"].as_str(), v["mode"].as_str()) {
        (Some("rectangular"), _) => 25.0,
        (Some("fixed-base"), _) => 100.0,
        (_, Some("predict")) => 145.0,
        _ => 175.0,
    };
    assert!(
        model.is_finite() && model > 0.0 && model <= bound,
        "model as the pipeline runs it: {model} instructions per steady sample"
    );
    assert_eq!(
        v["goals"]["model_instructions_per_sample_le_50"],
        Value::Bool(model <= 50.0)
    );
    assert_eq!(num(v, "model_adoptions"), 0.0, "adoptions while timed");
    for goal in [
        "firmware_equals_host",
        "plan_equals_host",
        "reference_error_le_goal",
        "board_flash_le_budget",
        "board_ram_le_8k",
    ] {
        assert_eq!(v["goals"][goal], Value::Bool(true), "goal {goal}");
    }
}

/// The rectangular model's report.
fn check_rectangular(v: &Value, samples: u64) {
    check_common(v, samples);
    assert_eq!(v["model"], "rectangular");
    assert_eq!(v["mu_estimate"], Value::Null);
    // The f32 recursion against the f64 closed form on the same (detected) train (measured 3.3e-7
    // gμ on the default scene, 3.4e-7 gμ on El Centro).
    assert!(num(v, "max_err_vs_reference_gmu") < 1e-6, "{v}");
    let ips = num(v, "instructions_per_sample");
    assert!(ips > 5.0 && ips <= 20.0, "instructions per sample {ips}");
    assert!(num(v, "instructions_per_reversal") > 0.0);
    // The model as the pipeline runs it: the recursion and the run's bookkeeping, no
    // identification.
    assert_eq!(v["model_tuning"], Value::Bool(false));
    let slide = num(v, "instructions_per_sample_model_sliding");
    let stuck = num(v, "instructions_per_sample_model_stuck");
    assert_eq!(
        num(v, "instructions_per_steady_sample_model"),
        slide.max(stuck)
    );
    for goal in [
        "instructions_per_sample_le_20",
        "instructions_per_sample_le_goal",
    ] {
        assert_eq!(v["goals"][goal], Value::Bool(true), "goal {goal}");
    }
}

/// Relative tolerance of the firmware's μ̂ against the scene's μ. Measured: 0.1999857 on 2 s of
/// the default scene and 0.1999834 on 5 s of El Centro (7.2e-5 and 8.3e-5 relative, μ std
/// 2.9e-5 and 3.2e-5, from 240 and 356 identification updates).
const MU_REL_TOL: f64 = 3e-4;

/// The stick-slip model's report: the f64 stick-slip estimator as the reference, the measured
/// instruction counts (the goal of 40 per sample: met, see docs/PERFORMANCE.md), μ̂ against the
/// scene's friction coefficient `mu`.
fn check_stick_slip(v: &Value, samples: u64, mu: f64) {
    check_common(v, samples);
    assert_eq!(v["model"], "stick-slip");
    assert!(num(v, "history") >= 2.0);
    // The f32 estimator against the f64 one on the same detected events and inputs (measured
    // 1.0e-6 gμ on the default scene, 1.2e-6 gμ on El Centro).
    assert!(num(v, "max_err_vs_reference_gmu") < 3e-6, "{v}");
    // μ identified from the measured top acceleration while sliding.
    let mu_hat = num(v, "mu_estimate");
    println!(
        "mu {mu_hat} ± {} from {} updates ({:.2e} relative)",
        num(v, "mu_std"),
        num(v, "mu_samples"),
        mu_hat / mu - 1.0
    );
    assert!(num(v, "mu_samples") > 0.0 && num(v, "mu_std") > 0.0, "{v}");
    assert!(
        (mu_hat / mu - 1.0).abs() < MU_REL_TOL,
        "mu {mu_hat} vs the scene's {mu}"
    );
    // Measured (docs/PERFORMANCE.md): in blocks of 16 (the pipeline's way) 34.7 per sliding
    // sample with the μ identification and 36.7 per stuck sample; one update() at a time 39.4
    // sliding and 63.2 stuck, 34 sliding without the identification; ~878 per event at age 0.5.
    assert_eq!(num(v, "block_size"), 16.0);
    let slide = num(v, "instructions_per_sample_in_blocks");
    assert!(slide > 15.0 && slide <= 40.0, "sliding in blocks {slide}");
    let stuck_blocks = num(v, "instructions_per_sample_stuck_in_blocks");
    assert!(
        stuck_blocks > 15.0 && stuck_blocks <= 40.0,
        "stuck in blocks {stuck_blocks}"
    );
    assert_eq!(
        num(v, "instructions_per_steady_sample"),
        slide.max(stuck_blocks)
    );
    // One `update()` at a time while sliding (not the pipeline's path, which runs blocks):
    // measured 52.6 with the sliding observer's correction and its finiteness test (39.2
    // before it).
    let ips = num(v, "instructions_per_sample");
    assert!(ips > 20.0 && ips <= 56.0, "instructions per sample {ips}");
    let stuck = num(v, "instructions_per_sample_stuck");
    assert!(stuck > 20.0 && stuck <= 70.0, "stuck {stuck}");
    let bare = num(v, "instructions_per_sample_without_identification");
    assert!(bare > 20.0 && bare <= ips, "without identification {bare}");
    let ev = num(v, "instructions_per_reversal");
    assert!(ev > 0.0 && ev < 1500.0, "per event {ev}");
    assert!(num(v, "instructions_per_event_max_age") > ev);
    assert_eq!(
        v["goals"]["instructions_per_sample_goal"].as_f64(),
        Some(40.0)
    );
    // The model as the pipeline runs it (fuse mode: f and ξ identified online): the estimator's
    // blocks and more.
    assert_eq!(v["model_tuning"], Value::Bool(true));
    let model_slide = num(v, "instructions_per_sample_model_sliding");
    let model_stuck = num(v, "instructions_per_sample_model_stuck");
    assert!(model_slide > slide, "model sliding {model_slide}");
    assert!(model_stuck > stuck_blocks, "model stuck {model_stuck}");
    assert_eq!(
        num(v, "instructions_per_steady_sample_model"),
        model_slide.max(model_stuck)
    );
    assert_eq!(
        v["goals"]["instructions_per_sample_le_goal"],
        Value::Bool(true)
    );
}

#[test]
fn qemu_command_rectangular_on_one_second_of_the_default_scene() {
    if !qemu_tests_run() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = short_copy(dir.path(), "table1.toml", 1.0);
    let v = run_json(&scene, Some("rectangular"));
    check_rectangular(&v, 10_000);
    assert_eq!(v["scene"], "table 1 specimen");
    assert_eq!(v["model_reason"], "chosen with --model");
}

#[test]
fn qemu_command_rectangular_on_the_first_five_seconds_of_el_centro() {
    if !qemu_tests_run() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = short_copy(dir.path(), "elcentro.toml", 5.0);
    let v = run_json(&scene, Some("rectangular"));
    check_rectangular(&v, 50_000);
}

#[test]
fn qemu_command_stick_slip_on_two_seconds_of_the_default_scene() {
    if !qemu_tests_run() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = short_copy(dir.path(), "table1.toml", 2.0);
    // The base sticks twice per cycle: `model::choose` picks the stick-slip model.
    let v = run_json(&scene, None);
    // μ = 0.2 in table1.toml.
    check_stick_slip(&v, 20_000, 0.2);
    assert_ne!(v["model_reason"], "chosen with --model");
}

/// Fuse mode with m1 told 5 % high: M is taken from the momentum balance within the 2 s (the
/// run's error 0.100 → 0.041 % RMS on the host), and the firmware, which retunes with it, stays
/// the host bit for bit (a version that deferred M to a run starting stuck took it at another
/// sample in batches of 16 than one sample at a time: 2.8e-5 gμ apart); the f64 reference,
/// retuned with the same m1, measured 4.0e-7 gμ.
#[test]
fn qemu_command_fuse_mode_takes_m_with_m1_told_5_percent_high() {
    if !qemu_tests_run() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = short_copy(dir.path(), "table1.toml", 2.0);
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(
        !text.contains("[estimator]"),
        "table1.toml tells no prior of its own"
    );
    let text = text.replacen(
        "[structure]",
        "[estimator]\nm1_kg = 30.975\n\n[structure]",
        1,
    );
    std::fs::write(&scene, text).unwrap();
    let v = run_json(&scene, None);
    check_stick_slip(&v, 20_000, 0.2);
    assert!(num(&v, "max_err_vs_reference_gmu") <= 2e-6);
}

/// Predict mode without a rest, every accelerometer 0.05 g off (table +, base −, top +), on
/// 2 s of El Centro: the table's offset from the input's start against the plan (the plan's
/// planned start reaches the image through `SSVR_PLANNED_START`: the same digest as the host's),
/// and the firmware is the host bit for bit; the f64 reference (its own table start) measured
/// 3.2e-6 gμ (9.8e-7 before the start allowed for the table's lag: El Centro's first
/// acceleration now leaves the offset a0/2 off, and the stuck 2 s carry it; `check_common`:
/// frames, digest, μ).
#[test]
fn qemu_command_predict_mode_finds_the_table_offset_at_the_start() {
    if !qemu_tests_run() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = short_copy(dir.path(), "elcentro.toml", 2.0);
    let text = std::fs::read_to_string(&scene).unwrap();
    let text = text.replacen(
        "[sensors]",
        "[sensors]\naccel_bias_m_s2 = [0.4903325, -0.4903325, 0.4903325]",
        1,
    );
    std::fs::write(&scene, text).unwrap();
    let v = run_json_mode(&scene, Some("stick-slip"), Some("predict"));
    check_common(&v, 20_000);
    assert_eq!(v["model"], "stick-slip");
    assert!(num(&v, "max_err_vs_reference_gmu") < 4e-6, "{v}");
}

/// At 1 kHz the open-loop start is 10 samples over 0.44 rad of p (the curved start: fuse mode
/// fits the top's offset beside the model's response to the table's; predict mode's table start
/// runs over the same 10 samples): `lab-offsets-no-rest.toml` (every accelerometer 0.05 g off,
/// gains 1 % off, 1 % dropped frames, μ told 10 % high) at 1 kHz, 2 s, both modes. The firmware
/// is the host bit for bit; the f64 reference measured 2.10e-6 gμ (fuse; 1.59e-6 with the wide
/// sliding observer capped at 0.1 rad per sample instead of 0.5, 1.08e-6 before the dropped
/// frames' gaps were refilled) and 6.9e-7 (predict). Fuse mode misses the estimator's steady-sample goal of 40 at 1 kHz (116.8: the
/// identifications' 500 Hz blocks come every other sample), the one goal the command may fail
/// on here.
#[test]
fn qemu_command_runs_the_curved_start_at_1_khz() {
    if !qemu_tests_run() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = short_copy(dir.path(), "lab-offsets-no-rest.toml", 2.0);
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(text.contains("rate_hz = 10000.0"));
    std::fs::write(
        &scene,
        text.replace("rate_hz = 10000.0", "rate_hz = 1000.0"),
    )
    .unwrap();
    for (mode, bound) in [("fuse", 2.4e-6), ("predict", 8e-7)] {
        let (ok, v) = run_json_status(&scene, Some("stick-slip"), Some(mode));
        let g = &v["goals"];
        assert_eq!(g["firmware_equals_host"], true, "{mode}: {v}");
        assert_eq!(g["reference_error_le_goal"], true, "{mode}: {v}");
        assert_eq!(g["plan_equals_host"], true, "{mode}: {v}");
        assert_eq!(g["board_flash_le_budget"], true, "{mode}: {v}");
        assert_eq!(g["board_ram_le_8k"], true, "{mode}: {v}");
        assert!(
            ok || g["instructions_per_sample_le_goal"] == false,
            "{mode}: {v}"
        );
        assert_eq!(num(&v, "samples"), 2_000.0);
        assert_eq!(num(&v, "max_err_vs_host_gmu"), 0.0);
        assert_eq!(num(&v, "frame_mismatches"), 0.0);
        assert!(num(&v, "max_err_vs_reference_gmu") < bound, "{mode}: {v}");
    }
}

#[test]
fn qemu_command_stick_slip_on_the_first_five_seconds_of_el_centro() {
    if !qemu_tests_run() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = short_copy(dir.path(), "elcentro.toml", 5.0);
    let v = run_json(&scene, None);
    // μ = 0.2 in elcentro.toml (μs = 0.25).
    check_stick_slip(&v, 50_000, 0.2);
}

#[test]
fn qemu_command_without_qemu_says_how_to_install_it() {
    let out = Command::cargo_bin("host-sim")
        .unwrap()
        .args(["qemu", "--json"])
        .env("QEMU_SYSTEM_ARM", "/nonexistent/qemu-system-arm")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("apt-get install -y qemu-system-arm"),
        "stderr: {err}"
    );
}
