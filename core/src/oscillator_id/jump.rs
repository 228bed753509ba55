//! A friction event's jump of the base acceleration placed at its time in the identifier's
//! blocks ([`OscillatorIdentifier::jump`]).

use super::{advance, GainRows, OscillatorIdentifier, JUMP_BLOCKS, N};
use crate::math::Real;

impl<T: Real, G: GainRows<T>> OscillatorIdentifier<T, G> {
    /// A jump `step` and a change of slope `kink` (per sample interval) of the base
    /// acceleration at a friction event (a slip start, a reversal, a stick; the detector's
    /// [`PhaseDetector::step_at`](crate::detect::acceleration::PhaseDetector::step_at)) `age`
    /// sample intervals before the next sample pushed.
    ///
    /// The blocks' averages of point samples stand for the signals' averages over the blocks:
    /// for a smooth signal a point sample is its cell's average (the interval of one sample
    /// around it) less h²/24 of its second derivative, the (1, 22, 1)/24 filter of the samples
    /// to O(h⁴), the same discrete filter for the top and the relative acceleration, which
    /// leaves their relation as it is. An event's part of the base acceleration,
    /// E(t) = step·H(t − tₑ) + kink·(t − tₑ)₊, is not smooth: its samples are corrected to its
    /// cells' averages less that filter of its samples, which changes the first sample at or
    /// after the event (k) and the one before (k − 1), nothing else. With φ = age − ⌊age⌋ the
    /// event's fraction of an interval before k (E(k) = step + kink·φ, E(k + 1) = step +
    /// kink·(1 + φ)), the base's corrections are
    ///
    /// * φ < ½: k: step·(φ − 11/24) + kink·((½ + φ)²/2 − (23φ + 1)/24); k − 1: −(step + kink·φ)/24;
    /// * φ ≥ ½: k: (step + kink·(φ − 1))/24; k − 1: step·(φ − ½ − 1/24) + kink·((φ − ½)²/2 − φ/24),
    ///
    /// and the relative acceleration's their negatives. Without them (point samples only) a
    /// jump between two samples sits at the boundary of their cells, up to half a sample from
    /// its time: on a harmonic input whose period is a whole number of samples the events fall
    /// at the same fraction of a sample every cycle, and f̂ and ξ̂ come out biased (Table 2 test
    /// 2 at 1 kHz: ξ̂ 23 % high, f̂ 0.17 % low; at 10 kHz ξ̂ 1.4 % high). With the step at the
    /// event's cell only (its average, the earlier correction) the default scene's exact
    /// record at 1 kHz still gave ξ̂ −0.35 %; with these, −0.013 % (the cells' averages
    /// themselves: −0.018 %).
    ///
    /// Each correction goes into the current block's sum (the next sample's too: the sums add),
    /// or into the chains as the response to the block average's change since its block (the
    /// chains are linear; the rows between are left as they are). Left as it is before the
    /// chains have run two blocks, more than [`JUMP_BLOCKS`] blocks back, or for a step, kink
    /// or age not finite.
    pub fn jump(&mut self, age: T, step: T, kink: T) {
        let a = age.to_f64();
        if self.started < 2 || !(0.0..1e6).contains(&a) || !step.is_finite() || !kink.is_finite() {
            return;
        }
        let whole = libm::floor(a);
        // (In T: on the M4F the f32 unit, not soft-float.)
        let phi = T::from_f64(a - whole);
        let c = |x: f64| T::from_f64(x);
        let half = c(0.5);
        // The base's corrections of samples k (`c0`) and k − 1 (`c1`): (step, kink) factors.
        let (c0, c1) = if phi < half {
            let h = half + phi;
            (
                (
                    phi - c(11.0 / 24.0),
                    h * h * half - (c(23.0) * phi + T::ONE) * c(1.0 / 24.0),
                ),
                (c(-1.0 / 24.0), -phi * c(1.0 / 24.0)),
            )
        } else {
            let h = phi - half;
            (
                (c(1.0 / 24.0), (phi - T::ONE) * c(1.0 / 24.0)),
                (h - c(1.0 / 24.0), h * h * half - phi * c(1.0 / 24.0)),
            )
        };
        let back = whole as u32;
        for (b, (fs, fk)) in [(back, c0), (back + 1, c1)] {
            self.correct(b, -(step * fs + kink * fk));
        }
    }

    /// The relative acceleration of the sample `back` intervals before the next one pushed
    /// changed by `delta` ([`Self::jump`]).
    fn correct(&mut self, back: u32, delta: T) {
        if back <= self.count {
            // (The current block's sum; `back` 0, the next sample, adds to it as well.)
            self.sum_r += delta;
            return;
        }
        let blocks = (back - self.count - 1) / self.decimation + 1;
        // (Not the first block, whose chains started from its own extrapolation, nor one
        // before the identifier's first sample.)
        if blocks > JUMP_BLOCKS || blocks >= self.started {
            return;
        }
        let mut v = [T::ZERO; N];
        advance(&mut v, &self.phi, &self.gamma, delta * self.inv_n);
        for _ in 1..blocks {
            advance(&mut v, &self.phi, &self.gamma, T::ZERO);
        }
        for (x, d) in self.xr.iter_mut().zip(v) {
            *x += d;
        }
    }
}
