//! The rectangular Duhamel method (RDM): eq (36), corrected and generalised to any train of friction
//! reversals, as a superposition of exact step responses (docs/equations.md):
//!
//! ```text
//! ü1(t) = gμ Σ_{t_j ≤ t} (s_j − s_{j−1}) (1 − ecm(t − t_j)) = gμ [ s(t) − Σ_{t_j ≤ t} Δs_j ecm(t − t_j) ]
//! ```
//!
//! with s = 0 before the first reversal. Terms are summed from the newest reversal backwards
//! (compensated summation) and the sum stops once the bound e^{−r1 τ}(1 + aτ) of every older term is
//! below 1e-20 (relative to gμ): an undamped structure keeps all terms.

use crate::closed_form::free_vibration::Kernel;
use crate::error::{Error, Param};
use crate::math::Libm;
use crate::structure::Structure;

/// Terms whose envelope is below this (per unit gμ) are dropped.
pub const TERM_TOLERANCE: f64 = 1e-20;

/// A friction reversal: at `time_s` the friction level becomes `level` (−1, 0 or +1 times F0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reversal {
    /// Time of the reversal (s).
    pub time_s: f64,
    /// Friction level after the reversal, in units of F0 = μ(m1+m2)g: +1 (F = +F0), −1, or 0 (stuck).
    pub level: f64,
}

/// A train of friction reversals. Before the first reversal the friction is zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ReversalTrain<'a> {
    /// Reversals at `first_s + k·half_period_s`, k = 0, 1, 2, …; levels `initial_sign`, then alternating.
    Periodic {
        /// Time of the first reversal (s).
        first_s: f64,
        /// Interval between reversals (s), > 0.
        half_period_s: f64,
        /// Level after the first reversal, ±1.
        initial_sign: f64,
    },
    /// Reversals at the given strictly increasing times; levels `initial_sign`, then alternating.
    Alternating {
        /// Reversal times (s), finite and strictly increasing.
        times_s: &'a [f64],
        /// Level after the first reversal, ±1.
        initial_sign: f64,
    },
    /// Arbitrary level changes (levels in [−1, 1]).
    Explicit(&'a [Reversal]),
}

impl<'a> ReversalTrain<'a> {
    /// Validate the train: finite, strictly increasing times, signs ±1, levels within [−1, 1].
    pub fn validate(&self) -> Result<(), Error> {
        let sign_ok = |s: f64| s == 1.0 || s == -1.0;
        match *self {
            ReversalTrain::Periodic {
                first_s,
                half_period_s,
                initial_sign,
            } => {
                crate::error::check(Param::ReversalTimes, first_s, true, "finite")?;
                crate::error::check(Param::Period, half_period_s, half_period_s > 0.0, "> 0 s")?;
                crate::error::check(
                    Param::ReversalSign,
                    initial_sign,
                    sign_ok(initial_sign),
                    "+1 or -1",
                )?;
            }
            ReversalTrain::Alternating {
                times_s,
                initial_sign,
            } => {
                crate::error::check(
                    Param::ReversalSign,
                    initial_sign,
                    sign_ok(initial_sign),
                    "+1 or -1",
                )?;
                check_increasing(times_s.iter().copied())?;
            }
            ReversalTrain::Explicit(rs) => {
                for r in rs {
                    crate::error::check(
                        Param::ReversalLevel,
                        r.level,
                        (-1.0..=1.0).contains(&r.level),
                        "a level in [-1, 1]",
                    )?;
                }
                check_increasing(rs.iter().map(|r| r.time_s))?;
            }
        }
        Ok(())
    }

