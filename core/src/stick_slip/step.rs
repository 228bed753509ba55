//! One sample interval of the general path: the stuck and the sliding maps, or piece by piece
//! through the phase changes inside it.

use super::estimator::StickSlipEstimator;
use super::maps::{mat, slide_step, stuck_step};
use super::observer::correct;
use super::packed::{self, MAX_SWITCHES};
use super::phase::Level;
use crate::math::{Real, Transcendentals};

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// One piece of an interval: from fraction `fa` to `fb` in `phase`, with table accelerations
    /// `u0`, `u1` at the interval's ends; `mu` scales the friction (0: free vibration only).
    pub(super) fn piece(
        &self,
        z: [T; 2],
        phase: Level,
        (fa, fb): (T, T),
        (u0, u1): (T, T),
        mu: T,
    ) -> [T; 2] {
        let c = &self.c;
        let tau = (fb - fa) * c.dt;
        if phase == 0 {
            let c1 = (u1 - u0) * c.rate;
            let c0 = u0 + fa * (u1 - u0);
            let lin = c.two_xi * c1 / c.p;
            let zp0 = [-c0 + lin, -(c1 / c.p)];
            let zpt = [-(c0 + c1 * tau) + lin, -(c1 / c.p)];
            let f = c.kf.eval::<M>(tau);
            let m = [f.ecp, c.p * f.es, -(c.p * f.es), f.ecm];
            let w = mat(&m, [z[0] - zp0[0], z[1] - zp0[1]]);
            [w[0] + zpt[0], w[1] + zpt[1]]
        } else {
            let v = -(T::from_f64(phase as f64) * c.g * mu);
            let f = c.ks.eval::<M>(tau);
            let m = [f.ecp, c.p * f.es, -(c.mp * f.es), f.ecm];
            let w = mat(&m, [z[0] - v, z[1]]);
            [w[0] + v, w[1]]
        }
    }

    /// An interval with switches, piece by piece (`z`: the state w at its start; returns w at
    /// its end).
    #[inline(never)]
    pub(super) fn step_switched(
        &self,
        z: [T; 2],
        (u0, u1): (T, T),
        iv: u8,
        fr: &[T; MAX_SWITCHES],
        mu: T,
    ) -> [T; 2] {
        // The pieces in z = T·w.
        let two_xi = self.c.two_xi;
        let z = [-(z[0] + two_xi * z[1]), z[1]];
        let (mut z, mut ph, mut fa) = (z, packed::start(iv), T::ZERO);
        for (j, &fs) in fr.iter().enumerate().take(packed::switches(iv)) {
            z = self.piece(z, ph, (fa, fs), (u0, u1), mu);
            ph = packed::after(iv, j);
            fa = fs;
        }
        let z = self.piece(z, ph, (fa, T::ONE), (u0, u1), mu);
        [-(z[0] + two_xi * z[1]), z[1]]
    }

    /// The fixed-base (stuck) map over one whole interval from the state `z` of its first sample
    /// and that sample's measured top acceleration `y0` (the observer's correction if finite).
    #[inline(always)]
    pub(super) fn step_stuck(&self, z: [T; 2], y0: T, u0: T, u1: T) -> [T; 2] {
        stuck_step(&self.closed, &self.open, z, y0, u0, u1)
    }

    /// The sliding map over one whole interval with the friction force `f` = ±g·μ, from the
    /// state `z` of its first sample and that sample's measured top acceleration `y0` (the
    /// observer's correction if finite).
    #[inline(always)]
    pub(super) fn step_sliding(&self, z: [T; 2], f: T, y0: T) -> [T; 2] {
        let d = [f * self.c.force_s[0], f * self.c.force_s[1]];
        slide_step(&self.slide, &self.c.phi_s, d, z, y0)
    }

    /// State at the end of an interval (phases `iv`, switch fractions `fr`) from its start, the
    /// friction scaled by `mu` (`gmu` = g·`mu`).
    #[inline(always)]
    pub(super) fn step(
        &self,
        z: [T; 2],
        (u0, u1): (T, T),
        y0: T,
        iv: u8,
        fr: &[T; MAX_SWITCHES],
        (mu, gmu): (T, T),
    ) -> [T; 2] {
        if packed::switches(iv) != 0 {
            // From the state corrected with the gain of the phase the interval starts in.
            let gain = if iv & 3 == 0 {
                self.gain
            } else {
                self.slide_gain
            };
            let z = correct(gain, z, y0);
            return self.step_switched(z, (u0, u1), iv, fr, mu);
        }
        match iv & 3 {
            0 => self.step_stuck(z, y0, u0, u1),
            // (±1·g)·μ = ±(g·μ) exactly.
            1 => self.step_sliding(z, gmu, y0),
            _ => self.step_sliding(z, -gmu, y0),
        }
    }
}
