//! The stick-slip aware estimator (ssvr-core) against the exact event-driven truth (host-sim), an
//! independent implementation: fed the truth's own events (late, back-dated) and the exact table
//! acceleration, the estimator must reproduce the truth's top acceleration up to rounding.
mod common;
use common::max_finite;
use host_sim::table_motion::TableMotion;
use host_sim::truth::{simulate, EventKind, TruthInput};
use ssvr_core::math::{F32Poly, Libm, Real, Transcendentals};
use ssvr_core::stick_slip::{StickSlipConfig, StickSlipEstimator};
use ssvr_core::{Structure, StructureParams};

fn structure(m1: f64, m2: f64, f_hz: f64, xi: f64, mu: f64, g: f64) -> Structure {
    Structure::new(StructureParams {
        m1_kg: m1,
        m2_kg: m2,
        natural_frequency_hz: f_hz,
        damping_ratio: xi,
        friction_coefficient: mu,
        gravity_m_s2: g,
    })
    .unwrap()
}

/// The truth's phase changes: (time, phase after it: 0 stuck, ±1 friction level).
fn phase_changes(truth: &host_sim::truth::Truth) -> Vec<(f64, i8)> {
    truth
        .events()
        .iter()
        .map(|e| {
            let phase = match e.kind {
                EventKind::SlipStart { direction } => -(direction.sign() as i8),
                EventKind::Reversal { new_direction } => -(new_direction.sign() as i8),
                EventKind::Stick => 0,
            };
            (e.time_s, phase)
        })
        .collect()
}

/// Max |prediction − truth| / peak |truth| with every event pushed `lag` samples late.
fn run<T: Real, M: Transcendentals<T>>(
    s: &Structure,
    table: &TableMotion,
    mu_s: f64,
    duration: f64,
    rate: f64,
    lag: f64,
) -> (f64, usize) {
    let truth = simulate(&TruthInput::new(s, table, duration).with_static_friction(mu_s)).unwrap();
    let events = phase_changes(&truth);
    let cfg = StickSlipConfig {
        identify_mu: false,
        ..StickSlipConfig::default()
    };
    let mut est = StickSlipEstimator::<T, M, 512>::new(s, rate, cfg).unwrap();
    let mut cursor = truth.sampler();
    let n = (duration * rate) as u64;
    let (mut next, mut max_err, mut peak) = (0usize, 0.0f64, 0.0f64);
    for k in 0..n {
        let t = k as f64 / rate;
        while let Some(&(te, phase)) = events.get(next) {
            if te + lag / rate > t {
                break;
            }
            est.push_event(phase, T::from_f64((t - te) * rate)).unwrap();
            next += 1;
        }
        let ts = cursor.sample(t).unwrap();
        let y = est.update(T::from_f64(ts.table_accel_m_s2), T::from_f64(f64::NAN));
        // Samples between an event and its (late) detection are wrong by design.
        let recent = events.get(next).is_some_and(|&(te, _)| te <= t);
        peak = max_finite(peak, ts.top_accel_m_s2.abs(), "truth |ü1|", k);
        if !recent {
            let e = (y.to_f64() - ts.top_accel_m_s2).abs();
            max_err = max_finite(max_err, e, "estimator error", k);
        }
    }
    (max_err / peak, events.len())
}

