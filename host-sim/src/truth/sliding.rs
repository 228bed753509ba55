//! Closed-form propagation of a sliding phase: the drift δ by the exact free vibration of eq (25)
//! about the sliding equilibrium, the centre of mass by the exact integrals of the table motion
//! (Coulomb friction); under a velocity-dependent law, one step of [`super::integrate`].

use super::model::Model;
use super::phase::Direction;
use super::piece::Piece;
use ssvr_core::math::Libm;

impl Piece {
    /// Exact (δ, δ', x2, ẋ2) at local time τ of a piece sliding in direction `dir`, from the
    /// piece's initial state.
    pub(super) fn sliding_state(
        &self,
        m: &Model,
        dir: Direction,
        tau: f64,
    ) -> (f64, f64, f64, f64) {
        if m.integrated {
            let (y, _) = self.integrate(m, dir, tau);
            return (y[0], y[1], y[2], y[3]);
        }
        let s0 = self.state;
        let s = dir.sign();
        let eq = s * m.delta_eq;
        let fv = m.kernel.eval::<Libm>(tau);
        let d0 = s0.delta - eq;
        let delta = eq + fv.ecp * d0 + fv.es * s0.delta_dot;
        let delta_dot = -m.omega0_sq * fv.es * d0 + fv.ecm * s0.delta_dot;
        // Centre of mass relative to the table: X'' = F/(m1+m2) − ü_g.
        let (d1, d2) = self.forcing.integrals(self.t0, tau);
        let x0 = s0.slip + m.r * s0.delta;
        let v0 = s0.slip_vel + m.r * s0.delta_dot;
        let a_cm = -s * m.f0 / m.m_total;
        let vx = v0 + a_cm * tau - d1;
        let xx = x0 + tau * (v0 + 0.5 * a_cm * tau) - d2;
        (delta, delta_dot, xx - m.r * delta, vx - m.r * delta_dot)
    }
}
