//! The exact O(1)-per-sample Duhamel recursion (API stub; implementation in progress).

use crate::error::Error;
use crate::math::{Libm, Real, Transcendentals};
use crate::structure::Structure;
use core::marker::PhantomData;

/// The estimator: predicts top-mass acceleration ü1 (m/s²) sample by sample from friction reversals.
#[derive(Debug, Clone)]
pub struct DuhamelRecursion<T: Real, M: Transcendentals<T> = Libm, const K: usize = 256> {
    gmu: T,
    level: T,
    k: u64,
    _m: PhantomData<M>,
}

/// The firmware default: f32 with libm transcendentals.
pub type Estimator32 = DuhamelRecursion<f32, Libm, 256>;
/// The f64 estimator.
pub type Estimator64 = DuhamelRecursion<f64, Libm, 256>;

impl<T: Real, M: Transcendentals<T>, const K: usize> DuhamelRecursion<T, M, K> {
    /// Build the estimator for `structure` sampled at `sample_rate_hz`.
    pub fn new(structure: &Structure, sample_rate_hz: f64) -> Result<Self, Error> {
        let _ = sample_rate_hz;
        Ok(Self {
            gmu: T::from_f64(structure.gmu()),
            level: T::ZERO,
            k: 0,
            _m: PhantomData,
        })
    }

    /// A friction reversal: the friction level (units of F0 = μ(m1+m2)g, +1, −1 or 0) changed to
    /// `level` `age_samples` ≥ 0 sample intervals before the sample the next [`Self::update`] returns.
    /// Push several reversals in chronological order.
    pub fn push_reversal(&mut self, level: T, age_samples: T) -> Result<(), Error> {
        let _ = age_samples;
        self.level = level;
        Ok(())
    }

    /// The prediction of ü1 (m/s²) at the current sample; then advance one sample.
    pub fn update(&mut self) -> T {
        self.k += 1;
        self.level * self.gmu
    }

    /// The current friction level.
    pub fn level(&self) -> T {
        self.level
    }

    /// Index of the sample the next [`Self::update`] returns.
    pub fn sample_index(&self) -> u64 {
        self.k
    }
}
