//! Steady-state peaks of |ü1| under harmonic input: of the exact stick-slip truth (run until its
//! transient has decayed, with a convergence check and the slip events per period) and of RDM (the
//! paper's alternating train) by the exact recursion.

use crate::table_motion::TableMotion;
use crate::truth::{simulate, EventKind, Truth, TruthInput};
use anyhow::{anyhow, Result};
use serde::Serialize;
use ssvr_core::recursion::Estimator64;
use ssvr_core::Structure;

/// Steady state of a truth under harmonic input: peak |ü1| over the last `cycles` periods, the same
/// over the `cycles` before (a convergence check), and the slip events per period in the last ones.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct SteadyPeak {
    /// Peak |ü1| over the last cycles (m/s²).
    pub peak_m_s2: f64,
    /// Peak over the cycles before (m/s²).
    pub previous_peak_m_s2: f64,
    /// Sticks per period in the last cycles.
    pub sticks_per_cycle: f64,
    /// Slip starts and reversals per period in the last cycles.
    pub slips_per_cycle: f64,
    /// Simulated duration (s).
    pub duration_s: f64,
}

/// The exact stick-slip truth under the harmonic table motion `a0`·sin(2πt/`period`).
pub(super) fn truth_harmonic(
    s: &Structure,
    a0: f64,
    period: f64,
    duration: f64,
    mu_s: f64,
) -> Result<Truth> {
    let table = TableMotion::Harmonic {
        amplitude_m_s2: a0,
        period_s: period,
    };
    simulate(&TruthInput::new(s, &table, duration).with_static_friction(mu_s))
        .map_err(|e| anyhow!("truth simulation: {e}"))
}

/// Peak |ü1| of the truth over [t0, t1], by dense sampling and a golden-section refinement.
fn truth_peak(truth: &Truth, t0: f64, t1: f64, points: usize) -> f64 {
    let h = (t1 - t0) / points as f64;
    let f = |t: f64| truth.sample(t).map_or(0.0, |s| s.top_accel_m_s2.abs());
    let mut cur = truth.sampler();
    let (mut best_t, mut best) = (t0, 0.0f64);
    for i in 0..=points {
        let t = t0 + i as f64 * h;
        let v = cur.sample(t).map_or(0.0, |s| s.top_accel_m_s2.abs());
        if v > best {
            best = v;
            best_t = t;
        }
    }
    let (mut lo, mut hi) = ((best_t - h).max(t0), (best_t + h).min(t1));
    let g = 0.618_033_988_749_895;
    for _ in 0..60 {
        let x1 = hi - g * (hi - lo);
        let x2 = lo + g * (hi - lo);
        if f(x1) > f(x2) {
            hi = x2;
        } else {
            lo = x1;
        }
    }
    best.max(f(0.5 * (lo + hi)))
}

/// Duration for the truth to reach its steady state: the slowest decay is the fixed-base ξp
/// (stuck phases) or the sliding drift's slow rate; 25 time constants, at least 60 periods.
fn settle_duration(s: &Structure, period: f64, quick: bool) -> f64 {
    let rate = (s.xi() * s.p()).min(s.slow_rate()).max(1e-3);
    let d = (25.0 / rate).max(60.0 * period);
    let d = d.min(if quick { 40.0 } else { 200.0 });
    (d / period).ceil() * period
}

/// The truth's steady state under harmonic input (see [`SteadyPeak`]).
pub(super) fn steady_peak(s: &Structure, a0: f64, period: f64, quick: bool) -> Result<SteadyPeak> {
    let duration = settle_duration(s, period, quick) + 2.0 * STEADY_CYCLES * period;
    let truth = truth_harmonic(s, a0, period, duration, s.mu())?;
    Ok(steady_of_truth(&truth, period))
}

/// Periods over which a steady-state peak is taken (and, before them, its convergence check).
pub const STEADY_CYCLES: f64 = 5.0;

/// The steady state of a truth under harmonic input of period `period` (see [`SteadyPeak`]): peak
/// |ü1| over the last [`STEADY_CYCLES`] periods of its duration (dense sampling and a
/// golden-section refinement), the same over the periods before, and the events per period.
pub fn steady_of_truth(truth: &Truth, period: f64) -> SteadyPeak {
    let cycles = STEADY_CYCLES;
    let duration = truth.duration_s();
    let t1 = duration;
    let t0 = t1 - cycles * period;
    let tp = t0 - cycles * period;
    let pts = 4000 * cycles as usize;
    let peak = truth_peak(truth, t0, t1, pts);
    let prev = truth_peak(truth, tp, t0, pts);
    let (mut sticks, mut slips) = (0usize, 0usize);
    for e in truth.events().iter().filter(|e| e.time_s >= t0) {
        match e.kind {
            EventKind::Stick => sticks += 1,
            _ => slips += 1,
        }
    }
    SteadyPeak {
        peak_m_s2: peak,
        previous_peak_m_s2: prev,
        sticks_per_cycle: sticks as f64 / cycles,
        slips_per_cycle: slips as f64 / cycles,
        duration_s: duration,
    }
}

/// Steady-state peak |ü1| / gμ of RDM (the paper's alternating train every T/2) by the exact
/// recursion at `per_period` samples per period (even), run until the transient has decayed.
pub fn rdm_steady_peak_gmu(s: &Structure, period: f64, per_period: u64) -> Result<f64> {
    let per_period = per_period.max(2) & !1;
    let rate = per_period as f64 / period;
    let settle = (20.0 / s.slow_rate().max(1e-6)).max(10.0 * period);
    let periods = ((settle / period).ceil() as u64 + 1).min(20_000_000 / per_period + 2);
    let mut est = Estimator64::new(s, rate).map_err(|e| anyhow!("estimator: {e}"))?;
    let half = per_period / 2;
    let total = periods * per_period;
    let mut peak = 0.0f64;
    let mut level = 1.0;
    for k in 0..total {
        if k % half == 0 {
            est.push_reversal(level, 0.0)
                .map_err(|e| anyhow!("estimator: {e}"))?;
            level = -level;
        }
        let y = est.update();
        if k >= total - per_period {
            peak = peak.max(y.abs());
        }
    }
    Ok(peak / s.gmu())
}
