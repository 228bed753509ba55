//! `host-sim bench --quick --json` and `host-sim reproduce --quick`: contracts and sanity.
//!
//! The bench's M4F column is measured under QEMU: `qemu-system-arm` must be installed (CI installs
//! it), or the test fails; `SSVR_SKIP_QEMU=1` skips that one check explicitly.

mod common;
use assert_cmd::Command;
use serde_json::Value;
use std::path::Path;

fn host_sim() -> Command {
    Command::cargo_bin("host-sim").expect("the host-sim binary")
}

fn row<'a>(rows: &'a [Value], scene: &str, method: &str, setting: &str) -> &'a Value {
    rows.iter()
        .find(|r| r["scene"] == scene && r["method"] == method && r["setting"] == setting)
        .unwrap_or_else(|| panic!("no row {scene} {method} {setting}"))
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number in {v}"))
}

#[test]
fn bench_quick_json_rows_are_complete_and_sane() {
    let dir = tempfile::tempdir().unwrap();
    let out = host_sim()
        .args(["bench", "--quick", "--json", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
    let rows = v["rows"].as_array().expect("rows");
    // 3 scenes × (4 recursion + 1 closed + 4 truncated) + 10 Fourier (harmonic) + 2 truth.
    assert_eq!(rows.len(), 3 * 9 + 10 + 2, "{rows:#?}");
    for r in rows {
        for key in ["method", "precision", "setting", "scene"] {
            assert!(r[key].is_string(), "{key} in {r}");
        }
        assert!(
            r.get("m4f_instructions_per_sample")
                .is_some_and(|m| m.is_null() || m.is_number()),
            "{r}"
        );
        let ns = num(r, "ns_per_sample");
        assert!(ns.is_finite() && ns > 0.0, "{r}");
        let (max, rms) = (num(r, "max_err_gmu"), num(r, "rms_err_gmu"));
        assert!(
            max.is_finite() && max >= 0.0 && rms >= 0.0 && rms <= max * (1.0 + 1e-12),
            "{r}"
        );
        if let Some(t) = r["max_err_vs_truth_gmu"].as_f64() {
            assert!(t.is_finite() && t >= 0.0, "{r}");
        }
        assert!(
            ["f32", "f64"].contains(&r["precision"].as_str().unwrap()),
            "{r}"
        );
    }
    // The firmware recursion's M4F count, measured under QEMU (required unless SSVR_SKIP_QEMU=1).
    if common::qemu_tests_run() {
        for r in rows.iter().filter(|r| {
            r["method"] == "rdm-recursion" && r["setting"] == "F32Poly (firmware default)"
        }) {
            let m4f = num(r, "m4f_instructions_per_sample");
            assert!(m4f > 5.0 && m4f <= 20.0, "{r}");
        }
    }
    let scenes: Vec<&str> = rows.iter().map(|r| r["scene"].as_str().unwrap()).collect();
    for s in ["harmonic", "long-train", "earthquake"] {
        assert!(scenes.contains(&s), "{s}");
    }
    // Fourier methods only on the harmonic scene; no truth on the prescribed long train.
    assert!(rows
        .iter()
        .filter(|r| r["method"] == "tfm" || r["method"] == "rfm")
        .all(|r| r["scene"] == "harmonic"));
    assert!(!rows
        .iter()
        .any(|r| r["method"] == "truth" && r["scene"] == "long-train"));

    // The recursion against the full closed form.
    let f64_h = rows
        .iter()
        .find(|r| {
            r["scene"] == "harmonic" && r["method"] == "rdm-recursion" && r["precision"] == "f64"
        })
        .expect("the f64 recursion on the harmonic scene");
    assert!(num(f64_h, "max_err_gmu") <= 1e-10, "{f64_h}");
    let fw = row(
        rows,
        "harmonic",
        "rdm-recursion",
        "F32Poly (firmware default)",
    );
    assert!(num(fw, "max_err_gmu") <= 1e-5, "{fw}");
    let fw_long = row(
        rows,
        "long-train",
        "rdm-recursion",
        "F32Poly (firmware default)",
    );
    assert!(num(fw_long, "max_err_gmu") <= 1e-5, "{fw_long}");
    // The full closed form is the reference; RFM converges to it; truncation works only with
    // damping.
    assert_eq!(
        num(
            row(rows, "harmonic", "rdm-closed", "full sum"),
            "max_err_gmu"
        ),
        0.0
    );
    assert!(
        num(row(rows, "harmonic", "rfm", "H=81"), "max_err_gmu")
            < 0.1 * num(row(rows, "harmonic", "rfm", "H=1"), "max_err_gmu")
    );
    assert!(
        num(
            row(rows, "harmonic", "rdm-truncated", "K=32"),
            "max_err_gmu"
        ) <= 1e-12
    );
    assert!(
        num(
            row(rows, "long-train", "rdm-truncated", "K=32"),
            "max_err_gmu"
        ) >= 0.1
    );
    // Model errors: the truth is its own reference.
    assert_eq!(
        num(
            row(rows, "earthquake", "truth", "exact stick-slip"),
            "max_err_vs_truth_gmu"
        ),
        0.0
    );
    // The recursion is much faster than the full sum on the long train (loose: timing on a
    // shared machine).
    let closed = num(
        row(rows, "long-train", "rdm-closed", "full sum"),
        "ns_per_sample",
    );
    assert!(closed / num(fw_long, "ns_per_sample") > 30.0);

    for f in [
        "bench.json",
        "bench.md",
        "pareto-harmonic.png",
        "pareto-long-train.png",
        "pareto-earthquake.png",
    ] {
        let p = dir.path().join(f);
        assert!(
            p.metadata().map(|m| m.len() > 1000).unwrap_or(false),
            "{}",
            p.display()
        );
    }
}

#[test]
fn bench_markdown_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let out = host_sim()
        .args(["bench", "--quick", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.starts_with("| scene | method | precision | setting | ns/sample"),
        "{text}"
    );
    assert!(
        text.contains("| long-train | rdm-closed | f64 | full sum |"),
        "{text}"
    );
}

fn png(path: &Path) -> bool {
    std::fs::read(path).is_ok_and(|b| b.len() > 1000 && b.starts_with(b"\x89PNG"))
}

#[test]
fn reproduce_quick_writes_the_report_and_the_figures() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("tmp");
    let out = host_sim()
        .args(["reproduce", "--quick", "--out"])
        .arg(&out_dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = std::fs::read_to_string(out_dir.join("report.md")).expect("report.md");
    let figures = [
        "fig6-table1-tfm-rfm-rdm.png",
        "fig9-m1-much-larger-than-m2.png",
        "fig10-peak-vs-mass-ratio.png",
        "fig11-sliding-response-spectra.png",
    ];
    for f in figures {
        assert!(png(&out_dir.join(f)), "{f}");
        assert!(
            report.contains(&format!("]({f})")),
            "report.md does not embed {f}"
        );
    }
    for heading in [
        "## Table 2",
        "## Fig. 6",
        "## Fig. 9",
        "## Fig. 10",
        "## Fig. 11",
    ] {
        assert!(report.contains(heading), "{heading}");
    }
    // Table 2: our TFM reproduces the paper's TFM column; test 1 slides continuously and the
    // truth agrees with TFM there.
    let v: Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("results.json")).unwrap())
            .unwrap();
    let t2 = v["table2"].as_array().unwrap();
    assert_eq!(t2.len(), 8);
    for t in t2 {
        let d = num(t, "tfm_gal") - num(&t["paper"], "tfm_gal");
        assert!(d.abs() < 1.0, "{t}");
    }
    let t1 = &t2[0];
    assert_eq!(num(&t1["truth"], "sticks_per_cycle"), 0.0);
    assert!(
        (num(t1, "truth_gal") - num(t1, "tfm_gal")).abs() < 1.0,
        "{t1}"
    );
}
