//! `host-sim robustness --quick --json`: the scorecard's shape, every number finite, and what
//! holds today: the unperturbed rows within 0.1 % RMS of the peak (measured 0.013–0.020 %), and a
//! base accelerometer 0.05 g off changing no event (measured: the same counts as unperturbed, so
//! the row meets its goal).

use assert_cmd::Command;
use serde_json::Value;

#[test]
fn the_quick_scorecard() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::cargo_bin("host-sim")
        .unwrap()
        .args(["robustness", "--quick", "--json", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 15, "3 scenes × 5 perturbations, fuse");
    for f in ["robustness.json", "robustness.md", "robustness.png"] {
        assert!(dir.path().join(f).is_file(), "{f}");
    }
    for r in rows {
        for key in ["rms_pct_of_peak", "max_pct_of_peak"] {
            let x = r[key].as_f64().unwrap();
            assert!(x.is_finite() && x >= 0.0, "{key} = {x} in {r}");
        }
        for o in r["accel_bias_m_s2"].as_array().unwrap() {
            assert!(o.as_f64().unwrap().is_finite(), "{r}");
        }
        assert_eq!(r["mode"], "fuse");
        assert_eq!(r["in_goal_range"], true, "{r}");
    }
    let row = |scene: &str, p: &str| {
        rows.iter()
            .find(|r| r["scene"] == scene && r["perturbation"] == p)
            .unwrap_or_else(|| panic!("no row {scene} {p}"))
    };
    for scene in [
        "table 1 specimen",
        "table 1 specimen, El Centro 1940 NS",
        "table 2 test 2",
    ] {
        let none = row(scene, "none");
        assert!(none["rms_pct_of_peak"].as_f64().unwrap() < 0.1, "{none}");
        let base = row(scene, "base_offset_0.05g");
        for k in ["matched", "missed", "false_events"] {
            assert_eq!(base[k], none[k], "{scene}: {k}");
        }
        assert_eq!(base["missed"], 0);
        assert_eq!(base["false_events"], 0);
        assert_eq!(base["events_ok"], true, "{base}");
        assert_eq!(base["goal_met"], true, "{base}");
        assert!(none["events_ok"].is_null(), "{none}");
    }
}

/// The goals' range (issue 13: a prior off by up to f ±8 %, ξ ×2 or ×0.5, μ ±25 %, m1 ±5 %;
/// offsets up to 0.05 g; gains ±1 %; 1 % dropped frames): every perturbation of the scorecard
/// is within it but the top accelerometer's gain 2 % high, a stress row, and a table 2 ms late
/// on its plan (not one of the perturbations), shown and not counted.
#[test]
fn only_the_top_gain_of_2_percent_and_the_tables_lag_are_beyond_the_goals_range() {
    let beyond: Vec<&str> = host_sim::report::robustness::perturbations()
        .iter()
        .filter(|p| !p.in_goal_range())
        .map(|p| p.id)
        .collect();
    assert_eq!(
        beyond,
        ["top_gain+2%", "table_lag_2ms", "all_offsets_0.05g_lag_2ms"]
    );
}

/// `host-sim robustness --json ARGS --out TMP`: its rows (the command must succeed).
fn scorecard_rows(args: &[&str]) -> Vec<Value> {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::cargo_bin("host-sim")
        .unwrap()
        .args(["robustness", "--json"])
        .args(args)
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    v["rows"].as_array().unwrap().clone()
}

