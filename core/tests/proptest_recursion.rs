//! Property tests: random structures (all three regimes, mass ratios 1e-3..1e6), sample rates and
//! reversal trains (sub-sample times, several per sample, levels ±1 and 0); the recursion matches the
//! closed form at every sample within the stated bounds.
mod common;
use common::*;
use proptest::prelude::*;
use ssvr_core::closed_form::duhamel::{Reversal, ReversalTrain};
use ssvr_core::math::Libm;

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
    #[test]
    fn recursion_matches_closed_form(
        log_ratio in -3.0f64..6.0,
        xi in 0.0f64..0.99,
        f_hz in 0.5f64..50.0,
        samples_per_period in 0.3f64..2000.0,
        gaps in proptest::collection::vec((0.0f64..400.0, 0usize..3), 1..40),
        first in 0.0f64..50.0,
    ) {
        let s = structure(10f64.powf(log_ratio), 1.0, f_hz, xi);
        let rate = f_hz * samples_per_period;
        let mut t = first / rate;
        let mut level = 0.0;
        let mut train = Vec::new();
        for (gap, kind) in gaps {
            // kind 0/1: reverse; 2: stick (level 0) unless already stuck.
            let next = match kind { 2 if level != 0.0 => 0.0, _ => if level > 0.0 { -1.0 } else { 1.0 } };
            train.push(Reversal { time_s: t, level: next });
            level = next;
            t += gap.max(1e-3) / rate;
        }
        let train = ReversalTrain::Explicit(&train);
        let n = ((t * rate) as u64 + 300).min(20_000);
        let e32 = run::<f32, Libm, 64>(&s, rate, &train, n, 1);
        let e64 = run::<f64, Libm, 64>(&s, rate, &train, n, 1);
        prop_assert!(e32.max <= 1e-5, "f32 {:e}", e32.max);
        prop_assert!(e64.max <= 1e-10, "f64 {:e}", e64.max);
    }
}
