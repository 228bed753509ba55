//! Sensing the contact phase (slip start, reversal, stick) from the measured slip acceleration:
//! the base accelerometer minus the table accelerometer, s̈ = ü2 − üg.
//!
//! The friction makes s̈ change sharply at every phase change, far above accelerometer noise:
//! with F the friction on the base and F_stick = m1·ü1 + m2·üg the force that keeps it stuck,
//! m2·s̈ = F − F_stick while sliding and s̈ = 0 while stuck. So
//!
//! * a **stick** is where the slip velocity v = ∫s̈ returns to zero and s̈ drops to zero (from a
//!   deceleration of order μ(m1 + m2)g/m2);
//! * a **reversal** is where v crosses zero and s̈ stays away from zero (F jumps by 2μ(m1+m2)g);
//! * a **slip start** is where s̈ leaves zero: a ramp S·(t − t_b) when static and kinetic friction
//!   are equal (F_stick crosses μ(m1+m2)g; or (t − t_b)² when it touches it), a jump plus a ramp
//!   when static friction exceeds kinetic.
//!
//! The slip velocity is integrated (trapezoid) from the last event, where it is known to be zero,
//! so integration noise does not accumulate across events: its error after n samples is about
//! σ·Δt·√n. A zero of v is located inside its sample interval from the pre-event acceleration
//! (extrapolated linearly); a slip start by a least-squares fit of the ramp (or jump) model to the
//! samples around the first one above the threshold, on a one-sample grid of trial times refined
//! by golden-section search. Times are relative to the current sample (exact for any run length).
//! Events are reported late (a stick or a reversal one sample, a slip start `confirm_samples`, a
//! stick without a jump `stall_samples` or more, at most [`PhaseDetectorConfig::max_age_samples`])
//! with their age in samples, which the estimator back-dates; an event is never earlier than the
//! one before it (a stick and the slip start after it can coincide). Non-finite or overflowing
//! input never panics: the velocity is then held at zero and events are timed mid-interval. Fixed-size ring of `N` samples; no
//! heap, no panics.
//!
//! The measured s̈ is not zero while stuck: the accelerometers' offsets and gains differ. Both are
//! tracked while the base sticks and removed from every sample ([`offsets`](self) holds how).
//!
//! Compared with the displacement detector ([`crate::detect::displacement`]), which must wait for the
//! slip to move by several times the displacement noise (a slow breakaway stays below 1 µm for
//! milliseconds), this one needs accelerometers on the base and the table.

use super::ring::slot;
use super::SlipEvent;
use crate::error::{check, Error, Param};

mod event_step;
mod gaps;
mod offsets;
mod slip_start;
use gaps::{missing, MISSING_KEPT};
use offsets::{GAIN_EXCITATION_THRESHOLDS, GAIN_PRIOR_SAMPLES};
pub use slip_start::{START_LINE_SAMPLES, START_PARABOLA_SAMPLES};

/// A jump of s̈ (against its linear extrapolation) larger than this many thresholds is a change
/// of the friction force.
const JUMP_THRESHOLDS: f32 = 3.0;

/// The stall rule's velocity bound: this many times `stall_samples` × threshold (m/s² × samples).
const STALL_VELOCITY: f32 = 8.0;

/// A sliding base with |s̈| below the threshold for this many times the longest back-dating is
/// declared stuck whatever its integrated velocity (the stick then back-dated to that limit).
const STALL_FORCE: usize = 8;

/// … plus this many times the magnitudes of s̈'s last second and third differences.
const CURVATURES: f32 = 4.0;

