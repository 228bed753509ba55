//! Tests of the `displacement` module.

use super::*;

#[test]
fn rings_and_the_longest_back_dating() {
    // 10 kHz: fits over 20 samples, sticks after 100.
    let c = DetectorConfig::for_noise(1e-6, 1e4).unwrap();
    assert_eq!((c.fit_half, c.stick_samples), (20, 100));
    assert_eq!((c.min_ring(), c.ring_for_sticks()), (64, 128));
    assert_eq!(c.max_age_samples(64), 142);
    assert_eq!(c.max_age_samples(128), 142);
    // 1 kHz: fits over 2 samples, sticks after 10.
    let c = DetectorConfig::for_noise(1e-6, 1e3).unwrap();
    assert_eq!((c.min_ring(), c.ring_for_sticks()), (8, 32));
    assert_eq!(c.max_age_samples(32), 32);
    assert!(ReversalDetector::<8>::new(c).is_ok());
}

#[test]
fn locates_events_with_the_slip_acceleration() {
    let cfg = DetectorConfig {
        hysteresis_m: 2e-6,
        fit_half: 20,
        stick_samples: 100,
        cubic_breakaway: true,
    };
    let dt = 1e-4f64;
    // Piecewise constant jerk: breakaway at t0 with a ramping acceleration (x ∝ u³), constant
    // deceleration to a reversal at te (the acceleration jumps), then a deceleration to a stick.
    let t0 = 0.0051234f64;
    let j = 400.0;
    let t1 = t0 + 0.008;
    let v1 = 0.5 * j * (t1 - t0).powi(2);
    let te = t1 + v1 / 3.0;
    let tm = te + 0.01;
    let vm: f64 = -2.0 * 0.01;
    let ts = tm + vm.abs() / 4.0;
    // (start, acceleration at start, jerk)
    let segs = [
        (t0, 0.0, j),
        (t1, -3.0, 0.0),
        (te, -2.0, 0.0),
        (tm, 4.0, 0.0),
        (ts, 0.0, 0.0),
    ];
    let slip = |t: f64| -> (f64, f64) {
        let (mut x, mut v) = (0.0f64, 0.0f64);
        if t < t0 {
            return (0.0, 0.0);
        }
        for (i, &(start, a0, jk)) in segs.iter().enumerate() {
            let end = segs.get(i + 1).map_or(f64::INFINITY, |s| s.0);
            let u = (t.min(end) - start).max(0.0);
            let a = if i == segs.len() - 1 {
                0.0
            } else {
                a0 + jk * u
            };
            if t < end || i == segs.len() - 1 {
                let (xa, va) = if i == segs.len() - 1 {
                    (x, 0.0)
                } else {
                    (
                        x + v * u + 0.5 * a0 * u * u + jk * u.powi(3) / 6.0,
                        v + a0 * u + 0.5 * jk * u * u,
                    )
                };
                let _ = va;
                return (xa, a);
            }
            x += v * u + 0.5 * a0 * u * u + jk * u.powi(3) / 6.0;
            v += a0 * u + 0.5 * jk * u * u;
        }
        (x, 0.0)
    };
    let mut det = ReversalDetector::<256>::new(cfg).unwrap();
    let mut found = std::vec::Vec::new();
    for k in 0..900u64 {
        let (x, a) = slip(k as f64 * dt);
        if let Some(e) = det.process_with_accel(x as f32, a as f32) {
            found.push((k as f64 - e.age_samples() as f64) * dt);
        }
    }
    std::println!("{found:?} vs {:?}", [t0, te, ts]);
    assert_eq!(found.len(), 3, "{found:?}");
    for (got, want) in found.iter().zip([t0, te, ts]) {
        assert!((got - want).abs() < 0.1 * dt, "{got} vs {want}");
    }
}

/// A piecewise-parabolic slip with a reversal at a sub-sample time and different curvatures.
#[test]
fn locates_a_sub_sample_reversal_without_noise() {
    let cfg = DetectorConfig {
        hysteresis_m: 2e-6,
        fit_half: 20,
        stick_samples: 10_000,
        cubic_breakaway: true,
    };
    let mut det = ReversalDetector::<64>::new(cfg).unwrap();
    let dt = 1e-4f64;
    let te = 0.0123456;
    let slip = |t: f64| {
        let u = t - te;
        if t < 0.002 {
            0.0
        } else if u < 0.0 {
            1e-3 - 0.5 * 3.0 * u * u
        } else {
            1e-3 - 0.5 * 5.0 * u * u
        }
    };
    let mut events = std::vec::Vec::new();
    for k in 0..400u64 {
        if let Some(e) = det.process(slip(k as f64 * dt) as f32) {
            events.push((k, e));
        }
    }
    let (k, e) = events
        .iter()
        .find(|(_, e)| matches!(e, SlipEvent::Reversal { .. }))
        .copied()
        .unwrap();
    let t_est = (k as f64 - e.age_samples() as f64) * dt;
    assert!((t_est - te).abs() < 0.05 * dt, "{t_est} vs {te}");
    assert_eq!(e.friction_level(), 1.0);
}
