//! Missing samples (a frame the logger dropped, or a non-finite sample) in the phase detector:
//! a missing sample is filled at once by the linear continuation of the two before it (held
//! right after a jump), so that the ring stays whole; its index is kept (the latest
//! [`MISSING_KEPT`]), so that the slip start's fit, its sliding side and the event's step leave
//! it out; the jump test of the samples just after a gap judges them against the continuation
//! over the gap with the curvature measured before it ([`PhaseDetector`]'s `jump_near_gap`);
//! and the measured sample after a gap has it refilled from the parabola through the measured
//! samples around it, the slide's integrated velocity corrected ([`PhaseDetector`]'s
//! `after_gap`). All of it is cold: a run with no missing sample pays one comparison per sample.

use super::{PhaseDetector, CURVATURES, JUMP_THRESHOLDS};
use crate::detect::ring::slot;

/// Longest run of missing samples refilled from the measured ones around it
/// ([`PhaseDetector`]'s `refill`): beyond it the linear continuation stays.
const MAX_REFILL: u8 = 30;

/// Whether bit `back` of a [`PhaseDetector`]'s missing mask is set: sample k − `back` missing.
#[inline(always)]
pub(super) fn missing(mask: u64, back: u64) -> bool {
    back < 64 && (mask >> back) & 1 != 0
}

/// Missing samples whose indices the phase detector keeps for its fits: in a window with more,
/// the older ones read as measured.
pub(super) const MISSING_KEPT: usize = 8;

impl<const N: usize> PhaseDetector<N> {
    /// A missing sample `k`: noted, and s̈ continued linearly (a repeated value would be a
    /// kink, which the jump test could take for a change of the friction force); held, right
    /// after a jump (a line through it would continue the jump).
    #[cold]
    #[inline(never)]
    pub(super) fn fill(&mut self, k: u64) -> f32 {
        let i = usize::from(self.missing_next) % MISSING_KEPT;
        if let Some(m) = self.missing_at.get_mut(i) {
            *m = k.saturating_add(1);
        }
        self.missing_next = ((i + 1) % MISSING_KEPT) as u8;
        self.gap = self.gap.saturating_add(1);
        if k > 1 && self.jump_at + 1 != k {
            2.0 * self.at(k - 1) - self.at(k - 2)
        } else if k > 0 {
            self.at(k - 1)
        } else {
            0.0
        }
    }

    /// After the measured sample `k` that follows missing ones (`quiet`: it made no event;
    /// the jump test read the fills): the gap refilled ([`Self::refill`]), and while sliding the
    /// velocity integrated over it corrected (not when it was just held at zero). Stuck, the
    /// slip start's fit leaves the gap out and its velocity reads the refill.
    #[cold]
    #[inline(never)]
    pub(super) fn after_gap(&mut self, k: u64, quiet: bool) {
        if quiet {
            let fill = self.at(k - 1);
            let dv = self.refill(k);
            if self.direction != 0 && !(self.v_held && self.v == 0.0) {
                // (The sample's own trapezoid read the last fill: half of its change.)
                self.v += dv + 0.5 * (self.at(k - 1) - fill);
            }
        }
        self.gap = 0;
    }

    /// The missing samples among the 64 up to `k` (the last one processed): bit j for sample
    /// k − j (of the latest [`MISSING_KEPT`] missing samples: older ones read as measured).
    #[cold]
    #[inline(never)]
    pub(super) fn missing_mask(&self, k: u64) -> u64 {
        let mut mask = 0u64;
        for &m in &self.missing_at {
            let back = k.saturating_add(1).wrapping_sub(m);
            if m != 0 && back < 64 {
                mask |= 1 << back;
            }
        }
        mask
    }

