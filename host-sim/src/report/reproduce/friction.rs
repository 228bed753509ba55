//! Velocity-dependent friction: how much the paper's Coulomb prediction misses when the
//! interface's friction coefficient depends on the sliding speed,
//! μ(v) = μ_fast − (μ_fast − μ_slow)·e^{−a|v|} (μs = μ_slow).
//!
//! The Table 1 specimen on harmonic table motion (the default scene's 2 m/s² at 0.143 s, and a
//! slower 0.3 s input that slides as well): the steady-state peak |ü1| of the exact stick-slip
//! truth for μ_slow/μ_fast = 1 (Coulomb, the paper's model, closed form) down to 0.4 and three
//! rates a, against the Coulomb peak.

use super::steady::{steady_of_truth, SteadyPeak, STEADY_CYCLES};
use super::{bar, Sweep, PAPER_G};
use crate::plot::figure;
use crate::plot::reproduce::friction_figure;
use crate::table_motion::TableMotion;
use crate::truth::{simulate, EventKind, TruthInput};
use anyhow::{anyhow, Result};
use rayon::prelude::*;
use serde::Serialize;
use ssvr_core::{FrictionLaw, Structure, StructureParams};
use std::path::Path;

/// The Table 1 specimen's top mass (kg).
pub const M1_KG: f64 = 29.5;
/// The Table 1 specimen's base mass (kg).
pub const M2_KG: f64 = 1.75;
/// The Table 1 specimen's natural frequency (Hz).
pub const NATURAL_FREQUENCY_HZ: f64 = 7.0;
/// The Table 1 specimen's damping ratio.
pub const DAMPING_RATIO: f64 = 0.05;
/// μ_fast: the friction coefficient at high sliding speed, the paper's Coulomb μ.
pub const MU_FAST: f64 = 0.2;
/// Table motion amplitude (m/s²).
pub const A0_M_S2: f64 = 2.0;
/// Table motion periods (s): the default scene's, and a slower input.
pub const PERIODS_S: [f64; 2] = [0.143, 0.3];
/// Rates a of the velocity dependence (s/m).
pub const RATES_S_M: [f64; 3] = [10.0, 30.0, 100.0];
/// The reference interface: μ_slow/μ_fast and a (s/m).
pub const REFERENCE: (f64, f64) = (0.6, 30.0);

/// The ratios μ_slow/μ_fast of the sweep (1 = Coulomb first).
pub fn mu_ratios(quick: bool) -> Vec<f64> {
    if quick {
        vec![1.0, 0.8, 0.6, 0.4]
    } else {
        vec![1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4]
    }
}

/// Simulated duration (s) before rounding up to whole input periods: long enough for the steady
/// state (the peak ratios of the 4 s and the 10 s runs agree to 1e-13; the peak over the last
/// periods equals the one over the periods before to 4e-9 at 4 s).
pub fn duration_s(quick: bool) -> f64 {
    if quick {
        4.0
    } else {
        10.0
    }
}

/// The Table 1 specimen with the paper's g and μ = μ_fast.
pub fn specimen() -> Result<Structure> {
    Structure::new(StructureParams {
        m1_kg: M1_KG,
        m2_kg: M2_KG,
        natural_frequency_hz: NATURAL_FREQUENCY_HZ,
        damping_ratio: DAMPING_RATIO,
        friction_coefficient: MU_FAST,
        gravity_m_s2: PAPER_G,
    })
    .map_err(|e| anyhow!("{e}"))
}

/// The friction law and μs of a ratio μ_slow/μ_fast = `ratio` at rate `rate_s_m`: Coulomb (the
/// closed-form truth) at ratio 1, else velocity-dependent with μs = μ_slow.
pub fn law(ratio: f64, rate_s_m: f64) -> Result<(FrictionLaw, f64)> {
    if ratio == 1.0 {
        return Ok((FrictionLaw::Coulomb, MU_FAST));
    }
    let mu_slow = ratio * MU_FAST;
    let law =
        FrictionLaw::velocity_dependent(mu_slow, rate_s_m, MU_FAST).map_err(|e| anyhow!("{e}"))?;
    Ok((law, mu_slow))
}

