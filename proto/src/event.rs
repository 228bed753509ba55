//! Friction events as the pipeline pushes them to the model and streams them.

use ssvr_core::detect::displacement::SlipEvent;

/// What a friction event is (the `ev` field of a frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum EventKind {
    /// The base started to slide.
    SlipStart = 1,
    /// The sliding direction reversed.
    Reversal = 2,
    /// The base stuck.
    Stick = 3,
    /// A reversal carried by the sensor log (the QEMU image's test hook).
    Log = 4,
}

impl EventKind {
    /// The kind of a streamed code, `None` for an unknown one.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            1 => Some(EventKind::SlipStart),
            2 => Some(EventKind::Reversal),
            3 => Some(EventKind::Stick),
            4 => Some(EventKind::Log),
            _ => None,
        }
    }

    /// Its streamed code.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// Its name in CSV files (`slip_start`, `reversal`, `stick`, `log`).
    pub const fn name(self) -> &'static str {
        match self {
            EventKind::SlipStart => "slip_start",
            EventKind::Reversal => "reversal",
            EventKind::Stick => "stick",
            EventKind::Log => "log",
        }
    }
}

/// A friction event of a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// What it is.
    pub kind: EventKind,
    /// Friction level after it, in units of μ(m1+m2)g: −1, 0 or +1.
    pub level: i8,
    /// Sample intervals between the event and this sample (≥ 0).
    pub age_samples: f32,
}

impl Event {
    /// A detector's event.
    #[inline]
    pub fn from_detector(e: &SlipEvent) -> Self {
        let kind = match e {
            SlipEvent::SlipStart { .. } => EventKind::SlipStart,
            SlipEvent::Reversal { .. } => EventKind::Reversal,
            SlipEvent::Stick { .. } => EventKind::Stick,
        };
        Self {
            kind,
            level: e.friction_level() as i8,
            age_samples: e.age_samples(),
        }
    }

    /// Whether it is a stick.
    #[inline(always)]
    pub fn is_stick(&self) -> bool {
        self.kind == EventKind::Stick
    }
}
