//! A slip start's confirmation at its second sample when it is strong (a jump breakaway the
//! prior expects, or in fuse mode a ramp: `strong_start`), its timing ([`PhaseDetector`]'s fit
//! of the ramp or jump model) and its sliding side at the start
//! ([`PhaseDetector::slip_start_accel`]).

use super::super::ring::rel;
use super::super::search::{golden_min, grid_min};
use super::super::SlipEvent;
use super::{missing, PhaseDetector};

/// Samples from the first one above the threshold that give a slip start's sliding side at its
/// start ([`PhaseDetector::slip_start_accel`]): three, for the parabola through them (the
/// sliding oscillation's curvature: it turns 0.19 rad per sample at 1 kHz), or the line when
/// the first is far from the start (a ramp start: its noise stays low extrapolated back).
pub const START_LINE_SAMPLES: u64 = 3;
const _: () = assert!(
    START_LINE_SAMPLES == 3,
    "the parabola is through three samples"
);

/// The first of them within this many samples of the start: the parabola through the three
/// ([`PhaseDetector::slip_start_accel`]).
pub const START_PARABOLA_SAMPLES: f32 = 2.0;

/// A ramp breakaway confirmed early ([`PhaseDetectorConfig::early_ramp_starts`]) has its second
/// sample at least this many times its first (a ramp from zero: twice or more, less the
/// curvature; a jump: about once).
pub(super) const RAMP_GROWTH: f32 = 1.5;

/// A jump breakaway whose first two samples are this many thresholds is confirmed at its
/// second ([`PhaseDetector`]'s `strong_start`): 20 × 6σ√2 ≈ 170 σ of a sample's noise; so is a
/// ramp breakaway whose second sample is (with [`PhaseDetectorConfig::early_ramp_starts`]).
pub(super) const STRONG_JUMP: f32 = 20.0;

impl<const N: usize> PhaseDetector<N> {
    /// A slip start confirmed early, at its second sample `k` (`along`: its s̈ towards the slide):
    /// a jump breakaway (expected: `jump_breakaway`) whose two samples are at least [`STRONG_JUMP`]
    /// thresholds, or (`early_ramp_starts`) a ramp breakaway whose second one is; the sample before
    /// the first within one, all three measured (a fill continues a line). Its sliding side, the
    /// parabola through its first three samples, comes a sample later
    /// ([`Self::late_slip_start_accel`]): the line through two put predict mode's M 1.35 % off on
    /// El Centro at 1 kHz. A burst of two such samples and nothing after them, which a fourth
    /// sample would reject as a spike, is taken for a slip start: ~170 σ twice running is a fault
    /// of the sensor, not noise.
    #[inline]
    pub(super) fn strong_start(&self, p: u64, k: u64, along: f32) -> bool {
        let strong = STRONG_JUMP * self.cfg.threshold_m_s2;
        let first_strong = if self.cfg.jump_breakaway {
            libm::fabsf(self.at(p)) >= strong
        } else {
            // (A ramp's second sample is at least twice its first, less its curvature; an
            // unexpected jump's is about its first: it waits for its fourth, whose sliding
            // side gives its slide's friction, not the breakaway's μs.)
            self.cfg.early_ramp_starts && along >= RAMP_GROWTH * libm::fabsf(self.at(p))
        };
        k == p + 1
            && along >= strong
            && first_strong
            && libm::fabsf(self.at(p - 1)) < self.cfg.threshold_m_s2
            && self.missing_mask(k) & 0b111 == 0
    }

