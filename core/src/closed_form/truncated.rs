//! The rectangular Duhamel method truncated to the `K` most recent reversals, streaming.
//!
//! The generalised eq (36) (see [`crate::closed_form::duhamel`]) sums one free-vibration term per
//! friction reversal:
//!
//! ```text
//! ü1(t) = gμ [ s(t) − Σ_{t_j ≤ t} Δs_j ecm(t − t_j) ]
//! ```
//!
//! [`TruncatedClosedForm`] keeps only the `K` newest reversals (time and level jump) in a fixed-size
//! [`heapless::Deque`] and sums those terms at each evaluation: O(K) per sample, no allocation. The
//! dropped terms are the truncation error; with damping it falls as e^{−a·(age of the K-th newest
//! reversal)}, for an undamped structure it does not fall at all (every reversal rings forever, so
//! only the full sum or the exact recursion [`crate::recursion`] is right). The result
//! equals [`DuhamelClosedForm::evaluate`](crate::closed_form::duhamel::DuhamelClosedForm::evaluate)
//! with `max_terms = K` (same terms, same compensated summation).

use crate::closed_form::duhamel::TERM_TOLERANCE;
use crate::closed_form::free_vibration::Kernel;
use crate::error::{Error, Param};
use crate::math::Libm;
use crate::structure::Structure;
use heapless::Deque;

/// One stored reversal.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Term {
    time_s: f64,
    level: f64,
    jump: f64,
}

/// The closed form of eq (36) truncated to the `K` newest reversal terms (`K` ≥ 1), fed one
/// reversal at a time.
#[derive(Debug, Clone)]
pub struct TruncatedClosedForm<const K: usize> {
    kernel: Kernel<f64>,
    gmu: f64,
    /// The newest `K` reversals, oldest first.
    terms: Deque<Term, K>,
    /// Friction level after the newest reversal (0 before the first).
    level: f64,
    /// Time of the newest reversal (−∞ before the first).
    last_time_s: f64,
    /// Reversals pushed so far (including those dropped from the window).
    pushed: usize,
}

impl<const K: usize> TruncatedClosedForm<K> {
    /// The truncated closed form of `structure`, no reversal yet (friction zero, at rest).
    pub fn new(structure: &Structure) -> Self {
        Self {
            kernel: Kernel::new(structure),
            gmu: structure.gmu(),
            terms: Deque::new(),
            level: 0.0,
            last_time_s: f64::NEG_INFINITY,
            pushed: 0,
        }
    }

    /// A friction reversal: at `time_s` the friction level (units of F0 = μ(m1+m2)g: +1, −1, or 0
    /// when the base sticks) becomes `level`. Times must be finite and strictly increasing; levels
    /// within [−1, 1]. When `K` reversals are stored the oldest is dropped. A rejected reversal
    /// changes nothing.
    pub fn push_reversal(&mut self, time_s: f64, level: f64) -> Result<(), Error> {
        if !time_s.is_finite() {
            return Err(Error::NotFinite(Param::ReversalTimes));
        }
        if time_s <= self.last_time_s {
            return Err(Error::NotIncreasing { index: self.pushed });
        }
        if !level.is_finite() {
            return Err(Error::NotFinite(Param::ReversalLevel));
        }
        if !(-1.0..=1.0).contains(&level) {
            return Err(Error::OutOfRange {
                param: Param::ReversalLevel,
                value: level,
                expected: "a level in [-1, 1]",
            });
        }
        if K == 0 {
            return Err(Error::CapacityExceeded(Param::ReversalTimes));
        }
        if self.terms.is_full() {
            self.terms.pop_front();
        }
        let term = Term {
            time_s,
            level,
            jump: level - self.level,
        };
        // Cannot fail: there is room (K ≥ 1 and one was made above).
        if self.terms.push_back(term).is_err() {
            return Err(Error::CapacityExceeded(Param::ReversalTimes));
        }
        self.level = level;
        self.last_time_s = time_s;
        self.pushed += 1;
        Ok(())
    }

    /// Top-mass acceleration ü1(t) (m/s²) from the stored reversals at or before `t` (meant for
    /// t at or after the newest reversal; reversals after `t` are ignored, and older ones already
    /// dropped from the window are missing). Terms whose envelope is below
    /// [`TERM_TOLERANCE`] end the sum, as in the full closed form.
    pub fn accel(&self, t: f64) -> f64 {
        let peak = self.kernel.envelope_peak();
        let mut level = None;
        // Neumaier-compensated sum of Δs_j ecm(t − t_j), newest first.
        let (mut sum, mut comp) = (0.0f64, 0.0f64);
        for r in self.terms.iter().rev() {
            if r.time_s > t {
                continue;
            }
            if level.is_none() {
                level = Some(r.level);
            }
            let tau = t - r.time_s;
            if tau > peak && self.kernel.envelope::<Libm>(tau) < TERM_TOLERANCE {
                break;
            }
            let term = r.jump * self.kernel.eval::<Libm>(tau).ecm;
            let s = sum + term;
            comp += if libm::fabs(sum) >= libm::fabs(term) {
                (sum - s) + term
            } else {
                (term - s) + sum
            };
            sum = s;
        }
        match level {
            Some(level) => self.gmu * (level - (sum + comp)),
            None => 0.0,
        }
    }