/// The scorecard at the board's own rate (`--rate-hz 1000`, `firmware/scenes/board.toml`), 1 %
/// of the frames dropped: no event missed or invented on any scene in either mode. A dropped
/// frame in a slide used to read as a reversal there (its linear fill has no curvature, and the
/// jump test judged the next sample against it): 2 missed and 2 invented events on the default
/// scene, 13.4 % RMS of the peak (fuse) and 13.6 % (predict). Measured now (fuse / predict):
/// default 0.148 / 0.322 %, El Centro 0.131 / 0.802 %, Table 2 test 2 0.095 / 0.368 %. Fuse
/// mode's rows meet their goals, max 1.57 / 1.83 / 0.45 %: El Centro's was 4.86 % while the
/// jump test of a sample whose two before it were measured still took the gap's n (a frame
/// dropped four samples before a stick: the stick's jump waited ten samples for the stall rule).
#[test]
fn dropped_frames_at_the_boards_rate_change_no_event() {
    let rows = scorecard_rows(&["--rate-hz", "1000", "--only", "dropout"]);
    let rows = &rows;
    assert_eq!(rows.len(), 12, "3 scenes × 2 modes × (none, dropout_1%)");
    for r in rows {
        assert_eq!(r["rate_hz"], 1000.0, "{r}");
        let rms = r["rms_pct_of_peak"].as_f64().unwrap();
        assert!(rms.is_finite(), "{r}");
        if r["perturbation"] != "dropout_1%" {
            continue;
        }
        let none = rows
            .iter()
            .find(|n| {
                n["scene"] == r["scene"] && n["mode"] == r["mode"] && n["perturbation"] == "none"
            })
            .unwrap();
        assert_eq!(r["matched"], none["matched"], "{r}");
        assert_eq!(r["missed"], 0, "{r}");
        assert_eq!(r["false_events"], 0, "{r}");
        let bound = if r["mode"] == "fuse" { 0.16 } else { 0.85 };
        assert!(rms <= bound, "{rms} > {bound}: {r}");
        if r["mode"] == "fuse" {
            let max = r["max_pct_of_peak"].as_f64().unwrap();
            assert!(max <= 1.9 && r["goal_met"] == true, "{r}");
        }
    }
}

/// The fuse rows unperturbed and told f off, at `rate` Hz, every scene: each meets the fuse goals
/// (RMS ≤ 0.3 %, max ≤ 2 % of the peak) within `rms_max` / `max_max` % of the peak, no event
/// missed or invented. Returns the rows.
fn fuse_rows_told_f_off(rate: &str, only: &str, rms_max: f64, max_max: f64) -> Vec<Value> {
    let rows = scorecard_rows(&["--rate-hz", rate, "--only", only, "--mode", "fuse"]);
    assert_eq!(rows.len(), 9, "3 scenes × (none, f+, f−)");
    for r in &rows {
        let (rms, max) = checked_row(r);
        assert!(rms <= rms_max && max <= max_max, "{r}");
        assert_eq!(r["goal_met"], true, "{r}");
    }
    rows
}

/// A row's RMS and max error (% of the peak), both finite, with no event missed or invented.
fn checked_row(r: &Value) -> (f64, f64) {
    let (rms, max) = (
        r["rms_pct_of_peak"].as_f64().unwrap(),
        r["max_pct_of_peak"].as_f64().unwrap(),
    );
    assert!(rms.is_finite() && max.is_finite(), "{r}");
    assert_eq!(
        (r["missed"].as_u64(), r["false_events"].as_u64()),
        (Some(0), Some(0)),
        "{r}"
    );
    (rms, max)
}

/// At 2 kHz the fuse rows unperturbed and told f 5 % off meet the fuse goals on every scene.
/// El Centro's jump breakaways (μs > μ) are confirmed early, not at their fourth sample: its max
/// went 2.37 → 1.59 %. The wide sliding observer is capped there instead of off: f ± 5 % went
/// from max 3.25 / 3.52 % (default) and 6.0 / 7.0 % (Table 2 test 2) to 1.37 / 1.28 % and 0.69 /
/// 0.82 % capped at 0.1 rad per sample, 0.55 / 0.59 % and 0.59 / 0.71 % at 0.5. Measured RMS /
/// max: default 0.065 / 0.42 %, f ± 5 % 0.086 / 0.55, 0.090 / 0.59 (its strong ramp starts
/// confirmed at their second sample: 0.071 / 0.53, 0.096 / 0.55, 0.100 / 0.59); El Centro 0.083 / 0.79,
/// 0.084 / 0.79 (both); Table 2 test 2 0.042 / 0.18, 0.056 / 0.59, 0.061 / 0.71.
#[test]
fn the_fuse_rows_told_f_5_percent_off_meet_the_goals_at_2_khz() {
    fuse_rows_told_f_off("2000", "f+5,f-5", 0.10, 0.85);
}

