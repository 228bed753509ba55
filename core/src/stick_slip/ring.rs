//! The history's ring of slots: where a sample is, and the slow path at the marks (the
//! identification blocks and the ring's wrap).

use super::estimator::{Mode, StickSlipEstimator};
use crate::math::{Real, Transcendentals};

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// The slot of sample `j` (k − history ≤ j ≤ k).
    pub(super) fn slot_of(&self, j: u64) -> usize {
        let at = j + self.shift as u64;
        let off = if at >= self.origin {
            at - self.origin
        } else {
            (at + (H - self.first) as u64).wrapping_sub(self.origin)
        };
        self.first + off as usize
    }

    /// The slot after slot `s` in the ring.
    pub(super) fn next_slot(&self, s: usize) -> usize {
        if s + 1 >= H {
            self.first
        } else {
            s + 1
        }
    }

    /// The slow path after storing the sample of slot `next − 1`: the identification block and
    /// the ring's wrap. Returns the prediction of that sample.
    #[inline(never)]
    pub(super) fn at_mark(&mut self, next: usize) -> T {
        if next == self.id_mark {
            self.identify(next);
        }
        if next >= H {
            self.wrap();
        } else {
            self.at = next - 1;
        }
        let mark = self.id_mark.min(H);
        self.mark = mark;
        (self.fast_until, self.stuck_until) = match self.mode {
            Mode::Slide => (mark.saturating_sub(2), 0),
            Mode::Stuck => (0, mark.saturating_sub(2)),
            _ => (0, 0),
        };
        self.slots.get(next - 1).map_or(T::ZERO, |s| s.z[0])
    }

    /// The ring's wrap.
    #[inline(never)]
    pub(super) fn wrap(&mut self) {
        let ring = H - self.first;
        self.at = self.first.wrapping_sub(1);
        self.origin += ring as u64;
        self.copy_last();
        if self.id_carry != usize::MAX {
            self.id_carry -= ring;
            if self.id_carry <= H {
                self.id_mark = self.id_carry;
            }
        }
    }

    /// Slot 0 = slot H − 1 (the copy before slot 1).
    pub(super) fn copy_last(&mut self) {
        if let (Some(&last), true) = (self.slots.last(), self.first == 1) {
            if let Some(s) = self.slots.first_mut() {
                *s = last;
            }
        }
    }
}
