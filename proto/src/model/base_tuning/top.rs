//! Fuse mode: the top accelerometer's offset and gain relative to the base's, from the momentum
//! balance's fit over the sliding blocks (the module's last paragraph).

use super::{BaseTuning, MAX_GAIN_ERROR};
use ssvr_core::sliding_id::SlidingEstimate;

impl BaseTuning {
    /// The top accelerometer's offset in use (m/s², fuse mode; 0 in predict mode).
    #[inline(always)]
    pub fn top_offset(&self) -> f32 {
        self.top_offset
    }

    /// The measured top acceleration `m` corrected by the offset and gain in use (fuse mode).
    #[inline(always)]
    pub fn top_corrected(&self, m: f32) -> f32 {
        (m - self.top_offset) * self.top_scale
    }

    /// Fuse mode: the top accelerometer's offset and gain (relative to the base's) from the
    /// momentum balance's fit, each adopted when it differs significantly from the one in use or
    /// is known twice as well. With t = G·ü1 + b_top and ü1 = (1 + r)·μ·g·s − r·(ü2 − b_table):
    /// θ = (−G·r, G·(1 + r)·μ·g, G·r·b_table + b_top), so b_top = θ2 + θ0·b_table and, with μ·g
    /// from the sliding base (`e`), G = θ1/(μ·g) + θ0: neither needs the prior's masses.
    pub(super) fn adopt_top(&mut self, e: Option<&SlidingEstimate>) {
        let Some(f) = self.top_fit.solve::<3>() else {
            return;
        };
        let b = f.theta[2] + f.theta[0] * self.offset as f64;
        let sd = libm::sqrt(libm::fmax(f.cov[2][2], 0.0));
        let change = libm::fabs(b - self.top_offset as f64);
        if sd > 0.0 && (change > 3.0 * sd || sd < 0.5 * self.top_offset_std_use) {
            self.top_offset = b as f32;
            self.top_offset_std_use = sd;
        }
        let Some(e) = e else {
            return;
        };
        let fa = e.friction_accel;
        let gain = f.theta[1] / fa + f.theta[0];
        let rel_fa = e.friction_accel_std / fa;
        let var = f.cov[1][1] / (fa * fa)
            + f.cov[0][0]
            + 2.0 * f.cov[0][1] / fa
            + (f.theta[1] / fa) * (f.theta[1] / fa) * rel_fa * rel_fa;
        let sd = libm::sqrt(libm::fmax(var, 0.0));
        let change = libm::fabs(gain - 1.0 / self.top_scale as f64);
        let plausible = libm::fabs(gain - 1.0) < MAX_GAIN_ERROR;
        if plausible && sd > 0.0 && (change > 3.0 * sd || sd < 0.5 * self.top_gain_std_use) {
            self.top_scale = (1.0 / gain) as f32;
            self.top_gain_std_use = sd;
        }
    }
}
