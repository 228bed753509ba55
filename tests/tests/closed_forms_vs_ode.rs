//! Issue 2: independent checks of the closed forms.
//!
//! * The generalised eq (36) (RDM, `DuhamelClosedForm`) against an independent DOP853 integration of
//!   the original equations of motion (1)-(2) in absolute coordinates (`ssvr_integration_tests::ode`),
//!   in all damping regimes, for the paper's periodic train and an irregular train with stuck phases.
//! * Continuity of the closed form across Mξ² = 1, the m2 → 0 limit (eq 39), RFM = RDM steady state
//!   ("(20) equals (36)"), RFM = lim_{α→0} TFM.
//! * The integrator itself against exact solutions typed from docs/equations.md.
//!
//! Every error is reported relative to gμ. Run with `--nocapture` to see the measured numbers.

use ssvr_core::closed_form::duhamel::{DuhamelClosedForm, Reversal, ReversalTrain};
use ssvr_core::closed_form::fourier::FourierResponse;
use ssvr_core::{Regime, Structure, StructureParams};
use ssvr_integration_tests::finite::{finite_max, max_finite};
use ssvr_integration_tests::ode::{ForceStep, State, Tolerance, TwoMassModel};
use std::f64::consts::PI;

const G: f64 = 9.80665;
/// The paper's input period (s) for the Table 1 specimen, "equal to the natural period".
const PERIOD: f64 = 0.143;
/// Reversals every T/2.
const HALF: f64 = PERIOD / 2.0;
/// Length of the compared histories (s).
const T_END: f64 = 3.0;
/// Output grid spacing (s): 3001 grid outputs over [0, T_END].
const DT: f64 = 1e-3;

fn structure(m1: f64, m2: f64, xi: f64) -> Structure {
    Structure::new(StructureParams {
        m1_kg: m1,
        m2_kg: m2,
        natural_frequency_hz: 7.0,
        damping_ratio: xi,
        friction_coefficient: 0.2,
        gravity_m_s2: G,
    })
    .expect("valid structure")
}

/// The Table 1 specimen (m1 29.5 kg, m2 1.75 kg, 7 Hz, μ 0.2) with damping ratio ξ.
fn table1(xi: f64) -> Structure {
    structure(29.5, 1.75, xi)
}

/// The regimes of issue 2 (name, structure, expected regime).
fn regime_cases() -> Vec<(&'static str, Structure, Regime)> {
    vec![
        ("underdamped (Table 1)", table1(0.05), Regime::Underdamped),
        (
            "critical (3/1, xi 0.5)",
            structure(3.0, 1.0, 0.5),
            Regime::Critical,
        ),
        (
            "overdamped (3/1, xi 0.7)",
            structure(3.0, 1.0, 0.7),
            Regime::Overdamped,
        ),
        (
            "strongly overdamped (1000/1, xi 0.3)",
            structure(1000.0, 1.0, 0.3),
            Regime::Overdamped,
        ),
        ("undamped (Table 1, xi 0)", table1(0.0), Regime::Underdamped),
    ]
}

/// An irregular train: reversal times off the output grid (except 0.6 s, on it), pairs closer than
/// the output spacing, stuck phases (level 0) entered from and left to either sign.
const IRREGULAR: &[(f64, f64)] = &[
    (0.013_579_1, 1.0),
    (0.081_234_5, -1.0),
    (0.150_000_7, 1.0),
    (0.150_321_3, -1.0),
    (0.262_5, 0.0),
    (0.497_310_9, 1.0),
    (0.566_123_4, -1.0),
    (0.6, 1.0),
    (0.712_345_6, 0.0),
    (0.712_395_6, -1.0),
    (0.950_017, 0.0),
    (1.200_000_3, -1.0),
    (1.333_333_3, 1.0),
    (1.400_7, -1.0),
    (1.401_2, 1.0),
    (1.555_555_5, 0.0),
    (2.014_1, 1.0),
    (2.087_654_3, -1.0),
    (2.161_111_1, 1.0),
    (2.3, -1.0),
    (2.45, 0.0),
    (2.7, 1.0),
];

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum TrainKind {
    /// The paper's alternating train: +1 at t = 0, reversals every T/2.
    Periodic,
    /// [`IRREGULAR`].
    Irregular,
}

