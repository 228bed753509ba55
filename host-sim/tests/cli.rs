//! Command-line tests of `host-sim` on scenes written to temporary files.

mod common;
use assert_cmd::Command;
use std::path::{Path, PathBuf};

const HARMONIC: &str = r#"name = "cli harmonic"
duration_s = 0.5
[structure]
m1_kg = 29.5
m2_kg = 1.75
natural_frequency_hz = 7.0
damping_ratio = 0.05
friction_coefficient = 0.2
[input]
kind = "harmonic"
amplitude_m_s2 = 2.0
period_s = 0.143
[sampling]
rate_hz = 1000.0
"#;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn host_sim() -> Command {
    Command::cargo_bin("host-sim").unwrap()
}

fn json(out: &[u8]) -> serde_json::Value {
    serde_json::from_slice(out).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(out)))
}

#[test]
fn peak_json_fields() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "h.toml", HARMONIC);
    for method in ["tfm", "rfm"] {
        let out = host_sim()
            .args([
                "peak",
                scene.to_str().unwrap(),
                "--method",
                method,
                "--json",
            ])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v = json(&out.stdout);
        assert_eq!(v["sliding"], true);
        assert_eq!(v["method"], method);
        assert_eq!(v["scene"], "cli harmonic");
        let peak = v["peak_m_s2"].as_f64().unwrap();
        assert!(peak > 1.96 && peak < 5.0, "{peak}");
        assert!(v["beta"].as_f64().unwrap() > 9.0);
        assert!(v["harmonics"].as_u64().unwrap() >= 16);
        let alpha = v["alpha_rad"].as_f64().unwrap();
        if method == "rfm" {
            assert_eq!(alpha, 0.0);
        } else {
            assert!(alpha > 0.0);
        }
    }
    // A fixed harmonic count.
    let out = host_sim()
        .args([
            "peak",
            scene.to_str().unwrap(),
            "--method",
            "tfm",
            "--harmonics",
            "5",
            "--json",
        ])
        .output()
        .unwrap();
    assert_eq!(json(&out.stdout)["harmonics"], 5);
    // No sliding: the fixed-base peak, alpha null.
    let still = write(
        dir.path(),
        "still.toml",
        &HARMONIC
            .replace("amplitude_m_s2 = 2.0", "amplitude_m_s2 = 0.1")
            .replace("period_s = 0.143", "period_s = 1.0"),
    );
    let out = host_sim()
        .args(["peak", still.to_str().unwrap(), "--method", "rfm", "--json"])
        .output()
        .unwrap();
    let v = json(&out.stdout);
    assert_eq!(v["sliding"], false);
    assert!(v["alpha_rad"].is_null());
    assert!((v["peak_m_s2"].as_f64().unwrap() - 0.1).abs() < 0.01);
}

#[test]
fn peak_of_a_non_harmonic_scene_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(
        dir.path(),
        "r.toml",
        &HARMONIC.replace(
            "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
            "kind = \"reversals\"\nhalf_period_s = 0.0715",
        ),
    );
    let out = host_sim()
        .args(["peak", scene.to_str().unwrap(), "--method", "tfm"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("harmonic") && err.contains("reversals"),
        "{err}"
    );
}

#[test]
fn bad_scene_names_file_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(
        dir.path(),
        "bad.toml",
        &HARMONIC.replace("damping_ratio = 0.05", "damping_ratio = 1.2"),
    );
    let out = host_sim()
        .args(["check", scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!(
            "{}:7: [structure] damping_ratio = 1.2",
            scene.display()
        )),
        "{err}"
    );
}

#[test]
fn trace_header_stride_and_precision() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "h.toml", HARMONIC);
    let s = scene.to_str().unwrap();
    let run = |args: &[&str]| {
        let out = host_sim().args(args).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let closed = run(&["trace", s, "--method", "rdm-closed", "--stride", "7"]);
    let lines: Vec<&str> = closed.lines().collect();
    assert_eq!(lines[0], "t_s,top_accel_m_s2");
    // 500 samples, k = 0, 7, …, 497: 72 rows.
    assert_eq!(lines.len(), 1 + 72);
    assert!(lines[1].starts_with("0,"));
    let row = |l: &str| -> (f64, f64) {
        let (t, y) = l.split_once(',').unwrap();
        (t.parse().unwrap(), y.parse().unwrap())
    };
    assert_eq!(row(lines[2]).0, 0.007);
    assert_eq!(row(lines[72]).0, 0.497);
    let rec = run(&["trace", s, "--method", "rdm-recursion", "--stride", "7"]);
    let rec32 = run(&[
        "trace",
        s,
        "--method",
        "rdm-recursion",
        "--precision",
        "f32",
        "--stride",
        "7",
    ]);
    let (mut d64, mut d32) = (0.0f64, 0.0f64);
    for ((a, b), c) in closed.lines().zip(rec.lines()).zip(rec32.lines()).skip(1) {
        let ((ta, ya), (tb, yb), (tc, yc)) = (row(a), row(b), row(c));
        assert_eq!(ta, tb);
        assert_eq!(ta, tc);
        d64 = common::max_finite(d64, (ya - yb).abs(), "f64 recursion − closed form", ta);
        d32 = common::max_finite(d32, (ya - yc).abs(), "f32 recursion − closed form", ta);
    }
    println!("trace: max |recursion − closed form| f64 {d64:.2e} m/s², f32 {d32:.2e} m/s²");
    // Measured 6.2e-15 and 2.4e-7 m/s².
    assert!(d64 < 3e-14, "{d64}");
    assert!(d32 < 1e-6, "{d32}");
    // TFM/RFM traces, to a file.
    let out = dir.path().join("tfm.csv");
    run(&[
        "trace",
        s,
        "--method",
        "tfm",
        "--stride",
        "100",
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(text.lines().count(), 1 + 5);
    assert_eq!(text.lines().next(), Some("t_s,top_accel_m_s2"));
    let rfm = run(&["trace", s, "--method", "rfm", "--harmonics", "3"]);
    assert_eq!(rfm.lines().count(), 1 + 500);
}

#[test]
fn check_json_fields() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(
        dir.path(),
        "r.toml",
        &HARMONIC.replace(
            "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
            "kind = \"reversals\"\ntimes_s = [0.0, 0.07153, 0.1431, 0.25, 0.30005]\ninitial_sign = -1",
        ),
    );
    for precision in ["f32", "f64"] {
        let out = host_sim()
            .args([
                "check",
                scene.to_str().unwrap(),
                "--precision",
                precision,
                "--json",
            ])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v = json(&out.stdout);
        assert_eq!(v["samples"], 500);
        assert_eq!(v["compared_samples"], 500);
        assert_eq!(v["reversals"], 5);
        assert_eq!(v["precision"], precision);
        let max = v["max_err_gmu"].as_f64().unwrap();
        let rms = v["rms_err_gmu"].as_f64().unwrap();
        println!("check {precision}: max {max:.2e} gμ, rms {rms:.2e} gμ");
        // Measured: f32 2.3e-7 gμ, f64 3.6e-15 gμ.
        let bound = if precision == "f32" { 1e-6 } else { 2e-14 };
        assert!(rms <= max && max < bound, "{max} {rms}");
        let at = v["max_err_at_s"].as_f64().unwrap();
        assert!((0.0..0.5).contains(&at));
    }
}
