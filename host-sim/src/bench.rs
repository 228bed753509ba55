//! `host-sim bench`: speed against error of every method on three fixed scenes.
//!
//! Scenes (see [`scenes`]):
//!
//! * `harmonic`: the built-in default scene (the paper's Table 1 specimen on 2 m/s² at 0.143 s,
//!   10 s at 10 kHz; `--quick`: 4 s). Errors over the second half (the steady state, so that the
//!   steady-state TFM/RFM can be compared).
//! * `long-train`: the Table 1 specimen made undamped (ξ = 0, so every reversal rings forever and
//!   the full closed form sums every term) under a prescribed alternating friction train every
//!   0.0715 s: 10^4 reversals, 715 s at 10 kHz = 7.15·10^6 samples (`--quick`: 10^3 reversals).
//!   The closed-form methods are timed and compared on 2000 evenly spaced samples (their cost per
//!   sample grows with the number of past reversals; evenly spaced samples give the run average);
//!   the recursion runs over every sample. The friction is prescribed, so there is no stick-slip
//!   truth: the closed form *is* the exact model. As a check of the closed form's own rounding, both
//!   are also compared with a double-double evaluation of the undamped sum.
//! * `earthquake`: `scenes/elcentro.toml` (El Centro 1940 NS on the Table 1 specimen, μ 0.2,
//!   μs 0.25; 32 s at 10 kHz; `--quick`: 12 s).
//!
//! Trains of the RDM methods (recursion, closed form, truncated closed form): on the harmonic scene
//! the paper's train (continuous reciprocating sliding, a reversal every T/2), phase-aligned with the
//! truth: its reversals to +F0 are at the upward zero crossings of the truth's friction force; on the
//! earthquake scene the friction train of the exact stick-slip truth (what the estimator sees from
//! the slip sensor: reversals, breakaways, and sticks as level 0). TFM and RFM are steady-state forms
//! for harmonic input, on the harmonic scene only, with the same phase (t = 0 of their friction
//! wave at the truth's upward zero crossing); they are not applicable to the other scenes (rows
//! skipped). On the harmonic scene RFM converges to the closed form; TFM's difference from it is
//! its trapezoid model.
//!
//! Cost: host nanoseconds per sample, the median of repeated runs after a warm-up run
//! (`std::time::Instant`), including the reversal pushes; for the truth, simulation plus sampling.
//! Error: max and RMS, in units of gμ, against the full f64 closed form (numerical error; for TFM,
//! RFM and the truth this includes their model difference) and against the truth (model error).

use crate::plots::{self, Figure, Marker, Panel, Series, Style};
use crate::scene::{parse_record, Input, Record, Scene, Units};
use crate::table_motion::TableMotion;
use crate::truth::{simulate, Truth, TruthInput};
use anyhow::{anyhow, bail, Context, Result};
use serde::Serialize;
use ssvr_core::closed_form::duhamel::DuhamelClosedForm;
use ssvr_core::closed_form::fourier::{FourierResponse, Tfm};
use ssvr_core::closed_form::truncated::TruncatedClosedForm;
use ssvr_core::math::{F32Poly, Libm, Micromath, Real, Transcendentals};
use ssvr_core::recursion::DuhamelRecursion;
use ssvr_core::{Reversal, ReversalTrain, Structure, StructureParams};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of [`run`].
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// Shorter scenes and fewer repetitions (under a minute).
    pub quick: bool,
    /// Output folder of the figures, `bench.json` and `bench.md`.
    pub out_dir: PathBuf,
    /// Print progress on standard error.
    pub progress: bool,
}

