//! The per-sample pipeline step, the one the firmware runs and the host runs for `host-sim run`
//! and to check the firmware: flag a sample, run the friction-event detector on it, push its
//! event to the model, predict.
//!
//! Samples are processed in batches of at most [`BATCH`] ([`Pipeline::step_batch`]); the result
//! is that of processing them one at a time ([`Pipeline::step`] is a batch of one), in this
//! order: steps 1–2 on every sample of the batch first, then steps 3–4 over the batch in runs
//! split at the samples with an event or with the table accelerometer's gain adopted
//! ([`Model::rescale_units`] before that sample) (a model's prediction of a run is its
//! per-sample prediction on each sample, bit for bit):
//!
//! 1. flags: `NOT_FINITE` if a channel is NaN/inf; `MISSING` with `ADC_ERROR`; the displacement
//!    is unusable (`DISP_INVALID`) if the sample is missing, the displacement is not finite,
//!    flagged saturated upstream, or at or beyond the displacement full scale; the
//!    accelerometers' offsets are removed ([`Zeroing`] on a rest before the input) (a missing
//!    sample's channels are NaN: the stick-slip estimator holds its last table acceleration);
//! 2. the detector processes its input ([`crate::DetectorInput::of`]; NaN when unusable) with the
//!    table acceleration (the slip-acceleration detector removes the accelerometers' gain
//!    mismatch against it); its event, or with [`EventSource::Log`] the sample's logged
//!    reversal, is the sample's; the model's inputs are prepared ([`model_inputs`]: the base in
//!    the table's units, and with [`Pipeline::with_table_gain`] the table accelerometer's gain
//!    identified against the displacement and divided out of every accelerometer);
//! 3. the event goes to the model ([`Model::push`]) before the sample's prediction: flags
//!    `EVENT_PUSHED` or `EVENT_REJECTED`;
//! 4. the model predicts the sample (always, valid or not, to keep time).

use crate::channel::Channel;
use crate::detector::EventDetector;
use crate::event::{Event, EventKind};
use crate::flags;
use crate::frame::{Frame, Sample};
use crate::model::{Model, Pushed};
use crate::table_gain::{GainEstimate, GainSlot, TableGain};
use crate::zeroing::Zeroing;
use ssvr_core::detect::EventStep;
use ssvr_core::stick_slip::MuEstimate;

/// Samples per batch: 16 (1.6 ms at 10 kHz) brings the stick-slip estimator's steady-state
/// sample under 40 M4F instructions (each run's set-up and the identification blocks spread
/// over the run); it is also the board's latency in samples.
pub const BATCH: usize = 16;
const _: () = assert!(
    BATCH >= 1 && BATCH <= 32,
    "events of a batch are a u32 mask"
);

/// A sample's zeroed `channels` (flags `f`) as the model reads them, the one preparation the
/// pipeline and the host's f64 reference share:
///
/// 1. the base is read in the table accelerometer's units: less the `offset` of the slip
///    acceleration, divided by 1 + the gain mismatch `k` (the base's gain relative to the
///    table's, minus 1) that the detector tracks;
/// 2. the table accelerometer's gain identification ([`TableGain::push`], when there is one)
///    takes the base less the table, the displacement (unless the flags say they are unusable)
///    and the detector's `event`;
/// 3. the three accelerometers are divided by the table's adopted gain.
#[inline(always)]
pub fn model_inputs(
    channels: &mut [f32; crate::CHANNELS],
    f: u8,
    (offset, k): (f32, f32),
    gain: Option<&mut TableGain>,
    index: u32,
    event: Option<&ssvr_core::detect::displacement::SlipEvent>,
) {
    let base = &mut channels[Channel::BaseAccel.index()];
    *base = (*base - offset) / (1.0 + k);
    if let Some(gain) = gain {
        table_gain_step(gain, channels, f, index, event);
    }
}

