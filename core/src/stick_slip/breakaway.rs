//! The static (breakaway) friction coefficient at a slip start: while the base sticks it moves
//! with the table, so the friction holding it is m1·ü1 + m2·üg; at the slip start that force
//! reaches μs·(m1 + m2)·g. Hence μs = |(M − 1)·ü1 + üg| / (M·g), M = 1 + m1/m2, from the top
//! and table accelerations at the slip start's time (interpolated between the kept samples).

use super::estimator::StickSlipEstimator;
use crate::math::{Real, Transcendentals};

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// The friction coefficient that held the base `age` samples before the next sample (a
    /// detected slip start's age): |(M − 1)·ü1 + üg| / (M·g), with ü1 the measured top
    /// acceleration (`measured`: the fuse mode) or the model's own prediction (the predict
    /// mode) and üg the measured table acceleration, interpolated linearly between the two
    /// kept samples around that time. `None` outside the history, for a negative or non-finite
    /// age, or with a non-finite measurement.
    pub fn breakaway_coefficient(&self, age: T, measured: bool) -> Option<T> {
        self.breakaway(age, measured).map(|(mu, _)| mu)
    }

    /// [`Self::breakaway_coefficient`] and its change over the sample interval it lies in (the
    /// interval before it for the latest kept sample): what an error of the slip start's time
    /// by up to a sample interval changes it by.
    pub fn breakaway(&self, age: T, measured: bool) -> Option<(T, T)> {
        let k = self.sample_index();
        // The time k − age lies between samples j0 = k − ⌈age⌉ and j0 + 1 (the latest kept
        // sample is k − 1: a younger time takes it); NaN fails the range test.
        let back = age.to_f64();
        if k == 0 || !(0.0..self.len as f64 - 1.0).contains(&back) {
            return None;
        }
        let whole = libm::ceil(back).max(1.0);
        let j0 = k.checked_sub(whole as u64)?;
        let w = T::from_f64(whole - back);
        let m = self.c.mp / self.c.p;
        let at = |j: u64| {
            self.slots.get(self.slot_of(j)).map(|s| {
                let top = if measured { s.y } else { s.z[0] };
                ((m - T::ONE) * top + s.u) / (m * self.c.g)
            })
        };
        let f0 = at(j0)?;
        let (f, step) = if j0 + 1 < k {
            let f1 = at(j0 + 1)?;
            (f0 + (f1 - f0) * w, (f1 - f0).abs())
        } else {
            // The latest kept sample: the interval before it, if kept.
            let step = match j0.checked_sub(1) {
                Some(j) if back + 1.0 < self.len as f64 - 1.0 => (f0 - at(j)?).abs(),
                _ => T::ZERO,
            };
            (f0, step)
        };
        let mu = f.abs();
        (mu.is_finite() && step.is_finite()).then_some((mu, step))
    }
}
