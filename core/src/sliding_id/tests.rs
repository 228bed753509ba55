//! The identifier against the exact sliding response (a damped sinusoid about μ·g·s + b, the
//! parameters put in are the independent reference), with and without noise, in f64 and f32.

use super::*;
use std::vec::Vec;

/// A seeded uniform generator in [−1, 1) (no dependency: a 64-bit LCG's high bits).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

struct Truth {
    omega: f64,
    zeta: f64,
    mu_g: f64,
    offset: f64,
}

/// Samples (value, level) at `rate`: sliding episodes of alternating direction, 100–600
/// samples long with random initial conditions, separated by stuck stretches (level 0);
/// white noise of RMS `noise`.
fn signal(t: &Truth, rate: f64, episodes: usize, noise: f64, seed: u64) -> Vec<(f64, i8)> {
    let mut g = Lcg(seed);
    let mut out = Vec::new();
    let wd = t.omega * (1.0 - t.zeta * t.zeta).sqrt();
    for e in 0..episodes {
        let s: i8 = if e % 2 == 0 { 1 } else { -1 };
        let n = 100 + (300.0 * (g.next() + 1.0)) as usize;
        let (a, b) = (20.0 * g.next(), 20.0 * g.next());
        for k in 0..n {
            let tt = k as f64 / rate;
            let y = t.mu_g * s as f64
                + t.offset
                + (-t.zeta * t.omega * tt).exp() * (a * (wd * tt).cos() + b * (wd * tt).sin());
            out.push((y + noise * 3f64.sqrt() * g.next(), s));
        }
        let stuck = 50 + (100.0 * (g.next() + 1.0)) as usize;
        for _ in 0..stuck {
            out.push((3.0 * g.next(), 0));
        }
    }
    out
}

fn table1() -> Truth {
    // The Table 1 specimen: f = 7 Hz, ξ = 0.05, m1/m2 = 29.5/1.75, μ = 0.2.
    let m = 1.0 + 29.5 / 1.75;
    let p = 2.0 * core::f64::consts::PI * 7.0;
    Truth {
        omega: p * libm::sqrt(m),
        zeta: 0.05 * libm::sqrt(m),
        mu_g: 0.2 * 9.80665,
        offset: 0.3,
    }
}

