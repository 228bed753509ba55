//! The adoption checks of the base tuning: when a check is due, and what it adopts from the
//! sliding identification (f and ξ, μ, the one-way friction before both directions have slid,
//! the table's offset).

use super::first_slides::FROM_BREAKAWAY;
use super::{
    BaseTuning, CHECK_EVERY, FIRST_CHECK_EVERY, MAX_REL_STD_MU, MAX_REL_STD_MU_OFFSET,
    MIN_REL_CHANGE_MU,
};
use ssvr_core::oscillator_id::OscillatorEstimate;
use ssvr_core::sliding_id::SlidingEstimate;
use ssvr_core::stick_slip::StickSlipCoefficients;

impl BaseTuning {
    /// Count `samples` samples; at a check, the coefficients (f, ξ) and the friction coefficient
    /// to adopt, if any ([`Self::due`], then [`Self::check_due`]).
    pub fn check(&mut self, samples: u32) -> (Option<StickSlipCoefficients<f32>>, Option<f32>) {
        if !self.due(samples) {
            return (None, None);
        }
        self.check_due()
    }

    /// Count `samples` samples: whether a check is due (then [`Self::check_due`] makes it).
    /// (The model tests this before it asks for the adoptions: their answer is ~130 bytes, and
    /// building and copying an empty one took ~8 instructions per sample.)
    #[inline(always)]
    pub fn due(&mut self, samples: u32) -> bool {
        if self.countdown > samples {
            self.countdown -= samples;
            return false;
        }
        true
    }

    /// The check that [`Self::due`] found due: the coefficients (f, ξ) and the friction
    /// coefficient to adopt, if any.
    pub fn check_due(&mut self) -> (Option<StickSlipCoefficients<f32>>, Option<f32>) {
        // (Until the first adoption: μ in predict mode, a top offset in fuse mode, from the
        // open-loop start or the momentum balance: fast checks continued after the start's
        // took Table 2 test 2's combined row from 0.25 to 0.64 % RMS, the table's offset then
        // adopted from noisier fits.)
        let first = if self.fuse {
            self.top_offset_std_use == 0.0
        } else {
            self.mu_adoptions == 0
        };
        self.countdown = if self.fast_checks > 0 && first {
            FIRST_CHECK_EVERY
        } else {
            CHECK_EVERY
        };
        // (Predict mode: a new M from the slip starts first.)
        if let Some(c) = self.take_mass() {
            return (Some(c), None);
        }
        let rows = self.id.rows_added().wrapping_add(self.top_fit.added());
        if rows == self.rows_seen {
            return (None, None);
        }
        self.rows_seen = rows;
        self.fast_checks = self.fast_checks.saturating_sub(1);
        self.adopt()
    }

    #[inline(never)]
    pub(super) fn adopt(&mut self) -> (Option<StickSlipCoefficients<f32>>, Option<f32>) {
        // (Fuse mode has no use for a one-way estimate: not even solved.)
        if self.fuse && !self.zeroed && !self.id.both_ways() {
            self.adopt_top(None);
            return (None, None);
        }
        let estimate = self.id.estimate(self.offset_known);
        if let Some(e) = &estimate {
            self.adopt_offset(e);
        }
        // (The top's offset from the table's offset of this check.)
        if self.fuse {
            self.adopt_top(estimate.as_ref());
        }
        let Some(e) = estimate else {
            return (None, None);
        };
        if e.one_way != 0 {
            return self.adopt_one_way(&e);
        }
        self.last = Some(e);
        let coefficients = if self.fuse {
            None
        } else {
            self.adoption.adopt(&self.oscillator(&e))
        };
        let mu = e.friction_accel / self.g as f64;
        let sd = e.friction_accel_std / self.g as f64;
        let plausible = self.plausible(mu);
        let adopt = !self.fuse && self.worth(mu, sd, self.mu_use, self.mu_std_use);
        if adopt {
            self.mu_use = mu as f32;
            self.mu_std_use = sd;
            self.mu_adoptions = self.mu_adoptions.saturating_add(1);
        }
        // Both ways slid and μ known (adopted, or the one in use confirmed): one μ for both
        // directions (an estimate not yet known keeps the directions' one-way levels).
        let known = adopt || (plausible && sd < MAX_REL_STD_MU * mu);
        let one = [self.mu_use; 2];
        let changed = !self.fuse && known && self.mu_dir != one;
        if known {
            self.mu_dir = one;
            self.mu_known = true;
        }
        (
            coefficients,
            (adopt || changed).then(|| self.mu_for(self.level)),
        )
    }

