//! The estimator (the exact O(1) recursion) driven sample by sample from a scene's reversal train,
//! in either precision.

use super::Precision;
use crate::scene::Scene;
use anyhow::{anyhow, Result};
use ssvr_core::math::{Libm, Real, Transcendentals};
use ssvr_core::recursion::DuhamelRecursion;
use ssvr_core::{ReversalTrain, Structure};

/// The estimator driven from a reversal train: before sample k it pushes every reversal j with
/// t_j in (t_{k−1}, t_k] (for k = 0: t_j ≤ 0), age (t_k − t_j)·rate, in chronological order.
pub struct RecursionRun<'a, T: Real, M: Transcendentals<T>, const K: usize> {
    est: DuhamelRecursion<T, M, K>,
    train: ReversalTrain<'a>,
    rate_hz: f64,
    next_reversal: usize,
    k: u64,
}

impl<'a, T: Real, M: Transcendentals<T>, const K: usize> RecursionRun<'a, T, M, K> {
    /// The estimator of `structure` at `rate_hz`, fed from `train`.
    pub fn new(structure: &Structure, rate_hz: f64, train: ReversalTrain<'a>) -> Result<Self> {
        train
            .validate()
            .map_err(|e| anyhow!("invalid reversal train: {e}"))?;
        let est = DuhamelRecursion::<T, M, K>::new(structure, rate_hz)
            .map_err(|e| anyhow!("cannot build the estimator: {e}"))?;
        Ok(Self {
            est,
            train,
            rate_hz,
            next_reversal: 0,
            k: 0,
        })
    }

    /// ü1 (m/s²) at the next sample, widened to f64.
    pub fn next_sample(&mut self) -> Result<f64> {
        let t = self.k as f64 / self.rate_hz;
        while let Some(r) = self.train.get(self.next_reversal) {
            if r.time_s > t {
                break;
            }
            let age = (t - r.time_s) * self.rate_hz;
            self.est
                .push_reversal(T::from_f64(r.level), T::from_f64(age))
                .map_err(|e| {
                    anyhow!(
                        "estimator: reversal #{} at t = {} s (sample {}): {e}",
                        self.next_reversal,
                        r.time_s,
                        self.k
                    )
                })?;
            self.next_reversal += 1;
        }
        self.k += 1;
        Ok(self.est.update().to_f64())
    }

    /// Reversals pushed so far.
    pub fn reversals(&self) -> usize {
        self.next_reversal
    }
}

/// The estimator in either precision (libm transcendentals, the default capacity).
pub enum AnyRecursion<'a> {
    /// f32.
    F32(Box<RecursionRun<'a, f32, Libm, 256>>),
    /// f64.
    F64(Box<RecursionRun<'a, f64, Libm, 256>>),
}

impl<'a> AnyRecursion<'a> {
    /// Build the estimator in `precision`.
    pub fn new(
        precision: Precision,
        structure: &Structure,
        rate_hz: f64,
        train: ReversalTrain<'a>,
    ) -> Result<Self> {
        Ok(match precision {
            Precision::F32 => {
                AnyRecursion::F32(Box::new(RecursionRun::new(structure, rate_hz, train)?))
            }
            Precision::F64 => {
                AnyRecursion::F64(Box::new(RecursionRun::new(structure, rate_hz, train)?))
            }
        })
    }

    /// ü1 (m/s²) at the next sample.
    pub fn next_sample(&mut self) -> Result<f64> {
        match self {
            AnyRecursion::F32(r) => r.next_sample(),
            AnyRecursion::F64(r) => r.next_sample(),
        }
    }

    /// Reversals pushed so far.
    pub fn reversals(&self) -> usize {
        match self {
            AnyRecursion::F32(r) => r.reversals(),
            AnyRecursion::F64(r) => r.reversals(),
        }
    }
}

/// The scene's RDM reversal train; `what` names the command in the error of a record scene.
pub(super) fn rdm_train<'a>(scene: &'a Scene, what: &str) -> Result<ReversalTrain<'a>> {
    scene.rdm_train().ok_or_else(|| {
        anyhow!(
            "{what} needs a harmonic or reversals scene; scene \"{}\" has kind = \"{}\" (its \
             reversals come from the stick-slip simulation)",
            scene.name,
            scene.input.kind()
        )
    })
}
