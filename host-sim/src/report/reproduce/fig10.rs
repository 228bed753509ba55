//! Fig. 10: the steady-state RDM peak (units of gμ) against the mass ratio M = (m1+m2)/m2 for ten
//! input periods, one panel per damping ratio, by the exact recursion (cheap: O(1) per sample),
//! cross-checked against the converged RFM.

use super::steady::rdm_steady_peak_gmu;
use super::{bar, structure, Sweep, PAPER_G};
use crate::plot::figure;
use crate::plot::reproduce::fig10_figure;
use anyhow::{anyhow, Result};
use rayon::prelude::*;
use serde::Serialize;
use ssvr_core::closed_form::fourier::FourierResponse;
use std::path::Path;

/// The Fig. 10 sweep.
#[derive(Debug, Clone, Serialize)]
pub struct Fig10 {
    /// Natural period T0 (s).
    pub natural_period_s: f64,
    /// Damping ratios (one panel each).
    pub xis: Vec<f64>,
    /// Input periods T (s).
    pub periods_s: Vec<f64>,
    /// Mass ratios M.
    pub mass_ratios: Vec<f64>,
    /// `peaks[xi][period][M]` (units of gμ).
    pub peaks_gmu: Vec<Vec<Vec<f64>>>,
    /// Largest relative difference from the converged RFM peak at the cross-checked points.
    pub rfm_check_max_rel_diff: f64,
    /// Cross-checked points.
    pub rfm_checks: usize,
    /// Samples per input period of the recursion runs.
    pub samples_per_period: u64,
}

/// Compute the Fig. 10 sweep (in parallel) and draw it to `path` (PNG).
pub fn fig10(sweep: Sweep, path: &Path) -> Result<Fig10> {
    let t0 = 0.2;
    let xis = vec![0.01, 0.02, 0.05, 0.10];
    let periods: Vec<f64> = (1..=10).map(|i| 0.05 * i as f64).collect();
    let nm = if sweep.quick { 8 } else { 120 };
    let ms: Vec<f64> = (0..nm)
        .map(|i| 1.1 * (100.0f64 / 1.1).powf(i as f64 / (nm - 1) as f64))
        .collect();
    let per_period = if sweep.quick { 400 } else { 2000 };
    let jobs: Vec<(usize, usize, usize)> = (0..xis.len())
        .flat_map(|a| (0..periods.len()).flat_map(move |b| (0..nm).map(move |c| (a, b, c))))
        .collect();
    let pb = bar(sweep, jobs.len(), "Fig. 10 (RDM recursion)");
    let vals: Result<Vec<f64>> = jobs
        .par_iter()
        .map(|&(a, b, c)| {
            let s = structure(ms[c] - 1.0, 1.0, t0, xis[a], 0.2, PAPER_G)?;
            let v = rdm_steady_peak_gmu(&s, periods[b], per_period);
            pb.inc(1);
            v
        })
        .collect();
    pb.finish_and_clear();
    let vals = vals?;
    let mut peaks = vec![vec![vec![0.0; nm]; periods.len()]; xis.len()];
    for (&(a, b, c), v) in jobs.iter().zip(vals) {
        peaks[a][b][c] = v;
    }
    // Cross-check a few points against the converged RFM (eq 20 = RDM's steady state).
    let checks: Vec<(usize, usize, usize)> = [(2usize, 3usize), (0, 1), (3, 7)]
        .iter()
        .flat_map(|&(a, b)| [0, nm / 2].into_iter().map(move |c| (a, b, c)))
        .collect();
    let mut max_rel = 0.0f64;
    for &(a, b, c) in &checks {
        let s = structure(ms[c] - 1.0, 1.0, t0, xis[a], 0.2, PAPER_G)?;
        let rfm = FourierResponse::rectangular(&s, periods[b])
            .map_err(|e| anyhow!("{e}"))?
            .converged_peak()
            .0
            / s.gmu();
        max_rel = max_rel.max((rfm - peaks[a][b][c]).abs() / rfm);
    }
    let result = Fig10 {
        natural_period_s: t0,
        xis,
        periods_s: periods,
        mass_ratios: ms,
        peaks_gmu: peaks,
        rfm_check_max_rel_diff: max_rel,
        rfm_checks: checks.len(),
        samples_per_period: per_period,
    };
    figure::render_png(&fig10_figure(&result), path)?;
    Ok(result)
}
