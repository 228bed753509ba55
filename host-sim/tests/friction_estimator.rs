//! The estimator on a velocity-dependent interface (issue 15): μ(v) = μ_fast − (μ_fast − μ_slow)·
//! e^{−a|v|} with μ_slow = 0.6·μ_fast, a = 30 s/m, on the default scene (`scenes/ptfe.toml`) and
//! El Centro (`scenes/elcentro-ptfe.toml`), whole runs.
//!
//! The options measured (RMS error, % of the peak; docs/PERFORMANCE.md has the table):
//!
//! | model | default fuse | default predict | El Centro fuse | El Centro predict |
//! |---|---:|---:|---:|---:|
//! | constant μ per episode (identified; the Coulomb model) | 2.09 | 29.2 | 0.57 | 9.64 |
//! | the law, μ(v) from the measured slip speed, identified online | 0.063 | 0.103 (prior's law) | 0.039 | 0.183 (prior's law) |
//!
//! (The constant-μ model's figures were 1.94 / 54.6 / 0.50 / 11.75 before its first slides took μ
//! from the slip starts' breakaway, issue 13.)
//!
//! Identified (fuse): μ_slow 0.11977 / 0.12019, μ_fast 0.19996 / 0.19953, a 30.04 / 30.50 s/m
//! (true 0.12, 0.2, 30). Bounds are a small margin over what is measured.

use host_sim::run::{run, RunOptions, RunOutcome};
use host_sim::scene::Scene;
use ssvr_core::FrictionLaw;
use ssvr_proto::Mode;
use std::path::Path;
use std::sync::atomic::AtomicBool;

fn scene(name: &str) -> Scene {
    Scene::load(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(name),
    )
    .unwrap()
}

fn go(s: &Scene, mode: Mode) -> RunOutcome {
    let mut opts = RunOptions::new("test");
    opts.mode = mode;
    let out = run(s, std::io::sink(), &opts, &AtomicBool::new(false)).unwrap();
    let e = &out.report.estimator;
    assert!(e.rms_err_pct_of_peak.is_finite() && e.max_err_pct_of_peak.is_finite());
    assert_eq!(out.report.detection.missed, 0);
    assert_eq!(out.report.detection.false_, 0);
    out
}

/// The same scene with the controller told Coulomb friction (the constant-μ model).
fn told_coulomb(mut s: Scene) -> Scene {
    s.estimator.friction = FrictionLaw::Coulomb;
    let e = &mut s.estimator;
    e.static_friction_coefficient = e
        .static_friction_coefficient
        .max(e.params.friction_coefficient);
    s
}

#[test]
fn the_law_meets_the_goal_where_constant_mu_does_not() {
    // (scene, fuse RMS bound, predict RMS bound, constant-μ fuse RMS at least, constant-μ
    // predict RMS at least); measured 0.063 / 0.103 / 2.09 / 29.2 and 0.039 / 0.183 / 0.57 / 7.35
    // (the constant-μ model's predict mode was 54.6 % and 11.75 % before its first slides took
    // μ from the breakaway, and El Centro's 9.64 % before that μ came from the slip start's
    // sliding side: μ(v) at the start, not μs times the prior's μ/μs).
    for (name, fuse_max, predict_max, coulomb_fuse_min, coulomb_predict_min) in [
        ("ptfe.toml", 0.075, 0.13, 1.8, 25.0),
        ("elcentro-ptfe.toml", 0.045, 0.21, 0.45, 6.5),
    ] {
        let s = scene(name);
        let fuse = go(&s, Mode::Fuse);
        let e = &fuse.report.estimator;
        let law = e
            .identified
            .friction
            .as_ref()
            .expect("the model follows the law");
        println!(
            "{name} fuse: {:.4} % RMS, {:.3} % max; law {law:?}",
            e.rms_err_pct_of_peak, e.max_err_pct_of_peak
        );
        assert!(e.rms_err_pct_of_peak < fuse_max, "{name}");
        assert!(e.rms_err_pct_of_peak <= 0.5, "{name}: the goal");
        assert_eq!(law.law, "velocity-dependent");
        assert!(law.adoptions > 0, "{name}");
        // Identified within 3 % (the goal); measured within 0.3 % (μ) and 1.7 % (a).
        assert!((law.mu_slow / 0.12 - 1.0).abs() < 5e-3, "{name}: {law:?}");
        assert!((law.mu_fast / 0.2 - 1.0).abs() < 5e-3, "{name}: {law:?}");
        assert!((law.rate_s_m / 30.0 - 1.0).abs() < 0.025, "{name}: {law:?}");

        let predict = go(&s, Mode::Predict);
        let e = &predict.report.estimator;
        println!("{name} predict: {:.4} % RMS", e.rms_err_pct_of_peak);
        assert!(e.rms_err_pct_of_peak < predict_max, "{name}");
        // Predict mode reads no top accelerometer: the prior's law, not identified.
        let law = e.identified.friction.as_ref().unwrap();
        assert_eq!(law.adoptions, 0);
        assert!((law.mu_slow - 0.12).abs() < 1e-7, "{law:?}");

        // The constant-μ model beside it.
        let c = told_coulomb(s.clone());
        let cf = go(&c, Mode::Fuse);
        let cp = go(&c, Mode::Predict);
        let (f, p) = (
            cf.report.estimator.rms_err_pct_of_peak,
            cp.report.estimator.rms_err_pct_of_peak,
        );
        println!("{name} constant μ: fuse {f:.3} %, predict {p:.2} % RMS");
        assert!(cf.report.estimator.identified.friction.is_none());
        assert!(
            f > coulomb_fuse_min && p > coulomb_predict_min,
            "{name}: {f} {p}"
        );
    }
}