    /// Time the slip start whose first sample above the threshold is `p`; the current sample is
    /// `k`. Least squares over the measured samples lo..=k for the trial start t_b (relative
    /// to k; a missing sample's fill continues the stuck samples, not the breakaway).
    pub(super) fn slip_start(&mut self, p: u64, k: u64) -> Option<SlipEvent> {
        self.pending = None;
        let s: i8 = if self.at(p) > 0.0 { 1 } else { -1 };
        let (stick_k, stick_age) = self.stick_at;
        let lo = p
            .saturating_sub(self.cfg.search_samples as u64)
            .max(k.saturating_sub(N as u64 - 1))
            .max(stick_k.saturating_sub(1));
        // The earliest start: the stick before it, or the window's first sample.
        let t_min = if stick_k >= lo && stick_k <= k {
            rel(stick_k, k) - stick_age
        } else {
            rel(lo, k)
        };
        let t_max = rel(p, k);
        let t_min = if t_min.is_finite() {
            t_min.min(t_max)
        } else {
            rel(lo, k)
        };
        let a = |i: u64| self.at(i);
        // (The missing samples' fills continue the stuck samples, not the breakaway.)
        let mask = self.missing_mask(k);
        let measured = |i: u64| !missing(mask, k - i);
        let tb = if self.cfg.jump_breakaway {
            // s̈ = (J + S·u)·[u > 0], u = t − t_b: the residual is constant between samples, so
            // t_b is the middle of the best sample interval.
            let resid = |tb: f32| {
                let (mut n, mut su, mut suu, mut sa, mut sua) = (0.0f32, 0.0, 0.0, 0.0, 0.0);
                for i in lo..=k {
                    let u = rel(i, k) - tb;
                    if u > 0.0 && measured(i) {
                        let y = a(i);
                        n += 1.0;
                        su += u;
                        suu += u * u;
                        sa += y;
                        sua += u * y;
                    }
                }
                let det = n * suu - su * su;
                if det.is_nan() || det <= 0.0 {
                    return f32::INFINITY;
                }
                // −(explained sum of squares): bᵀA⁻¹b.
                -((suu * sa * sa - 2.0 * su * sa * sua + n * sua * sua) / det)
            };
            let first = libm::floorf(t_min) + 0.5;
            let (best, _) = grid_min(&resid, (first, t_max), 1.0);
            // (max/min: NaN-safe.)
            best.max(t_min).min(t_max)
        } else {
            // s̈ = S·u^q·[u > 0], q = 1 (a linear crossing) or 2 (a tangent one).
            let resid_q = |tb: f32, q: i32| {
                let (mut sgg, mut sga) = (0.0f32, 0.0f32);
                for i in lo..=k {
                    let u = rel(i, k) - tb;
                    if u > 0.0 && measured(i) {
                        let g = if q == 1 { u } else { u * u };
                        sgg += g * g;
                        sga += g * a(i);
                    }
                }
                if sgg.is_nan() || sgg <= 0.0 {
                    return f32::INFINITY;
                }
                -(sga * sga / sgg)
            };
            let mut best = (t_max, f32::INFINITY);
            for q in [1, 2] {
                let f = |tb: f32| resid_q(tb, q);
                let (g, _) = grid_min(&f, (t_min, t_max), 1.0);
                let t = golden_min(&f, ((g - 1.0).max(t_min), (g + 1.0).min(t_max)), 14);
                let r = f(t);
                if r < best.1 {
                    best = (t, r);
                }
            }
            best.0
        };
        // Slip velocity at k since t_b: the piece up to the first sample after it (from zero,
        // or from the jump), then trapezoids.
        let j0 = k - (libm::floorf(-tb).max(0.0) as u64).min(k - lo);
        let first = rel(j0, k) - tb;
        let mut v = if self.cfg.jump_breakaway { 1.0 } else { 0.5 } * a(j0) * first.max(0.0);
        let v_unc = if self.cfg.jump_breakaway {
            libm::fabsf(a(j0))
        } else {
            0.0
        };
        let mut i = j0;
        while i < k {
            v += 0.5 * (a(i) + a(i + 1));
            i += 1;
        }
        // (Confirmed at its second sample: its sliding side a sample later.)
        if k + 1 < p + START_LINE_SAMPLES {
            self.start_accel = f32::NAN;
            self.side_due = Some((p, k, tb));
        } else {
            self.start_accel = self.start_line(p, k, tb);
            self.side_due = None;
        }
        self.v = v;
        self.v_unc = v_unc;
        self.v_held = false;
        self.in_band = 0;
        self.direction = s;
        Some(SlipEvent::SlipStart {
            direction: s,
            age_samples: (-tb).max(0.0),
        })
    }

