//! The friction-event detectors behind one trait: which channel each reads, and how a sample's
//! flags make that input unusable (NaN: the detector repeats its last value and keeps time).
//!
//! * [`DisplacementDetector`]: `ReversalDetector` on the base-to-table displacement
//!   (rectangular and fixed-base models);
//! * [`AccelerationDetector`]: `PhaseDetector` on the slip acceleration, base minus table
//!   accelerometer (stick-slip model: its stick and slip-start times must be right to a
//!   fraction of a sample).

use crate::channel::{Channel, CHANNELS};
use crate::flags;
use crate::plan::{DetectorPlan, Plan, PlanError};
use ssvr_core::detect::acceleration::PhaseDetector;
use ssvr_core::detect::displacement::{ReversalDetector, SlipEvent};
use ssvr_core::detect::EventStep;

/// The displacement detector with a ring of `N` samples.
pub type DisplacementDetector<const N: usize> = ReversalDetector<N>;
/// The slip-acceleration detector with a ring of `N` samples.
pub type AccelerationDetector<const N: usize> = PhaseDetector<N>;

/// What a detector reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DetectorInput {
    /// The base-to-table displacement (m).
    Displacement,
    /// The slip acceleration, base minus table accelerometer (m/s²).
    SlipAcceleration,
}

impl DetectorInput {
    /// The detector's input of a sample with frame flags `f` (NaN: unusable). The displacement
    /// is unusable with `DISP_INVALID`; the slip acceleration when the sample is missing, not
    /// finite or saturated.
    #[inline(always)]
    pub fn of(self, channels: &[f32; CHANNELS], f: u8) -> f32 {
        match self {
            DetectorInput::SlipAcceleration => {
                if f & (flags::MISSING | flags::NOT_FINITE | flags::SATURATED) != 0 {
                    f32::NAN
                } else {
                    channels[Channel::BaseAccel.index()] - channels[Channel::TableAccel.index()]
                }
            }
            DetectorInput::Displacement => {
                if f & flags::DISP_INVALID != 0 {
                    f32::NAN
                } else {
                    channels[Channel::Displacement.index()]
                }
            }
        }
    }
}

/// A friction-event detector the pipeline runs on every sample.
pub trait EventDetector: Sized {
    /// What it reads.
    const INPUT: DetectorInput;
    /// The detector of a plan; its ring must be the plan's.
    fn from_plan(plan: &Plan) -> Result<Self, PlanError>;
    /// Process one input sample (NaN: unusable); an event found, back-dated by its age.
    fn process(&mut self, x: f32) -> Option<SlipEvent>;
    /// [`EventDetector::process`] with the sample's table acceleration (m/s²), which the
    /// slip-acceleration detector regresses its input on to remove the accelerometers' gain
    /// mismatch; the displacement detector ignores it.
    #[inline(always)]
    fn process_with_reference(&mut self, x: f32, table_accel: f32) -> Option<SlipEvent> {
        let _ = table_accel;
        self.process(x)
    }
    /// The longest back-dating of its events (samples).
    fn max_age_samples(&self) -> usize;
    /// The offset of its input it tracks and removes (the slip acceleration's; 0 for the
    /// displacement, whose offset does not matter to its extrema).
    fn offset(&self) -> f32 {
        0.0
    }
    /// What the models' inputs subtract from the base accelerometer before dividing it by 1 +
    /// the gain mismatch ([`crate::pipeline::model_inputs`]): the base then reads in the table's units
    /// with the table's offset (the acceleration detector's
    /// [`PhaseDetector::base_offset`]; [`Self::offset`] by default).
    fn base_offset(&self) -> f32 {
        self.offset()
    }
    /// The gain mismatch of its input against the table acceleration it tracks and removes (the
    /// slip acceleration's; 0 for the displacement).
    fn gain_mismatch(&self) -> f32 {
        0.0
    }
    /// The last slip start's slip acceleration on its sliding side at its start (m/s²; NaN when
    /// the detector does not measure it: the displacement's).
    fn slip_start_accel(&self) -> f32 {
        f32::NAN
    }
    /// Whether the last slip start's sliding side comes a sample later (a strong jump breakaway
    /// confirmed at its second sample: NaN in [`Self::slip_start_accel`]).
    fn side_pending(&self) -> bool {
        false
    }
    /// That sliding side (m/s²), at the sample after such a slip start; NaN at any other.
    fn late_slip_start_accel(&self) -> f32 {
        f32::NAN
    }
    /// The step and kink of the detector's input at an event `age` sample intervals before the last
    /// sample processed, `stick` when the event is a stick (the base accelerometer's jump at a
    /// friction event; NaN when the detector does not read the base accelerometer: the
    /// displacement's).
    fn event_step(&self, age: f32, stick: bool) -> EventStep {
        let _ = (age, stick);
        EventStep::UNKNOWN
    }
}

impl<const N: usize> EventDetector for ReversalDetector<N> {
    const INPUT: DetectorInput = DetectorInput::Displacement;

    fn from_plan(plan: &Plan) -> Result<Self, PlanError> {
        match plan.detector {
            DetectorPlan::Displacement(c) if plan.ring == N => {
                ReversalDetector::new(c).map_err(PlanError::Core)
            }
            _ => Err(PlanError::Detector),
        }
    }

    #[inline(always)]
    fn process(&mut self, x: f32) -> Option<SlipEvent> {
        ReversalDetector::process(self, x)
    }

    fn max_age_samples(&self) -> usize {
        self.config().max_age_samples(N)
    }
}

impl<const N: usize> EventDetector for PhaseDetector<N> {
    const INPUT: DetectorInput = DetectorInput::SlipAcceleration;

    fn from_plan(plan: &Plan) -> Result<Self, PlanError> {
        match plan.detector {
            DetectorPlan::SlipAcceleration(c) if plan.ring == N => {
                PhaseDetector::new(c).map_err(PlanError::Core)
            }
            _ => Err(PlanError::Detector),
        }
    }

    #[inline(always)]
    fn process(&mut self, x: f32) -> Option<SlipEvent> {
        PhaseDetector::process(self, x)
    }

    #[inline(always)]
    fn process_with_reference(&mut self, x: f32, table_accel: f32) -> Option<SlipEvent> {
        PhaseDetector::process_with_reference(self, x, table_accel)
    }

    fn max_age_samples(&self) -> usize {
        self.config().max_age_samples()
    }

    fn offset(&self) -> f32 {
        PhaseDetector::offset(self)
    }

    fn base_offset(&self) -> f32 {
        PhaseDetector::base_offset(self)
    }

    fn gain_mismatch(&self) -> f32 {
        PhaseDetector::gain_mismatch(self)
    }

    fn slip_start_accel(&self) -> f32 {
        PhaseDetector::slip_start_accel(self)
    }

    fn side_pending(&self) -> bool {
        PhaseDetector::side_pending(self)
    }

    fn late_slip_start_accel(&self) -> f32 {
        PhaseDetector::late_slip_start_accel(self)
    }

    fn event_step(&self, age: f32, stick: bool) -> EventStep {
        PhaseDetector::step_at(self, age, stick)
    }
}
