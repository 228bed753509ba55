//! Measuring every method on one bench scene ([`measure_scene`]): the recursion in f32 and f64 with
//! each set of transcendentals, the full and truncated closed forms, RFM and TFM, and the truth;
//! cost as the median of timed runs, errors against the full closed form, the truth and (on
//! `long-train`) a double-double reference.

use super::double_double::dd_undamped;
use super::scenes::{simulate_truth, BenchScene};
use super::table::Row;
use anyhow::{anyhow, Result};
use ssvr_core::closed_form::duhamel::DuhamelClosedForm;
use ssvr_core::closed_form::fourier::{FourierResponse, Tfm};
use ssvr_core::closed_form::truncated::TruncatedClosedForm;
use ssvr_core::math::{F32Poly, Libm, Micromath, Real, Transcendentals};
use ssvr_core::recursion::DuhamelRecursion;
use ssvr_core::{Reversal, ReversalTrain};
use std::time::Instant;

/// Cortex-M4F instructions per steady-state sample of the firmware's f32 recursion
/// (`Estimator32::update()`, the rectangular model), measured under QEMU
/// ([`crate::qemu::measure_instruction_counts`]: the QEMU image built for the rectangular
/// model, SysTick with `-icount shift=0`). The count does not depend on the scene (the firmware
/// times the recursion on its own input), so it is measured once per process and cached. `None`
/// when QEMU is not installed or the image cannot be built or run.
pub fn m4f_instructions_per_sample(scene: &BenchScene) -> Option<f64> {
    static COUNT: std::sync::OnceLock<Option<f64>> = std::sync::OnceLock::new();
    let _ = scene;
    *COUNT.get_or_init(|| {
        if !crate::qemu::image::qemu_available() {
            return None;
        }
        crate::qemu::measure_instruction_counts(crate::model::Model::Rectangular)
            .map(|ic| ic.instructions_per_sample)
            .map_err(|e| eprintln!("bench: no M4F instruction count: {e:#}"))
            .ok()
    })
}

/// Median seconds of `reps` timed runs after one warm-up run.
fn median_secs(reps: usize, mut f: impl FnMut() -> Result<()>) -> Result<f64> {
    f()?;
    let mut t = Vec::with_capacity(reps);
    for _ in 0..reps.max(1) {
        let start = Instant::now();
        f()?;
        t.push(start.elapsed().as_secs_f64());
    }
    t.sort_by(f64::total_cmp);
    Ok(t[t.len() / 2])
}

/// (sample index, level, age in samples) of each push: reversal j is pushed before the first
/// sample k with t_k ≥ t_j (the convention of `RecursionRun`).
fn pushes<T: Real>(train: &[Reversal], rate: f64, samples: u64) -> Vec<(u64, T, T)> {
    let mut out = Vec::with_capacity(train.len());
    for r in train {
        let mut k = (r.time_s * rate).ceil().max(0.0) as u64;
        while (k as f64 / rate) < r.time_s {
            k += 1;
        }
        while k > 0 && ((k - 1) as f64 / rate) >= r.time_s {
            k -= 1;
        }
        if k >= samples {
            break;
        }
        let age = (k as f64 / rate - r.time_s) * rate;
        out.push((k, T::from_f64(r.level), T::from_f64(age)));
    }
    out
}

/// Run the estimator over every sample into `out`.
fn run_recursion<T: Real, M: Transcendentals<T> + Clone>(
    est0: &DuhamelRecursion<T, M, 256>,
    pushes: &[(u64, T, T)],
    out: &mut [T],
) -> Result<()> {
    let mut est = est0.clone();
    let mut p = 0;
    for (k, y) in out.iter_mut().enumerate() {
        while let Some(&(kk, level, age)) = pushes.get(p) {
            if kk != k as u64 {
                break;
            }
            est.push_reversal(level, age)
                .map_err(|e| anyhow!("estimator: {e}"))?;
            p += 1;
        }
        *y = est.update();
    }
    Ok(())
}

