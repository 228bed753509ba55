//! The methods run on a scene: steady-state peaks (TFM, RFM), traces of ü1 (RDM closed form, RDM
//! recursion, TFM, RFM) and the check of the recursion against the closed form.

use crate::scene::{Input, Scene};
use anyhow::{anyhow, bail, Context, Result};
use serde::Serialize;
use ssvr_core::closed_form::duhamel::DuhamelClosedForm;
use ssvr_core::closed_form::fourier::{FourierResponse, Tfm};
use ssvr_core::math::{Libm, Real, Transcendentals};
use ssvr_core::recursion::DuhamelRecursion;
use ssvr_core::{ReversalTrain, Structure};
use std::io::Write;

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

fn harmonic(scene: &Scene, what: &str) -> Result<(f64, f64)> {
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
fn fourier(scene: &Scene, method: PeakMethod) -> Result<(Tfm, Option<FourierResponse>)> {
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

fn check_harmonics(h: Option<u32>) -> Result<()> {
    use ssvr_core::closed_form::fourier::MAX_HARMONICS;
    match h {
        Some(h) if h == 0 || h > MAX_HARMONICS => {
            bail!("--harmonics {h} is out of range: expected 1 to {MAX_HARMONICS}")
        }
        _ => Ok(()),
    }
}

/// The estimator driven from a reversal train: before sample k it pushes every reversal j with
/// t_j in (t_{k−1}, t_k] (for k = 0: t_j ≤ 0), age (t_k − t_j)·rate, in chronological order.
pub struct RecursionRun<'a, T: Real, M: Transcendentals<T>, const K: usize> {
    est: DuhamelRecursion<T, M, K>,
    train: ReversalTrain<'a>,
    rate_hz: f64,
    next_reversal: usize,
    k: u64,
}

impl<'a, T: Real, M: Transcendentals<T>, const K: usize> RecursionRun<'a, T, M, K> {
    /// The estimator of `structure` at `rate_hz`, fed from `train`.
    pub fn new(structure: &Structure, rate_hz: f64, train: ReversalTrain<'a>) -> Result<Self> {
        train
            .validate()
            .map_err(|e| anyhow!("invalid reversal train: {e}"))?;
        let est = DuhamelRecursion::<T, M, K>::new(structure, rate_hz)
            .map_err(|e| anyhow!("cannot build the estimator: {e}"))?;
        Ok(Self {
            est,
            train,
            rate_hz,
            next_reversal: 0,
            k: 0,
        })
    }

    /// ü1 (m/s²) at the next sample, widened to f64.
    pub fn next_sample(&mut self) -> Result<f64> {
        let t = self.k as f64 / self.rate_hz;
        while let Some(r) = self.train.get(self.next_reversal) {
            if r.time_s > t {
                break;
            }
            let age = (t - r.time_s) * self.rate_hz;
            self.est
                .push_reversal(T::from_f64(r.level), T::from_f64(age))
                .map_err(|e| {
                    anyhow!(
                        "estimator: reversal #{} at t = {} s (sample {}): {e}",
                        self.next_reversal,
                        r.time_s,
                        self.k
                    )
                })?;
            self.next_reversal += 1;
        }
        self.k += 1;
        Ok(self.est.update().to_f64())
    }

    /// Reversals pushed so far.
    pub fn reversals(&self) -> usize {
        self.next_reversal
    }
}

/// The estimator in either precision (libm transcendentals, the default capacity).
pub enum AnyRecursion<'a> {
    /// f32.
    F32(Box<RecursionRun<'a, f32, Libm, 256>>),
    /// f64.
    F64(Box<RecursionRun<'a, f64, Libm, 256>>),
}

impl<'a> AnyRecursion<'a> {
    /// Build the estimator in `precision`.
    pub fn new(
        precision: Precision,
        structure: &Structure,
        rate_hz: f64,
        train: ReversalTrain<'a>,
    ) -> Result<Self> {
        Ok(match precision {
            Precision::F32 => {
                AnyRecursion::F32(Box::new(RecursionRun::new(structure, rate_hz, train)?))
            }
            Precision::F64 => {
                AnyRecursion::F64(Box::new(RecursionRun::new(structure, rate_hz, train)?))
            }
        })
    }

    /// ü1 (m/s²) at the next sample.
    pub fn next_sample(&mut self) -> Result<f64> {
        match self {
            AnyRecursion::F32(r) => r.next_sample(),
            AnyRecursion::F64(r) => r.next_sample(),
        }
    }

    /// Reversals pushed so far.
    pub fn reversals(&self) -> usize {
        match self {
            AnyRecursion::F32(r) => r.reversals(),
            AnyRecursion::F64(r) => r.reversals(),
        }
    }
}

fn rdm_train<'a>(scene: &'a Scene, what: &str) -> Result<ReversalTrain<'a>> {
    scene.rdm_train().ok_or_else(|| {
        anyhow!(
            "{what} needs a harmonic or reversals scene; scene \"{}\" has kind = \"{}\" (its \
             reversals come from the stick-slip simulation)",
            scene.name,
            scene.input.kind()
        )
    })
}

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

/// Runs longer than this are compared on a dense subset (see [`check`]).
pub const FULL_CHECK_SAMPLES: u64 = 2_000_000;

