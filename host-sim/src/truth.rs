//! The exact Coulomb stick-slip "truth": eq (1)-(2) of the paper, solved relative to the moving table
//! with true (non-regularised) Coulomb friction and every stick, slip and reversal event located by
//! root finding.
//!
//! # Model
//!
//! Coordinates are relative to the table: x2 is the slip of the base, x1 the displacement of the top
//! mass, δ = x1 − x2 the storey drift; ü_g is the table acceleration. With K = m1 p², C = 2 m1 p ξ:
//!
//! ```text
//! m1 (ẍ1 + ü_g) + C(ẋ1 − ẋ2) + K(x1 − x2) = 0
//! m2 (ẍ2 + ü_g) − C(ẋ1 − ẋ2) − K(x1 − x2) = F
//! ```
//!
//! F is the friction force on the base (positive along +x). The absolute top acceleration is always
//! ü1 = −(2pξ δ' + p² δ) (eq 23 / m1), and F = m1 ü1 + m2 ü2 (eq 4).
//!
//! * **Stuck** (ẋ2 = 0): the base moves with the table, so δ obeys the fixed-base oscillator
//!   δ'' + 2ξp δ' + p² δ = −ü_g, and the friction needed to hold the base is F_req = m1 ü1 + m2 ü_g.
//!   The base stays stuck while |F_req| ≤ μs F0, F0 = μ (m1+m2) g.
//! * **Sliding** in direction s = ±1 (sign of ẋ2): F = −s F0. δ obeys eq (25),
//!   δ'' + 2Mpξ δ' + Mp² δ = −F/m2 (independent of the table), and the centre of mass relative to the
//!   table obeys X'' = F/(m1+m2) − ü_g; the slip is x2 = X − m1 δ/(m1+m2).
//!
//! Events: a stuck base breaks away when |F_req| exceeds μs F0, in the direction −sign(F_req) (the way
//! the net force pushes it). A sliding base stops when ẋ2 reaches 0; it then sticks if
//! |F_req| ≤ μs F0, otherwise it reverses. At t = 0 the structure is at rest relative to the table
//! with the base stuck.
//!
//! # Exactness
//!
//! Between events the motion is linear with constant friction and is propagated in closed form:
//!
//! * the sliding drift δ by the exact free vibration of `ssvr_core::closed_form::free_vibration::Kernel` (all three
//!   damping regimes), the centre of mass by exact polynomial / trigonometric integrals of ü_g;
//! * the stuck (fixed-base) drift by the exact homogeneous solution plus, for a record segment (ü_g
//!   linear in time), the exact polynomial particular solution, or, for harmonic input, the exact
//!   Duhamel integral of the sinusoid written with φ1(z) = (eᶻ − 1)/z, which stays exact at resonance
//!   even for ξ = 0.
//!
//! Events are bracketed on a grid of 64 points per shortest time scale of the phase (stuck: p and the
//! input frequency; sliding: also the drift's ω0, or for an overdamped drift its slow rate, with a
//! geometric refinement down to the fast rate a + ν right after each transition). A crossing hidden
//! between two grid points shows as a sign change of the event function's analytic derivative; the
//! extremum is then located and tested. Roots are refined by Brent's method to ~1e-15 s (a few ulp
//! of t), and an event is placed on the side where the threshold is already crossed, so the new phase
//! starts consistently. Right after a transition the event function is ≈ 0; it is followed on a fine
//! sub-grid until it is clearly on the allowed side, which handles grazing transitions (e.g. a
//! breakaway with μs = μ starts with zero slip acceleration).
//!
//! The only errors are rounding errors: against an independent RK4 integration at dt = 1e-6 s the
//! top acceleration agrees to ~3e-13 gμ and event times to ~1e-14 s (tests/truth_vs_rk4.rs).
//!
//! Limits:
//! * excursions within rounding tolerances are ignored: a slide whose slip velocity never exceeds
//!   1e-13·gμ/p (a few ns long even when it starts with zero acceleration), or a holding force that
//!   touches the threshold by less than 1e-11·μs F0 right after a stick;
//! * a slip velocity that touches zero and recovers in the same direction is followed without an
//!   event; several events at the same instant are possible (e.g. at a jump of a record) and the
//!   solver gives up with [`TruthError::TooManyEvents`] after 16 without progress;
//! * the stuck response to harmonic input loses precision as 1/√(1 − ξ²) for ξ → 1;
//! * cost: one closed-form evaluation per grid point, i.e. O(duration · fastest rate) plus a few dozen
//!   per event (a light base with little damping, M ≫ 1, has a fast sliding drift ω0 = p√M).
//!
//! # Conventions
//!
//! The table acceleration is taken right-continuous at record samples (zero from the last sample
//! on); a sample at an event time shows the state just after the event. ü1 and the slip are
//! continuous at every event; the base acceleration jumps.
//!
//! # Use
//!
//! ```
//! use host_sim::{table_motion::TableMotion, truth::{simulate, TruthInput}};
//! use ssvr_core::{Structure, StructureParams};
//!
//! let s = Structure::new(StructureParams {
//!     m1_kg: 29.5,
//!     m2_kg: 1.75,
//!     natural_frequency_hz: 7.0,
//!     damping_ratio: 0.05,
//!     friction_coefficient: 0.2,
//!     gravity_m_s2: 9.80665,
//! })
//! .unwrap();
//! let table = TableMotion::Harmonic { amplitude_m_s2: 2.0, period_s: 0.143 };
//! let truth = simulate(&TruthInput::new(&s, &table, 2.0).with_static_friction(0.25)).unwrap();
//! let mut cursor = truth.sampler();
//! for k in 0..=2000 {
//!     let sample = cursor.sample(k as f64 * 1e-3).unwrap();
//!     assert!(sample.top_accel_m_s2.abs() <= truth.peak_top_accel_m_s2() * (1.0 + 1e-12));
//! }
//! assert!(truth.slip_phases() > 0);
//! ```