/// One row of the bench: a method with one setting on one scene.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Row {
    /// `rdm-recursion`, `rdm-closed`, `rdm-truncated`, `rfm`, `tfm` or `truth`.
    pub method: String,
    /// `f32` or `f64` (of the per-sample arithmetic).
    pub precision: String,
    /// The setting: transcendentals of the recursion, `K=…` terms, `H=…` harmonics, ….
    pub setting: String,
    /// Scene id: `harmonic`, `long-train` or `earthquake`.
    pub scene: String,
    /// Host nanoseconds per sample (median of the repetitions).
    pub ns_per_sample: f64,
    /// Largest |method − full f64 closed form| / gμ over the compared samples.
    pub max_err_gmu: f64,
    /// RMS of (method − full f64 closed form) / gμ.
    pub rms_err_gmu: f64,
    /// Cortex-M4F instructions per sample under QEMU (null: not measured).
    pub m4f_instructions_per_sample: Option<f64>,
    /// Largest |method − exact stick-slip truth| / gμ (null: no truth for the scene).
    pub max_err_vs_truth_gmu: Option<f64>,
    /// RMS of (method − truth) / gμ (null: no truth for the scene).
    pub rms_err_vs_truth_gmu: Option<f64>,
    /// Largest |method − double-double evaluation of the undamped sum| / gμ (`long-train` only).
    pub max_err_vs_dd_gmu: Option<f64>,
    /// Samples of the scene.
    pub samples: u64,
    /// Samples evaluated per timed run.
    pub timed_samples: u64,
    /// Samples compared.
    pub compared_samples: u64,
}

/// Description of a bench scene (in the JSON report).
#[derive(Debug, Clone, Serialize)]
pub struct SceneInfo {
    /// Scene id.
    pub id: String,
    /// What it is.
    pub description: String,
    /// Samples.
    pub samples: u64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Reversals (friction level changes) of the RDM train.
    pub reversals: usize,
    /// Samples compared.
    pub compared_samples: u64,
    /// gμ (m/s²).
    pub gmu_m_s2: f64,
}

/// The bench report (`--json`).
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The rows.
    pub rows: Vec<Row>,
    /// The scenes.
    pub scenes: Vec<SceneInfo>,
    /// Rows not run and why, and other remarks.
    pub notes: Vec<String>,
    /// Whether `--quick` was given.
    pub quick: bool,
    /// Full closed form ns/sample over firmware-default recursion ns/sample on `long-train`.
    pub long_train_speedup: Option<f64>,
}

/// A bench scene.
pub struct BenchScene {
    /// Id (`harmonic`, `long-train`, `earthquake`).
    pub id: &'static str,
    /// What it is.
    pub description: String,
    /// The structure.
    pub structure: Structure,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Samples t_k = k / rate, k = 0..samples.
    pub samples: u64,
    /// The friction train of the RDM methods.
    pub train: Vec<Reversal>,
    /// Harmonic input (A0, T), for TFM/RFM.
    pub harmonic: Option<(f64, f64)>,
    /// Table motion, static friction and duration of the truth (None: no truth).
    pub truth_input: Option<(TableMotion, f64, f64)>,
    /// The truth.
    pub truth: Option<Truth>,
    /// Sample indices where errors are computed (increasing).
    pub eval: Vec<u64>,
    /// Whether the closed-form methods are timed on `eval` only (else on every sample).
    pub closed_form_on_eval_only: bool,
    /// Time of the upward zero crossing of the truth's friction in the steady state (Fourier phase).
    pub fourier_origin_s: Option<f64>,
}

/// Cortex-M4F instructions per steady-state sample of the firmware's f32 recursion
/// (`Estimator32::update()`, the rectangular model), measured under QEMU
/// ([`crate::qemu_cmd::measure_instruction_counts`]: the QEMU image built for the rectangular
/// model, SysTick with `-icount shift=0`). The count does not depend on the scene (the firmware
/// times the recursion on its own input), so it is measured once per process and cached. `None`
/// when QEMU is not installed or the image cannot be built or run.
pub fn m4f_instructions_per_sample(scene: &BenchScene) -> Option<f64> {
    static COUNT: std::sync::OnceLock<Option<f64>> = std::sync::OnceLock::new();
    let _ = scene;
    *COUNT.get_or_init(|| {
        if !crate::qemu_runner::qemu_available() {
            return None;
        }
        crate::qemu_cmd::measure_instruction_counts(crate::model::Model::Rectangular)
            .map(|ic| ic.instructions_per_sample)
            .map_err(|e| eprintln!("bench: no M4F instruction count: {e:#}"))
            .ok()
    })
}