    /// At the measured sample `k` after missing ones: their linear fills in the ring replaced by
    /// the parabola through the two measured samples before the gap and `k` (the line through
    /// the last one and `k` when the one before it is missing too), so that the velocity
    /// integrated over the gap is that of the slip acceleration's curve, not of its
    /// continuation (at 1 kHz a sliding oscillation's curvature put a stick after a gap half a
    /// sample off). Returns the change of the trapezoidal velocity already integrated over the
    /// gap: every fill but the last counted in full, the last by half (its other half comes
    /// with the sample `k`). Gaps longer than [`MAX_REFILL`] samples are left as they are.
    #[cold]
    #[inline(never)]
    pub(super) fn refill(&mut self, k: u64) -> f32 {
        let gap = self.gap;
        let n = u32::from(gap) + 1;
        if gap == 0 || gap > MAX_REFILL || n as usize + 2 > N || k < u64::from(n) + 1 {
            return 0.0;
        }
        let left = k - u64::from(n);
        let (a0, a1, ak) = (self.at(left - 1), self.at(left), self.at(k));
        // (The parabola's first point neither missing nor before the latest jump.)
        let parabola = !missing(self.missing_mask(k), u64::from(n) + 1) && left > self.jump_at;
        let nf = n as f32;
        let mut dv = 0.0;
        for m in 1..n {
            let x = m as f32;
            let value = if parabola {
                x * (x - nf) / (nf + 1.0) * a0 - (x + 1.0) * (x - nf) / nf * a1
                    + (x + 1.0) * x / ((nf + 1.0) * nf) * ak
            } else {
                a1 + (ak - a1) * x / nf
            };
            let i = left + u64::from(m);
            let slot = slot::<N>(i);
            let weight = if m + 1 == n { 0.5 } else { 1.0 };
            dv += weight * (value - self.ring[slot]);
            self.ring[slot] = value;
        }
        dv
    }

    /// Whether one of the four samples before `k` is missing: the latest missing one within
    /// four of it.
    #[inline(always)]
    pub(super) fn near_gap(&self, k: u64) -> bool {
        let latest = usize::from(self.missing_next).wrapping_sub(1) % MISSING_KEPT;
        self.missing_at
            .get(latest)
            .is_some_and(|&m| m != 0 && k.saturating_add(1).wrapping_sub(m) <= 4)
    }

