//! What a real lab has (issue 13), on the default scene (2 s, stick-slip model): accelerometer
//! offsets, a rest before the input, dropped frames. Bounds are a small margin over what is
//! measured on these 2 s; the unperturbed run is the reference (0.0339 % RMS of the peak with the
//! fuse mode's observers, 28 of 28 events).

use host_sim::run::{run, RunOptions, RunOutcome};
use host_sim::scene::Scene;
use ssvr_proto::Mode;
use std::sync::atomic::AtomicBool;

fn scene(bias: [f64; 3], start_s: f64, dropout: f64) -> Scene {
    let mut s = Scene::default_scene();
    s.start_s = start_s;
    s.duration_s = 2.0 + start_s;
    s.samples = (s.duration_s * s.rate_hz).round() as u64;
    s.sensors.accel_bias_m_s2 = bias;
    s.sensors.dropout_probability = dropout;
    s
}

/// The first 2 s of El Centro (the base stuck throughout).
fn elcentro_2s() -> Scene {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut s = Scene::load(dir.join("elcentro.toml")).unwrap();
    s.duration_s = 2.0;
    s.samples = (s.duration_s * s.rate_hz).round() as u64;
    s
}

fn go(s: &Scene, mode: Mode) -> RunOutcome {
    let mut opts = RunOptions::new("test");
    opts.mode = mode;
    let out = run(s, std::io::sink(), &opts, &AtomicBool::new(false)).unwrap();
    let e = &out.report.estimator;
    assert!(e.rms_err_pct_of_peak.is_finite() && e.max_err_pct_of_peak.is_finite());
    out
}

/// The base accelerometer 0.05 g off (the slip acceleration's offset: the detector's input): no
/// event missed or invented, the same error as without it (measured 0.0339 % for every offset,
/// the offset identified within 1.1e-4 m/s²).
#[test]
fn a_base_offset_changes_no_event() {
    let clean = go(&scene([0.0; 3], 0.0, 0.0), Mode::Fuse);
    for b in [0.05, -0.05, 0.49, -0.49] {
        let out = go(&scene([0.0, b, 0.0], 0.0, 0.0), Mode::Fuse);
        let (d, c) = (&out.report.detection, &clean.report.detection);
        assert_eq!(
            (d.matched, d.missed, d.false_),
            (c.matched, c.missed, c.false_),
            "base {b}"
        );
        assert_eq!(d.missed, 0);
        let e = &out.report.estimator;
        assert!(
            e.rms_err_pct_of_peak < 0.036,
            "base {b}: {} %",
            e.rms_err_pct_of_peak
        );
        let est = e.identified.accel_bias_m_s2[1];
        assert!((est - b).abs() < 2e-3, "base {b}: identified {est}");
    }
}

/// Every accelerometer 0.05 g off with a 0.5 s rest before the input: the pipeline zeroes them
/// on the rest (measured: fuse 0.0342 %, predict 0.019 % RMS, offsets within 3e-4 m/s²).
#[test]
fn a_rest_zeroes_every_accelerometer() {
    let bias = [0.49, -0.49, 0.49];
    for mode in [Mode::Fuse, Mode::Predict] {
        let out = go(&scene(bias, 0.5, 0.0), mode);
        let e = &out.report.estimator;
        let bound = if mode == Mode::Fuse { 0.036 } else { 0.04 };
        assert!(
            e.rms_err_pct_of_peak < bound,
            "{mode:?}: {} %",
            e.rms_err_pct_of_peak
        );
        assert_eq!(out.report.detection.missed, 0);
        assert_eq!(out.report.detection.false_, 0);
        for (o, b) in e.identified.accel_bias_m_s2.iter().zip(bias) {
            assert!((o - b).abs() < 2e-3, "{mode:?}: {o} vs {b}");
        }
    }
}

