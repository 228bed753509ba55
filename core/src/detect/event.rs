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