/// At the board's 1 kHz the fuse rows unperturbed and told f 8 % off meet the fuse goals on
/// every scene, with the wide sliding observer capped at 0.5 rad per sample (0.1 before: the
/// default scene's f ± 8 % 0.60 / 5.47 % and 0.63 / 5.12 %, Table 2 test 2's 0.31 / 2.34 % and
/// 0.34 / 2.18 %, RMS / max of the peak). Measured: default 0.105 / 0.50 %, f ± 8 % 0.237 /
/// 0.99, 0.253 / 1.05; El Centro 0.131 / 1.83, 0.139 / 1.83 (both); Table 2 test 2 0.111 / 0.47,
/// 0.176 / 1.36, 0.218 / 1.53. The default scene's smooth (ramp) slip starts are confirmed at
/// their second sample in fuse mode (`PhaseDetectorConfig::early_ramp_starts`): its max was
/// 1.91 % on all three rows (the model running on in the stuck phase for the three samples
/// before a fourth sample's confirmation), now 0.50 % unperturbed.
#[test]
fn the_fuse_rows_told_f_8_percent_off_meet_the_goals_at_1_khz() {
    let rows = fuse_rows_told_f_off("1000", "f+8,f-8", 0.27, 1.95);
    let none = rows
        .iter()
        .find(|r| r["scene"] == "table 1 specimen" && r["perturbation"] == "none")
        .unwrap();
    let max = none["max_pct_of_peak"].as_f64().unwrap();
    assert!(max < 0.55, "{none}");
}

/// At the board's 1 kHz predict mode confirms a strong slip start at its second sample, as fuse
/// mode does, and takes the slide's friction from its sliding side a sample later, the slide
/// re-run from its start with it (`BaseTuning::late_slide_side`,
/// `StickSlipEstimator::set_friction_since_event`). It used to wait for the fourth sample, the
/// model running on in the stuck phase: on the default scene (smooth ramp starts, 1.7 and 3.8
/// m/s² at their first two samples against a threshold of 0.042) up to 0.05 m/s² off the top
/// per slip start. Default scene, RMS / max % of the peak, before → after: unperturbed 0.305 /
/// 2.39 → 0.156 / 0.59, gains ± 1 % 0.314 / 2.88 → 0.172 / 1.20; El Centro (jump breakaways,
/// already confirmed early) 0.796 / 7.76 and Table 2 test 2 (slow ramps) 0.103 / 0.34
/// unperturbed, as before. No event missed or invented.
#[test]
fn predict_mode_confirms_strong_slip_starts_early_at_the_boards_rate() {
    let rows = scorecard_rows(&[
        "--rate-hz",
        "1000",
        "--only",
        "gains_1%",
        "--mode",
        "predict",
    ]);
    assert_eq!(rows.len(), 6, "3 scenes × (none, gains_1%)");
    for r in &rows {
        let (rms, max) = checked_row(r);
        let (rms_max, max_max) = match r["scene"].as_str().unwrap() {
            "table 1 specimen" if r["perturbation"] == "none" => (0.18, 0.7),
            "table 1 specimen" => (0.19, 1.35),
            "table 2 test 2" if r["perturbation"] == "none" => (0.115, 0.40),
            _ => (f64::INFINITY, f64::INFINITY),
        };
        assert!(rms <= rms_max && max <= max_max, "{r}");
    }
}
