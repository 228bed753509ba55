//! A slip start's timing ([`PhaseDetector`]'s fit of the ramp or jump model) and its sliding
//! side at the start ([`PhaseDetector::slip_start_accel`]).

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

impl<const N: usize> PhaseDetector<N> {
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
