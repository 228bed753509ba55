//! Tests of the `plan` module.

use super::*;
use crate::model::open_start_samples;

fn specimen(rate: f64) -> Specimen {
    Specimen {
        structure: crate::test_params(),
        static_friction_coefficient: 0.25,
        sample_rate_hz: rate,
        disp_noise_rms_m: 1e-6,
        accel_noise_rms_m_s2: 5e-3,
        disp_range_m: 0.05,
        friction: FrictionLaw::Coulomb,
    }
}

/// The planned start: the least-squares line through the planned input's first
/// `open_start_samples` samples; exact for a line, within A·(ω·T)³/30 of 0 for a sine from
/// rest (T the start's length), carried by the words; only in a plan without a rest
/// (either mode); `None` without a plan.
#[test]
fn the_plan_carries_the_planned_start() {
    let plan = Plan::new(specimen(10_000.0), ModelKind::StickSlip)
        .unwrap()
        .with_mode(Mode::Predict);
    assert_eq!(plan.planned_start, None);
    assert_eq!(Plan::from_words(&plan.to_words()), Ok(plan));
    let line = plan.with_planned_input(|t| 0.06 + 3.0 * t);
    let p = line.planned_start.unwrap();
    assert!((p.accel_m_s2 - 0.06).abs() < 1e-6, "{p:?}");
    assert!((p.rise_per_sample_m_s2 - 3e-4).abs() < 1e-9, "{p:?}");
    assert_eq!(Plan::from_words(&line.to_words()), Ok(line));
    assert_ne!(line.digest(), plan.digest());
    // Its text form (`SSVR_PLANNED_START`) round-trips; anything else is an error.
    let text = std::format!("{p}");
    assert_eq!(text.parse::<PlannedStart>(), Ok(p));
    for bad in ["", "3d75c28f", "3d75c28f,39d1b717,0", "7fc00000,0", "x,y"] {
        assert_eq!(
            bad.parse::<PlannedStart>(),
            Err(PlanError::Words),
            "{bad:?}"
        );
    }
    // A later `with_rest` drops it, `with_mode` keeps it (fuse mode without a rest uses
    // it too); `with_planned_start` keeps the rule.
    assert_eq!(line.with_rest(0.5).planned_start, None);
    assert_eq!(line.with_mode(Mode::Fuse).planned_start, Some(p));
    let fuse = Plan::new(specimen(10_000.0), ModelKind::StickSlip).unwrap();
    assert_eq!(fuse.with_planned_start(Some(p)).planned_start, Some(p));
    assert_eq!(
        fuse.with_rest(0.5)
            .with_planned_start(Some(p))
            .planned_start,
        None
    );
    // 2 m/s² at 7 Hz from rest: the start is 22 samples (0.1 rad of p), ω·T = 0.097.
    let w = 2.0 * core::f64::consts::PI * 7.0;
    let sine = plan.with_planned_input(|t| 2.0 * libm::sin(w * t));
    let a = sine.planned_start.unwrap().accel_m_s2;
    let n = open_start_samples(&plan.specimen.structure, 10_000.0);
    assert_eq!(n, 22);
    let bound = 2.0 * libm::pow(w * n as f64 / 10_000.0, 3.0) / 30.0;
    assert!((a as f64).abs() < 1.5 * bound, "{a} against {bound}");
    // Only without a rest; no start at 500 Hz (10 samples would span 0.88 rad of p), 10
    // samples at 2 kHz; none for a planned input that is not finite.
    let fuse = Plan::new(specimen(10_000.0), ModelKind::StickSlip).unwrap();
    assert!(fuse.with_planned_input(|_| 1.0).planned_start.is_some());
    let rest = plan.with_rest(0.5);
    assert_eq!(rest.with_planned_input(|_| 1.0).planned_start, None);
    let coarse = |rate| {
        Plan::new(specimen(rate), ModelKind::StickSlip)
            .unwrap()
            .with_mode(Mode::Predict)
            .with_planned_input(|_| 1.0)
            .planned_start
    };
    assert_eq!(coarse(500.0), None);
    assert!(coarse(2_000.0).is_some());
    assert_eq!(plan.with_planned_input(|_| f64::NAN).planned_start, None);
    assert_eq!(plan.with_planned_input(|_| 1e300).planned_start, None);
}