/// The Table 1 specimen with damping ratio `xi` (g = 9.80665).
fn table1(xi: f64) -> Result<Structure> {
    Structure::new(StructureParams {
        m1_kg: 29.5,
        m2_kg: 1.75,
        natural_frequency_hz: 7.0,
        damping_ratio: xi,
        friction_coefficient: 0.2,
        gravity_m_s2: ssvr_core::structure::STANDARD_GRAVITY,
    })
    .map_err(|e| anyhow!("{e}"))
}

/// The El Centro scene: `scenes/elcentro.toml` from the source tree, or (when the binary runs
/// elsewhere) the same scene built from the embedded record.
pub fn elcentro_scene() -> Result<Scene> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/elcentro.toml");
    if let Ok(s) = Scene::load(&path) {
        return Ok(s);
    }
    const RECORD: &str = include_str!("../scenes/elcentro-1940-ns.txt");
    let rec_path = PathBuf::from("elcentro-1940-ns.txt (embedded)");
    let (times_s, accel_m_s2) =
        parse_record(RECORD, &rec_path, Units::G.factor()).map_err(|e| anyhow!("{e}"))?;
    let mut s = Scene::default_scene();
    s.name = "table 1 specimen, El Centro 1940 NS".into();
    s.duration_s = 32.0;
    s.samples = 320_000;
    s.static_friction_coefficient = 0.25;
    s.input = Input::Record(Record {
        path: rec_path,
        units: Units::G,
        scale: 1.0,
        motion: TableMotion::Record {
            times_s,
            accel_m_s2,
        },
    });
    Ok(s)
}

fn simulate_truth(s: &Structure, table: &TableMotion, mu_s: f64, duration: f64) -> Result<Truth> {
    simulate(&TruthInput::new(s, table, duration).with_static_friction(mu_s))
        .map_err(|e| anyhow!("truth simulation: {e}"))
}