/// A detected slip start's sliding side (`slip_accel`, the detector's
/// [`EventDetector::slip_start_accel`]) in the units the model reads after [`model_inputs`]: the
/// detector's slip acceleration is the base accelerometer's units (the gain mismatch `k` to the
/// table's removed from the table's share, not from the base's), so divided by 1 + k, and
/// multiplied by the table gain's `inverse` (1 without one) as the accelerometers are.
#[inline(always)]
pub fn slip_start_input(slip_accel: f32, k: f32, inverse: f32) -> f32 {
    slip_accel / (1.0 + k) * inverse
}

/// Steps 2–3 of [`model_inputs`].
#[inline(always)]
fn table_gain_step(
    gain: &mut TableGain,
    channels: &mut [f32; crate::CHANNELS],
    f: u8,
    index: u32,
    event: Option<&ssvr_core::detect::displacement::SlipEvent>,
) {
    let table = channels[Channel::TableAccel.index()];
    let base = channels[Channel::BaseAccel.index()];
    // (A NaN base or table makes `a` NaN, held by the gain; a NaN top does not matter here.
    // Saturation is flagged per sample, not per channel: a saturated sample is not used.)
    let a = if f & (flags::MISSING | flags::SATURATED) == 0 {
        base - table
    } else {
        f32::NAN
    };
    let s = if f & flags::DISP_INVALID == 0 {
        channels[Channel::Displacement.index()]
    } else {
        f32::NAN
    };
    gain.push(index, a, s, event);
    let inv = gain.inverse();
    const _: () = assert!(
        Channel::TableAccel.index() == 0
            && Channel::BaseAccel.index() == 1
            && Channel::TopAccel.index() == 2
    );
    let [table, base, top, _] = channels;
    (*table, *base, *top) = (*table * inv, *base * inv, *top * inv);
}

/// Where the model's friction events come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventSource {
    /// The detector (the firmware's path).
    Detector,
    /// The reversals carried by the sensor log's records (the QEMU image's test hook; the
    /// detector still runs, its events are not used).
    Log,
}

/// A batch's events as its samples are detected ([`Pipeline::step_batch`]).
struct BatchEvents {
    /// Bit j: sample j has an event.
    mask: u32,
    /// The slip starts' sliding sides, in order, for their pushes (a batch may hold two; a
    /// third, were there one, would go without: the breakaway's μ instead).
    starts: [f32; 2],
    noted: usize,
    /// The base's step and kink at each event, in order; a fifth event in one batch, were
    /// there one, would go without (its identification blocks as sampled).
    steps: [EventStep; 4],
    stepped: usize,
    /// Bit j: sample j brings the sliding side of a slip start confirmed at its second sample
    /// ([`EventDetector::late_slip_start_accel`]); the sides, in order (three at most: the
    /// batch's first may belong to the previous batch's last slip start, beside two of its own).
    late_mask: u32,
    lates: [f32; 3],
    late_noted: usize,
    /// Bit j: the table accelerometer's gain was adopted at sample j (its samples and those
    /// after it in the new units), the units' factor ([`Model::rescale_units`]).
    units_mask: u32,
    units: f32,
}

impl BatchEvents {
    #[inline(always)]
    fn new() -> Self {
        Self {
            mask: 0,
            starts: [f32::NAN; 2],
            noted: 0,
            steps: [EventStep::UNKNOWN; 4],
            stepped: 0,
            late_mask: 0,
            lates: [f32::NAN; 3],
            late_noted: 0,
            units_mask: 0,
            units: 1.0,
        }
    }
}

/// Counters of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Samples processed (model predictions).
    pub samples: u32,
    /// Samples with any of [`flags::INVALID`].
    pub invalid: u32,
    /// Frames dropped because the streaming queue was full (counted by the streaming side).
    pub dropped: u32,
    /// Friction events (slip starts, reversals, sticks; or logged reversals).
    pub events: u32,
    /// Events pushed to and accepted by the model (sticks too, for the stick-slip model).
    pub pushed: u32,
    /// Events the model rejected.
    pub rejected: u32,
    /// Sticks among the events.
    pub sticks: u32,
    /// Events pushed with their age clamped to the model's history.
    pub clamped: u32,
}

