//! Fig. 9: the RDM response when m1 ≫ m2 ((m1+m2)/m2 = 100, μ 0.2, ξ 0.05, p = 2π·5 rad/s,
//! reversals every T/2 = 0.1 s).

use super::{structure, PAPER_G};
use crate::plot::figure;
use crate::plot::reproduce::fig9_figure;
use anyhow::Result;
use serde::Serialize;
use ssvr_core::closed_form::duhamel::DuhamelClosedForm;
use ssvr_core::ReversalTrain;
use std::path::Path;

/// Numbers of Fig. 9.
#[derive(Debug, Clone, Serialize)]
pub struct Fig9 {
    /// M.
    pub mass_ratio: f64,
    /// Mξ².
    pub m_xi_sq: f64,
    /// Damped circular frequency n of the relative motion (rad/s).
    pub n_rad_s: f64,
    /// Decay rate a (1/s).
    pub a_per_s: f64,
    /// Peak |ü1| / gμ in the steady state.
    pub steady_peak_gmu: f64,
}

/// Compute Fig. 9 and draw it to `path` (PNG).
pub fn fig9(path: &Path) -> Result<Fig9> {
    let s = structure(99.0, 1.0, 0.2, 0.05, 0.2, PAPER_G)?;
    let period = 0.2;
    let cf = DuhamelClosedForm::new(&s);
    let train = ReversalTrain::Periodic {
        first_s: 0.0,
        half_period_s: period / 2.0,
        initial_sign: 1.0,
    };
    let gmu = s.gmu();
    let sample = |t0: f64, t1: f64, n: usize| -> Vec<(f64, f64)> {
        (0..=n)
            .map(|i| {
                let t = t0 + (t1 - t0) * i as f64 / n as f64;
                (t, cf.accel(&train, t) / gmu)
            })
            .collect()
    };
    let rect = |t0: f64, t1: f64, n: usize| -> Vec<(f64, f64)> {
        (0..=n)
            .map(|i| {
                let t = t0 + (t1 - t0) * i as f64 / n as f64;
                (t, train.level_at(t))
            })
            .collect()
    };
    let fig = fig9_figure(
        [rect(0.0, 1.0, 4000), sample(0.0, 1.0, 4000)],
        [rect(0.095, 0.16, 2000), sample(0.095, 0.16, 2000)],
    );
    figure::render_png(&fig, path)?;
    let steady = sample(0.8, 1.0, 4000)
        .iter()
        .fold(0.0f64, |m, p| m.max(p.1.abs()));
    Ok(Fig9 {
        mass_ratio: s.mass_ratio(),
        m_xi_sq: s.mass_ratio() * s.xi() * s.xi(),
        n_rad_s: s.omega_d(),
        a_per_s: s.a(),
        steady_peak_gmu: steady,
    })
}
