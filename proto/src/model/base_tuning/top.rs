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

#[cfg(test)]
mod tests {
    use super::super::*;

    fn params() -> StructureParams {
        StructureParams {
            m1_kg: 29.5,
            m2_kg: 1.75,
            natural_frequency_hz: 7.0,
            damping_ratio: 0.05,
            friction_coefficient: 0.2,
            gravity_m_s2: 9.80665,
        }
    }

    /// A deterministic stand-in for the sensor's noise: uniform in ±√3·`rms` (that RMS).
    fn noise(k: u32, rms: f32) -> f32 {
        let h = k.wrapping_mul(2_654_435_761).rotate_left(13) ^ 0x9e37_79b9;
        let u = (h.wrapping_mul(2_246_822_519) >> 8) as f32 / (1u32 << 24) as f32;
        (2.0 * u - 1.0) * 1.732_050_8 * rms
    }

    /// The start's length is the first 0.1 rad of p (22 samples at 7 Hz and 10 kHz, at least
    /// one at a coarse rate); only fuse mode without a rest has one.
    #[test]
    fn the_open_start_is_fuse_mode_without_a_rest() {
        let b = |zeroed, fuse, rate| {
            BaseTuning::new(params(), rate, zeroed, fuse, 37)
                .unwrap()
                .open_start()
        };
        // 0.1 × 10 000 / (2π·7) = 22.7.
        assert_eq!(b(false, true, 10_000.0), 22);
        assert_eq!(b(false, true, 200.0), 1);
        assert_eq!(b(true, true, 10_000.0), 0);
        assert_eq!(b(false, false, 10_000.0), 0);
    }

    /// Measured − predicted over the start, in runs of any length (a missing sample skipped):
    /// an offset of ±0.05 m/s² under 5e-3 m/s² of noise comes out within its standard error
    /// (5e-3/√21 = 1.1e-3), taken with that standard deviation; without an offset nothing is
    /// taken (3σ), and the momentum balance's later estimates decide. Samples after the start
    /// are not read.
    #[test]
    fn the_start_gives_the_top_offset() {
        for offset in [0.05f32, -0.05, 0.0] {
            let mut b = BaseTuning::new(params(), 10_000.0, false, true, 37).unwrap();
            let n = b.open_start();
            let pred: [f32; 40] = core::array::from_fn(|k| 0.3 * libm::sinf(k as f32 * 0.05));
            let mut measured: [f32; 40] =
                core::array::from_fn(|k| pred[k] + offset + noise(k as u32, 5e-3));
            measured[3] = f32::NAN;
            // Samples after the start: far off, never read.
            measured[n..].iter_mut().for_each(|m| *m = 1e3);
            let mut at = 0;
            for len in [5usize, 16, 19] {
                let to = (at + len).min(40);
                b.note_open_start(&measured[at..to], &pred[at..to]);
                at = to;
            }
            assert_eq!(b.open_start(), 0);
            let (found, sd) = (b.top_offset(), b.top_offset_std_use);
            if offset == 0.0 {
                assert_eq!((found, sd), (0.0, 0.0));
            } else {
                // Measured: 7.4e-4 off, σ 1.04e-3.
                assert!((found - offset).abs() < 1e-3, "{found} for {offset}");
                assert!(sd > 0.9e-3 && sd < 1.2e-3, "σ {sd}");
            }
        }
    }
}
