//! The per-sample pipeline shared by both images: validate a sample, feed reversals to the
//! estimator, predict, and queue a frame for the streaming loop.
//!
//! The sample side (TIM2 interrupt on the board, the log-replay loop under QEMU) owns a
//! [`Pipeline`] and the [`Producer`] of a heapless SPSC queue; the streaming side owns the
//! [`Consumer`] and turns each [`FrameOut`] into one defmt `sample` message ([`emit`]).

use heapless::spsc::{Consumer, Producer};
use ssvr_core::duhamel_recursion::Estimator32;

/// Number of measured channels: table accel, base accel, top accel (m/s²), base-to-table
/// displacement (m).
pub const CHANNELS: usize = 4;

/// Capacity of the sample -> streaming queue (a heapless queue of N holds N - 1 frames).
pub const QUEUE_LEN: usize = 64;

/// Bits of [`FrameOut::flags`] (the `flags` field of every `sample` message).
pub mod flags {
    /// A channel is NaN or infinite.
    pub const NOT_FINITE: u8 = 1 << 0;
    /// A channel is at the ADC full scale (clipped).
    pub const SATURATED: u8 = 1 << 1;
    /// The sample is missing (not acquired / dropped upstream); the channels are meaningless.
    pub const MISSING: u8 = 1 << 2;
    /// Frames were lost before this one because the streaming queue was full.
    pub const OVERRUN: u8 = 1 << 3;
    /// A friction reversal was pushed to the estimator at this sample.
    pub const REVERSAL: u8 = 1 << 4;
    /// A reversal was rejected by the estimator (invalid level/age or capacity).
    pub const REVERSAL_REJECTED: u8 = 1 << 5;
    /// The ADC reported an error (SPI, CRC) for this sample (board image; implies `MISSING`).
    pub const ADC_ERROR: u8 = 1 << 6;
    /// Any of the flags that make the measured channels unusable.
    pub const INVALID: u8 = NOT_FINITE | SATURATED | MISSING | ADC_ERROR;
}

/// A friction reversal for the estimator (see `DuhamelRecursion::push_reversal`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reversal {
    /// New friction level in units of μ(m1+m2)g: +1, −1 (or 0).
    pub level: f32,
    /// Sample intervals between the reversal and the sample the next update returns (≥ 0).
    pub age_samples: f32,
}

/// One acquired sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Table accel, base accel, top accel (m/s²), base-to-table displacement (m).
    pub channels: [f32; CHANNELS],
    /// Acquisition flags (bits of [`flags`]: `SATURATED`, `MISSING`, `ADC_ERROR`).
    pub flags: u8,
    /// A reversal reported with this sample (from the log until the detector exists).
    pub reversal: Option<Reversal>,
}

impl Sample {
    /// A sample that was not acquired.
    #[cfg_attr(not(feature = "board"), allow(dead_code))]
    pub const fn missing(extra_flags: u8) -> Self {
        Self {
            channels: [f32::NAN; CHANNELS],
            flags: flags::MISSING | extra_flags,
            reversal: None,
        }
    }
}

/// One streamed frame: the measured channels and the prediction of the top-mass acceleration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameOut {
    /// Sample index since start (the estimator's time).
    pub index: u32,
    /// Bits of [`flags`].
    pub flags: u8,
    /// Measured channels, as acquired (NaN when missing).
    pub channels: [f32; CHANNELS],
    /// Predicted top-mass acceleration (m/s²) at this sample.
    pub prediction: f32,
}

/// Counters of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Samples processed (estimator updates).
    pub samples: u32,
    /// Samples with any of [`flags::INVALID`].
    pub invalid: u32,
    /// Frames dropped because the queue was full.
    pub dropped: u32,
    /// Reversals accepted by the estimator.
    pub reversals: u32,
    /// Reversals rejected by the estimator.
    pub rejected: u32,
}

/// The estimator and its sample clock.
pub struct Pipeline {
    estimator: Estimator32,
    index: u32,
    overrun: bool,
    /// Counters.
    pub stats: Stats,
}

impl Pipeline {
    /// Start at sample 0.
    pub fn new(estimator: Estimator32) -> Self {
        Self {
            estimator,
            index: 0,
            overrun: false,
            stats: Stats::default(),
        }
    }

    /// Process one sample: flag it, push its reversal, update the estimator (always, to keep
    /// time, whether the sample is valid or not) and build its frame. Never panics.
    pub fn step(&mut self, s: &Sample) -> FrameOut {
        let mut f = s.flags & (flags::SATURATED | flags::MISSING | flags::ADC_ERROR);
        if f & flags::ADC_ERROR != 0 {
            f |= flags::MISSING;
        }
        if s.channels.iter().any(|c| !c.is_finite()) {
            f |= flags::NOT_FINITE;
        }
        if let Some(r) = s.reversal {
            match self.estimator.push_reversal(r.level, r.age_samples) {
                Ok(()) => {
                    f |= flags::REVERSAL;
                    self.stats.reversals = self.stats.reversals.wrapping_add(1);
                }
                Err(_) => {
                    f |= flags::REVERSAL_REJECTED;
                    self.stats.rejected = self.stats.rejected.wrapping_add(1);
                }
            }
        }
        let prediction = self.estimator.update();
        if f & flags::INVALID != 0 {
            self.stats.invalid = self.stats.invalid.wrapping_add(1);
        }
        let frame = FrameOut {
            index: self.index,
            flags: f,
            channels: s.channels,
            prediction,
        };
        self.index = self.index.wrapping_add(1);
        self.stats.samples = self.stats.samples.wrapping_add(1);
        frame
    }

    /// [`Self::step`], then queue the frame; a full queue drops it and flags the next frame
    /// that gets through with [`flags::OVERRUN`].
    pub fn produce(&mut self, s: &Sample, producer: &mut Producer<'_, FrameOut>) {
        let mut frame = self.step(s);
        if self.overrun {
            frame.flags |= flags::OVERRUN;
        }
        match producer.enqueue(frame) {
            Ok(()) => self.overrun = false,
            Err(_) => {
                self.overrun = true;
                self.stats.dropped = self.stats.dropped.wrapping_add(1);
            }
        }
    }
}

/// Stream one frame as a defmt message. The host decoder (host-sim `qemu_runner`) parses the
/// `key=value` fields of messages that start with `sample `.
pub fn emit(f: &FrameOut) {
    defmt::info!(
        "sample idx={=u32} flags={=u8} table={=f32} base={=f32} top={=f32} disp={=f32} pred={=f32}",
        f.index,
        f.flags,
        f.channels[0],
        f.channels[1],
        f.channels[2],
        f.channels[3],
        f.prediction
    );
}

/// Stream every queued frame; returns how many.
pub fn drain(consumer: &mut Consumer<'_, FrameOut>) -> u32 {
    let mut n: u32 = 0;
    while let Some(f) = consumer.dequeue() {
        emit(&f);
        n = n.wrapping_add(1);
    }
    n
}

/// Report the counters of a run.
pub fn emit_stats(s: &Stats) {
    defmt::info!(
        "stats samples={=u32} invalid={=u32} dropped={=u32} reversals={=u32} rejected={=u32}",
        s.samples,
        s.invalid,
        s.dropped,
        s.reversals,
        s.rejected
    );
}