/// Run the truncated closed form at `times` into `out`, pushing the train's reversals as they pass.
fn run_truncated<const K: usize>(
    tc0: &TruncatedClosedForm<K>,
    train: &[Reversal],
    times: &[f64],
    out: &mut [f64],
) -> Result<()> {
    let mut tc = tc0.clone();
    let mut next = 0;
    for (&t, y) in times.iter().zip(out.iter_mut()) {
        while let Some(r) = train.get(next) {
            if r.time_s > t {
                break;
            }
            tc.push_reversal(r.time_s, r.level)
                .map_err(|e| anyhow!("truncated closed form: {e}"))?;
            next += 1;
        }
        *y = tc.accel(t);
    }
    Ok(())
}

/// (max, rms) of |y − reference| / gμ.
fn errors(y: &[f64], reference: &[f64], gmu: f64) -> (f64, f64) {
    let (mut max, mut sq) = (0.0f64, 0.0f64);
    for (a, b) in y.iter().zip(reference) {
        let e = (a - b).abs() / gmu;
        let e = if e.is_nan() { f64::INFINITY } else { e };
        max = max.max(e);
        sq += e * e;
    }
    (max, (sq / y.len().max(1) as f64).sqrt())
}

/// Context of one scene's measurements.
struct Ctx<'a> {
    sc: &'a BenchScene,
    reps: usize,
    times_all: Vec<f64>,
    times_eval: Vec<f64>,
    reference: Vec<f64>,
    truth_ref: Option<Vec<f64>>,
    dd_ref: Option<Vec<f64>>,
    rows: Vec<Row>,
    progress: bool,
}