    /// Index of the last reversal at or before `t`, if any.
    pub fn last_index_at_or_before(&self, t: f64) -> Option<usize> {
        match *self {
            ReversalTrain::Periodic {
                first_s,
                half_period_s,
                ..
            } => {
                if t.is_nan() || t < first_s {
                    return None;
                }
                let mut k = libm::floor((t - first_s) / half_period_s);
                // Guard against the division rounding across a reversal time.
                if first_s + k * half_period_s > t {
                    k -= 1.0;
                } else if first_s + (k + 1.0) * half_period_s <= t {
                    k += 1.0;
                }
                if k < 0.0 || k >= usize::MAX as f64 {
                    None
                } else {
                    Some(k as usize)
                }
            }
            ReversalTrain::Alternating { times_s, .. } => {
                let n = times_s.partition_point(|&x| x <= t);
                n.checked_sub(1)
            }
            ReversalTrain::Explicit(rs) => rs.partition_point(|r| r.time_s <= t).checked_sub(1),
        }
    }

    /// Number of reversals (None: unbounded periodic train).
    pub fn len(&self) -> Option<usize> {
        match *self {
            ReversalTrain::Periodic { .. } => None,
            ReversalTrain::Alternating { times_s, .. } => Some(times_s.len()),
            ReversalTrain::Explicit(rs) => Some(rs.len()),
        }
    }

    /// Whether the train has no reversal at all.
    pub fn is_empty(&self) -> bool {
        self.len() == Some(0)
    }

    /// The j-th reversal (time and level after it); `None` past the end.
    pub fn get(&self, j: usize) -> Option<Reversal> {
        match *self {
            ReversalTrain::Periodic {
                first_s,
                half_period_s,
                initial_sign,
            } => Some(Reversal {
                time_s: first_s + j as f64 * half_period_s,
                level: if j.is_multiple_of(2) {
                    initial_sign
                } else {
                    -initial_sign
                },
            }),
            ReversalTrain::Alternating {
                times_s,
                initial_sign,
            } => times_s.get(j).map(|&t| Reversal {
                time_s: t,
                level: if j.is_multiple_of(2) {
                    initial_sign
                } else {
                    -initial_sign
                },
            }),
            ReversalTrain::Explicit(rs) => rs.get(j).copied(),
        }
    }

    /// Level of the friction (units of F0) at time t: 0 before the first reversal.
    pub fn level_at(&self, t: f64) -> f64 {
        self.last_index_at_or_before(t)
            .and_then(|j| self.get(j))
            .map_or(0.0, |r| r.level)
    }

    /// Jump of the level at the j-th reversal.
    pub fn jump(&self, j: usize) -> f64 {
        let now = self.get(j).map_or(0.0, |r| r.level);
        let before = if j == 0 {
            0.0
        } else {
            self.get(j - 1).map_or(0.0, |r| r.level)
        };
        now - before
    }
}

fn check_increasing(times: impl Iterator<Item = f64>) -> Result<(), Error> {
    let mut prev = f64::NEG_INFINITY;
    for (i, t) in times.enumerate() {
        if !t.is_finite() {
            return Err(Error::NotFinite(Param::ReversalTimes));
        }
        if t <= prev {
            return Err(Error::NotIncreasing { index: i });
        }
        prev = t;
    }
    Ok(())
}

/// The generalised eq (36) for one structure (full f64 precision).
#[derive(Debug, Clone, Copy)]
pub struct DuhamelClosedForm {
    kernel: Kernel<f64>,
    gmu: f64,
}

/// One evaluation of the closed form and how many terms it summed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluation {
    /// Top-mass absolute acceleration ü1 (m/s²).
    pub accel_m_s2: f64,
    /// Number of reversal terms summed (those still above [`TERM_TOLERANCE`]).
    pub terms: usize,
}

impl DuhamelClosedForm {
    /// The closed form of a structure.
    pub fn new(structure: &Structure) -> Self {
        Self {
            kernel: Kernel::new(structure),
            gmu: structure.gmu(),
        }
    }

    /// Top-mass acceleration ü1(t) (m/s²) under the reversal train (assumed validated).
    pub fn accel(&self, train: &ReversalTrain<'_>, t: f64) -> f64 {
        self.evaluate(train, t, usize::MAX).accel_m_s2
    }

