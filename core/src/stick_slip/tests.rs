//! Unit tests of the stick-slip estimator.

use super::maps::mat;
use super::packed;
use super::phase::Level;
use super::*;
use crate::error::Param;
use crate::math::{F32Poly, Libm};
use crate::structure::{Structure, StructureParams};

fn structure(mu: f64, xi: f64) -> Structure {
    Structure::new(StructureParams {
        m1_kg: 29.5,
        m2_kg: 1.75,
        natural_frequency_hz: 7.0,
        damping_ratio: xi,
        friction_coefficient: mu,
        gravity_m_s2: 9.80665,
    })
    .unwrap()
}

/// Table acceleration and measured top acceleration of sample k.
fn inputs(k: u64) -> (f32, f32) {
    let t = k as f32 * 1e-4;
    (2.0 * (43.9 * t).sin(), 1.5 * (40.0 * t).cos())
}

/// (sample, phase, age) events: slip, stick, slip back, old stick, slip.
const EVENTS: [(u64, i8, f32); 6] = [
    (40, 1, 0.25),
    (300, 0, 100.5),
    (330, -1, 3.75),
    (700, 0, 60.0),
    (705, 1, 0.0),
    (720, 1, 2.5),
];

fn drive<const H: usize>(
    est: &mut StickSlipEstimator<f32, F32Poly, H>,
    n: u64,
) -> std::vec::Vec<u32> {
    (0..n)
        .map(|k| {
            for &(_, p, a) in EVENTS.iter().filter(|e| e.0 == k) {
                est.push_event(p, a).unwrap();
            }
            let (u, y) = inputs(k);
            est.update(u, y).to_bits()
        })
        .collect()
}

/// [`drive`] skipping the events older than the history.
fn drive_lenient<const H: usize>(
    est: &mut StickSlipEstimator<f32, F32Poly, H>,
    n: u64,
) -> std::vec::Vec<u32> {
    (0..n)
        .map(|k| {
            for &(_, p, a) in EVENTS.iter().filter(|e| e.0 == k) {
                let _ = est.push_event(p, a);
            }
            let (u, y) = inputs(k);
            est.update(u, y).to_bits()
        })
        .collect()
}

#[test]
fn coefficients_round_trip_through_their_bits() {
    for xi in [0.05, 0.0, 0.99, 0.5] {
        let s = structure(0.2, xi);
        let c = StickSlipCoefficients::<f32>::new(&s, 1e4).unwrap();
        let back = StickSlipCoefficients::<f32>::from_bits(&c.to_bits()).unwrap();
        assert_eq!(back.to_bits(), c.to_bits());
        let mut bad = c.to_bits();
        bad[31] = 3;
        assert!(StickSlipCoefficients::<f32>::from_bits(&bad).is_none());
    }
    let s = structure(0.2, 0.05);
    let cfg = StickSlipConfig::DEFAULT;
    let mut a = StickSlipEstimator::<f32, F32Poly, 200>::new(&s, 1e4, cfg).unwrap();
    let c = StickSlipCoefficients::<f32>::from_bits(&a.coefficients().to_bits()).unwrap();
    let mut b = StickSlipEstimator::<f32, F32Poly, 200>::from_coefficients(c, cfg, 200).unwrap();
    assert_eq!(drive(&mut a, 3000), drive(&mut b, 3000));
}

