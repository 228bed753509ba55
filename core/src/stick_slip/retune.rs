//! Adopting new coefficients in place ([`StickSlipEstimator::retune`]): an identified natural
//! frequency or damping ratio, mid-run.

use super::coefficients::StickSlipCoefficients;
use super::estimator::sliding_observers;
use super::estimator::StickSlipEstimator;
use super::maps::{power, StuckMap};
use super::observer::observer_gain;
use super::packed;
use crate::math::{Real, Transcendentals};

/// The identification's n-step sliding maps of `c`, composed in f64 from the per-sample ones:
/// Φs^n − I and the response to the friction force +g.
pub(super) fn block_maps<T: Real>(c: &StickSlipCoefficients<T>, n: u32) -> ([T; 4], [T; 2]) {
    let per_sample = (c.phi_s.map(T::to_f64), c.force_s.map(T::to_f64));
    let (a, f) = power(&per_sample, n);
    let g = c.g.to_f64();
    (
        a.map(T::from_f64),
        [T::from_f64(g * f[0]), T::from_f64(g * f[1])],
    )
}

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// Adopt the coefficients `c` (of the same sample rate and gravity: an identified natural
    /// frequency or damping ratio) from the next sample on, keeping the μ in use.
    ///
    /// The state (ü1, pδ') of every kept sample keeps its top acceleration (what the stuck
    /// observer and the measurement pin down) and its relative velocity δ' (pδ' scaled by
    /// p_new/p_old); δ follows from the new p and ξ. A late event then re-simulates the history
    /// with the new coefficients. The friction identification's sliding episode goes on with
    /// the new maps from its free and unit-μ parts as they are (their pδ' scaled alike), as the
    /// model's own state does. (Ending it, the next block started a new episode mid-slide,
    /// and on Table 2 test 2 four blocks of it gave μ̂ = 0.105 for 0.2, adopted: 2.1 % of the
    /// peak on 20 rows of the scorecard once f was adopted within the first 0.2 s, in slides.)
    /// A large change (p or the mass ratio M by more than 0.1 %, or 2ξ by more than 10 %: an M
    /// alone kept μ̂'s blocks of the old M and the narrow sliding observer, and took Table 2
    /// test 2 at 1 kHz with m1 told 5 % off from 0.33 to 0.39–0.42 % RMS) also restarts its least
    /// squares from μ̂ with the initial information: what the old model biased is dropped, and
    /// μ̂ is adopted again once `min_blocks` new blocks are in; a small one keeps them (a short
    /// window of new blocks would scatter μ̂ more than the old model's bias).
    pub fn retune(&mut self, c: StickSlipCoefficients<T>) {
        let scale = c.p / self.c.p;
        let dp = (scale - T::ONE).abs();
        let dxi = ((c.two_xi - self.c.two_xi) / self.c.two_xi).abs();
        // (M = mp/p.)
        let dm = ((c.mp * self.c.p) / (self.c.mp * c.p) - T::ONE).abs();
        let large =
            !(dp <= T::from_f64(1e-3) && dm <= T::from_f64(1e-3) && dxi <= T::from_f64(0.1));
        if scale.is_finite() {
            for s in self.slots.iter_mut() {
                s.z[1] = s.z[1] * scale;
            }
            self.id.z_start[1] = self.id.z_start[1] * scale;
            self.id.zh[1] = self.id.zh[1] * scale;
            self.id.zu[1] = self.id.zu[1] * scale;
        }
        self.c = c;
        self.gain = observer_gain::<T, M>(&c, self.cfg.observer_bandwidth);
        self.closed = StuckMap::closed(&c, self.gain);
        self.slides = sliding_observers::<T, M>(&c, &self.cfg);
        self.open = StuckMap::open(&c);
        self.gmu = c.g * self.mu_use;
        self.set_drive();
        (self.id.block_phi, self.id.block_force) = block_maps(&c, self.cfg.identify_every);
        if large {
            let r = &mut self.id.rls;
            (r.a, r.b, r.n) = (T::ONE, r.mu, 0);
        }
        // The wide sliding observer until μ̂ is adopted again after a large change.
        self.slide_narrow &= !large && !self.hold_wide;
        (self.slide_gain, self.slide) = self.slides[usize::from(self.slide_narrow)];
    }
}

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// Use the kinetic friction coefficient `mu` from the next interval on: a velocity-dependent
    /// friction law sets it for every sliding sample from the slip speed. A late event's
    /// re-simulation uses the coefficient in force then for the intervals it revises.
    #[inline(always)]
    pub fn set_friction(&mut self, mu: T) {
        self.mu_use = mu;
        self.gmu = self.c.g * mu;
        self.set_drive();
    }

    /// [`Self::set_friction`] as if `mu` had been set before the last event was pushed (the
    /// slip start or reversal that began the current slide): the intervals since it are
    /// re-simulated with `mu`, as the event's own push re-simulated them, and `top_shift` (m/s²,
    /// when finite) is added to the last sample's measured top acceleration, which the next
    /// interval's correction reads (a measurement that is a model of the top with μ in it:
    /// predict mode's momentum balance). For a slide whose friction is known a sample after its
    /// start was pushed (the sliding side of a slip start confirmed at its second sample):
    /// unlike [`Self::shift_top`] the state is not shifted, its slide re-run from the start
    /// instead. Stuck: [`Self::set_friction`] alone (the top shift ignored). Sliding with the
    /// event beyond the history: the friction set and the top shifted, nothing re-run (an event
    /// inside the interval just beyond it: the re-run from the first plain sample on); the
    /// model calls it a sample after the event, well within the history.
    pub fn set_friction_since_event(&mut self, mu: T, top_shift: T) {
        self.set_friction(mu);
        if self.phase == 0 {
            return;
        }
        if top_shift.is_finite() {
            self.adjust_last(|s| s.y += top_shift);
        }
        let k = self.sample_index();
        let limit = if k < self.len as u64 {
            k
        } else {
            self.len as u64 - 1
        };
        // The event: a switch into the current phase inside the interval before the plain
        // ones, else at the first plain sample.
        let plain = packed::new(self.phase);
        let (i, code) = match self.plain_from.checked_sub(1) {
            Some(j) if k - j <= limit => {
                let c = self.iv.get(self.slot_of(j)).copied().unwrap_or(plain);
                if packed::switches(c) > 0 && packed::end(c) == self.phase {
                    (j, c)
                } else {
                    (self.plain_from, plain)
                }
            }
            _ => (self.plain_from, plain),
        };
        let back = k.saturating_sub(i);
        if back < 2 || back > limit {
            return;
        }
        self.resimulate(self.slot_of(i), back as usize, code);
        self.set_fast_mode();
    }

    /// Add `d` (m/s²) to the top acceleration of the last sample's state (its relative velocity
    /// kept) and to that sample's measured top acceleration, which the next interval's
    /// correction reads. For a change of what the measurement means between two samples: a
    /// measurement that is a model of the top acceleration (predict mode's momentum balance,
    /// (1 + r)·μ·g·s − r·ü2) jumps with the μ in it, and with the state shifted alike the
    /// sliding observer sees no jump (else its transient, frozen into an open-loop stuck phase
    /// when the base sticks during it, grows there into a free oscillation). A late event's
    /// re-simulation from an earlier sample does not see the shift.
    pub fn shift_top(&mut self, d: T) {
        if !d.is_finite() {
            return;
        }
        self.adjust_last(|s| {
            s.z[0] += d;
            s.y += d;
        });
    }

    /// Remove from the last sample's state the fixed-base response to a constant table
    /// acceleration `b` over the last `intervals` intervals, from rest: for an offset of the
    /// table input found after the model has integrated it (predict mode's table start: 22
    /// samples of a 0.49 m/s² offset left a free oscillation of ~0.05 m/s² in the stuck model,
    /// which has no observer in predict mode). The open stuck map is affine in its input, so
    /// the response is z ← z + A·z + (b0 + b1)·b from z = 0, in `T` as the model's own steps
    /// (`intervals` steps once: ~10 M4F instructions each in f32; in f64, soft-float on the
    /// M4F, ~50 times that); the last sample's stored input loses `b` too, the next interval's
    /// start. It assumes the last `intervals` intervals were stuck and open loop (no stuck
    /// observer: predict mode). Only while stuck
    /// (a slide since changed the map: nothing is done); a late event's re-simulation from an
    /// earlier sample does not see it, as [`Self::shift_top`].
    pub fn remove_input_offset(&mut self, b: T, intervals: u32) {
        if !b.is_finite() || self.phase != 0 {
            return;
        }
        let m = &self.open;
        let (a, f0, f1) = (m.a, (m.b0[0] + m.b1[0]) * b, (m.b0[1] + m.b1[1]) * b);
        let mut dz = [T::ZERO; 2];
        for _ in 0..intervals {
            dz = [
                dz[0] + (a[0] * dz[0] + a[1] * dz[1] + f0),
                dz[1] + (a[2] * dz[0] + a[3] * dz[1] + f1),
            ];
        }
        // (The last sample's input too: the next interval starts from it.)
        self.adjust_last(|s| {
            s.z[0] -= dz[0];
            s.z[1] -= dz[1];
            s.u -= b;
        });
    }

    /// Apply `f` to the last sample's slot (and the ring's copy of it).
    fn adjust_last(&mut self, f: impl Fn(&mut super::estimator::Slot<T>)) {
        // (Right after a wrap of a ring without a copy slot, `at` is one before slot 0: the
        // last sample is in the last slot.)
        let at = if self.at < H { self.at } else { H - 1 };
        if let Some(s) = self.slots.get_mut(at) {
            f(s);
        }
        // The ring's copy of its last slot (slot 0, when it has one), either way.
        if self.first == 1 && at + 1 == H {
            self.copy_last();
        } else if self.first == 1 && at == 0 {
            if let Some(&s) = self.slots.first() {
                if let Some(last) = self.slots.last_mut() {
                    *last = s;
                }
            }
        }
    }
}