    /// ü1(t), summing at most `max_terms` of the newest reversal terms (the truncated closed form;
    /// `usize::MAX` for the full sum, which still stops at [`TERM_TOLERANCE`]).
    pub fn evaluate(&self, train: &ReversalTrain<'_>, t: f64, max_terms: usize) -> Evaluation {
        let Some(last) = train.last_index_at_or_before(t) else {
            return Evaluation {
                accel_m_s2: 0.0,
                terms: 0,
            };
        };
        let level = train.get(last).map_or(0.0, |r| r.level);
        let peak = self.kernel.envelope_peak();
        // Neumaier-compensated sum of Δs_j ecm(t − t_j), newest first.
        let (mut sum, mut comp) = (0.0f64, 0.0f64);
        let mut terms = 0usize;
        let mut j = last;
        loop {
            if terms >= max_terms {
                break;
            }
            let Some(r) = train.get(j) else { break };
            let tau = t - r.time_s;
            if tau > peak && self.kernel.envelope::<Libm>(tau) < TERM_TOLERANCE {
                break;
            }
            let term = train.jump(j) * self.kernel.eval::<Libm>(tau).ecm;
            let s = sum + term;
            comp += if libm::fabs(sum) >= libm::fabs(term) {
                (sum - s) + term
            } else {
                (term - s) + sum
            };
            sum = s;
            terms += 1;
            if j == 0 {
                break;
            }
            j -= 1;
        }
        Evaluation {
            accel_m_s2: self.gmu * (level - (sum + comp)),
            terms,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::StructureParams;

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

    #[test]
    fn paper_eq36_form_for_the_alternating_train() {
        // Corrected eq (36) with ε, written term by term as printed (with the restored "+").
        let s = table1(0.05);
        let (a, n, eps) = (s.a(), s.n().unwrap(), s.epsilon().unwrap());
        let half = 0.0715;
        let train = ReversalTrain::Periodic {
            first_s: 0.0,
            half_period_s: half,
            initial_sign: 1.0,
        };
        let cf = DuhamelClosedForm::new(&s);
        for k in 0..2000 {
            let t = k as f64 * 1e-3 + 1e-6;
            let nn = (t / half).floor() as i64 + 1; // block number N
            let mut u = if nn % 2 == 1 { 1.0 } else { -1.0 };
            u -= (-a * t).exp() * (n * t + eps).cos() / eps.cos();
            for i in 1..nn {
                let ti = t - i as f64 * half;
                let sgn = if i % 2 == 1 { 1.0 } else { -1.0 };
                u += 2.0 * sgn * (-a * ti).exp() * (n * ti + eps).cos() / eps.cos();
            }
            let want = s.gmu() * u;
            let got = cf.accel(&train, t);
            assert!((got - want).abs() < 1e-11, "t={t}: {got} vs {want}");
        }
    }

    #[test]
    fn rest_before_first_reversal_and_continuous_at_it() {
        let s = table1(0.05);
        let cf = DuhamelClosedForm::new(&s);
        let times = [0.5, 0.6, 0.75];
        let train = ReversalTrain::Alternating {
            times_s: &times,
            initial_sign: -1.0,
        };
        assert_eq!(cf.accel(&train, 0.4999), 0.0);
        for &t in &times {
            let (l, r) = (cf.accel(&train, t - 1e-12), cf.accel(&train, t));
            assert!((l - r).abs() < 1e-6, "jump at {t}: {l} {r}");
        }
    }

    #[test]
    fn bad_trains_are_rejected() {
        let t = [0.0, 0.1, 0.1];
        let e = ReversalTrain::Alternating {
            times_s: &t,
            initial_sign: 1.0,
        }
        .validate()
        .unwrap_err();
        assert_eq!(e, Error::NotIncreasing { index: 2 });
        let e = ReversalTrain::Periodic {
            first_s: 0.0,
            half_period_s: 0.1,
            initial_sign: 0.5,
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.param(), Param::ReversalSign);
    }
}
