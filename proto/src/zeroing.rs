//! Zeroing the accelerometers on the rest before the input: the table is at rest (and logged)
//! for the plan's first `rest_samples` samples, so each accelerometer's mean over them is its
//! offset. During the rest the running mean is removed from every sample; after it the mean of
//! the whole rest is, from every sample to the end. Without a rest nothing is removed (the slip
//! acceleration's offset, the base's against the table's, is tracked by its detector while the
//! base sticks).

use crate::channel::{Channel, CHANNELS};
use crate::flags;

/// The accelerometers zeroed: table, base, top.
const ACCELS: [Channel; 3] = [Channel::TableAccel, Channel::BaseAccel, Channel::TopAccel];

/// The offsets of the three accelerometers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Zeroing {
    rest: u32,
    n: u32,
    sum: [f32; 3],
    offset: [f32; 3],
}

impl Zeroing {
    /// Zeroing over a rest of `rest_samples` samples (0: none).
    pub const fn new(rest_samples: u32) -> Self {
        Self {
            rest: rest_samples,
            n: 0,
            sum: [0.0; 3],
            offset: [0.0; 3],
        }
    }

    /// The offsets removed (m/s²): table, base, top.
    pub fn offsets(&self) -> [f32; 3] {
        self.offset
    }

    /// Remove the offsets from sample `index`'s accelerometers (flags `f`: a missing, non-finite
    /// or saturated sample is not part of the mean).
    #[inline(always)]
    pub fn apply(&mut self, index: u32, channels: &mut [f32; CHANNELS], f: u8) {
        if self.rest == 0 {
            return;
        }
        if index < self.rest && f & (flags::MISSING | flags::NOT_FINITE | flags::SATURATED) == 0 {
            self.n += 1;
            let n = self.n as f32;
            for (j, c) in ACCELS.iter().enumerate() {
                self.sum[j] += channels[c.index()];
                self.offset[j] = self.sum[j] / n;
            }
        }
        for (j, c) in ACCELS.iter().enumerate() {
            channels[c.index()] -= self.offset[j];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rest_mean_is_removed_and_frozen_after_it() {
        let mut z = Zeroing::new(100);
        let bias = [0.3f32, -0.2, 0.1];
        let mut last = [0.0f32; CHANNELS];
        for k in 0..300u32 {
            let wiggle = if k % 2 == 0 { 1e-3 } else { -1e-3 };
            let moving = if k >= 100 { 1.5 } else { 0.0 };
            let mut ch = [
                bias[0] + wiggle + moving,
                bias[1] + wiggle + moving,
                bias[2] + wiggle,
                0.01,
            ];
            let f = if k == 7 { flags::MISSING } else { 0 };
            if k == 7 {
                ch = [f32::NAN; CHANNELS];
            }
            z.apply(k, &mut ch, f);
            last = ch;
        }
        for (o, b) in z.offsets().iter().zip(bias) {
            assert!((o - b).abs() < 2e-5, "{o} vs {b}");
        }
        assert!((last[0] - (1.5 - 1e-3)).abs() < 3e-5, "{last:?}");
        assert_eq!(last[3], 0.01);
        let mut none = Zeroing::new(0);
        let mut ch = [1.0, 2.0, 3.0, 4.0];
        none.apply(0, &mut ch, 0);
        assert_eq!(ch, [1.0, 2.0, 3.0, 4.0]);
    }
}
