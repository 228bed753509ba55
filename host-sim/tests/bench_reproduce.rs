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
    // Measured (--quick): f64 1.2e-13, F32Poly 3.8e-7 on the harmonic scene, 1.4e-6 on the long
    // train.
    assert!(num(f64_h, "max_err_gmu") <= 5e-13, "{f64_h}");
    let fw = row(
        rows,
        "harmonic",
        "rdm-recursion",
        "F32Poly (firmware default)",
    );
    assert!(num(fw, "max_err_gmu") <= 1e-6, "{fw}");
    let fw_long = row(
        rows,
        "long-train",
        "rdm-recursion",
        "F32Poly (firmware default)",
    );
    assert!(num(fw_long, "max_err_gmu") <= 3e-6, "{fw_long}");
    // The full closed form is the reference; RFM converges to it; truncation works only with
    // damping. Measured (--quick): RFM 6.4e-3 at H=81 against 1.26 at H=1 (ratio 5.1e-3); K=32 0
    // and K=16 2.3e-16 on the harmonic scene; K=32 1.01 on the undamped long train.
    assert_eq!(
        num(
            row(rows, "harmonic", "rdm-closed", "full sum"),
            "max_err_gmu"
        ),
        0.0
    );
    assert!(
        num(row(rows, "harmonic", "rfm", "H=81"), "max_err_gmu")
            < 0.01 * num(row(rows, "harmonic", "rfm", "H=1"), "max_err_gmu")
    );
    assert!(
        num(
            row(rows, "harmonic", "rdm-truncated", "K=32"),
            "max_err_gmu"
        ) <= 1e-15
    );
    assert!(
        num(
            row(rows, "long-train", "rdm-truncated", "K=32"),
            "max_err_gmu"
        ) >= 0.5
    );
    // Model errors: the truth is its own reference.
    assert_eq!(
        num(
            row(rows, "earthquake", "truth", "exact stick-slip"),
            "max_err_vs_truth_gmu"
        ),
        0.0
    );
    // The speed-up of the recursion over the full sum is counted, not timed:
    // `long_train_work_is_counted` below.

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

/// Work per sample on the bench's long reversal train, counted: (the full closed form's kernel
/// terms per compared sample, the recursion's steps per sample). The full sum evaluates one kernel
/// term (exponential, sine and cosine) per past reversal at every sample (undamped: none is
/// dropped); the recursion does one table step per sample plus one kernel evaluation per reversal.
fn long_train_work(quick: bool) -> (f64, f64) {
    use ssvr_core::closed_form::duhamel::{DuhamelClosedForm, ReversalTrain};
    let scenes = host_sim::report::bench::scenes(quick).unwrap();
    let sc = scenes.iter().find(|s| s.id == "long-train").unwrap();
    let train = ReversalTrain::Explicit(&sc.train);
    let cf = DuhamelClosedForm::new(&sc.structure);
    let terms: usize = sc
        .eval
        .iter()
        .map(|&k| cf.evaluate(&train, k as f64 / sc.rate_hz, usize::MAX).terms)
        .sum();
    let closed = terms as f64 / sc.eval.len() as f64;
    let recursion = (sc.samples + sc.train.len() as u64) as f64 / sc.samples as f64;
    (closed, recursion)
}

/// The recursion's advantage over the full closed-form sum on the long train, as operation counts
/// (the project never puts a timing inside a test). Measured, and exact: 500.5 kernel terms per
/// compared sample for the full sum against 1 + 1/715 steps per sample for the recursion with
/// `--quick` (10^3 reversals, ratio 499.8), 5000.5 against the same with the full bench (10^4
/// reversals, ratio 4994, the goal being ≥ 1000). docs/PERFORMANCE.md's 5.7·10^4× (full bench,
/// host ns per sample: 90 µs against 1.6 ns) is this ratio times the cost of one kernel term
/// (~18 ns) over one table step (~1.6 ns).
#[test]
fn long_train_work_is_counted() {
    let steps = 1.0 + 1.0 / 715.0; // a reversal every 0.0715 s at 10 kHz
    for (quick, terms, ratio_min) in [(true, 500.5, 499.0), (false, 5000.5, 4990.0)] {
        let (closed, recursion) = long_train_work(quick);
        let ratio = closed / recursion;
        println!(
            "long-train (quick {quick}): full sum {closed} terms per sample, recursion {recursion} \
             steps per sample, ratio {ratio:.1}"
        );
        assert_eq!(closed, terms, "quick {quick}");
        assert!((recursion / steps - 1.0).abs() < 1e-12, "{recursion}");
        assert!(ratio >= ratio_min, "quick {quick}: {ratio}");
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
