//! The table acceleration as pieces of smooth [`Forcing`] (affine between record samples, or one
//! sinusoid), with the exact integrals the sliding phase needs.

use super::input::TruthError;
use crate::table_motion::TableMotion;
use std::f64::consts::PI;

/// Table acceleration on one piece, as a function of the local time τ = t − t0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Forcing {
    /// ü_g = u0 + u1 τ.
    Affine { u0: f64, u1: f64 },
    /// ü_g = amp · sin(ω (t0 + τ) − phase) (phase = ω·start for an input that starts late).
    Harmonic { amp: f64, omega: f64, phase: f64 },
}

impl Forcing {
    pub(super) const ZERO: Forcing = Forcing::Affine { u0: 0.0, u1: 0.0 };

    /// (ü_g, dü_g/dt) at τ.
    pub(super) fn accel(&self, t0: f64, tau: f64) -> (f64, f64) {
        match *self {
            Forcing::Affine { u0, u1 } => (u0 + u1 * tau, u1),
            Forcing::Harmonic { amp, omega, phase } => {
                let (s, c) = (omega * (t0 + tau) - phase).sin_cos();
                (amp * s, amp * omega * c)
            }
        }
    }

    /// (D1, D2): ∫ü_g and its integral from t0 to t0 + τ (table velocity and displacement gained).
    pub(super) fn integrals(&self, t0: f64, tau: f64) -> (f64, f64) {
        match *self {
            Forcing::Affine { u0, u1 } => (
                tau * (u0 + 0.5 * u1 * tau),
                tau * tau * (0.5 * u0 + u1 * tau / 6.0),
            ),
            Forcing::Harmonic { amp, omega, phase } => {
                // cos a − cos b = 2 sin((a+b)/2) sin((b−a)/2), sin b − sin a = 2 cos((a+b)/2) sin((b−a)/2).
                let half = (0.5 * omega * tau).sin();
                let mid = omega * (t0 + 0.5 * tau) - phase;
                let (sm, cm) = mid.sin_cos();
                let d1 = 2.0 * amp / omega * sm * half;
                let d2 = amp / omega * ((omega * t0 - phase).cos() * tau - 2.0 * cm * half / omega);
                (d1, d2)
            }
        }
    }

    /// The same forcing with its local time origin moved by `shift` (affine only; harmonic uses
    /// absolute time).
    pub(super) fn shifted(&self, shift: f64) -> Forcing {
        match *self {
            Forcing::Affine { u0, u1 } => Forcing::Affine {
                u0: u0 + u1 * shift,
                u1,
            },
            h => h,
        }
    }
}

/// A stretch of time on which the table acceleration is one smooth function.
#[derive(Debug, Clone, Copy)]
pub(super) struct Segment {
    pub(super) start: f64,
    pub(super) end: f64,
    /// Forcing with τ measured from `start`.
    pub(super) forcing: Forcing,
}

/// The table acceleration cut into [`Segment`]s from t = 0 on (a record: zero before its first
/// sample, linear between samples, zero after its last), after checking the motion.
pub(super) fn segments(table: &TableMotion) -> Result<Vec<Segment>, TruthError> {
    let whole = |forcing| {
        Ok(vec![Segment {
            start: 0.0,
            end: f64::INFINITY,
            forcing,
        }])
    };
    match table {
        TableMotion::None => whole(Forcing::ZERO),
        TableMotion::Harmonic {
            amplitude_m_s2,
            period_s,
        } => {
            let (amp, period) = (*amplitude_m_s2, *period_s);
            let omega = 2.0 * PI / period;
            if !(amp.is_finite() && period.is_finite() && period > 0.0 && omega.is_finite()) {
                return Err(TruthError::Harmonic {
                    amplitude_m_s2: amp,
                    period_s: period,
                });
            }
            whole(Forcing::Harmonic {
                amp,
                omega,
                phase: 0.0,
            })
        }
        TableMotion::Delayed { start_s, motion } => {
            let start = *start_s;
            if !(start.is_finite() && start >= 0.0) {
                return Err(TruthError::Start { start_s: start });
            }
            // Zero until `start`, then the motion's own segments, `start` later.
            let mut out = vec![Segment {
                start: 0.0,
                end: start,
                forcing: Forcing::ZERO,
            }];
            for seg in segments(motion)? {
                out.push(Segment {
                    start: seg.start + start,
                    end: seg.end + start,
                    forcing: match seg.forcing {
                        Forcing::Harmonic { amp, omega, phase } => Forcing::Harmonic {
                            amp,
                            omega,
                            phase: phase + omega * start,
                        },
                        affine => affine,
                    },
                });
            }
            Ok(out.into_iter().filter(|s| s.end > s.start).collect())
        }
        TableMotion::Record {
            times_s,
            accel_m_s2,
        } => {
            if times_s.len() != accel_m_s2.len() {
                return Err(TruthError::RecordLengths {
                    times: times_s.len(),
                    accels: accel_m_s2.len(),
                });
            }
            for (i, (t, a)) in times_s.iter().zip(accel_m_s2).enumerate() {
                if !(t.is_finite() && a.is_finite()) {
                    return Err(TruthError::RecordNotFinite { index: i });
                }
                if i > 0 && *t <= times_s[i - 1] {
                    return Err(TruthError::RecordNotIncreasing { index: i });
                }
            }
            let n = times_s.len();
            if n < 2 {
                return whole(Forcing::ZERO);
            }
            // Zero before the first sample, linear between samples, zero after the last.
            let mut raw = Vec::with_capacity(n + 1);
            raw.push(Segment {
                start: f64::NEG_INFINITY,
                end: times_s[0],
                forcing: Forcing::ZERO,
            });
            for k in 0..n - 1 {
                let (t0, t1) = (times_s[k], times_s[k + 1]);
                let slope = (accel_m_s2[k + 1] - accel_m_s2[k]) / (t1 - t0);
                if !slope.is_finite() {
                    return Err(TruthError::RecordNotFinite { index: k + 1 });
                }
                raw.push(Segment {
                    start: t0,
                    end: t1,
                    forcing: Forcing::Affine {
                        u0: accel_m_s2[k],
                        u1: slope,
                    },
                });
            }
            raw.push(Segment {
                start: times_s[n - 1],
                end: f64::INFINITY,
                forcing: Forcing::ZERO,
            });
            Ok(raw
                .into_iter()
                .filter(|s| s.end > 0.0)
                .map(|s| {
                    if s.start < 0.0 {
                        Segment {
                            start: 0.0,
                            end: s.end,
                            forcing: if s.start.is_finite() {
                                s.forcing.shifted(-s.start)
                            } else {
                                s.forcing
                            },
                        }
                    } else {
                        s
                    }
                })
                .collect())
        }
    }
}
