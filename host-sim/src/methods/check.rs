//! The check of the recursion against the closed form over every sample of a scene (a dense subset
//! for very long runs).

use super::recursion::{rdm_train, AnyRecursion};
use super::Precision;
use crate::scene::Scene;
use anyhow::{Context, Result};
use serde::Serialize;
use ssvr_core::closed_form::duhamel::DuhamelClosedForm;

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
    use super::super::{trace, TraceMethod, TraceOptions};
    use super::*;
    use crate::scene::{Input, Reversals};

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