/// Detector settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseDetectorConfig {
    /// |s̈| above which the base slides (m/s²): a few times the slip acceleration's noise RMS.
    pub threshold_m_s2: f32,
    /// Samples from the first one above the threshold to the slip start's report (its fit).
    pub confirm_samples: usize,
    /// Samples before the first one above the threshold searched for the slip start.
    pub search_samples: usize,
    /// Samples of |s̈| below the threshold after which a sliding base is declared stuck even
    /// without a jump of s̈ (when the integrated velocity is about zero too).
    pub stall_samples: usize,
    /// Breakaway shape: static friction above kinetic makes s̈ jump at a slip start (then the
    /// time is known to the sample interval only); equal ones make it ramp up from zero.
    pub jump_breakaway: bool,
    /// Confirm a ramp breakaway (not `jump_breakaway`) at its second sample above the
    /// threshold when that one is at least 20 thresholds (~170 σ of the noise) and 1.5 times
    /// the first (a ramp's shape: a jump that was not expected, μs told equal to μ, waits for
    /// its fourth sample, whose sliding side gives the slide its μ), as a strong jump
    /// breakaway is confirmed early, instead of at its `confirm_samples`th: at coarse rates a
    /// smooth start reaches that within a sample (1.7 and 3.8 m/s² on the default scene at 1 kHz, against a
    /// threshold of 0.042), while the model ran on in the stuck phase (in predict mode up to
    /// 2.4 % of the peak on the sample before the report). Its sliding side comes a sample
    /// later ([`PhaseDetector::late_slip_start_accel`]) and the slide's friction from its
    /// breakaway until then: in fuse mode read on the measured top; in predict mode on the
    /// model's state, so there the sliding side replaces it a sample later (`ssvr_proto`'s
    /// `BaseTuning::late_slide_side`). Every plan sets it (`ssvr_proto`'s `Plan::new`; fuse
    /// mode's only while predict mode kept the breakaway's friction for the whole slide: the
    /// default scene at 1 kHz with every accelerometer 0.05 g off and no rest then had its max
    /// error at 4.3 % of the peak instead of 2.2 %).
    pub early_ramp_starts: bool,
}

impl PhaseDetectorConfig {
    /// Defaults for the noise RMS of each accelerometer (base and table, m/s²): a threshold of 6σ
    /// of their difference (σ·√2; at least 1 mm/s²), slip starts confirmed over 4 samples and
    /// searched up to 32 samples before the first one above the threshold.
    pub fn for_noise(accel_noise_rms_m_s2: f64) -> Result<Self, Error> {
        check(
            Param::NoiseRms,
            accel_noise_rms_m_s2,
            accel_noise_rms_m_s2 >= 0.0,
            ">= 0 m/s²",
        )?;
        Ok(Self {
            threshold_m_s2: (6.0 * libm::sqrt(2.0) * accel_noise_rms_m_s2).max(1e-3) as f32,
            confirm_samples: 4,
            search_samples: 32,
            stall_samples: 10,
            jump_breakaway: false,
            early_ramp_starts: false,
        })
    }

    /// The breakaway shape for static and kinetic friction coefficients (a jump when μs > μ).
    pub fn with_friction(mut self, mu_static: f64, mu_kinetic: f64) -> Self {
        self.jump_breakaway = mu_static > mu_kinetic;
        self
    }

    /// With ramp breakaways confirmed early when strong ([`Self::early_ramp_starts`]).
    pub fn with_early_ramp_starts(mut self, early: bool) -> Self {
        self.early_ramp_starts = early;
        self
    }

    /// The ring the detector needs (a power of two holding the slip start's fit window).
    pub fn min_ring(&self) -> usize {
        self.search_samples
            .saturating_add(self.confirm_samples)
            .saturating_add(2)
            .checked_next_power_of_two()
            .unwrap_or(usize::MAX)
    }

    /// The oldest event this detector reports (samples): a slip start's search window.
    pub fn max_age_samples(&self) -> usize {
        self.search_samples
            .saturating_add(self.confirm_samples)
            .saturating_add(1)
    }
}