/// 1 % of the frames dropped: no false event, the error stays near the clean run's (measured on
/// 10 s: 0.019 % RMS, 0.19 % max of the peak).
#[test]
fn dropped_frames_cost_little() {
    let out = go(&scene([0.0; 3], 0.0, 0.01), Mode::Fuse);
    let e = &out.report.estimator;
    assert!(e.rms_err_pct_of_peak < 0.05, "{} %", e.rms_err_pct_of_peak);
    assert!(e.max_err_pct_of_peak < 0.5, "{} %", e.max_err_pct_of_peak);
    assert_eq!(out.report.detection.false_, 0);
    assert_eq!(out.report.detection.missed, 0);
}

/// Gain errors of +1 % on the table and −1 % on the base: the detector tracks the mismatch
/// while the base sticks (reported as `base_vs_table_gain_error`: measured −0.01996 on 2 s for
/// 0.99/1.01 − 1 = −0.01980) and no event is missed or invented.
#[test]
fn a_gain_mismatch_is_tracked() {
    let mut s = scene([0.0; 3], 0.0, 0.0);
    s.sensors.accel_gain_error = [0.01, -0.01, 0.0];
    let out = go(&s, Mode::Fuse);
    let k = out
        .report
        .estimator
        .identified
        .base_vs_table_gain_error
        .unwrap();
    assert!((k - (0.99 / 1.01 - 1.0)).abs() < 5e-4, "{k}");
    assert_eq!(out.report.detection.missed, 0);
    assert_eq!(out.report.detection.false_, 0);
}

/// The table accelerometer's own gain, against the displacement sensor over the sliding
/// episodes (`ssvr_proto::table_gain`), on 10 s of the default scene (139 episodes): with every
/// accelerometer's gain off by ±1 % (the table's by `e`), e is found within 1.5e-4 and adopted
/// (the one in use within 1e-3, the smallest change re-adopted),
/// so μ comes out within 1e-3 and the fuse mode's error is back under its goal. Measured (each
/// estimate ~6e-5 low, within 0.8σ): e = +1 %: 0.009942 ± 8.2e-5 (in use 0.009656), μ 0.20003,
/// 0.164 % RMS (0.65 % before); e = −1 %: −0.010057 ± 8.0e-5 (in use −0.010331), μ 0.20000,
/// 0.162 % RMS. Without a gain error: −5.7e-5 ± 8.1e-5, not adopted.
#[test]
fn the_table_gain_is_found_against_the_displacement() {
    for e in [0.01, -0.01, 0.0] {
        let mut s = scene([0.0; 3], 0.0, 0.0);
        s.duration_s = 10.0;
        s.samples = (s.duration_s * s.rate_hz).round() as u64;
        s.sensors.accel_gain_error = [e, -e, e];
        let out = go(&s, Mode::Fuse);
        let est = &out.report.estimator;
        let g = est.identified.table_gain_error.clone().unwrap();
        println!(
            "e {e}: {g:?}, mu {:?}, {} % RMS, {} % max",
            est.mu_estimate, est.rms_err_pct_of_peak, est.max_err_pct_of_peak
        );
        assert!(g.std.is_finite() && g.std < 1e-4, "{e}: {g:?}");
        assert!((g.estimate - e).abs() < 1.5e-4, "{e}: {g:?}");
        if e == 0.0 {
            assert_eq!(g.in_use, 0.0);
        } else {
            // (Adopted early, within 3σ of 2e-3; re-adopted only beyond 1e-3: measured 3e-4.)
            assert!((g.in_use - e).abs() < 1e-3, "{e}: {g:?}");
        }
        let mu = est.mu_estimate.unwrap();
        assert!((mu / 0.2 - 1.0).abs() < 1e-3, "{e}: {mu}");
        assert!(est.rms_err_pct_of_peak < 0.18, "{e}");
        assert_eq!(out.report.detection.missed, 0);
        assert_eq!(out.report.detection.false_, 0);
    }
}

