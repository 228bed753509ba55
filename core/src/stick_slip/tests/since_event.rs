//! Tests of a slide's friction set after its start was pushed
//! ([`StickSlipEstimator::set_friction_since_event`]).

use super::*;
use crate::math::Libm;
use crate::structure::table1 as structure;
use std::vec::Vec;

/// The estimator of these tests: Table 1 at 1 kHz, no μ identification, a history of 8.
fn estimator<const H: usize>() -> StickSlipEstimator<f64, Libm, H> {
    let cfg = StickSlipConfig {
        identify_mu: false,
        ..StickSlipConfig::DEFAULT
    };
    StickSlipEstimator::with_history(&structure(), 1e3, cfg, 8).unwrap()
}

/// Table and measured top acceleration of sample k at 1 kHz (the top NaN: open loop).
fn inputs(k: u64, measured: bool) -> (f64, f64) {
    let t = k as f64 * 1e-3;
    let y = if measured {
        1.5 * libm::cos(40.0 * t)
    } else {
        f64::NAN
    };
    (2.0 * libm::sin(43.9 * t), y)
}

/// Run to sample `at`, push a slip start `age` samples old there (friction 0.25 set before
/// it when `before`), run `later` more samples, then (unless `before`) set 0.25 since the event;
/// the predictions of the 200 samples after.
fn run<const H: usize>(at: u64, age: f64, later: u64, before: bool, measured: bool) -> Vec<f64> {
    let mut e = estimator::<H>();
    for k in 0..at {
        let (u, y) = inputs(k, measured);
        e.update(u, y);
    }
    if before {
        e.set_friction(0.25);
    }
    e.push_event(1, age).unwrap();
    for k in at..at + later {
        let (u, y) = inputs(k, measured);
        e.update(u, y);
    }
    if !before {
        e.set_friction_since_event(0.25, 0.0);
    }
    (at + later..at + later + 200)
        .map(|k| {
            let (u, y) = inputs(k, measured);
            e.update(u, y)
        })
        .collect()
}

/// The friction set a sample or three after a slip start was pushed (at a sample, 0 to 5
/// samples old, or inside an interval; the intervals since it re-run, up to the history's
/// limit) gives the predictions of an estimator that had
/// it before the push, to 1e-12 m/s² (measured: 0, bit for bit; the same steps, by the
/// re-simulation instead of the updates): open loop and with the sliding observer on a measured
/// top, rings with and without the copy slot, before and after a wrap. Without it (the friction
/// set from the next sample on) they differ by up to 0.12 m/s² (the μ step of 0.05 over one
/// interval and a half, open loop), so the test sees the re-run.
#[test]
fn friction_since_the_event_is_as_if_set_before_it() {
    fn check<const H: usize>() -> f64 {
        let mut worst = 0.0f64;
        for at in [30u64, 33, 37, 41] {
            for (age, later) in [
                (0.0, 2),
                (1.0, 1),
                (2.0, 1),
                (5.0, 1),
                (0.25, 1),
                (1.6, 1),
                (2.5, 3),
            ] {
                for measured in [false, true] {
                    let want = run::<H>(at, age, later, true, measured);
                    let got = run::<H>(at, age, later, false, measured);
                    for (a, b) in want.iter().zip(&got) {
                        assert!(a.is_finite() && b.is_finite());
                        worst = worst.max((a - b).abs());
                    }
                }
            }
        }
        worst
    }
    let (a, b) = (check::<9>(), check::<10>());
    assert!(a <= 1e-12 && b <= 1e-12, "{a:e} {b:e}");
    // The friction from the next sample on only: far from it.
    let mut e = estimator::<10>();
    for k in 0..33 {
        let (u, _) = inputs(k, false);
        e.update(u, f64::NAN);
    }
    e.push_event(1, 1.6).unwrap();
    let (u, _) = inputs(33, false);
    e.update(u, f64::NAN);
    e.set_friction(0.25);
    let want = run::<10>(33, 1.6, 1, true, false);
    assert!(want.iter().all(|x| x.is_finite()));
    let got: Vec<f64> = (34..234)
        .map(|k| e.update(inputs(k, false).0, f64::NAN))
        .collect();
    assert!(got.iter().all(|x| x.is_finite()));
    let diff = got
        .iter()
        .zip(&want)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(diff > 0.05, "{diff:e}");
}

/// Stuck, the friction is set and nothing else: nothing re-run, a top shift (finite or not)
/// ignored; the next prediction is bit for bit that after `set_friction` alone.
#[test]
fn stuck_friction_since_the_event_only_sets_it() {
    let mut e = estimator::<10>();
    for k in 0..20 {
        let (u, y) = inputs(k, true);
        e.update(u, y);
    }
    let mut b = e.clone();
    b.set_friction(0.25);
    let (u, y) = inputs(20, true);
    let want = b.update(u, y).to_bits();
    for shift in [f64::NAN, 0.3] {
        let mut a = e.clone();
        a.set_friction_since_event(0.25, shift);
        assert_eq!(a.update(u, y).to_bits(), want, "{shift}");
        assert_eq!(a.mu_used(), 0.25);
    }
}

/// Two switches inside one interval (a stick, then a slip start the other way): the re-run
/// starts at that interval with both, as the slip start's push did; the predictions are those
/// of an estimator that had the friction before that push, to 1e-12 m/s² (measured: 0).
#[test]
fn two_switches_in_one_interval_are_re_run_alike() {
    let run = |before: bool| -> Vec<f64> {
        let mut e = estimator::<10>();
        for k in 0..30 {
            if k == 10 {
                e.push_event(1, 0.0).unwrap();
            }
            let (u, y) = inputs(k, false);
            e.update(u, y);
        }
        e.push_event(0, 1.7).unwrap();
        if before {
            e.set_friction(0.25);
        }
        e.push_event(-1, 1.2).unwrap();
        let (u, y) = inputs(30, false);
        e.update(u, y);
        if !before {
            e.set_friction_since_event(0.25, 0.0);
        }
        (31..231)
            .map(|k| {
                let (u, y) = inputs(k, false);
                e.update(u, y)
            })
            .collect()
    };
    let (want, got) = (run(true), run(false));
    assert!(want.iter().chain(&got).all(|x| x.is_finite()));
    let worst = want
        .iter()
        .zip(&got)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(worst <= 1e-12, "{worst:e}");
}
