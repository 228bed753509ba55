//! `host-sim qemu [SCENE] --json` end to end on short copies of the default scene (1 s) and of
//! the El Centro scene (its first 5 s): the firmware's QEMU image built for the scene, every
//! prediction compared with the host and the closed form, and the goals (firmware = host to
//! ≤ 1e-6·gμ, ≤ 20 instructions per steady-state sample, board image ≤ 32 KiB flash and ≤ 8 KiB
//! static RAM).
//!
//! Needs `qemu-system-arm` (skipped with a message when missing) and the `thumbv7em-none-eabihf`
//! target; the first run builds the firmware.

use assert_cmd::Command;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn qemu_available() -> bool {
    let ok = host_sim::qemu_runner::qemu_available();
    if !ok {
        eprintln!("SKIPPED: qemu-system-arm not found (apt-get install -y qemu-system-arm)");
    }
    ok
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

fn run_json(scene: &Path) -> Value {
    let out = Command::cargo_bin("host-sim")
        .unwrap()
        .args(["qemu", scene.to_str().unwrap(), "--json"])
        .timeout(std::time::Duration::from_secs(600))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    eprintln!("{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        out.status.success(),
        "host-sim qemu failed: {:?}",
        out.status
    );
    serde_json::from_str(&stdout).unwrap()
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("no number `{key}` in {v}"))
}

fn check_goals(v: &Value, samples: u64) {
    for key in [
        "samples",
        "max_err_vs_host_gmu",
        "max_err_vs_reference_gmu",
        "instructions_per_sample",
        "instructions_per_reversal",
        "flash_bytes",
        "ram_bytes",
        "reversals",
        "frames_flagged",
        "board_flash_bytes",
        "board_ram_bytes",
    ] {
        num(v, key);
    }
    assert!(v["scene"].is_string());
    assert_eq!(v["samples"].as_u64(), Some(samples));
    assert_eq!(v["passed"], Value::Bool(true));
    assert_eq!(v["frame_mismatches"].as_u64(), Some(0));
    // Firmware = host: bit-identical in practice, the goal is 1e-6 gμ.
    assert!(num(v, "max_err_vs_host_gmu") <= 1e-6);
    assert_eq!(num(v, "max_err_vs_host_gmu"), 0.0);
    // The f32 recursion against the f64 closed form on the same (detected) train.
    assert!(num(v, "max_err_vs_reference_gmu") < 1e-5);
    assert!(num(v, "reversals") >= 1.0);
    let ips = num(v, "instructions_per_sample");
    assert!(ips > 5.0 && ips <= 20.0, "instructions per sample {ips}");
    assert!(num(v, "instructions_per_reversal") > 0.0);
    assert!(num(v, "flash_bytes") > 0.0 && num(v, "ram_bytes") > 0.0);
    assert!(num(v, "board_flash_bytes") <= 32.0 * 1024.0);
    assert!(num(v, "board_ram_bytes") <= 8.0 * 1024.0);
    for goal in [
        "firmware_equals_host",
        "instructions_per_sample_le_20",
        "board_flash_le_32k",
        "board_ram_le_8k",
    ] {
        assert_eq!(v["goals"][goal], Value::Bool(true), "goal {goal}");
    }
}

#[test]
fn qemu_command_on_one_second_of_the_default_scene() {
    if !qemu_available() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = short_copy(dir.path(), "table1.toml", 1.0);
    let v = run_json(&scene);
    check_goals(&v, 10_000);
    assert_eq!(v["scene"], "table 1 specimen");
}

#[test]
fn qemu_command_on_the_first_five_seconds_of_el_centro() {
    if !qemu_available() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scene = short_copy(dir.path(), "elcentro.toml", 5.0);
    let v = run_json(&scene);
    check_goals(&v, 50_000);
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
