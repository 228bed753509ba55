//! What no causal estimator can do in predict mode (issue 13). Until the base first slides it
//! moves with the table and the displacement reads zero, so every channel predict mode reads
//! (the table, the base, the displacement; never the top; none saturated) is the same for two
//! specimens that share the table and the prior, while their tops respond differently. An
//! estimator whose prediction of each sample uses the samples up to it (the streamed
//! prediction that is scored; not a smoother that waits for the first slide) predicts the
//! same p for both there (the same draws of the sensors' noise too: they do not depend on the
//! specimen), and ‖p − ü1_a‖ + ‖p − ü1_b‖ ≥ ‖ü1_a − ü1_b‖: one of the two errs by at least half
//! their difference. Over the run's N samples, in % of the larger peak:
//!
//! `bound = 100 · ½ · √(Σ_{t < t1} (ü1_a − ü1_b)² / N) / max(peak_a, peak_b)`,
//!
//! t1 the earlier of the two first slides. Both specimens below are the El Centro scene's,
//! with f such that the prior the scene tells (7 Hz) is 8 % (or 5 %) off, one high and one
//! low: within the range of issue 13's goals, whose predict-mode goal is ≤ 1 % RMS. The bound
//! comes from the exact stick-slip truth and, independently, from an RK4 integration of the
//! fixed-base oscillator over the stuck window (the two agree to 1e-13).

use host_sim::scene::Scene;
use host_sim::table_motion::TableMotion;
use host_sim::truth::{simulate, Truth, TruthInput};
use ssvr_core::Structure;
use std::path::Path;

fn elcentro() -> Scene {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    Scene::load(dir.join("elcentro.toml")).unwrap()
}

/// The scene's specimen with f scaled by `f`.
fn specimen(s: &Scene, f: f64) -> Structure {
    let mut p = *s.structure.params();
    p.natural_frequency_hz *= f;
    Structure::new(p).unwrap()
}

fn truth(s: &Scene, st: &Structure) -> Truth {
    let table = s.table_motion();
    simulate(
        &TruthInput::new(st, &table, s.duration_s)
            .with_static_friction(s.static_friction_coefficient)
            .with_friction(s.friction),
    )
    .unwrap()
}

/// The first slide's time (the run's end if none).
fn first_slide(s: &Scene, t: &Truth) -> f64 {
    t.events().first().map_or(s.duration_s, |e| e.time_s)
}

/// ü1 at the scene's samples before `t1`, from the truth; checks that every channel predict
/// mode reads is the table's motion there (base = table, no slip).
fn stuck_top(s: &Scene, t: &Truth, t1: f64) -> Vec<f64> {
    let mut c = t.sampler();
    (0..s.samples)
        .map(|k| k as f64 / s.rate_hz)
        .take_while(|&t| t < t1)
        .map(|time| {
            let x = c.sample(time).unwrap();
            assert!(
                (x.base_accel_m_s2 - x.table_accel_m_s2).abs() < 1e-9,
                "{time} s"
            );
            assert_eq!((x.slip_m, x.slip_velocity_m_s), (0.0, 0.0), "{time} s");
            x.top_accel_m_s2
        })
        .collect()
}