/// The three bench scenes.
pub fn scenes(quick: bool) -> Result<Vec<BenchScene>> {
    let mut out = Vec::new();

    // Harmonic: the default scene.
    let mut sc = Scene::default_scene();
    if quick {
        sc.duration_s = 4.0;
        sc.samples = (sc.duration_s * sc.rate_hz).round() as u64;
    }
    let (a0, period) = match sc.input {
        Input::Harmonic {
            amplitude_m_s2,
            period_s,
        } => (amplitude_m_s2, period_s),
        _ => bail!("internal: the default scene is not harmonic"),
    };
    let table = sc.table_motion();
    let mu_s = sc.static_friction_coefficient;
    let truth = simulate_truth(&sc.structure, &table, mu_s, sc.duration_s)?;
    let half = sc.samples / 2;
    let origin = truth.friction_zero_crossing(sc.time(half), period);
    // The paper's train (continuous reciprocating sliding, reversals every T/2), phase-aligned
    // with the truth: the first reversal to +1 at the truth's upward friction zero crossing mod T.
    let first = origin.map_or(0.0, |t| t.rem_euclid(period));
    let train: Vec<Reversal> = (0..)
        .map(|j| Reversal {
            time_s: first + j as f64 * period / 2.0,
            level: if j % 2 == 0 { 1.0 } else { -1.0 },
        })
        .take_while(|r| r.time_s < sc.duration_s)
        .collect();
    out.push(BenchScene {
        id: "harmonic",
        description: format!(
            "{} on {a0} m/s² at {period} s, {} s at {} Hz; RDM train = the paper's (reversals every T/2) aligned with the truth's upward friction zero crossing (first at {first:.6} s); errors over t >= {} s",
            sc.name,
            sc.duration_s,
            sc.rate_hz,
            sc.time(half)
        ),
        structure: sc.structure,
        rate_hz: sc.rate_hz,
        samples: sc.samples,
        train,
        harmonic: Some((a0, period)),
        truth_input: Some((table, mu_s, sc.duration_s)),
        eval: (half..sc.samples).collect(),
        closed_form_on_eval_only: false,
        fourier_origin_s: origin,
        truth: Some(truth),
    });

    // Long reversal train: undamped, prescribed alternating friction.
    let reversals: usize = if quick { 1_000 } else { 10_000 };
    let h = 0.0715;
    let rate = 10_000.0;
    let samples = (reversals as f64 * h * rate).round() as u64;
    let train: Vec<Reversal> = (0..reversals)
        .map(|j| Reversal {
            time_s: j as f64 * h,
            level: if j % 2 == 0 { 1.0 } else { -1.0 },
        })
        .collect();
    let n_eval: u64 = if quick { 400 } else { 2000 };
    let eval: Vec<u64> = (0..n_eval)
        .map(|i| ((i as f64 + 0.5) * samples as f64 / n_eval as f64) as u64)
        .collect();
    out.push(BenchScene {
        id: "long-train",
        description: format!(
            "table 1 specimen with ξ = 0 (undamped), prescribed alternating friction every {h} s: {reversals} reversals, {} s at {rate} Hz; closed forms timed and all errors on {n_eval} evenly spaced samples",
            samples as f64 / rate
        ),
        structure: table1(0.0)?,
        rate_hz: rate,
        samples,
        train,
        harmonic: None,
        truth_input: None,
        truth: None,
        eval,
        closed_form_on_eval_only: true,
        fourier_origin_s: None,
    });

    // Earthquake: El Centro.
    let mut sc = elcentro_scene()?;
    if quick {
        sc.duration_s = 12.0;
        sc.samples = (sc.duration_s * sc.rate_hz).round() as u64;
    }
    let table = sc.table_motion();
    let mu_s = sc.static_friction_coefficient;
    let truth = simulate_truth(&sc.structure, &table, mu_s, sc.duration_s)?;
    out.push(BenchScene {
        id: "earthquake",
        description: format!(
            "{} (μ {}, μs {}), {} s at {} Hz; RDM train = the truth's friction train (stuck intervals at level 0)",
            sc.name,
            sc.structure.mu(),
            mu_s,
            sc.duration_s,
            sc.rate_hz
        ),
        structure: sc.structure,
        rate_hz: sc.rate_hz,
        samples: sc.samples,
        train: truth.friction_reversals(),
        harmonic: None,
        truth_input: Some((table, mu_s, sc.duration_s)),
        eval: (0..sc.samples).collect(),
        closed_form_on_eval_only: false,
        fourier_origin_s: None,
        truth: Some(truth),
    });
    Ok(out)
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

// ---------------------------------------------------------------------------------------------
// Double-double reference of the undamped sum (long-train only).

fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// ü1(t) of an undamped structure (ecm(τ) = cos nτ) with every term in double-double: the
/// arguments t − t_j and n·(t − t_j) and the reduction mod 2π are carried to ~1e-30 relative, so the
/// only rounding left is that of cos and of the final sum (~1e-16 per term).
fn dd_undamped(n: f64, gmu: f64, train: &[Reversal], t: f64) -> f64 {
    const TWO_PI_HI: f64 = std::f64::consts::TAU;
    const TWO_PI_LO: f64 = 2.449_293_598_294_706_4e-16;
    let last = train.partition_point(|r| r.time_s <= t);
    if last == 0 {
        return 0.0;
    }
    let level = train[last - 1].level;
    let (mut sum, mut comp) = (0.0f64, 0.0f64);
    let mut prev_level = 0.0;
    for r in &train[..last] {
        let jump = r.level - prev_level;
        prev_level = r.level;
        let (th, tl) = two_sum(t, -r.time_s);
        let ph = n * th;
        let pl = n.mul_add(th, -ph) + n * tl;
        let k = (ph / TWO_PI_HI).round();
        let kh = k * TWO_PI_HI;
        let kl = k.mul_add(TWO_PI_HI, -kh);
        let rh = ph - kh; // exact (Sterbenz)
        let rl = pl - kl - k * TWO_PI_LO;
        let (rs, re) = two_sum(rh, rl);
        let c = rs.cos() - rs.sin() * re;
        let term = jump * c;
        let s = sum + term;
        comp += if sum.abs() >= term.abs() {
            (sum - s) + term
        } else {
            (term - s) + sum
        };
        sum = s;
    }
    gmu * (level - (sum + comp))
}

// ---------------------------------------------------------------------------------------------

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

/// Measure every method on one scene.
fn bench_scene(
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

/// Run the bench: measure, write `bench.json`, `bench.md` and the Pareto figures into the output
/// folder, and return the report.
pub fn run(opts: &BenchOptions) -> Result<Report> {
    std::fs::create_dir_all(&opts.out_dir)
        .with_context(|| format!("cannot create {}", opts.out_dir.display()))?;
    let reps = if opts.quick { 3 } else { 9 };
    let t0 = Instant::now();
    let scenes = scenes(opts.quick)?;
    let mut rows = Vec::new();
    let mut notes = Vec::new();
    let mut infos = Vec::new();
    for sc in &scenes {
        rows.extend(bench_scene(sc, reps, opts.progress, &mut notes)?);
        infos.push(SceneInfo {
            id: sc.id.into(),
            description: sc.description.clone(),
            samples: sc.samples,
            rate_hz: sc.rate_hz,
            reversals: sc.train.len(),
            compared_samples: sc.eval.len() as u64,
            gmu_m_s2: sc.structure.gmu(),
        });
    }
    let find = |scene: &str, method: &str, setting: &str| {
        rows.iter()
            .find(|r| r.scene == scene && r.method == method && r.setting.starts_with(setting))
    };
    let long_train_speedup = match (
        find("long-train", "rdm-closed", "full"),
        find("long-train", "rdm-recursion", "F32Poly"),
    ) {
        (Some(c), Some(r)) => Some(c.ns_per_sample / r.ns_per_sample),
        _ => None,
    };
    notes.push(format!(
        "measured in {:.1} s{}",
        t0.elapsed().as_secs_f64(),
        if opts.quick { " (--quick)" } else { "" }
    ));
    let report = Report {
        rows,
        scenes: infos,
        notes,
        quick: opts.quick,
        long_train_speedup,
    };
    let json = serde_json::to_string_pretty(&report).context("serialising the bench report")?;
    let md = markdown(&report);
    let write = |name: &str, text: &str| {
        let p = opts.out_dir.join(name);
        std::fs::write(&p, text).with_context(|| format!("cannot write {}", p.display()))
    };
    write("bench.json", &json)?;
    write("bench.md", &md)?;
    for sc in &scenes {
        let path = opts.out_dir.join(format!("pareto-{}.png", sc.id));
        plots::render_png(&pareto_figure(&report, sc), &path)?;
    }
    Ok(report)
}

fn sci(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:.1e}")
    }
}

