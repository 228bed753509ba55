//! Fig. 11: sliding response spectra, peak |ü1| against natural period for harmonic input (truth,
//! fixed base, TFM, RFM) and for the El Centro record (truth, fixed base, RDM fed with the truth's
//! friction train).

use super::steady::{rdm_steady_peak_gmu, steady_peak};
use super::{bar, structure, Sweep, PAPER_G};
use crate::plot::figure;
use crate::plot::reproduce::spectra_figure;
use crate::report::bench::elcentro_scene;
use crate::truth::{simulate, TruthInput};
use anyhow::{anyhow, Result};
use rayon::prelude::*;
use serde::Serialize;
use ssvr_core::closed_form::fourier::Tfm;
use ssvr_core::recursion::Estimator64;
use ssvr_core::{Reversal, ReversalTrain, Structure};
use std::path::Path;

/// One point of the harmonic spectrum (m/s²).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct HarmonicPoint {
    /// Natural period T0 (s).
    pub natural_period_s: f64,
    /// Truth steady-state peak.
    pub truth: f64,
    /// Fixed-base steady-state peak (no sliding).
    pub fixed_base: f64,
    /// TFM peak (fixed-base when not sliding).
    pub tfm: f64,
    /// RFM peak (= RDM steady state), when sliding.
    pub rfm: Option<f64>,
    /// Whether the base slides by the TFM criterion.
    pub sliding: bool,
    /// Truth sticks per cycle.
    pub truth_sticks_per_cycle: f64,
}

/// One point of the El Centro spectrum (m/s²).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct QuakePoint {
    /// Natural period T0 (s).
    pub natural_period_s: f64,
    /// Truth peak |ü1| (sliding base).
    pub truth: f64,
    /// Fixed base (the base never slides).
    pub fixed_base: f64,
    /// RDM (recursion) with the truth's friction train (stuck intervals as level 0); None when
    /// the base never slides.
    pub rdm_truth_train: Option<f64>,
    /// Largest |slip| (m).
    pub max_slip_m: f64,
}

/// The spectra.
#[derive(Debug, Clone, Serialize)]
pub struct Spectra {
    /// Harmonic input amplitude (m/s²).
    pub harmonic_a0_m_s2: f64,
    /// Harmonic input period (s).
    pub harmonic_period_s: f64,
    /// Harmonic spectrum.
    pub harmonic: Vec<HarmonicPoint>,
    /// El Centro spectrum.
    pub quake: Vec<QuakePoint>,
    /// gμ (m/s²).
    pub gmu_m_s2: f64,
    /// μs of the El Centro runs.
    pub quake_mu_static: f64,
}

/// Compute both spectra (in parallel) and draw them to `path` (PNG).
pub fn spectra(sweep: Sweep, path: &Path) -> Result<Spectra> {
    let (m1, m2, xi, mu) = (29.5, 1.75, 0.05, 0.2);
    let (a0, period) = (2.0, 0.143);
    let n = if sweep.quick { 8 } else { 80 };
    let t0s: Vec<f64> = (0..n)
        .map(|i| 0.05 * (2.0f64 / 0.05).powf(i as f64 / (n - 1) as f64))
        .collect();
    let quake = elcentro_scene()?;
    let quake_table = quake.table_motion();
    let mu_s = quake.static_friction_coefficient;
    let quake_duration = if sweep.quick { 12.0 } else { 40.0 };

    let pb = bar(sweep, 2 * n, "Fig. 11 spectra (truth runs)");
    let harmonic: Result<Vec<HarmonicPoint>> = t0s
        .par_iter()
        .map(|&t0| {
            let s = structure(m1, m2, t0, xi, mu, PAPER_G)?;
            let tfm = Tfm::new(&s, a0, period).map_err(|e| anyhow!("{e}"))?;
            let (sliding, tfm_peak) = match tfm {
                Tfm::Sliding { response, .. } => (true, response.converged_peak().0),
                Tfm::FixedBase(f) => (false, f.peak_m_s2),
            };
            let rfm = if sliding {
                Some(rdm_steady_peak_gmu(&s, period, 2000)? * s.gmu())
            } else {
                None
            };
            let truth = steady_peak(&s, a0, period, sweep.quick)?;
            pb.inc(1);
            Ok(HarmonicPoint {
                natural_period_s: t0,
                truth: truth.peak_m_s2,
                fixed_base: a0 * s.fixed_base_transmissibility(2.0 * std::f64::consts::PI / period),
                tfm: tfm_peak,
                rfm,
                sliding,
                truth_sticks_per_cycle: truth.sticks_per_cycle,
            })
        })
        .collect();
    let quake_pts: Result<Vec<QuakePoint>> = t0s
        .par_iter()
        .map(|&t0| {
            let s = structure(m1, m2, t0, xi, mu, PAPER_G)?;
            let truth = simulate(
                &TruthInput::new(&s, &quake_table, quake_duration).with_static_friction(mu_s),
            )
            .map_err(|e| anyhow!("truth simulation: {e}"))?;
            // Fixed base: friction far above anything the record can produce.
            let stiff = structure(m1, m2, t0, xi, 10.0, PAPER_G)?;
            let fixed = simulate(&TruthInput::new(&stiff, &quake_table, quake_duration))
                .map_err(|e| anyhow!("truth simulation (fixed base): {e}"))?;
            let train = truth.friction_reversals();
            let rdm = if train.is_empty() {
                None
            } else {
                Some(rdm_peak_with_train(&s, &train, quake_duration)?)
            };
            pb.inc(1);
            Ok(QuakePoint {
                natural_period_s: t0,
                truth: truth.peak_top_accel_m_s2(),
                fixed_base: fixed.peak_top_accel_m_s2(),
                rdm_truth_train: rdm,
                max_slip_m: truth.max_abs_slip_m(),
            })
        })
        .collect();
    pb.finish_and_clear();
    let harmonic = harmonic?;
    let quake_pts = quake_pts?;
    let gmu = PAPER_G * mu;

    let result = Spectra {
        harmonic_a0_m_s2: a0,
        harmonic_period_s: period,
        harmonic,
        quake: quake_pts,
        gmu_m_s2: gmu,
        quake_mu_static: mu_s,
    };
    let fig = spectra_figure(&result, (m1, m2, xi, mu), quake_duration);
    figure::render_png(&fig, path)?;
    Ok(result)
}

/// Peak |ü1| of the RDM recursion (f64) fed with `train`, sampled at 2 kHz over `duration`.
fn rdm_peak_with_train(s: &Structure, train: &[Reversal], duration: f64) -> Result<f64> {
    let rate = 2000.0;
    let mut est = Estimator64::new(s, rate).map_err(|e| anyhow!("estimator: {e}"))?;
    let t = ReversalTrain::Explicit(train);
    let mut feeder = ssvr_core::recursion::TrainFeeder::new(rate);
    let n = (duration * rate) as u64;
    let mut peak = 0.0f64;
    for k in 0..n {
        feeder
            .feed(&t, &mut est, k)
            .map_err(|e| anyhow!("estimator: {e}"))?;
        peak = peak.max(est.update().abs());
    }
    Ok(peak)
}