impl Ctx<'_> {
    /// Record a row from outputs at the eval samples.
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        method: &str,
        precision: &str,
        setting: &str,
        ns: f64,
        y_eval: &[f64],
        timed: u64,
        m4f: Option<f64>,
    ) {
        let gmu = self.sc.structure.gmu();
        let (max, rms) = errors(y_eval, &self.reference, gmu);
        let vs_truth = self.truth_ref.as_ref().map(|r| errors(y_eval, r, gmu));
        let vs_dd = self.dd_ref.as_ref().map(|r| errors(y_eval, r, gmu).0);
        if self.progress {
            eprintln!(
                "bench: {:<10} {:<13} {:<4} {:<24} {:>12.3} ns/sample  max err {:.2e} gμ{}",
                self.sc.id,
                method,
                precision,
                setting,
                ns,
                max,
                vs_truth.map_or(String::new(), |(m, _)| format!(", vs truth {m:.2e} gμ"))
            );
        }
        self.rows.push(Row {
            method: method.into(),
            precision: precision.into(),
            setting: setting.into(),
            scene: self.sc.id.into(),
            ns_per_sample: ns,
            max_err_gmu: max,
            rms_err_gmu: rms,
            m4f_instructions_per_sample: m4f,
            max_err_vs_truth_gmu: vs_truth.map(|e| e.0),
            rms_err_vs_truth_gmu: vs_truth.map(|e| e.1),
            max_err_vs_dd_gmu: vs_dd,
            samples: self.sc.samples,
            timed_samples: timed,
            compared_samples: y_eval.len() as u64,
        });
    }

    fn recursion<T: Real, M: Transcendentals<T> + Clone>(
        &mut self,
        precision: &str,
        setting: &str,
        m4f: Option<f64>,
    ) -> Result<()> {
        let sc = self.sc;
        let est = DuhamelRecursion::<T, M, 256>::new(&sc.structure, sc.rate_hz)
            .map_err(|e| anyhow!("estimator: {e}"))?;
        let p = pushes::<T>(&sc.train, sc.rate_hz, sc.samples);
        let mut out = vec![T::ZERO; sc.samples as usize];
        let secs = median_secs(self.reps, || run_recursion(&est, &p, &mut out))?;
        let y: Vec<f64> = sc.eval.iter().map(|&k| out[k as usize].to_f64()).collect();
        drop(out);
        let ns = secs * 1e9 / sc.samples as f64;
        self.push("rdm-recursion", precision, setting, ns, &y, sc.samples, m4f);
        Ok(())
    }

    /// Times of the closed-form methods' timed runs.
    fn cf_times(&self) -> &[f64] {
        if self.sc.closed_form_on_eval_only {
            &self.times_eval
        } else {
            &self.times_all
        }
    }

    /// Pick the eval samples from outputs at `cf_times`.
    fn cf_pick(&self, out: &[f64]) -> Vec<f64> {
        if self.sc.closed_form_on_eval_only {
            out.to_vec()
        } else {
            self.sc.eval.iter().map(|&k| out[k as usize]).collect()
        }
    }

    fn closed(&mut self) -> Result<()> {
        let sc = self.sc;
        let cf = DuhamelClosedForm::new(&sc.structure);
        let train = ReversalTrain::Explicit(&sc.train);
        let times = self.cf_times().to_vec();
        let mut out = vec![0.0; times.len()];
        let secs = median_secs(self.reps, || {
            for (y, &t) in out.iter_mut().zip(&times) {
                *y = cf.accel(&train, t);
            }
            Ok(())
        })?;
        let y = self.cf_pick(&out);
        let ns = secs * 1e9 / times.len() as f64;
        self.push(
            "rdm-closed",
            "f64",
            "full sum",
            ns,
            &y,
            times.len() as u64,
            None,
        );
        Ok(())
    }

    fn truncated<const K: usize>(&mut self) -> Result<()> {
        let sc = self.sc;
        let tc = TruncatedClosedForm::<K>::new(&sc.structure);
        let times = self.cf_times().to_vec();
        let mut out = vec![0.0; times.len()];
        let secs = median_secs(self.reps, || {
            run_truncated(&tc, &sc.train, &times, &mut out)
        })?;
        let y = self.cf_pick(&out);
        let ns = secs * 1e9 / times.len() as f64;
        self.push(
            "rdm-truncated",
            "f64",
            &format!("K={K}"),
            ns,
            &y,
            times.len() as u64,
            None,
        );
        Ok(())
    }

    fn fourier(&mut self, name: &str, response: &FourierResponse, origin: f64) -> Result<()> {
        let times: Vec<f64> = self.times_all.iter().map(|t| t - origin).collect();
        let mut out = vec![0.0; times.len()];
        for h in [1u32, 3, 9, 27, 81] {
            let secs = median_secs(self.reps, || {
                for (y, &t) in out.iter_mut().zip(&times) {
                    *y = response.accel(t, h);
                }
                Ok(())
            })?;
            let y: Vec<f64> = self.sc.eval.iter().map(|&k| out[k as usize]).collect();
            let ns = secs * 1e9 / times.len() as f64;
            self.push(
                name,
                "f64",
                &format!("H={h}"),
                ns,
                &y,
                times.len() as u64,
                None,
            );
        }
        Ok(())
    }

    fn truth(&mut self) -> Result<()> {
        let sc = self.sc;
        let Some((table, mu_s, duration)) = &sc.truth_input else {
            return Ok(());
        };
        let times = self.times_all.clone();
        let mut out = vec![0.0; times.len()];
        let secs = median_secs(self.reps.min(3), || {
            let truth = simulate_truth(&sc.structure, table, *mu_s, *duration)?;
            let mut cur = truth.sampler();
            for (y, &t) in out.iter_mut().zip(&times) {
                *y = cur
                    .sample(t)
                    .map(|s| s.top_accel_m_s2)
                    .ok_or_else(|| anyhow!("truth: no sample at t = {t} s"))?;
            }
            Ok(())
        })?;
        let y: Vec<f64> = sc.eval.iter().map(|&k| out[k as usize]).collect();
        let ns = secs * 1e9 / times.len() as f64;
        self.push(
            "truth",
            "f64",
            "exact stick-slip",
            ns,
            &y,
            times.len() as u64,
            None,
        );
        Ok(())
    }
}