/// The phase detector with a ring of `N` samples of slip acceleration.
#[derive(Debug, Clone)]
pub struct PhaseDetector<const N: usize> {
    cfg: PhaseDetectorConfig,
    ring: [f32; N],
    /// Index of the next sample (samples seen so far).
    k: u64,
    /// Slip direction: +1, −1, or 0 while stuck.
    direction: i8,
    /// Slip velocity at the last sample (m/s² × samples), while sliding.
    v: f32,
    /// The integrated velocity was found off and is held at zero until the next event.
    v_held: bool,
    /// Uncertainty of the integrated velocity from the slip start (m/s² × samples): a jump
    /// breakaway is known to a sample only, so up to the jump times a sample.
    v_unc: f32,
    /// Consecutive samples with |s̈| below the threshold (while sliding).
    in_band: usize,
    /// While stuck: the first sample above the threshold (a slip start being confirmed).
    pending: Option<u64>,
    /// The last stick: the first stuck sample and the stick's age at it (samples).
    stick_at: (u64, f32),
    /// Offset of the slip acceleration (m/s²): the two accelerometers' offsets differ, and a
    /// stuck base has s̈ = 0, so the measured s̈ while stuck is the offset (tracked, and
    /// subtracted from every sample).
    bias: f32,
    /// Samples in the initial offset's mean.
    bias_n: u32,
    /// Gain mismatch of the two accelerometers: the part of the table acceleration in the
    /// measured s̈ (tracked while stuck, and subtracted from every sample).
    gain: f32,
    /// Information of the gain mismatch (exponentially forgotten sum of the squared table
    /// accelerations that informed it, (m/s²)²).
    gain_info: f32,
    /// The table acceleration at rest (m/s²): the mean of the first samples (those in the
    /// offset's), its accelerometer's offset. The gain mismatch is regressed on the table
    /// acceleration less it, so that an offset of the table accelerometer is not mistaken for
    /// excitation (the rest of that offset's share is in the tracked offset).
    table_zero: f32,
    /// The last slip start's sliding side at its start time: s̈ of the parabola (or line)
    /// through its first samples above the threshold, extrapolated back (m/s²; NaN before any).
    start_accel: f32,
    /// A slip start confirmed at its second sample ([`STRONG_JUMP`]) whose sliding side waits
    /// for its third: its first sample above the threshold, the confirming sample and the
    /// start's time relative to it.
    side_due: Option<(u64, u64, f32)>,
    /// That sliding side, once its third sample is in (NaN: none), and the sample it came with.
    late_side: (f32, u64),
    /// The latest [`MISSING_KEPT`] missing samples' indices + 1 (0: none),
    /// a ring: a missing sample is filled in the ring by the linear continuation of the two
    /// before it, and the fits leave it out ([`Self::missing_mask`]).
    missing_at: [u64; MISSING_KEPT],
    /// The first sample after the latest jump of s̈ the detector knows of (an event's, or a slip
    /// start's first sample above the threshold): a fill does not continue a slope across it.
    jump_at: u64,
    /// The next slot of `missing_at`.
    missing_next: u8,
    /// Missing samples since the last measured one.
    gap: u8,
}

impl<const N: usize> PhaseDetector<N> {
    /// A detector that starts stuck.
    pub fn new(cfg: PhaseDetectorConfig) -> Result<Self, Error> {
        check(
            Param::Threshold,
            cfg.threshold_m_s2 as f64,
            cfg.threshold_m_s2 > 0.0,
            "threshold > 0 m/s²",
        )?;
        if cfg.confirm_samples < 2 {
            return Err(Error::OutOfRange {
                param: Param::ConfirmSamples,
                value: cfg.confirm_samples as f64,
                expected: "confirm_samples >= 2",
            });
        }
        if cfg.stall_samples < 2 {
            return Err(Error::OutOfRange {
                param: Param::StallSamples,
                value: cfg.stall_samples as f64,
                expected: "stall_samples >= 2",
            });
        }
        if cfg.min_ring() > N {
            return Err(Error::OutOfRange {
                param: Param::RingLength,
                value: N as f64,
                expected: "a ring of at least search + confirm samples + 2 (a power of two)",
            });
        }
        Ok(Self {
            cfg,
            ring: [0.0; N],
            k: 0,
            direction: 0,
            v: 0.0,
            v_held: false,
            v_unc: 0.0,
            in_band: 0,
            pending: None,
            stick_at: (0, 0.0),
            bias: 0.0,
            bias_n: 0,
            gain: 0.0,
            table_zero: 0.0,
            start_accel: f32::NAN,
            side_due: None,
            late_side: (f32::NAN, 0),
            missing_at: [0; MISSING_KEPT],
            jump_at: 0,
            missing_next: 0,
            gap: 0,
            gain_info: GAIN_PRIOR_SAMPLES
                * (GAIN_EXCITATION_THRESHOLDS * cfg.threshold_m_s2)
                * (GAIN_EXCITATION_THRESHOLDS * cfg.threshold_m_s2),
        })
    }