use crate::table_motion::TableMotion;
use core::fmt;
use ssvr_core::closed_form::free_vibration::Kernel;
use ssvr_core::math::Libm;
use ssvr_core::{Regime, Reversal, Structure};
use std::f64::consts::PI;

/// Maximum number of events of one simulation (a guard against pathological chattering).
pub const MAX_EVENTS: usize = 10_000_000;

/// Grid points per shortest time scale (2π/ω of the fastest frequency or rate) for event bracketing.
const GRID_PER_PERIOD: f64 = 64.0;

/// Consecutive events at the same instant after which the solver gives up (no progress).
const MAX_EVENTS_AT_ONE_INSTANT: usize = 16;

/// Inputs of [`simulate`].
#[derive(Debug, Clone, Copy)]
pub struct TruthInput<'a> {
    /// The structure (m1, m2, p, ξ, kinetic μ, g).
    pub structure: &'a Structure,
    /// Static friction coefficient μs ≥ μ (breakaway threshold μs (m1+m2) g); `None` means μs = μ.
    pub mu_static: Option<f64>,
    /// The table acceleration.
    pub table: &'a TableMotion,
    /// Simulated duration (s), finite and > 0. Past the end of a record the table is at rest.
    pub duration_s: f64,
}

impl<'a> TruthInput<'a> {
    /// Inputs with μs = μ.
    pub fn new(structure: &'a Structure, table: &'a TableMotion, duration_s: f64) -> Self {
        Self {
            structure,
            mu_static: None,
            table,
            duration_s,
        }
    }

    /// The same inputs with a static friction coefficient μs (must be ≥ μ).
    pub fn with_static_friction(mut self, mu_static: f64) -> Self {
        self.mu_static = Some(mu_static);
        self
    }
}

/// Why a simulation could not be run.
#[derive(Debug, Clone, PartialEq)]
pub enum TruthError {
    /// The duration is not finite or not > 0.
    Duration(f64),
    /// μs is not finite or below the kinetic μ.
    StaticFriction {
        /// The offending μs.
        mu_static: f64,
        /// The kinetic μ of the structure.
        mu: f64,
    },
    /// The harmonic table motion has a non-finite amplitude or a period that is not finite and > 0.
    Harmonic {
        /// Amplitude (m/s²).
        amplitude_m_s2: f64,
        /// Period (s).
        period_s: f64,
    },
    /// The record's time and acceleration arrays have different lengths.
    RecordLengths {
        /// Number of times.
        times: usize,
        /// Number of accelerations.
        accels: usize,
    },
    /// A record time or acceleration is NaN or infinite.
    RecordNotFinite {
        /// Index of the sample.
        index: usize,
    },
    /// Record times are not strictly increasing.
    RecordNotIncreasing {
        /// Index of the first time not greater than its predecessor.
        index: usize,
    },
    /// More than [`MAX_EVENTS`] events, or events that make no progress in time.
    TooManyEvents {
        /// Time reached (s).
        time_s: f64,
    },
    /// The response overflowed (inputs far outside any physical range).
    NotFinite {
        /// Time reached (s).
        time_s: f64,
    },
}

impl fmt::Display for TruthError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TruthError::Duration(d) => write!(f, "duration {d} s: expected a finite value > 0"),
            TruthError::StaticFriction { mu_static, mu } => write!(
                f,
                "static friction coefficient {mu_static}: expected a finite value >= the kinetic {mu}"
            ),
            TruthError::Harmonic {
                amplitude_m_s2,
                period_s,
            } => write!(
                f,
                "harmonic table motion (amplitude {amplitude_m_s2} m/s^2, period {period_s} s): \
                 expected a finite amplitude and a finite period > 0"
            ),
            TruthError::RecordLengths { times, accels } => write!(
                f,
                "record has {times} times but {accels} accelerations"
            ),
            TruthError::RecordNotFinite { index } => {
                write!(f, "record sample {index} is not finite")
            }
            TruthError::RecordNotIncreasing { index } => {
                write!(f, "record time {index} is not greater than the previous one")
            }
            TruthError::TooManyEvents { time_s } => write!(
                f,
                "stick-slip events do not progress in time (stopped at t = {time_s} s)"
            ),
            TruthError::NotFinite { time_s } => {
                write!(f, "the response overflowed at t = {time_s} s")
            }
        }
    }
}