/// The detector, the model and the sample clock.
#[derive(Debug, Clone)]
pub struct Pipeline<M, D, G = Option<TableGain>> {
    model: M,
    detector: D,
    source: EventSource,
    disp_range_m: f32,
    index: u32,
    zeroing: Zeroing,
    gain: G,
    /// The last slip start's sliding side comes with the next sample
    /// ([`EventDetector::side_pending`]).
    side_due: bool,
    /// Counters.
    pub stats: Stats,
}

impl<M: Model, D: EventDetector, G: GainSlot> Pipeline<M, D, G> {
    /// Start at sample 0; a displacement at or beyond ±`disp_range_m` is unusable.
    pub fn new(model: M, detector: D, source: EventSource, disp_range_m: f32) -> Self {
        Self {
            model,
            detector,
            source,
            disp_range_m,
            index: 0,
            zeroing: Zeroing::new(0),
            gain: G::none(),
            side_due: false,
            stats: Stats::default(),
        }
    }

    /// Identify the table accelerometer's gain against the displacement sensor ([`TableGain`])
    /// when `plan` does ([`crate::Plan::identifies_table_gain`]) and give the model every
    /// accelerometer divided by it (nothing with the slot `G = ()`: [`GainSlot`]).
    pub fn with_table_gain(mut self, plan: &crate::Plan) -> Self {
        if let Some(g) = TableGain::of_plan(plan, self.detector.max_age_samples()) {
            self.gain = G::of(g);
        }
        self
    }

    /// The table accelerometer's gain (1 + e) identified against the displacement sensor.
    pub fn table_gain(&self) -> Option<GainEstimate> {
        self.gain.get().and_then(TableGain::estimate)
    }

    /// Zero the accelerometers on a rest of `rest_samples` samples before the input
    /// ([`Zeroing`]).
    pub fn with_rest(mut self, rest_samples: u32) -> Self {
        self.zeroing = Zeroing::new(rest_samples);
        self
    }

    /// The accelerometers' offsets the model identified and removes from its inputs beyond
    /// [`Self::offsets`] ([`Model::offsets`]).
    pub fn model_offsets(&self) -> [f32; 3] {
        self.model.offsets()
    }

    /// The accelerometers' offsets removed (m/s²): table, base, top; the base's includes the
    /// offset its detector tracks against the table.
    pub fn offsets(&self) -> [f32; 3] {
        let mut o = self.zeroing.offsets();
        o[1] += self.detector.offset();
        o
    }