/// One point of the sweep.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct FrictionPoint {
    /// μ_slow/μ_fast (1 = Coulomb).
    pub mu_ratio: f64,
    /// Rate a (s/m).
    pub rate_s_m: f64,
    /// Steady-state peak |ü1| / gμ_fast.
    pub peak_gmu: f64,
    /// Peak over the Coulomb peak (ratio 1) of the same input.
    pub peak_over_coulomb: f64,
    /// Largest |slip| over the run (m; from rest, so it includes the start-up transient's offset).
    pub max_slip_m: f64,
    /// Peak-to-peak slip over the steady-state window (the last periods; m).
    pub steady_slip_p2p_m: f64,
    /// The truth's steady state (m/s², with its convergence check and events per period).
    pub steady: SteadyPeak,
}

/// The sweep for one input period.
#[derive(Debug, Clone, Serialize)]
pub struct FrictionCase {
    /// Input period (s).
    pub period_s: f64,
    /// Simulated duration (s, whole periods).
    pub duration_s: f64,
    /// The Coulomb (paper's) steady-state peak |ü1| / gμ_fast.
    pub coulomb_peak_gmu: f64,
    /// `points[rate][ratio]`, in the order of [`Friction::rates_s_m`] and [`Friction::mu_ratios`]
    /// (the ratio-1 point is the Coulomb truth in every row).
    pub points: Vec<Vec<FrictionPoint>>,
}

/// The velocity-dependent friction sweep.
#[derive(Debug, Clone, Serialize)]
pub struct Friction {
    /// Input amplitude (m/s²).
    pub a0_m_s2: f64,
    /// μ_fast (the structure's and the paper's μ).
    pub mu_fast: f64,
    /// gμ_fast (m/s²).
    pub gmu_m_s2: f64,
    /// Rates a (s/m).
    pub rates_s_m: Vec<f64>,
    /// Ratios μ_slow/μ_fast.
    pub mu_ratios: Vec<f64>,
    /// One case per input period.
    pub cases: Vec<FrictionCase>,
}

impl Friction {
    /// The point at (period index, rate, ratio), if swept.
    pub fn point(&self, case: usize, rate_s_m: f64, mu_ratio: f64) -> Option<&FrictionPoint> {
        let a = self.rates_s_m.iter().position(|&x| x == rate_s_m)?;
        let r = self
            .mu_ratios
            .iter()
            .position(|&x| (x - mu_ratio).abs() < 1e-12)?;
        self.cases.get(case)?.points.get(a)?.get(r)
    }

    /// The point farthest from the Coulomb peak (largest |peak/Coulomb − 1|) and its case index.
    pub fn largest_miss(&self) -> Option<(usize, &FrictionPoint)> {
        self.cases
            .iter()
            .enumerate()
            .flat_map(|(c, case)| case.points.iter().flatten().map(move |p| (c, p)))
            .max_by(|x, y| {
                (x.1.peak_over_coulomb - 1.0)
                    .abs()
                    .total_cmp(&(y.1.peak_over_coulomb - 1.0).abs())
            })
    }
}

