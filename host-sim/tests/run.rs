//! `host-sim run`: CSV header, row count and flushing, JSON fields, detection on the default scene,
//! a record scene, errors, and no command = `run` on the built-in default scene.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

const HEADER: &str = "t_s,table_accel_m_s2,base_accel_m_s2,measured_top_accel_m_s2,rel_disp_m,reversal,predicted_top_accel_m_s2,truth_top_accel_m_s2,ideal_predicted_top_accel_m_s2,truth_slip_m,truth_slip_dir,detected_event,event_age_samples,flags";

const SHORT: &str = r#"name = "short harmonic"
duration_s = 0.8
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
rate_hz = 5000.0
"#;

fn host_sim() -> Command {
    Command::cargo_bin("host-sim").unwrap()
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn json(out: &[u8]) -> serde_json::Value {
    serde_json::from_slice(out).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(out)))
}

fn ok(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "status {:?}\nstdout: {}\nstderr: {}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Header, then one complete row per sample.
fn check_csv(path: &Path, samples: usize) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(HEADER));
    let cols = HEADER.split(',').count();
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), samples);
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r.len(), cols, "row {k}: {r:?}");
    }
    assert!(text.ends_with('\n'));
    rows
}

#[test]
fn csv_header_rows_default_path_and_summary() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "short.toml", SHORT);
    let out = host_sim()
        .args(["run", scene.to_str().unwrap()])
        .output()
        .unwrap();
    ok(&out);
    // Default output: <scene-stem>.run.csv next to the scene.
    let csv = dir.path().join("short.run.csv");
    let rows = check_csv(&csv, 4000);
    assert_eq!(rows[0][0], "0");
    assert_eq!(rows[1][0], "0.0002");
    assert_eq!(rows[3999][0], "0.7998");
    for r in &rows {
        assert!(["-1", "0", "1"].contains(&r[5].as_str()), "{r:?}");
        for c in [1, 2, 3, 4, 6, 7, 8, 9] {
            let v: f64 = r[c].parse().unwrap();
            assert!(v.is_finite());
        }
    }
    let text = String::from_utf8_lossy(&out.stdout);
    for s in [
        "short harmonic",
        "peak |ü1|",
        "max |error|",
        "latency",
        "short.run.csv",
    ] {
        assert!(text.contains(s), "{s:?} missing from:\n{text}");
    }
}

#[test]
fn json_fields_and_out_option() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "short.toml", SHORT);
    let csv = dir.path().join("sub.csv");
    let out = host_sim()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            csv.to_str().unwrap(),
            "--json",
        ])
        .output()
        .unwrap();
    ok(&out);
    let v = json(&out.stdout);
    assert_eq!(v["samples"], 4000);
    assert_eq!(v["out"], csv.to_str().unwrap());
    for k in [
        "peak_top_accel_m_s2",
        "max_abs_slip_m",
        "final_slip_m",
        "slip_phases",
    ] {
        assert!(v["truth"][k].is_number(), "truth.{k}: {v}");
    }
    for k in [
        "max_err_m_s2",
        "rms_err_m_s2",
        "reversals_detected",
        "reversals_true",
    ] {
        assert!(v["estimator"][k].is_number(), "estimator.{k}: {v}");
    }
    for k in [
        "missed",
        "false",
        "latency_mean_ms",
        "latency_max_ms",
        "timing_err_rms_ms",
        "timing_err_max_ms",
    ] {
        assert!(v["detection"][k].is_number(), "detection.{k}: {v}");
    }
    assert_eq!(v["estimator"]["precision"], "f32");
    assert_eq!(v["estimator"]["on_stick"], "keep");
    check_csv(&csv, 4000);
}

