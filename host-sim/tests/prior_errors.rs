//! The controller told a wrong specimen (issue 13): the prior's μ, f and m1 off, on the default
//! scene (3 s) and the first 8 s of El Centro. Fuse mode identifies μ (adopted after 128 sliding
//! samples, at any identification block) and f, ξ (from the stuck phases), and corrects its
//! state from the top accelerometer while stuck and while sliding; predict mode identifies μ
//! from the base accelerometer. Bounds are a small margin over what is measured.

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
    let mut opts = RunOptions::new("test");
    opts.mode = mode;
    let out = run(s, std::io::sink(), &opts, &AtomicBool::new(false)).unwrap();
    let e = &out.report.estimator;
    assert!(e.rms_err_pct_of_peak.is_finite() && e.max_err_pct_of_peak.is_finite());
    assert_eq!(out.report.detection.missed, 0);
    assert_eq!(out.report.detection.false_, 0);
    out
}

fn elcentro() -> Scene {
    Scene::load(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/elcentro.toml")).unwrap()
}

/// Fuse mode, μ told 25 % high or low: the sliding observer holds the first episodes and μ̂ is
/// adopted early (measured on these 3 s: default 0.101 % RMS, max 1.39 % / 1.46 %; El Centro
/// 0.094 %, max 1.33 % / 1.30 %; μ̂ within 3e-4; the first episode's error weighs more in 3 s
/// than over the whole run: 0.061 % and 0.035 % RMS there).
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
            assert!(e.rms_err_pct_of_peak < 0.12, "{name} {mu}");
            assert!(e.max_err_pct_of_peak < 1.6, "{name} {mu}");
            let m = e.mu_estimate.unwrap();
            assert!((m / 0.2 - 1.0).abs() < 1e-3, "{name} {mu}: {m}");
        }
    }
}

/// Predict mode on El Centro, μ told 10 % high: μ̂ from the base accelerometer converges to the
/// truth (measured 0.20028 on these 8 s) and the prediction stays within the goal (measured
/// 0.49 % RMS on these 8 s, 0.26 % over the whole record).
#[test]
fn predict_identifies_mu_from_the_base() {
    let out = go(&told(elcentro(), 8.0, 1.1, 1.0, 1.0), Mode::Predict);
    let e = &out.report.estimator;
    let m = e.mu_estimate.unwrap();
    println!("predict: {} % RMS, mu {m}", e.rms_err_pct_of_peak);
    assert!((m / 0.2 - 1.0).abs() < 5e-3, "{m}");
    assert!(e.rms_err_pct_of_peak < 0.6);
}