/// Predict mode, the table accelerometer's gain 1 % off (the default scene, 10 s): the gain is
/// adopted after eight sliding episodes (~0.5 s), and every accelerometer then reads in the new
/// units. What the model had identified from the samples before (the sliding base's μ̂, its
/// rows and the offsets) is rescaled with them (`Model::rescale_units`): measured 0.124 % RMS
/// and μ̂ 0.20010 (before the rescaling 0.298 % and 0.20022, the μ adopted at 0.4 s from rows
/// in the old units, +1.0 %, then 0.2010 and 0.2004 at 1.4 and 4.5 s); the gain known from
/// the start gives 0.022 %. No event missed or invented.
#[test]
fn predict_mode_rescales_what_it_found_when_the_table_gain_is_adopted() {
    let mut s = scene([0.0; 3], 0.0, 0.0);
    s.duration_s = 10.0;
    s.samples = (s.duration_s * s.rate_hz).round() as u64;
    s.sensors.accel_gain_error = [0.01, 0.0, 0.0];
    let out = go(&s, Mode::Predict);
    let est = &out.report.estimator;
    let mu = est.mu_estimate.unwrap();
    println!("{} % RMS, μ {mu}", est.rms_err_pct_of_peak);
    assert!(
        est.rms_err_pct_of_peak < 0.15,
        "{}",
        est.rms_err_pct_of_peak
    );
    assert!((mu / 0.2 - 1.0).abs() < 8e-4, "{mu}");
    assert_eq!(out.report.detection.missed, 0);
    assert_eq!(out.report.detection.false_, 0);
}

/// Without a rest, the top accelerometer's offset from the run's open-loop start (the first
/// p·t ≤ 0.1 rad, 22 samples at 7 Hz and 10 kHz: `OpenStart` in `ssvr_proto::model::base_tuning`):
/// the specimen starts at rest as the model does, so the top reads its offset before the model's
/// response to the table's has grown. Fuse mode, 2 s of the default scene (sliding from 0.03 s:
/// the momentum balance refines it) and of El Centro (stuck throughout: before this, the top
/// offset passed into the prediction until the first slide, 1.76 % RMS in these 2 s). Measured:
/// default, top ±0.05 m/s²: found within 4.6e-5, 0.0401 % RMS (clean 0.0339 %); El Centro,
/// top ±0.05: the start's estimate alone, within 1.8e-3 (its standard error 1.1e-3), 0.080 %
/// RMS (clean 0.036 %). Every accelerometer 0.05 g off: the next test. No event missed or
/// invented.
#[test]
fn the_top_offset_is_found_at_the_open_loop_start() {
    let elcentro = elcentro_2s();
    let cases = [
        (
            "default",
            scene([0.0; 3], 0.0, 0.0),
            [0.05, -0.05],
            2e-4,
            [0.045, 0.045],
        ),
        ("El Centro", elcentro, [0.05, -0.05], 4e-3, [0.09, 0.09]),
    ];
    for (name, base, tops, within, rms) in cases {
        for (top, rms) in tops.into_iter().zip(rms) {
            let mut s = base.clone();
            s.sensors.accel_bias_m_s2 = [0.0, 0.0, top];
            let out = go(&s, Mode::Fuse);
            let e = &out.report.estimator;
            let found = e.identified.accel_bias_m_s2[2];
            assert!((found - top).abs() < within, "{name} {top}: found {found}");
            let r = e.rms_err_pct_of_peak;
            assert!(r < rms, "{name} {top}: {r} % RMS");
            assert_eq!(out.report.detection.missed, 0, "{name} {top}");
            assert_eq!(out.report.detection.false_, 0, "{name} {top}");
        }
    }
}

