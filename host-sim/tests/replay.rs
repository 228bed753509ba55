//! `host-sim replay`: a `run` CSV replayed gives `run`'s predictions bit for bit; a hand-made
//! recording (other column names, g and mm, a rest with offsets, blank cells) predicts as well as
//! `run` on the same motion; bad recordings are errors naming the file, line and column, or
//! flagged samples.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

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

fn f(v: &serde_json::Value) -> f64 {
    let x = v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"));
    assert!(x.is_finite(), "{v}");
    x
}

const STRUCTURE: &str = r#"[structure]
m1_kg = 29.5
m2_kg = 1.75
natural_frequency_hz = 7.0
damping_ratio = 0.05
friction_coefficient = 0.2
"#;

/// The default scene (table 1 specimen, 2 m/s² at 0.143 s, 10 kHz), `duration_s` s long, with
/// `extra` appended to `[input]`, and `sensors` as its `[sensors]` table.
fn run_scene(duration_s: f64, extra_input: &str, sensors: &str) -> String {
    format!(
        "name = \"short default\"\nduration_s = {duration_s}\n{STRUCTURE}[input]\nkind = \
         \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143\n{extra_input}[sampling]\nrate_hz = \
         10000.0\n{sensors}"
    )
}

/// A replay scene on `file` with the `[recording]` keys `keys`.
fn replay_scene(file: &str, keys: &str) -> String {
    format!("{STRUCTURE}[recording]\nfile = \"{file}\"\n{keys}")
}

const RUN_COLUMNS: &str = r#"time_column = "t_s"
table_accel_column = "table_accel_m_s2"
base_accel_column = "base_accel_m_s2"
top_accel_column = "measured_top_accel_m_s2"
slip_column = "rel_disp_m"
accel_units = "m/s2"
slip_units = "m"
"#;

fn column(path: &Path, name: &str) -> Vec<String> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let i = r.headers().unwrap().iter().position(|h| h == name).unwrap();
    r.records().map(|x| x.unwrap()[i].to_string()).collect()
}

#[test]
fn a_run_csv_replayed_gives_runs_predictions_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "short.toml", &run_scene(1.5, "", ""));
    let rep = write(
        dir.path(),
        "rep.toml",
        &replay_scene("run.csv", RUN_COLUMNS),
    );
    for model in ["stick-slip", "rectangular", "fixed-base"] {
        let run_csv = dir.path().join("run.csv");
        let out = host_sim()
            .args([
                "run",
                scene.to_str().unwrap(),
                "--json",
                "--model",
                model,
                "--out",
            ])
            .arg(&run_csv)
            .output()
            .unwrap();
        ok(&out);
        let rep_csv = dir.path().join(format!("rep-{model}.csv"));
        let out = host_sim()
            .args([
                "replay",
                rep.to_str().unwrap(),
                "--json",
                "--model",
                model,
                "--out",
            ])
            .arg(&rep_csv)
            .output()
            .unwrap();
        ok(&out);
        let j = json(&out.stdout);
        assert_eq!(j["samples"], 15000);
        assert_eq!(j["flagged_samples"], 0);
        assert_eq!(j["model"], model);
        assert_eq!(j["mode"], "fuse");
        assert_eq!(f(&j["rate_hz"]), 10000.0);
        let a = column(&run_csv, "predicted_top_accel_m_s2");
        let b = column(&rep_csv, "predicted_top_accel_m_s2");
        assert_eq!(a.len(), 15000);
        assert_eq!(a.len(), b.len());
        let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
        assert_eq!(differ, 0, "{model}: {differ} predictions differ");
        // The detected events too.
        assert_eq!(
            column(&run_csv, "detected_event"),
            column(&rep_csv, "detected_event"),
            "{model}"
        );
        // Measured columns are copied exactly.
        for c in ["t_s", "table_accel_m_s2", "measured_top_accel_m_s2"] {
            assert_eq!(column(&run_csv, c), column(&rep_csv, c), "{model} {c}");
        }
    }
}