fn ns(v: f64) -> String {
    if v >= 1000.0 {
        format!("{:.3e}", v)
    } else if v >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// The markdown tables of a report.
pub fn markdown(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| scene | method | precision | setting | ns/sample | max err vs closed form (gμ) | rms | max err vs truth (gμ) | rms vs truth | M4F instr/sample |"
    );
    let _ = writeln!(s, "|---|---|---|---|---:|---:|---:|---:|---:|---:|");
    for row in &r.rows {
        let opt = |v: Option<f64>| v.map_or("–".to_string(), sci);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            row.scene,
            row.method,
            row.precision,
            row.setting,
            ns(row.ns_per_sample),
            sci(row.max_err_gmu),
            sci(row.rms_err_gmu),
            opt(row.max_err_vs_truth_gmu),
            opt(row.rms_err_vs_truth_gmu),
            row.m4f_instructions_per_sample
                .map_or("–".to_string(), |v| format!("{v:.1}")),
        );
    }
    let dd: Vec<&Row> = r
        .rows
        .iter()
        .filter(|row| row.max_err_vs_dd_gmu.is_some())
        .collect();
    if !dd.is_empty() {
        let _ = writeln!(
            s,
            "\nlong-train against a double-double evaluation of the undamped sum (the closed form's own rounding):\n"
        );
        let _ = writeln!(
            s,
            "| method | precision | setting | max err vs double-double (gμ) |"
        );
        let _ = writeln!(s, "|---|---|---|---:|");
        for row in dd {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} |",
                row.method,
                row.precision,
                row.setting,
                sci(row.max_err_vs_dd_gmu.unwrap_or(f64::NAN))
            );
        }
    }
    if let Some(x) = r.long_train_speedup {
        let _ = writeln!(
            s,
            "\nlong-train: the recursion (f32, F32Poly) is {x:.3e}× faster per sample than the full closed-form sum."
        );
    }
    if !r.scenes.is_empty() {
        let _ = writeln!(s, "\nScenes:\n");
        for sc in &r.scenes {
            let _ = writeln!(
                s,
                "- `{}`: {} ({} samples, {} reversals in the RDM train, {} compared; gμ = {:.4} m/s²)",
                sc.id, sc.description, sc.samples, sc.reversals, sc.compared_samples, sc.gmu_m_s2
            );
        }
    }
    if !r.notes.is_empty() {
        let _ = writeln!(s, "\nNotes:\n");
        for n in &r.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    s
}

