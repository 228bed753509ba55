//! The controller told a wrong specimen (issue 13): the prior's μ or f off, on the first seconds
//! of the default scene and of El Centro. Fuse mode identifies μ (adopted after 128 sliding
//! samples, at any identification block) and f, ξ (from the stuck phases), and corrects its
//! state from the top accelerometer while stuck and while sliding. Predict mode identifies them
//! from the base accelerometer while sliding and corrects its sliding state by the momentum
//! balance. Bounds are a small margin over what is measured.

use host_sim::run::{run, RunOptions, RunOutcome};
use host_sim::scene::Scene;
use ssvr_proto::Mode;
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// `scene` for `seconds`, the prior's μ (and μs) scaled by `mu`, f by `f`, m1 by `m1`.
fn told(mut s: Scene, seconds: f64, mu: f64, f: f64, m1: f64) -> Scene {
    s.duration_s = seconds;
    s.samples = (s.duration_s * s.rate_hz).round() as u64;
    let e = &mut s.estimator;
    e.params.friction_coefficient *= mu;
    e.static_friction_coefficient *= mu;
    e.params.natural_frequency_hz *= f;
    e.params.m1_kg *= m1;
    s
}

fn go(s: &Scene, mode: Mode) -> RunOutcome {
    go_csv(s, mode).0
}

/// The run and its CSV.
fn go_csv(s: &Scene, mode: Mode) -> (RunOutcome, Vec<u8>) {
    let mut opts = RunOptions::new("test");
    opts.mode = mode;
    let mut csv = Vec::new();
    let out = run(s, &mut csv, &opts, &AtomicBool::new(false)).unwrap();
    let e = &out.report.estimator;
    assert!(e.rms_err_pct_of_peak.is_finite() && e.max_err_pct_of_peak.is_finite());
    assert_eq!(out.report.detection.missed, 0);
    assert_eq!(out.report.detection.false_, 0);
    (out, csv)
}