/// The built-in default scene (10 s at 10 kHz): the measured figures of the report.
#[test]
fn default_scene_detection_and_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = host_sim()
        .current_dir(dir.path())
        .args(["run", "--json"])
        .output()
        .unwrap();
    ok(&out);
    let v = json(&out.stdout);
    assert_eq!(v["out"], "default.run.csv");
    check_csv(&dir.path().join("default.run.csv"), 100_000);
    let e = &v["estimator"];
    let d = &v["detection"];
    let detected = e["reversals_detected"].as_f64().unwrap();
    let truth = e["reversals_true"].as_f64().unwrap();
    // Measured: 140 detected, 140 true (the base sticks twice per cycle: 140 slip starts), none
    // missed, none false.
    assert!(truth >= 100.0, "{v}");
    assert_eq!(detected, truth, "{v}");
    assert_eq!(d["missed"], 0, "{v}");
    assert_eq!(d["false"], 0, "{v}");
    // The stick-slip model's detector works on the slip acceleration (base − table
    // accelerometer). Measured: latency mean 0.35 ms, max 0.42 ms; event-time error rms 3.4 µs,
    // max 9 µs.
    assert_eq!(v["detector"]["kind"], "slip-acceleration", "{v}");
    assert!(d["latency_max_ms"].as_f64().unwrap() < 1.0, "{v}");
    assert!(d["timing_err_max_ms"].as_f64().unwrap() < 0.05, "{v}");
    assert_eq!(e["sticks_detected"], e["sticks_true"], "{v}");
    // The base sticks ~57 % of the time: the stick-slip model is chosen. Measured: rms 0.00042
    // m/s² (0.016 % of the 2.60 m/s² peak), max 0.068 %; the paper's rectangular model on the
    // same events 1.81 m/s² (69 %); the stick-slip model fed the exact events 0.00041 m/s² rms.
    assert_eq!(e["model"], "stick-slip", "{v}");
    let peak = v["truth"]["peak_top_accel_m_s2"].as_f64().unwrap();
    assert!((peak - 2.6016).abs() < 1e-3, "{v}");
    let rms_err = e["rms_err_m_s2"].as_f64().unwrap();
    let rect_rms = e["rectangular_rms_err_m_s2"].as_f64().unwrap();
    assert!(rms_err < 1e-3 * peak, "{v}");
    assert!(e["max_err_pct_of_peak"].as_f64().unwrap() < 0.5, "{v}");
    assert!(rect_rms > 1.5 && rect_rms < 2.2, "{v}");
    assert!(
        e["ideal_rms_err_m_s2"].as_f64().unwrap() < 1e-3 * peak,
        "{v}"
    );
    // μ identified within 0.1 % (measured 0.199948: 2.6e-4 relative).
    let mu = e["mu_estimate"].as_f64().unwrap();
    assert!((mu / 0.2 - 1.0).abs() < 1e-3, "{v}");
    // The accelerometer itself is within a few noise RMS of the truth.
    assert!(e["measured_max_err_m_s2"].as_f64().unwrap() < 0.05, "{v}");
}

/// El Centro (a record scene with μs > μ), shortened to 6 s.
#[test]
fn record_scene_runs() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = std::fs::read_to_string(scenes.join("elcentro.toml"))
        .unwrap()
        .replace("duration_s = 32.0", "duration_s = 6.0");
    assert!(text.contains("duration_s = 6.0"));
    write(dir.path(), "ec.toml", &text);
    std::fs::copy(
        scenes.join("elcentro-1940-ns.txt"),
        dir.path().join("elcentro-1940-ns.txt"),
    )
    .unwrap();
    let out = host_sim()
        .current_dir(dir.path())
        .args(["run", "ec.toml", "--json", "--plot", "ec.svg"])
        .output()
        .unwrap();
    ok(&out);
    let v = json(&out.stdout);
    assert_eq!(v["input"], "record");
    assert_eq!(v["samples"], 60_000);
    check_csv(&dir.path().join("ec.run.csv"), 60_000);
    let e = &v["estimator"];
    let truth = e["reversals_true"].as_u64().unwrap();
    let detected = e["reversals_detected"].as_u64().unwrap();
    // Measured on the first 6 s: 20 slip starts true, 20 detected, all matched; 20 sticks true, 18
    // detected; max error 4.58 m/s², rms 1.67 m/s² (peak 2.76 m/s²).
    assert!(truth >= 10, "{v}");
    assert!(detected.abs_diff(truth) as f64 <= 0.1 * truth as f64, "{v}");
    assert!(e["sticks_true"].as_u64().unwrap() >= 10, "{v}");
    let svg = std::fs::read_to_string(dir.path().join("ec.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("slip, base to table (mm)"));
}

#[test]
fn png_plot_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "short.toml", SHORT);
    let png = dir.path().join("p.png");
    let out = host_sim()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--plot",
            png.to_str().unwrap(),
            "--plot-window",
            "0.5",
        ])
        .output()
        .unwrap();
    ok(&out);
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.starts_with(b"\x89PNG"));
}