    /// The sliding side's s̈ at the time `tb` (relative to the current sample k) from the samples
    /// p.. ([`START_LINE_SAMPLES`] of them, up to k): the parabola through three when the first
    /// is within [`START_PARABOLA_SAMPLES`] of `tb` (the sliding oscillation's curvature: at
    /// 1 kHz a line took the slide's μ ~1 % low), else the least-squares line (the parabola's noise grows
    /// with the distance: 10× the samples' at 2, 43× at 5); NaN with fewer than two. A missing
    /// one (its fill continues the stuck samples) is left out: the line through the other two.
    pub(super) fn start_line(&self, p: u64, k: u64, tb: f32) -> f32 {
        let end = k.min(p + START_LINE_SAMPLES - 1);
        let x0 = rel(p, k) - tb;
        // (A missing sample among them: the line through the other two, if two.)
        let span = (1u64 << (end.saturating_sub(p) + 1).min(START_LINE_SAMPLES)) - 1;
        let back = k - end;
        let gaps = if back < 64 {
            (self.missing_mask(k) >> back) & span
        } else {
            0
        };
        if gaps != 0 {
            let mut two = (p..=end).filter(|&i| (gaps >> (end - i)) & 1 == 0);
            let (Some(i), Some(j)) = (two.next(), two.next()) else {
                return f32::NAN;
            };
            let (xi, xj) = (rel(i, k) - tb, rel(j, k) - tb);
            let (ai, aj) = (self.at(i), self.at(j));
            return ai - (aj - ai) * xi / (xj - xi);
        }
        if end >= p + 2 && x0 < START_PARABOLA_SAMPLES {
            // Lagrange at 0 through x0, x0 + 1, x0 + 2 (times from the start).
            let (x1, x2) = (x0 + 1.0, x0 + 2.0);
            return 0.5 * x1 * x2 * self.at(p) - x0 * x2 * self.at(p + 1)
                + 0.5 * x0 * x1 * self.at(p + 2);
        }
        let (mut n, mut sx, mut sy, mut sxx, mut sxy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
        let mut i = p;
        while i <= end {
            // (Time from the start: small numbers, no cancellation in f32.)
            let x = rel(i, k) - tb;
            let y = self.at(i);
            n += 1.0;
            sx += x;
            sy += y;
            sxx += x * x;
            sxy += x * y;
            i += 1;
        }
        let det = n * sxx - sx * sx;
        if n < 2.0 || det.is_nan() || det <= 0.0 {
            return f32::NAN;
        }
        // The intercept at x = 0 (the start).
        (sxx * sy - sx * sxy) / det
    }
}

#[cfg(test)]
mod tests {
    use super::super::{PhaseDetector, PhaseDetectorConfig};

    /// A strong jump breakaway (μs > μ told: `jump_breakaway`) is confirmed at its second
    /// sample, not its fourth: at 1 kHz each sample the stuck phase's prediction runs on past
    /// the start costs the top up to ~0.05 m/s² on El Centro. Its time is as good (within its
    /// sample interval); its sliding side is NaN at the confirmation and comes a sample later,
    /// the parabola through its first three samples (within 2e-3 m/s², as a fourth sample's
    /// confirmation gives it at once). A jump below 20 thresholds, or a start not expected to
    /// jump, waits for the fourth, and a lone spike of any size is no slip start.
    #[test]
    fn a_strong_jump_breakaway_is_confirmed_at_its_second_sample() {
        let run = |cfg: PhaseDetectorConfig, jump: f64, spike: bool| {
            let mut d = PhaseDetector::<64>::new(cfg).unwrap();
            let tb = 50.4;
            let mut found = None;
            let mut side = None;
            for k in 0..120u64 {
                let u = k as f64 - tb;
                let a = if spike {
                    if k == 51 {
                        jump
                    } else {
                        0.0
                    }
                } else if u > 0.0 {
                    jump + 0.3 * u - 0.02 * u * u
                } else {
                    0.0
                };
                let pending = d.side_pending();
                let event = d.process(a as f32);
                if pending {
                    assert!(!d.side_pending());
                    side = Some(d.late_slip_start_accel() as f64);
                } else {
                    assert!(d.late_slip_start_accel().is_nan(), "{k}");
                }
                if let Some(e) = event {
                    assert!(found.is_none(), "{e:?} at {k}");
                    let start = k as f64 - e.age_samples() as f64;
                    found = Some((k, start - tb));
                    if !d.side_pending() {
                        side = Some(d.slip_start_accel() as f64);
                    } else {
                        assert!(d.slip_start_accel().is_nan());
                    }
                }
            }
            // (Its sliding side against the signal's at the start found: a jump start is timed
            // to its sample interval.)
            found.map(|(k, x)| {
                let at_start = jump + 0.3 * x - 0.02 * x * x;
                (k, x, side.unwrap_or(f64::NAN) - at_start)
            })
        };
        let cfg = PhaseDetectorConfig::for_noise(5e-3).unwrap();
        let thr = f64::from(cfg.threshold_m_s2);
        let jumps = cfg.with_friction(0.25, 0.2);
        // First sample above the threshold: 51; confirmed at 52 (strong) or 54.
        let (k, dt, side) = run(jumps, 8.75, false).unwrap();
        assert_eq!(k, 52);
        assert!(dt.abs() <= 0.5 && side.abs() < 2e-3, "{dt} {side}");
        let (k4, dt4, side4) = run(jumps, 10.0 * thr, false).unwrap();
        assert_eq!(k4, 54);
        assert!(dt4.abs() <= 0.5 && side4.abs() < 2e-3, "{dt4} {side4}");
        assert_eq!(
            run(cfg, 8.75, false).unwrap().0,
            54,
            "not told to expect a jump"
        );
        assert_eq!(run(jumps, 100.0, true), None, "a spike");
    }

