//! The slip acceleration's step and kink at a friction event ([`PhaseDetector::step_at`]), for
//! the oscillator identifier, which places them at the event's time in its block averages
//! ([`OscillatorIdentifier::jump`](crate::oscillator_id::OscillatorIdentifier::jump)).

use super::super::EventStep;
use super::{missing, PhaseDetector};

impl<const N: usize> PhaseDetector<N> {
    /// The change of the slip acceleration (m/s²) at the event just detected, `age` sample
    /// intervals before the last sample processed, `stick` when the event is a stick: the line
    /// after the event less the line before it, both at the event's time (the step), and the
    /// change of their slopes (the kink, m/s² per sample interval). Before: the line through
    /// the two samples before the event. After: through the first two samples at or after it
    /// when both have been processed; with only the first, a stick's line is flat (stuck, the
    /// base moves with the table: the slip acceleration is constant), another event's has the
    /// slope before it (no kink).
    ///
    /// The base accelerometer's jump and kink at a friction event (the table's acceleration is
    /// smooth), for the identifier, which needs the event's time to a fraction of a sample.
    /// Taking the slope on each side keeps a kink (a slip start when μs = μ: the slope of s̈
    /// changes, s̈ does not jump) from reading as a step: the second difference across it, the
    /// earlier estimate, read steps of 0.6–1.4 m/s² at the default scene's slip starts at
    /// 1 kHz (kinks of 1.2–2.6 m/s² a sample), which biased the identified ξ by −3 %.
    ///
    /// [`EventStep::UNKNOWN`] when the slide's integrated velocity is uncertain by more than a
    /// quarter sample's worth of the s̈ before the event (a jump breakaway, μs > μ, is timed to
    /// a sample only, and the velocity carries that: at 1 kHz on El Centro the sticks' ages came
    /// out up to 0.8 sample off), when one of the samples is missing, beyond the ring or for an
    /// age not finite.
    pub fn step_at(&self, age: f32, stick: bool) -> EventStep {
        let back = libm::floorf(age);
        if !(back >= 0.0 && back + 3.0 <= N as f32) || self.k < back as u64 + 3 {
            return EventStep::UNKNOWN;
        }
        let phi = age - back;
        let back = back as u64;
        // The first sample at or after the event, and the two before it.
        let k = self.k - 1 - back;
        let (at, before, earlier) = (self.at(k), self.at(k - 1), self.at(k - 2));
        // The sample after the first one, when processed (a stick's slope after is 0).
        let after = (back >= 1 && !stick).then(|| self.at(k + 1));
        if self.v_unc > 0.25 * libm::fabsf(before) || {
            let mask = self.missing_mask(self.k - 1);
            (0..3).any(|j| missing(mask, back + j)) || (after.is_some() && missing(mask, back - 1))
        } {
            return EventStep::UNKNOWN;
        }
        let slope_before = before - earlier;
        let slope_after = match after {
            Some(next) => next - at,
            None if stick => 0.0,
            None => slope_before,
        };
        EventStep {
            step: (at - slope_after * phi) - (before + slope_before * (1.0 - phi)),
            kink: slope_after - slope_before,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{PhaseDetector, PhaseDetectorConfig};

    /// A detector fed `x(k)` for k in 0..n (offset-free from the start: the first samples,
    /// the offset's, are 0).
    fn fed(n: u32, x: impl Fn(f32) -> f32) -> PhaseDetector<64> {
        let cfg = PhaseDetectorConfig::for_noise(5e-3).unwrap();
        let mut d = PhaseDetector::<64>::new(cfg).unwrap();
        for k in 0..n {
            d.process(if k < 100 { 0.0 } else { x(k as f32) });
        }
        d
    }

    /// A ramp of 0.01 m/s² per sample with a step of 2 m/s² at sample 500 (its first sample
    /// after), read 0.4 sample ages later and 6 samples after it: the step, the ramp's slope
    /// removed, no kink, to f32's rounding; unknown beyond the ring or for a NaN age.
    #[test]
    fn the_step_at_an_event() {
        let d = fed(506, |k| {
            0.01 * (k - 100.0) + if k >= 500.0 { 2.0 } else { 0.0 }
        });
        // The last sample is 505: sample 500 is 5 back, the event 5.4 sample intervals old.
        let e = d.step_at(5.4, false);
        assert!((e.step - 2.0).abs() < 1e-4 && e.kink.abs() < 1e-4, "{e:?}");
        let none = d.step_at(2.0, false);
        assert!(none.step.abs() < 1e-4 && none.kink.abs() < 1e-4, "{none:?}");
        assert!(!d.step_at(62.0, false).is_known() && !d.step_at(f32::NAN, false).is_known());
        assert!(!d.step_at(-1.0, false).is_known());
    }

    /// A kink without a step (a slip start when μs = μ): s̈ = 0.8·(k − k_e) m/s² after an event
    /// at k_e = 499.3 (0.7 of a sample before sample 500), read 1.7 and 3.7 samples after it:
    /// no step and the kink, to f32's rounding (the second difference across it, the earlier
    /// estimate, read a step of 0.56 m/s²). A stick read at its first sample (0.3 after it),
    /// s̈ from a slope of −0.5 m/s² a sample to 0 (stuck) with a step of 3 m/s²: the step at
    /// its time and the kink, the slope after taken as flat.
    #[test]
    fn a_kink_is_not_a_step() {
        let ke = 499.3;
        let ramp = |k: f32| if k >= 500.0 { 0.8 * (k - ke) } else { 0.0 };
        for (n, age) in [(502, 1.7), (504, 3.7)] {
            let e = fed(n, ramp).step_at(age, false);
            assert!(
                e.step.abs() < 1e-4 && (e.kink - 0.8).abs() < 1e-4,
                "{age}: {e:?}"
            );
        }
        let ks = 499.7;
        let stick = |k: f32| {
            if k < 500.0 {
                10.0 - 0.5 * (k - ks)
            } else {
                0.0
            }
        };
        let e = fed(501, stick).step_at(0.3, true);
        // Before the stick, s̈ at its time is 10; after, 0.
        assert!(
            (e.step + 10.0).abs() < 1e-4 && (e.kink - 0.5).abs() < 1e-4,
            "{e:?}"
        );
    }
}
