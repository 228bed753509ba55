//! Fuse mode: the top accelerometer's offset and gain relative to the base's, from the momentum
//! balance's fit over the sliding blocks (the module's last paragraph), and before it, the top
//! offset from the run's first samples ([`OpenStart`]).

use super::{BaseTuning, MAX_GAIN_ERROR};
use ssvr_core::sliding_id::SlidingEstimate;
use ssvr_core::StructureParams;

/// The open-loop start's length in radians of the prior's p: the model's response to a table
/// offset b_t has grown to b_t·(p·t)²/2 by its end, and its mean over the start to a sixth of
/// that, ~1.7e-3·b_t.
pub const OPEN_START_RAD: f64 = 0.1;

/// Fuse mode without a rest: the top accelerometer's offset from the run's first samples.
/// While the base sticks, a constant offset b_t of the table accelerometer is a constant table
/// acceleration for the fixed-base dynamics (the model's top acceleration comes out b_t high once
/// its transient has decayed) and the top accelerometer reads b_top high: after the transient
/// only their difference is observable, until the sliding phases separate them (El Centro sticks
/// for 2 s). The transient separates them: the specimen starts at rest, as the model does, and
/// over the first p·t ≤ [`OPEN_START_RAD`] the model's response to b_t is below ~1e-2·b_t,
/// while the top accelerometer reads b_top from the first sample. So the model runs open loop
/// (no stuck-phase observer: its prediction does not follow the measurement) for those samples,
/// and the mean of measured − predicted is b_top, to the sensor noise over √n
/// (n = 22 at 7 Hz and 10 kHz). The model's error in f or ξ is a fraction (p·t)² of the top's
/// small response then, and the table's offset is left to the stuck-phase observer as before.
#[derive(Debug, Clone)]
pub(super) struct OpenStart {
    /// Samples of the start still to come (0: none, or done).
    left: u32,
    /// Σ (measured − predicted), its squares and its count.
    sum: f32,
    sum2: f32,
    n: u32,
}

impl OpenStart {
    /// The start of the prior `params` at `rate` (`on`: fuse mode without a rest); at least
    /// one sample.
    pub(super) fn new(on: bool, params: &StructureParams, rate: f64) -> Self {
        let p = 2.0 * core::f64::consts::PI * params.natural_frequency_hz;
        let n = libm::floor(OPEN_START_RAD * rate / p);
        Self {
            left: if on && n.is_finite() {
                n.clamp(1.0, 1e4) as u32
            } else {
                0
            },
            sum: 0.0,
            sum2: 0.0,
            n: 0,
        }
    }
}

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

    /// Fuse mode: how many of the next samples are in the open-loop start ([`OpenStart`]: the
    /// model's top input NaN).
    #[inline(always)]
    pub fn open_start(&self) -> usize {
        self.start.left as usize
    }

    /// The open-loop start's `measured` top accelerations and the model's predictions `pred` of
    /// them (the run's first [`Self::open_start`] samples): at its end, the top offset is their
    /// mean difference, known to its standard error.
    #[inline(never)]
    pub fn note_open_start(&mut self, measured: &[f32], pred: &[f32]) {
        let s = &mut self.start;
        let k = measured.len().min(pred.len()).min(s.left as usize);
        for (&m, &p) in measured.iter().zip(pred).take(k) {
            let r = m - p;
            if r.is_finite() {
                (s.sum, s.sum2, s.n) = (s.sum + r, s.sum2 + r * r, s.n + 1);
            }
        }
        s.left -= k as u32;
        if s.left > 0 || s.n == 0 {
            return;
        }
        let n = s.n as f64;
        let mean = s.sum as f64 / n;
        let var = (s.sum2 as f64 / n - mean * mean) * n / libm::fmax(n - 1.0, 1.0);
        let sd = libm::sqrt(libm::fmax(var, 0.0) / n);
        // Adopted like the momentum balance's (3σ from the prior's 0), which later replaces it
        // when better known or different.
        if libm::fabs(mean) > 3.0 * sd {
            self.top_offset = mean as f32;
            self.top_offset_std_use = sd;
        }
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
