//! The exact state at one time ([`TruthSample`]), read from a [`Truth`] one time at a time
//! ([`Truth::sample`]) or by a cursor for increasing times ([`Sampler`]).

use super::phase::Phase;
use super::response::Truth;

/// The exact state at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthSample {
    /// Time (s).
    pub time_s: f64,
    /// Contact state (the state just after `time_s` if an event happens exactly then).
    pub phase: Phase,
    /// Table acceleration ü_g (m/s²; right limit at a record sample).
    pub table_accel_m_s2: f64,
    /// Absolute acceleration of the base ü2 (m/s²).
    pub base_accel_m_s2: f64,
    /// Absolute acceleration of the top mass ü1 = −(2pξ δ' + p² δ) (m/s²).
    pub top_accel_m_s2: f64,
    /// Slip x2: displacement of the base relative to the table (m).
    pub slip_m: f64,
    /// Slip velocity ẋ2 (m/s).
    pub slip_velocity_m_s: f64,
    /// Storey drift δ = x1 − x2 (m).
    pub rel_disp_m: f64,
    /// Drift velocity δ' (m/s).
    pub rel_vel_m_s: f64,
    /// Friction on the base F/F0, F0 = μ(m1+m2)g: −1 sliding positive, +1 sliding negative, and while
    /// stuck the holding force m1 ü1 + m2 ü_g over F0 (within [−μs/μ, μs/μ]).
    pub friction_level: f64,
}

/// The state at rest (before the motion starts).
pub(super) fn rest_sample(t: f64) -> TruthSample {
    TruthSample {
        time_s: t,
        phase: Phase::Stuck,
        table_accel_m_s2: 0.0,
        base_accel_m_s2: 0.0,
        top_accel_m_s2: 0.0,
        slip_m: 0.0,
        slip_velocity_m_s: 0.0,
        rel_disp_m: 0.0,
        rel_vel_m_s: 0.0,
        friction_level: 0.0,
    }
}

impl Truth {
    /// The exact state at time t: `None` for NaN or t past the duration (times within a relative
    /// 1e-12 of the end, e.g. `k·dt` rounded up, are accepted); the rest state for t < 0.
    /// For many increasing times use [`Truth::sampler`].
    pub fn sample(&self, t: f64) -> Option<TruthSample> {
        if !self.covers(t) {
            return None;
        }
        if t < 0.0 {
            return Some(rest_sample(t));
        }
        let i = self.pieces.partition_point(|p| p.t0 <= t).saturating_sub(1);
        Some(self.sample_in(i, t))
    }

    pub(super) fn covers(&self, t: f64) -> bool {
        t <= self.duration_s * (1.0 + 1e-12)
    }

    /// A cursor evaluating samples in O(1) for non-decreasing times (any order works).
    pub fn sampler(&self) -> Sampler<'_> {
        Sampler {
            truth: self,
            index: 0,
        }
    }

    pub(super) fn sample_in(&self, i: usize, t: f64) -> TruthSample {
        let piece = &self.pieces[i];
        let tau = (t - piece.t0).max(0.0);
        let e = piece.eval(&self.model, tau);
        TruthSample {
            time_s: t,
            phase: piece.phase,
            table_accel_m_s2: e.ug,
            base_accel_m_s2: match piece.phase {
                Phase::Stuck => e.ug,
                _ => (e.friction - self.model.m1 * e.top) / self.model.m2,
            },
            top_accel_m_s2: e.top,
            slip_m: e.slip,
            slip_velocity_m_s: e.slip_vel,
            rel_disp_m: e.delta,
            rel_vel_m_s: e.delta_dot,
            friction_level: e.friction / self.model.f0,
        }
    }
}

/// A cursor over a [`Truth`], cheap for non-decreasing times.
#[derive(Debug, Clone)]
pub struct Sampler<'a> {
    truth: &'a Truth,
    index: usize,
}

impl Sampler<'_> {
    /// The exact state at time t (see [`Truth::sample`]).
    pub fn sample(&mut self, t: f64) -> Option<TruthSample> {
        let truth = self.truth;
        if !truth.covers(t) {
            return None;
        }
        if t < 0.0 {
            return Some(rest_sample(t));
        }
        let pieces = &truth.pieces;
        if self.index >= pieces.len() || pieces[self.index].t0 > t {
            self.index = pieces.partition_point(|p| p.t0 <= t).saturating_sub(1);
        }
        while self.index + 1 < pieces.len() && pieces[self.index + 1].t0 <= t {
            self.index += 1;
        }
        Some(truth.sample_in(self.index, t))
    }
}
