//! The simulation: [`simulate`] walks the run piece by piece (one phase under one smooth forcing),
//! locates each event, applies the transition (breakaway, stick, reversal) and keeps the pieces of
//! the resulting [`Truth`].

use super::events::scan;
use super::forcing::segments;
use super::input::{TruthError, TruthInput};
use super::integrate::next_step;
use super::model::Model;
use super::phase::{Direction, Event, EventKind, Phase};
use super::piece::{Piece, State};
use super::response::Truth;
use super::roots::{brent, time_tol};
use super::sampler::rest_sample;
use super::MAX_EVENTS;
use ssvr_core::FrictionLaw;

/// Consecutive events at the same instant after which the solver gives up (no progress).
const MAX_EVENTS_AT_ONE_INSTANT: usize = 16;

/// Run the exact stick-slip simulation.
pub fn simulate(input: &TruthInput<'_>) -> Result<Truth, TruthError> {
    let s = input.structure;
    let duration = input.duration_s;
    if !(duration.is_finite() && duration > 0.0) {
        return Err(TruthError::Duration(duration));
    }
    let law = match input.friction {
        FrictionLaw::Coulomb => FrictionLaw::Coulomb,
        FrictionLaw::VelocityDependent { mu_slow, rate_s_m } => {
            FrictionLaw::velocity_dependent(mu_slow, rate_s_m, s.mu())
                .map_err(TruthError::Friction)?
        }
    };
    let at_rest = law.at_rest(s.mu());
    let mu_static = input.mu_static.unwrap_or(at_rest);
    if !(mu_static.is_finite() && mu_static >= at_rest) {
        return Err(TruthError::StaticFriction {
            mu_static,
            mu: at_rest,
        });
    }
    let segs = segments(input.table)?;
    let m = Model::new(s, mu_static, input.table, law, input.integrate_sliding);
    // The integrated sliding phases' next step (s).
    let mut h_next = m.h_slide / 16.0;

    let mut pieces: Vec<Piece> = Vec::new();
    let mut events: Vec<Event> = Vec::new();
    let mut peak_top = (0.0f64, 0.0f64);
    let mut max_abs_slip = 0.0f64;
    let mut t = 0.0f64;
    let mut state = State::default();
    let mut phase = Phase::Stuck;
    let mut soft = false;
    let mut seg_idx = 0usize;
    let mut same_instant = 0usize;
    let mut last_transition = 0.0f64;

    while t < duration {
        while seg_idx + 1 < segs.len() && segs[seg_idx].end <= t {
            seg_idx += 1;
        }
        let seg = segs[seg_idx];
        let mut t_end = seg.end.min(duration);
        let piece = Piece {
            t0: t,
            phase,
            state,
            forcing: seg.forcing.shifted(t - seg.start),
        };
        if let (true, Some(dir)) = (m.integrated, phase.direction()) {
            // One accepted step of the integration is one piece.
            let floor = 8.0 * f64::EPSILON * t.abs().max(m.h_fast);
            let proposed = h_next.min(m.h_slide);
            let mut h = proposed.min(t_end - t).max(floor);
            loop {
                let e = piece.step_error(&m, dir, h);
                if !e.is_finite() {
                    return Err(TruthError::NotFinite { time_s: t });
                }
                if e <= 1.0 || h <= floor {
                    // A step cut short by the segment's end does not shrink the next one.
                    h_next = if h < proposed && e <= 1.0 {
                        proposed.max(next_step(h, e))
                    } else {
                        next_step(h, e)
                    };
                    break;
                }
                h = next_step(h, e).max(floor);
            }
            t_end = (t + h).min(t_end);
        }
        let len = t_end - t;
        let age0 = t - last_transition;
        let sc = scan(&piece, &m, len, soft, age0);
        let tau_end = sc.event.unwrap_or(len);
        let end = piece.eval(&m, tau_end);
        if !(end.delta.is_finite()
            && end.delta_dot.is_finite()
            && end.slip.is_finite()
            && end.slip_vel.is_finite()
            && end.top.is_finite())
        {
            return Err(TruthError::NotFinite { time_s: t });
        }
        let t_next = match sc.event {
            Some(tau_e) => t + tau_e,
            None => t_end,
        };
        if sc.event.is_some() {
            // A new phase starts: the integration restarts with a small step.
            h_next = m.h_slide / 16.0;
        }
        if t_next > t {
            let (pk, at) = piece_peak(&piece, &m, tau_end, age0);
            if pk > peak_top.0 {
                peak_top = (pk, t + at);
            }
            pieces.push(piece);
            same_instant = 0;
        }
        max_abs_slip = max_abs_slip.max(end.slip.abs());
        state = State {
            delta: end.delta,
            delta_dot: end.delta_dot,
            slip: end.slip,
            slip_vel: end.slip_vel,
        };
        if sc.event.is_none() {
            t = t_next;
            soft = !sc.armed;
            continue;
        }
        let te = t_next;
        last_transition = te;
        same_instant += 1;
        if same_instant > MAX_EVENTS_AT_ONE_INSTANT || events.len() >= MAX_EVENTS {
            return Err(TruthError::TooManyEvents { time_s: te });
        }
        state.slip_vel = 0.0;
        match phase.direction() {
            None => {
                let direction = Direction::pushed_by(end.f_req);
                events.push(Event {
                    time_s: te,
                    kind: EventKind::SlipStart { direction },
                });
                phase = Phase::sliding(direction);
                soft = true;
            }
            Some(dir) => {
                // Stopped: stick, or slide on if the holding force exceeds μs F0 (or is at the
                // threshold and growing).
                let excess = end.f_req.abs() - m.fs;
                let outward = end.f_req.signum() * end.f_req_dot_stuck > 0.0;
                let slides = excess > m.tol_f || (excess >= -m.tol_f && outward);
                if !slides {
                    events.push(Event {
                        time_s: te,
                        kind: EventKind::Stick,
                    });
                    phase = Phase::Stuck;
                    soft = excess >= -m.tol_f;
                } else {
                    let new_direction = Direction::pushed_by(end.f_req);
                    if new_direction == dir.opposite() {
                        events.push(Event {
                            time_s: te,
                            kind: EventKind::Reversal { new_direction },
                        });
                    }
                    // Same direction: the slip velocity only touched zero; slide on.
                    phase = Phase::sliding(new_direction);
                    soft = true;
                }
            }
        }
        t = te;
    }

    let model = m;
    let mut truth = Truth {
        model,
        pieces,
        events,
        duration_s: duration,
        mu_ratio: mu_static / s.mu(),
        peak_top,
        max_abs_slip,
        final_sample: rest_sample(0.0),
    };
    if truth.pieces.is_empty() {
        // Only possible through zero-length pieces; keep a valid (rest) piece.
        truth.pieces.push(Piece {
            t0: 0.0,
            phase: Phase::Stuck,
            state: State::default(),
            forcing: segs[0].forcing,
        });
    }
    truth.final_sample = truth.sample(duration).unwrap_or(rest_sample(duration));
    truth.max_abs_slip = truth.max_abs_slip.max(truth.final_sample.slip_m.abs());
    Ok(truth)
}

/// Peak |ü1| on [0, len] of a piece: grid values and every zero of the jerk.
fn piece_peak(piece: &Piece, m: &Model, len: f64, age0: f64) -> (f64, f64) {
    let at = |x: f64| {
        let e = piece.eval(m, x);
        (e.top, e.jerk)
    };
    let (u0, j0) = at(0.0);
    let mut best = (u0.abs(), 0.0);
    let (mut ta, mut ja) = (0.0, j0);
    loop {
        let tb = (ta + m.grid_step(piece.phase, age0 + ta)).min(len);
        let (ub, jb) = at(tb);
        if ub.abs() > best.0 {
            best = (ub.abs(), tb);
        }
        if (ja > 0.0 && jb < 0.0) || (ja < 0.0 && jb > 0.0) {
            let tm = brent(|x| at(x).1, ta, ja, tb, jb, time_tol(piece.t0, tb)).0;
            let um = at(tm).0.abs();
            if um > best.0 {
                best = (um, tm);
            }
        }
        if tb >= len {
            return best;
        }
        (ta, ja) = (tb, jb);
    }
}
