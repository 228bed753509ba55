//! The sliding phases' friction levels and the breakaway coefficient.

use super::*;

#[test]
fn sliding_phases_are_their_friction_levels() {
    for p in [
        SlidingPhase::Negative,
        SlidingPhase::Stuck,
        SlidingPhase::Positive,
    ] {
        assert_eq!(SlidingPhase::from_level(p.level()), Ok(p));
    }
    assert_eq!(SlidingPhase::Negative.level(), -1);
    assert_eq!(SlidingPhase::Positive.level(), 1);
    assert_eq!(
        SlidingPhase::from_level(2).unwrap_err().param(),
        Param::Phase
    );
    let s = structure(0.2, 0.05);
    let mut e =
        StickSlipEstimator::<f32, F32Poly, 64>::new(&s, 1e4, StickSlipConfig::DEFAULT).unwrap();
    assert_eq!(e.phase(), SlidingPhase::Stuck);
    e.push_event(SlidingPhase::Negative.level(), 0.0).unwrap();
    assert_eq!(e.phase(), SlidingPhase::Negative);
}

/// The breakaway coefficient at an age: |(M − 1)·ü1 + üg| / (M·g) of the top and table
/// accelerations interpolated at that time, computed here by hand from the inputs fed; the
/// slide's coefficient the same with üg + s̈. (Against the exact stick-slip truth:
/// `host-sim/tests/prior_errors.rs`, a static coefficient told wrong.)
#[test]
fn breakaway_coefficient_interpolates_the_held_force() {
    let s = structure(0.2, 0.05);
    let cfg = StickSlipConfig {
        identify_mu: false,
        ..StickSlipConfig::DEFAULT
    };
    let mut est = StickSlipEstimator::<f64, Libm, 40>::with_history(&s, 1e4, cfg, 39).unwrap();
    let u = |k: u64| 0.5 + 0.01 * k as f64;
    let y = |k: u64| 1.0 - 0.02 * k as f64;
    for k in 0..100u64 {
        est.update(u(k), y(k));
    }
    // The next sample is 100; age 2.25 is time 97.75.
    let m = s.mass_ratio();
    let want = |t: f64| {
        let (uu, yy) = (0.5 + 0.01 * t, 1.0 - 0.02 * t);
        ((m - 1.0) * yy + uu).abs() / (m * s.g())
    };
    for age in [1.0, 2.25, 10.5, 30.0] {
        let got = est.breakaway_coefficient(age, true).unwrap();
        assert!((got - want(100.0 - age)).abs() < 1e-12, "{age}: {got}");
    }
    // Younger than the last kept sample: that sample's value.
    let got = est.breakaway_coefficient(0.3, true).unwrap();
    assert!((got - want(99.0)).abs() < 1e-12, "{got}");
    assert!(est.breakaway_coefficient(38.5, true).is_none());
    assert!(est.breakaway_coefficient(-1.0, true).is_none());
    assert!(est.breakaway_coefficient(f64::NAN, true).is_none());
    // The model's own prediction instead of the measurement: finite.
    assert!(est.breakaway_coefficient(2.0, false).unwrap().is_finite());
    // The slide's coefficient: the base's acceleration üg + s̈ for the table's.
    for (age, slip) in [(2.25, 0.0), (2.25, -3.0), (10.5, 0.7)] {
        let got = est.slide_coefficient(age, true, slip).unwrap();
        let t = 100.0 - age;
        let (uu, yy) = (0.5 + 0.01 * t + slip, 1.0 - 0.02 * t);
        let want = ((m - 1.0) * yy + uu).abs() / (m * s.g());
        assert!((got - want).abs() < 1e-12, "{age} {slip}: {got}");
    }
    assert!(est.slide_coefficient(2.0, true, f64::NAN).is_none());
}