impl std::error::Error for TruthError {}

/// Direction of sliding of the base relative to the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// ẋ2 > 0.
    Positive,
    /// ẋ2 < 0.
    Negative,
}

impl Direction {
    /// +1 or −1.
    pub fn sign(self) -> f64 {
        match self {
            Direction::Positive => 1.0,
            Direction::Negative => -1.0,
        }
    }

    fn opposite(self) -> Self {
        match self {
            Direction::Positive => Direction::Negative,
            Direction::Negative => Direction::Positive,
        }
    }

    /// The direction a net friction demand F_req pushes the base: −sign(F_req).
    fn pushed_by(f_req: f64) -> Self {
        if f_req > 0.0 {
            Direction::Negative
        } else {
            Direction::Positive
        }
    }
}

/// Contact state of the base.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// The base moves with the table.
    Stuck,
    /// The base slides in the +x direction relative to the table (friction level −1).
    SlidingPos,
    /// The base slides in the −x direction relative to the table (friction level +1).
    SlidingNeg,
}

impl Phase {
    fn sliding(d: Direction) -> Self {
        match d {
            Direction::Positive => Phase::SlidingPos,
            Direction::Negative => Phase::SlidingNeg,
        }
    }

    /// The sliding direction, `None` when stuck.
    pub fn direction(self) -> Option<Direction> {
        match self {
            Phase::Stuck => None,
            Phase::SlidingPos => Some(Direction::Positive),
            Phase::SlidingNeg => Some(Direction::Negative),
        }
    }
}

/// What happened at an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// A stuck base breaks away.
    SlipStart {
        /// Direction of the slide that starts.
        direction: Direction,
    },
    /// A sliding base stops and sticks.
    Stick,
    /// A sliding base stops and immediately slides back.
    Reversal {
        /// Direction of the new slide.
        new_direction: Direction,
    },
}

/// A located event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// Time (s).
    pub time_s: f64,
    /// What happened.
    pub kind: EventKind,
}

/// The exact state at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthSample {
    /// Time (s).
    pub time_s: f64,
    /// Contact state (the state just after `time_s` if an event happens exactly then).
    pub phase: Phase,
    /// Table acceleration ü_g (m/s²; right limit at a record sample).
    pub table_accel_m_s2: f64,
    /// Absolute acceleration of the base ü2 (m/s²).
    pub base_accel_m_s2: f64,
    /// Absolute acceleration of the top mass ü1 = −(2pξ δ' + p² δ) (m/s²).
    pub top_accel_m_s2: f64,
    /// Slip x2: displacement of the base relative to the table (m).
    pub slip_m: f64,
    /// Slip velocity ẋ2 (m/s).
    pub slip_velocity_m_s: f64,
    /// Storey drift δ = x1 − x2 (m).
    pub rel_disp_m: f64,
    /// Drift velocity δ' (m/s).
    pub rel_vel_m_s: f64,
    /// Friction on the base F/F0, F0 = μ(m1+m2)g: −1 sliding positive, +1 sliding negative, and while
    /// stuck the holding force m1 ü1 + m2 ü_g over F0 (within [−μs/μ, μs/μ]).
    pub friction_level: f64,
}

// ---------------------------------------------------------------------------------------------------
// Input segments
// ---------------------------------------------------------------------------------------------------

/// Table acceleration on one piece, as a function of the local time τ = t − t0.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Forcing {
    /// ü_g = u0 + u1 τ.
    Affine { u0: f64, u1: f64 },
    /// ü_g = amp · sin(ω (t0 + τ)).
    Harmonic { amp: f64, omega: f64 },
}

impl Forcing {
    const ZERO: Forcing = Forcing::Affine { u0: 0.0, u1: 0.0 };

    /// (ü_g, dü_g/dt) at τ.
    fn accel(&self, t0: f64, tau: f64) -> (f64, f64) {
        match *self {
            Forcing::Affine { u0, u1 } => (u0 + u1 * tau, u1),
            Forcing::Harmonic { amp, omega } => {
                let (s, c) = (omega * (t0 + tau)).sin_cos();
                (amp * s, amp * omega * c)
            }
        }
    }

    /// (D1, D2): ∫ü_g and its integral from t0 to t0 + τ (table velocity and displacement gained).
    fn integrals(&self, t0: f64, tau: f64) -> (f64, f64) {
        match *self {
            Forcing::Affine { u0, u1 } => (
                tau * (u0 + 0.5 * u1 * tau),
                tau * tau * (0.5 * u0 + u1 * tau / 6.0),
            ),
            Forcing::Harmonic { amp, omega } => {
                // cos a − cos b = 2 sin((a+b)/2) sin((b−a)/2), sin b − sin a = 2 cos((a+b)/2) sin((b−a)/2).
                let half = (0.5 * omega * tau).sin();
                let mid = omega * (t0 + 0.5 * tau);
                let (sm, cm) = mid.sin_cos();
                let d1 = 2.0 * amp / omega * sm * half;
                let d2 = amp / omega * ((omega * t0).cos() * tau - 2.0 * cm * half / omega);
                (d1, d2)
            }
        }
    }

