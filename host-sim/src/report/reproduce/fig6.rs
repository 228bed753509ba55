//! Fig. 6 (b-d): TFM, RFM and RDM steady-state time histories of the Table 1 specimen on 200 gal
//! at 0.143 s, with the phase-aligned truth beside each.

use super::steady::truth_harmonic;
use super::PAPER_G;
use crate::plot::figure;
use crate::plot::reproduce::fig6_figure;
use crate::truth::EventKind;
use anyhow::{anyhow, Result};
use serde::Serialize;
use ssvr_core::closed_form::duhamel::DuhamelClosedForm;
use ssvr_core::closed_form::fourier::{FourierResponse, Tfm};
use ssvr_core::{ReversalTrain, Structure, StructureParams};
use std::path::Path;

/// Peaks of Fig. 6 (gal).
#[derive(Debug, Clone, Serialize)]
pub struct Fig6 {
    /// TFM steady-state peak.
    pub tfm_gal: f64,
    /// RFM steady-state peak.
    pub rfm_gal: f64,
    /// RDM peak over the plotted window.
    pub rdm_gal: f64,
    /// Truth peak over the plotted window.
    pub truth_gal: f64,
    /// Truth sticks per cycle.
    pub truth_sticks_per_cycle: f64,
    /// Harmonics used for TFM/RFM.
    pub harmonics: u32,
}

/// The Table 1 specimen with gravity `g`.
fn table1_structure(g: f64) -> Result<Structure> {
    Structure::new(StructureParams {
        m1_kg: 29.5,
        m2_kg: 1.75,
        natural_frequency_hz: 7.0,
        damping_ratio: 0.05,
        friction_coefficient: 0.2,
        gravity_m_s2: g,
    })
    .map_err(|e| anyhow!("{e}"))
}

/// Compute Fig. 6 and draw it to `path` (PNG).
pub fn fig6(path: &Path) -> Result<Fig6> {
    let s = table1_structure(PAPER_G)?;
    let (a0, period) = (2.0, 0.143);
    let t_a = 40.0 * period;
    let shown = 3.0 * period;
    let n = 800;
    let ts: Vec<f64> = (0..=n).map(|i| i as f64 * shown / n as f64).collect();
    let (response, _) = match Tfm::new(&s, a0, period).map_err(|e| anyhow!("{e}"))? {
        Tfm::Sliding {
            response,
            alpha_rad,
            ..
        } => (response, alpha_rad),
        Tfm::FixedBase(_) => anyhow::bail!("Fig. 6: the Table 1 specimen does not slide"),
    };
    let (tfm_peak, h) = response.converged_peak();
    let rect = FourierResponse::rectangular(&s, period).map_err(|e| anyhow!("{e}"))?;
    let (rfm_peak, hr) = rect.converged_peak();
    let h = h.max(hr);
    let cf = DuhamelClosedForm::new(&s);
    let train = ReversalTrain::Periodic {
        first_s: 0.0,
        half_period_s: period / 2.0,
        initial_sign: 1.0,
    };
    let truth = truth_harmonic(&s, a0, period, t_a + 6.0 * period, s.mu())?;
    let zc = truth
        .friction_zero_crossing(t_a, period)
        .ok_or_else(|| anyhow!("Fig. 6: no friction zero crossing in the truth"))?;
    let gal = |v: f64| v * 100.0;
    let tfm: Vec<(f64, f64)> = ts
        .iter()
        .map(|&t| (t, gal(response.accel(t_a + t, h))))
        .collect();
    let rfm: Vec<(f64, f64)> = ts
        .iter()
        .map(|&t| (t, gal(rect.accel(t_a + t, h))))
        .collect();
    let rdm: Vec<(f64, f64)> = ts
        .iter()
        .map(|&t| (t, gal(cf.accel(&train, t_a + t))))
        .collect();
    let mut cur = truth.sampler();
    let tr: Vec<(f64, f64)> = ts
        .iter()
        .map(|&t| {
            (
                t,
                gal(cur.sample(zc + t).map_or(f64::NAN, |x| x.top_accel_m_s2)),
            )
        })
        .collect();
    let peak = |v: &[(f64, f64)]| v.iter().fold(0.0f64, |m, p| m.max(p.1.abs()));
    let sticks = truth
        .events()
        .iter()
        .filter(|e| e.time_s >= t_a && e.time_s < t_a + 5.0 * period)
        .filter(|e| matches!(e.kind, EventKind::Stick))
        .count() as f64
        / 5.0;
    let ylim = peak(&tfm).max(peak(&rfm)).max(peak(&rdm)).max(peak(&tr)) * 1.15;
    let fig = fig6_figure(&tfm, &rfm, &rdm, &tr, ylim, shown, h);
    figure::render_png(&fig, path)?;
    Ok(Fig6 {
        tfm_gal: gal(tfm_peak),
        rfm_gal: gal(rfm_peak),
        rdm_gal: peak(&rdm),
        truth_gal: peak(&tr),
        truth_sticks_per_cycle: sticks,
        harmonics: h,
    })
}
