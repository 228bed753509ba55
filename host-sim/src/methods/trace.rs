//! The CSV trace `t_s,top_accel_m_s2` of ü1 at a scene's samples by one method: the RDM closed
//! form, the RDM recursion, TFM or RFM.

use super::peak::{check_harmonics, fourier, harmonic};
use super::recursion::{rdm_train, AnyRecursion};
use super::{PeakMethod, Precision, TraceMethod};
use crate::scene::Scene;
use anyhow::{anyhow, bail, Result};
use ssvr_core::closed_form::duhamel::DuhamelClosedForm;
use std::io::Write;

/// Options of [`trace`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TraceOptions {
    /// The method.
    pub method: TraceMethod,
    /// Precision of `rdm-recursion` (the other methods run in f64).
    pub precision: Precision,
    /// Harmonics of TFM/RFM (None: the converged count of the peak).
    pub harmonics: Option<u32>,
    /// Output every `stride`-th sample (≥ 1).
    pub stride: u64,
}

/// Write the CSV trace `t_s,top_accel_m_s2` of the scene's samples k = 0, stride, 2·stride, … to
/// `out` (values in shortest round-trip f64 form). The recursion runs over every sample.
pub fn trace(scene: &Scene, opts: TraceOptions, out: &mut dyn Write) -> Result<()> {
    if opts.stride == 0 {
        bail!("--stride 0 is out of range: expected >= 1");
    }
    check_harmonics(opts.harmonics)?;
    let io = |e: std::io::Error| anyhow::Error::new(e).context("writing the trace");
    writeln!(out, "t_s,top_accel_m_s2").map_err(io)?;
    let n = scene.samples;
    let mut row =
        |k: u64, y: f64| -> Result<()> { writeln!(out, "{},{}", scene.time(k), y).map_err(io) };
    match opts.method {
        TraceMethod::RdmClosed => {
            let train = rdm_train(scene, "trace --method rdm-closed")?;
            train
                .validate()
                .map_err(|e| anyhow!("invalid reversal train: {e}"))?;
            let cf = DuhamelClosedForm::new(&scene.structure);
            let mut k = 0;
            while k < n {
                row(k, cf.accel(&train, scene.time(k)))?;
                k = k.saturating_add(opts.stride);
            }
        }
        TraceMethod::RdmRecursion => {
            let train = rdm_train(scene, "trace --method rdm-recursion")?;
            let mut rec =
                AnyRecursion::new(opts.precision, &scene.structure, scene.rate_hz, train)?;
            for k in 0..n {
                let y = rec.next_sample()?;
                if k % opts.stride == 0 {
                    row(k, y)?;
                }
            }
        }
        TraceMethod::Tfm | TraceMethod::Rfm => {
            let pm = if opts.method == TraceMethod::Tfm {
                PeakMethod::Tfm
            } else {
                PeakMethod::Rfm
            };
            harmonic(scene, &format!("trace --method {}", opts.method.name()))?;
            let (tfm, response) = fourier(scene, pm)?;
            let eval: Box<dyn Fn(f64) -> f64> = match response {
                Some(r) => {
                    let h = match opts.harmonics {
                        Some(h) => h,
                        None => r.converged_peak().1,
                    };
                    Box::new(move |t| r.accel(t, h))
                }
                None => Box::new(move |t| tfm.accel(t, 1)),
            };
            let mut k = 0;
            while k < n {
                row(k, eval(scene.time(k)))?;
                k = k.saturating_add(opts.stride);
            }
        }
    }
    Ok(())
}
