//! The friction events the detectors report: a slip start, a reversal of sliding or a stick, each
//! with its age in samples (the estimators back-date it).

/// A detected change of sliding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SlipEvent {
    /// The base started to slide from rest in `direction` (+1 or −1).
    SlipStart {
        /// Slip direction.
        direction: i8,
        /// Samples between the event and the current sample (≥ 0).
        age_samples: f32,
    },
    /// The sliding direction reversed; the base now slides in `direction`.
    Reversal {
        /// New slip direction.
        direction: i8,
        /// Samples between the event and the current sample (≥ 0).
        age_samples: f32,
    },
    /// The base stopped and sticks.
    Stick {
        /// Samples between the event and the current sample (≥ 0).
        age_samples: f32,
    },
}

impl SlipEvent {
    /// The friction level after the event in units of F0 (friction opposes slip; 0 while stuck).
    pub fn friction_level(&self) -> f32 {
        match *self {
            SlipEvent::SlipStart { direction, .. } | SlipEvent::Reversal { direction, .. } => {
                -(direction as f32)
            }
            SlipEvent::Stick { .. } => 0.0,
        }
    }

    /// Age of the event in samples.
    pub fn age_samples(&self) -> f32 {
        match *self {
            SlipEvent::SlipStart { age_samples, .. }
            | SlipEvent::Reversal { age_samples, .. }
            | SlipEvent::Stick { age_samples } => age_samples,
        }
    }
}

/// The slip acceleration's change at a friction event
/// ([`PhaseDetector::step_at`](crate::detect::acceleration::PhaseDetector::step_at)): the base
/// accelerometer's jump and change of slope there (the table's acceleration is smooth).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventStep {
    /// The jump at the event's time (m/s²): the line after it less the line before it.
    pub step: f32,
    /// The change of slope at the event (m/s² per sample interval).
    pub kink: f32,
}

impl EventStep {
    /// Not known (NaN).
    pub const UNKNOWN: Self = Self {
        step: f32::NAN,
        kink: f32::NAN,
    };

    /// Both scaled by `factor` (another accelerometer's units).
    pub fn scaled(self, factor: f32) -> Self {
        Self {
            step: self.step * factor,
            kink: self.kink * factor,
        }
    }

    /// Whether both are finite.
    pub fn is_known(&self) -> bool {
        self.step.is_finite() && self.kink.is_finite()
    }
}