fn elcentro() -> Scene {
    Scene::load(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/elcentro.toml")).unwrap()
}

/// Fuse mode, μ told 25 % high or low: the first slides take μ from the slip starts' breakaway
/// (the force that held the base, from the measured top), and μ̂ is adopted early (measured on
/// these 3 s: default 0.034 % RMS, max 0.13 %; El Centro 0.032 %, max 0.40 %; μ̂ within 5e-5.
/// With the prior's μ in the first slides, before the breakaway: 0.102 % / 1.39–1.46 % and
/// 0.097 % / 1.30–1.33 %).
#[test]
fn fuse_holds_with_mu_told_25_percent_off() {
    for (name, scene) in [
        ("default", Scene::default_scene()),
        ("El Centro", elcentro()),
    ] {
        for mu in [1.25, 0.75] {
            let out = go(&told(scene.clone(), 3.0, mu, 1.0, 1.0), Mode::Fuse);
            let e = &out.report.estimator;
            println!(
                "{name} mu x{mu}: {} % RMS, {} % max, mu {:?}",
                e.rms_err_pct_of_peak, e.max_err_pct_of_peak, e.mu_estimate
            );
            assert!(e.rms_err_pct_of_peak < 0.04, "{name} {mu}");
            assert!(e.max_err_pct_of_peak < 0.45, "{name} {mu}");
            let m = e.mu_estimate.unwrap();
            assert!((m / 0.2 - 1.0).abs() < 1e-3, "{name} {mu}: {m}");
        }
    }
}

/// Fuse mode, f told 8 % high or low: f and ξ are identified from the stuck phases and adopted
/// (measured on these 5 s of the default scene: f within 1.8e-4 of 7.0 Hz (the goal: 0.5 %),
/// ξ within 6e-4 of 0.05; RMS error 0.109 % / 0.129 % of the peak, mostly before the first
/// adoption, which the stuck observer at 6p holds).
#[test]
fn fuse_identifies_f_told_8_percent_off() {
    for f in [1.08, 0.92] {
        let out = go(&told(Scene::default_scene(), 5.0, 1.0, f, 1.0), Mode::Fuse);
        let e = &out.report.estimator;
        let id = &e.identified;
        println!(
            "f x{f}: {} % RMS, f {} Hz, xi {}",
            e.rms_err_pct_of_peak, id.natural_frequency_hz, id.damping_ratio
        );
        assert!((id.natural_frequency_hz / 7.0 - 1.0).abs() < 5e-4, "f x{f}");
        assert!((id.damping_ratio / 0.05 - 1.0).abs() < 2e-3, "f x{f}");
        assert!(e.rms_err_pct_of_peak < 0.15, "f x{f}");
    }
}

/// The static friction coefficient from the detected slip starts (the force that held the base,
/// m1·ü1 + m2·üg, at each): El Centro has μs = 0.25 above μ = 0.2; told 0.2 (the detector then
/// expects ramps, not jumps) or 0.3, or right. Measured: 0.24854 ± 8.0e-4, 0.24995 ± 3.9e-4
/// (31 slip starts); the default scene (μs = μ = 0.2) 0.19992.
#[test]
fn identifies_the_static_friction_at_the_slip_starts() {
    for (told_s, want) in [(0.2, 0.25), (0.3, 0.25), (0.25, 0.25)] {
        let mut s = elcentro();
        s.estimator.static_friction_coefficient = told_s;
        let out = go(&s, Mode::Fuse);
        let id = &out.report.estimator.identified;
        let (mu_s, n) = (
            id.static_friction_coefficient,
            id.static_friction_slip_starts.unwrap(),
        );
        println!("told {told_s}: mu_s {mu_s} from {n} slip starts");
        assert_eq!(n, 31);
        assert!((mu_s / want - 1.0).abs() < 8e-3, "told {told_s}: {mu_s}");
    }
    let out = go(&Scene::default_scene(), Mode::Fuse);
    let mu_s = out.report.estimator.identified.static_friction_coefficient;
    assert!((mu_s / 0.2 - 1.0).abs() < 1e-3, "{mu_s}");
}

/// Predict mode (no top accelerometer), μ told 25 % high or low: μ is identified from the base
/// accelerometer while sliding (the sliding oscillator's equilibria, `core::sliding_id`) and
/// adopted at the first significant estimate; the sliding state follows the momentum balance.
/// Before any estimate each slide starts from its slip start's breakaway coefficient (from the
/// model's ü1) blended with the prior's (`PREDICT_BREAKAWAY_WEIGHT`). Measured on these 3 s of
/// the default scene: μ̂ within 4e-4 of 0.2; RMS 0.57 % of the peak (3.04 % with the prior's μ
/// until the first estimate), all in the first slides, 0.025 % after the first second; the
/// prior's open loop: 14.7 % over the whole run.
#[test]
fn predict_identifies_mu_from_the_base_accelerometer() {
    for mu in [1.25, 0.75] {
        let (out, csv) = go_csv(
            &told(Scene::default_scene(), 3.0, mu, 1.0, 1.0),
            Mode::Predict,
        );
        let e = &out.report.estimator;
        let m = e.mu_estimate.unwrap();
        println!(
            "mu x{mu}: {} % RMS, {} % max, mu {m}",
            e.rms_err_pct_of_peak, e.max_err_pct_of_peak
        );
        assert!((m / 0.2 - 1.0).abs() < 1e-3, "mu x{mu}: {m}");
        assert!(e.rms_err_pct_of_peak < 0.62, "mu x{mu}");
        // After the first adoption the error is that of the exact prior's.
        let late = late_rms(&csv, 1.0);
        println!("  after 1 s: {late} % RMS");
        assert!(late < 0.03, "mu x{mu}: {late}");
    }
}

/// Predict mode on El Centro, μ told 25 % high or low, no rest: the base first slides one way
/// for several episodes, and until it has slid both ways the friction and the table's offset
/// are one constant. Each direction's friction level is adopted for that direction alone
/// (`SlidingEstimate::one_way`), so the prior's μ goes at the first episodes; before them, the
/// slip starts' breakaway. Measured over the whole run: 0.201–0.202 % RMS of the peak (0.759 %
/// without the breakaway, 1.52 % when one-way estimates were not used either); μ̂
/// within 1e-3 (bound 1e-2).
#[test]
fn predict_adopts_one_way_friction_before_both_ways() {
    for mu in [1.25, 0.75] {
        let mut s = elcentro();
        s.estimator.params.friction_coefficient *= mu;
        s.estimator.static_friction_coefficient *= mu;
        let out = go(&s, Mode::Predict);
        let e = &out.report.estimator;
        let m = e.mu_estimate.unwrap();
        println!(
            "El Centro mu x{mu}: {} % RMS, {} % max, mu {m}",
            e.rms_err_pct_of_peak, e.max_err_pct_of_peak
        );
        assert!((m / 0.2 - 1.0).abs() < 1e-2, "mu x{mu}: {m}");
        assert!(e.rms_err_pct_of_peak < 0.23, "mu x{mu}");
    }
}

/// Predict mode, f told 8 % high or low, or ξ twice: f and ξ are identified from the sliding
/// base (ω = p·√M, ζ = ξ·√M with the prior's M) and adopted (measured on these 5 s of the
/// default scene: f̂ within 6e-5 of 7 Hz and ξ̂ within 6e-4 of 0.05, the adopted ones within
/// 4.5e-4 and 3.7e-3; RMS 0.44–0.66 % of the peak, 0.033–0.037 % after 2 s).
#[test]
fn predict_identifies_f_and_xi_from_the_base_accelerometer() {
    for (f, xi) in [(1.08, 1.0), (0.92, 1.0), (1.0, 2.0)] {
        let mut s = told(Scene::default_scene(), 5.0, 1.0, f, 1.0);
        s.estimator.params.damping_ratio *= xi;
        let (out, csv) = go_csv(&s, Mode::Predict);
        let e = &out.report.estimator;
        let id = &e.identified;
        let used = id.in_use.as_ref().unwrap();
        println!(
            "f x{f} xi x{xi}: {} % RMS, f {} Hz (in use {}), xi {} (in use {})",
            e.rms_err_pct_of_peak,
            id.natural_frequency_hz,
            used.natural_frequency_hz,
            id.damping_ratio,
            used.damping_ratio
        );
        assert!((id.natural_frequency_hz / 7.0 - 1.0).abs() < 5e-4, "f x{f}");
        assert!((id.damping_ratio / 0.05 - 1.0).abs() < 5e-3, "xi x{xi}");
        assert!(
            (used.natural_frequency_hz / 7.0 - 1.0).abs() < 2e-3,
            "f x{f}"
        );
        assert!(used.adoptions > 0);
        let late = late_rms(&csv, 2.0);
        println!("  after 2 s: {late} % RMS");
        assert!(late < 0.055, "f x{f} xi x{xi}");
    }
}

/// Predict mode with m1 told 5 % high or low: the sliding base shows p·√M, so the f adopted
/// from it first is the one that keeps p·√M right with the prior's M (2.3 % off), and the stuck
/// phases run on it. Once μ is known, the slip starts' residual (their slides' μ from the
/// momentum balance on the model's ü1 against μ: −5.9 % / +6.0 %) moves M until it is within
/// the dead band of 1 % (`proto::model::base_tuning::mass`), f and ξ rescaled with ω and ζ held.
/// Measured on these 3 s of the default scene: f̂ 2.1e-4 / 8.5e-4 off 7 Hz at the end (6.84 /
/// 7.17 Hz from the prior's M; the dead band allows ~4e-3), RMS 0.84 / 0.95 % of the peak,
/// 0.038 / 0.090 % after 2 s (over 10 s: 0.46 / 0.52 %, 1.99 / 2.08 % before).
#[test]
fn predict_finds_m_from_the_slip_starts() {
    for m1 in [1.05, 0.95] {
        let (out, csv) = go_csv(
            &told(Scene::default_scene(), 3.0, 1.0, 1.0, m1),
            Mode::Predict,
        );
        let e = &out.report.estimator;
        let id = &e.identified;
        let late = late_rms(&csv, 2.0);
        println!(
            "m1 x{m1}: {} % RMS, {late} % after 2 s, f {} Hz (in use {:?})",
            e.rms_err_pct_of_peak, id.natural_frequency_hz, id.in_use
        );
        assert!(
            (id.natural_frequency_hz / 7.0 - 1.0).abs() < 1.5e-3,
            "m1 x{m1}"
        );
        assert!(e.rms_err_pct_of_peak < 1.0, "m1 x{m1}");
        assert!(late < 0.1, "m1 x{m1}: {late}");
        // The report's m1 in use: the one the slip starts gave (29.5 kg in the truth; measured
        // 29.495 / 29.489 kg).
        let m1_use = id.in_use.as_ref().unwrap().m1_kg;
        assert!((m1_use / 29.5 - 1.0).abs() < 1e-3, "m1 x{m1}: {m1_use}");
    }
}

/// RMS error (% of the peak of the truth) of the samples after `from_s`, from the run's CSV.
fn late_rms(csv: &[u8], from_s: f64) -> f64 {
    let text = std::str::from_utf8(csv).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (t, p, y) = (
        col("t_s"),
        col("predicted_top_accel_m_s2"),
        col("truth_top_accel_m_s2"),
    );
    let (mut sum, mut n, mut peak) = (0.0f64, 0usize, 0.0f64);
    for line in lines {
        let v: Vec<&str> = line.split(',').collect();
        let num = |i: usize| v[i].parse::<f64>().unwrap();
        let truth = num(y);
        assert!(truth.is_finite());
        peak = peak.max(truth.abs());
        if num(t) >= from_s {
            let e = num(p) - truth;
            assert!(e.is_finite());
            sum += e * e;
            n += 1;
        }
    }
    100.0 * (sum / n as f64).sqrt() / peak
}

/// Fuse mode at 1 and 2 kHz, μ told 25 % high or low, no rest: the first slides take μ from the
/// slip starts' breakaway, as at 10 kHz. At these rates μ̂ comes late (128 sliding samples are
/// 128 ms at 1 kHz, longer than a slide), and with the prior's μ until then the first slides
/// were 29 % of the peak off: 5.45 / 3.58 % RMS (1 / 2 kHz) before the breakaway's μ, measured
/// now 0.309 / 0.083 % (the right μ told: 0.195 / 0.080 %; at 1 kHz the breakaway comes out
/// 1–3 % low), max 1.67 / 0.54 %; μ̂ within 1.1e-3.
#[test]
fn fuse_takes_the_breakaway_at_low_rates() {
    for (rate, rms, max) in [(1000.0, 0.34, 1.85), (2000.0, 0.095, 0.6)] {
        for mu in [1.25, 0.75] {
            let mut s = Scene::default_scene();
            s.rate_hz = rate;
            let s = told(s, 2.5, mu, 1.0, 1.0);
            let out = go(&s, Mode::Fuse);
            let e = &out.report.estimator;
            println!(
                "{rate} Hz, mu x{mu}: {} % RMS, {} % max, mu {:?}",
                e.rms_err_pct_of_peak, e.max_err_pct_of_peak, e.mu_estimate
            );
            assert!(e.rms_err_pct_of_peak < rms, "{rate} Hz, mu x{mu}");
            assert!(e.max_err_pct_of_peak < max, "{rate} Hz, mu x{mu}");
            let m = e.mu_estimate.unwrap();
            assert!((m / 0.2 - 1.0).abs() < 1.3e-3, "{rate} Hz, mu x{mu}: {m}");
        }
    }
}

/// Fuse mode with m1 told 5 % high or low, at 1 kHz and 10 kHz: the momentum balance's fit of
/// the measured top gives r = m2/m1 (to 0.05 %: M 17.85 for 17.857), and M is taken from it
/// with the f and ξ in use. Measured over 10 s: 0.264 / 0.274 % RMS at 1 kHz (0.63 / 0.59 %
/// with the prior's M, over the goal of 0.3 %; right m1: 0.213 %), 0.036 / 0.036 % at 10 kHz
/// (0.099 / 0.107 %).
#[test]
fn fuse_takes_m_from_the_momentum_balance() {
    for (rate, bound) in [(1000.0, 0.29), (10_000.0, 0.045)] {
        for m1 in [1.05, 0.95] {
            let mut s = Scene::default_scene();
            s.rate_hz = rate;
            let s = told(s, 10.0, 1.0, 1.0, m1);
            let e = go(&s, Mode::Fuse).report.estimator;
            let m1_use = e.identified.in_use.as_ref().unwrap().m1_kg;
            println!(
                "{rate} Hz, m1 x{m1}: {} % RMS, m1 in use {m1_use} kg",
                e.rms_err_pct_of_peak
            );
            assert!(e.rms_err_pct_of_peak < bound, "{rate} Hz, m1 x{m1}");
            // The report's m1 in use: the one taken (29.5 kg in the truth; measured 29.385 kg at
            // 1 kHz, 29.494 at 10 kHz, either way told).
            let tol = if rate < 5000.0 { 5e-3 } else { 1e-3 };
            assert!(
                (m1_use / 29.5 - 1.0).abs() < tol,
                "{rate} Hz, m1 x{m1}: {m1_use}"
            );
        }
    }
}

/// The first slides' μ comes from each slip start's sliding side (the momentum balance just
/// after it), which needs no μs, so a static coefficient told wrong (alone) costs nothing: El
/// Centro told μs = μ (the truth's μs is 25 % above) and the default scene told μs = 0.25 (the
/// truth's is μ = 0.2). Measured: predict 0.066 / 0.022 % RMS of the peak, fuse 0.034 /
/// 0.035 %, max 0.48 / 0.15 %, as told right. (From the breakaway's μs times the prior's μ/μs,
/// the previous way, they were 0.54 / 0.81 %, 0.044 / 0.054 % and 1.32 / 1.19 %.) No event
/// missed or invented.
#[test]
fn a_static_coefficient_told_wrong_costs_nothing() {
    let mut ec = elcentro();
    ec.estimator.static_friction_coefficient = 0.2;
    let mut d = Scene::default_scene();
    d.estimator.static_friction_coefficient = 0.25;
    for (name, s, predict, fuse, fuse_max) in [
        ("El Centro", ec, 0.075, 0.04, 0.55),
        ("default", d, 0.03, 0.04, 0.17),
    ] {
        let p = go(&s, Mode::Predict).report.estimator;
        let f = go(&s, Mode::Fuse).report.estimator;
        println!(
            "{name}: predict {} % RMS, fuse {} % RMS, {} % max",
            p.rms_err_pct_of_peak, f.rms_err_pct_of_peak, f.max_err_pct_of_peak
        );
        assert!(p.rms_err_pct_of_peak < predict, "{name}");
        assert!(f.rms_err_pct_of_peak < fuse, "{name}");
        assert!(f.max_err_pct_of_peak < fuse_max, "{name}");
    }
}

/// Fuse mode, every perturbation of the scorecard at once and no rest (the default scene's
/// `all_combined`: f told 8 % high, ξ ×2, μ +25 %, m1 +5 %, every accelerometer 0.05 g off,
/// gains ±1 %, 1 % dropped frames). The first slide starts at 48 ms, before f and ξ are
/// identified; the sliding observer stays wide until they are known (`hold_wide`). Measured
/// on its first second: max 1.68 % of the peak at 70 ms (2.18 % when it narrowed at μ̂'s
/// adoption, mid-slide, and RMS 0.60 %), RMS 0.58 % (the whole 10 s: 0.192 %).
#[test]
fn fuse_holds_every_perturbation_at_once() {
    let p = host_sim::report::robustness::perturbations()
        .into_iter()
        .find(|p| p.id == "all_combined")
        .unwrap();
    let mut s = p.apply(&Scene::default_scene());
    s.duration_s = 1.0;
    s.samples = (s.duration_s * s.rate_hz).round() as u64;
    let out = go(&s, Mode::Fuse);
    let e = &out.report.estimator;
    assert!(e.max_err_pct_of_peak < 1.75, "{}", e.max_err_pct_of_peak);
    assert!(e.rms_err_pct_of_peak < 0.62, "{}", e.rms_err_pct_of_peak);
}

/// Table 2 test 2 (a 5 Hz sine: 200 samples a period at 1 kHz, the friction events at the same
/// fraction of a sample every cycle) told its own specimen, fuse mode: the oscillator
/// identification places each event's jump of the base acceleration at its time
/// (`OscillatorIdentifier::jump`), else the samples put it at a cell boundary, the same way
/// every cycle. Measured at 1 kHz: ξ̂ 0.01597 for 0.016 (−0.19 %; the same with the base
/// accelerometer's gain 2 % off either way: the step is taken in the model's units), f̂
/// −0.011 %, nothing adopted, 0.112 % RMS (before: ξ̂ +23 %, f̂ −0.17 %, both adopted,
/// 0.238 %); at 10 kHz ξ̂ +0.31 % (+1.4 % before), 0.0188 % RMS (0.0200).
#[test]
fn the_events_between_samples_bias_no_identification() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let base = Scene::load(dir.join("table2-test2.toml")).unwrap();
    let f = 1.0 / 0.184;
    for (rate, xi_within, f_within, rms) in
        [(1_000.0, 9e-3, 2e-4, 0.12), (10_000.0, 5e-3, 1e-4, 0.02)]
    {
        let mut s = base.clone();
        s.rate_hz = rate;
        s.samples = (s.duration_s * rate).round() as u64;
        let out = go(&s, Mode::Fuse);
        let e = &out.report.estimator;
        let id = &e.identified;
        let (df, dxi) = (
            id.natural_frequency_hz / f - 1.0,
            id.damping_ratio / 0.016 - 1.0,
        );
        std::println!(
            "{rate} Hz: f {df:e}, ξ {dxi:e}, {} % RMS",
            e.rms_err_pct_of_peak
        );
        assert!(
            df.abs() < f_within && dxi.abs() < xi_within,
            "{rate} Hz: f {df:e}, ξ {dxi:e}"
        );
        assert!(
            e.rms_err_pct_of_peak < rms,
            "{rate} Hz: {} % RMS",
            e.rms_err_pct_of_peak
        );
    }
}