#[test]
fn a_hand_made_recording_in_g_and_mm_predicts_as_run_does() {
    let dir = tempfile::tempdir().unwrap();
    // A rest of 0.3 s before the input and accelerometer offsets, zeroed on the rest.
    let scene = write(
        dir.path(),
        "rest.toml",
        &run_scene(
            2.0,
            "start_s = 0.3\n",
            "[sensors]\naccel_bias_m_s2 = [0.05, -0.03, 0.04]\n",
        ),
    );
    let run_csv = dir.path().join("run.csv");
    let out = host_sim()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--json",
            "--model",
            "stick-slip",
            "--out",
        ])
        .arg(&run_csv)
        .output()
        .unwrap();
    ok(&out);
    let run_json = json(&out.stdout);
    // The run's own prediction against its measured top accelerometer.
    let meas = column(&run_csv, "measured_top_accel_m_s2");
    let pred = column(&run_csv, "predicted_top_accel_m_s2");
    let sq: f64 = meas
        .iter()
        .zip(&pred)
        .map(|(m, p)| (p.parse::<f64>().unwrap() - m.parse::<f64>().unwrap()).powi(2))
        .sum();
    let run_rms = (sq / meas.len() as f64).sqrt();
    assert!(run_rms.is_finite() && run_rms > 0.0, "{run_rms}");

    // The recording: other names, g and mm, 9 significant digits, three blank cells.
    let g = 9.80665;
    let mut r = csv::Reader::from_path(&run_csv).unwrap();
    let mut w = csv::Writer::from_path(dir.path().join("test-07.csv")).unwrap();
    w.write_record(["Time (s)", "A table", "A base", "A top", "LVDT"])
        .unwrap();
    let blank = [(5000usize, 3usize), (8000, 1), (12000, 2)];
    for (k, rec) in r.records().enumerate() {
        let rec = rec.unwrap();
        let v = |i: usize| rec[i].parse::<f64>().unwrap();
        let mut cells = vec![
            rec[0].to_string(),
            format!("{:.9e}", v(1) / g),
            format!("{:.9e}", v(2) / g),
            format!("{:.9e}", v(3) / g),
            format!("{:.9e}", v(4) * 1e3),
        ];
        for (row, col) in blank {
            if k == row {
                cells[col] = String::new();
            }
        }
        w.write_record(&cells).unwrap();
    }
    w.flush().unwrap();
    drop(w);
    let rep = write(
        dir.path(),
        "test-07.toml",
        &replay_scene(
            "test-07.csv",
            "time_column = \"Time (s)\"\ntable_accel_column = \"A table\"\nbase_accel_column = \
             \"A base\"\ntop_accel_column = \"A top\"\nslip_column = \"LVDT\"\naccel_units = \
             \"g\"\nslip_units = \"mm\"\nstart_s = 0.3\n",
        ),
    );
    let out = host_sim()
        .args(["replay", rep.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    ok(&out);
    let j = json(&out.stdout);
    assert_eq!(j["samples"], 20000);
    assert_eq!(j["flagged_samples"], 3);
    assert_eq!(j["bad_cells"], 3);
    assert_eq!(j["model"], "stick-slip"); // the default with a base accelerometer
    assert!(dir.path().join("test-07.replay.csv").exists());
    let v = &j["vs_measured_top"];
    let rms = f(&v["rms_err_m_s2"]);
    eprintln!(
        "replay RMS vs measured top {rms:.6} m/s² ({:.4} % of peak), run's {run_rms:.6} m/s²",
        f(&v["rms_err_pct_of_peak"])
    );
    // Within 5 % of run's (+ 0.2 mm/s²: units round trip, the three blank cells).
    assert!(
        (rms - run_rms).abs() <= 0.05 * run_rms + 2e-4,
        "replay {rms} vs run {run_rms}"
    );
    assert!(f(&v["peak_measured_m_s2"]) > 2.0);
    // The offsets are zeroed on the rest as run zeroes them (within 1 mm/s²).
    for i in 0..3 {
        let a = f(&j["identified"]["accel_bias_m_s2"][i]);
        let b = f(&run_json["estimator"]["identified"]["accel_bias_m_s2"][i]);
        assert!((a - b).abs() < 1e-3, "offset {i}: replay {a} run {b}");
    }
    assert!(f(&j["events"]["slip_starts"]) >= 1.0);
}

const SMALL_COLUMNS: &str = r#"time_column = "t"
table_accel_column = "a"
top_accel_column = "top"
accel_units = "m/s2"
"#;

#[test]
fn a_missing_column_is_an_error_naming_file_line_1_and_column() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "x.csv", "t,a,b\n0,0,0\n0.001,0,0\n");
    let rep = write(dir.path(), "x.toml", &replay_scene("x.csv", SMALL_COLUMNS));
    let out = host_sim()
        .args(["replay", rep.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("x.csv:1:"), "{err}");
    assert!(
        err.contains("`top`") && err.contains("top_accel_column"),
        "{err}"
    );
    // An unreadable file names it.
    let rep = write(
        dir.path(),
        "y.toml",
        &replay_scene("nope.csv", SMALL_COLUMNS),
    );
    let out = host_sim()
        .args(["replay", rep.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("nope.csv") && err.contains("cannot read"),
        "{err}"
    );
}

#[test]
fn a_non_increasing_time_is_an_error_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("t,a,top\n");
    for k in 0..50 {
        text += &format!("{},0.1,0.2\n", k as f64 / 1000.0);
    }
    text += "0.049,0.1,0.2\n"; // line 52: not after line 51's 0.049
    write(dir.path(), "x.csv", &text);
    let rep = write(dir.path(), "x.toml", &replay_scene("x.csv", SMALL_COLUMNS));
    let out = host_sim()
        .args(["replay", rep.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("x.csv:52:"), "{err}");
    assert!(
        err.contains("column `t`") && err.contains("does not increase"),
        "{err}"
    );
}

/// The same with CRLF line ends (a Windows logger's): the line named is still the file's.
#[test]
fn a_non_increasing_time_names_the_line_with_crlf_line_ends() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("t,a,top\r\n");
    for k in 0..50 {
        text += &format!("{},0.1,0.2\r\n", k as f64 / 1000.0);
    }
    text += "0.049,0.1,0.2\r\n"; // line 52
    write(dir.path(), "x.csv", &text);
    let rep = write(dir.path(), "x.toml", &replay_scene("x.csv", SMALL_COLUMNS));
    let out = host_sim()
        .args(["replay", rep.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("x.csv:52:") && err.contains("(line 51:"),
        "{err}"
    );
}

#[test]
fn text_cells_and_time_gaps_are_flagged_samples() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("t,a,top\n");
    for k in 0..100 {
        if k == 60 || k == 61 {
            continue; // a gap of two samples
        }
        let a = if k == 30 {
            "oops".into()
        } else {
            format!("{}", 0.01 * k as f64)
        };
        let top = if k == 40 { "NaN" } else { "0.0" };
        text += &format!("{},{a},{top}\n", k as f64 / 1000.0);
    }
    write(dir.path(), "x.csv", &text);
    let rep = write(dir.path(), "x.toml", &replay_scene("x.csv", SMALL_COLUMNS));
    let out_csv = dir.path().join("o.csv");
    let out = host_sim()
        .args(["replay", rep.to_str().unwrap(), "--json", "--out"])
        .arg(&out_csv)
        .output()
        .unwrap();
    ok(&out);
    let j = json(&out.stdout);
    assert_eq!(j["rows"], 98);
    assert_eq!(j["samples"], 100);
    assert_eq!(j["bad_cells"], 2);
    assert_eq!(j["gap_samples"], 2);
    assert_eq!(j["flagged_samples"], 4);
    assert_eq!(j["model"], "fixed-base");
    assert_eq!(f(&j["rate_hz"]), 1000.0);
    let flags = column(&out_csv, "flags");
    assert_eq!(flags.len(), 100);
    let fl = |k: usize| flags[k].parse::<u8>().unwrap();
    assert_ne!(fl(30) & 1, 0, "text cell: NOT_FINITE");
    assert_ne!(fl(40) & 1, 0, "NaN cell: NOT_FINITE");
    assert_ne!(fl(60) & 4, 0, "gap: MISSING");
    assert_ne!(fl(61) & 4, 0, "gap: MISSING");
    assert_eq!(column(&out_csv, "t_s")[61], "0.061");
    // Every prediction is a number.
    for p in column(&out_csv, "predicted_top_accel_m_s2") {
        assert!(p.parse::<f32>().unwrap().is_finite(), "{p}");
    }
}