/// The recursion against the closed form.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckReport {
    /// Scene name.
    pub scene: String,
    /// Precision of the recursion.
    pub precision: Precision,
    /// Samples the recursion ran over.
    pub samples: u64,
    /// Samples compared with the closed form.
    pub compared_samples: u64,
    /// Reversals within the run.
    pub reversals: usize,
    /// Largest |recursion − closed form| / gμ (JSON null if not finite).
    pub max_err_gmu: f64,
    /// RMS of (recursion − closed form) / gμ over the compared samples.
    pub rms_err_gmu: f64,
    /// Time of the largest error (s).
    pub max_err_at_s: f64,
    /// Largest |error| (m/s²).
    pub max_err_m_s2: f64,
    /// gμ (m/s²).
    pub gmu_m_s2: f64,
}

/// Run the estimator over every sample of the scene and compare it with the closed form: at every
/// sample, or for runs over [`FULL_CHECK_SAMPLES`] at every sample within ±3 samples of a
/// reversal, every 7th sample and the last 1000 samples.
pub fn check(scene: &Scene, precision: Precision) -> Result<CheckReport> {
    check_with_limit(scene, precision, FULL_CHECK_SAMPLES)
}

/// [`check`] with the run length above which the dense subset is compared.
pub fn check_with_limit(
    scene: &Scene,
    precision: Precision,
    full_check_samples: u64,
) -> Result<CheckReport> {
    let train = rdm_train(scene, "check")?;
    let mut rec = AnyRecursion::new(precision, &scene.structure, scene.rate_hz, train)
        .with_context(|| format!("scene \"{}\"", scene.name))?;
    let cf = DuhamelClosedForm::new(&scene.structure);
    let gmu = scene.gmu();
    let n = scene.samples;
    let dense = n > full_check_samples;
    let mut near = 0usize; // first reversal with t_j·rate ≥ k − 3
    let (mut max_err, mut max_at, mut sum_sq, mut compared) = (0.0f64, 0.0f64, 0.0f64, 0u64);
    for k in 0..n {
        let y = rec.next_sample()?;
        let compare = !dense || k % 7 == 0 || k + 1000 >= n || {
            let kf = k as f64;
            while train
                .get(near)
                .is_some_and(|r| r.time_s * scene.rate_hz < kf - 3.0)
            {
                near += 1;
            }
            train
                .get(near)
                .is_some_and(|r| r.time_s * scene.rate_hz <= kf + 3.0)
        };
        if !compare {
            continue;
        }
        let t = scene.time(k);
        let err = (y - cf.accel(&train, t)).abs();
        compared += 1;
        sum_sq += err * err;
        if err.is_nan() || err > max_err {
            max_err = if err.is_nan() { f64::INFINITY } else { err };
            max_at = t;
        }
    }
    let rms = if compared > 0 {
        (sum_sq / compared as f64).sqrt()
    } else {
        0.0
    };
    Ok(CheckReport {
        scene: scene.name.clone(),
        precision,
        samples: n,
        compared_samples: compared,
        reversals: rec.reversals(),
        max_err_gmu: max_err / gmu,
        rms_err_gmu: rms / gmu,
        max_err_at_s: max_at,
        max_err_m_s2: max_err,
        gmu_m_s2: gmu,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Reversals;

    fn reversal_scene(times: &[f64]) -> Scene {
        let mut s = Scene::default_scene();
        s.input = Input::Reversals(Reversals::Times {
            times_s: times.to_vec(),
            initial_sign: 1.0,
        });
        s.duration_s = 0.2;
        s.samples = 2000;
        s
    }

    #[test]
    fn dense_subset_of_long_runs() {
        let times = [0.0, 0.05003, 0.1];
        let s = reversal_scene(&times);
        let full = check_with_limit(&s, Precision::F64, u64::MAX).unwrap();
        assert_eq!(full.compared_samples, 2000);
        assert_eq!(full.reversals, 3);
        let dense = check_with_limit(&s, Precision::F64, 100).unwrap();
        let expected = (0..2000u64)
            .filter(|&k| {
                k % 7 == 0
                    || k >= 1000
                    || times.iter().any(|t| (t * 10_000.0 - k as f64).abs() <= 3.0)
            })
            .count() as u64;
        assert_eq!(dense.compared_samples, expected);
        assert!(dense.max_err_gmu <= full.max_err_gmu);
        assert!(full.max_err_gmu < 1e-9, "{full:?}");
    }

    #[test]
    fn recursion_matches_closed_form_on_the_default_scene() {
        let s = Scene::default_scene();
        let r = check(&s, Precision::F64).unwrap();
        assert_eq!(r.samples, 100_000);
        // Reversals at k·T/2 ≤ 9.9999 s: k = 0 ..= 139.
        assert_eq!(r.reversals, 140);
        assert!(r.max_err_gmu < 1e-9, "{r:?}");
        let r32 = check(&s, Precision::F32).unwrap();
        assert!(r32.max_err_gmu < 1e-4, "{r32:?}");
    }

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

    #[test]
    fn record_scenes_have_no_rdm_train() {
        let mut s = Scene::default_scene();
        s.input = Input::Record(crate::scene::Record {
            path: "r.txt".into(),
            units: crate::scene::Units::G,
            scale: 1.0,
            motion: crate::table_motion::TableMotion::None,
        });
        let e = check(&s, Precision::F64).unwrap_err().to_string();
        assert!(e.contains("record"), "{e}");
        let mut out = Vec::new();
        let opts = TraceOptions {
            method: TraceMethod::Tfm,
            precision: Precision::F64,
            harmonics: None,
            stride: 1,
        };
        assert!(trace(&s, opts, &mut out).is_err());
    }
}
