//! # ssvr-core
//!
//! Sliding-vibrating response (SSVR) of an elastic structure on a friction base: a top mass `m1` on a
//! spring and dashpot over a sliding base `m2` with Coulomb friction `μ(m1+m2)g`.
//!
//! * [`structure`]: the validated [`Structure`] and its derived quantities (M, p, a, ζ, n, ε, ε').
//! * [`closed_form`]: the closed forms, evaluated from the whole friction history:
//!   * [`closed_form::free_vibration`]: the exact free vibration of the relative motion (the
//!     building block of every method), evaluated robustly in all three damping regimes;
//!   * [`closed_form::fourier`]: the trapezoid (TFM, eq 14-18) and rectangular (RFM, eq 20-22)
//!     Fourier methods;
//!   * [`closed_form::duhamel`]: the rectangular Duhamel method (RDM, eq 36) generalised to any
//!     train of friction reversals;
//!   * [`closed_form::truncated`]: eq (36) truncated to the K newest reversals (O(K) per sample;
//!     a baseline).
//! * [`recursion`]: eq (36) as an exact O(1)-per-sample recursion (the estimator).
//! * [`detect`]: friction reversals, sticks and slip starts sensed from the slip displacement
//!   ([`detect::displacement`]), or from the slip acceleration (base minus table accelerometer,
//!   [`detect::acceleration`]).
//! * [`stick_slip`]: the stick-slip aware estimator with online friction identification.
//! * [`sliding_id`]: the sliding oscillator and the friction identified from the base
//!   accelerometer alone.
//! * [`friction`]: the friction law of the sliding interface (Coulomb, or velocity-dependent);
//!   [`friction_id`]: its online identification from the sliding phases.
//!
//! The library is `#![no_std]`, allocates nothing and never panics on any input: every fallible
//! operation returns a typed [`Error`].
#![no_std]
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

#[cfg(any(test, feature = "std"))]
extern crate std;

pub mod closed_form;
pub mod detect;
pub mod error;
pub mod friction;
pub mod friction_id;
pub mod least_squares;
pub mod math;
pub mod oscillator_id;
pub mod recursion;
pub mod sliding_id;
pub mod stick_slip;
pub mod structure;

pub use closed_form::duhamel::{Reversal, ReversalTrain};
pub use error::{Error, Param};
pub use friction::FrictionLaw;
pub use structure::{Regime, Structure, StructureParams};
