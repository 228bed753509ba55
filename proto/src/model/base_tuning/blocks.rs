//! The blocks of sliding samples waiting in a ring for late events (the module's **Labels**):
//! an event relabels the blocks after it, the block being summed closes into the ring, the
//! oldest block leaves it for the identification.

use super::{sign, takes, BaseTuning, Block, GUARD};

impl BaseTuning {
    /// An event `age` samples before the next sample, setting the phase `level` (0: stuck):
    /// the blocks after it are relabelled, those with a sample within `GUARD` (2) samples of it
    /// dropped.
    /// An event the estimator would reject (a level outside −1..=1, an age not finite or
    /// negative) changes nothing; the model passes only those it pushed.
    pub fn event(&mut self, level: i8, age: f32) {
        if !takes(level, age) {
            return;
        }
        // Distances back from the next sample: a sample j is after the event (and its guard)
        // when sample − j < age − GUARD, before it when sample − j > age + GUARD.
        if self.cur_n as f32 >= age - GUARD {
            self.cur.level = 0;
        }
        let d = self.d as f32;
        let sample = self.cur.start.wrapping_add(self.cur_n);
        for k in 1..=self.filled {
            let Some(b) = self.ring.get_mut((self.at + self.wait - k) % self.wait) else {
                break;
            };
            let first = sample.wrapping_sub(b.start) as f32;
            if first < age - GUARD {
                b.level = level;
            } else if first - d + 1.0 > age + GUARD {
                break;
            } else {
                b.level = 0;
            }
        }
        self.level = level;
        // (0 ≤ age: ahead ≤ GUARD.)
        let ahead = GUARD - age;
        let skip = if ahead >= 0.0 {
            (ahead as u8).saturating_add(1)
        } else {
            0
        };
        self.skip = self.skip.max(skip);
    }

    /// A run of base and top samples (NaN: missing or saturated) in the phase of the last
    /// event (the tops are read in fuse mode only).
    #[inline(always)]
    pub fn push_run(&mut self, base: &[f32], top: &[f32]) {
        let (mut base, mut top) = (base, top);
        loop {
            // The samples up to the end of the block being summed.
            let k = (self.d.saturating_sub(self.cur_n) as usize)
                .min(base.len())
                .min(top.len());
            let (Some((b_now, b_rest)), Some((t_now, t_rest))) =
                (base.split_at_checked(k), top.split_at_checked(k))
            else {
                return;
            };
            if k == 0 {
                return;
            }
            if self.skip > 0 {
                // A sample within the guard after an event: the block is not used.
                self.skip = self.skip.saturating_sub(k.min(u8::MAX as usize) as u8);
                self.cur.level = 0;
            }
            let (mut sb, mut st) = (self.cur.base, self.cur.top);
            for (&b, &t) in b_now.iter().zip(t_now) {
                sb += b;
                st += t;
            }
            (self.cur.base, self.cur.top) = (sb, st);
            self.cur_n += k as u32;
            if self.cur_n >= self.d {
                self.close();
            }
            (base, top) = (b_rest, t_rest);
        }
    }

    /// Closes the block being summed: into the ring, the oldest one out of it to the
    /// identification.
    #[inline(never)]
    fn close(&mut self) {
        let mut b = self.cur;
        (b.base, b.top) = (b.base * self.inv_d, b.top * self.inv_d);
        if b.level != 0 {
            b.level = self.level;
        }
        self.cur = Block {
            base: 0.0,
            top: 0.0,
            level: 1,
            start: b.start.wrapping_add(self.d),
        };
        self.cur_n = 0;
        let Some(slot) = self.ring.get_mut(self.at) else {
            return;
        };
        let old = core::mem::replace(slot, b);
        self.at = if self.at + 1 >= self.wait {
            0
        } else {
            self.at + 1
        };
        if self.filled < self.wait {
            self.filled += 1;
            return;
        }
        self.id.push_block(old.base - self.id_shift, old.level);
        if self.fuse && old.level != 0 && (old.base - old.top).is_finite() {
            self.top_fit.add(&[old.base, sign(old.level), 1.0], old.top);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::*;
    extern crate std;
    use std::vec::Vec;

    fn tuning() -> BaseTuning {
        BaseTuning::new(test_params(), 10_000.0, false, true, 37).unwrap()
    }

    /// Events the estimator would reject change nothing and never panic; an event relabels the
    /// waiting blocks after it and drops those within the guard (the block being summed too).
    #[test]
    fn events_relabel_the_waiting_blocks() {
        let mut b = tuning();
        let d = b.d as usize;
        assert!(
            b.wait >= 2 && b.wait * d >= 37 + 3,
            "{} blocks of {d}",
            b.wait
        );
        // A slip start long enough ago that no sample to come is within its guard.
        b.event(1, 10.0);
        let ones = [1.0f32; 64];
        // Two whole blocks and 3 samples of a third, sliding +1.
        b.push_run(&ones[..2 * d + 3], &ones[..2 * d + 3]);
        let before: Vec<i8> = (0..b.filled).map(|k| b.ring[k].level).collect();
        assert_eq!(before, [1, 1]);
        for (level, age) in [(2, 1.0), (-1, f32::NAN), (1, -300.0), (0, f32::INFINITY)] {
            b.event(level, age);
            let after: Vec<i8> = (0..b.filled).map(|k| b.ring[k].level).collect();
            assert_eq!(after, before, "event ({level}, {age}) was applied");
        }
        // A stick 5 samples ago: the current block (3 samples, all within 5 + GUARD) dropped,
        // the second block (samples 3..3 + d back) straddles the guard: dropped; the first
        // (before the event and its guard) kept.
        b.event(0, 5.0);
        assert_eq!(b.cur.level, 0);
        assert_eq!(b.level, 0);
        let levels: Vec<i8> = (0..b.filled).map(|k| b.ring[k].level).collect();
        assert_eq!(levels, [1, 0]);
    }
}
