//! Online friction identification: the state of the pending block and of the sliding episode,
//! and the work done on a block once it is final (see the module documentation of
//! [`crate::stick_slip`]).

use super::estimator::{Mode, StickSlipEstimator};
use super::maps::mat;
use super::packed;
use super::phase::Level;
use super::rls::Rls;
use crate::math::{Real, Transcendentals};

/// What the identification knows about a block of intervals that is not final yet: one bit
/// per interval (bit j: interval `from + j`).
#[derive(Debug, Clone, Copy)]
pub(super) struct Pending {
    /// First interval of the block (the block is `from .. from + n`).
    pub(super) from: u64,
    /// The intervals that do not slide throughout without a switch.
    pub(super) other: u32,
    /// The intervals that slide in phase −1.
    pub(super) neg: u32,
    /// The phase at the end of the block.
    pub(super) end: Level,
    /// Every interval slides in this phase without a switch (0: not so).
    pub(super) sign: Level,
}

impl Pending {
    /// A block of intervals from `from` on, all plain in `phase` (`full`: the block's bits).
    #[inline(always)]
    fn set_plain(&mut self, from: u64, phase: Level, full: u32) {
        self.from = from;
        self.other = if phase == 0 { full } else { 0 };
        self.neg = if phase < 0 { full } else { 0 };
        self.end = phase;
        self.sign = phase;
    }

    /// `sign` from the bits.
    fn settle(&mut self, full: u32) {
        self.sign = if self.other != 0 {
            0
        } else if self.neg == 0 {
            1
        } else if self.neg == full {
            -1
        } else {
            0
        };
    }
}