    /// The current slip direction (+1, −1, 0 stuck).
    pub fn direction(&self) -> i8 {
        self.direction
    }

    /// Samples processed.
    pub fn samples(&self) -> u64 {
        self.k
    }

    /// The settings.
    pub fn config(&self) -> &PhaseDetectorConfig {
        &self.cfg
    }

    /// The last slip start's slip acceleration on its sliding side at its start time (m/s²;
    /// NaN before any): its first [`START_LINE_SAMPLES`] samples above the threshold, the
    /// parabola through them (the first within [`START_PARABOLA_SAMPLES`] of the start) or
    /// their least-squares line (further), extrapolated back to the start; NaN for a slip start
    /// confirmed at its second sample, whose side comes a sample later
    /// ([`Self::late_slip_start_accel`]). The slip acceleration is zero before
    /// the start and jumps there by (μs − μ)·(m1 + m2)·g/m2 toward the sliding direction (a
    /// Coulomb interface): with the table's acceleration and the top's at the start, it gives
    /// the kinetic friction of the slide from the momentum balance, whatever μs is. Read it
    /// with the [`SlipEvent::SlipStart`] it belongs to: the next slip start replaces it.
    pub fn slip_start_accel(&self) -> f32 {
        self.start_accel
    }

    /// Whether the last slip start, confirmed at its second sample (a strong jump breakaway),
    /// has its sliding side still to come: NaN in [`Self::slip_start_accel`], the parabola through
    /// its first three samples in [`Self::late_slip_start_accel`] one sample later.
    pub fn side_pending(&self) -> bool {
        self.side_due.is_some()
    }

    /// The sliding side (m/s², as [`Self::slip_start_accel`]) of the slip start confirmed at the
    /// sample before the last one processed, at its second sample: the parabola through its
    /// first three; NaN at any other sample, or when that third sample brought an event or the
    /// base stuck.
    pub fn late_slip_start_accel(&self) -> f32 {
        let (side, at) = self.late_side;
        if at != 0 && at + 1 == self.k {
            side
        } else {
            f32::NAN
        }
    }

    pub(super) fn at(&self, i: u64) -> f32 {
        self.ring[slot::<N>(i)]
    }

    /// Process one sample of the slip acceleration, base minus table accelerometer (m/s²),
    /// without the table acceleration: no gain mismatch is tracked or removed. A non-finite sample
    /// continues the last two linearly.
    pub fn process(&mut self, slip_accel: f32) -> Option<SlipEvent> {
        self.process_with_reference(slip_accel, 0.0)
    }

    /// Process one sample of the slip acceleration, base minus table accelerometer, with the
    /// table accelerometer's sample (m/s²): the gain mismatch is tracked and removed too. A
    /// non-finite sample, or one whose table acceleration is not finite, continues the last two
    /// linearly; a table acceleration beyond 10⁴ m/s² does not inform the gain mismatch.
    pub fn process_with_reference(
        &mut self,
        slip_accel: f32,
        table_accel: f32,
    ) -> Option<SlipEvent> {
        let k = self.k;
        // The table acceleration less its value at rest, and the gain mismatch's share of it
        // removed (a non-finite table acceleration makes the sample non-finite).
        let reference = table_accel - self.table_zero;
        let x = slip_accel - self.gain * reference;
        let measured = x.is_finite();
        let a = if measured {
            self.unbias(x, reference)
        } else {
            self.fill(k)
        };
        self.ring[slot::<N>(k)] = a;
        self.k += 1;
        if k < 3 {
            if measured {
                self.gap = 0;
            }
            return None;
        }
        let event = if self.direction == 0 {
            self.stuck(k, a, measured)
        } else {
            self.sliding(k, a)
        };
        if measured && self.gap != 0 {
            self.after_gap(k, event.is_none());
        }
        if self.side_due.is_some() {
            self.complete_side(k, event.is_none());
        }
        event
    }

