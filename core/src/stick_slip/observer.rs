//! The stuck-phase observer: its per-sample gain and the measurement correction of a state.

use super::coefficients::StickSlipCoefficients;
use crate::math::{Real, Transcendentals};

/// The stuck-phase observer's per-sample gain for a bandwidth of `b`·p, in the estimator's state
/// coordinates (ü1, pδ'). In z = (p²δ, pδ') a stuck interval maps the error e by the fixed-base
/// transition Φ; the measurement ü1 = c·z, c = (−1, −2ξ); the correction z += G·(ü1_pred −
/// ü1_meas) at the interval's start makes it e ← Φ(I + G·c)e. G is placed so that this map has a
/// double eigenvalue ρ = e^(−b·p·Δt) (the exact discrete counterpart of critically damped error
/// dynamics at b·p, stable at any sampling): trace 2ρ and determinant ρ², i.e.
/// c·G = ρ²/det Φ − 1 and c·Φ·G = 2ρ − tr Φ. Mapped to (ü1, pδ'): Δü1 = −(ΔG0 + 2ξΔG1).
pub(super) fn observer_gain<T: Real, M: Transcendentals<T>>(
    c: &StickSlipCoefficients<T>,
    b: f64,
) -> [T; 2] {
    if b.is_nan() || b <= 0.0 {
        return [T::ZERO; 2];
    }
    let (p, two_xi, dt) = (c.p.to_f64(), c.two_xi.to_f64(), c.dt.to_f64());
    let f = c.kf.eval::<M>(c.dt);
    let (ecp, es, ecm) = (f.ecp.to_f64(), f.es.to_f64(), f.ecm.to_f64());
    let phi = [ecp, p * es, -p * es, ecm];
    let rho = libm::exp(-b * p * dt);
    let (tr, det_phi) = (phi[0] + phi[3], phi[0] * phi[3] - phi[1] * phi[2]);
    let cv = [-1.0, -two_xi];
    let cphi = [
        cv[0] * phi[0] + cv[1] * phi[2],
        cv[0] * phi[1] + cv[1] * phi[3],
    ];
    let rhs = [rho * rho / det_phi - 1.0, 2.0 * rho - tr];
    let det = cv[0] * cphi[1] - cv[1] * cphi[0];
    let g0 = (rhs[0] * cphi[1] - cv[1] * rhs[1]) / det;
    let g1 = (cv[0] * rhs[1] - cphi[0] * rhs[0]) / det;
    if !(g0.is_finite() && g1.is_finite()) {
        return [T::ZERO; 2];
    }
    [T::from_f64(-(g0 + two_xi * g1)), T::from_f64(g1)]
}

/// The measurement correction of the state `z` (ü1 first) of a sample that starts a stuck
/// interval, with the sample's measured top acceleration `y` (none if not finite): the stored
/// state stays the prediction, the interval starts from the corrected one.
#[inline(always)]
pub(super) fn correct<T: Real>(gain: [T; 2], z: [T; 2], y: T) -> [T; 2] {
    if y.is_finite() {
        let r = z[0] - y;
        [z[0] + gain[0] * r, z[1] + gain[1] * r]
    } else {
        z
    }
}
