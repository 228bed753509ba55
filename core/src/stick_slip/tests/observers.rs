//! The stuck and sliding observers: their error decays at their bandwidths; a held sliding
//! observer stays wide.

use super::*;

/// The open-loop estimator the observers are measured against: no observer, no identification.
const OPEN: StickSlipConfig = StickSlipConfig {
    identify_mu: false,
    observer_bandwidth: 0.0,
    sliding_observer: false,
    ..StickSlipConfig::DEFAULT
};

/// The stuck-phase observer: an error injected into the state (10 ms of a wrong table
/// acceleration) decays like critically damped dynamics at b·p, (1 + b·p·t)·e^(−b·p·t),
/// whatever the damping, at fine and at coarse sampling; the measured top acceleration is an
/// open-loop estimator's prediction (exact for the same model).
#[test]
fn the_observer_error_decays_at_its_bandwidth() {
    for (xi, rate, b) in [
        (0.0, 1e4, 2.0),
        (0.05, 1e4, 2.0),
        (0.9, 1e4, 2.0),
        (0.3, 1e3, 10.0),
        (0.0, 200.0, 10.0),
    ] {
        let s = structure(0.2, xi);
        let open = OPEN;
        let obs = StickSlipConfig {
            observer_bandwidth: b,
            sliding_observer: true,
            ..open
        };
        let mut reference = StickSlipEstimator::<f64, Libm, 8>::new(&s, rate, open).unwrap();
        let mut est = StickSlipEstimator::<f64, Libm, 8>::new(&s, rate, obs).unwrap();
        let w = b * s.p();
        let dt = 1.0 / rate;
        let inject = (0.01 * rate).ceil() as u64;
        let (mut e0, mut worst) = (0.0f64, 0.0f64);
        for k in 0..(inject + (12.0 / (w * dt)) as u64) {
            let u = (2.0 * core::f64::consts::PI * 3.0 * k as f64 * dt).sin();
            let wrong = if k < inject { u + 1.0 } else { u };
            let y = reference.update(u, f64::NAN);
            let pred = est.update(wrong, y);
            let err = (pred - y).abs();
            assert!(err.is_finite(), "error at sample {k} is not finite: {err}");
            if k == inject {
                e0 = err.max(1e-12);
            }
            if k > inject {
                let t = (k - inject) as f64 * dt;
                let bound = 20.0 * (1.0 + w * t) * libm::exp(-w * t);
                worst = worst.max(err / e0 / bound);
            }
        }
        std::println!("xi {xi} rate {rate} b {b}: worst {:.3} of the bound", worst);
        // Measured: ≤ 0.13 of the bound at 10 kHz, 0.50 at b·p·Δt = 0.44 (1 kHz, b = 10),
        // where the discrete double eigenvalue's transient is larger than the continuous
        // one; with the gain of the continuous design this case diverged.
        assert!(worst < 1.0, "xi {xi} rate {rate} b {b}: {worst}");
    }
}

/// The sliding-phase observer: a state error made before a slip start (10 ms of a wrong table
/// acceleration while stuck) decays while sliding like critically damped dynamics at the
/// sliding observer's bandwidth w = 2·b·p·√M (wide: μ̂ not adopted), (1 + w·t)·e^(−w·t) (the
/// reference is the open-loop estimator, exact for the same model); a fast or overdamped
/// sliding oscillator gets no sliding observer. Capped (`cap_sliding_observer`), the wide
/// bandwidth beyond 0.1 rad per sample is allowed up to 0.5: 0.37 at 2 kHz, and at 1 kHz 0.74
/// is held to 0.5; the error decays at that.
#[test]
fn the_sliding_observer_error_decays_at_its_bandwidth() {
    for (xi, rate, b, cap) in [
        (0.0, 1e4, 2.0, false),
        (0.05, 1e4, 2.0, false),
        (0.1, 2e4, 1.0, false),
        (0.05, 2e3, 2.0, true),
        (0.05, 1e3, 2.0, true),
    ] {
        let s = structure(0.2, xi);
        let open = OPEN;
        let obs = StickSlipConfig {
            observer_bandwidth: b,
            sliding_observer: true,
            cap_sliding_observer: cap,
            ..open
        };
        let dt = 1.0 / rate;
        let w = 2.0 * b * s.p() * libm::sqrt(s.mass_ratio());
        assert_eq!(w * dt > 0.1, cap, "{rate}");
        let w = w.min(super::observer::SLIDE_CAPPED_BANDWIDTH / dt);
        let run = |cfg: StickSlipConfig, reference: Option<&[f64]>| {
            let mut est = StickSlipEstimator::<f64, Libm, 8>::new(&s, rate, cfg).unwrap();
            let inject = (0.01 * rate).ceil() as u64;
            let mut out = std::vec::Vec::new();
            for k in 0..(inject + (12.0 / (w * dt)) as u64) {
                let u = (2.0 * core::f64::consts::PI * 3.0 * k as f64 * dt).sin();
                let wrong = if k < inject { u + 1.0 } else { u };
                if k == inject {
                    est.push_event(1, 0.0).unwrap();
                }
                let y = reference.map_or(f64::NAN, |r| r[k as usize]);
                out.push(est.update(if reference.is_some() { wrong } else { u }, y));
            }
            (out, inject as usize)
        };
        let (truth, inject) = run(open, None);
        let (pred, _) = run(obs, Some(&truth));
        let e0 = (pred[inject] - truth[inject]).abs().max(1e-12);
        let mut worst = 0.0f64;
        for k in inject + 1..pred.len() {
            let err = (pred[k] - truth[k]).abs();
            assert!(err.is_finite(), "error at sample {k} is not finite: {err}");
            let t = (k - inject) as f64 * dt;
            worst = worst.max(err / e0 / ((1.0 + w * t) * libm::exp(-w * t)));
        }
        std::println!("xi {xi} rate {rate} b {b}: worst {worst:.3} of the bound, e0 {e0:.3e}");
        // Measured: 0.89, 0.88, 0.93 and, capped, 0.64 (2 kHz) and 0.47 (1 kHz) of the
        // critically damped curve.
        assert!(worst < 1.1, "xi {xi} rate {rate} b {b}: {worst}");
        assert!(e0 > 1e-3, "an error was injected: {e0}");
    }
    // A nearly massless base (√M ≈ 130): the sliding oscillator is too fast for the sample rate.
    let light = Structure::new(StructureParams {
        m2_kg: 0.001,
        ..*structure(0.2, 0.05).params()
    })
    .unwrap();
    let est =
        StickSlipEstimator::<f32, F32Poly, 8>::new(&light, 1e4, StickSlipConfig::DEFAULT).unwrap();
    assert_eq!(est.slides[0].0, [0.0; 2]);
    let est = StickSlipEstimator::<f32, F32Poly, 8>::new(
        &structure(0.2, 0.05),
        1e4,
        StickSlipConfig::DEFAULT,
    )
    .unwrap();
    assert!(est.slides[0].0[0] != 0.0 && est.slides[1].0[0] != 0.0);
    assert!(est.slides[1].0[0].abs() < est.slides[0].0[0].abs());
    // At 2 kHz: no sliding observer uncapped; capped, the wide one only (the narrow one, the
    // model known, would let the noise in).
    for cap in [false, true] {
        let cfg = StickSlipConfig {
            cap_sliding_observer: cap,
            ..StickSlipConfig::DEFAULT
        };
        let est =
            StickSlipEstimator::<f32, F32Poly, 8>::new(&structure(0.2, 0.05), 2e3, cfg).unwrap();
        assert_eq!(est.slides[0].0[0] != 0.0, cap);
        assert_eq!(est.slides[1].0, [0.0; 2]);
    }
}