#[test]
fn the_history_length_not_the_storage_decides() {
    let s = structure(0.2, 0.05);
    let cfg = StickSlipConfig {
        use_identified_mu: true,
        min_blocks: 100,
        ..StickSlipConfig::DEFAULT
    };
    let mut a = StickSlipEstimator::<f32, F32Poly, 144>::new(&s, 1e4, cfg).unwrap();
    let mut b = StickSlipEstimator::<f32, F32Poly, 512>::with_history(&s, 1e4, cfg, 144).unwrap();
    assert_eq!(b.history(), 144);
    assert_eq!(drive(&mut a, 5000), drive(&mut b, 5000));
    let (ma, mb) = (a.mu_estimate().unwrap(), b.mu_estimate().unwrap());
    assert_eq!((ma.mu, ma.std, ma.blocks), (mb.mu, mb.std, mb.blocks));
    for d in 0..150 {
        assert_eq!(
            a.prediction_at(4999 - d).map(f32::to_bits),
            b.prediction_at(4999 - d).map(f32::to_bits)
        );
    }
    assert!(a.prediction_at(5000 - 145).is_none() && a.prediction_at(5000).is_none());
    // Storages with a copy slot, and a multiple of the block plus one (the wrap aligned with
    // the blocks): the same results.
    assert_eq!(storage_for(144, 16), 145);
    let mut c = StickSlipEstimator::<f32, F32Poly, 145>::new(&s, 1e4, cfg).unwrap();
    let mut d = StickSlipEstimator::<f32, F32Poly, 145>::with_history(&s, 1e4, cfg, 144).unwrap();
    let mut e = StickSlipEstimator::<f32, F32Poly, 146>::with_history(&s, 1e4, cfg, 144).unwrap();
    let mut b = StickSlipEstimator::<f32, F32Poly, 512>::with_history(&s, 1e4, cfg, 144).unwrap();
    let want = drive(&mut b, 5000);
    assert_eq!(drive(&mut c, 5000), want);
    assert_eq!(drive(&mut d, 5000), want);
    assert_eq!(drive(&mut e, 5000), want);
    for short in [2, 3, 17, 39, 40, 48] {
        let mut a =
            StickSlipEstimator::<f32, F32Poly, 512>::with_history(&s, 1e4, cfg, short).unwrap();
        let mut b =
            StickSlipEstimator::<f32, F32Poly, 49>::with_history(&s, 1e4, cfg, short).unwrap();
        let mut c =
            StickSlipEstimator::<f32, F32Poly, 48>::with_history(&s, 1e4, cfg, short).unwrap();
        let want = drive_lenient(&mut a, 3000);
        assert_eq!(drive_lenient(&mut b, 3000), want, "{short}");
        assert_eq!(drive_lenient(&mut c, 3000), want, "{short}");
        assert_eq!(a.mu_estimate(), b.mu_estimate(), "{short}");
        assert_eq!(a.mu_estimate(), c.mu_estimate(), "{short}");
        for d in 0..60 {
            let (pa, pb) = (a.prediction_at(2999 - d), b.prediction_at(2999 - d));
            assert_eq!(pa.map(f32::to_bits), pb.map(f32::to_bits), "{short}");
        }
    }
    assert!(StickSlipEstimator::<f32, F32Poly, 64>::with_history(&s, 1e4, cfg, 65).is_err());
    assert!(StickSlipEstimator::<f32, F32Poly, 64>::with_history(&s, 1e4, cfg, 1).is_err());
}

#[test]
fn events_within_the_history_are_accepted() {
    let s = structure(0.2, 0.05);
    let mut e =
        StickSlipEstimator::<f64, Libm, 64>::new(&s, 1e4, StickSlipConfig::DEFAULT).unwrap();
    for k in 0..10 {
        e.update(0.1, f64::NAN);
        // Back to sample 0, not before it (the next sample is k + 1).
        assert!(e.push_event(1, k as f64 + 1.5).is_err());
        assert!(e.push_event(1, k as f64 + 1.0).is_ok());
        assert!(e.push_event(1, k as f64 + 0.5).is_ok());
    }
    for _ in 0..100 {
        e.update(0.1, f64::NAN);
    }
    // history 64: an age < 63 samples, or exactly 63 (on a sample), is accepted.
    for age in [0.0, 0.5, 1.0, 61.5, 62.0, 62.75, 63.0] {
        assert!(e.push_event(0, age).is_ok(), "{age}");
    }
    for age in [63.5, 64.0, 1e9, f64::INFINITY, f64::NAN, -1.0] {
        assert!(e.push_event(0, age).is_err(), "{age}");
    }
    assert!(e.push_event(2, 1.0).is_err());
}

mod blocks;
mod friction;
mod identification;
mod observers;
mod retune;
mod since_event;