    /// Process a batch of samples (at most [`BATCH`], and at most `frames.len()`; the rest of
    /// `samples` is ignored) into `frames`. Returns the number of frames written. Never panics.
    /// Batches that never straddle a multiple of [`BATCH`] samples from the run's start (the
    /// board's whole batches; a replay's last partial one) give the frames of one sample at a
    /// time bit for bit: the model's checks fall due at multiples of `BATCH` samples and are
    /// made at a run's end (`proto/tests/batch_equals_step.rs`). A batch across such a multiple
    /// makes a check due inside it at its end instead, and an adoption then starts later.
    pub fn step_batch(&mut self, samples: &[Sample], frames: &mut [Frame]) -> usize {
        let mut n = 0;
        let mut ev = BatchEvents::new();
        let first = self.index;
        for (s, fr) in samples.iter().zip(frames.iter_mut()).take(BATCH) {
            let channels;
            (*fr, channels) = self.detect(s);
            if self.side_due {
                self.note_late_side(&mut ev, n);
            }
            if let Some(e) = &fr.event {
                self.note_event(&mut ev, n, e);
            }
            self.model.note_inputs(n, &channels, fr.flags);
            n += 1;
        }
        if let Some((at, c)) = self.gain.get_mut().and_then(TableGain::take_change) {
            Self::note_units(&mut ev, at.wrapping_sub(first), c);
        }
        let BatchEvents {
            mask: events,
            starts,
            steps,
            late_mask,
            lates,
            units_mask,
            units,
            ..
        } = ev;
        let split = events | units_mask;
        let (mut i, mut pushed, mut stepped, mut late) = (0, 0usize, 0usize, 0usize);
        while i < n {
            if units_mask & (1 << i) != 0 {
                self.model.rescale_units(units);
            }
            if late_mask & (1 << i) != 0 {
                self.model
                    .note_late_slip_start(lates.get(late).copied().unwrap_or(f32::NAN));
                late += 1;
            }
            if let Some(fr) = frames.get_mut(i) {
                if let Some(e) = fr.event {
                    if e.kind == EventKind::SlipStart {
                        let a = starts.get(pushed).copied().unwrap_or(f32::NAN);
                        self.model.note_slip_start(a);
                        pushed += 1;
                    }
                    self.model
                        .note_event_step(steps.get(stepped).copied().unwrap_or(EventStep::UNKNOWN));
                    stepped += 1;
                    fr.flags |= self.push(&e);
                }
            }
            // The run up to the next event or change of units (bit j: sample j has one).
            let later = split.checked_shr(i as u32 + 1).unwrap_or(0);
            let end = if later == 0 {
                n
            } else {
                i + 1 + later.trailing_zeros() as usize
            };
            if let Some(run) = frames.get_mut(i..end) {
                self.model.predict_run(run, i);
            }
            i = end;
        }
        n
    }

    /// The event `e` just detected at sample `n` of the batch, into `ev`: its bit, the base's
    /// step at it ([`EventDetector::event_step`]) and a slip start's sliding side
    /// ([`EventDetector::slip_start_accel`]), both in the model's units ([`slip_start_input`]).
    /// (Out of the samples' loop: the steps in it cost the whole step ~9 instructions a sample
    /// without any event.)
    #[cold]
    #[inline(never)]
    fn note_event(&mut self, ev: &mut BatchEvents, n: usize, e: &Event) {
        ev.mask |= 1 << n;
        let k = self.detector.gain_mismatch();
        let inverse = self.gain.get().map_or(1.0, TableGain::inverse);
        if let Some(x) = ev.steps.get_mut(ev.stepped) {
            let stick = e.kind == EventKind::Stick;
            *x = self
                .detector
                .event_step(e.age_samples, stick)
                .scaled(slip_start_input(1.0, k, inverse));
        }
        ev.stepped += 1;
        if e.kind == EventKind::SlipStart {
            if let Some(a) = ev.starts.get_mut(ev.noted) {
                *a = slip_start_input(self.detector.slip_start_accel(), k, inverse);
            }
            ev.noted += 1;
            self.side_due = self.detector.side_pending();
        }
    }

    /// The table accelerometer's gain adopted at sample `n` of the batch, the samples' units
    /// changed by `c` from it on: noted for the model's rescaling before that sample's run
    /// ([`Model::rescale_units`]).
    #[cold]
    #[inline(never)]
    fn note_units(ev: &mut BatchEvents, n: u32, c: f32) {
        if (n as usize) < BATCH {
            ev.units_mask = 1 << n;
            ev.units = c;
        }
    }

    /// The sample `n` after a slip start confirmed at its second sample: its sliding side, in
    /// the model's units, noted for the model before the sample's run (the run starts there).
    #[cold]
    #[inline(never)]
    fn note_late_side(&mut self, ev: &mut BatchEvents, n: usize) {
        self.side_due = false;
        let a = self.detector.late_slip_start_accel();
        if a.is_nan() {
            return;
        }
        let inverse = self.gain.get().map_or(1.0, TableGain::inverse);
        if let Some(x) = ev.lates.get_mut(ev.late_noted) {
            *x = slip_start_input(a, self.detector.gain_mismatch(), inverse);
            ev.late_mask |= 1 << n;
            ev.mask |= 1 << n;
        }
        ev.late_noted += 1;
    }

