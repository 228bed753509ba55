//! The static (breakaway) friction coefficient at a slip start: while the base sticks it moves
//! with the table, so the friction holding it is m1·ü1 + m2·üg; at the slip start that force
//! reaches μs·(m1 + m2)·g. Hence μs = |(M − 1)·ü1 + üg| / (M·g), M = 1 + m1/m2, from the top
//! and table accelerations at the slip start's time (interpolated between the kept samples).
//!
//! Just after the start the base slides: m2·ü2 + m1·ü1 = −μ·(m1 + m2)·g·s, so the kinetic
//! μ = |(M − 1)·ü1 + ü2| / (M·g) with ü2 = üg + s̈ the base's acceleration on the sliding side,
//! s̈ the slip acceleration there (a detector's parabola through the first sliding samples,
//! extrapolated back to the start: ü1 is continuous, ü2 jumps by (μs − μ)·M·g). That needs no
//! μs ([`StickSlipEstimator::slide_coefficient`]).

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
        self.slide_coefficient(age, measured, T::ZERO)
    }

    /// The kinetic friction coefficient of the slide a slip start `age` samples old begins:
    /// |(M − 1)·ü1 + üg + s̈| / (M·g), as [`Self::breakaway_coefficient`] with the base's
    /// acceleration on the sliding side, üg + `slip_accel`, for the table's: `slip_accel` is the
    /// slip acceleration's sliding side at the start (m/s², the detector's; 0 gives μs). `None`
    /// as there, and for a non-finite `slip_accel`.
    pub fn slide_coefficient(&self, age: T, measured: bool, slip_accel: T) -> Option<T> {
        self.coefficient_of(self.slide_demand(age, measured)?, slip_accel)
    }

    /// The force per unit mass that held the base `age` samples before the next sample,
    /// (M − 1)·ü1 + üg (m/s², signed; `measured` as in [`Self::slide_coefficient`]): kept
    /// at a slip start whose sliding side comes later, for [`Self::coefficient_of`]. `None` as
    /// there.
    pub fn slide_demand(&self, age: T, measured: bool) -> Option<T> {
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
        let at = |j: u64| {
            self.slots.get(self.slot_of(j)).map(|s| {
                let top = if measured { s.y } else { s.z[0] };
                (s.u, top)
            })
        };
        let (u0, y0) = at(j0)?;
        let (u1, y1) = if j0 + 1 < k { at(j0 + 1)? } else { (u0, y0) };
        let (u, y) = (u0 + (u1 - u0) * w, y0 + (y1 - y0) * w);
        let m = self.c.mp / self.c.p;
        Some((m - T::ONE) * y + u)
    }

    /// The kinetic friction coefficient |`demand` + `slip_accel`| / (M·g) of a slide whose
    /// [`Self::slide_demand`] at its start is `demand` (`None` when not finite).
    pub fn coefficient_of(&self, demand: T, slip_accel: T) -> Option<T> {
        let m = self.c.mp / self.c.p;
        let mu = (demand + slip_accel).abs() / (m * self.c.g);
        mu.is_finite().then_some(mu)
    }
}