#[test]
fn follows_the_truth_through_stick_phases() {
    let t1 = structure(29.5, 1.75, 7.0, 0.05, 0.2, 9.80665);
    // Table 2 test 2: sticks twice per cycle (docs/equations.md, "Corrections to the print").
    let t2 = structure(2.0, 1.0, 1.0 / 0.184, 0.016, 0.2, 9.80);
    let elcentro = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/elcentro-1940-ns.txt"),
    )
    .unwrap();
    let (mut times, mut acc) = (Vec::new(), Vec::new());
    for line in elcentro.lines() {
        let v: Vec<f64> = line
            .split_whitespace()
            .filter_map(|x| x.parse().ok())
            .collect();
        if v.len() == 2 && times.len() < 800 {
            times.push(v[0]);
            acc.push(v[1] * 9.80665);
        }
    }
    let record = TableMotion::Record {
        times_s: times,
        accel_m_s2: acc,
    };
    let harmonic = |a: f64, t: f64| TableMotion::Harmonic {
        amplitude_m_s2: a,
        period_s: t,
    };
    let small = TableMotion::Record {
        times_s: vec![0.0, 0.02, 0.04, 0.1, 0.5],
        accel_m_s2: vec![0.0, 0.3, -0.2, 0.1, 0.0],
    };
    // (name, structure, table, μs, duration, f64 bound, f32 bound): bounds are the measured values
    // (worst over the lags, in the comments) with a margin of 2-5. Harmonic input is sampled and interpolated linearly by the estimator (the truth
    // uses the exact sine): an O((ωΔt)²) input error, so harmonic cases are not exact; records are
    // piecewise linear and reproduced to rounding.
    let cases: Vec<(&str, &Structure, TableMotion, f64, f64, f64, f64)> = vec![
        (
            "stuck only, small record",
            &t1,
            small,
            0.2,
            1.0,
            5e-12, // measured 1.4e-12
            3e-6,  // measured 9.0e-7
        ),
        (
            "table 1, 2 m/s2",
            &t1,
            harmonic(2.0, 0.143),
            0.2,
            3.0,
            5e-6, // measured 1.2e-6
            1e-5, // measured 2.3e-6
        ),
        // μs > μ at resonance: the error dynamics under the event sequence grow (about ×2 per
        // 0.3 s): the interpolation error (∝ Δt², see @100k) and f32 rounding are amplified.
        (
            "table 1, mu_s 0.25",
            &t1,
            harmonic(2.0, 0.143),
            0.25,
            3.0,
            2e-3, // measured 7.4e-4
            5e-3, // measured 2.0e-3
        ),
        (
            "table 1, mu_s 0.25 @100k",
            &t1,
            harmonic(2.0, 0.143),
            0.25,
            3.0,
            2e-5, // measured 7.6e-6
            3e-2, // measured 1.2e-2
        ),
        (
            "table 2 test 2",
            &t2,
            harmonic(1.255, 0.2),
            0.2,
            4.0,
            2e-6, // measured 6.5e-7
            1e-5, // measured 3.3e-6
        ),
        // Measured f64 2.4e-12, f32 2.5e-6.
        ("el centro 15 s", &t1, record, 0.25, 15.0, 1e-11, 1e-5),
    ];
    for (name, s, table, mu_s, dur, b64, b32) in &cases {
        let rate = if name.ends_with("@100k") { 1e5 } else { 1e4 };
        for lag in [0.0, 0.37, 23.6] {
            let (e64, n) = run::<f64, Libm>(s, table, *mu_s, *dur, rate, lag);
            let (e32, _) = run::<f32, F32Poly>(s, table, *mu_s, *dur, rate, lag);
            println!("{name}, lag {lag}: {n} events, f64 {e64:.2e}, f32 {e32:.2e} of peak");
            assert!(e64 <= *b64, "{name} lag {lag}: f64 {e64:e}");
            assert!(e32 <= *b32, "{name} lag {lag}: f32 {e32:e}");
        }
    }
}

/// μ̂ from the measured top acceleration (truth + the default sensor noise) with the truth's events.
fn identify(truth_mu: f64, model_mu: f64, table: &TableMotion, duration: f64) -> (f64, f64, u32) {
    use host_sim::scene::Sensors;
    use host_sim::sensors::measure_all;
    let s_true = structure(2.0, 1.0, 1.0 / 0.184, 0.016, truth_mu, 9.80665);
    let s_model = structure(2.0, 1.0, 1.0 / 0.184, 0.016, model_mu, 9.80665);
    let truth = simulate(&TruthInput::new(&s_true, table, duration)).unwrap();
    let rate = 1e4;
    let frames = measure_all(&Sensors::default(), &truth, rate, (duration * rate) as u64);
    // The model adopts μ̂ (at sliding-episode starts): the slip-start states then come from the
    // identified friction, not from the model's initial guess.
    let cfg = StickSlipConfig {
        use_identified_mu: true,
        ..StickSlipConfig::default()
    };
    let mut est = StickSlipEstimator::<f32, F32Poly, 512>::new(&s_model, rate, cfg).unwrap();
    let mut next = 0;
    let events = truth.events();
    for (k, (_, f)) in frames.iter().enumerate() {
        let t = k as f64 / rate;
        while let Some(e) = events.get(next) {
            if e.time_s > t {
                break;
            }
            let phase = match e.kind {
                EventKind::SlipStart { direction } => -(direction.sign() as i8),
                EventKind::Reversal { new_direction } => -(new_direction.sign() as i8),
                EventKind::Stick => 0,
            };
            est.push_event(phase, ((t - e.time_s) * rate) as f32)
                .unwrap();
            next += 1;
        }
        est.update(f.table_accel_m_s2, f.top_accel_m_s2);
    }
    let m = est.mu_estimate().unwrap();
    (m.mu, m.std, m.blocks)
}

