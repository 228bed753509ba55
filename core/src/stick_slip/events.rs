//! [`StickSlipEstimator::push_event`]: a phase change reported late, written into the history's
//! phases and re-simulated from.

use super::estimator::{Mode, StickSlipEstimator};
use super::packed;
use crate::error::{Error, Param};
use crate::math::{Real, Transcendentals};

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// Write the phase bytes of the plain intervals `max(plain_from, oldest) .. to` (the current
    /// phase), before an event changes the phase from `to` on.
    pub(super) fn materialize(&mut self, to: u64) {
        let k = self.sample_index();
        let lo = self.plain_from.max((k + 1).saturating_sub(self.len as u64));
        let code = packed::new(self.phase);
        let mut j = lo;
        let mut s = self.slot_of(lo);
        while j < to {
            if let Some(b) = self.iv.get_mut(s) {
                *b = code;
            }
            s = self.next_slot(s);
            j += 1;
        }
    }

    /// A phase change detected late: the base entered the phase of friction level `phase`
    /// ([`SlidingPhase::level`](super::SlidingPhase::level): 0 stuck, ±1 sliding; any other
    /// level is an error) `age_samples` ≥ 0 sample intervals before the sample the next
    /// [`Self::update`] returns.
    /// Push events in chronological order. Events older than the history (`history − 2`
    /// samples; older ones may be accepted when they fall on a sample) are an error.
    pub fn push_event(&mut self, phase: i8, age_samples: T) -> Result<(), Error> {
        if !(-1..=1).contains(&phase) {
            return Err(Error::OutOfRange {
                param: Param::Phase,
                value: phase as f64,
                expected: "a phase of -1, 0 or 1",
            });
        }
        if !age_samples.is_finite() || age_samples < T::ZERO {
            return Err(Error::OutOfRange {
                param: Param::EventTime,
                value: age_samples.to_f64(),
                expected: "a finite age >= 0 samples",
            });
        }
        let k = self.sample_index();
        if k == 0 {
            self.phase = phase;
            self.note_event(0, true, phase);
            return Ok(());
        }
        if age_samples == T::ZERO {
            // From interval k on (interval k − 1 keeps its phases).
            if phase != self.phase {
                if self.plain_from < k {
                    self.materialize(k);
                }
                self.plain_from = k;
                self.phase = phase;
                self.mode = Mode::Cold;
                self.fast_until = 0;
                self.stuck_until = 0;
                self.note_event(k, true, phase);
            }
            return Ok(());
        }
        // The event lies in interval i (from sample i to i + 1) at fraction f, or at sample i:
        // `back` = k − i samples before sample k.
        let whole = age_samples.floor();
        let frac = age_samples - whole;
        let (back, f) = if frac == T::ZERO {
            (whole.to_usize_sat(), T::ZERO)
        } else {
            (whole.to_usize_sat().saturating_add(1), T::ONE - frac)
        };
        // i ≥ max(k − history + 1, 0).
        let limit = if k < self.len as u64 {
            k as usize
        } else {
            self.len - 1
        };
        if back > limit {
            return Err(Error::OutOfRange {
                param: Param::EventTime,
                value: age_samples.to_f64(),
                expected: "an age within the estimator's history",
            });
        }
        let i = k - back as u64;
        // The intervals before i keep their phases; interval i gets the event (a switch, or the
        // new phase throughout), every later one the new phase.
        if self.plain_from < i {
            self.materialize(i);
        }
        let si = self.slot_of(i);
        let code = if f == T::ZERO {
            self.plain_from = i;
            packed::new(phase)
        } else {
            let mut b = if i >= self.plain_from {
                packed::new(self.phase)
            } else {
                self.iv.get(si).copied().unwrap_or(0)
            };
            if let (Some(iv), Some(fr)) = (self.iv.get_mut(si), self.fr.get_mut(si)) {
                packed::add(&mut b, fr, f, phase);
                *iv = b;
            }
            self.plain_from = i + 1;
            b
        };
        self.phase = phase;
        self.note_event(i, f == T::ZERO, phase);
        let plain = packed::new(phase);
        if back >= 2 {
            self.resimulate(si, back, code);
        }
        // Interval k − 1 → k: with a switch (the event in it), else plain in the new phase.
        if back >= 2 || code == plain {
            self.set_fast_mode();
        } else {
            self.mode = Mode::Cold;
            self.fast_until = 0;
            self.stuck_until = 0;
        }
        Ok(())
    }

    /// Re-simulate the `back − 1` intervals from slot `si` on (samples i + 1 .. k − 1): the first
    /// with the phases `code`, the others plain in the current phase.
    #[inline(never)]
    pub(super) fn resimulate(&mut self, si: usize, back: usize, code: u8) {
        let mu = (self.mu_use, self.gmu);
        let plain = packed::new(self.phase);
        let mut code = code;
        let mut sa = si;
        let mut z = self.slots.get(si).map_or([T::ZERO; 2], |s| s.z);
        for _ in 1..back {
            let sb = self.next_slot(sa);
            let (Some(a), Some(b), Some(fr)) =
                (self.slots.get(sa), self.slots.get(sb), self.fr.get(sa))
            else {
                break;
            };
            z = self.step(z, (a.u, b.u), a.y, code, fr, mu);
            if let Some(b) = self.slots.get_mut(sb) {
                b.z = z;
            }
            code = plain;
            sa = sb;
        }
        // The copy of the ring's last slot, if it was re-simulated.
        self.copy_last();
    }
}