    /// The same forcing with its local time origin moved by `shift` (affine only; harmonic uses
    /// absolute time).
    fn shifted(&self, shift: f64) -> Forcing {
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
struct Segment {
    start: f64,
    end: f64,
    /// Forcing with τ measured from `start`.
    forcing: Forcing,
}

fn segments(table: &TableMotion) -> Result<Vec<Segment>, TruthError> {
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
            whole(Forcing::Harmonic { amp, omega })
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

// ---------------------------------------------------------------------------------------------------
// Small complex arithmetic for the exact stuck response to a sinusoid
// ---------------------------------------------------------------------------------------------------

#[derive(Debug, Clone, Copy, PartialEq)]
struct Cx {
    re: f64,
    im: f64,
}

impl Cx {
    const fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }
    fn cis(theta: f64) -> Self {
        let (s, c) = theta.sin_cos();
        Self::new(c, s)
    }
    fn add(self, o: Self) -> Self {
        Self::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: Self) -> Self {
        Self::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: Self) -> Self {
        Self::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn scale(self, k: f64) -> Self {
        Self::new(self.re * k, self.im * k)
    }
    fn div(self, o: Self) -> Self {
        // Smith's algorithm (no overflow of |o|²).
        if o.re.abs() >= o.im.abs() {
            let r = o.im / o.re;
            let d = o.re + o.im * r;
            Self::new((self.re + self.im * r) / d, (self.im - self.re * r) / d)
        } else {
            let r = o.re / o.im;
            let d = o.re * r + o.im;
            Self::new((self.re * r + self.im) / d, (self.im * r - self.re) / d)
        }
    }
    fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }
}

/// φ1(z) = (eᶻ − 1)/z, exact near 0 (series) and through a cancellation-free eᶻ − 1 elsewhere.
fn phi1(z: Cx) -> Cx {
    if z.abs() < 0.5 {
        // 1 + z/2 (1 + z/3 (1 + …)): Σ z^k/(k+1)!, truncated where 0.5^21/22! < 1e-27.
        let mut acc = Cx::new(1.0, 0.0);
        for k in (1..=20).rev() {
            acc = Cx::new(1.0, 0.0).add(acc.mul(z).scale(1.0 / (k as f64 + 1.0)));
        }
        acc
    } else {
        let (s, c) = z.im.sin_cos();
        let half = (0.5 * z.im).sin();
        let em1 = Cx::new(z.re.exp_m1() * c - 2.0 * half * half, z.re.exp() * s);
        em1.div(z)
    }
}

// ---------------------------------------------------------------------------------------------------
// The model and its exact propagation on one piece
// ---------------------------------------------------------------------------------------------------

/// Constants of one simulation.
#[derive(Debug, Clone, Copy)]
struct Model {
    m1: f64,
    m2: f64,
    m_total: f64,
    /// m1/(m1+m2).
    r: f64,
    /// M = (m1+m2)/m2.
    mass_ratio: f64,
    p2: f64,
    two_xi_p: f64,
    /// Kinetic friction F0 = μ(m1+m2)g (N).
    f0: f64,
    /// Breakaway threshold μs(m1+m2)g (N).
    fs: f64,
    /// gμ/p² (m): the sliding equilibrium drift per unit direction.
    delta_eq: f64,
    /// Fixed-base decay rate ξp and damped frequency p√(1−ξ²).
    fb_alpha: f64,
    fb_n: f64,
    /// Sliding free vibration (eq 25).
    kernel: Kernel<f64>,
    omega0_sq: f64,
    /// Bracketing grid steps (s): stuck, sliding, and the finest sliding step right after a
    /// transition when the sliding drift is overdamped (its fast mode e^{−(a+ν)τ}).
    h_stuck: f64,
    h_slide: f64,
    h_fast: f64,
    /// Tolerances of "near the threshold": force (N) and slip velocity (m/s).
    tol_f: f64,
    tol_v: f64,
}

impl Model {
    fn new(s: &Structure, mu_static: f64, table: &TableMotion) -> Self {
        let (m1, m2, p, xi) = (s.m1(), s.m2(), s.p(), s.xi());
        let m_total = m1 + m2;
        let f0 = s.mu() * m_total * s.g();
        let fb_n = p * ((1.0 - xi) * (1.0 + xi)).sqrt();
        // Time scales: the fixed-base frequency, the input frequency and, while sliding, the drift's
        // frequency ω0 (under/critically damped) or its slow rate (overdamped); the overdamped fast
        // mode only matters for a few 1/(a+ν) after a transition and gets a geometric grid there.
        let omega_in = match table {
            TableMotion::Harmonic { period_s, .. } => 2.0 * PI / period_s,
            _ => 0.0,
        };
        let omega_stuck = p.max(omega_in);
        let (omega_slide, omega_fast) = match s.regime() {
            Regime::Overdamped => (
                omega_stuck.max(s.slow_rate()),
                omega_stuck.max(s.slow_rate()).max(s.a() + s.omega_d()),
            ),
            _ => {
                let w = omega_stuck.max(s.omega0_sq().sqrt());
                (w, w)
            }
        };
        let step = |w: f64| 2.0 * PI / (GRID_PER_PERIOD * w);
        Self {
            m1,
            m2,
            m_total,
            r: m1 / m_total,
            mass_ratio: s.mass_ratio(),
            p2: p * p,
            two_xi_p: 2.0 * xi * p,
            f0,
            fs: mu_static * m_total * s.g(),
            delta_eq: s.gmu() / (p * p),
            fb_alpha: xi * p,
            fb_n,
            kernel: Kernel::new(s),
            omega0_sq: s.omega0_sq(),
            h_stuck: step(omega_stuck),
            h_slide: step(omega_slide),
            h_fast: step(omega_fast),
            tol_f: 1e-11 * mu_static * m_total * s.g(),
            tol_v: 1e-13 * s.gmu() / p,
        }
    }

    /// Grid step at a point of a piece of `phase`, `age` seconds after the last transition: uniform,
    /// except a geometric refinement (steps of age/8, at least `h_fast`) just after an overdamped
    /// slide starts.
    fn grid_step(&self, phase: Phase, age: f64) -> f64 {
        match phase {
            Phase::Stuck => self.h_stuck,
            _ => self.h_slide.min(self.h_fast.max(0.125 * age)),
        }
    }
}

/// The continuous state at the start of a piece.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct State {
    delta: f64,
    delta_dot: f64,
    slip: f64,
    slip_vel: f64,
}

/// Everything evaluated at one instant of a piece.
#[derive(Debug, Clone, Copy)]
struct Eval {
    delta: f64,
    delta_dot: f64,
    slip: f64,
    slip_vel: f64,
    ug: f64,
    /// ü1.
    top: f64,
    /// dü1/dt.
    jerk: f64,
    /// Friction that would hold the base: m1 ü1 + m2 ü_g (N).
    f_req: f64,
    /// d f_req/dt under the stuck dynamics (N/s).
    f_req_dot_stuck: f64,
    /// Friction actually acting (N).
    friction: f64,
    /// ẍ2.
    slip_acc: f64,
}

/// An interval of one phase and one smooth table forcing, from t0 to the next piece's t0.
#[derive(Debug, Clone, Copy)]
struct Piece {
    t0: f64,
    phase: Phase,
    state: State,
    forcing: Forcing,
}

impl Piece {
    fn eval(&self, m: &Model, tau: f64) -> Eval {
        let (ug, ug_dot) = self.forcing.accel(self.t0, tau);
        let s0 = self.state;
        let (delta, delta_dot, slip, slip_vel) = match self.phase.direction() {
            None => {
                let (y, yd) = self.stuck_drift(m, tau);
                (y, yd, s0.slip, 0.0)
            }
            Some(dir) => {
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
                let force = -dir.sign() * m.f0;
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

    /// Exact fixed-base drift δ'' + 2ξp δ' + p² δ = −ü_g from the piece's initial state.
    fn stuck_drift(&self, m: &Model, tau: f64) -> (f64, f64) {
        let (alpha, n) = (m.fb_alpha, m.fb_n);
        let e = (-alpha * tau).exp();
        let (sn, cs) = (n * tau).sin_cos();
        let ec = e * cs;
        let es = e * sn / n;
        let (ecp, ecm) = (ec + alpha * es, ec - alpha * es);
        let hom = |y0: f64, v0: f64| (ecp * y0 + es * v0, -m.p2 * es * y0 + ecm * v0);
        let s0 = self.state;
        match self.forcing {
            Forcing::Affine { u0, u1 } => {
                // Particular solution c0 + c1 τ of y'' + 2αy' + p²y = −u0 − u1 τ.
                let c1 = -u1 / m.p2;
                let c0 = (-u0 - 2.0 * alpha * c1) / m.p2;
                let (y, v) = hom(s0.delta - c0, s0.delta_dot - c1);
                (y + c0 + c1 * tau, v + c1)
            }
            Forcing::Harmonic { amp, omega } => {
                let (y, v) = hom(s0.delta, s0.delta_dot);
                if tau == 0.0 {
                    return (y, v);
                }
                // Zero-state response to q(u) = −amp sin(ω(t0+u)) = Im(Q e^{iωu}), Q = −amp e^{iωt0}:
                // ∫₀^τ h(τ−u) e^{iωu} du with h(s) = (e^{μ1 s} − e^{μ2 s})/(2in), and
                // ∫₀^τ e^{μ(τ−u)} e^{iωu} du = τ e^{iωτ} φ1((μ − iω)τ) (exact at resonance).
                let mu1 = Cx::new(-alpha, n);
                let mu2 = Cx::new(-alpha, -n);
                let io = Cx::new(0.0, omega);
                let rot = Cx::cis(omega * tau).scale(tau);
                let j1 = rot.mul(phi1(mu1.sub(io).scale(tau)));
                let j2 = rot.mul(phi1(mu2.sub(io).scale(tau)));
                let q = Cx::cis(omega * self.t0).scale(-amp);
                let inv = Cx::new(0.0, -0.5 / n);
                let yf = q.mul(j1.sub(j2)).mul(inv).im;
                let vf = q.mul(mu1.mul(j1).sub(mu2.mul(j2))).mul(inv).im;
                (y + yf, v + vf)
            }
        }
    }

    /// The event function and its derivative: crossing above 0 is the event (breakaway when stuck,
    /// stop when sliding).
    fn event_fn(&self, m: &Model, tau: f64) -> (f64, f64) {
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

// ---------------------------------------------------------------------------------------------------
// Root finding
// ---------------------------------------------------------------------------------------------------

/// Brent's method on [a, b] where f(a) and f(b) have opposite signs (or one is 0). Returns the final
/// bracket (b, f(b), c, f(c)) with |b − c| ≤ tol or f(b) = 0.
fn brent(
    mut f: impl FnMut(f64) -> f64,
    mut a: f64,
    mut fa: f64,
    mut b: f64,
    mut fb: f64,
    tol: f64,
) -> (f64, f64, f64, f64) {
    let (mut c, mut fc) = (b, fb);
    let (mut d, mut e) = (b - a, b - a);
    for _ in 0..300 {
        if (fb > 0.0 && fc > 0.0) || (fb < 0.0 && fc < 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol1 = 2.0 * f64::EPSILON * b.abs() + 0.5 * tol;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol1 || fb == 0.0 {
            break;
        }
        if e.abs() >= tol1 && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let q0 = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * q0 * (q0 - r) - (b - a) * (r - 1.0));
                q = (q0 - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            }
            p = p.abs();
            let min1 = 3.0 * xm * q - (tol1 * q).abs();
            let min2 = (e * q).abs();
            if 2.0 * p < min1.min(min2) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol1 { d } else { tol1.copysign(xm) };
        fb = f(b);
    }
    (b, fb, c, fc)
}

/// Time tolerance of event location at local time τ of a piece starting at t0.
fn time_tol(t0: f64, tau: f64) -> f64 {
    1e-15 + 4.0 * f64::EPSILON * (t0.abs() + tau.abs())
}

/// The first τ in (lo, hi] where the event function becomes > 0, given e(lo) ≤ 0 < e(hi): the
/// boundary between the sets {e ≤ 0} and {e > 0} (values ≤ 0 are mapped below zero so that an exact
/// zero at `lo` does not end the search there).
fn locate(piece: &Piece, m: &Model, lo: f64, elo: f64, hi: f64, ehi: f64) -> f64 {
    if elo > 0.0 {
        return lo;
    }
    let g = |e: f64| {
        if e > 0.0 {
            e
        } else {
            e.min(-f64::MIN_POSITIVE)
        }
    };
    let tol = time_tol(piece.t0, hi);
    let (b, fb, c, _) = brent(|x| g(piece.event_fn(m, x).0), lo, g(elo), hi, g(ehi), tol);
    if fb > 0.0 {
        b
    } else {
        c
    }
}

/// The extremum of the event function between a and b, where its derivative changes sign.
fn extremum(piece: &Piece, m: &Model, a: f64, da: f64, b: f64, db: f64) -> f64 {
    let tol = time_tol(piece.t0, b);
    brent(|x| piece.event_fn(m, x).1, a, da, b, db, tol).0
}

/// Result of scanning a piece for its first event.
struct Scan {
    /// Local time of the event, if one happens on the piece.
    event: Option<f64>,
    /// Whether the event function has been clearly negative (soft starts become armed).
    armed: bool,
}

/// Walks the event function of one piece forward in time.
///
/// Armed: e ≤ 0 at the current point; the event is the first crossing to e > 0 (a crossing between
/// grid points shows as e > 0 at the next point, or as a maximum above 0 where e' changes sign).
/// Unarmed (soft start right after a transition, e ≈ 0): the walk waits until e < −tol; a clear
/// excursion e > tol before that is an event (the transition went the other way), and excursions
/// within ±tol are rounding. Unarmed stretches are walked on a fine sub-grid, geometric near the
/// start (a transition with e = e' = 0 leaves only quadratically).
struct Walker<'a> {
    piece: &'a Piece,
    m: &'a Model,
    tol: f64,
    armed: bool,
    ta: f64,
    ea: f64,
    da: f64,
}

impl Walker<'_> {
    fn ev(&self, x: f64) -> (f64, f64) {
        self.piece.event_fn(self.m, x)
    }

    /// Walk to the grid point tb; `Some(τ)` at the first event.
    fn step(&mut self, tb: f64) -> Option<f64> {
        if !self.armed {
            let (ta, w) = (self.ta, tb - self.ta);
            let geometric = (7..=40).rev().map(|k| ta + w * 0.5f64.powi(k));
            let uniform = (1..=64).map(|j| ta + w * (j as f64 / 64.0));
            for x in geometric.chain(uniform) {
                if x <= self.ta || x > tb {
                    continue;
                }
                let (e, d) = self.ev(x);
                if let Some(hit) = self.advance(x, e, d) {
                    return Some(hit);
                }
            }
            return None;
        }
        let (eb, db) = self.ev(tb);
        self.advance(tb, eb, db)
    }

    fn advance(&mut self, tb: f64, eb: f64, db: f64) -> Option<f64> {
        let (ta, ea, da) = (self.ta, self.ea, self.da);
        (self.ta, self.ea, self.da) = (tb, eb, db);
        let (piece, m) = (self.piece, self.m);
        if self.armed {
            if eb > 0.0 {
                return Some(locate(piece, m, ta, ea, tb, eb));
            }
            if da > 0.0 && db < 0.0 {
                let tm = extremum(piece, m, ta, da, tb, db);
                let em = self.ev(tm).0;
                if em > 0.0 {
                    return Some(locate(piece, m, ta, ea, tm, em));
                }
            }
            return None;
        }
        let mut peak = (tb, eb);
        if da > 0.0 && db < 0.0 {
            let tm = extremum(piece, m, ta, da, tb, db);
            let em = self.ev(tm).0;
            if em > peak.1 {
                peak = (tm, em);
            }
        }
        if peak.1 > self.tol {
            return Some(if ea <= 0.0 {
                locate(piece, m, ta, ea, peak.0, peak.1)
            } else {
                ta
            });
        }
        if eb < -self.tol {
            self.armed = true;
        }
        None
    }
}

/// Find the first event on a piece of length `len`. `soft`: the piece starts right at a transition
/// (event function ≈ 0), so the walk starts unarmed.
/// `age0`: time from the last transition to the piece start (sets the grid, see [`Model::grid_step`]).
fn scan(piece: &Piece, m: &Model, len: f64, soft: bool, age0: f64) -> Scan {
    let tol = if piece.phase == Phase::Stuck {
        m.tol_f
    } else {
        m.tol_v
    };
    let (e0, d0) = piece.event_fn(m, 0.0);
    if !soft && e0 > 0.0 {
        // Already beyond the threshold at the start (a jump of the table acceleration).
        return Scan {
            event: Some(0.0),
            armed: true,
        };
    }
    let mut w = Walker {
        piece,
        m,
        tol,
        armed: !soft || e0 < -tol,
        ta: 0.0,
        ea: e0,
        da: d0,
    };
    loop {
        let tb = (w.ta + m.grid_step(piece.phase, age0 + w.ta)).min(len);
        if let Some(hit) = w.step(tb) {
            return Scan {
                event: Some(hit),
                armed: true,
            };
        }
        if tb >= len {
            return Scan {
                event: None,
                armed: w.armed,
            };
        }
    }
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

// ---------------------------------------------------------------------------------------------------
// The simulation
// ---------------------------------------------------------------------------------------------------

/// The exact stick-slip response over [0, duration].
#[derive(Debug, Clone)]
pub struct Truth {
    model: Model,
    pieces: Vec<Piece>,
    events: Vec<Event>,
    duration_s: f64,
    mu_ratio: f64,
    peak_top: (f64, f64),
    max_abs_slip: f64,
    final_sample: TruthSample,
}

/// Run the exact stick-slip simulation.
pub fn simulate(input: &TruthInput<'_>) -> Result<Truth, TruthError> {
    let s = input.structure;
    let duration = input.duration_s;
    if !(duration.is_finite() && duration > 0.0) {
        return Err(TruthError::Duration(duration));
    }
    let mu_static = input.mu_static.unwrap_or(s.mu());
    if !(mu_static.is_finite() && mu_static >= s.mu()) {
        return Err(TruthError::StaticFriction {
            mu_static,
            mu: s.mu(),
        });
    }
    let segs = segments(input.table)?;
    let m = Model::new(s, mu_static, input.table);

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
        let t_end = seg.end.min(duration);
        let piece = Piece {
            t0: t,
            phase,
            state,
            forcing: seg.forcing.shifted(t - seg.start),
        };
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

fn rest_sample(t: f64) -> TruthSample {
    TruthSample {
        time_s: t,
        phase: Phase::Stuck,
        table_accel_m_s2: 0.0,
        base_accel_m_s2: 0.0,
        top_accel_m_s2: 0.0,
        slip_m: 0.0,
        slip_velocity_m_s: 0.0,
        rel_disp_m: 0.0,
        rel_vel_m_s: 0.0,
        friction_level: 0.0,
    }
}

impl Truth {
    /// The events in time order.
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    /// Simulated duration (s).
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }

    /// μs/μ of the simulation.
    pub fn static_to_kinetic_ratio(&self) -> f64 {
        self.mu_ratio
    }

    /// The exact state at time t: `None` for NaN or t past the duration (times within a relative
    /// 1e-12 of the end, e.g. `k·dt` rounded up, are accepted); the rest state for t < 0.
    /// For many increasing times use [`Truth::sampler`].
    pub fn sample(&self, t: f64) -> Option<TruthSample> {
        if !self.covers(t) {
            return None;
        }
        if t < 0.0 {
            return Some(rest_sample(t));
        }
        let i = self.pieces.partition_point(|p| p.t0 <= t).saturating_sub(1);
        Some(self.sample_in(i, t))
    }

    fn covers(&self, t: f64) -> bool {
        t <= self.duration_s * (1.0 + 1e-12)
    }

    /// The first upward zero crossing of the friction F/F0 in [t0, t0 + period) (a 4000-point scan,
    /// then bisection to rounding), e.g. to phase a rectangular friction train with the truth.
    pub fn friction_zero_crossing(&self, t0: f64, period: f64) -> Option<f64> {
        let f = |t: f64| self.sample(t).map(|s| s.friction_level);
        let n = 4000;
        let h = period / n as f64;
        let mut prev = f(t0)?;
        for i in 1..=n {
            let t = t0 + i as f64 * h;
            let v = f(t)?;
            if prev < 0.0 && v >= 0.0 {
                let (mut lo, mut hi) = (t - h, t);
                for _ in 0..80 {
                    let mid = 0.5 * (lo + hi);
                    if f(mid)? < 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return Some(hi);
            }
            prev = v;
        }
        None
    }

    /// A cursor evaluating samples in O(1) for non-decreasing times (any order works).
    pub fn sampler(&self) -> Sampler<'_> {
        Sampler {
            truth: self,
            index: 0,
        }
    }

    fn sample_in(&self, i: usize, t: f64) -> TruthSample {
        let piece = &self.pieces[i];
        let tau = (t - piece.t0).max(0.0);
        let e = piece.eval(&self.model, tau);
        TruthSample {
            time_s: t,
            phase: piece.phase,
            table_accel_m_s2: e.ug,
            base_accel_m_s2: match piece.phase {
                Phase::Stuck => e.ug,
                _ => (e.friction - self.model.m1 * e.top) / self.model.m2,
            },
            top_accel_m_s2: e.top,
            slip_m: e.slip,
            slip_velocity_m_s: e.slip_vel,
            rel_disp_m: e.delta,
            rel_vel_m_s: e.delta_dot,
            friction_level: e.friction / self.model.f0,
        }
    }

    /// Peak |ü1| over [0, duration] (m/s²), located exactly (zeros of the jerk).
    pub fn peak_top_accel_m_s2(&self) -> f64 {
        self.peak_top.0
    }

    /// Time of [`Truth::peak_top_accel_m_s2`] (s).
    pub fn peak_top_accel_time_s(&self) -> f64 {
        self.peak_top.1
    }

    /// Largest |slip| over [0, duration] (m); slip extremes are at stops, so this is exact.
    pub fn max_abs_slip_m(&self) -> f64 {
        self.max_abs_slip
    }

    /// Slip at the end of the simulation (m).
    pub fn final_slip_m(&self) -> f64 {
        self.final_sample.slip_m
    }

    /// The state at the end of the simulation.
    pub fn final_sample(&self) -> TruthSample {
        self.final_sample
    }

    /// Number of intervals of one-directional sliding (breakaways plus reversals).
    pub fn slip_phases(&self) -> usize {
        self.events
            .iter()
            .filter(|e| !matches!(e.kind, EventKind::Stick))
            .count()
    }

    /// The friction train: (time, level) at every change of the friction level F/F0 while sliding:
    /// −1 (sliding positive) or +1 (sliding negative) from a breakaway or reversal on, and 0.0 marking
    /// the start of a stuck interval (the actual holding force is then in [`TruthSample`], not 0).
    /// Times are strictly increasing (events at one instant are merged; the last level wins).
    pub fn friction_train(&self) -> Vec<(f64, f64)> {
        let mut out: Vec<(f64, f64)> = Vec::with_capacity(self.events.len());
        for e in &self.events {
            let level = match e.kind {
                EventKind::SlipStart { direction } => -direction.sign(),
                EventKind::Reversal { new_direction } => -new_direction.sign(),
                EventKind::Stick => 0.0,
            };
            if let Some(last) = out.last_mut() {
                if last.0 == e.time_s {
                    last.1 = level;
                    let n = out.len();
                    if n >= 2 && out[n - 2].1 == level {
                        out.pop();
                    }
                    continue;
                }
                if last.1 == level {
                    continue;
                }
            } else if level == 0.0 {
                continue;
            }
            out.push((e.time_s, level));
        }
        out
    }

    /// [`Truth::friction_train`] as `ssvr_core` reversals, for
    /// `ReversalTrain::Explicit` and the Duhamel closed form. Only a run that slides without stuck
    /// intervals has exactly the rectangular friction the closed form assumes.
    pub fn friction_reversals(&self) -> Vec<Reversal> {
        self.friction_train()
            .into_iter()
            .map(|(time_s, level)| Reversal { time_s, level })
            .collect()
    }
}

/// A cursor over a [`Truth`], cheap for non-decreasing times.
#[derive(Debug, Clone)]
pub struct Sampler<'a> {
    truth: &'a Truth,
    index: usize,
}

impl Sampler<'_> {
    /// The exact state at time t (see [`Truth::sample`]).
    pub fn sample(&mut self, t: f64) -> Option<TruthSample> {
        let truth = self.truth;
        if !truth.covers(t) {
            return None;
        }
        if t < 0.0 {
            return Some(rest_sample(t));
        }
        let pieces = &truth.pieces;
        if self.index >= pieces.len() || pieces[self.index].t0 > t {
            self.index = pieces.partition_point(|p| p.t0 <= t).saturating_sub(1);
        }
        while self.index + 1 < pieces.len() && pieces[self.index + 1].t0 <= t {
            self.index += 1;
        }
        Some(truth.sample_in(self.index, t))
    }
}