    /// Number of reversals pushed so far.
    pub fn pushed(&self) -> usize {
        self.pushed
    }

    /// Number of reversals stored (at most `K`).
    pub fn stored(&self) -> usize {
        self.terms.len()
    }

    /// Friction level after the newest reversal.
    pub fn level(&self) -> f64 {
        self.level
    }

    /// Back to rest, no friction, no reversal.
    pub fn reset(&mut self) {
        self.terms.clear();
        self.level = 0.0;
        self.last_time_s = f64::NEG_INFINITY;
        self.pushed = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::closed_form::duhamel::{DuhamelClosedForm, Reversal, ReversalTrain};
    use crate::structure::StructureParams;
    use std::vec::Vec;

    fn table1(xi: f64) -> Structure {
        Structure::new(StructureParams {
            m1_kg: 29.5,
            m2_kg: 1.75,
            natural_frequency_hz: 7.0,
            damping_ratio: xi,
            friction_coefficient: 0.2,
            gravity_m_s2: 9.80665,
        })
        .unwrap()
    }

    /// Streams `train` into a `TruncatedClosedForm<K>` and compares it at many times with the
    /// closed form summing at most K terms.
    fn compare<const K: usize>(s: &Structure, train: &[Reversal], times: &[f64]) -> f64 {
        let cf = DuhamelClosedForm::new(s);
        let tr = ReversalTrain::Explicit(train);
        let mut tc = TruncatedClosedForm::<K>::new(s);
        let mut next = 0;
        let mut worst = 0.0f64;
        for &t in times {
            while next < train.len() && train[next].time_s <= t {
                tc.push_reversal(train[next].time_s, train[next].level)
                    .unwrap();
                next += 1;
            }
            let want = cf.evaluate(&tr, t, K).accel_m_s2;
            worst = worst.max((tc.accel(t) - want).abs() / s.gmu());
        }
        worst
    }

    fn alternating(n: usize, half: f64) -> Vec<Reversal> {
        (0..n)
            .map(|j| Reversal {
                time_s: j as f64 * half,
                level: if j % 2 == 0 { 1.0 } else { -1.0 },
            })
            .collect()
    }

    #[test]
    fn equals_the_closed_form_with_k_terms() {
        let times: Vec<f64> = (0..3000).map(|k| k as f64 * 1.37e-3).collect();
        for xi in [0.0, 0.05, 0.5] {
            let s = table1(xi);
            let train = alternating(60, 0.0715);
            assert!(compare::<1>(&s, &train, &times) <= 1e-14, "xi {xi}");
            assert!(compare::<4>(&s, &train, &times) <= 1e-14, "xi {xi}");
            assert!(compare::<16>(&s, &train, &times) <= 1e-14, "xi {xi}");
            assert!(compare::<64>(&s, &train, &times) <= 1e-14, "xi {xi}");
        }
        // Irregular levels, including stuck intervals (level 0).
        let train = [
            Reversal {
                time_s: 0.01,
                level: -1.0,
            },
            Reversal {
                time_s: 0.05,
                level: 0.0,
            },
            Reversal {
                time_s: 0.0713,
                level: 1.0,
            },
            Reversal {
                time_s: 0.2,
                level: -1.0,
            },
            Reversal {
                time_s: 0.21,
                level: 0.0,
            },
            Reversal {
                time_s: 0.4,
                level: 1.0,
            },
        ];
        assert!(compare::<2>(&table1(0.05), &train, &times) <= 1e-14);
        assert!(compare::<8>(&table1(0.05), &train, &times) <= 1e-14);
    }

    #[test]
    fn enough_terms_reproduce_the_full_sum_with_damping() {
        let s = table1(0.05);
        let train = alternating(200, 0.0715);
        let cf = DuhamelClosedForm::new(&s);
        let tr = ReversalTrain::Explicit(&train);
        let mut tc = TruncatedClosedForm::<32>::new(&s);
        for r in &train {
            tc.push_reversal(r.time_s, r.level).unwrap();
        }
        assert_eq!(tc.stored(), 32);
        assert_eq!(tc.pushed(), 200);
        let t = 199.0 * 0.0715 + 0.03;
        assert!((tc.accel(t) - cf.accel(&tr, t)).abs() < 1e-12 * s.gmu());
    }

    #[test]
    fn bad_reversals_are_rejected_and_change_nothing() {
        let s = table1(0.05);
        let mut tc = TruncatedClosedForm::<4>::new(&s);
        assert_eq!(tc.accel(1.0), 0.0);
        tc.push_reversal(0.1, 1.0).unwrap();
        assert_eq!(
            tc.push_reversal(0.1, -1.0).unwrap_err(),
            Error::NotIncreasing { index: 1 }
        );
        assert_eq!(
            tc.push_reversal(f64::NAN, -1.0).unwrap_err(),
            Error::NotFinite(Param::ReversalTimes)
        );
        assert_eq!(
            tc.push_reversal(0.2, 1.5).unwrap_err().param(),
            Param::ReversalLevel
        );
        assert_eq!(tc.pushed(), 1);
        assert_eq!(tc.level(), 1.0);
        // Before the first reversal: at rest.
        assert_eq!(tc.accel(0.05), 0.0);
        tc.reset();
        assert_eq!(tc.stored(), 0);
    }
}