/// The default scene told its own specimen, fuse mode: the identified f and ξ at 1, 2 and
/// 10 kHz, each event's step and kink of the base acceleration taken from the detector's
/// ring (`PhaseDetector::step_at`) and placed at its time (`OscillatorIdentifier::jump`).
/// Measured ξ̂ +0.63 %, +0.06 %, −0.034 % and f̂ −0.036 %, −0.016 %, +0.0004 % (before, when
/// the step was the second difference across the event, which read a slip start's kink as a
/// step of 0.6–1.4 m/s² at 1 kHz: ξ̂ −3.0 %, −0.36 %, −0.05 %; f̂ −0.086 %, −0.012 %, 0.000 %).
/// Nothing adopted (the prior is right).
#[test]
fn the_default_scenes_identification_at_coarse_rates() {
    for (rate, xi_within, f_within) in [
        (1_000.0, 8e-3, 5e-4),
        (2_000.0, 1.5e-3, 3e-4),
        (10_000.0, 6e-4, 2e-5),
    ] {
        let mut s = Scene::default_scene();
        s.rate_hz = rate;
        s.samples = (s.duration_s * rate).round() as u64;
        let out = go(&s, Mode::Fuse);
        let id = &out.report.estimator.identified;
        let (df, dxi) = (
            id.natural_frequency_hz / 7.0 - 1.0,
            id.damping_ratio / 0.05 - 1.0,
        );
        std::println!("{rate} Hz: f {df:e}, ξ {dxi:e}");
        assert!(
            df.abs() < f_within && dxi.abs() < xi_within,
            "{rate} Hz: f {df:e}, ξ {dxi:e}"
        );
        assert_eq!(
            id.in_use.as_ref().map(|u| u.adoptions),
            Some(0),
            "{rate} Hz"
        );
    }
}