    /// One sample (a batch of one).
    pub fn step(&mut self, s: &Sample) -> Frame {
        let mut f = [Frame::EMPTY];
        self.step_batch(core::slice::from_ref(s), &mut f);
        f[0]
    }

    /// A sample's flags, its event (counted), its frame (index assigned, no prediction yet) and
    /// its channels with the accelerometers' offsets removed.
    #[inline(always)]
    fn detect(&mut self, s: &Sample) -> (Frame, [f32; crate::CHANNELS]) {
        let mut f = s.flags & flags::ACQUISITION;
        if f & flags::ADC_ERROR != 0 {
            f |= flags::MISSING;
        }
        // (Written out: the firmware, built for size, looped over the four at ~7 instructions
        // each.)
        let [c0, c1, c2, c3] = s.channels;
        if !(c0.is_finite() && c1.is_finite() && c2.is_finite() && c3.is_finite()) {
            f |= flags::NOT_FINITE;
        }
        let disp = s.channels[Channel::Displacement.index()];
        if f & flags::MISSING != 0 || !disp.is_finite() || disp.abs() >= self.disp_range_m {
            f |= flags::DISP_INVALID;
        }
        if f & flags::INVALID != 0 {
            self.stats.invalid = self.stats.invalid.wrapping_add(1);
        }
        let mut channels = s.channels;
        self.zeroing.apply(self.index, &mut channels, f);
        let detected = self.detector.process_with_reference(
            D::INPUT.of(&channels, f),
            channels[Channel::TableAccel.index()],
        );
        // The base accelerometer's offset and gain against the table's, tracked by the detector
        // while the base sticks: the models read the base corrected by them (in the table
        // accelerometer's units).
        model_inputs(
            &mut channels,
            f,
            (self.detector.base_offset(), self.detector.gain_mismatch()),
            self.gain.get_mut(),
            self.index,
            detected.as_ref(),
        );
        let event = match self.source {
            EventSource::Detector => detected.as_ref().map(Event::from_detector),
            EventSource::Log => s.reversal.map(|r| Event {
                kind: EventKind::Log,
                level: r.level,
                age_samples: r.age_samples,
            }),
        };
        if let Some(e) = &event {
            self.stats.events = self.stats.events.wrapping_add(1);
            if e.is_stick() {
                self.stats.sticks = self.stats.sticks.wrapping_add(1);
            }
        }
        let frame = Frame {
            index: self.index,
            flags: f,
            event,
            channels: s.channels,
            prediction: 0.0,
        };
        self.index = self.index.wrapping_add(1);
        self.stats.samples = self.stats.samples.wrapping_add(1);
        (frame, channels)
    }

    /// Push an event to the model (before its sample's prediction): the flags it adds.
    fn push(&mut self, e: &Event) -> u8 {
        match self.model.push(e) {
            Ok(Pushed::No) => 0,
            Ok(p) => {
                self.stats.pushed = self.stats.pushed.wrapping_add(1);
                if p == Pushed::Clamped {
                    self.stats.clamped = self.stats.clamped.wrapping_add(1);
                }
                flags::EVENT_PUSHED
            }
            Err(_) => {
                self.stats.rejected = self.stats.rejected.wrapping_add(1);
                flags::EVENT_REJECTED
            }
        }
    }

    /// The model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The detector.
    pub fn detector(&self) -> &D {
        &self.detector
    }
}