/// Fuse mode without a rest takes the table accelerometer's offset from the input's start
/// against the plan, as predict mode does (`BaseTuning::note_table_start`, over the same samples
/// as the top's open-loop start), and removes the model's response to it so far: every
/// accelerometer 0.05 g off on the first 2 s of El Centro (stuck throughout, so no sliding
/// phase can separate the table's offset from the top's) and of the default scene. Measured:
/// El Centro, the table's offset 0.029 m/s² high (its record starts at 0.062 m/s², so a table
/// that follows at once and one still at rest read a0 apart: the start takes the midpoint,
/// docs/ROBUSTNESS.md), the top's within 1.5e-3, 0.0387 % RMS (0.59 % before: the stuck-phase
/// observer left κ·b_t ≈ b_t/35 of the table's offset in the model; the clean run's 0.036 %);
/// default, both within 1e-3, 0.0366 % RMS (0.136 % before; clean 0.0339 %). No event missed
/// or invented.
#[test]
fn fuse_mode_takes_the_tables_offset_from_the_start() {
    let g = 0.49;
    for (name, mut s, table_within, top_within, rms) in [
        ("El Centro", elcentro_2s(), 0.035, 2.5e-3, 0.042),
        ("default", scene([0.0; 3], 0.0, 0.0), 2e-3, 5e-4, 0.040),
    ] {
        s.sensors.accel_bias_m_s2 = [g, -g, g];
        let out = go(&s, Mode::Fuse);
        let e = &out.report.estimator;
        let [table, _, top] = e.identified.accel_bias_m_s2;
        assert!(
            (table - g).abs() < table_within,
            "{name}: table offset {table}"
        );
        assert!((top - g).abs() < top_within, "{name}: top offset {top}");
        assert!(
            e.rms_err_pct_of_peak < rms,
            "{name}: {} % RMS",
            e.rms_err_pct_of_peak
        );
        assert_eq!(out.report.detection.missed, 0, "{name}");
        assert_eq!(out.report.detection.false_, 0, "{name}");
    }
}

/// The top accelerometer's gain before the first slide (fuse mode): the oscillator identifier's
/// fit with the base's filtered signals (`ssvr_core::oscillator_id::TopGainFit`) separates it
/// on a record. The first 2 s of El Centro (stuck throughout) with the top's gain 2 % high and
/// 1 % low: measured 0.302 / 0.149 % RMS, 0.97 / 0.48 % max (the momentum balance alone, which
/// needs slides: 0.753 / 0.379 % RMS, 2.37 / 1.10 % max); without a gain error the same as
/// before (0.0358 %: nothing adopted).
#[test]
fn the_top_gain_is_found_before_the_first_slide() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut s = Scene::load(dir.join("elcentro.toml")).unwrap();
    s.duration_s = 2.0;
    s.samples = (s.duration_s * s.rate_hz).round() as u64;
    for (g, rms, max) in [(0.02, 0.32, 1.02), (-0.01, 0.16, 0.52), (0.0, 0.037, 0.45)] {
        let mut s = s.clone();
        s.sensors.accel_gain_error = [0.0, 0.0, g];
        let out = go(&s, Mode::Fuse);
        let e = &out.report.estimator;
        assert!(
            e.rms_err_pct_of_peak < rms,
            "gain {g}: {} % RMS",
            e.rms_err_pct_of_peak
        );
        assert!(
            e.max_err_pct_of_peak < max,
            "gain {g}: {} % max",
            e.max_err_pct_of_peak
        );
    }
}

/// Predict mode without a rest: the table accelerometer's offset from the input's start
/// against the plan (`BaseTuning::note_table_start`, `ssvr_proto::table_start`: the measured
/// table's line and first half's mean over the first 0.1 rad of p against the planned input's
/// line, for a table any lag late), and the model's response to it over those samples removed
/// from its state (`StickSlipEstimator::remove_input_offset`). Every accelerometer 0.05 g off
/// (table +, base −), on the first 2 s of the default scene and of El Centro (stuck
/// throughout). The default scene's sine starts from rest: its offset is found within 4e-3
/// m/s² (the default scene's both-ways fit then finds it within 2e-4). El Centro's record
/// starts at 0.06 m/s², and a table that follows it at once reads as one still at rest
/// 0.06 m/s² higher: the start takes their midpoint, 0.03 off, and the stuck 2 s carry that
/// (4.42 / 20.4 % RMS before the table start: the offset drove the stuck model until the base
/// had slid both ways). Unperturbed, nothing is taken. Bounds: the measured RMS (printed) and
/// a few % over it.
#[test]
fn predict_finds_the_table_offset_at_the_input_start() {
    let elcentro = elcentro_2s();
    let g = 0.05 * 9.80665;
    for (name, base) in [
        ("default", scene([0.0; 3], 0.0, 0.0)),
        ("El Centro", elcentro),
    ] {
        for bias in [[g, -g, g], [0.0; 3]] {
            let r = predict_table_start(name, &base, bias, 0.0);
            // (Measured: 0.036 / 1.212 / 0.026 / 0.024 % RMS.)
            let bound = match (name, bias[0] == 0.0) {
                ("default", false) => 0.04,
                (_, false) => 1.25,
                _ => 0.03,
            };
            assert!(r < bound, "{name} {bias:?}: {r} % RMS");
        }
    }
}

