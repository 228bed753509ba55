//! The design choice measured: a straightforward f32 state-space recursion (coefficients rounded to
//! f32, state propagated sample by sample) against the same closed form. The issue predicts it
//! misses the 1e-5 bound by 10-1000x on the undamped, 1 MHz and resonant cases; the anchored table
//! (see `stability.rs`) meets it everywhere. This test records the baseline's errors and asserts
//! that it does fail where predicted (so the comparison in docs/PERFORMANCE.md stays true).
mod common;
use common::*;
use ssvr_core::closed_form::duhamel::{DuhamelClosedForm, ReversalTrain};
use ssvr_core::closed_form::free_vibration::Kernel;
use ssvr_core::math::Libm;
use ssvr_core::Structure;

/// w_{k+1} = Ψ(Δt)·w_k in f32; reversals add their exact contribution at the next sample.
fn naive_max_error(
    s: &Structure,
    rate: f64,
    train: &ReversalTrain<'_>,
    n: u64,
    stride: u64,
) -> f64 {
    let k = Kernel::<f64>::new(s);
    let omega0 = s.omega0_sq().sqrt();
    let (mw, p2w) = (s.mass_ratio() * omega0, s.p() * s.p() / omega0);
    let f = k.eval::<Libm>(1.0 / rate);
    let psi = [
        f.ecm as f32,
        (-p2w * f.es) as f32,
        (mw * f.es) as f32,
        f.ecp as f32,
    ];
    let cf = DuhamelClosedForm::new(s);
    let gmu = s.gmu();
    let (mut w0, mut w1, mut level) = (0.0f32, 0.0f32, 0.0f64);
    let (mut next, mut max_err, mut peak) = (0usize, 0.0f64, 0.0f64);
    for i in 0..n {
        let t = i as f64 / rate;
        while let Some(r) = train.get(next) {
            if r.time_s > t {
                break;
            }
            let g = -(r.level - level) * gmu;
            let e = k.eval::<Libm>(t - r.time_s);
            w0 += (g * e.ecm) as f32;
            w1 += (g * mw * e.es) as f32;
            level = r.level;
            next += 1;
        }
        let y = (level * gmu) as f32 + w0;
        if i % stride == 0 {
            let want = cf.accel(train, t);
            peak = max_finite(peak, want.abs(), "closed form |ü1|", i);
            max_err = max_finite(max_err, (y as f64 - want).abs(), "naive error", i);
        }
        let (a, b) = (psi[0] * w0 + psi[1] * w1, psi[2] * w0 + psi[3] * w1);
        w0 = a;
        w1 = b;
    }
    max_err / gmu.max(peak)
}

#[test]
fn naive_f32_recursion_misses_the_bound_where_predicted() {
    let t1 = |xi| structure(29.5, 1.75, 7.0, xi);
    let damped = naive_max_error(&t1(0.05), 1e4, &paper_train(0.0715), 200_000, 7);
    let undamped = naive_max_error(&t1(0.0), 1e4, &paper_train(0.0715), 1_000_000, 101);
    let mhz = naive_max_error(&t1(0.05), 1e6, &paper_train(0.0715), 2_000_000, 37);
    let s = t1(0.001);
    let half = std::f64::consts::PI / s.n().unwrap();
    let resonant = naive_max_error(&s, 1e4, &paper_train(half), 200_000, 3);
    println!(
        "naive f32: damped {damped:.3e}, undamped {undamped:.3e}, 1 MHz {mhz:.3e}, resonant {resonant:.3e}"
    );
    assert!(damped < 1e-5, "naive damped {damped:e}");
    assert!(undamped > 1e-5 && mhz > 1e-5 && resonant > 1e-5);
}
