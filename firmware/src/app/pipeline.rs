//! The per-sample pipeline shared by both images: validate a sample, run the reversal detector on
//! its displacement, feed the detected events to the estimator, predict, and queue a frame for
//! the streaming loop.
//!
//! The sample side (TIM2 interrupt on the board, the log-replay loop under QEMU) owns a
//! [`Pipeline`] and the [`Producer`] of a heapless SPSC queue; the streaming side owns the
//! [`Consumer`] and turns each [`FrameOut`] into one defmt `sample` message ([`emit`]).
//!
//! Per sample, in this order (host-sim's `qemu_cmd::HostPipeline` mirrors it step by step):
//!
//! 1. flags: `NOT_FINITE` if a channel is NaN/inf; the displacement is unusable (`DISP_INVALID`)
//!    if the sample is missing, the displacement is not finite, flagged saturated upstream, or at
//!    or beyond the compiled-in full scale `scene::DISP_RANGE_M`;
//! 2. the model's detector processes its input, or NaN when that is unusable (the detector then
//!    repeats its last value and keeps time): the reversal detector (`ssvr_core::reversal_detector`)
//!    the displacement (rectangular, fixed-base), the phase detector (`ssvr_core::phase_detector`)
//!    the slip acceleration, base minus table accelerometer (stick-slip; unusable when the sample
//!    is missing, not finite or saturated);
//! 3. the event goes to the estimator of the compiled-in model ([`super::model::push`]):
//!    rectangular: a slip start or reversal as `push_reversal(event.friction_level(),
//!    event.age_samples())`, a stick is reported but not pushed (the rectangular model keeps its
//!    level); stick-slip: every event as `push_event(level, age)` (0 for a stick); fixed-base:
//!    none;
//! 4. the model's update gives the prediction of this sample (always, valid sample or not): the
//!    rectangular `update()`, or the stick-slip `update(table, top)` with the measured table
//!    acceleration and the measured top acceleration (NaN, i.e. not used for the friction
//!    identification, when the sample is saturated or missing).

use super::model::{self, Estimator, Pushed};
use super::scene::{self, Detector};
use heapless::spsc::{Consumer, Producer};
use ssvr_core::reversal_detector::SlipEvent;

/// Number of measured channels: table accel, base accel, top accel (m/s²), base-to-table
/// displacement (m).
pub const CHANNELS: usize = 4;

/// Index of the table accelerometer channel.
pub const TABLE: usize = 0;
/// Index of the base accelerometer channel.
pub const BASE: usize = 1;
/// Index of the displacement channel.
pub const DISP: usize = 3;

/// Capacity of the sample -> streaming queue (a heapless queue of N holds N - 1 frames). The
/// board streams from its main loop as soon as a frame is queued, so 31 frames (3.1 ms at
/// 10 kHz) of slack is plenty there and keeps its static RAM under 8 KiB with room for the
/// detector's ring at high rates; the QEMU replay drains every 16 samples.
#[cfg(feature = "board")]
#[allow(dead_code)] // the board image queues raw samples instead (board.rs)
pub const QUEUE_LEN: usize = 32;
/// Capacity of the sample -> streaming queue (a heapless queue of N holds N - 1 frames).
#[cfg(not(feature = "board"))]
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
    /// A friction event was pushed to the estimator at this sample (rectangular model: a slip
    /// start or reversal; stick-slip model: any event, sticks included).
    pub const REVERSAL: u8 = 1 << 4;
    /// The estimator rejected the event (invalid level/age).
    pub const REVERSAL_REJECTED: u8 = 1 << 5;
    /// The ADC reported an error (SPI, CRC) for this sample (board image; implies `MISSING`).
    pub const ADC_ERROR: u8 = 1 << 6;
    /// The displacement was unusable (missing, not finite, saturated): the detector repeated
    /// its last value.
    pub const DISP_INVALID: u8 = 1 << 7;
    /// Any of the flags that make a measured channel unusable.
    pub const INVALID: u8 = NOT_FINITE | SATURATED | MISSING | ADC_ERROR | DISP_INVALID;
}