    /// The sample `k` after a slip start confirmed at its second: its sliding side from the
    /// first three (`quiet`: `k` brought no event).
    #[cold]
    #[inline(never)]
    fn complete_side(&mut self, k: u64, quiet: bool) {
        let Some((p, confirmed, tb)) = self.side_due else {
            return;
        };
        if confirmed == k {
            // (Confirmed at this very sample.)
            return;
        }
        self.side_due = None;
        if quiet && self.direction != 0 && confirmed + 1 == k {
            self.late_side = (self.start_line(p, k, tb - 1.0), k);
        }
    }

    /// A sliding sample: integrate the slip velocity; a stick or a reversal where s̈ jumps (the
    /// friction force changes at once) or, for a gentle stop, where v returns to zero.
    fn sliding(&mut self, k: u64, a: f32) -> Option<SlipEvent> {
        let d = self.direction as f32;
        let (a1, a2) = (self.at(k - 1), self.at(k - 2));
        // The pre-event acceleration over (k − 1, k]: a1 + b·τ (τ in samples from k − 1).
        let b = a1 - a2;
        let thr = self.cfg.threshold_m_s2;
        // While sliding s̈ is continuous; the friction force can only jump towards the sliding
        // direction (a stick or a reversal ends a deceleration).
        // Judged against the signal's own curvature (its last second difference, and how fast
        // that changes, its last third difference): coarse sampling of a fast s̈ misses its
        // linear extrapolation by about their sum without any event. (Near a zero of the
        // sliding oscillation's s̈ the second difference is small and the third is not: at
        // 700 Hz, with the second alone, a deceleration's zero crossing read as a reversal.)
        // (The curvature only when the miss exceeds the threshold's part: most samples.)
        let miss = d * (a - (a1 + b));
        let jump = miss > JUMP_THRESHOLDS * thr
            && if !self.near_gap(k) {
                miss > JUMP_THRESHOLDS * thr + CURVATURES * self.curvature(k, b, a2)
            } else {
                // (A missing sample's own linear fill makes no jump: miss 0.)
                self.jump_near_gap(k, miss)
            };
        let v_end = self.v + a1 + 0.5 * b;
        let crossed = d * v_end <= 0.0;
        let stuck = libm::fabsf(a) < thr;
        self.in_band = if stuck {
            self.in_band.saturating_add(1)
        } else {
            0
        };
        let m = self.cfg.stall_samples;
        if self.in_band >= m && self.stalled(m, thr) {
            let cap = self.cfg.max_age_samples();
            // s̈ has stayed at zero for `stall_samples` with no jump seen (a stick too gentle or
            // too noisy for one), and the velocity is about zero: the base sticks, since the
            // first sample of the run.
            // (Capped at the longest back-dating the detector promises; after `STALL_FORCE`
            // times that in the band the base is declared stuck whatever the velocity says:
            // the integrated velocity can be off for good, e.g. after overflowing input.)
            let n = self.in_band.min(cap.saturating_sub(1)).max(1);
            let age = (n - 1) as f32 + 0.5;
            self.direction = 0;
            self.v = 0.0;
            self.v_held = false;
            self.pending = None;
            self.in_band = 0;
            self.stick_at = (k + 1 - n as u64, 0.5);
            self.jump_at = k;
            return Some(SlipEvent::Stick { age_samples: age });
        }
        // A gentle stop (s̈ → 0 as v → 0, no jump) is only seen through v, when v is trusted.
        if !(jump || (crossed && stuck && !self.v_held)) {
            if crossed {
                // v reached zero but s̈ shows no event: the integrated velocity is off (by the
                // jump at the slip start, known to a sample only). Hold it at zero. (A velocity
                // that overflowed is reset by the next event, or by the forced stall.)
                self.v = 0.0;
                self.v_held = true;
            } else {
                self.v += 0.5 * (a1 + a);
            }
            return None;
        }
        let tau = if self.v_held {
            0.5
        } else {
            // v(τ) = v + a1·τ + b·τ²/2 = 0: the linear root, then a Newton step; an
            // integrated velocity that puts the zero outside the interval of the jump is off:
            // the middle of the interval.
            let mut tau = if a1 != 0.0 { -self.v / a1 } else { 0.5 };
            let dv = a1 + b * tau;
            if dv != 0.0 {
                tau -= (self.v + a1 * tau + 0.5 * b * tau * tau) / dv;
            }
            if (0.0..=1.0).contains(&tau) {
                tau
            } else if jump || !tau.is_finite() {
                0.5
            } else {
                tau.clamp(0.0, 1.0)
            }
        };
        let age = 1.0 - tau;
        self.v_held = false;
        if stuck {
            // s̈ dropped to zero: the base sticks.
            self.direction = 0;
            self.v = 0.0;
            self.pending = None;
            self.stick_at = (k, age);
            self.in_band = 0;
            self.jump_at = k;
            return Some(SlipEvent::Stick { age_samples: age });
        }
        if d * a < 0.0 {
            // s̈ jumped but stays away from zero against the old direction: a reversal. The
            // velocity since it, with the post-event acceleration (slope b too).
            let direction = -self.direction;
            self.direction = direction;
            self.v = a * age - 0.5 * b * age * age;
            self.jump_at = k;
            return Some(SlipEvent::Reversal {
                direction,
                age_samples: age,
            });
        }
        // A jump to acceleration in the sliding direction is not a friction change (noise).
        self.v += 0.5 * (a1 + a);
        None
    }