/// The friction steps of a train up to T_END, for the integrator (times built here, not by the core).
fn force_steps(kind: TrainKind) -> Vec<ForceStep> {
    match kind {
        TrainKind::Periodic => (0..)
            .map(|k| ForceStep {
                time_s: 0.0 + k as f64 * HALF,
                level: if k % 2 == 0 { 1.0 } else { -1.0 },
            })
            .take_while(|s| s.time_s <= T_END)
            .collect(),
        TrainKind::Irregular => IRREGULAR
            .iter()
            .map(|&(time_s, level)| ForceStep { time_s, level })
            .collect(),
    }
}

fn irregular_reversals() -> Vec<Reversal> {
    IRREGULAR
        .iter()
        .map(|&(time_s, level)| Reversal { time_s, level })
        .collect()
}

/// The same train for the closed form.
fn core_train(kind: TrainKind, irregular: &[Reversal]) -> ReversalTrain<'_> {
    match kind {
        TrainKind::Periodic => ReversalTrain::Periodic {
            first_s: 0.0,
            half_period_s: HALF,
            initial_sign: 1.0,
        },
        TrainKind::Irregular => ReversalTrain::Explicit(irregular),
    }
}

/// Grid outputs k·DT on [0, T_END] plus every reversal time, sorted.
fn output_times(steps: &[ForceStep]) -> Vec<f64> {
    let n = (T_END / DT).round() as usize;
    let mut t: Vec<f64> = (0..=n).map(|k| k as f64 * DT).collect();
    t.extend(steps.iter().map(|s| s.time_s));
    t.sort_by(f64::total_cmp);
    t.dedup();
    t
}

/// Max |closed form − ODE|/gμ over the outputs, with its time, the output count and the step count.
fn closed_form_vs_ode(s: &Structure, kind: TrainKind, tol: Tolerance) -> (f64, f64, usize, usize) {
    let irregular = irregular_reversals();
    let train = core_train(kind, &irregular);
    train.validate().expect("valid train");
    let steps = force_steps(kind);
    let outputs = output_times(&steps);
    let ode = TwoMassModel::new(s.params()).solve([0.0; 4], 0.0, &steps, &outputs, tol);
    let cf = DuhamelClosedForm::new(s);
    let (mut worst, mut at) = (0.0f64, 0.0f64);
    for (&t, &want) in outputs.iter().zip(&ode.top_accel) {
        let got = cf.accel(&train, t);
        assert!(got.is_finite(), "closed form not finite at t = {t}");
        let e = max_finite(0.0, (got - want).abs() / s.gmu(), "|cf − ODE|", t);
        if e > worst {
            (worst, at) = (e, t);
        }
    }
    (worst, at, outputs.len(), ode.accepted_steps)
}

// ---------------------------------------------------------------------------------------------
// 1. RDM closed form = ODE in all regimes, for both trains.
// ---------------------------------------------------------------------------------------------

#[test]
fn closed_form_equals_ode_in_all_regimes() {
    // (integrator tolerance, bound on max |closed form − ODE|/gμ)
    const RUNS: [(Tolerance, f64); 2] = [(Tolerance::TIGHT, 1e-9), (Tolerance::REFERENCE, 1e-10)];
    let mut overall = [0.0f64; 2];
    for (name, s, regime) in regime_cases() {
        assert_eq!(s.regime(), regime, "{name}: regime");
        for kind in [TrainKind::Periodic, TrainKind::Irregular] {
            for (i, (tol, bound)) in RUNS.into_iter().enumerate() {
                let (err, at, n, steps) = closed_form_vs_ode(&s, kind, tol);
                println!(
                    "{name:38} {kind:9?} ODE tol {:e}: max |cf - ode|/gmu = {err:.2e} at \
                     t = {at:.6} s ({n} outputs, {steps} ODE steps)",
                    tol.rel
                );
                assert!(n >= 2000);
                assert!(
                    err <= bound,
                    "{name} {kind:?} tol {tol:?}: {err:e} at t = {at}"
                );
                overall[i] = overall[i].max(err);
            }
        }
    }
    println!(
        "overall max: {:.2e} (ODE tol 1e-12, bound 1e-9), {:.2e} (ODE tol 1e-13, bound 1e-10)",
        overall[0], overall[1]
    );
}

// ---------------------------------------------------------------------------------------------
// 2. Continuity of the closed form across Mξ² = 1.
// ---------------------------------------------------------------------------------------------