    /// With `early_ramp_starts` (fuse mode's plan), a ramp breakaway (μs = μ) whose second
    /// sample above the threshold is at least 20 thresholds is confirmed there, not at its
    /// fourth, its time as good (the ramp's fit over two samples: within 0.01 of a sample here,
    /// 0.03 over four, whose curvature biases the ramp's fit more) and its sliding side a
    /// sample later (the parabola through its first three at the start found: zero to the
    /// slope times the time's error, 0.02 m/s²; 0.06 over four). At 1 kHz the default scene's smooth
    /// starts reach 1.7 and 3.8 m/s² at their first two samples (threshold 0.042): the max
    /// error of fuse mode there went 1.91 → 1.45 % of the peak. A slower ramp (10 kHz's) waits
    /// for the fourth sample; so does a ramp without `early_ramp_starts` (predict mode's plan);
    /// a lone spike is no slip start.
    #[test]
    fn a_strong_ramp_breakaway_is_confirmed_at_its_second_sample_in_fuse_mode() {
        let run = |cfg: PhaseDetectorConfig, slope: f64, spike: bool| {
            let mut d = PhaseDetector::<64>::new(cfg).unwrap();
            let tb = 50.4;
            let signal = |u: f64| slope * u - 0.02 * u * u;
            let (mut found, mut side) = (None, None);
            for k in 0..120u64 {
                let u = k as f64 - tb;
                let a = match (spike, k == 51, u > 0.0) {
                    (true, true, _) => 2.0 * slope,
                    (false, _, true) => signal(u),
                    _ => 0.0,
                };
                let pending = d.side_pending();
                let event = d.process(a as f32);
                if pending {
                    side = Some(d.late_slip_start_accel() as f64);
                }
                if let Some(e) = event {
                    assert!(found.is_none(), "{e:?} at {k}");
                    found = Some((k, k as f64 - e.age_samples() as f64 - tb));
                    if !d.side_pending() {
                        side = Some(d.slip_start_accel() as f64);
                    }
                }
            }
            found.map(|(k, dt)| (k, dt, side.unwrap_or(f64::NAN)))
        };
        let run_jump = |cfg: PhaseDetectorConfig, jump: f64| {
            let mut d = PhaseDetector::<64>::new(cfg).unwrap();
            (0..120u64)
                .find(|&k| {
                    let u = k as f64 - 50.4;
                    let a = if u > 0.0 { jump + 0.3 * u } else { 0.0 };
                    d.process(a as f32).is_some()
                })
                .unwrap_or(0)
        };
        let cfg = PhaseDetectorConfig::for_noise(5e-3).unwrap();
        let early = cfg.with_early_ramp_starts(true);
        // First sample above the threshold: 51 (0.6 of a sample into the ramp).
        let (k, dt, side) = run(early, 2.0, false).unwrap();
        let (k4, dt4, side4) = run(cfg, 2.0, false).unwrap();
        // Measured: −0.0096 of a sample and −0.019 m/s² (early), −0.031 and −0.062 (fourth).
        assert_eq!(k, 52);
        assert!(dt.abs() < 0.012 && side.abs() < 0.025, "{dt} {side}");
        assert_eq!(k4, 54, "predict mode's plan");
        assert!(dt4.abs() < 0.035 && side4.abs() < 0.07, "{dt4} {side4}");
        assert_eq!(run(early, 0.2, false).unwrap().0, 54, "a slow ramp");
        assert_eq!(run(early, 2.0, true), None, "a spike");
        // A first sample below 20 thresholds (0.59 m/s², the second 1.55): a ramp's is
        // confirmed at its second, a jump breakaway keeps its own rule (both samples strong).
        assert_eq!(run(early, 1.0, false).unwrap().0, 52);
        let jumps = early.with_friction(0.25, 0.2);
        assert_eq!(
            run(jumps, 1.0, false).unwrap().0,
            54,
            "a jump's first below 20"
        );
        // A jump not expected (μs told equal to μ): its second sample about its first.
        assert_eq!(run_jump(early, 8.75), 54, "an unexpected jump");
        assert_eq!(run_jump(jumps, 8.75), 52, "an expected one");
    }
}