/// The steady state, the largest |slip| and the steady-state peak-to-peak slip of the truth under
/// harmonic input with the law ([`law`]) of `ratio` and `rate`.
fn run(
    s: &Structure,
    period: f64,
    duration: f64,
    ratio: f64,
    rate: f64,
) -> Result<(SteadyPeak, f64, f64)> {
    let table = TableMotion::Harmonic {
        amplitude_m_s2: A0_M_S2,
        period_s: period,
    };
    let (law, mu_s) = law(ratio, rate)?;
    let truth = simulate(
        &TruthInput::new(s, &table, duration)
            .with_static_friction(mu_s)
            .with_friction(law),
    )
    .map_err(|e| anyhow!("truth simulation (μ_slow/μ_fast {ratio}, a {rate} s/m): {e}"))?;
    let steady = steady_of_truth(&truth, period);
    // Slip extremes are where the slip velocity vanishes: at sticks and reversals (and the ends).
    let t0 = duration - STEADY_CYCLES * period;
    let mut times = vec![t0, duration];
    times.extend(
        truth
            .events()
            .iter()
            .filter(|e| e.time_s >= t0 && !matches!(e.kind, EventKind::SlipStart { .. }))
            .map(|e| e.time_s),
    );
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for t in times {
        let x = truth
            .sample(t)
            .ok_or_else(|| anyhow!("internal: no truth sample at {t} s"))?
            .slip_m;
        (lo, hi) = (lo.min(x), hi.max(x));
    }
    let out = (steady, truth.max_abs_slip_m(), hi - lo);
    if ![out.0.peak_m_s2, out.0.previous_peak_m_s2, out.1, out.2]
        .iter()
        .all(|x| x.is_finite())
    {
        return Err(anyhow!(
            "truth (μ_slow/μ_fast {ratio}, a {rate} s/m): a peak or slip is not finite"
        ));
    }
    Ok(out)
}

/// Compute the sweep (in parallel) and draw it to `path` (PNG).
pub fn friction(sweep: Sweep, path: &Path) -> Result<Friction> {
    let s = specimen()?;
    let gmu = s.gmu();
    let ratios = mu_ratios(sweep.quick);
    let rates = RATES_S_M.to_vec();
    let durations: Vec<f64> = PERIODS_S
        .iter()
        .map(|&t| (duration_s(sweep.quick) / t).ceil() * t)
        .collect();
    // (period, rate, ratio); the Coulomb point once per period (rate index 0).
    let jobs: Vec<(usize, usize, usize)> = (0..PERIODS_S.len())
        .flat_map(|c| {
            let ratios = &ratios;
            (0..rates.len()).flat_map(move |a| {
                (0..ratios.len())
                    .filter(move |&r| ratios[r] != 1.0 || a == 0)
                    .map(move |r| (c, a, r))
            })
        })
        .collect();
    let pb = bar(sweep, jobs.len(), "friction (truth runs)");
    let vals: Result<Vec<(SteadyPeak, f64, f64)>> = jobs
        .par_iter()
        .map(|&(c, a, r)| {
            let v = run(&s, PERIODS_S[c], durations[c], ratios[r], rates[a]);
            pb.inc(1);
            v
        })
        .collect();
    pb.finish_and_clear();
    let vals = vals?;
    let mut cases = Vec::new();
    for (c, &period) in PERIODS_S.iter().enumerate() {
        let at = |a: usize, r: usize| {
            let a = if ratios[r] == 1.0 { 0 } else { a };
            jobs.iter()
                .position(|&j| j == (c, a, r))
                .map(|i| vals[i])
                .ok_or_else(|| anyhow!("internal: no friction run {c} {a} {r}"))
        };
        let coulomb_r = ratios
            .iter()
            .position(|&x| x == 1.0)
            .ok_or_else(|| anyhow!("internal: no Coulomb ratio"))?;
        let coulomb = at(0, coulomb_r)?.0.peak_m_s2;
        let mut points = Vec::new();
        for (a, &rate) in rates.iter().enumerate() {
            let mut row = Vec::new();
            for (r, &ratio) in ratios.iter().enumerate() {
                let (steady, slip, p2p) = at(a, r)?;
                row.push(FrictionPoint {
                    mu_ratio: ratio,
                    rate_s_m: rate,
                    peak_gmu: steady.peak_m_s2 / gmu,
                    peak_over_coulomb: steady.peak_m_s2 / coulomb,
                    max_slip_m: slip,
                    steady_slip_p2p_m: p2p,
                    steady,
                });
            }
            points.push(row);
        }
        cases.push(FrictionCase {
            period_s: period,
            duration_s: durations[c],
            coulomb_peak_gmu: coulomb / gmu,
            points,
        });
    }
    let result = Friction {
        a0_m_s2: A0_M_S2,
        mu_fast: MU_FAST,
        gmu_m_s2: gmu,
        rates_s_m: rates,
        mu_ratios: ratios,
        cases,
    };
    figure::render_png(&friction_figure(&result), path)?;
    Ok(result)
}