#[test]
fn plot_svg_and_png() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write(dir.path(), "short.toml", &run_scene(0.5, "", ""));
    let run_csv = dir.path().join("run.csv");
    ok(&host_sim()
        .args(["run", scene.to_str().unwrap(), "--out"])
        .arg(&run_csv)
        .output()
        .unwrap());
    let rep = write(
        dir.path(),
        "rep.toml",
        &replay_scene("run.csv", RUN_COLUMNS),
    );
    for name in ["p.svg", "p.png"] {
        let p = dir.path().join(name);
        let out = host_sim()
            .args([
                "replay",
                rep.to_str().unwrap(),
                "--plot-window",
                "0.3",
                "--plot",
            ])
            .arg(&p)
            .output()
            .unwrap();
        ok(&out);
        assert!(std::fs::metadata(&p).unwrap().len() > 10_000, "{name}");
    }
    let bad = host_sim()
        .args(["replay", rep.to_str().unwrap(), "--plot", "x.pdf"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
}

/// A velocity-dependent interface: the replay scene's `[friction]` makes the model follow the
/// law as `run`'s does; the replayed predictions are `run`'s bit for bit, and both report the
/// identified law.
#[test]
fn a_velocity_dependent_run_replays_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let law = "[friction]\nlaw = \"velocity-dependent\"\nmu_slow = 0.12\nrate_s_m = 30.0\n";
    let scene = write(
        dir.path(),
        "ptfe.toml",
        &run_scene(1.5, "", "").replace("[input]", &format!("{law}[input]")),
    );
    let rep = write(
        dir.path(),
        "rep.toml",
        &replay_scene("run.csv", RUN_COLUMNS).replace("[recording]", &format!("{law}[recording]")),
    );
    let run_csv = dir.path().join("run.csv");
    let out = host_sim()
        .args(["run", scene.to_str().unwrap(), "--json", "--out"])
        .arg(&run_csv)
        .output()
        .unwrap();
    ok(&out);
    let run_json = json(&out.stdout);
    let rep_csv = dir.path().join("rep.csv");
    let out = host_sim()
        .args(["replay", rep.to_str().unwrap(), "--json", "--out"])
        .arg(&rep_csv)
        .output()
        .unwrap();
    ok(&out);
    let j = json(&out.stdout);
    assert_eq!(j["model"], "stick-slip");
    let a = column(&run_csv, "predicted_top_accel_m_s2");
    let b = column(&rep_csv, "predicted_top_accel_m_s2");
    assert_eq!(a.len(), 15000);
    assert_eq!(a.len(), b.len());
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert_eq!(differ, 0, "{differ} predictions differ");
    let law_run = &run_json["estimator"]["identified"]["friction"];
    let law_rep = &j["identified"]["friction"];
    assert_eq!(law_run["law"], "velocity-dependent");
    assert_eq!(law_run, law_rep);
    assert!(
        (f(&law_rep["mu_slow"]) / 0.12 - 1.0).abs() < 0.03,
        "{law_rep}"
    );
    assert!(
        (f(&law_rep["mu_fast"]) / 0.2 - 1.0).abs() < 0.03,
        "{law_rep}"
    );
}
