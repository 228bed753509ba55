//! The paper's Table 2 ([`TABLE2`]: eight shake-table tests with the measured, TFM and numerical
//! peaks) and our results for each test ([`table2`]: our TFM, our RFM = the steady state of RDM,
//! and the steady-state peak of the exact stick-slip truth).

use super::steady::{steady_peak, SteadyPeak};
use super::{bar, structure, Sweep, PAPER_G};
use anyhow::{anyhow, Result};
use rayon::prelude::*;
use serde::Serialize;
use ssvr_core::closed_form::fourier::{FourierResponse, Tfm};
use ssvr_core::Structure;

/// One row of the paper's Table 2 (units as printed: s, gal).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Table2Row {
    /// Test number.
    pub no: u32,
    /// Natural period of the specimen (s).
    pub natural_period_s: f64,
    /// m1/m2.
    pub mass_ratio_m1_m2: f64,
    /// ξ.
    pub xi: f64,
    /// μ.
    pub mu: f64,
    /// Input amplitude (gal).
    pub a0_gal: f64,
    /// Input period (s).
    pub period_s: f64,
    /// Measured peak (gal).
    pub test_gal: f64,
    /// The paper's TFM peak (gal).
    pub tfm_gal: f64,
    /// The paper's numerical peak (gal).
    pub num_gal: f64,
}

/// A [`Table2Row`] from the printed columns in order.
#[allow(clippy::too_many_arguments)]
const fn row(
    no: u32,
    natural_period_s: f64,
    mass_ratio_m1_m2: f64,
    xi: f64,
    mu: f64,
    a0_gal: f64,
    period_s: f64,
    test_gal: f64,
    tfm_gal: f64,
    num_gal: f64,
) -> Table2Row {
    Table2Row {
        no,
        natural_period_s,
        mass_ratio_m1_m2,
        xi,
        mu,
        a0_gal,
        period_s,
        test_gal,
        tfm_gal,
        num_gal,
    }
}

/// The paper's Table 2 (also the reference data of the cross-crate tests).
pub const TABLE2: [Table2Row; 8] = [
    row(
        1, 0.13, 1.0, 0.0144, 0.20, 702.0, 0.125, 497.0, 561.0, 566.0,
    ),
    row(2, 0.184, 2.0, 0.016, 0.20, 125.5, 0.2, 381.0, 388.0, 388.0),
    row(3, 0.065, 2.0, 0.012, 0.20, 331.0, 0.1, 496.0, 528.0, 480.0),
    row(4, 0.065, 2.0, 0.012, 0.20, 436.0, 0.1, 597.0, 551.0, 597.0),
    row(5, 0.184, 2.0, 0.016, 0.20, 209.0, 0.2, 380.0, 393.0, 448.0),
    row(6, 0.20, 3.0, 0.016, 0.20, 158.0, 0.2, 381.0, 392.0, 382.0),
    row(7, 0.20, 3.0, 0.016, 0.20, 167.5, 0.2, 397.0, 392.0, 393.0),
    row(8, 0.09, 3.0, 0.016, 0.20, 192.5, 0.143, 430.0, 472.0, 329.0),
];

impl Table2Row {
    /// The row's structure in SI with the paper's g: m2 = 1 kg, m1 = the m1/m2 ratio (only the ratio
    /// matters).
    pub fn structure(&self) -> Result<Structure> {
        structure(
            self.mass_ratio_m1_m2,
            1.0,
            self.natural_period_s,
            self.xi,
            self.mu,
            PAPER_G,
        )
    }
}

/// Our results for one Table 2 test.
#[derive(Debug, Clone, Serialize)]
pub struct Table2Result {
    /// The paper's row.
    pub paper: Table2Row,
    /// Whether the base slides by the TFM criterion βA0 > gμ.
    pub sliding: bool,
    /// Our TFM peak (gal; fixed-base peak when not sliding).
    pub tfm_gal: f64,
    /// Our RFM peak (gal) = the steady-state RDM peak.
    pub rfm_gal: f64,
    /// The exact stick-slip truth's steady state.
    pub truth: SteadyPeak,
    /// Truth peak (gal).
    pub truth_gal: f64,
}

/// Our results for every test of Table 2 (in parallel).
pub fn table2(sweep: Sweep) -> Result<Vec<Table2Result>> {
    let pb = bar(sweep, TABLE2.len(), "Table 2 (truth runs)");
    let out: Result<Vec<Table2Result>> = TABLE2
        .par_iter()
        .map(|r| {
            let s = r.structure()?;
            let a0 = r.a0_gal / 100.0;
            let tfm = Tfm::new(&s, a0, r.period_s).map_err(|e| anyhow!("{e}"))?;
            let (sliding, tfm_peak) = match tfm {
                Tfm::Sliding { response, .. } => (true, response.converged_peak().0),
                Tfm::FixedBase(f) => (false, f.peak_m_s2),
            };
            let rfm = FourierResponse::rectangular(&s, r.period_s)
                .map_err(|e| anyhow!("{e}"))?
                .converged_peak()
                .0;
            let truth = steady_peak(&s, a0, r.period_s, sweep.quick)?;
            pb.inc(1);
            Ok(Table2Result {
                paper: *r,
                sliding,
                tfm_gal: tfm_peak * 100.0,
                rfm_gal: rfm * 100.0,
                truth_gal: truth.peak_m_s2 * 100.0,
                truth,
            })
        })
        .collect();
    pb.finish_and_clear();
    out
}