#[test]
fn for_rate_takes_any_rate() {
    for r in [f64::NAN, -1.0, 0.0, 1.0, 1e3, 1e4, 1e9, f64::INFINITY] {
        let c = StickSlipConfig::DEFAULT.for_rate(r);
        assert!((1..=MAX_IDENTIFY_EVERY).contains(&c.identify_every), "{r}");
    }
    assert_eq!(StickSlipConfig::DEFAULT.for_rate(1e4).identify_every, 32);
    assert_eq!(StickSlipConfig::DEFAULT.for_rate(1e3).identify_every, 3);
}

/// `hold_wide`: μ̂ adopted, the held estimator keeps the wide sliding observer while the other
/// narrows at the adoption; released, it narrows at the next adoption of μ̂ (the next
/// identification block: measured at sample 5 022, released at 5 000), and stays so. The measured top is the truth model's
/// (μ = 0.2), sliding back and forth; both estimators start from μ = 0.25.
#[test]
fn a_held_sliding_observer_stays_wide_until_released() {
    let cfg = StickSlipConfig {
        use_identified_mu: true,
        ..StickSlipConfig::DEFAULT
    }
    .for_rate(1e4);
    let mut truth = StickSlipEstimator::<f64, Libm, 64>::new(
        &structure(0.2, 0.05),
        1e4,
        StickSlipConfig {
            identify_mu: false,
            ..StickSlipConfig::DEFAULT
        },
    )
    .unwrap();
    let mut free =
        StickSlipEstimator::<f64, Libm, 64>::new(&structure(0.25, 0.05), 1e4, cfg).unwrap();
    let mut held = free.clone();
    held.hold_wide(true);
    let wide = free.slides[0].0;
    assert_ne!(wide, free.slides[1].0, "the two observers differ");
    let (mut released_at, mut narrowed_at) = (None, None);
    for k in 0..12_000u64 {
        if k % 700 == 0 {
            let s = if (k / 700) % 2 == 0 { 1 } else { -1 };
            for e in [&mut truth, &mut free, &mut held] {
                e.push_event(s, 0.0).unwrap();
            }
        }
        let u = 2.0 * (43.9 * k as f64 * 1e-4).sin();
        let y = truth.update(u, f64::NAN);
        free.update(u, y);
        held.update(u, y);
        assert_eq!(held.mu_adopted(), free.mu_adopted(), "k {k}");
        // Narrow once μ̂ is adopted; the held one wide until released.
        let narrow = free.slides[1].0;
        assert_eq!(
            free.slide_gain,
            if free.mu_adopted() { narrow } else { wide }
        );
        if released_at.is_none() {
            assert_eq!(held.slide_gain, wide, "k {k}");
            if free.mu_adopted() && k >= 5_000 {
                held.hold_wide(false);
                released_at = Some(k);
            }
        } else if held.slide_gain == narrow {
            narrowed_at = narrowed_at.or(Some(k));
        } else {
            assert!(narrowed_at.is_none(), "k {k}: wide again");
        }
    }
    assert!(free.mu_adopted());
    assert_eq!(released_at, Some(5_000));
    // Narrow at the first identification block after the release that adopts μ̂ (mid-slide:
    // the slide from 4 900 on), and for good.
    let at = narrowed_at.unwrap();
    std::println!("narrowed at {at}");
    assert!(at > 5_000 && at <= 5_600, "{at}");
}