/// Floor at which exact zeros are drawn on the log error axis.
const ZERO_FLOOR: f64 = 1e-17;

/// The Pareto figure of one scene: error against cost, one panel per reference.
fn pareto_figure(r: &Report, sc: &BenchScene) -> Figure {
    let rows: Vec<&Row> = r.rows.iter().filter(|row| row.scene == sc.id).collect();
    let families: [(&str, &str, Marker, usize); 6] = [
        (
            "rdm-recursion",
            "RDM recursion (estimator)",
            Marker::Circle,
            0,
        ),
        ("rdm-closed", "RDM closed form, full sum", Marker::Square, 6),
        (
            "rdm-truncated",
            "RDM closed form, K newest terms",
            Marker::Triangle,
            1,
        ),
        ("rfm", "RFM, H harmonics", Marker::Ring, 2),
        ("tfm", "TFM, H harmonics", Marker::Cross, 3),
        ("truth", "exact stick-slip truth", Marker::Square, 4),
    ];
    let short = |row: &Row| -> String {
        match row.method.as_str() {
            "rdm-recursion" => match (row.precision.as_str(), row.setting.as_str()) {
                ("f64", _) => "f64".into(),
                (_, s) if s.starts_with("F32Poly") => "f32 poly (fw)".into(),
                (_, s) => format!("f32 {s}"),
            },
            "rdm-closed" => String::new(),
            "truth" => String::new(),
            _ => row.setting.clone(),
        }
    };
    let mut panels = Vec::new();
    type Get = Box<dyn Fn(&Row) -> Option<f64>>;
    let kinds: Vec<(&str, bool, Get)> = vec![
        (
            "numerical: max error against the full f64 closed form",
            false,
            Box::new(|row: &Row| Some(row.max_err_gmu)),
        ),
        (
            "model: max error against the exact stick-slip truth",
            true,
            Box::new(|row: &Row| row.max_err_vs_truth_gmu),
        ),
        (
            "numerical: max error against a double-double evaluation",
            false,
            Box::new(|row: &Row| row.max_err_vs_dd_gmu),
        ),
    ];
    for (title, model, get) in kinds {
        if rows.iter().all(|row| get(row).is_none()) {
            continue;
        }
        let mut p = Panel::new(
            title,
            "host cost (ns per sample, log)",
            "max |error| (gμ, log)",
        );
        p.log_x = true;
        p.log_y = true;
        p.legend = plotters::prelude::SeriesLabelPosition::UpperRight;
        let mut any_zero = false;
        for (method, label, marker, ci) in families {
            let mut pts = Vec::new();
            let mut labels = Vec::new();
            for row in rows.iter().filter(|row| row.method == method) {
                if model && method == "truth" {
                    continue; // the reference of this panel
                }
                if let Some(e) = get(row) {
                    if e == 0.0 {
                        any_zero = true;
                    }
                    pts.push((row.ns_per_sample, e.max(ZERO_FLOOR)));
                    labels.push(short(row));
                }
            }
            if pts.is_empty() {
                continue;
            }
            let style = if pts.len() > 1 && matches!(method, "rdm-truncated" | "rfm" | "tfm") {
                Style::LineMarkers(marker, 6)
            } else {
                Style::Markers(marker, 7)
            };
            merge_close_labels(&pts, &mut labels);
            let mut s = Series::new(label, pts, plots::color(ci), style);
            s.labels = labels;
            p.series.push(s);
        }
        // The Pareto front: the lower-left envelope of every point.
        let mut all: Vec<(f64, f64)> = p.series.iter().flat_map(|s| s.points.clone()).collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut front = Vec::new();
        let mut best = f64::INFINITY;
        for (x, y) in all {
            if y < best {
                best = y;
                front.push((x, y));
            }
        }
        p.series.insert(
            0,
            Series::new("Pareto front", front, plots::color(8), Style::Dashed),
        );
        let ymax = p
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|q| q.1))
            .fold(ZERO_FLOOR, f64::max);
        let (xmin, xmax) = p
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|q| q.0))
            .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
        p.x_range = Some((xmin / 2.0, xmax * 4.0));
        let ymin = p
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|q| q.1))
            .fold(f64::INFINITY, f64::min);
        p.y_range = Some((ymin.max(ZERO_FLOOR) / 5.0, ymax * 20.0));
        p.legend_outside = Some(330);
        if any_zero {
            p.notes.push(format!(
                "error 0 (the reference itself) drawn at {ZERO_FLOOR:.0e}"
            ));
        }
        panels.push(p);
    }
    let cols = panels.len().max(1);
    Figure {
        title: format!("host-sim bench: speed against error, scene \"{}\"", sc.id),
        panels,
        cols,
        panel_size: (1150, 760),
    }
}