#[test]
fn closed_form_is_continuous_across_critical_damping() {
    // (ξ, regime, bound on the difference from critical): measured 4.5e-10 gμ at ξ = 0.5 ∓ 2.5e-10
    // (the true change of the response with ξ) and 2.0e-15 at ξ = 0.5 ∓ 1e-15.
    const TOL: f64 = 1e-9;
    // Each side against the ODE of its own ξ: measured ≤ 1.0e-12.
    const ODE_TOL: f64 = 3e-12;
    let critical = structure(3.0, 1.0, 0.5);
    assert_eq!(critical.regime(), Regime::Critical);
    let neighbours = [
        (0.5 - 2.5e-10, Regime::Underdamped, TOL),
        (0.5 + 2.5e-10, Regime::Overdamped, TOL),
        (0.5 - 1e-15, Regime::Underdamped, 1e-14),
        (0.5 + 1e-15, Regime::Overdamped, 1e-14),
    ];
    let irregular = irregular_reversals();
    for kind in [TrainKind::Periodic, TrainKind::Irregular] {
        let train = core_train(kind, &irregular);
        let outputs = output_times(&force_steps(kind));
        let at_critical: Vec<f64> = {
            let cf = DuhamelClosedForm::new(&critical);
            outputs.iter().map(|&t| cf.accel(&train, t)).collect()
        };
        for (xi, regime, bound) in neighbours {
            let s = structure(3.0, 1.0, xi);
            assert_eq!(s.regime(), regime, "xi = {xi}");
            let cf = DuhamelClosedForm::new(&s);
            let worst = finite_max(
                "difference from critical",
                outputs.iter().zip(&at_critical).map(|(&t, &c)| {
                    let v = cf.accel(&train, t);
                    assert!(v.is_finite(), "xi = {xi}, t = {t}");
                    (v - c).abs() / s.gmu()
                }),
            );
            println!(
                "{kind:?}: xi = 0.5 {:+.1e} ({regime:?}) vs critical: max diff/gmu = {worst:.2e}",
                xi - 0.5
            );
            assert!(worst <= bound, "{kind:?} xi = {xi}: {worst:e}");
        }
        // Each side also matches the ODE of its own ξ.
        for xi in [0.5 - 2.5e-10, 0.5 + 2.5e-10] {
            let (err, at, _, _) =
                closed_form_vs_ode(&structure(3.0, 1.0, xi), kind, Tolerance::TIGHT);
            println!(
                "{kind:?}: xi = 0.5 {:+.1e} vs ODE: {err:.2e} at t = {at:.6}",
                xi - 0.5
            );
            assert!(err <= ODE_TOL, "{kind:?} xi = {xi}: {err:e} at {at}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 3. m2 → 0: eq (39), ü1 → gμ s(t).
// ---------------------------------------------------------------------------------------------

/// The reversals at or before t that still matter (the newest `keep`), as (time, jump Δs), computed
/// here from the train's definition.
fn recent_jumps(kind: TrainKind, steps: &[ForceStep], t: f64, keep: usize) -> Vec<(f64, f64)> {
    match kind {
        TrainKind::Periodic => {
            if t < 0.0 {
                return vec![];
            }
            let mut k = (t / HALF).floor() as i64;
            if k as f64 * HALF > t {
                k -= 1;
            }
            let level = |j: i64| if j % 2 == 0 { 1.0 } else { -1.0 };
            (k.saturating_sub(keep as i64 - 1).max(0)..=k)
                .map(|j| {
                    let jump = if j == 0 { 1.0 } else { level(j) - level(j - 1) };
                    (j as f64 * HALF, jump)
                })
                .collect()
        }
        TrainKind::Irregular => {
            let n = steps.partition_point(|r| r.time_s <= t);
            (n.saturating_sub(keep)..n)
                .map(|j| {
                    let before = if j == 0 { 0.0 } else { steps[j - 1].level };
                    (steps[j].time_s, steps[j].level - before)
                })
                .collect()
        }
    }
}

#[test]
fn massless_base_limit_is_eq39() {
    // Eq (39): ü1 → gμ s(t) once the fast transient (rate ≈ 2a = 2Mpξ ≈ 4e9/s here) has died.
    const TOL: f64 = 1e-6;
    const SETTLE: f64 = 1e-6;
    // The leading correction, typed from the transfer function in docs/equations.md: the slow pole
    // r1 = p/(2ξ)·(1 + ε), ε = 1/(4Mξ²), nearly cancels the zero at p/(2ξ) and leaves the residue ε,
    // so ü1 = gμ [s(t) + ε Σ_j Δs_j e^{−r1 (t − t_j)}] + O(ε², r1/(2a)). Checking this to 1e-10·gμ
    // shows the closed form is accurate far beyond the 1e-6 of eq (39) itself (measured 6.0e-14 at
    // ξ = 0.05, 2.3e-16 at ξ = 0.3; eq 39 itself 2.0e-7).
    const TOL_CORRECTED: f64 = 3e-13;
    for xi in [0.05, 0.3] {
        let s = structure(1.0, 1e-9, xi);
        let gmu = s.gmu();
        let p = 2.0 * PI * 7.0;
        let m = 1.0 + 1.0 / 1e-9;
        let eps = 1.0 / (4.0 * m * xi * xi);
        let r1 = p / (2.0 * xi);
        let cf = DuhamelClosedForm::new(&s);
        let irregular = irregular_reversals();
        for kind in [TrainKind::Periodic, TrainKind::Irregular] {
            let train = core_train(kind, &irregular);
            let steps = force_steps(kind);
            let mut times = output_times(&steps);
            for st in &steps {
                for d in [1e-15, 1e-12, 1e-9, 1e-7, 1e-6, 2e-6, 1e-5] {
                    times.push(st.time_s + d);
                }
            }
            for base in [1e3, 1e6] {
                for k in 0..200 {
                    times.push(base + k as f64 * 0.000_731);
                }
            }
            let (mut worst, mut worst_at, mut worst_corr, mut checked) = (0.0f64, 0.0, 0.0f64, 0);
            let mut max_abs = 0.0f64;
            for &t in &times {
                let v = cf.accel(&train, t);
                assert!(v.is_finite(), "xi {xi} {kind:?}: NaN/inf at t = {t}");
                max_abs = max_abs.max(v.abs() / gmu);
                let jumps = recent_jumps(kind, &steps, t, 60);
                let level: f64 = match kind {
                    TrainKind::Periodic => jumps.last().map_or(0.0, |&(tj, _)| {
                        if ((tj / HALF).round() as i64) % 2 == 0 {
                            1.0
                        } else {
                            -1.0
                        }
                    }),
                    TrainKind::Irregular => {
                        let n = steps.partition_point(|r| r.time_s <= t);
                        if n == 0 {
                            0.0
                        } else {
                            steps[n - 1].level
                        }
                    }
                };
                let t_last = jumps.last().map_or(f64::NEG_INFINITY, |&(tj, _)| tj);
                if t - t_last > SETTLE {
                    checked += 1;
                    let e = max_finite(0.0, (v - gmu * level).abs() / gmu, "|ü1 − gμ s|", t);
                    if e > worst {
                        (worst, worst_at) = (e, t);
                    }
                    let corr: f64 = jumps
                        .iter()
                        .map(|&(tj, dj)| dj * (-r1 * (t - tj)).exp())
                        .sum();
                    let e = (v - gmu * (level + eps * corr)).abs() / gmu;
                    worst_corr = max_finite(worst_corr, e, "|ü1 − corrected eq 39|", t);
                }
            }
            println!(
                "m2/m1 = 1e-9, xi {xi}, {kind:?}: max |u1'' - gmu s|/gmu = {worst:.2e} at \
                 t = {worst_at} (2 eps = {:.2e}); with the eps correction {worst_corr:.2e} \
                 ({checked} times settled, {} total); max |u1''|/gmu = {max_abs:.9}",
                2.0 * eps,
                times.len()
            );
            assert!(worst <= TOL, "xi {xi} {kind:?}: {worst:e} at {worst_at}");
            assert!(
                worst_corr <= TOL_CORRECTED,
                "xi {xi} {kind:?}: {worst_corr:e}"
            );
            // The fast transition is monotone; only the ε-overshoot goes beyond ±gμ.
            assert!(max_abs <= 1.0 + 2.0 * eps + 1e-12, "overshoot {max_abs}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 4. RFM = steady state of the RDM ("(20) equals (36)").
// ---------------------------------------------------------------------------------------------

/// max |f| over [t0, t0 + period]: a grid, then golden-section refinement around the 3 best points.
fn peak_abs(f: impl Fn(f64) -> f64, t0: f64, period: f64, grid: usize) -> f64 {
    let h = period / grid as f64;
    let mut vals: Vec<(f64, f64)> = (0..grid)
        .map(|i| {
            let t = t0 + i as f64 * h;
            (t, f(t).abs())
        })
        .collect();
    vals.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut best = vals[0].1;
    let g = (5f64.sqrt() - 1.0) / 2.0;
    for &(tc, _) in vals.iter().take(3) {
        let (mut lo, mut hi) = (tc - h, tc + h);
        for _ in 0..80 {
            let (x1, x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
            if f(x1).abs() > f(x2).abs() {
                hi = x2;
            } else {
                lo = x1;
            }
        }
        for t in [0.5 * (lo + hi), lo, hi] {
            best = max_finite(best, f(t).abs(), "|ü1| near the peak", t);
        }
    }
    best
}

/// Σ_{k ≥ h} |A_n| + |B_n| (n = 2k + 1): a bound on the truncation error of an h-harmonic RFM sum,
/// summed to n = 8e6 plus the asymptotic c/n² remainder.
fn rfm_tail_bound(r: &FourierResponse, harmonics: u32) -> f64 {
    const K_MAX: u32 = 4_000_000;
    let mut sum = 0.0;
    for k in harmonics..K_MAX {
        let (a, b) = r.coefficients(2 * k + 1);
        sum += a.abs() + b.abs();
    }
    let n = (2 * K_MAX + 1) as f64;
    let (a, _) = r.coefficients(2 * K_MAX + 1);
    sum + a.abs() * n * n / (2.0 * n)
}

#[test]
fn rfm_equals_rdm_steady_state() {
    const HARMONICS: u32 = 20_000;
    const SETTLED_PERIODS: f64 = 60.0;
    let s = table1(0.05);
    let gmu = s.gmu();
    let rfm = FourierResponse::rectangular(&s, PERIOD).unwrap();
    let cf = DuhamelClosedForm::new(&s);
    let train = ReversalTrain::Periodic {
        first_s: 0.0,
        half_period_s: HALF,
        initial_sign: 1.0,
    };
    let t_ss = SETTLED_PERIODS * PERIOD;
    let rdm = |tau: f64| cf.accel(&train, t_ss + tau);
    // Transient left after 60 periods: e^{-a t} relative to gμ.
    let transient = (-s.a() * t_ss).exp();
    assert!(transient < 1e-100, "{transient}");

    // Time history over one period.
    let tail = rfm_tail_bound(&rfm, HARMONICS) / gmu;
    let n = 2000;
    let (mut worst, mut worst_at, mut worst_interior) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..n {
        let tau = i as f64 * PERIOD / n as f64;
        let e = (rdm(tau) - rfm.accel(tau, HARMONICS)).abs() / gmu;
        let e = max_finite(0.0, e, "|RDM − RFM|", tau);
        if e > worst {
            (worst, worst_at) = (e, tau);
        }
        // Away from the reversals (|τ − kT/2| > T/20) the Fourier sum converges much faster.
        let phase = (tau / HALF).fract();
        if (0.1..=0.9).contains(&phase) {
            worst_interior = worst_interior.max(e);
        }
    }
    println!(
        "RFM ({HARMONICS} harmonics) vs RDM steady state over one period: max diff/gmu = \
         {worst:.2e} at tau = {worst_at:.6} s (truncation bound {tail:.2e}); away from \
         reversals {worst_interior:.2e}"
    );
    // Measured: 2.84e-5 (at a reversal, the truncation bound 2.85e-5), 1.0e-12 away from reversals.
    assert!(worst <= tail + 1e-9, "{worst:e} > bound {tail:e}");
    assert!(worst <= 5e-5, "{worst:e}");
    assert!(worst_interior <= 5e-12, "{worst_interior:e}");

    // Peak.
    let peak_rdm = peak_abs(rdm, 0.0, PERIOD, 4000);
    let peak_rfm = rfm.peak(HARMONICS);
    let (peak_conv, h_conv) = rfm.converged_peak();
    let rel = (peak_rfm - peak_rdm).abs() / peak_rdm;
    let rel_conv = (peak_conv - peak_rdm).abs() / peak_rdm;
    println!(
        "peak: RDM {peak_rdm:.12} m/s2 ({:.9} gmu), RFM({HARMONICS}) {peak_rfm:.12} (rel {rel:.2e}), \
         RFM converged ({h_conv} harmonics) {peak_conv:.12} (rel {rel_conv:.2e})",
        peak_rdm / gmu
    );
    // Measured: 4.9e-10 at 20 000 harmonics, 1.8e-7 converged (512 harmonics).
    assert!(rel <= 2e-9, "{rel:e}");
    assert!(rel_conv <= 5e-7, "{rel_conv:e}");
}

// ---------------------------------------------------------------------------------------------
// 5. RFM = lim α→0 TFM.
// ---------------------------------------------------------------------------------------------

#[test]
fn rfm_is_the_alpha_to_zero_limit_of_tfm() {
    const HARMONICS: u32 = 2000;
    let s = table1(0.05);
    let gmu = s.gmu();
    let rfm = FourierResponse::rectangular(&s, PERIOD).unwrap();
    let history_diff = |alpha: f64| -> (f64, f64) {
        let tfm = FourierResponse::trapezoid(&s, PERIOD, alpha).unwrap();
        let coeff_bound: f64 = (0..HARMONICS)
            .map(|k| {
                let n = 2 * k + 1;
                let ((a1, b1), (a2, b2)) = (tfm.coefficients(n), rfm.coefficients(n));
                (a1 - a2).abs() + (b1 - b2).abs()
            })
            .sum::<f64>()
            / gmu;
        let worst = finite_max(
            "|TFM − RFM|",
            (0..1000).map(|i| {
                let t = i as f64 * PERIOD / 1000.0;
                (tfm.accel(t, HARMONICS) - rfm.accel(t, HARMONICS)).abs() / gmu
            }),
        );
        (worst, coeff_bound)
    };
    let (d6, b6) = history_diff(1e-6);
    let (d5, b5) = history_diff(1e-5);
    let (d4, b4) = history_diff(1e-4);
    println!(
        "TFM(alpha) - RFM, {HARMONICS} harmonics, max over a period /gmu: alpha 1e-4: {d4:.2e} \
         (coefficient bound {b4:.2e}), 1e-5: {d5:.2e} ({b5:.2e}), 1e-6: {d6:.2e} ({b6:.2e})"
    );
    assert!(d6 <= 1e-9, "{d6:e}");
    assert!(d6 <= b6 + 1e-14 && d5 <= b5 + 1e-14 && d4 <= b4 + 1e-14);
    // The difference vanishes as α² (sin(nα)/(nα) = 1 − (nα)²/6 + …).
    let ratio = d4 / d5;
    assert!((80.0..=120.0).contains(&ratio), "d(1e-4)/d(1e-5) = {ratio}");
    // Peaks.
    let p_rfm = rfm.peak(HARMONICS);
    let p_tfm = FourierResponse::trapezoid(&s, PERIOD, 1e-6)
        .unwrap()
        .peak(HARMONICS);
    let rel = (p_tfm - p_rfm).abs() / p_rfm;
    println!("peak: RFM {p_rfm:.12}, TFM(1e-6) {p_tfm:.12}, rel {rel:.2e}");
    // Measured 1.7e-12.
    assert!(rel <= 5e-12, "{rel:e}");
}

// ---------------------------------------------------------------------------------------------
// 6. The integrator against exact solutions typed from docs/equations.md.
// ---------------------------------------------------------------------------------------------

/// Derived constants typed from docs/equations.md: (p, ξ, M, a, gμ).
fn notes_constants(pr: &StructureParams) -> (f64, f64, f64, f64, f64) {
    let p = 2.0 * PI * pr.natural_frequency_hz;
    let xi = pr.damping_ratio;
    let m = (pr.m1_kg + pr.m2_kg) / pr.m2_kg;
    (
        p,
        xi,
        m,
        m * p * xi,
        pr.gravity_m_s2 * pr.friction_coefficient,
    )
}

/// Exact response from rest to F stepping 0 → +F0 at τ = 0: absolute state and ü1 = R(τ)
/// (docs/equations.md, "Free vibration"; δ = −(gμ/p²)(1 − g(τ)), centre of mass at gμτ²/2).
fn exact_step(pr: &StructureParams, tau: f64) -> (State, f64) {
    let (p, xi, m, a, gmu) = notes_constants(pr);
    let disc = 1.0 - m * xi * xi;
    // g(τ) = e^{−aτ}(cos nτ + (a/n) sin nτ), its derivative, and h(τ) of R = gμ(1 − h).
    let (g, dg, h) = if disc > 0.0 {
        let n = p * m.sqrt() * disc.sqrt();
        let (e, (sn, cs)) = ((-a * tau).exp(), (n * tau).sin_cos());
        (
            e * (cs + a / n * sn),
            -e * (a * a + n * n) / n * sn,
            e * (cs - a / n * sn),
        )
    } else if disc == 0.0 {
        let e = (-a * tau).exp();
        (e * (1.0 + a * tau), -e * a * a * tau, e * (1.0 - a * tau))
    } else {
        let nu = p * m.sqrt() * (-disc).sqrt();
        let (ep, em) = ((-(a - nu) * tau).exp(), (-(a + nu) * tau).exp());
        let (ch, sh) = ((ep + em) / 2.0, (ep - em) / 2.0); // e^{−aτ}cosh ντ, e^{−aτ}sinh ντ
        (
            ch + a / nu * sh,
            -(a * a - nu * nu) / nu * sh,
            ch - a / nu * sh,
        )
    };
    let l = gmu / (p * p);
    let (delta, ddelta) = (-l * (1.0 - g), l * dg);
    let (xc, vc) = (gmu * tau * tau / 2.0, gmu * tau);
    let (w1, w2) = (
        pr.m2_kg / (pr.m1_kg + pr.m2_kg),
        pr.m1_kg / (pr.m1_kg + pr.m2_kg),
    );
    (
        [
            xc + w1 * delta,
            vc + w1 * ddelta,
            xc - w2 * delta,
            vc - w2 * ddelta,
        ],
        gmu * (1.0 - h),
    )
}

/// Exact free vibration (F = 0) from the absolute state y0, underdamped: (state, ü1).
fn exact_free(pr: &StructureParams, y0: State, t: f64) -> (State, f64) {
    let (p, xi, m, a, _) = notes_constants(pr);
    let w0sq = m * p * p;
    let n = (w0sq - a * a).sqrt();
    let (m1, m2) = (pr.m1_kg, pr.m2_kg);
    let (d0, dd0) = (y0[0] - y0[2], y0[1] - y0[3]);
    let (xc0, vc0) = (
        (m1 * y0[0] + m2 * y0[2]) / (m1 + m2),
        (m1 * y0[1] + m2 * y0[3]) / (m1 + m2),
    );
    let (e, (sn, cs)) = ((-a * t).exp(), (n * t).sin_cos());
    let delta = e * (d0 * cs + (dd0 + a * d0) / n * sn);
    let ddelta = e * (dd0 * cs - (a * dd0 + w0sq * d0) / n * sn);
    let (xc, vc) = (xc0 + vc0 * t, vc0);
    let (w1, w2) = (m2 / (m1 + m2), m1 / (m1 + m2));
    (
        [
            xc + w1 * delta,
            vc + w1 * ddelta,
            xc - w2 * delta,
            vc - w2 * ddelta,
        ],
        -(2.0 * p * xi * ddelta + p * p * delta),
    )
}

/// Errors of an ODE solution against an exact one: (ü1/gμ, displacement/L, velocity/(Lω0)).
fn errors(
    model: &TwoMassModel,
    gmu: f64,
    got: &[State],
    got_acc: &[f64],
    want: &[(State, f64)],
) -> (f64, f64, f64) {
    let (mut ea, mut eu, mut ev) = (0.0f64, 0.0f64, 0.0f64);
    for (k, ((y, acc), (yw, accw))) in got.iter().zip(got_acc).zip(want).enumerate() {
        ea = max_finite(ea, (acc - accw).abs() / gmu, "ü1 error", k);
        let (l, v) = (model.length_scale, model.velocity_scale);
        for i in [0, 2] {
            eu = max_finite(eu, (y[i] - yw[i]).abs() / l, "displacement error", k);
            ev = max_finite(ev, (y[i + 1] - yw[i + 1]).abs() / v, "velocity error", k);
        }
    }
    (ea, eu, ev)
}

#[test]
fn integrator_matches_exact_solutions() {
    const TOL: f64 = 1e-10;
    // (a) Step response from rest, all regimes: a step at t0 = 0.0123 s, outputs to 2 s.
    let t_step = 0.0123;
    for (name, s, _) in regime_cases() {
        let pr = *s.params();
        let model = TwoMassModel::new(&pr);
        let outputs: Vec<f64> = (0..=2000).map(|k| k as f64 * 1e-3).collect();
        let steps = [ForceStep {
            time_s: t_step,
            level: 1.0,
        }];
        let sol = model.solve([0.0; 4], 0.0, &steps, &outputs, Tolerance::TIGHT);
        let want: Vec<(State, f64)> = outputs
            .iter()
            .map(|&t| {
                if t < t_step {
                    ([0.0; 4], 0.0)
                } else {
                    exact_step(&pr, t - t_step)
                }
            })
            .collect();
        let (ea, eu, ev) = errors(&model, s.gmu(), &sol.states, &sol.top_accel, &want);
        println!(
            "step response, {name:38}: u1'' {ea:.2e} gmu, u {eu:.2e} L, v {ev:.2e} L*w0 \
             ({} steps, {} rejected)",
            sol.accepted_steps, sol.rejected_steps
        );
        // Measured: ü1 ≤ 3.7e-11 gμ, u ≤ 1.0e-10 L, v ≤ 1.5e-11 L·ω0.
        assert!(ea <= TOL && eu <= 3e-10 && ev <= 5e-11, "{name}");
    }

    // (b) Free vibration from an arbitrary absolute state, 10 s (≈ 300 cycles undamped).
    for xi in [0.05, 0.0] {
        let s = table1(xi);
        let pr = *s.params();
        let model = TwoMassModel::new(&pr);
        let l = model.length_scale;
        let y0 = [0.37 + l, -0.21 + 3.0 * l * 190.0, 0.37, -0.21];
        let outputs: Vec<f64> = (0..=10_000).map(|k| k as f64 * 1e-3).collect();
        let want: Vec<(State, f64)> = outputs.iter().map(|&t| exact_free(&pr, y0, t)).collect();
        // The initial amplitude is ≈ 3.2 L, so the acceleration scale is ≈ 3.2 gμ here; undamped,
        // the global (phase) error grows linearly over the ≈ 300 cycles.
        for (tol, bound) in [(Tolerance::TIGHT, 1e-9), (Tolerance::REFERENCE, 2e-10)] {
            let sol = model.solve(y0, 0.0, &[], &outputs, tol);
            let (ea, eu, ev) = errors(&model, s.gmu(), &sol.states, &sol.top_accel, &want);
            println!(
                "free vibration xi {xi}, 10 s, tol {:e}: u1'' {ea:.2e} gmu, u {eu:.2e} L, \
                 v {ev:.2e} L*w0 ({} steps)",
                tol.rel, sol.accepted_steps
            );
            assert!(
                ea <= bound && eu <= 1e-8 && ev <= bound,
                "xi {xi} tol {tol:?}"
            );
        }
    }

    // (c) A friction train, undamped (no decay hides errors): the integrator against the superposition
    // Σ Δs_j R(t − t_j) of the typed step responses (notes, "Any train of reversals"). The error falls
    // with the tolerance (outputs every 10 ms so that the tolerance, not the output times, sets the
    // step size).
    let s = table1(0.0);
    let pr = *s.params();
    let model = TwoMassModel::new(&pr);
    let steps = force_steps(TrainKind::Periodic);
    let outputs: Vec<f64> = (0..=300).map(|k| k as f64 * 0.01).collect();
    let exact: Vec<f64> = outputs
        .iter()
        .map(|&t| {
            let mut prev_level = 0.0;
            let mut sum = 0.0;
            for st in steps.iter().take_while(|st| st.time_s <= t) {
                sum += (st.level - prev_level) * exact_step(&pr, t - st.time_s).1;
                prev_level = st.level;
            }
            sum
        })
        .collect();
    let mut prev = f64::INFINITY;
    for (tol, bound) in [(1e-8, 1e-6), (1e-10, 1e-8), (1e-12, 1e-10), (1e-13, 2e-11)] {
        let sol = model.solve(
            [0.0; 4],
            0.0,
            &steps,
            &outputs,
            Tolerance { rel: tol, abs: tol },
        );
        let e = finite_max(
            "|ODE − exact|",
            sol.top_accel
                .iter()
                .zip(&exact)
                .map(|(a, b)| (a - b).abs() / s.gmu()),
        );
        println!(
            "undamped periodic train, 3 s, tolerance {tol:e}: max |ode - exact|/gmu = {e:.2e} \
             ({} steps)",
            sol.accepted_steps
        );
        assert!(
            e < prev && e <= bound,
            "tolerance {tol:e}: {e:e} (previous {prev:e})"
        );
        prev = e;
    }
}
