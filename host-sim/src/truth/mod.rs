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
//! # Velocity-dependent friction
//!
//! Under a velocity-dependent law ([`ssvr_core::FrictionLaw`], [`TruthInput::with_friction`]) the
//! sliding force is −s·μ(|ẋ2|)·(m1+m2)g and a sliding phase has no closed form: it is integrated
//! by the error-controlled Dormand–Prince 5(4) pair (or, when the law's rate makes it stiff, by
//! Rodas5), one accepted step per piece, with a dense output of order 5 (one step of length τ
//! from the piece's start); stuck phases stay closed form and events
//! are located on the dense output as on the closed forms. A slide starts at μ_slow; while
//! μ_slow·N < |F_req| < μ_fast·N the base can creep at a small speed instead of sticking.
//! Against RK4 at dt = 1e-6 s: 9e-11 of the peak, events to 2e-12 s (Rodas5 at a = 1000 s/m:
//! 1.1e-10); a → ∞ reproduces the Coulomb truth (3e11 s/m: 1.7e-10 of the peak)
//! (tests/truth_friction.rs).
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

mod events;
mod forcing;
mod input;
mod integrate;
mod model;
mod phase;
mod piece;
mod response;
mod roots;
mod sampler;
mod simulate;
mod sliding;
mod stiff;
mod stuck;

pub use input::{TruthError, TruthInput};
pub use phase::{Direction, Event, EventKind, Phase};
pub use response::Truth;
pub use sampler::{Sampler, TruthSample};
pub use simulate::simulate;

/// Maximum number of events of one simulation (a guard against pathological chattering).
pub const MAX_EVENTS: usize = 10_000_000;
