//! Shared harness: run the recursion over a reversal train and compare it with the closed form.
#![allow(dead_code)]

use ssvr_core::closed_form::duhamel::{DuhamelClosedForm, ReversalTrain};
use ssvr_core::math::{Real, Transcendentals};
use ssvr_core::recursion::{DuhamelRecursion, TrainFeeder};
use ssvr_core::{Structure, StructureParams};

/// `acc.max(value)`, failing on a non-finite `value`: `f64::max` drops NaN (`a.max(NaN) == a`), so an
/// estimator returning NaN would pass a bound checked on a plain running maximum. The panic message
/// names the quantity (`what`) and where it occurred (`at`: a sample index, a time, a case).
#[track_caller]
pub fn max_finite(acc: f64, value: f64, what: &str, at: impl std::fmt::Display) -> f64 {
    assert!(value.is_finite(), "{what} at {at} is not finite: {value}");
    acc.max(value)
}

/// The maximum of `values` (0 when empty), failing on any non-finite one (reported with its
/// position in `values`).
#[track_caller]
pub fn finite_max(what: &str, values: impl IntoIterator<Item = f64>) -> f64 {
    values.into_iter().enumerate().fold(0.0, |m, (i, v)| {
        max_finite(m, v, what, format_args!("index {i}"))
    })
}

pub fn structure(m1: f64, m2: f64, f_hz: f64, xi: f64) -> Structure {
    Structure::new(StructureParams {
        m1_kg: m1,
        m2_kg: m2,
        natural_frequency_hz: f_hz,
        damping_ratio: xi,
        friction_coefficient: 0.2,
        gravity_m_s2: 9.80665,
    })
    .unwrap()
}

/// Errors of one run, in units of max(gμ, peak |ü1|).
#[derive(Debug, Clone, Copy)]
pub struct RunErrors {
    pub max: f64,
    pub rms: f64,
    pub first_tenth: f64,
    pub last_tenth: f64,
    pub compared: usize,
    pub scale: f64,
}

/// Run `n` samples; compare every `stride`-th sample, every sample within ±3 of a reversal and the
/// last 1000 samples with the closed form.
pub fn run<T: Real, M: Transcendentals<T>, const K: usize>(
    s: &Structure,
    rate: f64,
    train: &ReversalTrain<'_>,
    n: u64,
    stride: u64,
) -> RunErrors {
    train.validate().unwrap();
    let mut est = DuhamelRecursion::<T, M, K>::new(s, rate).unwrap();
    let cf = DuhamelClosedForm::new(s);
    let mut feeder = TrainFeeder::new(rate);
    let mut errs: Vec<(u64, f64)> = Vec::new();
    let mut peak: f64 = 0.0;
    let mut near_until = 0u64;
    for k in 0..n {
        let pushed = feeder.feed(train, &mut est, k).unwrap();
        if pushed > 0 {
            near_until = k + 3;
        }
        // Look ahead: the next reversal within 3 samples.
        let next_soon = train
            .get(feeder.pushed())
            .is_some_and(|r| r.time_s <= (k + 3) as f64 / rate);
        let y = est.update().to_f64();
        if k % stride == 0 || k <= near_until || next_soon || k + 1000 >= n {
            let t = k as f64 / rate;
            let want = cf.accel(train, t);
            peak = max_finite(
                peak,
                want.abs(),
                "closed form |ü1|",
                format_args!("sample {k}"),
            );
            errs.push((k, (y - want).abs()));
        }
    }
    let scale = s.gmu().max(peak);
    let tenth = n / 10;
    let max_in = |lo: u64, hi: u64| {
        errs.iter()
            .filter(|(k, _)| *k >= lo && *k < hi)
            .fold(0.0, |m, &(k, e)| {
                max_finite(m, e, "recursion error", format_args!("sample {k}"))
            })
            / scale
    };
    RunErrors {
        max: max_in(0, n),
        rms: (errs.iter().map(|e| e.1 * e.1).sum::<f64>() / errs.len() as f64).sqrt() / scale,
        first_tenth: max_in(0, tenth),
        last_tenth: max_in(n - tenth, n),
        compared: errs.len(),
        scale,
    }
}

pub fn paper_train(half: f64) -> ReversalTrain<'static> {
    ReversalTrain::Periodic {
        first_s: 0.0,
        half_period_s: half,
        initial_sign: 1.0,
    }
}
