//! A [`Piece`]: one interval of one contact phase under one smooth table forcing, and everything
//! evaluated on it at a local time (drift, slip, ü1, jerk, friction, the event function). The
//! closed-form propagation of each phase is in [`super::stuck`] and [`super::sliding`].

use super::forcing::Forcing;
use super::model::Model;
use super::phase::Phase;

/// The continuous state at the start of a piece.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(super) struct State {
    pub(super) delta: f64,
    pub(super) delta_dot: f64,
    pub(super) slip: f64,
    pub(super) slip_vel: f64,
}

/// Everything evaluated at one instant of a piece.
#[derive(Debug, Clone, Copy)]
pub(super) struct Eval {
    pub(super) delta: f64,
    pub(super) delta_dot: f64,
    pub(super) slip: f64,
    pub(super) slip_vel: f64,
    pub(super) ug: f64,
    /// ü1.
    pub(super) top: f64,
    /// dü1/dt.
    pub(super) jerk: f64,
    /// Friction that would hold the base: m1 ü1 + m2 ü_g (N).
    pub(super) f_req: f64,
    /// d f_req/dt under the stuck dynamics (N/s).
    pub(super) f_req_dot_stuck: f64,
    /// Friction actually acting (N).
    pub(super) friction: f64,
    /// ẍ2.
    pub(super) slip_acc: f64,
}

/// An interval of one phase and one smooth table forcing, from t0 to the next piece's t0.
#[derive(Debug, Clone, Copy)]
pub(super) struct Piece {
    pub(super) t0: f64,
    pub(super) phase: Phase,
    pub(super) state: State,
    pub(super) forcing: Forcing,
}

impl Piece {
    pub(super) fn eval(&self, m: &Model, tau: f64) -> Eval {
        let (ug, ug_dot) = self.forcing.accel(self.t0, tau);
        let s0 = self.state;
        let (delta, delta_dot, slip, slip_vel) = match self.phase.direction() {
            None => {
                let (y, yd) = self.stuck_drift(m, tau);
                (y, yd, s0.slip, 0.0)
            }
            Some(dir) => self.sliding_state(m, dir, tau),
        };
        let top = -(m.two_xi_p * delta_dot + m.p2 * delta);
        let f_req = m.m1 * top + m.m2 * ug;
        // δ'' under each dynamics, then the jerk dü1/dt = −(2pξ δ'' + p² δ').
        let jerk_of = |dd: f64| -(m.two_xi_p * dd + m.p2 * delta_dot);
        let jerk_stuck = jerk_of(top - ug);
        let f_req_dot_stuck = m.m1 * jerk_stuck + m.m2 * ug_dot;
        let (jerk, friction, slip_acc) = match self.phase.direction() {
            None => (jerk_stuck, f_req, 0.0),
            Some(dir) => {
                let force = if m.integrated {
                    m.sliding_force(dir.sign(), slip_vel)
                } else {
                    -dir.sign() * m.f0
                };
                (
                    jerk_of(m.mass_ratio * top - force / m.m2),
                    force,
                    (force - f_req) / m.m2,
                )
            }
        };
        Eval {
            delta,
            delta_dot,
            slip,
            slip_vel,
            ug,
            top,
            jerk,
            f_req,
            f_req_dot_stuck,
            friction,
            slip_acc,
        }
    }

    /// The event function and its derivative: crossing above 0 is the event (breakaway when stuck,
    /// stop when sliding).
    pub(super) fn event_fn(&self, m: &Model, tau: f64) -> (f64, f64) {
        let e = self.eval(m, tau);
        match self.phase.direction() {
            None => {
                let sg = if e.f_req >= 0.0 { 1.0 } else { -1.0 };
                (e.f_req.abs() - m.fs, sg * e.f_req_dot_stuck)
            }
            Some(d) => (-d.sign() * e.slip_vel, -d.sign() * e.slip_acc),
        }
    }
}