#[test]
fn errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "short.toml", SHORT);
    // Output in a missing folder.
    let bad = dir.path().join("missing").join("x.csv");
    let out = host_sim()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            bad.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(bad.to_str().unwrap()), "{err}");
    // Unsupported plot type: rejected before running.
    let out = host_sim()
        .args(["run", scene.to_str().unwrap(), "--plot", "x.pdf"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("x.pdf"));
    // A reversals scene has no table motion.
    let rev = write(
        dir.path(),
        "rev.toml",
        &SHORT.replace(
            "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
            "kind = \"reversals\"\nhalf_period_s = 0.0715",
        ),
    );
    let out = host_sim()
        .args(["run", rev.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("rev.toml") && err.contains("reversals"),
        "{err}"
    );
    // A bad scene: file, line and key.
    let broken = write(
        dir.path(),
        "broken.toml",
        &SHORT.replace("damping_ratio = 0.05", "damping_ratio = 1.5"),
    );
    let out = host_sim()
        .args(["run", broken.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("broken.toml:7:") && err.contains("damping_ratio"),
        "{err}"
    );
}

#[test]
fn no_command_runs_the_default_scene() {
    let dir = tempfile::tempdir().unwrap();
    let out = host_sim().current_dir(dir.path()).output().unwrap();
    ok(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("host-sim run: \"table 1 specimen\""),
        "{text}"
    );
    assert!(dir.path().join("default.run.csv").is_file());
}

/// Ctrl-C (SIGINT) mid-run: the process stops with status 130 and the CSV holds complete rows.
#[cfg(unix)]
#[test]
fn an_interrupted_run_keeps_complete_rows() {
    let dir = tempfile::tempdir().unwrap();
    // Long enough (60 s at 10 kHz) to be still running when the signal comes.
    let scene = write(
        dir.path(),
        "long.toml",
        &SHORT
            .replace("duration_s = 0.8", "duration_s = 60.0")
            .replace("rate_hz = 5000.0", "rate_hz = 10000.0"),
    );
    let csv = dir.path().join("long.run.csv");
    let bin = assert_cmd::cargo::cargo_bin("host-sim");
    let child = std::process::Command::new(bin)
        .args(["run", scene.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for the first flushed rows (the handler is installed before the file is created).
    let start = std::time::Instant::now();
    while std::fs::metadata(&csv).map_or(0, |m| m.len()) == 0 {
        assert!(start.elapsed().as_secs() < 60, "no output");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let killed = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let out = child.wait_with_output().unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows = text.lines().count() - 1;
    if out.status.success() {
        // Finished before the signal arrived: then every row is there.
        assert_eq!(rows, 600_000);
    } else {
        assert_eq!(out.status.code(), Some(130), "{out:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("interrupted") && err.contains(&format!("{rows} rows")),
            "{err}"
        );
        assert!(
            rows > 0 && rows < 600_000 && rows / 4096 * 4096 == rows,
            "{rows}"
        );
    }
    assert!(text.ends_with('\n'));
    let cols = HEADER.split(',').count();
    assert!(text.lines().all(|l| l.split(',').count() == cols));
}

/// "Model only what a scene needs": the model follows the scene's sliding.
#[test]
fn the_model_fits_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let scene = |amp: f64, t0: f64, ratio: f64, xi: f64, period: f64| {
        format!(
            "duration_s = 3.0\ngravity_m_s2 = 9.80\n[structure]\nm1_kg = {ratio}\nm2_kg = 1.0\n\
             natural_period_s = {t0}\ndamping_ratio = {xi}\nfriction_coefficient = 0.2\n\
             [input]\nkind = \"harmonic\"\namplitude_m_s2 = {amp}\nperiod_s = {period}\n\
             [sampling]\nrate_hz = 10000.0\n"
        )
    };
    for (name, text, model) in [
        // Far below the friction limit: no sliding.
        (
            "still.toml",
            scene(0.05, 0.184, 2.0, 0.016, 0.2),
            "fixed-base",
        ),
        // Table 2 test 1: slides continuously after one early stick (docs/equations.md).
        (
            "t1.toml",
            scene(7.02, 0.13, 1.0, 0.0144, 0.125),
            "rectangular",
        ),
        // Table 2 test 2: sticks twice per cycle.
        (
            "t2.toml",
            scene(1.255, 0.184, 2.0, 0.016, 0.2),
            "stick-slip",
        ),
    ] {
        let path = write(dir.path(), name, &text);
        let out = host_sim()
            .current_dir(dir.path())
            .args(["run", path.to_str().unwrap(), "--json"])
            .output()
            .unwrap();
        ok(&out);
        let v = json(&out.stdout);
        assert_eq!(v["estimator"]["model"], model, "{name}: {v}");
        if model == "fixed-base" {
            // Measured: the fixed-base model follows the (never sliding) truth to sensor noise.
            let peak = v["truth"]["peak_top_accel_m_s2"].as_f64().unwrap();
            let rms = v["estimator"]["rms_err_m_s2"].as_f64().unwrap();
            println!(
                "{name}: fixed-base rms {rms} m/s² = {} of the peak",
                rms / peak
            );
            assert!(rms < 0.01 * peak, "{v}");
        }
    }
}

/// Issue 7's scenes with the default sensors: El Centro (full record) and Table 2 test 2.
#[test]
fn stick_slip_scenes_prediction_and_friction() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    // Issue 7's goal: the prediction within 1 % of the peak top acceleration.
    for file in ["elcentro.toml", "table2-test2.toml"] {
        let dir = tempfile::tempdir().unwrap();
        let out = host_sim()
            .current_dir(dir.path())
            .args([
                "run",
                scenes.join(file).to_str().unwrap(),
                "--json",
                "--out",
                "x.csv",
            ])
            .output()
            .unwrap();
        ok(&out);
        let v = json(&out.stdout);
        let e = &v["estimator"];
        assert_eq!(e["model"], "stick-slip", "{file}: {v}");
        // Measured: RMS El Centro 0.021 %, Table 2 test 2 0.013 %; max 0.46 % and 0.066 %; the
        // rectangular model 75 % and 56 % RMS.
        let rms_pct = e["rms_err_pct_of_peak"].as_f64().unwrap();
        assert!(rms_pct < 0.06, "{file}: {rms_pct} %");
        let max_pct = e["max_err_pct_of_peak"].as_f64().unwrap();
        assert!(max_pct < 1.0, "{file}: {max_pct} %");
        assert_eq!(v["detection"]["missed"], 0, "{file}: {v}");
        assert_eq!(v["detection"]["false"], 0, "{file}: {v}");
        let peak = v["truth"]["peak_top_accel_m_s2"].as_f64().unwrap();
        assert!(
            e["rectangular_rms_err_m_s2"].as_f64().unwrap() > 0.5 * peak,
            "{v}"
        );
        // μ within 2e-4 relative (measured 0.2000099 and 0.1999916: 5.0e-5 and 4.2e-5).
        let mu = e["mu_estimate"].as_f64().unwrap();
        assert!((mu / 0.2 - 1.0).abs() < 2e-4, "{file}: mu {mu}");
    }
}

/// The stick-slip model on hard cases (the Table 1 specimen, 2 m/s² at 0.143 s, 5 s): an undamped
/// structure (switching between the sliding and the stuck dynamics at given times pumps errors up
/// at ~20/s without the stuck-phase measurement correction), a nearly massless base, coarse
/// sampling with static friction above kinetic (slip starts known to a sample only), and
/// accelerometers 40× noisier than the default. Every event is found, none invented; the error
/// stays within the bound.
#[test]
fn stick_slip_hard_cases() {
    // (name, m2, ξ, rate, μs, accel noise, measured RMS %, bound %)
    let cases = [
        ("undamped", 1.75, 0.0, 10_000.0, 0.2, 5e-3, 0.043, 0.2),
        ("light base", 0.001, 0.05, 10_000.0, 0.2, 5e-3, 0.188, 0.3),
        // (0.74 % before the strong jump breakaways were confirmed at their second sample.)
        (
            "1 kHz, μs > μ",
            1.75,
            0.05,
            1_000.0,
            0.25,
            5e-3,
            0.379,
            0.45,
        ),
        // Coarse sampling: the detector judges a jump of s̈ against its second and third
        // differences (with the second alone, a deceleration's zero crossing read as a
        // reversal: 18 / 6 / 1 events missed and as many invented at 500 / 700 / 800 Hz, 48 /
        // 34 / 14 % RMS).
        ("800 Hz", 1.75, 0.05, 800.0, 0.2, 5e-3, 0.342, 0.4),
        ("700 Hz", 1.75, 0.05, 700.0, 0.2, 5e-3, 0.434, 0.5),
        ("500 Hz", 1.75, 0.05, 500.0, 0.2, 5e-3, 0.998, 1.1),
        (
            "noisy accelerometers",
            1.75,
            0.05,
            10_000.0,
            0.2,
            0.2,
            1.43,
            1.5,
        ),
    ];
    for (name, m2, xi, rate, mu_s, noise, _measured, bound) in cases {
        let dir = tempfile::tempdir().unwrap();
        let text = format!(
            "name = \"{name}\"\nduration_s = 5.0\n[structure]\nm1_kg = 29.5\nm2_kg = {m2}\n\
             natural_frequency_hz = 7.0\ndamping_ratio = {xi}\nfriction_coefficient = 0.2\n\
             static_friction_coefficient = {mu_s}\n[input]\nkind = \"harmonic\"\n\
             amplitude_m_s2 = 2.0\nperiod_s = 0.143\n[sampling]\nrate_hz = {rate}\n\
             [sensors]\naccel_noise_rms_m_s2 = {noise}\n"
        );
        let scene = write(dir.path(), "hard.toml", &text);
        let out = host_sim()
            .current_dir(dir.path())
            .args(["run", scene.to_str().unwrap(), "--json", "--out", "x.csv"])
            .output()
            .unwrap();
        ok(&out);
        let v = json(&out.stdout);
        let e = &v["estimator"];
        assert_eq!(e["model"], "stick-slip", "{name}: {v}");
        assert_eq!(v["detection"]["missed"], 0, "{name}: {v}");
        assert_eq!(v["detection"]["false"], 0, "{name}: {v}");
        let rms = e["rms_err_pct_of_peak"].as_f64().unwrap();
        let mu = e["mu_estimate"].as_f64().unwrap();
        println!("{name}: rms {rms} % of the peak, mu {mu}");
        assert!(rms < bound, "{name}: rms {rms} % (bound {bound} %)");
        // μ̂ within 0.5 % (identification blocks of ~3.2 ms: 3 samples at 1 kHz), and within
        // the issue's 1 % with accelerometers 40× noisier: there μ̂'s own σ is 6.4e-3 relative.
        // Measured with μ̂ adopted mid-episode and the fuse mode's observers: 1.2e-3 (undamped:
        // no damping forgets the episode's start state), 3.1e-3, 8.7e-4 and 6.3e-3 (noisy; f
        // and ξ adopted at 3.6 s, 0.11 % and 1.8 % off, as the 40× noise biases their fit, μ's
        // least squares restarted).
        let mu_bound = if noise > 0.1 { 1e-2 } else { 5e-3 };
        assert!((mu / 0.2 - 1.0).abs() < mu_bound, "{name}: mu {mu}");
    }
}