#[test]
fn identifies_the_friction_coefficient() {
    let table = TableMotion::Harmonic {
        amplitude_m_s2: 1.255,
        period_s: 0.2,
    };
    for (truth_mu, model_mu) in [(0.2, 0.2), (0.17, 0.2), (0.23, 0.2)] {
        let (mu, std, n) = identify(truth_mu, model_mu, &table, 8.0);
        println!(
            "true mu {truth_mu}, model {model_mu}: mu_hat {mu:.7} ± {std:.2e} from {n} samples \
             ({:.2e} relative)",
            mu / truth_mu - 1.0
        );
        // Measured: ≤ 1.05e-4 relative, std ≤ 1.1e-4 of μ.
        assert!(
            (mu / truth_mu - 1.0).abs() < 3e-4,
            "mu_hat {mu} vs {truth_mu}"
        );
        assert!(std > 0.0 && std < 3e-4 * truth_mu, "std {std}");
    }
}

/// Max |prediction − truth| / peak over the first and the last tenth of a run fed the truth's
/// events one sample late and the truth's top acceleration plus deterministic noise (5 mm/s²)
/// as the measurement, with the stuck-phase observer at `bandwidth` (× p).
fn observed(s: &Structure, table: &TableMotion, duration: f64, bandwidth: f64) -> (f64, f64) {
    let rate = 1e4;
    let truth = simulate(&TruthInput::new(s, table, duration)).unwrap();
    let events = phase_changes(&truth);
    let cfg = StickSlipConfig {
        identify_mu: false,
        observer_bandwidth: bandwidth,
        sliding_observer: bandwidth > 0.0,
        ..StickSlipConfig::default()
    };
    let mut est = StickSlipEstimator::<f32, F32Poly, 64>::new(s, rate, cfg).unwrap();
    let mut cursor = truth.sampler();
    let n = (duration * rate) as u64;
    let (mut next, mut peak) = (0usize, 0.0f64);
    let (mut first, mut last) = (0.0f64, 0.0f64);
    let mut lcg = 12345u64;
    for k in 0..n {
        let t = k as f64 / rate;
        while let Some(&(te, phase)) = events.get(next) {
            if te + 1.0 / rate > t {
                break;
            }
            est.push_event(phase, ((t - te) * rate) as f32).unwrap();
            next += 1;
        }
        let ts = cursor.sample(t).unwrap();
        lcg = lcg
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let noise = 5e-3 * 3f64.sqrt() * (2.0 * (lcg >> 11) as f64 / (1u64 << 53) as f64 - 1.0);
        let y = est.update(
            ts.table_accel_m_s2 as f32,
            (ts.top_accel_m_s2 + noise) as f32,
        );
        peak = max_finite(peak, ts.top_accel_m_s2.abs(), "truth |ü1|", k);
        let recent = events.get(next).is_some_and(|&(te, _)| te <= t);
        let e = if recent {
            0.0
        } else {
            max_finite(
                0.0,
                (y as f64 - ts.top_accel_m_s2).abs(),
                "observed error",
                k,
            )
        };
        if k < n / 10 {
            first = first.max(e);
        } else if k >= n - n / 10 {
            last = last.max(e);
        }
    }
    (first / peak, last / peak)
}

/// Hard case: an undamped structure (ξ = 0), stick-slip at 2 m/s², 20 s. Switching between the
/// sliding and the stuck dynamics at given times pumps up any error (parametric, ~20/s here):
/// open loop (bandwidth 0) the prediction runs away from the truth; with the stuck-phase
/// observer (the default, 2p) the error stays at the noise level, the same at the end of the run
/// as at its start.
#[test]
fn the_observer_keeps_an_undamped_structure_bounded() {
    let s = structure(29.5, 1.75, 7.0, 0.0, 0.2, 9.80665);
    let table = TableMotion::Harmonic {
        amplitude_m_s2: 2.0,
        period_s: 0.143,
    };
    let (first, last) = observed(&s, &table, 20.0, 2.0);
    eprintln!("observer 2p: first tenth {first:.2e}, last tenth {last:.2e} of peak");
    // Measured: 7.7e-4 / 7.2e-4 of the peak (open loop over 2 s: 1.1e-5 / 3e8).
    assert!(first < 2e-3 && last < 2e-3, "{first} {last}");
    let (open_first, open_last) = observed(&s, &table, 2.0, 0.0);
    eprintln!("open loop: first tenth {open_first:.2e}, last tenth {open_last:.2e} of peak");
    assert!(open_last > 100.0 * last, "{open_first} {open_last}");
}

#[test]
#[should_panic(expected = "estimator error at 3 is not finite: NaN")]
fn a_nan_prediction_fails_the_error_maximum() {
    // `f64::max` would keep 1e-3 and a bound of 1e-2 would pass.
    let mut max_err = 1e-3;
    for (k, y) in [0.5, 0.25, 0.125, f64::NAN].into_iter().enumerate() {
        max_err = max_finite(max_err, (y - 0.5f64).abs(), "estimator error", k);
    }
    assert!(max_err <= 1e-2);
}