fn run<T: Real>(t: &Truth, rate: f64, noise: f64, episodes: usize) -> SlidingEstimate {
    let mut id = SlidingIdentifier::<T>::new(rate, t.omega, 1.0).unwrap();
    for (y, s) in signal(t, rate, episodes, noise, 7) {
        id.push(T::from_f64(y), s);
    }
    id.estimate(false).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

#[test]
fn exact_without_noise_in_f64() {
    let t = table1();
    for rate in [1000.0, 2500.0, 10_000.0] {
        let e = run::<f64>(&t, rate, 0.0, 40);
        assert!(rel(e.omega, t.omega) < 1e-9, "{rate}: {e:?}");
        assert!(rel(e.damping_ratio, t.zeta) < 1e-8, "{rate}: {e:?}");
        assert!(rel(e.friction_accel, t.mu_g) < 1e-8, "{rate}: {e:?}");
        assert!((e.offset - t.offset).abs() < 1e-8, "{rate}: {e:?}");
    }
}

#[test]
fn noisy_f32_within_its_standard_deviations() {
    // 5e-3 m/s² RMS noise (the scenes' default) in f32, as on the firmware: measured errors
    // 2e-5 (ω), 6e-4 (ζ), 1e-4 (μg); bounds a few times that, and within 4σ.
    let t = table1();
    let e = run::<f32>(&t, 10_000.0, 5e-3, 60);
    std::println!("{e:?}");
    assert!(rel(e.omega, t.omega) < 2e-4, "{e:?}");
    assert!(rel(e.damping_ratio, t.zeta) < 5e-3, "{e:?}");
    assert!(rel(e.friction_accel, t.mu_g) < 1e-3, "{e:?}");
    assert!((e.offset - t.offset).abs() < 2e-3, "{e:?}");
    assert!((e.omega - t.omega).abs() < 4.0 * e.omega_std, "{e:?}");
    assert!(
        (e.friction_accel - t.mu_g).abs() < 4.0 * e.friction_accel_std,
        "{e:?}"
    );
    assert!(e.omega_std > 0.0 && e.friction_accel_std > 0.0);
}

/// One direction only, offset not known: the estimate is that direction's friction with the
/// offset in it, μ·g + s·b (exact without noise), ω and ζ as from both; the other direction
/// then separates them.
#[test]
fn one_way_gives_that_direction_s_level() {
    let t = table1();
    let mut id = SlidingIdentifier::<f64>::new(10_000.0, t.omega, 1.0).unwrap();
    let samples = signal(&t, 10_000.0, 2, 0.0, 7);
    let first_minus = samples.iter().position(|&(_, s)| s < 0).unwrap();
    for &(y, s) in &samples[..first_minus] {
        id.push(y, s);
    }
    let e = id.estimate(false).unwrap();
    assert_eq!(e.one_way, 1);
    assert!(rel(e.friction_accel, t.mu_g + t.offset) < 1e-8, "{e:?}");
    assert!(rel(e.omega, t.omega) < 1e-9, "{e:?}");
    assert!(rel(e.damping_ratio, t.zeta) < 1e-8, "{e:?}");
    assert_eq!(e.offset, 0.0);
    // A zeroed accelerometer: the offset is taken as 0, not a one-way estimate.
    assert_eq!(id.estimate(true).unwrap().one_way, 0);
    for &(y, s) in &samples[first_minus..] {
        id.push(y, s);
    }
    let e = id.estimate(false).unwrap();
    assert_eq!(e.one_way, 0);
    assert!(rel(e.friction_accel, t.mu_g) < 1e-8, "{e:?}");
    assert!((e.offset - t.offset).abs() < 1e-8, "{e:?}");
}

#[test]
fn nothing_before_enough_rows_and_no_panic_on_bad_input() {
    let mut id = SlidingIdentifier::<f32>::new(10_000.0, 186.0, 0.9999).unwrap();
    assert!(id.estimate(true).is_none());
    for k in 0..10_000 {
        let y = if k % 7 == 0 { f32::NAN } else { 1.0 };
        id.push(y, if k % 2 == 0 { 1 } else { -1 });
    }
    // A constant: singular normal equations.
    for _ in 0..10_000 {
        id.push(1.0, 1);
    }
    assert!(id.estimate(true).is_none());
    assert!(SlidingIdentifier::<f32>::new(0.0, 186.0, 1.0).is_err());
    assert!(SlidingIdentifier::<f32>::new(1e4, 186.0, 1.5).is_err());
}

#[test]
fn an_overdamped_sliding_oscillator_gives_no_estimate() {
    let mut id = SlidingIdentifier::<f64>::new(10_000.0, 186.0, 1.0).unwrap();
    // ü2 = μg·s + two decaying exponentials (real roots): no underdamped fit.
    let mut g = Lcg(3);
    for e in 0..40 {
        let s: i8 = if e % 2 == 0 { 1 } else { -1 };
        let (a, b) = (10.0 * g.next(), 10.0 * g.next());
        for k in 0..300 {
            let t = k as f64 / 1e4;
            id.push(
                2.0 * s as f64 + a * (-50.0 * t).exp() + b * (-400.0 * t).exp(),
                s,
            );
        }
        id.push(0.0, 0);
    }
    assert!(id.estimate(true).is_none());
}

#[test]
fn the_series_match_libm() {
    for k in 0..=1000 {
        let x = 0.05 + 0.95 * k as f64 / 1000.0;
        let l = super::ln(x).unwrap();
        assert!((l - libm::log(x)).abs() <= 1e-13, "ln {x}: {l}");
        let c = k as f64 / 1000.0;
        let a = super::acos(c).unwrap();
        assert!(
            (a - libm::acos(c)).abs() <= 2e-15,
            "acos {c}: {a} {}",
            libm::acos(c)
        );
    }
    assert!(super::ln(0.01).is_none() && super::ln(1.5).is_none());
    assert!(super::acos(-0.1).is_none() && super::acos(1.1).is_none());
}

/// A change of units mid-record (an accelerometer's gain correction adopted: the samples so far
/// were 1.01 times what the same accelerations read from then on), at a sample inside a
/// sliding episode: rescaled by 1/1.01 there, the estimate is the one of the whole record in the
/// new units, exact without noise in f64 (measured: ω, ζ, μ·g and the offset within 3e-9);
/// not rescaled, μ·g and the offset come out 0.5 % and 0.7 % off.
#[test]
fn a_change_of_units_is_rescaled() {
    let t = table1();
    let rate = 10_000.0;
    let samples = signal(&t, rate, 40, 0.0, 7);
    // A sample inside a sliding episode, about halfway.
    let at = (samples.len() / 2..samples.len())
        .find(|&k| samples[k].1 != 0 && samples[k - 1].1 == samples[k].1)
        .unwrap();
    let run = |rescale: bool| {
        let mut id = SlidingIdentifier::<f64>::new(rate, t.omega, 1.0).unwrap();
        for (k, &(y, s)) in samples.iter().enumerate() {
            if k == at && rescale {
                id.rescale((1.0 / 1.01) as f32);
            }
            let c = if k < at { 1.01 } else { 1.0 };
            id.push(c * y, s);
        }
        id.estimate(false).unwrap()
    };
    // (The factor passes through f32: the old units are 1/f32(1/1.01) times the new.)
    let c = 1.0 / f64::from((1.0 / 1.01) as f32);
    let mut fixed = SlidingIdentifier::<f64>::new(rate, t.omega, 1.0).unwrap();
    for (k, &(y, s)) in samples.iter().enumerate() {
        fixed.push(if k < at { y * 1.01 / c } else { y }, s);
    }
    let reference = fixed.estimate(false).unwrap();
    let (e, stale) = (run(true), run(false));
    std::println!("{e:?}\n{stale:?}");
    assert!(rel(e.omega, t.omega) < 1e-8, "{e:?}");
    assert!(rel(e.damping_ratio, t.zeta) < 1e-7, "{e:?}");
    assert!(
        rel(e.friction_accel, reference.friction_accel) < 1e-8,
        "{e:?}"
    );
    assert!(rel(e.friction_accel, t.mu_g) < 1e-7, "{e:?}");
    assert!((e.offset - t.offset).abs() < 1e-7, "{e:?}");
    assert!(rel(stale.friction_accel, t.mu_g) > 3e-3, "{stale:?}");
}