/// A wrong prior law (μ_slow 25 % high, a ×2, μ_fast +10 %): identified from the sliding phases
/// all the same (to the same values: the fit does not start from the prior), adopted from 256
/// observations on; the error before the first adoption dominates (measured on the default
/// scene 0.087 / 0.084 / 0.074 % RMS, El Centro 0.044 / 0.052 / 0.046 %).
#[test]
fn a_wrong_prior_law_is_identified() {
    for (name, bound) in [("ptfe.toml", 0.10), ("elcentro-ptfe.toml", 0.06)] {
        for (mu_slow, rate, mu_fast) in [(0.15, 30.0, 0.2), (0.12, 60.0, 0.2), (0.12, 30.0, 0.22)] {
            let mut s = scene(name);
            s.estimator.friction = FrictionLaw::velocity_dependent(mu_slow, rate, mu_fast).unwrap();
            s.estimator.params.friction_coefficient = mu_fast;
            s.estimator.static_friction_coefficient =
                s.estimator.static_friction_coefficient.max(mu_slow);
            let out = go(&s, Mode::Fuse);
            let e = &out.report.estimator;
            let law = e.identified.friction.as_ref().unwrap();
            println!(
                "{name} told ({mu_slow}, {rate}, {mu_fast}): {:.4} % RMS; {law:?}",
                e.rms_err_pct_of_peak
            );
            assert!(e.rms_err_pct_of_peak < bound, "{name}");
            assert!((law.mu_slow / 0.12 - 1.0).abs() < 5e-3, "{name}: {law:?}");
            assert!((law.mu_fast / 0.2 - 1.0).abs() < 5e-3, "{name}: {law:?}");
        }
    }
}

/// A Coulomb scene has no law in the model and its report has no `friction`.
#[test]
fn coulomb_scenes_model_no_law() {
    let mut s = Scene::default_scene();
    s.duration_s = 2.0;
    s.samples = 20_000;
    let out = go(&s, Mode::Fuse);
    assert!(out.report.estimator.identified.friction.is_none());
    let json = serde_json::to_value(&out.report).unwrap();
    assert!(json["estimator"]["identified"].get("friction").is_none());
}

/// The law under a base accelerometer offset of 0.05 g (no rest before the input: the detector
/// tracks it while the base sticks, and the slip speed reads the corrected base), a base gain
/// 1 % high and 1 % dropped frames, on the default PTFE scene (measured 0.0632 % RMS, the law
/// within 0.6 %; unperturbed 0.0630 %).
#[test]
fn the_law_holds_under_base_offset_gain_and_dropouts() {
    let mut s = scene("ptfe.toml");
    s.sensors.accel_bias_m_s2 = [0.0, 0.49, 0.0];
    s.sensors.accel_gain_error = [0.0, 0.01, 0.0];
    s.sensors.dropout_probability = 0.01;
    let out = go(&s, Mode::Fuse);
    let e = &out.report.estimator;
    let law = e.identified.friction.as_ref().unwrap();
    println!("perturbed: {:.4} % RMS; {law:?}", e.rms_err_pct_of_peak);
    assert!(e.rms_err_pct_of_peak < 0.075);
    assert!((law.mu_slow / 0.12 - 1.0).abs() < 0.015, "{law:?}");
    assert!((law.mu_fast / 0.2 - 1.0).abs() < 0.01, "{law:?}");
}
