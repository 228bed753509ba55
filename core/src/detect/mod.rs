//! Friction events (slip starts, reversals, sticks) sensed online from the sensors, with their
//! sub-sample age for the estimators to back-date:
//!
//! * [`displacement`]: from the slip displacement (base minus table), by hysteresis on its
//!   running extremum and parabola fits around it;
//! * [`acceleration`]: from the slip acceleration (base minus table accelerometer), by the jumps
//!   the friction makes in it and the zeros of the integrated slip velocity.
//!
//! Both report a [`SlipEvent`].

pub mod acceleration;
pub mod displacement;
mod event;
mod ring;
mod search;

pub use event::{EventStep, SlipEvent};