/// What a friction event in a frame is (`ev=` field of a `sample` message).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum EventKind {
    /// The detector saw the base start to slide (pushed).
    SlipStart = 1,
    /// The detector saw the sliding direction reverse (pushed).
    Reversal = 2,
    /// The detector saw the base stick (pushed by the stick-slip model only).
    Stick = 3,
    /// A reversal event of the sensor log (test hook of the QEMU image; pushed).
    Log = 4,
}

/// A friction event of a sample, as streamed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// What it is.
    pub kind: EventKind,
    /// Friction level after it, units of μ(m1+m2)g: −1, 0 or +1.
    pub level: i8,
    /// Sample intervals between the event and this sample (≥ 0).
    pub age_samples: f32,
}

impl Event {
    /// The detector's event as streamed.
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
}

/// A friction reversal given with a sample (the sensor log's test hook).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reversal {
    /// New friction level in units of μ(m1+m2)g: +1, −1 (or 0).
    pub level: f32,
    /// Sample intervals between the reversal and the sample the next update returns (≥ 0).
    pub age_samples: f32,
}

/// The detector's input of a sample with flags `f` (NaN: unusable): the displacement, or for the
/// phase detector the slip acceleration (base minus table accelerometer).
#[inline(always)]
pub fn detector_input(channels: &[f32; CHANNELS], f: u8) -> f32 {
    if scene::DETECTOR_ON_ACCEL {
        if f & (flags::MISSING | flags::NOT_FINITE | flags::SATURATED) != 0 {
            f32::NAN
        } else {
            channels[BASE] - channels[TABLE]
        }
    } else if f & flags::DISP_INVALID != 0 {
        f32::NAN
    } else {
        channels[DISP]
    }
}

/// Where the estimator's friction events come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventSource {
    /// The reversal detector on the displacement channel (the firmware's path).
    Detector,
    /// The reversal events carried by the samples (the QEMU image's test hook; the detector
    /// still runs, its events are not used).
    #[cfg_attr(not(feature = "qemu"), allow(dead_code))]
    Samples,
}

/// One acquired sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Table accel, base accel, top accel (m/s²), base-to-table displacement (m).
    pub channels: [f32; CHANNELS],
    /// Acquisition flags (bits of [`flags`]: `SATURATED`, `MISSING`, `ADC_ERROR`, and
    /// `DISP_INVALID` when the displacement channel itself is saturated).
    pub flags: u8,
    /// A reversal given with this sample (used with [`EventSource::Samples`] only).
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

/// One streamed frame: the measured channels, the friction event of this sample if any, and
/// the prediction of the top-mass acceleration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameOut {
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

/// Counters of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Samples processed (estimator updates).
    pub samples: u32,
    /// Samples with any of [`flags::INVALID`].
    pub invalid: u32,
    /// Frames dropped because the queue was full.
    pub dropped: u32,
    /// Friction events (slip starts, reversals, sticks; or log reversals with the test hook).
    pub events: u32,
    /// Events pushed to and accepted by the estimator.
    pub reversals: u32,
    /// Events rejected by the estimator.
    pub rejected: u32,
    /// Sticks (pushed by the stick-slip model only).
    pub sticks: u32,
    /// Events pushed with their age clamped to the stick-slip history.
    pub clamped: u32,
}

/// The detector, the estimator and the sample clock.
pub struct Pipeline {
    estimator: Estimator,
    detector: Detector,
    source: EventSource,
    index: u32,
    #[cfg_attr(feature = "board", allow(dead_code))]
    overrun: bool,
    /// Counters.
    pub stats: Stats,
}

impl Pipeline {
    /// Start at sample 0.
    pub fn new(estimator: Estimator, detector: Detector, source: EventSource) -> Self {
        Self {
            estimator,
            detector,
            source,
            index: 0,
            overrun: false,
            stats: Stats::default(),
        }
    }

