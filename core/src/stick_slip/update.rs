//! [`StickSlipEstimator::update`]: the per-sample paths, from the inline steady states to the
//! general one, and the mode that selects them.

use super::estimator::{unlikely, Mode, Slot, StickSlipEstimator};
use super::maps::{slide_step, stuck_step};
use super::packed::{self, MAX_SWITCHES};
use crate::math::{Real, Transcendentals};

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// Process sample k: `table_accel` is the measured table acceleration (m/s²), `measured_top`
    /// the measured top acceleration (for μ identification; NaN to skip). A non-finite table
    /// acceleration is replaced by the previous one (flag it upstream). Returns the predicted ü1.
    #[inline(always)]
    pub fn update(&mut self, table_accel: T, measured_top: T) -> T {
        // The steady states inline: the interval k − 1 → k plain sliding (the forcing
        // precomputed in `drive`) or plain stuck, sample k − 1 in the slot before, no mark after
        // sample k (`at < fast_until`, `at < stuck_until`).
        let at = self.at;
        if at < self.fast_until {
            // Slots at and at + 1 (`at < H − 1`: both exist).
            if let (Some([prev, cur, ..]), true) =
                (self.slots.get_mut(at..), table_accel.is_finite())
            {
                let z = slide_step(&self.slide, &self.c.phi_s, self.drive, prev.z, prev.y);
                *cur = Slot {
                    u: table_accel,
                    y: measured_top,
                    z,
                };
                self.at = at + 1;
                return z[0];
            }
        }
        if at < self.stuck_until {
            // (Laid out after the sliding path, which falls through to the caller.)
            unlikely();
            if let (Some([prev, cur, ..]), true) =
                (self.slots.get_mut(at..), table_accel.is_finite())
            {
                let z = stuck_step(
                    &self.closed,
                    &self.open,
                    prev.z,
                    prev.y,
                    prev.u,
                    table_accel,
                );
                self.at = at + 1;
                cur.z = z;
                cur.y = measured_top;
                cur.u = table_accel;
                return z[0];
            }
        }
        unlikely();
        self.update_other(table_accel, measured_top)
    }

    /// [`Self::update`] in every other case: stuck with a mark after sample k (the fixed-base map)
    /// here, the rest in [`Self::update_edge`].
    #[inline(never)]
    pub(super) fn update_other(&mut self, table_accel: T, measured_top: T) -> T {
        let at = self.at;
        if self.mode == Mode::Slide {
            return self.update_edge(table_accel, measured_top);
        }
        if self.mode == Mode::Stuck {
            if let (Some([prev, cur, ..]), true) =
                (self.slots.get_mut(at..), table_accel.is_finite())
            {
                let z = stuck_step(
                    &self.closed,
                    &self.open,
                    prev.z,
                    prev.y,
                    prev.u,
                    table_accel,
                );
                *cur = Slot {
                    u: table_accel,
                    y: measured_top,
                    z,
                };
                return self.stored(at + 1, z[0]);
            }
        }
        self.update_edge(table_accel, measured_top)
    }

    /// [`Self::update`] sliding with a mark after sample k, else [`Self::update_cold`].
    #[inline(never)]
    pub(super) fn update_edge(&mut self, table_accel: T, measured_top: T) -> T {
        let at = self.at;
        if self.mode == Mode::Slide {
            if let (Some([prev, cur, ..]), true) =
                (self.slots.get_mut(at..), table_accel.is_finite())
            {
                let z = slide_step(&self.slide, &self.c.phi_s, self.drive, prev.z, prev.y);
                *cur = Slot {
                    u: table_accel,
                    y: measured_top,
                    z,
                };
                return self.stored(at + 1, z[0]);
            }
        }
        self.update_cold(table_accel, measured_top)
    }

    /// [`Self::update`] of sample 0 (at rest), of the ring's first slot (without a copy slot
    /// before it), after an interval with switches or a phase change, or with a non-finite table
    /// acceleration.
    #[cold]
    #[inline(never)]
    pub(super) fn update_cold(&mut self, table_accel: T, measured_top: T) -> T {
        let pos = self.at.wrapping_add(1);
        let k = self.sample_index();
        let (u, z) = if k == 0 {
            let u = if table_accel.is_finite() {
                table_accel
            } else {
                T::ZERO
            };
            (u, [T::ZERO; 2])
        } else {
            let sp = if pos <= self.first { H - 1 } else { pos - 1 };
            // The previous sample's slot: the copy in slot 0 after a wrap if there is one (slot
            // H − 1 may already hold this pass's sample: a block's run that reached it and is
            // being redone sample by sample); its phases stay at `sp`.
            let prev_slot = if pos >= 1 { pos - 1 } else { H - 1 };
            let prev = self.slots.get(prev_slot).copied().unwrap_or(Slot {
                u: T::ZERO,
                y: T::ZERO,
                z: [T::ZERO; 2],
            });
            let u = if table_accel.is_finite() {
                table_accel
            } else {
                prev.u
            };
            let fr = self.fr.get(sp).copied().unwrap_or([T::ZERO; MAX_SWITCHES]);
            let iv = if self.mode == Mode::Cold && k - 1 < self.plain_from {
                self.iv.get(sp).copied().unwrap_or(0)
            } else {
                packed::new(self.phase)
            };
            let z = self.step(
                prev.z,
                (prev.u, u),
                prev.y,
                iv,
                &fr,
                (self.mu_use, self.gmu),
            );
            (u, z)
        };
        if let Some(s) = self.slots.get_mut(pos) {
            *s = Slot {
                u,
                y: measured_top,
                z,
            };
        }
        self.stored(pos, z[0]);
        if self.mode == Mode::Cold {
            // Interval k → k + 1 is plain in the current phase.
            self.set_fast_mode();
        }
        z[0]
    }

    /// After storing a sample in slot `pos` (its prediction `z0`): the mark's work if the mark
    /// follows it, else the ring index moves on. Returns the prediction.
    #[inline(always)]
    pub(super) fn stored(&mut self, pos: usize, z0: T) -> T {
        if pos + 1 == self.mark {
            self.at_mark(pos + 1)
        } else {
            self.at = pos;
            z0
        }
    }

    /// `fast_until` from the mode and the mark.
    pub(super) fn refresh_fast(&mut self) {
        let until = self.mark.saturating_sub(2);
        (self.fast_until, self.stuck_until) = match self.mode {
            Mode::Slide => (until, 0),
            Mode::Stuck => (0, until),
            _ => (0, 0),
        };
    }

    /// The mode (and its precomputed input) for a plain interval in the current phase from
    /// sample k − 1.
    pub(super) fn set_fast_mode(&mut self) {
        if self.phase == 0 {
            self.mode = Mode::Stuck;
        } else {
            self.set_drive();
            self.mode = Mode::Slide;
        }
        self.refresh_fast();
    }

    /// The sliding forcing per interval of the current phase and μ.
    pub(super) fn set_drive(&mut self) {
        // (±1·g)·μ = ±(g·μ) exactly.
        let f = if self.phase > 0 { self.gmu } else { -self.gmu };
        self.drive = [f * self.c.force_s[0], f * self.c.force_s[1]];
    }
}
