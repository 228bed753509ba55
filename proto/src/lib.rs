//! # ssvr-proto: the contract between the firmware and the host
//!
//! Everything both sides must agree on is written here once:
//!
//! * [`channel`], [`flags`], [`event`], [`frame`]: the measured channels, the bits of a frame's
//!   flags, the friction events and the streamed frame;
//! * [`log`]: the binary sensor log the QEMU image replays (format version 1, `LOG_FORMAT.md`);
//! * [`plan`]: what a scene and a model turn into for the estimator (detector settings, ring and
//!   history sizes, stick-slip settings and coefficients), as words the firmware's build embeds;
//! * [`model`] and [`detector`]: the estimator models and friction-event detectors behind two
//!   small traits;
//! * [`zeroing`]: the accelerometers' offsets from the rest before the input; [`table_gain`]: the
//!   table accelerometer's gain against the displacement sensor;
//! * [`pipeline`]: **the** per-sample step (flags → detector → events → model), run by the
//!   firmware, by `host-sim qemu`'s check and by `host-sim run`;
//! * [`stream`]: the defmt messages a frame, the counters and the plan are streamed as (feature
//!   `defmt`), and their names and field keys, which the host decoder reads back by type.
//!
//! `#![no_std]`, no allocation, no panics on data paths.
#![no_std]
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

#[cfg(any(test, feature = "std"))]
extern crate std;

pub mod channel;
pub mod detector;
pub mod event;
pub mod flags;
pub mod frame;
pub mod log;
pub mod model;
pub mod pipeline;
pub mod plan;
pub mod planned_start;
pub mod stream;
pub mod table_gain;
pub mod table_start;
pub mod zeroing;

pub use channel::{Channel, CHANNELS};
pub use detector::{AccelerationDetector, DetectorInput, DisplacementDetector, EventDetector};
pub use event::{Event, EventKind};
pub use frame::{Frame, Sample};
pub use model::{
    FixedBaseModel, FromPlan, Mode, Model, ModelKind, Pushed, RectangularModel, StaticFriction,
    StickSlipLawModel, StickSlipModel,
};
pub use pipeline::{EventSource, Pipeline, Stats, Step, BATCH};
pub use plan::{DetectorPlan, Plan, PlanError, PlannedStart, Specimen};

/// The Table 1 specimen, the prior of the crate's unit tests.
#[cfg(test)]
pub(crate) fn test_params() -> ssvr_core::StructureParams {
    ssvr_core::StructureParams {
        m1_kg: 29.5,
        m2_kg: 1.75,
        natural_frequency_hz: 7.0,
        damping_ratio: 0.05,
        friction_coefficient: 0.2,
        gravity_m_s2: 9.80665,
    }
}