/// Predict mode on `base` (`name`: "default" or "El Centro") with accelerometer offsets `bias`
/// and the table `lag_s` late: the table's offset found within 4e-3 m/s², or within half El
/// Centro's first acceleration (0.031 m/s²) and 4e-3 when there is one (measured 0.0308 off);
/// no event missed or invented.
/// Returns the RMS error (% of the peak).
fn predict_table_start(name: &str, base: &Scene, bias: [f64; 3], lag_s: f64) -> f64 {
    let mut s = base.clone();
    s.sensors.accel_bias_m_s2 = bias;
    s.table_lag_s = lag_s;
    let out = go(&s, Mode::Predict);
    let e = &out.report.estimator;
    let found = e.identified.accel_bias_m_s2[0];
    let within = if name == "El Centro" && bias[0] != 0.0 {
        0.031 + 4e-3
    } else {
        4e-3
    };
    let r = e.rms_err_pct_of_peak;
    eprintln!("{name} {bias:?} lag {lag_s} s: table offset {found}, {r} % RMS");
    assert!(
        (found - bias[0]).abs() < within,
        "{name} {bias:?} lag {lag_s} s: found {found}"
    );
    assert_eq!(out.report.detection.missed, 0, "{name} lag {lag_s} s");
    assert_eq!(out.report.detection.false_, 0, "{name} lag {lag_s} s");
    r
}

/// Predict mode without a rest on a table that follows its plan late (`[input] table_lag_s`, the
/// truth's alone: a servo table's lag), 0.1 to 20 ms, on the first 2 s of the default scene and
/// of El Centro, with and without every accelerometer 0.05 g off. The table start allows for
/// any lag (`ssvr_proto::table_start`): no offset is taken for a lagging table that reads its own
/// rest (taking the intercept less the plan's, as before, a lag of 0.2–1 ms read as an offset
/// of up to the plan's rise per sample times the lag, and El Centro's first acceleration for one:
/// 0.22–0.73 % RMS over its 32 s without any offset), and 0.05 g is found within 4e-3 m/s² (the
/// default scene) or half El Centro's first acceleration. Bounds: the measured RMS (printed)
/// and a few % over it.
#[test]
fn predict_allows_for_the_tables_lag() {
    let g = 0.05 * 9.80665;
    for (name, base) in [
        ("default", scene([0.0; 3], 0.0, 0.0)),
        ("El Centro", elcentro_2s()),
    ] {
        for bias in [[0.0; 3], [g, -g, g]] {
            let mut worst = 0.0f64;
            for lag_ms in [0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 20.0] {
                worst = worst.max(predict_table_start(name, &base, bias, lag_ms * 1e-3));
            }
            // (Measured worst: 0.033 / 0.170 (0.2 ms) / 0.028 / 1.268 (20 ms) % RMS.)
            let bound = match (name, bias[0] == 0.0) {
                ("default", true) => 0.035,
                ("default", false) => 0.18,
                (_, true) => 0.03,
                _ => 1.3,
            };
            assert!(worst < bound, "{name} {bias:?}: {worst} % RMS");
        }
    }
}