    /// Process one sample: flag it, run the detector, push its event, update the estimator
    /// (always, to keep time, whether the sample is valid or not) and build its frame. Never
    /// panics.
    pub fn step(&mut self, s: &Sample) -> FrameOut {
        let mut f =
            s.flags & (flags::SATURATED | flags::MISSING | flags::ADC_ERROR | flags::DISP_INVALID);
        if f & flags::ADC_ERROR != 0 {
            f |= flags::MISSING;
        }
        if s.channels.iter().any(|c| !c.is_finite()) {
            f |= flags::NOT_FINITE;
        }
        let disp = s.channels[DISP];
        if f & flags::MISSING != 0 || !disp.is_finite() || disp.abs() >= scene::DISP_RANGE_M {
            f |= flags::DISP_INVALID;
        }
        let detected = self.detector.process(detector_input(&s.channels, f));
        let event = match self.source {
            EventSource::Detector => detected.as_ref().map(Event::from_detector),
            EventSource::Samples => s.reversal.map(|r| Event {
                kind: EventKind::Log,
                level: r.level as i8,
                age_samples: r.age_samples,
            }),
        };
        if let Some(e) = &event {
            self.stats.events = self.stats.events.wrapping_add(1);
            if e.kind == EventKind::Stick {
                self.stats.sticks = self.stats.sticks.wrapping_add(1);
            }
            match model::push(&mut self.estimator, e) {
                Ok(Pushed::No) => {}
                Ok(p) => {
                    f |= flags::REVERSAL;
                    self.stats.reversals = self.stats.reversals.wrapping_add(1);
                    if p == Pushed::Clamped {
                        self.stats.clamped = self.stats.clamped.wrapping_add(1);
                    }
                }
                Err(_) => {
                    f |= flags::REVERSAL_REJECTED;
                    self.stats.rejected = self.stats.rejected.wrapping_add(1);
                }
            }
        }
        let top_valid = f & (flags::SATURATED | flags::MISSING) == 0;
        let prediction = model::update(&mut self.estimator, &s.channels, top_valid);
        if f & flags::INVALID != 0 {
            self.stats.invalid = self.stats.invalid.wrapping_add(1);
        }
        let frame = FrameOut {
            index: self.index,
            flags: f,
            event,
            channels: s.channels,
            prediction,
        };
        self.index = self.index.wrapping_add(1);
        self.stats.samples = self.stats.samples.wrapping_add(1);
        frame
    }

    /// The estimator.
    pub fn estimator(&self) -> &Estimator {
        &self.estimator
    }

    /// [`Self::step`], then queue the frame; a full queue drops it and flags the next frame
    /// that gets through with [`flags::OVERRUN`].
    #[cfg_attr(feature = "board", allow(dead_code))]
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
/// `key=value` fields of messages that start with `sample `; a frame with a friction event has
/// three more fields: `ev` ([`EventKind`] as u8), `level` (i8) and `age` (f32, samples).
pub fn emit(f: &FrameOut) {
    match &f.event {
        None => defmt::info!(
            "sample idx={=u32} flags={=u8} table={=f32} base={=f32} top={=f32} disp={=f32} pred={=f32}",
            f.index,
            f.flags,
            f.channels[0],
            f.channels[1],
            f.channels[2],
            f.channels[3],
            f.prediction
        ),
        Some(e) => defmt::info!(
            "sample idx={=u32} flags={=u8} table={=f32} base={=f32} top={=f32} disp={=f32} pred={=f32} ev={=u8} level={=i8} age={=f32}",
            f.index,
            f.flags,
            f.channels[0],
            f.channels[1],
            f.channels[2],
            f.channels[3],
            f.prediction,
            e.kind as u8,
            e.level,
            e.age_samples
        ),
    }
}

/// Stream every queued frame; returns how many.
#[cfg_attr(feature = "board", allow(dead_code))]
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
        "stats samples={=u32} invalid={=u32} dropped={=u32} events={=u32} reversals={=u32} rejected={=u32} sticks={=u32} clamped={=u32}",
        s.samples,
        s.invalid,
        s.dropped,
        s.events,
        s.reversals,
        s.rejected,
        s.sticks,
        s.clamped
    );
}