#[test]
fn words_carry_the_friction_law() {
    let law = FrictionLaw::VelocityDependent {
        mu_slow: 0.12,
        rate_s_m: 30.0,
    };
    let mut s = specimen(10_000.0);
    s.static_friction_coefficient = 0.12;
    let coulomb = Plan::new(s, ModelKind::StickSlip).unwrap();
    s.friction = law;
    let plan = Plan::new(s, ModelKind::StickSlip).unwrap();
    assert!(plan.follows_law() && !coulomb.follows_law());
    let back = Plan::from_words(&plan.to_words()).unwrap();
    assert_eq!(back.specimen.friction, law);
    assert_ne!(plan.digest(), coulomb.digest());
    // μ_slow = μ_fast is Coulomb friction: no law followed.
    s.friction = FrictionLaw::VelocityDependent {
        mu_slow: 0.2,
        rate_s_m: 30.0,
    };
    assert!(!Plan::new(s, ModelKind::StickSlip).unwrap().follows_law());
    // An invalid law is refused.
    s.friction = FrictionLaw::VelocityDependent {
        mu_slow: 0.3,
        rate_s_m: 30.0,
    };
    assert!(Plan::new(s, ModelKind::StickSlip).is_err());
}

#[test]
fn words_round_trip_for_every_model_and_rate() {
    for rate in [200.0, 1000.0, 10_000.0, 100_000.0] {
        for m in ModelKind::ALL {
            let p = match Plan::new(specimen(rate), m) {
                Ok(p) => p,
                Err(PlanError::History(h)) => {
                    assert!(h > MAX_HISTORY);
                    continue;
                }
                Err(e) => panic!("{m:?} at {rate} Hz: {e}"),
            };
            let w = p.to_words();
            assert_eq!(Plan::from_words(&w), Ok(p), "{m:?} at {rate} Hz");
            let q = p.with_mode(Mode::Predict).with_rest(0.5);
            assert_eq!(Plan::from_words(&q.to_words()), Ok(q), "{m:?} at {rate} Hz");
            assert_eq!(q.rest_samples as f64, (0.5 * rate).floor());
            assert!(!q.stick_slip.identify_mu && q.stick_slip.observer_bandwidth == 0.0);
            // Strong ramp starts confirmed early in both modes; the mode leaves the detector.
            if let (DetectorPlan::SlipAcceleration(f), DetectorPlan::SlipAcceleration(r)) =
                (p.detector, q.detector)
            {
                assert!(f.early_ramp_starts && r.early_ramp_starts, "{m:?}");
                assert_eq!(q.with_mode(Mode::Fuse).detector, p.detector);
            }
            assert_ne!(q.digest(), p.digest());
            let want = if m == ModelKind::FixedBase {
                (p.max_age + 2).min(FIXED_BASE_HISTORY)
            } else {
                p.max_age + 2
            };
            assert_eq!(p.history, want);
            assert!(p.storage > p.history);
            assert!(p.ring.is_power_of_two());
        }
    }
}

#[test]
fn the_digest_changes_with_any_setting() {
    let a = Plan::new(specimen(10_000.0), ModelKind::StickSlip).unwrap();
    let mut s = specimen(10_000.0);
    s.accel_noise_rms_m_s2 = 6e-3;
    let b = Plan::new(s, ModelKind::StickSlip).unwrap();
    let c = Plan::new(specimen(10_000.0), ModelKind::FixedBase).unwrap();
    assert_ne!(a.digest(), b.digest());
    assert_ne!(a.digest(), c.digest());
    assert_eq!(
        a.digest(),
        Plan::new(specimen(10_000.0), ModelKind::StickSlip)
            .unwrap()
            .digest()
    );
}

#[test]
fn malformed_words_are_errors() {
    let p = Plan::new(specimen(1000.0), ModelKind::Rectangular).unwrap();
    let mut w = p.to_words();
    w[0] = 99;
    assert_eq!(Plan::from_words(&w), Err(PlanError::Words));
    let mut w = p.to_words();
    w[1] = 7;
    assert_eq!(Plan::from_words(&w), Err(PlanError::Words));
}

#[test]
fn bad_specimens_are_typed_errors() {
    let mut s = specimen(1000.0);
    s.structure.damping_ratio = 1.5;
    assert!(matches!(
        Plan::new(s, ModelKind::Rectangular),
        Err(PlanError::Core(_))
    ));
    let mut s = specimen(1000.0);
    s.disp_noise_rms_m = f64::NAN;
    assert!(matches!(
        Plan::new(s, ModelKind::Rectangular),
        Err(PlanError::Core(_))
    ));
}
