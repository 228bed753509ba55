//! The steady-state peak of |ü1| of a harmonic scene by the trapezoid (TFM) or rectangular (RFM)
//! Fourier method, and the Fourier responses the traces of TFM/RFM use.

use super::PeakMethod;
use crate::scene::{Input, Scene};
use anyhow::{anyhow, bail, Result};
use serde::Serialize;
use ssvr_core::closed_form::fourier::{FourierResponse, Tfm};

/// The steady-state peak of |ü1| of a harmonic scene.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeakReport {
    /// Scene name.
    pub scene: String,
    /// "tfm" or "rfm".
    pub method: PeakMethod,
    /// Peak of |ü1| (m/s²); the fixed-base peak when the base does not slide.
    pub peak_m_s2: f64,
    /// The peak in units of gμ.
    pub peak_gmu: f64,
    /// Whether the base slides (βA0 > gμ, the TFM criterion, used for both methods).
    pub sliding: bool,
    /// Ramp phase α (rad): eq (17) for TFM, 0 for RFM; None (JSON null) when not sliding.
    pub alpha_rad: Option<f64>,
    /// β of eq (18).
    pub beta: f64,
    /// Harmonics summed; None (JSON null) when not sliding (the fixed-base peak is exact).
    pub harmonics: Option<u32>,
    /// Whether `harmonics` is the converged count (no `--harmonics` given).
    pub converged: bool,
    /// Input amplitude A0 (m/s²).
    pub amplitude_m_s2: f64,
    /// Input period T (s).
    pub period_s: f64,
    /// gμ (m/s²).
    pub gmu_m_s2: f64,
}

/// (A0, T) of a harmonic scene; `what` names the command in the error of any other scene.
pub(super) fn harmonic(scene: &Scene, what: &str) -> Result<(f64, f64)> {
    match scene.input {
        Input::Harmonic {
            amplitude_m_s2,
            period_s,
        } => Ok((amplitude_m_s2, period_s)),
        ref other => bail!(
            "{what} needs a harmonic scene ([input] kind = \"harmonic\"); scene \"{}\" has kind = \"{}\"",
            scene.name,
            other.kind()
        ),
    }
}

/// The sliding Fourier response of a method, or None when the base does not slide.
pub(super) fn fourier(scene: &Scene, method: PeakMethod) -> Result<(Tfm, Option<FourierResponse>)> {
    let what = match method {
        PeakMethod::Tfm => "tfm",
        PeakMethod::Rfm => "rfm",
    };
    let (a0, period) = harmonic(scene, what)?;
    let s = &scene.structure;
    let tfm = Tfm::new(s, a0, period).map_err(|e| anyhow!("{e}"))?;
    let response = match (&tfm, method) {
        (Tfm::FixedBase(_), _) => None,
        (Tfm::Sliding { response, .. }, PeakMethod::Tfm) => Some(*response),
        (Tfm::Sliding { .. }, PeakMethod::Rfm) => {
            Some(FourierResponse::rectangular(s, period).map_err(|e| anyhow!("{e}"))?)
        }
    };
    Ok((tfm, response))
}

/// The steady-state peak of |ü1| by TFM or RFM (`harmonics` None: the converged count).
pub fn peak(scene: &Scene, method: PeakMethod, harmonics: Option<u32>) -> Result<PeakReport> {
    let (a0, period) = harmonic(
        scene,
        match method {
            PeakMethod::Tfm => "peak --method tfm",
            PeakMethod::Rfm => "peak --method rfm",
        },
    )?;
    check_harmonics(harmonics)?;
    let (tfm, response) = fourier(scene, method)?;
    let gmu = scene.gmu();
    let (peak, sliding, alpha, beta, h) = match (tfm, response) {
        (Tfm::Sliding { beta, .. }, Some(r)) => {
            let (peak, h) = match harmonics {
                Some(h) => (r.peak(h), h),
                None => r.converged_peak(),
            };
            (peak, true, Some(r.alpha()), beta, Some(h))
        }
        (Tfm::FixedBase(f), _) => (f.peak_m_s2, false, None, f.beta, None),
        (Tfm::Sliding { .. }, None) => bail!("internal: sliding without a response"),
    };
    Ok(PeakReport {
        scene: scene.name.clone(),
        method,
        peak_m_s2: peak,
        peak_gmu: peak / gmu,
        sliding,
        alpha_rad: alpha,
        beta,
        harmonics: h,
        converged: harmonics.is_none() && sliding,
        amplitude_m_s2: a0,
        period_s: period,
        gmu_m_s2: gmu,
    })
}

/// A `--harmonics` count within 1 ..= MAX_HARMONICS (or none).
pub(super) fn check_harmonics(h: Option<u32>) -> Result<()> {
    use ssvr_core::closed_form::fourier::MAX_HARMONICS;
    match h {
        Some(h) if h == 0 || h > MAX_HARMONICS => {
            bail!("--harmonics {h} is out of range: expected 1 to {MAX_HARMONICS}")
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peaks_of_the_default_scene() {
        let s = Scene::default_scene();
        let tfm = peak(&s, PeakMethod::Tfm, None).unwrap();
        let rfm = peak(&s, PeakMethod::Rfm, None).unwrap();
        assert!(tfm.sliding && rfm.sliding);
        assert_eq!(rfm.alpha_rad, Some(0.0));
        let alpha = (s.gmu() / (tfm.beta * 2.0)).asin();
        assert!((tfm.alpha_rad.unwrap() - alpha).abs() < 1e-12);
        // A rectangular wave excites more than the trapezoid.
        assert!(rfm.peak_m_s2 > tfm.peak_m_s2 && tfm.peak_m_s2 > s.gmu());
        assert!(peak(&s, PeakMethod::Tfm, Some(0)).is_err());
    }
}