/// Measure every method on one scene: its rows, and notes on the rows skipped.
pub fn measure_scene(
    sc: &BenchScene,
    reps: usize,
    progress: bool,
    notes: &mut Vec<String>,
) -> Result<Vec<Row>> {
    let times_all: Vec<f64> = (0..sc.samples).map(|k| k as f64 / sc.rate_hz).collect();
    let times_eval: Vec<f64> = sc.eval.iter().map(|&k| k as f64 / sc.rate_hz).collect();
    let cf = DuhamelClosedForm::new(&sc.structure);
    let train = ReversalTrain::Explicit(&sc.train);
    train
        .validate()
        .map_err(|e| anyhow!("scene {}: invalid reversal train: {e}", sc.id))?;
    let reference: Vec<f64> = times_eval.iter().map(|&t| cf.accel(&train, t)).collect();
    let truth_ref = sc.truth.as_ref().map(|truth| {
        let mut cur = truth.sampler();
        times_eval
            .iter()
            .map(|&t| cur.sample(t).map_or(f64::NAN, |s| s.top_accel_m_s2))
            .collect::<Vec<f64>>()
    });
    let dd_ref = (sc.id == "long-train").then(|| {
        let n = sc.structure.omega_d();
        let gmu = sc.structure.gmu();
        times_eval
            .iter()
            .map(|&t| dd_undamped(n, gmu, &sc.train, t))
            .collect::<Vec<f64>>()
    });
    let mut cx = Ctx {
        sc,
        reps,
        times_all,
        times_eval,
        reference,
        truth_ref,
        dd_ref,
        rows: Vec::new(),
        progress,
    };
    let m4f = m4f_instructions_per_sample(sc);
    cx.recursion::<f32, Libm>("f32", "libm", None)?;
    cx.recursion::<f32, Micromath>("f32", "micromath", None)?;
    cx.recursion::<f32, F32Poly>("f32", "F32Poly (firmware default)", m4f)?;
    cx.recursion::<f64, Libm>("f64", "libm", None)?;
    cx.closed()?;
    cx.truncated::<4>()?;
    cx.truncated::<8>()?;
    cx.truncated::<16>()?;
    cx.truncated::<32>()?;
    match (sc.harmonic, sc.fourier_origin_s) {
        (Some((a0, period)), Some(origin)) => {
            let tfm = Tfm::new(&sc.structure, a0, period).map_err(|e| anyhow!("{e}"))?;
            match tfm {
                Tfm::Sliding { response, .. } => {
                    let rfm = FourierResponse::rectangular(&sc.structure, period)
                        .map_err(|e| anyhow!("{e}"))?;
                    cx.fourier("rfm", &rfm, origin)?;
                    cx.fourier("tfm", &response, origin)?;
                }
                Tfm::FixedBase(_) => notes.push(format!(
                    "{}: rfm/tfm skipped: the base does not slide (βA0 <= gμ)",
                    sc.id
                )),
            }
        }
        (Some(_), None) => notes.push(format!(
            "{}: rfm/tfm skipped: no friction zero crossing found in the truth's steady state",
            sc.id
        )),
        (None, _) => notes.push(format!(
            "{}: rfm/tfm not applicable (steady-state forms for harmonic input): rows skipped",
            sc.id
        )),
    }
    if sc.truth_input.is_some() {
        cx.truth()?;
    } else {
        notes.push(format!(
            "{}: no truth row: the friction is prescribed, so the full closed form is the exact model (vs-truth columns null); max_err_vs_dd_gmu compares with a double-double evaluation of the undamped sum",
            sc.id
        ));
    }
    Ok(cx.rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pushes_follow_the_recursion_run_convention() {
        let train = [
            Reversal {
                time_s: 0.0,
                level: 1.0,
            },
            Reversal {
                time_s: 0.00025,
                level: -1.0,
            },
            Reversal {
                time_s: 0.00031,
                level: 1.0,
            },
            Reversal {
                time_s: 5.0,
                level: -1.0,
            },
        ];
        let p = pushes::<f64>(&train, 1e4, 100);
        assert_eq!(p.len(), 3);
        assert_eq!((p[0].0, p[0].2), (0, 0.0));
        assert_eq!(p[1].0, 3);
        assert!((p[1].2 - 0.5).abs() < 1e-9);
        assert_eq!(p[2].0, 4);
        assert!((p[2].2 - 0.9).abs() < 1e-9);
    }
}
