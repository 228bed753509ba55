//! The data and computations of `host-sim reproduce` (the command: [`crate::cmd::reproduce`]): the
//! seed paper's results regenerated.
//!
//! * [`table2`]: Table 2, the paper's eight tests beside our TFM, RFM and the truth's steady state.
//! * [`steady`]: steady-state peaks (the truth under harmonic input, RDM by the exact recursion).
//! * [`fig6`], [`fig9`], [`fig10`], [`spectra`] (Fig. 11): the figures' numbers; the figures are
//!   drawn by [`crate::plot::reproduce`].
//! * [`friction`]: beyond the paper, how much its Coulomb prediction misses when the friction is
//!   velocity-dependent.
//! * [`markdown`]: `report.md`, what matches the paper and what differs.
//!
//! Sweeps run in parallel (rayon) with a progress bar (indicatif) on standard error.

pub mod fig10;
pub mod fig6;
pub mod fig9;
pub mod friction;
pub mod markdown;
pub mod spectra;
pub mod steady;
pub mod table2;

use anyhow::{anyhow, Result};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use ssvr_core::{Structure, StructureParams};

pub use fig10::Fig10;
pub use fig6::Fig6;
pub use fig9::Fig9;
pub use friction::{Friction, FrictionCase, FrictionPoint};
pub use spectra::{HarmonicPoint, QuakePoint, Spectra};
pub use steady::{rdm_steady_peak_gmu, steady_of_truth, SteadyPeak};
pub use table2::{Table2Result, Table2Row, TABLE2};

/// The paper's gravity (980 gal).
pub const PAPER_G: f64 = 9.80;

/// How the sweeps run.
#[derive(Debug, Clone, Copy)]
pub struct Sweep {
    /// Fewer sweep points and shorter runs.
    pub quick: bool,
    /// Show progress bars.
    pub progress: bool,
}

/// Everything `reproduce` computed (also written as `results.json`).
#[derive(Debug, Clone, Serialize)]
pub struct Results {
    /// Table 2.
    pub table2: Vec<Table2Result>,
    /// Fig. 6.
    pub fig6: Fig6,
    /// Fig. 9.
    pub fig9: Fig9,
    /// Fig. 10.
    pub fig10: Fig10,
    /// Fig. 11.
    pub spectra: Spectra,
    /// Velocity-dependent friction against the paper's Coulomb prediction.
    pub friction: Friction,
    /// Seconds per part.
    pub seconds: Vec<(String, f64)>,
    /// `--quick`.
    pub quick: bool,
}

/// A structure from the paper's parameters (natural period instead of frequency).
fn structure(
    m1: f64,
    m2: f64,
    natural_period_s: f64,
    xi: f64,
    mu: f64,
    g: f64,
) -> Result<Structure> {
    Structure::new(StructureParams {
        m1_kg: m1,
        m2_kg: m2,
        natural_frequency_hz: 1.0 / natural_period_s,
        damping_ratio: xi,
        friction_coefficient: mu,
        gravity_m_s2: g,
    })
    .map_err(|e| anyhow!("{e}"))
}

/// A progress bar on standard error (hidden without `progress`).
fn bar(sweep: Sweep, len: usize, what: &str) -> ProgressBar {
    if !sweep.progress {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(len as u64);
    if let Ok(style) = ProgressStyle::with_template(
        "{msg:<28} [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta})",
    ) {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(what.to_string());
    pb
}
