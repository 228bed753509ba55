//! The result of a simulation, [`Truth`]: its pieces and events, and what is read off them as a
//! whole (peaks, slip, the friction train). Sampling at given times is in [`super::sampler`].

use super::model::Model;
use super::phase::{Event, EventKind};
use super::piece::Piece;
use super::sampler::TruthSample;
use ssvr_core::Reversal;

/// The exact stick-slip response over [0, duration].
#[derive(Debug, Clone)]
pub struct Truth {
    pub(super) model: Model,
    pub(super) pieces: Vec<Piece>,
    pub(super) events: Vec<Event>,
    pub(super) duration_s: f64,
    pub(super) mu_ratio: f64,
    pub(super) peak_top: (f64, f64),
    pub(super) max_abs_slip: f64,
    pub(super) final_sample: TruthSample,
}

impl Truth {
    /// The events in time order.
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    /// Simulated duration (s).
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// μs/μ of the simulation.
    pub fn static_to_kinetic_ratio(&self) -> f64 {
        self.mu_ratio
    }

    /// The first upward zero crossing of the friction F/F0 in [t0, t0 + period) (a 4000-point scan,
    /// then bisection to rounding), e.g. to phase a rectangular friction train with the truth.
    pub fn friction_zero_crossing(&self, t0: f64, period: f64) -> Option<f64> {
        let f = |t: f64| self.sample(t).map(|s| s.friction_level);
        let n = 4000;
        let h = period / n as f64;
        let mut prev = f(t0)?;
        for i in 1..=n {
            let t = t0 + i as f64 * h;
            let v = f(t)?;
            if prev < 0.0 && v >= 0.0 {
                let (mut lo, mut hi) = (t - h, t);
                for _ in 0..80 {
                    let mid = 0.5 * (lo + hi);
                    if f(mid)? < 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return Some(hi);
            }
            prev = v;
        }
        None
    }

    /// Peak |ü1| over [0, duration] (m/s²), located exactly (zeros of the jerk).
    pub fn peak_top_accel_m_s2(&self) -> f64 {
        self.peak_top.0
    }

    /// Time of [`Truth::peak_top_accel_m_s2`] (s).
    pub fn peak_top_accel_time_s(&self) -> f64 {
        self.peak_top.1
    }

    /// Largest |slip| over [0, duration] (m); slip extremes are at stops, so this is exact.
    pub fn max_abs_slip_m(&self) -> f64 {
        self.max_abs_slip
    }

    /// Slip at the end of the simulation (m).
    pub fn final_slip_m(&self) -> f64 {
        self.final_sample.slip_m
    }

    /// The state at the end of the simulation.
    pub fn final_sample(&self) -> TruthSample {
        self.final_sample
    }

    /// Number of intervals of one-directional sliding (breakaways plus reversals).
    pub fn slip_phases(&self) -> usize {
        self.events
            .iter()
            .filter(|e| !matches!(e.kind, EventKind::Stick))
            .count()
    }

    /// The friction train: (time, level) at every change of the friction level F/F0 while sliding:
    /// −1 (sliding positive) or +1 (sliding negative) from a breakaway or reversal on, and 0.0 marking
    /// the start of a stuck interval (the actual holding force is then in [`TruthSample`], not 0).
    /// Times are strictly increasing (events at one instant are merged; the last level wins).
    pub fn friction_train(&self) -> Vec<(f64, f64)> {
        let mut out: Vec<(f64, f64)> = Vec::with_capacity(self.events.len());
        for e in &self.events {
            let level = match e.kind {
                EventKind::SlipStart { direction } => -direction.sign(),
                EventKind::Reversal { new_direction } => -new_direction.sign(),
                EventKind::Stick => 0.0,
            };
            if let Some(last) = out.last_mut() {
                if last.0 == e.time_s {
                    last.1 = level;
                    let n = out.len();
                    if n >= 2 && out[n - 2].1 == level {
                        out.pop();
                    }
                    continue;
                }
                if last.1 == level {
                    continue;
                }
            } else if level == 0.0 {
                continue;
            }
            out.push((e.time_s, level));
        }
        out
    }

    /// [`Truth::friction_train`] as `ssvr_core` reversals, for
    /// `ReversalTrain::Explicit` and the Duhamel closed form. Only a run that slides without stuck
    /// intervals has exactly the rectangular friction the closed form assumes.
    pub fn friction_reversals(&self) -> Vec<Reversal> {
        self.friction_train()
            .into_iter()
            .map(|(time_s, level)| Reversal { time_s, level })
            .collect()
    }
}
