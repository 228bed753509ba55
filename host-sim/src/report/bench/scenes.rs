//! The three bench scenes ([`scenes`]): `harmonic` (the default scene), `long-train` (an undamped
//! structure under a prescribed 10^4-reversal friction train) and `earthquake` (El Centro), each
//! with the friction train of the RDM methods, the truth where there is one and the samples
//! compared.

use crate::scene::{parse_record, Input, Record, Scene, Units};
use crate::table_motion::TableMotion;
use crate::truth::{simulate, Truth, TruthInput};
use anyhow::{anyhow, bail, Result};
use ssvr_core::{Reversal, Structure, StructureParams};
use std::path::{Path, PathBuf};

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

/// The Table 1 specimen with damping ratio `xi` (g = 9.80665).
pub(super) fn table1(xi: f64) -> Result<Structure> {
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
    const RECORD: &str = include_str!("../../../scenes/elcentro-1940-ns.txt");
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

/// The exact stick-slip truth of a bench scene.
pub(super) fn simulate_truth(
    s: &Structure,
    table: &TableMotion,
    mu_s: f64,
    duration: f64,
) -> Result<Truth> {
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