    /// Whether `mu` is within a factor of 2 of the prior's.
    pub(super) fn plausible(&self, mu: f64) -> bool {
        mu > 0.5 * self.prior_mu && mu < 2.0 * self.prior_mu
    }

    /// Whether an estimate `mu` ± `sd` is worth adopting in place of `in_use` (known to
    /// `std_use`; 0: a prior): plausible, known to [`MAX_REL_STD_MU`], and differing from it
    /// significantly (3σ, and by [`MIN_REL_CHANGE_MU`]) or known twice as well (the sliding top
    /// acceleration's error is (1 + r)·g times μ's): a right prior stays, a wrong one goes at the
    /// first significant estimate.
    pub(super) fn worth(&self, mu: f64, sd: f64, in_use: f32, std_use: f64) -> bool {
        let change = libm::fabs(mu - in_use as f64);
        self.plausible(mu)
            && sd < MAX_REL_STD_MU * mu
            && change > MIN_REL_CHANGE_MU * mu
            && (sd < 0.5 * std_use || change > 3.0 * sd)
    }

    /// Predict mode, the base slid one way only and no rest: f and ξ adopted as from both ways
    /// (the oscillation does not depend on the constant), and that direction's friction level
    /// adopted for it alone, like μ (when it differs significantly from the one in use or is
    /// known twice as well).
    pub(super) fn adopt_one_way(
        &mut self,
        e: &SlidingEstimate,
    ) -> (Option<StickSlipCoefficients<f32>>, Option<f32>) {
        if self.fuse {
            return (None, None);
        }
        let coefficients = self.adoption.adopt(&self.oscillator(e));
        let i = if e.one_way > 0 { 0 } else { 1 };
        let mu = e.friction_accel / self.g as f64;
        let sd = e.friction_accel_std / self.g as f64;
        let (Some(in_use), Some(std_use)) = (self.mu_dir.get(i), self.mu_dir_std.get(i)) else {
            return (coefficients, None);
        };
        // A level from a slip start's breakaway gives way to any estimate known well enough:
        // taken for a prior, an estimate within 3σ of it would leave it, and its blend's share
        // of the prior's error, slip start after slip start.
        let adopt = if *std_use == FROM_BREAKAWAY {
            self.plausible(mu) && sd < MAX_REL_STD_MU * mu
        } else {
            self.worth(mu, sd, *in_use, *std_use)
        };
        if adopt {
            if let (Some(m), Some(s)) = (self.mu_dir.get_mut(i), self.mu_dir_std.get_mut(i)) {
                (*m, *s) = (mu as f32, sd);
            }
        }
        (coefficients, adopt.then(|| self.mu_for(self.level)))
    }

    /// The table accelerometer's offset of the sliding base's fit `e`, adopted like μ (when it
    /// differs significantly from the one in use or is known twice as well), from a fit whose
    /// friction is plausible and known.
    pub(super) fn adopt_offset(&mut self, e: &SlidingEstimate) {
        let mu = e.friction_accel / self.g as f64;
        let known = mu > 0.5 * self.prior_mu
            && mu < 2.0 * self.prior_mu
            && e.friction_accel_std / (self.g as f64) < MAX_REL_STD_MU_OFFSET * mu;
        // (The fit's offset is what is left after `id_shift`.)
        let offset = e.offset + self.id_shift as f64;
        let change = libm::fabs(offset - self.offset as f64);
        if known
            && e.offset_std > 0.0
            && (change > 3.0 * e.offset_std || e.offset_std < 0.5 * self.offset_std_use)
        {
            self.offset = offset as f32;
            self.offset_std_use = e.offset_std;
        }
    }

    /// The fixed-base oscillator of a sliding one, with the prior's M.
    pub(super) fn oscillator(&self, e: &SlidingEstimate) -> OscillatorEstimate {
        let to_hz = 1.0 / (2.0 * core::f64::consts::PI * self.root_m);
        OscillatorEstimate {
            natural_frequency_hz: e.omega * to_hz,
            natural_frequency_std_hz: e.omega_std * to_hz,
            damping_ratio: e.damping_ratio / self.root_m,
            damping_ratio_std: e.damping_ratio_std / self.root_m,
            blocks: e.rows as u32,
        }
    }
}
