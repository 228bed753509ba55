//! A sample as acquired, and the frame the pipeline makes of it.

use crate::channel::CHANNELS;
use crate::event::Event;
use crate::flags;
use crate::log::LogReversal;

/// One acquired sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Table accel, base accel, top accel (m/s²), base-to-table displacement (m)
    /// ([`crate::Channel`] order).
    pub channels: [f32; CHANNELS],
    /// Acquisition flags (bits of [`flags::ACQUISITION`]: `SATURATED`, `MISSING`, `ADC_ERROR`,
    /// and `DISP_INVALID` when the displacement channel itself is saturated).
    pub flags: u8,
    /// A reversal given with this sample (used with [`crate::EventSource::Log`] only).
    pub reversal: Option<LogReversal>,
}

impl Sample {
    /// A sample that was not acquired.
    pub const fn missing(extra_flags: u8) -> Self {
        Self {
            channels: [f32::NAN; CHANNELS],
            flags: flags::MISSING | extra_flags,
            reversal: None,
        }
    }
}

/// One streamed frame: the measured channels, the friction event of this sample if any, and
/// the prediction of the top-mass acceleration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Sample index since start (the estimator's time).
    pub index: u32,
    /// Bits of [`flags`].
    pub flags: u8,
    /// The friction event detected (or given) at this sample.
    pub event: Option<Event>,
    /// Measured channels, as acquired (NaN when missing).
    pub channels: [f32; CHANNELS],
    /// Predicted top-mass acceleration (m/s²) at this sample.
    pub prediction: f32,
}

impl Frame {
    /// A placeholder (overwritten by the pipeline).
    pub const EMPTY: Self = Self {
        index: 0,
        flags: 0,
        event: None,
        channels: [0.0; CHANNELS],
        prediction: 0.0,
    };
}
