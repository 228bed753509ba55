//! `host-sim monitor` end to end: `host-sim qemu SCENE --json --stream-out S.bin` on 1 s of the
//! default scene (table1.toml), then `host-sim monitor --elf <the report's elf> --input S.bin`:
//! one row per sample, the predictions, events and measured channels equal to `host-sim run`'s
//! for the same scene and model (bit for bit as text), and a damaged copy of the stream (bytes
//! flipped in the middle, the end cut off) read to its end with the damage reported.
//!
//! Needs `qemu-system-arm` like tests/qemu_cli.rs: without it the test fails; `SSVR_SKIP_QEMU=1`
//! skips it explicitly.

mod common;
use assert_cmd::Command;
use common::qemu_tests_run;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A copy of `scenes/table1.toml` with `duration_s` replaced.
fn short_copy(dir: &Path, duration_s: f64) -> PathBuf {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let text = std::fs::read_to_string(scenes.join("table1.toml")).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        if line.split('=').next().unwrap_or("").trim() == "duration_s" {
            out.push_str(&format!("duration_s = {duration_s:?}\n"));
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    let path = dir.join("table1.toml");
    std::fs::write(&path, out).unwrap();
    path
}

fn host_sim(args: &[&str]) -> std::process::Output {
    let out = Command::cargo_bin("host-sim")
        .unwrap()
        .args(args)
        .timeout(std::time::Duration::from_secs(600))
        .output()
        .unwrap();
    eprintln!("{}", String::from_utf8_lossy(&out.stderr));
    out
}

/// The rows of a CSV as column → cell maps.
fn rows(path: &Path) -> Vec<HashMap<String, String>> {
    let mut rdr = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    rdr.records()
        .map(|r| {
            let r = r.unwrap();
            header
                .iter()
                .cloned()
                .zip(r.iter().map(String::from))
                .collect()
        })
        .collect()
}

const COMPARED: [&str; 8] = [
    "t_s",
    "table_accel_m_s2",
    "base_accel_m_s2",
    "measured_top_accel_m_s2",
    "rel_disp_m",
    "predicted_top_accel_m_s2",
    "detected_event",
    "event_age_samples",
];

#[test]
fn monitor_decodes_the_qemu_stream_into_runs_predictions() {
    if !qemu_tests_run() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = short_copy(d, 1.0);
    let stream = d.join("s.bin");
    let out = host_sim(&[
        "qemu",
        scene.to_str().unwrap(),
        "--json",
        "--stream-out",
        stream.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "host-sim qemu failed");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let samples = v["samples"].as_u64().unwrap() as usize;
    assert_eq!(samples, 10_000);
    let model = v["model"].as_str().unwrap().to_string();
    let elf = v["elf"].as_str().unwrap().to_string();
    assert!(Path::new(&elf).is_file(), "the report's elf {elf} is kept");

    // monitor on the saved stream.
    let m_csv = d.join("m.csv");
    let out = host_sim(&[
        "monitor",
        "--elf",
        &elf,
        "--input",
        stream.to_str().unwrap(),
        "--out",
        m_csv.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let text = std::fs::read_to_string(&m_csv).unwrap();
    assert_eq!(text.lines().next(), Some(host_sim::replay::CSV_HEADER));
    let m = rows(&m_csv);
    assert_eq!(m.len(), samples);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("0 malformed frames"), "{err}");
    // The firmware's f in use (its `osc` message; fuse mode, the scene's 7 Hz).
    assert!(err.contains(" f 7.0"), "{err}");

    // `run` on the same scene and model: the same pipeline.
    let r_csv = d.join("r.csv");
    let out = host_sim(&[
        "run",
        scene.to_str().unwrap(),
        "--model",
        &model,
        "--out",
        r_csv.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let r = rows(&r_csv);
    assert_eq!(r.len(), samples);
    let mut events = 0;
    for (k, (a, b)) in m.iter().zip(&r).enumerate() {
        for key in COMPARED {
            assert_eq!(a[key], b[key], "{key} at row {k}");
        }
        let p: f32 = a["predicted_top_accel_m_s2"].parse().unwrap();
        assert!(p.is_finite(), "prediction at row {k}: {p}");
        events += usize::from(!a["detected_event"].is_empty());
    }
    // The events the firmware reported to qemu's own decoding.
    let qemu_events = ["slip_starts", "detected_reversals", "sticks"]
        .iter()
        .map(|k| v[k].as_u64().unwrap() as usize)
        .sum::<usize>();
    assert_eq!(events, qemu_events);
    assert!(events > 0);

    // A damaged copy: bytes flipped in the middle, a zero byte (a frame boundary) inserted, the
    // end cut off mid-frame.
    let mut bytes = std::fs::read(&stream).unwrap();
    let n = bytes.len();
    for k in 0..5 {
        bytes[n / 2 + k * 997] ^= 0x5a;
    }
    bytes[n / 3] = 0;
    bytes.truncate(n - 37);
    let damaged = d.join("damaged.bin");
    std::fs::write(&damaged, &bytes).unwrap();
    let c_csv = d.join("c.csv");
    let out = host_sim(&[
        "monitor",
        "--elf",
        &elf,
        "--input",
        damaged.to_str().unwrap(),
        "--out",
        c_csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "monitor on a damaged stream exits 0");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("malformed defmt frame"), "{err}");
    assert!(err.contains("ends inside a frame"), "{err}");
    let c = rows(&c_csv);
    // Measured: 9 998 rows, 9 994 of them equal to the clean run's row of the same time (the
    // others: a damaged float, undetectable without a checksum).
    assert!(
        c.len() >= samples - 20 && c.len() < samples,
        "{} rows",
        c.len()
    );
    let clean: HashMap<&str, &HashMap<String, String>> =
        m.iter().map(|row| (row["t_s"].as_str(), row)).collect();
    let same = c
        .iter()
        .filter(|row| clean.get(row["t_s"].as_str()) == Some(row))
        .count();
    assert!(same >= samples - 40, "{same} rows equal the clean run's");
    let mut last = -1.0;
    for row in &c {
        let t: f64 = row["t_s"].parse().unwrap();
        assert!(t > last, "time goes back at {t}");
        last = t;
    }
}

#[test]
fn monitor_without_a_readable_elf_names_the_file() {
    let out = Command::cargo_bin("host-sim")
        .unwrap()
        .args(["monitor", "--elf", "/nonexistent/fw.elf", "--input", "-"])
        .write_stdin(Vec::new())
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/nonexistent/fw.elf"), "{err}");
}