/// Join the labels of points drawn close to each other (within a factor 2.5 in x and 2 in y).
fn merge_close_labels(pts: &[(f64, f64)], labels: &mut [String]) {
    for i in 1..pts.len().min(labels.len()) {
        for j in 0..i {
            let close = (pts[i].0 / pts[j].0).ln().abs() < 2.5f64.ln()
                && (pts[i].1 / pts[j].1).log10().abs() < 0.3;
            if close && !labels[j].is_empty() {
                let l = std::mem::take(&mut labels[i]);
                if !l.is_empty() {
                    labels[j] = format!("{}, {l}", labels[j]);
                }
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn double_double_reference_matches_the_closed_form_at_small_times() {
        let s = table1(0.0).unwrap();
        let train: Vec<Reversal> = (0..40)
            .map(|j| Reversal {
                time_s: j as f64 * 0.0715 + 1e-5,
                level: if j % 2 == 0 { 1.0 } else { -1.0 },
            })
            .collect();
        let cf = DuhamelClosedForm::new(&s);
        let tr = ReversalTrain::Explicit(&train);
        for k in 0..3000 {
            let t = k as f64 * 1e-3;
            let want = cf.accel(&tr, t);
            let got = dd_undamped(s.omega_d(), s.gmu(), &train, t);
            // The f64 closed form rounds n·τ (~3e-14 rad per term at τ ~ 1 s).
            assert!(
                (got - want).abs() < 1e-12 * s.gmu(),
                "t = {t}: {got} vs {want}"
            );
        }
    }

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

    #[test]
    fn close_labels_are_merged() {
        let pts = [(1.3, 1e-7), (1.6, 1.2e-7), (1.5, 1e-13)];
        let mut labels = vec!["a".to_string(), "b".into(), "c".into()];
        merge_close_labels(&pts, &mut labels);
        assert_eq!(labels, ["a, b", "", "c"]);
    }
}