/// ü1 = −(2ξp ẋ + p² x) of the fixed-base oscillator ẍ + 2ξp ẋ + p² x = −ü_g from rest, by RK4 at
/// `sub` steps per sample (the record's knots, every 0.02 s, fall on steps), at the scene's
/// samples before `t1`.
fn rk4_top(s: &Scene, st: &Structure, table: &TableMotion, t1: f64, sub: u32) -> Vec<f64> {
    let (p, xi) = (st.p(), st.xi());
    let f = |t: f64, y: [f64; 2]| [y[1], -table.accel(t) - 2.0 * xi * p * y[1] - p * p * y[0]];
    let dt = 1.0 / (s.rate_hz * f64::from(sub));
    let mut y = [0.0_f64; 2];
    let mut out = Vec::new();
    for k in 0..s.samples {
        let t0 = k as f64 / s.rate_hz;
        if t0 >= t1 {
            break;
        }
        out.push(-(2.0 * xi * p * y[1] + p * p * y[0]));
        for j in 0..sub {
            // Each step evaluates ü_g strictly inside or at the right of a step's knots: the
            // record is linear between knots and continuous after its first sample.
            let t = t0 + f64::from(j) * dt;
            let k1 = f(t, y);
            let k2 = f(
                t + dt / 2.0,
                [y[0] + dt / 2.0 * k1[0], y[1] + dt / 2.0 * k1[1]],
            );
            let k3 = f(
                t + dt / 2.0,
                [y[0] + dt / 2.0 * k2[0], y[1] + dt / 2.0 * k2[1]],
            );
            let k4 = f(t + dt, [y[0] + dt * k3[0], y[1] + dt * k3[1]]);
            for i in 0..2 {
                y[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
    }
    out
}

/// The bound in % of the larger peak, over the run's samples.
fn bound_pct(s: &Scene, a: &[f64], b: &[f64], peak: f64) -> f64 {
    assert_eq!(a.len(), b.len());
    let sum: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    let pct = 100.0 * 0.5 * (sum / s.samples as f64).sqrt() / peak;
    assert!(pct.is_finite(), "{pct}");
    pct
}

/// The bound for the two specimens of El Centro the prior is `off` from, one each way (truths
/// f/(1 + off) and f/(1 − off): the prior is then `off` high for one, low for the other); by the
/// truth and by RK4; and the stuck window's end.
fn elcentro_bound(off: f64) -> (f64, f64, f64) {
    pair_bound(1.0 / (1.0 + off), 1.0 / (1.0 - off))
}

/// The bound for El Centro's specimen with f scaled by `a` and by `b`.
fn pair_bound(a: f64, b: f64) -> (f64, f64, f64) {
    let s = elcentro();
    let (sa, sb) = (specimen(&s, a), specimen(&s, b));
    let (ta, tb) = (truth(&s, &sa), truth(&s, &sb));
    let t1 = first_slide(&s, &ta).min(first_slide(&s, &tb));
    let (pa, pb) = (ta.peak_top_accel_m_s2(), tb.peak_top_accel_m_s2());
    assert!(pa.is_finite() && pb.is_finite(), "peaks {pa}, {pb}");
    let peak = pa.max(pb);
    let by_truth = bound_pct(&s, &stuck_top(&s, &ta, t1), &stuck_top(&s, &tb, t1), peak);
    let table = s.table_motion();
    let (ra, rb) = (
        rk4_top(&s, &sa, &table, t1, 4),
        rk4_top(&s, &sb, &table, t1, 4),
    );
    (by_truth, bound_pct(&s, &ra, &rb, peak), t1)
}

/// f told 8 % off (one specimen each way, 6.48 and 7.61 Hz told 7 Hz): one of the two is
/// predicted with at least 1.398 % RMS error over the 32 s whatever the causal estimator (the
/// base stuck for the first 1.644 s), against a goal of 1 %. The scorecard's predict rows
/// measure 1.61 / 2.20 % (f +8 / −8 % on the scene's own specimen).
#[test]
fn no_estimator_meets_the_predict_goal_on_el_centro_with_f_told_8_percent_off() {
    let (by_truth, by_rk4, t1) = elcentro_bound(0.08);
    assert!((t1 - 1.644).abs() < 1e-3, "first slide at {t1} s");
    assert!((by_truth - 1.398).abs() < 0.002, "bound {by_truth} %");
    assert!(
        (by_rk4 - by_truth).abs() < 1e-9 * by_truth,
        "RK4 {by_rk4} %, truth {by_truth} %"
    );
    assert!(by_truth > 1.0);
}

/// f told 5 % off: still beyond the goal, at least 1.043 %; the scorecard's rows measure
/// 1.20 / 1.34 %.
#[test]
fn no_estimator_meets_the_predict_goal_on_el_centro_with_f_told_5_percent_off() {
    let (by_truth, by_rk4, _) = elcentro_bound(0.05);
    assert!((by_truth - 1.043).abs() < 0.002, "bound {by_truth} %");
    assert!(
        (by_rk4 - by_truth).abs() < 1e-9 * by_truth,
        "RK4 {by_rk4} %, truth {by_truth} %"
    );
    assert!(by_truth > 1.0);
}

/// The scorecard's own specimen (7 Hz) in each pair: told 7.56 Hz (its `f+8%` row) it shares
/// the prior with 8.217 Hz told 8 % low, and one of the two errs by at least 1.137 %; told
/// 6.44 Hz (`f-8%`), with 5.963 Hz told 8 % high: 1.585 %. Told 5 % off: 0.893 % (with
/// 7.737 Hz: below the goal, no proof for that row) and 1.339 % (with 6.333 Hz).
#[test]
fn the_scorecards_own_specimen_pairs() {
    for (a, b, bound) in [
        (1.0, 1.08 / 0.92, 1.137),
        (0.92 / 1.08, 1.0, 1.585),
        (1.0, 1.05 / 0.95, 0.893),
        (0.95 / 1.05, 1.0, 1.339),
    ] {
        let (by_truth, by_rk4, _) = pair_bound(a, b);
        assert!((by_truth - bound).abs() < 0.002, "{a} / {b}: {by_truth} %");
        assert!((by_rk4 - by_truth).abs() < 1e-9 * by_truth);
    }
}