/// A pipeline whatever its model and detector (the host picks them at run time).
pub trait Step {
    /// [`Pipeline::step_batch`].
    fn step_batch(&mut self, samples: &[Sample], frames: &mut [Frame]) -> usize;
    /// [`Pipeline::step`].
    fn step(&mut self, s: &Sample) -> Frame;
    /// The counters.
    fn stats(&self) -> Stats;
    /// The model's identified friction coefficient.
    fn mu_estimate(&self) -> Option<MuEstimate>;
    /// The model's revised prediction of an earlier sample ([`Model::revised`]).
    fn revised(&self, sample: u64) -> Option<f32>;
    /// The detector's longest back-dating (samples).
    fn max_age_samples(&self) -> usize;
    /// [`Pipeline::offsets`].
    fn offsets(&self) -> [f32; 3];
    /// [`Pipeline::table_gain`].
    fn table_gain(&self) -> Option<GainEstimate>;
    /// [`Pipeline::model_offsets`].
    fn model_offsets(&self) -> [f32; 3];
    /// The model's identified and adopted f and ξ ([`Model::oscillator`]).
    fn oscillator(&self) -> Option<crate::model::OscillatorReport>;
    /// The model's static friction identified at the slip starts ([`Model::static_friction`]).
    fn static_friction(&self) -> Option<crate::model::StaticFriction>;
    /// The base accelerometer's gain against the table's, as its detector tracks and removes it
    /// ([`EventDetector::gain_mismatch`]; 0 for the displacement detector).
    fn gain_mismatch(&self) -> f32;
    /// The model's velocity-dependent friction law ([`Model::friction_law`]).
    fn friction_law(&self) -> Option<crate::model::FrictionReport>;
}

impl<M: Model, D: EventDetector, G: GainSlot> Step for Pipeline<M, D, G> {
    fn step_batch(&mut self, samples: &[Sample], frames: &mut [Frame]) -> usize {
        Pipeline::step_batch(self, samples, frames)
    }
    fn step(&mut self, s: &Sample) -> Frame {
        Pipeline::step(self, s)
    }
    fn stats(&self) -> Stats {
        self.stats
    }
    fn mu_estimate(&self) -> Option<MuEstimate> {
        self.model.mu_estimate()
    }
    fn revised(&self, sample: u64) -> Option<f32> {
        self.model.revised(sample)
    }
    fn max_age_samples(&self) -> usize {
        self.detector.max_age_samples()
    }
    fn model_offsets(&self) -> [f32; 3] {
        Pipeline::model_offsets(self)
    }
    fn offsets(&self) -> [f32; 3] {
        Pipeline::offsets(self)
    }
    fn table_gain(&self) -> Option<GainEstimate> {
        Pipeline::table_gain(self)
    }
    fn oscillator(&self) -> Option<crate::model::OscillatorReport> {
        self.model.oscillator()
    }
    fn static_friction(&self) -> Option<crate::model::StaticFriction> {
        self.model.static_friction()
    }
    fn gain_mismatch(&self) -> f32 {
        self.detector.gain_mismatch()
    }
    fn friction_law(&self) -> Option<crate::model::FrictionReport> {
        self.model.friction_law()
    }
}

#[cfg(test)]
mod tests {
    /// A slip start's sliding side in the model's units: accelerometers with gains 1 + e_b (base)
    /// and 1 + e_t (table), a true slip acceleration of 2 m/s² on a table at 1 m/s². The
    /// detector's s̈ (base − table less k times the table, k = (e_b − e_t)/(1 + e_t)) comes out
    /// (1 + e_b)·2; the model reads (base/(1 + k) − table)/(1 + e_t) = 2; so must the slip start's.
    #[test]
    fn a_slip_starts_sliding_side_is_in_the_models_units() {
        let (e_b, e_t) = (0.01f32, -0.01f32);
        let (base, table) = ((1.0 + e_b) * 3.0, (1.0 + e_t) * 1.0);
        let k = (e_b - e_t) / (1.0 + e_t);
        let detector = base - table - k * table;
        let inverse = 1.0 / (1.0 + e_t);
        let model = (base / (1.0 + k) - table) * inverse;
        assert!((model - 2.0).abs() < 1e-6, "{model}");
        let got = super::slip_start_input(detector, k, inverse);
        assert!((got - 2.0).abs() < 1e-6, "{got}");
    }
}
