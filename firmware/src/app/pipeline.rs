//! The pipeline shared by both images: validate a sample, run the friction-event detector on it,
//! feed the detected events to the estimator, predict, and hand a frame to the streaming side.
//!
//! Samples are processed in batches of [`BATCH`] ([`Pipeline::step_batch`]; the board's main
//! loop waits for a whole batch, so predictions come [`BATCH`] samples late; the QEMU replay
//! processes the log in batches and the last, partial one at its end). The QEMU replay owns a
//! [`Pipeline`] and the [`Producer`] of a heapless SPSC queue ([`Pipeline::produce_batch`]); the
//! streaming side owns the [`Consumer`] and turns each [`FrameOut`] into one defmt `sample`
//! message ([`emit`]).
//!
//! The result is that of processing sample by sample, in this order (host-sim's
//! `qemu_cmd::HostPipeline` mirrors it step by step, and the firmware's frames equal its frames
//! bit for bit): steps 1–2 run on every sample of the batch first, then steps 3–4 over the batch
//! in runs split at the samples with an event (the stick-slip estimator's `update_block` on a
//! run is its `update` on each sample, bit for bit):
//!
//! 1. flags: `NOT_FINITE` if a channel is NaN/inf; the displacement is unusable (`DISP_INVALID`)
//!    if the sample is missing, the displacement is not finite, flagged saturated upstream, or at
//!    or beyond the compiled-in full scale `scene::DISP_RANGE_M`;
//! 2. the model's detector processes its input, or NaN when that is unusable (the detector then
//!    repeats its last value and keeps time): the reversal detector (`ssvr_core::detect::displacement`)
//!    the displacement (rectangular, fixed-base), the phase detector (`ssvr_core::detect::acceleration`)
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
use ssvr_core::detect::displacement::SlipEvent;

/// Number of measured channels: table accel, base accel, top accel (m/s²), base-to-table
/// displacement (m).
pub const CHANNELS: usize = 4;

/// Index of the table accelerometer channel.
pub const TABLE: usize = 0;
/// Index of the base accelerometer channel.
pub const BASE: usize = 1;
/// Index of the displacement channel.
pub const DISP: usize = 3;

/// Samples per batch: the pipeline runs the detector on each sample of a batch, then the
/// estimator over the batch (`update_block`) in runs split at the events. 16 (1.6 ms at 10 kHz)
/// brings the stick-slip estimator's steady-state sample under 40 instructions (the cost of
/// each run's set-up and of the identification blocks spread over the run); it is also the
/// board's latency in samples.
pub const BATCH: usize = 16;
const _: () = assert!(
    BATCH >= 1 && BATCH <= 32,
    "events of a batch are a u32 mask"
);

/// Capacity of the sample -> streaming queue (a heapless queue of N holds N - 1 frames). The
/// board streams from its main loop as soon as a frame is queued, so 31 frames (3.1 ms at
/// 10 kHz) of slack is plenty there and keeps its static RAM under 8 KiB with room for the
/// detector's ring at high rates; the QEMU replay drains after every batch.
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

impl FrameOut {
    /// A placeholder (overwritten by [`Pipeline::step_batch`]).
    pub const EMPTY: Self = Self {
        index: 0,
        flags: 0,
        event: None,
        channels: [0.0; CHANNELS],
        prediction: 0.0,
    };
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
    /// The estimator's inputs and outputs of a run.
    buffers: model::RunBuffers,
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
            buffers: model::RunBuffers::new(),
        }
    }

    /// Process a batch of samples (at most [`BATCH`], and at most `frames.len()`; the rest of
    /// `samples` is ignored) into `frames`: per sample, flag it and run the detector; then the
    /// estimator over the batch in runs split at the events, each event pushed before the
    /// update of its sample, exactly as sample by sample (bit for bit: `update_block` is
    /// `update` on a block); the estimator is updated for every sample, valid or not, to keep
    /// time. Returns the number of frames written. Never panics.
    pub fn step_batch(&mut self, samples: &[Sample], frames: &mut [FrameOut]) -> usize {
        let (mut n, mut events) = (0, 0u32);
        for (s, fr) in samples.iter().zip(frames.iter_mut()).take(BATCH) {
            *fr = self.detect(s);
            if fr.event.is_some() {
                events |= 1 << n;
            }
            model::note_inputs(&mut self.buffers, n, fr);
            n += 1;
        }
        let mut i = 0;
        while i < n {
            if let Some(fr) = frames.get_mut(i) {
                if let Some(e) = fr.event {
                    fr.flags |= self.push(&e);
                }
            }
            // The run up to the next event (bit j of `events`: sample j has one).
            let later = events.checked_shr(i as u32 + 1).unwrap_or(0);
            let end = if later == 0 {
                n
            } else {
                i + 1 + later.trailing_zeros() as usize
            };
            if let Some(run) = frames.get_mut(i..end) {
                model::predict_run(&mut self.estimator, run, &mut self.buffers, i);
            }
            i = end;
        }
        n
    }

    /// A sample's flags, its detector event (counted) and its frame (index assigned, no
    /// prediction yet).
    fn detect(&mut self, s: &Sample) -> FrameOut {
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
        if f & flags::INVALID != 0 {
            self.stats.invalid = self.stats.invalid.wrapping_add(1);
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
        }
        let frame = FrameOut {
            index: self.index,
            flags: f,
            event,
            channels: s.channels,
            prediction: 0.0,
        };
        self.index = self.index.wrapping_add(1);
        self.stats.samples = self.stats.samples.wrapping_add(1);
        frame
    }

    /// Push an event to the estimator (before its sample's update): the flags it adds.
    fn push(&mut self, e: &Event) -> u8 {
        match model::push(&mut self.estimator, e) {
            Ok(Pushed::No) => 0,
            Ok(p) => {
                self.stats.reversals = self.stats.reversals.wrapping_add(1);
                if p == Pushed::Clamped {
                    self.stats.clamped = self.stats.clamped.wrapping_add(1);
                }
                flags::REVERSAL
            }
            Err(_) => {
                self.stats.rejected = self.stats.rejected.wrapping_add(1);
                flags::REVERSAL_REJECTED
            }
        }
    }

    /// The estimator.
    pub fn estimator(&self) -> &Estimator {
        &self.estimator
    }

    /// [`Self::step_batch`], then queue the frames; a full queue drops a frame and flags the
    /// next frame that gets through with [`flags::OVERRUN`].
    #[cfg_attr(feature = "board", allow(dead_code))]
    pub fn produce_batch(&mut self, samples: &[Sample], producer: &mut Producer<'_, FrameOut>) {
        let mut frames = [FrameOut::EMPTY; BATCH];
        let n = self.step_batch(samples, &mut frames);
        for mut frame in frames.into_iter().take(n) {
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
