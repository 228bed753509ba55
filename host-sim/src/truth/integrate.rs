//! Sliding phases under a velocity-dependent friction law: no closed form, so the state
//! (δ, δ', x2, ẋ2) is integrated by the Dormand–Prince 5(4) pair with error control (by Rodas5
//! when the phases are stiff: [`super::stiff`]).
//!
//! # Dense output
//!
//! A piece of such a phase is one accepted step of length h. Its state at any τ ∈ [0, h] is the
//! 5th-order Dormand–Prince solution of *one step of length τ* from the piece's initial state:
//! a continuous extension of order 5 whose local error, ∝ τ⁵, is below the step's controlled
//! error, and which equals the accepted step's result at τ = h exactly (so the next piece starts
//! from the very state this one ends in). Events (the base stops: ẋ2 = 0) are located on it by
//! the same walk and Brent refinement as on the closed forms ([`super::events`]).
//!
//! # Equations (sliding in direction s = ±1, table acceleration ü_g)
//!
//! ```text
//! ü1  = −(2ξp δ' + p² δ)
//! F   = −s·μ(s·ẋ2)·(m1+m2)·g,   μ(v) = μ_fast − (μ_fast − μ_slow)·e^{−a v}
//! ẍ2  = (F − m1 ü1)/m2 − ü_g
//! δ'' = ü1 − ü_g − ẍ2
//! ```
//!
//! μ is evaluated at the signed speed s·ẋ2 (smooth through 0, where a step can overshoot the
//! stop by rounding), not at |ẋ2|.
//!
//! # Error control
//!
//! Each component's error estimate is scaled by `TOL·(|y| + its unit)` (units gμ/p² for δ and
//! x2, gμ/p for the velocities) and the max norm kept ≤ 1; steps are also at most the sliding
//! grid step of the event walk (64 per fastest period). With `TOL` = 1e-13 the Coulomb limits
//! reproduce the closed-form truth to ~1e-11 of the peak (tests/truth_friction.rs).

use super::model::Model;
use super::phase::Direction;
use super::piece::Piece;

/// Relative tolerance of a step (per component, max norm).
pub(super) const TOL: f64 = 1e-13;

const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
/// 5th-order weights (the last stage row of `A`, FSAL).
const B: [f64; 7] = [
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
    0.0,
];
/// 5th minus 4th order weights: the error estimate.
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

type Y = [f64; 4];

impl Model {
    /// The friction force (N) sliding in direction `s` at slip velocity `v`.
    pub(super) fn sliding_force(&self, s: f64, v: f64) -> f64 {
        // μ at the signed speed s·v; the exponent is clamped (an overshoot of the stop by far more
        // than rounding cannot happen inside a located phase).
        let x = (-self.rate * s * v).min(50.0);
        -s * (self.mu_fast - self.mu_drop * x.exp()) * self.normal
    }

    pub(super) fn rhs(&self, s: f64, y: &Y, ug: f64) -> Y {
        let top = -(self.two_xi_p * y[1] + self.p2 * y[0]);
        let f = self.sliding_force(s, y[3]);
        let x2dd = (f - self.m1 * top) / self.m2 - ug;
        [y[1], top - ug - x2dd, y[3], x2dd]
    }
}

impl Piece {
    /// One Dormand–Prince step of length `tau` from the piece's initial state, sliding in
    /// direction `dir`: the 5th-order state and the error estimate (5th − 4th order).
    pub(super) fn dopri(&self, m: &Model, dir: Direction, tau: f64) -> (Y, Y) {
        let s = dir.sign();
        let s0 = self.state;
        let y0 = [s0.delta, s0.delta_dot, s0.slip, s0.slip_vel];
        let mut k = [[0.0; 4]; 7];
        for i in 0..7 {
            let mut y = y0;
            for (j, kj) in k.iter().enumerate().take(i) {
                let a = A[i][j];
                if a != 0.0 {
                    for c in 0..4 {
                        y[c] += tau * a * kj[c];
                    }
                }
            }
            let ug = self.forcing.accel(self.t0, C[i] * tau).0;
            k[i] = m.rhs(s, &y, ug);
        }
        let mut y = y0;
        let mut err = [0.0; 4];
        for i in 0..7 {
            for c in 0..4 {
                y[c] += tau * B[i] * k[i][c];
                err[c] += tau * E[i] * k[i][c];
            }
        }
        (y, err)
    }

    /// One step of length `tau` of the model's method: Dormand–Prince, or Rodas5 when the
    /// sliding phases are stiff ([`super::stiff`]).
    pub(super) fn integrate(&self, m: &Model, dir: Direction, tau: f64) -> (Y, Y) {
        if m.stiff {
            self.rodas(m, dir, tau)
        } else {
            self.dopri(m, dir, tau)
        }
    }

    /// The scaled error norm of a step of length `h` (≤ 1: accept).
    pub(super) fn step_error(&self, m: &Model, dir: Direction, h: f64) -> f64 {
        let (y, err) = self.integrate(m, dir, h);
        let s0 = self.state;
        let y0 = [s0.delta, s0.delta_dot, s0.slip, s0.slip_vel];
        let unit = [m.disp_unit, m.vel_unit, m.disp_unit, m.vel_unit];
        (0..4)
            .map(|c| err[c].abs() / (TOL * (unit[c] + y0[c].abs().max(y[c].abs()))))
            // (A NaN error stays NaN: `f64::max` would drop it and accept the step.)
            .fold(0.0, |acc, x| if x > acc || x.is_nan() { x } else { acc })
    }
}

/// The next step after one with error norm `e` (accepted or not): the usual safety factor 0.9
/// and the 5th-order exponent, changes limited to [0.2, 5].
pub(super) fn next_step(h: f64, e: f64) -> f64 {
    let factor = if e == 0.0 {
        5.0
    } else {
        (0.9 * e.powf(-0.2)).clamp(0.2, 5.0)
    };
    h * factor
}