    /// |second difference| + |third difference| of s̈ at k − 1 (`b` = a(k−1) − a(k−2), `a2` =
    /// a(k−2)).
    #[inline]
    fn curvature(&self, k: u64, b: f32, a2: f32) -> f32 {
        let (a3, a4) = (self.at(k - 3), self.at(k.saturating_sub(4)));
        let c1 = b - (a2 - a3);
        let c2 = a2 - a3 - (a3 - a4);
        libm::fabsf(c1) + libm::fabsf(c1 - c2)
    }

    /// The stall rule (|s̈| in the band for `m` ≥ `stall_samples` samples): the integrated
    /// velocity is held or about zero, or the band has lasted `STALL_FORCE` × the longest
    /// back-dating.
    #[cold]
    fn stalled(&self, m: usize, thr: f32) -> bool {
        self.v_held
            || libm::fabsf(self.v) <= STALL_VELOCITY * m as f32 * thr + self.v_unc
            || self.in_band >= STALL_FORCE.saturating_mul(self.cfg.max_age_samples())
    }

    /// A stuck sample (`measured`: not a fill, which only counts towards a pending slip start's
    /// confirmation, as its last sample after measured ones: a noise spike and the fills
    /// continuing it are no slip start): watch for s̈ leaving zero; confirm and time the slip
    /// start.
    fn stuck(&mut self, k: u64, a: f32, measured: bool) -> Option<SlipEvent> {
        let thr = self.cfg.threshold_m_s2;
        let Some(p) = self.pending else {
            // (A fill starts no slip start: it continues the noise.)
            if measured && libm::fabsf(a) >= thr {
                self.pending = Some(k);
                self.jump_at = k;
            }
            return None;
        };
        let s = if self.at(p) > 0.0 { 1.0 } else { -1.0 };
        if !measured {
            let before = (self.missing_mask(k) >> 1) & ((1u64 << (k - p).min(63)) - 1);
            if k - p + 1 < self.cfg.confirm_samples as u64 || before != 0 {
                return None;
            }
            return self.slip_start(p, k);
        }
        // A noise spike: the samples after it must keep its sign, at least half the threshold.
        if s * a < 0.5 * thr {
            self.pending = None;
            if libm::fabsf(a) >= thr {
                self.pending = Some(k);
                self.jump_at = k;
            }
            return None;
        }
        if k - p + 1 < self.cfg.confirm_samples as u64 && !self.strong_start(p, k, s * a) {
            return None;
        }
        self.slip_start(p, k)
    }
}

#[cfg(test)]
mod tests;