    /// The jump test of the sample `k` when one of the four before it, which the test's
    /// continuation and curvature read, is missing. Its n = k − (the last measured sample
    /// before that gap) samples from the measured curve: on the first measured sample after
    /// the gap, a1 + b is the fills' linear continuation of the last two measured samples over
    /// n, whose miss without any event is the measured curvature's n·(n + 1)/2 times (once
    /// over one sample), its noise the two samples' (n + 1)·a − n·a' against the
    /// one-sample continuation's 2·a − a' (variances (n + 1)² + n² + 1 against 6); the
    /// samples after it read the gap refilled from a parabola, whose own curvature is smoothed
    /// over the gap, and take the same bound. The curvature is that of the measured samples
    /// before the gap, not of the fills (whose second difference is 0 by construction: at
    /// 1 kHz on a sliding oscillation a missing sample then read as a reversal).
    #[cold]
    #[inline(never)]
    pub(super) fn jump_near_gap(&self, k: u64, miss: f32) -> bool {
        let mask = self.missing_mask(k);
        let recent = mask & 0b11110;
        // (None of the four missing, the sample itself maybe: the plain test, n = 1.)
        let n = if recent == 0 {
            1
        } else {
            let last = recent.trailing_zeros();
            // (A gap longer than the kept indices: its count, on the first sample after it.)
            (last + (mask >> last).trailing_ones())
                .max(u32::from(self.gap) + 1)
                .min(N as u32 / 2)
        };
        let j = k.saturating_sub(u64::from(n)).max(3) + 1;
        let (a1, a2) = (self.at(j - 1), self.at(j - 2));
        let curvature = self.curvature(j, a1 - a2, a2);
        // (The two samples before k measured, the gap only under the curvature's (k − 3 or
        // k − 4): the continuation is the plain one, over one sample, its curvature the larger
        // of the measured one before the gap and the plain one through the refill. Over n it
        // had a stick's jump of 1.5 m/s² on El Centro at 1 kHz two samples later wait ten
        // samples for the stall rule: 4.9 % of the peak.)
        let (n, curvature) = if recent & 0b110 == 0 {
            let (b1, b2) = (self.at(k - 1), self.at(k - 2));
            (1, curvature.max(self.curvature(k, b1 - b2, b2)))
        } else {
            (n, curvature)
        };
        let n = n as f32;
        // (√(((n + 1)² + n² + 1)/6) ≤ (2n + 1)/3, equal at n = 1.)
        let noise = (2.0 * n + 1.0) / 3.0;
        miss > JUMP_THRESHOLDS * self.cfg.threshold_m_s2 * noise
            + CURVATURES * curvature * n * (n + 1.0) / 2.0
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::Noise;
    use super::super::{PhaseDetector, PhaseDetectorConfig};
    use crate::detect::SlipEvent;

    /// Where the coarse slide starts, and its length (samples).
    const COARSE_SLIDE_START: u64 = 20;
    const COARSE_SLIDE_SAMPLES: u64 = 200;

    /// A sliding oscillation of 34 samples per period and 7 m/s² (the Table 1 specimen's at
    /// 1 kHz) on a slow ramp from [`COARSE_SLIDE_START`], with the default accelerometers' noise.
    fn coarse_slide() -> std::vec::Vec<f64> {
        let sigma = 5e-3 * core::f64::consts::SQRT_2;
        let (tb, w, amp) = (
            COARSE_SLIDE_START as f64,
            2.0 * core::f64::consts::PI / 34.0,
            7.0,
        );
        let mut noise = Noise(7);
        (0..COARSE_SLIDE_SAMPLES)
            .map(|k| {
                let u = k as f64 - tb;
                let s = if u <= 0.0 {
                    0.0
                } else {
                    amp * libm::sin(w * u) + u / 34.0
                };
                s + sigma * noise.next()
            })
            .collect()
    }

    /// The detector over `signal` with the samples in `gap` missing: its events with their
    /// times, and the detector after them.
    fn run_with_gap(
        signal: &[f64],
        cfg: PhaseDetectorConfig,
        gap: core::ops::Range<u64>,
    ) -> (std::vec::Vec<(f64, SlipEvent)>, PhaseDetector<64>) {
        let mut d = PhaseDetector::<64>::new(cfg).unwrap();
        let mut events = std::vec::Vec::new();
        for (k, &a) in signal.iter().enumerate() {
            let k = k as u64;
            let x = if gap.contains(&k) { f32::NAN } else { a as f32 };
            if let Some(e) = d.process(x) {
                events.push((k as f64 - e.age_samples() as f64, e));
            }
        }
        (events, d)
    }

    /// Missing samples in a slide sampled coarsely are no event, wherever they fall, one to
    /// three in a row: a sliding oscillation of 34 samples per period and 7 m/s² (the Table 1
    /// specimen's at 1 kHz) on a slow ramp, with the default accelerometers' noise. The measured
    /// sample after a gap is judged against the continuation over the gap with the curvature
    /// of the measured samples before it (the linear fills' own second difference is 0: with
    /// it, 9 of these 160 single gaps and 59 of the 160 double ones read as a reversal). A
    /// reversal at a gap is still found, within the gap of its time.
    #[test]
    fn missing_samples_in_a_coarse_slide_are_no_event() {
        let cfg = PhaseDetectorConfig::for_noise(5e-3).unwrap();
        let (tb, n) = (COARSE_SLIDE_START as f64, COARSE_SLIDE_SAMPLES);
        let signal = coarse_slide();
        let run = |gap: core::ops::Range<u64>| run_with_gap(&signal, cfg, gap).0;
        let clean = run(0..0);
        assert_eq!(clean.len(), 1, "{clean:?}");
        assert!(matches!(
            clean[0].1,
            SlipEvent::SlipStart { direction: 1, .. }
        ));
        let mut gaps = 0;
        for len in 1..=3u64 {
            for at in (tb as u64 + 10)..(n - 10) {
                let events = run(at..at + len);
                assert_eq!(events, clean, "{len} missing at {at}");
                gaps += 1;
            }
        }
        assert_eq!(gaps, 3 * 160);

        // The reversal of `a_reversal_keeps_sliding` (at 83.8), its neighbours missing.
        let (tb, j, ur) = (50.5, 2.0, 33.3);
        let c = 3.0 * j / (ur * ur);
        let cfg = PhaseDetectorConfig::for_noise(0.0)
            .unwrap()
            .with_friction(0.25, 0.2);
        for gap in [82..83, 83..84, 84..85, 83..85] {
            let mut d = PhaseDetector::<64>::new(cfg).unwrap();
            let mut events = std::vec::Vec::new();
            for k in 0..120u64 {
                let u = k as f64 - tb;
                let a = if u <= 0.0 {
                    0.0
                } else if u <= ur {
                    j - c * u * u
                } else {
                    j - c * u * u + j
                };
                let x = if gap.contains(&k) { f32::NAN } else { a as f32 };
                if let Some(e) = d.process(x) {
                    events.push((k as f64 - e.age_samples() as f64, e));
                }
            }
            assert_eq!(events.len(), 2, "{gap:?}: {events:?}");
            assert!(
                matches!(events[1].1, SlipEvent::Reversal { direction: -1, .. }),
                "{gap:?}: {events:?}"
            );
            let late = events[1].0 - (tb + ur);
            assert!(
                late.abs() <= (gap.end - gap.start) as f64 + 0.5,
                "{gap:?}: {events:?}"
            );
        }
    }

    /// A stick's jump two or three samples after a missing sample is found at once: its jump
    /// test reads the two measured samples before it, over one sample, with the larger of the
    /// curvature before the gap and the one through the refill. With the gap's n (four or five)
    /// the curvature's noise times n·(n + 1)/2 hid a jump of 1.5 m/s² (El Centro at 1 kHz: the
    /// stick waited ten samples for the stall rule, 4.9 % of the peak): here 40 noisy slides,
    /// each with a frame missing three and four samples before the stick, all found within a
    /// sample of it (before: 41 of the 80).
    #[test]
    fn a_stick_just_after_a_gap_is_found_at_once() {
        let cfg = PhaseDetectorConfig::for_noise(5e-3).unwrap();
        let sigma = 5e-3 * core::f64::consts::SQRT_2;
        // A ramp start at 20.3 into a decelerating slide, s̈ = 0.3·u − 0.0125·u², that sticks
        // at u = 30.2 (s̈ −2.3 m/s²) and stays stuck. Its integrated velocity is not back at
        // zero there (as after an offset's drift, or when it is not trusted), so only the jump
        // tells the stick at once (else the stall rule, ten samples later).
        let (tb, us) = (20.3, 30.2);
        let stick = tb + us;
        let first_after = libm::ceil(stick) as u64;
        let mut found = 0;
        for seed in 0..40u64 {
            let mut noise = super::super::tests::Noise(seed + 11);
            let signal: std::vec::Vec<f64> = (0..90u64)
                .map(|k| {
                    let u = k as f64 - tb;
                    let s = if u <= 0.0 || u > us {
                        0.0
                    } else {
                        0.3 * u - 0.0125 * u * u
                    };
                    s + sigma * noise.next()
                })
                .collect();
            for back in [3u64, 4] {
                let at = first_after - back;
                let (events, _) = run_with_gap(&signal, cfg, at..at + 1);
                let stuck = events
                    .iter()
                    .find(|(_, e)| matches!(e, SlipEvent::Stick { .. }))
                    .map(|&(t, _)| t);
                assert!(
                    events
                        .iter()
                        .filter(|(_, e)| !matches!(e, SlipEvent::Stick { .. }))
                        .count()
                        == 1,
                    "seed {seed}, gap at {at}: {events:?}"
                );
                if stuck.is_some_and(|t| (t - stick).abs() <= 1.0) {
                    found += 1;
                }
            }
        }
        assert_eq!(found, 80);
    }

    /// Review cases of the gap handling. (1) Long gaps in the coarse slide of
    /// `missing_samples_in_a_coarse_slide_are_no_event`: the jump test's n is the gap's own
    /// count when it is longer than the 8 missing indices kept, and the gap is refilled up to
    /// 30 samples (measured: none of the 480 gaps of 10, 15 and 20 samples reads as an event; a
    /// second read measured, with n from the kept indices and no refill beyond 8, 131 of 400
    /// gaps of 12 and 20 as a reversal). (2) Gaps in a stuck phase with the default noise start
    /// no slip start (the fills continue the noise: it measured 61 of 160 gaps of 8 samples
    /// starting one). (3) A reversal with the two samples after it missing: the fills hold the
    /// value after the jump instead of continuing it, and the slide's velocity is the gapless
    /// run's within 1 % (it measured 100 % off). (4) A strong burst with a missing sample among
    /// its first two, or just before them, is no slip start (a fill continues a line: it
    /// measured one).
    #[test]
    fn gaps_long_stuck_and_after_a_jump() {
        // (1)
        let cfg = PhaseDetectorConfig::for_noise(5e-3).unwrap();
        let (tb, n) = (COARSE_SLIDE_START as f64, COARSE_SLIDE_SAMPLES);
        let slide = coarse_slide();
        let run = run_with_gap;
        let clean = run(&slide, cfg, 0..0).0;
        let mut wrong = 0;
        for len in [10u64, 15, 20] {
            for at in (tb as u64 + 10)..(n - 30) {
                if run(&slide, cfg, at..at + len).0 != clean {
                    wrong += 1;
                }
            }
        }
        std::println!("long gaps: {wrong} of 480");
        assert!(wrong <= 2, "{wrong}");
        // (2)
        let mut noise = Noise(11);
        let sigma = 5e-3 * core::f64::consts::SQRT_2;
        let stuck: std::vec::Vec<f64> = (0..300).map(|_| sigma * noise.next()).collect();
        for len in [4u64, 8, 24] {
            for at in 20..(300 - len) {
                let events = run(&stuck, cfg, at..at + len).0;
                assert!(events.is_empty(), "{len} missing at {at}: {events:?}");
            }
        }
        // (3)
        let (tb, j, ur) = (50.5, 2.0, 33.3);
        let c = 3.0 * j / (ur * ur);
        let jumps = PhaseDetectorConfig::for_noise(0.0)
            .unwrap()
            .with_friction(0.25, 0.2);
        let rev: std::vec::Vec<f64> = (0..95u64)
            .map(|k| {
                let u = k as f64 - tb;
                if u <= 0.0 {
                    0.0
                } else if u <= ur {
                    j - c * u * u
                } else {
                    j - c * u * u + j
                }
            })
            .collect();
        let (e0, d0) = run(&rev, jumps, 0..0);
        let (e1, d1) = run(&rev, jumps, 85..87);
        assert_eq!(e0.len(), 2, "{e0:?}");
        assert_eq!(e1, e0);
        assert!(
            (d1.v - d0.v).abs() <= 0.01 * d0.v.abs(),
            "{} vs {}",
            d1.v,
            d0.v
        );
        // (4)
        let thr = f64::from(cfg.threshold_m_s2);
        for burst in [[100.0, f64::NAN, 100.0], [f64::NAN, 100.0, 100.0]] {
            let mut signal = std::vec![0.0; 60];
            for (i, b) in burst.iter().enumerate() {
                signal[30 + i] = b * thr;
            }
            let mut d = PhaseDetector::<64>::new(cfg.with_friction(0.25, 0.2)).unwrap();
            for (k, &a) in signal.iter().enumerate() {
                assert_eq!(d.process(a as f32), None, "{burst:?} at {k}");
            }
        }
    }
}