/// At 1 kHz the open-loop start is 10 samples over 0.44 rad of p (the curved start: at least
/// `MIN_OPEN_START` samples while they span at most 0.5 rad), where before there was none:
/// every accelerometer 0.05 g off without a rest, the first 2 s of the default scene and of El
/// Centro. Fuse mode takes the top's offset from it, the model's response to the table's
/// offset fitted beside it; both modes take the table's against the plan (fuse mode since the
/// fifteenth session), provisionally from the start's first sample on (its 10 samples span
/// 0.44 rad: `BaseTuning::begin_table_start`). Measured, % RMS, fuse / predict: default 0.125 /
/// 0.268 (no offsets: 0.193 / 0.275; 0.146 / 0.280 without the provisional offset, fuse 0.491
/// while it left the table's offset to the stuck-phase observer), El Centro 0.160 / 0.999
/// (0.206 / 0.232; 0.177 / 1.002 without the provisional offset, fuse 0.658 before; El Centro's
/// record starts at a0 = 0.06 m/s², which leaves the table's offset a0/2 off, as at 10 kHz:
/// predict mode carries it, fuse mode's stuck-phase observer follows the top); before, with no
/// start: 4.73 / 6.54 and 19.8 / 20.2. Fuse mode's max: default 0.496 %, El Centro 1.53 % (2.14
/// and 2.26 % without the provisional offset: the model integrated the table's offset over the
/// start). No event missed or invented.
#[test]
fn a_1_khz_run_finds_the_offsets_at_its_start() {
    let g = 0.49;
    let at_1_khz = |mut s: Scene| {
        s.rate_hz = 1_000.0;
        s.samples = (s.duration_s * s.rate_hz).round() as u64;
        s.sensors.accel_bias_m_s2 = [g, -g, g];
        s
    };
    let cases = [
        (
            "default",
            at_1_khz(scene([0.0; 3], 0.0, 0.0)),
            [0.14, 0.29],
            0.55,
        ),
        ("El Centro", at_1_khz(elcentro_2s()), [0.17, 1.03], 1.65),
    ];
    for (name, s, rms, fuse_max) in cases {
        for (mode, rms) in [Mode::Fuse, Mode::Predict].into_iter().zip(rms) {
            let out = go(&s, mode);
            let e = &out.report.estimator;
            let r = e.rms_err_pct_of_peak;
            assert!(r < rms, "{name} {mode:?}: {r} % RMS");
            if mode == Mode::Fuse {
                let max = e.max_err_pct_of_peak;
                assert!(max < fuse_max, "{name}: {max} % max");
            }
            assert_eq!(out.report.detection.missed, 0, "{name} {mode:?}");
            assert_eq!(out.report.detection.false_, 0, "{name} {mode:?}");
        }
    }
}

/// Fuse mode's top offset from the momentum balance, b_top = θ2 + θ0·b_table with θ0 = −G·r,
/// takes the table's offset in use; before that is known its σ includes |θ0| times an
/// unknown lab offset's (0.05 g). Table 2 test 2 (r = ½) at 5 kHz, the table accelerometer
/// 0.05 g off, no rest: the top's fit came before the table's and took b_top = 0.245 m/s² for
/// 0 (0.17 % RMS, 5.4 % max); then 0.063 / 0.47 % (10 kHz: 0.065 / 0.56 %), and since fuse
/// mode takes the table's offset from the input's start too (fifteenth session), 0.0266 /
/// 0.124 %, the table's offset found there within 1e-3.
#[test]
fn the_top_offset_waits_for_the_tables() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut s = Scene::load(dir.join("table2-test2.toml")).unwrap();
    s.rate_hz = 5_000.0;
    s.samples = (s.duration_s * s.rate_hz).round() as u64;
    s.sensors.accel_bias_m_s2 = [0.49, 0.0, 0.0];
    let out = go(&s, Mode::Fuse);
    let e = &out.report.estimator;
    assert!(
        e.rms_err_pct_of_peak < 0.03,
        "{} % RMS",
        e.rms_err_pct_of_peak
    );
    assert!(
        e.max_err_pct_of_peak < 0.14,
        "{} % max",
        e.max_err_pct_of_peak
    );
    let found = e.identified.accel_bias_m_s2;
    assert!(
        (found[0] - 0.49).abs() < 2e-3 && found[2].abs() < 2e-3,
        "{found:?}"
    );
    assert_eq!(out.report.detection.missed, 0);
    assert_eq!(out.report.detection.false_, 0);
}
