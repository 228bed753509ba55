//! The methods run on a scene: steady-state peaks (TFM, RFM), traces of ü1 (RDM closed form, RDM
//! recursion, TFM, RFM) and the check of the recursion against the closed form.
//!
//! * `peak`: [`peak()`], the steady-state peak by TFM or RFM.
//! * `recursion`: [`RecursionRun`], [`AnyRecursion`], the estimator driven from a reversal train.
//! * `trace`: [`trace()`], the CSV trace of ü1; `check`: [`check()`], the recursion against the
//!   closed form.
//! * Here: the method and precision choices of the command line.

mod check;
mod peak;
mod recursion;
mod trace;

use serde::Serialize;

pub use check::{check, check_with_limit, CheckReport, FULL_CHECK_SAMPLES};
pub use peak::{peak, PeakReport};
pub use recursion::{AnyRecursion, RecursionRun};
pub use trace::{trace, TraceOptions};

/// Floating-point precision of the recursion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// f32 (the firmware default).
    F32,
    /// f64.
    F64,
}

impl Precision {
    /// "f32" or "f64".
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        }
    }
}

/// Steady-state peak methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PeakMethod {
    /// Trapezoid Fourier method (eq 14-18).
    Tfm,
    /// Rectangular Fourier method (eq 20-22).
    Rfm,
}

/// Methods that produce a trace of ü1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TraceMethod {
    /// The generalised eq (36), full f64 precision.
    RdmClosed,
    /// The estimator (exact O(1) recursion) in the chosen precision.
    RdmRecursion,
    /// Trapezoid Fourier method (harmonic scenes).
    Tfm,
    /// Rectangular Fourier method (harmonic scenes).
    Rfm,
}

impl TraceMethod {
    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            TraceMethod::RdmClosed => "rdm-closed",
            TraceMethod::RdmRecursion => "rdm-recursion",
            TraceMethod::Tfm => "tfm",
            TraceMethod::Rfm => "rfm",
        }
    }
}