/// The friction identification's state.
#[derive(Debug, Clone, Copy)]
pub(super) struct Ident<T> {
    /// Block length n.
    pub(super) every: u64,
    /// The bits of a block (n ones).
    pub(super) full: u32,
    /// The next block to process.
    pub(super) pend: Pending,
    /// Φs^n − I.
    pub(super) block_phi: [T; 4],
    /// The n-step response to the friction force +g (from rest).
    pub(super) block_force: [T; 2],
    pub(super) zh: [T; 2],
    pub(super) zu: [T; 2],
    /// The state at the end of the block before (kept by [`StickSlipEstimator::identify_other`]:
    /// the start of a block that starts an episode).
    pub(super) z_start: [T; 2],
    pub(super) episode: bool,
    pub(super) rls: Rls<T>,
}

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// An event changed the phases from interval `i` on (`at_start`: all of interval i, else
    /// from a switch inside it): update the pending identification block.
    pub(super) fn note_event(&mut self, i: u64, at_start: bool, phase: Level) {
        let (full, p) = (self.id.full, &mut self.id.pend);
        let Some(j) = i.checked_sub(p.from) else {
            // The whole block after the event (not reached: events do not reach final blocks).
            p.set_plain(p.from, phase, full);
            return;
        };
        if j >= self.id.every {
            return;
        }
        // Intervals j (at_start) or j + 1 (a switch in j) on: plain `phase`.
        let from_bit = if at_start { j } else { j + 1 };
        let later = if from_bit >= 32 {
            0
        } else {
            full & (u32::MAX << from_bit)
        };
        let (other, neg) = match phase {
            0 => (later, 0),
            p if p < 0 => (0, later),
            _ => (0, 0),
        };
        p.other = (p.other & !later) | other;
        p.neg = (p.neg & !later) | neg;
        if !at_start {
            p.other |= 1 << j;
        }
        p.end = phase;
        p.settle(full);
    }

    /// The pending block: what the identification needs of the intervals `from .. from + n`
    /// (some of them before `plain_from`, within the history).
    #[inline(never)]
    pub(super) fn summarize(&mut self, from: u64) {
        let (mut other, mut neg) = (0u32, 0u32);
        let mut last = 0;
        let plain = packed::new(self.phase);
        let mut s = self.slot_of(from);
        for j in 0..self.id.every {
            last = if from + j >= self.plain_from {
                plain
            } else {
                self.iv.get(s).copied().unwrap_or(0)
            };
            s = self.next_slot(s);
            if packed::switches(last) != 0 || packed::start(last) == 0 {
                other |= 1 << j;
            } else if packed::start(last) < 0 {
                neg |= 1 << j;
            }
        }
        let p = &mut self.id.pend;
        *p = Pending {
            from,
            other,
            neg,
            end: packed::end(last),
            sign: 0,
        };
        p.settle(self.id.full);
    }

    /// Friction identification on the pending block, which ends at sample d = k + 2 − history
    /// (final now: sample k, slot `next − 1`, was just stored), then the summary of the next
    /// block and the next block's mark.
    #[inline(always)]
    pub(super) fn identify(&mut self, next: usize) {
        // Sample d is in the slot history − 2 before.
        let (pos, back) = (next - 1, self.len - 2);
        let sd = if pos >= self.first + back {
            pos - back
        } else {
            pos + (H - self.first) - back
        };
        let (from, sign) = (self.id.pend.from, self.id.pend.sign);
        let yd = self.slots.get(sd).map_or(T::ZERO, |s| s.y);
        let id = &mut self.id;
        if id.episode && sign != 0 && yd.is_finite() {
            // Sliding in one direction throughout, the episode going on: the n-step maps of
            // z_h (free vibration, μ = 0) and z_u (the response per unit μ, force ±g).
            let (a, f) = (&id.block_phi, &id.block_force);
            let f = if sign > 0 { *f } else { [-f[0], -f[1]] };
            let (zh, zu) = (id.zh, id.zu);
            let (wh, wu) = (mat(a, zh), mat(a, zu));
            let zh = [zh[0] + wh[0], zh[1] + wh[1]];
            let zu = [zu[0] + (wu[0] + f[0]), zu[1] + (wu[1] + f[1])];
            id.zh = zh;
            id.zu = zu;
            // ü1 = −(z0 + 2ξ·z1) = w0: φ = w0 of z_u, the target y − w0 of z_h.
            let (phi, target) = (zu[0], yd - zh[0]);
            id.rls.update(phi, target);
            self.adopt_mu();
        } else {
            self.identify_other(sd);
        }
        let from = from + self.id.every;
        if from >= self.plain_from {
            self.id.pend.set_plain(from, self.phase, self.id.full);
        } else {
            self.summarize(from);
        }
        let due = next + self.id.every as usize;
        if due <= H {
            self.id_mark = due;
        } else {
            self.id_mark = usize::MAX;
            self.id_carry = due;
        }
    }

    /// [`Self::identify`] of any other block: reversals on samples inside it, no measurement
    /// at its end, or the start or the end of an episode.
    #[cold]
    #[inline(never)]
    pub(super) fn identify_other(&mut self, sd: usize) {
        let b = self.id.pend;
        let (zd, yd) = self
            .slots
            .get(sd)
            .map_or(([T::ZERO; 2], T::ZERO), |s| (s.z, s.y));
        let slides = b.other == 0;
        if slides && !self.id.episode {
            // The block slides throughout: an episode starts at its start.
            self.start_episode(self.id.z_start);
        }
        let c = &self.c;
        let id = &mut self.id;
        if slides {
            if b.neg == 0 || b.neg == id.full {
                let (a, f) = (&id.block_phi, &id.block_force);
                let f = if b.neg == 0 { *f } else { [-f[0], -f[1]] };
                let (wh, wu) = (mat(a, id.zh), mat(a, id.zu));
                id.zh = [id.zh[0] + wh[0], id.zh[1] + wh[1]];
                id.zu = [id.zu[0] + (wu[0] + f[0]), id.zu[1] + (wu[1] + f[1])];
            } else {
                // Reversals on samples inside the block: sample by sample.
                for j in 0..id.every {
                    let g = if b.neg >> j & 1 == 0 { c.g } else { -c.g };
                    let (wh, wu) = (mat(&c.phi_s, id.zh), mat(&c.phi_s, id.zu));
                    id.zh = [id.zh[0] + wh[0], id.zh[1] + wh[1]];
                    id.zu = [
                        id.zu[0] + (wu[0] + g * c.force_s[0]),
                        id.zu[1] + (wu[1] + g * c.force_s[1]),
                    ];
                }
            }
            if yd.is_finite() {
                let (phi, target) = (id.zu[0], yd - id.zh[0]);
                id.rls.update(phi, target);
                self.adopt_mu();
            }
        } else if b.end != 0 {
            // An episode starts at the block's end.
            self.start_episode(zd);
        } else {
            id.episode = false;
        }
        self.id.z_start = zd;
    }

    /// The model adopts μ̂ if so set, there are `min_blocks` blocks, and μ̂ is plausible: within
    /// a factor of 2 of the structure's μ (a μ̂ outside that range means a wrong structure or
    /// bad measurements, not a friction estimate); the sliding observer then narrows (unless
    /// held wide: [`Self::hold_wide`]).
    #[inline(always)]
    fn adopt_mu(&mut self) {
        let mu_hat = self.id.rls.mu;
        let plausible =
            mu_hat >= self.c.mu * T::from_f64(0.5) && mu_hat <= self.c.mu * T::from_f64(2.0);
        if self.cfg.use_identified_mu && self.id.rls.n >= self.cfg.min_blocks && plausible {
            self.mu_use = mu_hat;
            self.gmu = self.c.g * self.mu_use;
            self.mu_adopted = true;
            if !self.slide_narrow && !self.hold_wide {
                self.slide_narrow = true;
                (self.slide_gain, self.slide) = self.slides[1];
            }
            if self.mode == Mode::Slide {
                self.set_drive();
            }
        }
    }

    /// A sliding episode starts at state `z`: z = z_h + μ·z_u with z_u = 0; the model adopts
    /// μ̂ if so set and there are enough samples.
    pub(super) fn start_episode(&mut self, z: [T; 2]) {
        self.adopt_mu();
        let id = &mut self.id;
        id.zh = z;
        id.zu = [T::ZERO; 2];
        id.episode = true;
    }
}
