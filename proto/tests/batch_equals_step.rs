//! The firmware runs the pipeline in batches of `BATCH` samples, the host one sample at a time:
//! both must give the same frames bit for bit (flags, events, predictions) and the same counters,
//! for every model, on signals with friction events, events at batch edges, strong jump
//! breakaways whose sliding side comes a sample later, and unusable samples (NaN, missing,
//! saturated), and with the sensor log's reversals as the events; with the
//! table accelerometer's gain identification on (its samples are the detector's, taken one at a
//! time in either case).

use ssvr_core::StructureParams;
use ssvr_proto::log::LogReversal;
use ssvr_proto::{
    flags, AccelerationDetector, DisplacementDetector, EventDetector, EventSource, FixedBaseModel,
    Frame, FromPlan, Mode, Model, ModelKind, Pipeline, Plan, RectangularModel, Sample, Specimen,
    StickSlipModel, BATCH,
};

const H: usize = 2048;

fn specimen() -> Specimen {
    Specimen {
        structure: StructureParams {
            m1_kg: 29.5,
            m2_kg: 1.75,
            natural_frequency_hz: 7.0,
            damping_ratio: 0.05,
            friction_coefficient: 0.2,
            gravity_m_s2: 9.80665,
        },
        static_friction_coefficient: 0.25,
        sample_rate_hz: 10_000.0,
        disp_noise_rms_m: 1e-6,
        accel_noise_rms_m_s2: 5e-3,
        disp_range_m: 0.05,
        friction: ssvr_core::FrictionLaw::Coulomb,
    }
}

/// Sample k: table and top accelerations, a slip acceleration that sticks 600 samples, breaks
/// away and slides (base − table), a displacement triangle (a reversal every 700 samples), and
/// unusable samples here and there; every 997th sample carries a logged reversal.
/// The table acceleration of [`sample`] (`from_rest`: of [`sample_from_rest`]).
fn table_of(k: usize, from_rest: bool) -> f32 {
    let fade = if from_rest { fade(k) } else { 1.0 };
    2.0 * (k as f32 * 1e-4 * 44.0).sin() * fade
}

/// [`sample_from_rest`]'s fade-in.
fn fade(k: usize) -> f32 {
    ((k as f32 / 2000.0).min(1.0)).powi(2)
}

fn sample(k: usize) -> Sample {
    let t = k as f32 * 1e-4;
    let table = table_of(k, false);
    let top = 1.5 * (t * 44.0 + 0.3).sin();
    let m = k % 1000;
    let slip_accel = if m < 600 {
        0.0
    } else if m < 620 {
        0.2 * (m - 599) as f32
    } else if m < 640 {
        -2.0
    } else {
        0.0
    };
    let half = 700;
    let p = k % (2 * half);
    let disp = 1e-5 * (if p < half { p } else { 2 * half - p }) as f32 - 3e-3;
    let mut s = Sample {
        channels: [table, table + slip_accel, top, disp],
        flags: 0,
        reversal: (k % 997 == 5).then_some(LogReversal {
            level: if (k / 997).is_multiple_of(2) { 1 } else { -1 },
            age_samples: 0.25 + (k % 3) as f32,
        }),
    };
    match k % 1237 {
        100 => s.channels[1] = f32::NAN,
        200 => s = Sample::missing(0),
        300 => s.flags = flags::SATURATED,
        400 => s.flags = flags::SATURATED | flags::DISP_INVALID,
        _ => {}
    }
    s
}

/// [`sample`] with strong jump breakaways (μs > μ): every 1001st sample the slip acceleration
/// jumps from 0 to 2 m/s² (~47 of the detector's thresholds, beyond its 20 for a slip start
/// confirmed at its second sample), slides on a ramp for 20 samples, then at −2 m/s² for 20. A
/// period of 1001 samples puts the breakaways at every position of a batch of 16 in turn.
fn sample_with_jumps(k: usize) -> Sample {
    let mut s = sample(k);
    let m = k % 1001;
    let slip_accel = if (600..620).contains(&m) {
        2.0 + 0.1 * (m - 600) as f32
    } else if (620..640).contains(&m) {
        -2.0
    } else {
        0.0
    };
    if s.channels[1].is_finite() {
        s.channels[1] = s.channels[0] + slip_accel;
    }
    s
}

fn compare<M: Model + FromPlan + Clone, D: EventDetector + Clone>(
    model: ModelKind,
    source: EventSource,
) {
    compare_with::<M, D>(model, source, 0.0, [0.0; 3], Signal::Ramps, Mode::Fuse);
}

/// [`sample`] starting at rest: the accelerations faded in over the first 2 000 samples, the
/// top with a deterministic noise of ~5e-3 m/s² (the sensor's).
fn sample_from_rest(k: usize) -> Sample {
    let mut s = sample(k);
    let fade = fade(k);
    let h = (k as u32).wrapping_mul(2_654_435_761).rotate_left(13);
    let noise = ((h >> 8) as f32 / (1u32 << 24) as f32 - 0.5) * 1.7e-2;
    for c in &mut s.channels[..3] {
        *c *= fade;
    }
    s.channels[2] += noise;
    s
}

/// The signals a comparison runs on.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Signal {
    /// [`sample`]: ramp breakaways.
    Ramps,
    /// [`sample_from_rest`].
    FromRest,
    /// [`sample_with_jumps`]: strong jump breakaways.
    Jumps,
}

impl Signal {
    fn sample(self, k: usize) -> Sample {
        match self {
            Signal::Ramps => sample(k),
            Signal::FromRest => sample_from_rest(k),
            Signal::Jumps => sample_with_jumps(k),
        }
    }
}

/// [`compare`] with a rest of `rest_s` before the input and accelerometer offsets, on `signal`,
/// in `mode` (predict mode: the table's planned input the samples' own, less their offset).
fn compare_with<M: Model + FromPlan + Clone, D: EventDetector + Clone>(
    model: ModelKind,
    source: EventSource,
    rest_s: f64,
    bias: [f32; 3],
    signal: Signal,
    mode: Mode,
) -> Pipeline<M, D> {
    let rate = specimen().sample_rate_hz;
    let from_rest = signal == Signal::FromRest;
    // (The planned table: the samples' own before their dropouts.)
    let table = |t: f64| f64::from(table_of((t * rate).round() as usize, from_rest));
    let plan = Plan::new(specimen(), model)
        .unwrap()
        .with_mode(mode)
        .with_rest(rest_s)
        .with_planned_input(table);
    let build = || -> Pipeline<M, D> {
        Pipeline::new(
            M::from_plan(&plan).unwrap(),
            D::from_plan(&plan).unwrap(),
            source,
            plan.disp_range_m(),
        )
        .with_rest(plan.rest_samples)
        .with_table_gain(&plan)
    };
    let (mut one, mut batched) = (build(), build());
    let n = 20_000;
    let samples: Vec<Sample> = (0..n)
        .map(|k| {
            let mut s = signal.sample(k);
            for (c, b) in s.channels.iter_mut().zip(bias) {
                *c += b;
            }
            s
        })
        .collect();
    let single: Vec<Frame> = samples.iter().map(|s| one.step(s)).collect();
    let mut frames = Vec::new();
    // Batches of varying length (1 ..= BATCH) that never straddle a multiple of BATCH, the
    // pipeline's contract (`Pipeline::step_batch`): 1 + 15, 2 + 14, ..., 8 + 8, 16, and the
    // run's last partial one.
    let mut k = 0;
    let mut first = 1;
    while k < n {
        for len in [first, BATCH - first] {
            let end = (k + len).min(n);
            let mut out = [Frame::EMPTY; BATCH];
            let got = batched.step_batch(&samples[k..end], &mut out);
            assert_eq!(got, end - k);
            frames.extend_from_slice(&out[..got]);
            k = end;
        }
        first = first % BATCH + 1;
    }
    let mut events = 0;
    for (i, (a, b)) in single.iter().zip(&frames).enumerate() {
        assert_eq!(a.index, b.index, "{model:?} index @{i}");
        assert_eq!(a.flags, b.flags, "{model:?} flags @{i}");
        assert_eq!(a.event, b.event, "{model:?} event @{i}");
        assert_eq!(
            a.prediction.to_bits(),
            b.prediction.to_bits(),
            "{model:?} prediction @{i}: {} vs {}",
            a.prediction,
            b.prediction
        );
        assert!(
            a.prediction.is_finite(),
            "{model:?} prediction @{i} not finite"
        );
        events += usize::from(a.event.is_some());
    }
    assert_eq!(one.stats, batched.stats, "{model:?} counters");
    assert_eq!(one.offsets(), batched.offsets(), "{model:?} offsets");
    // The identification too (the events' steps in its blocks: `OscillatorIdentifier::jump`).
    assert_eq!(
        ssvr_proto::pipeline::Step::oscillator(&one),
        ssvr_proto::pipeline::Step::oscillator(&batched),
        "{model:?} oscillator"
    );
    assert!(events > 10, "{model:?}: only {events} events");
    assert!(one.stats.invalid > 0, "{model:?}: no invalid sample");
    if model != ModelKind::FixedBase {
        assert!(one.stats.pushed > 10, "{model:?}: {:?}", one.stats);
    }
    one
}

#[test]
fn rectangular_batches_equal_single_steps() {
    compare::<RectangularModel, DisplacementDetector<64>>(
        ModelKind::Rectangular,
        EventSource::Detector,
    );
}

#[test]
fn stick_slip_batches_equal_single_steps() {
    compare::<StickSlipModel<H>, AccelerationDetector<64>>(
        ModelKind::StickSlip,
        EventSource::Detector,
    );
}

#[test]
fn fixed_base_batches_equal_single_steps() {
    compare::<FixedBaseModel<H>, DisplacementDetector<64>>(
        ModelKind::FixedBase,
        EventSource::Detector,
    );
}

#[test]
fn logged_reversals_batches_equal_single_steps() {
    compare::<RectangularModel, DisplacementDetector<64>>(ModelKind::Rectangular, EventSource::Log);
    compare::<StickSlipModel<H>, AccelerationDetector<64>>(ModelKind::StickSlip, EventSource::Log);
}

#[test]
fn zeroed_offsets_batches_equal_single_steps() {
    let bias = [0.49, -0.3, 0.2];
    compare_with::<StickSlipModel<H>, AccelerationDetector<64>>(
        ModelKind::StickSlip,
        EventSource::Detector,
        0.05,
        bias,
        Signal::Ramps,
        Mode::Fuse,
    );
    compare_with::<RectangularModel, DisplacementDetector<64>>(
        ModelKind::Rectangular,
        EventSource::Detector,
        0.05,
        bias,
        Signal::Ramps,
        Mode::Fuse,
    );
}

/// The stick-slip model's offsets (table, base, top) after a run without a rest that starts at
/// rest ([`sample_from_rest`]) with accelerometer offsets `bias`, in `mode`; [`compare_with`]
/// checks batches against single steps.
fn offsets_after_a_start(bias: [f32; 3], mode: Mode) -> [f32; 3] {
    compare_with::<StickSlipModel<H>, AccelerationDetector<64>>(
        ModelKind::StickSlip,
        EventSource::Detector,
        0.0,
        bias,
        Signal::FromRest,
        mode,
    )
    .model()
    .offsets()
}

/// Fuse mode without a rest, starting at rest: the top offset is taken at the end of the
/// open-loop start (`OpenStart`), at the same sample whatever the batching (a batch is split
/// there; before, a batch of 16 took it up to 15 samples later than single steps did).
#[test]
fn an_open_start_batches_equal_single_steps() {
    let top = offsets_after_a_start([0.0, 0.0, 0.2], Mode::Fuse)[2];
    assert!((top - 0.2).abs() < 5e-3, "top offset {top}");
}

#[test]
fn a_model_type_refuses_another_models_plan() {
    let plan = Plan::new(specimen(), ModelKind::StickSlip).unwrap();
    assert!(RectangularModel::from_plan(&plan).is_err());
    assert!(FixedBaseModel::<H>::from_plan(&plan).is_err());
    assert!(DisplacementDetector::<256>::from_plan(&plan).is_err());
    assert!(AccelerationDetector::<128>::from_plan(&plan).is_err());
}

/// Two slip starts in one batch (a slip, a stick and a slip within 16 samples: seen at 1 kHz):
/// each push gets its own slip start's sliding side, noted right before it, in batches as one
/// sample at a time. A detector that scripts the events and a model that records what it gets.
#[test]
fn two_slip_starts_in_a_batch_keep_their_own_sliding_sides() {
    use ssvr_core::detect::displacement::SlipEvent;

    #[derive(Debug, Clone, Default)]
    struct Script {
        k: u32,
    }
    impl EventDetector for Script {
        const INPUT: ssvr_proto::DetectorInput = ssvr_proto::DetectorInput::SlipAcceleration;
        fn from_plan(_: &Plan) -> Result<Self, ssvr_proto::PlanError> {
            Ok(Self::default())
        }
        fn process(&mut self, _: f32) -> Option<SlipEvent> {
            self.k += 1;
            match self.k - 1 {
                3 | 11 | 20 => Some(SlipEvent::SlipStart {
                    direction: 1,
                    age_samples: 0.5,
                }),
                7 | 15 => Some(SlipEvent::Stick { age_samples: 0.5 }),
                _ => None,
            }
        }
        fn max_age_samples(&self) -> usize {
            8
        }
        fn slip_start_accel(&self) -> f32 {
            // The sample it was found at, so that each push shows whose it got.
            (self.k - 1) as f32
        }
    }

    #[derive(Debug, Clone, Default)]
    struct Record {
        noted: f32,
        got: Vec<(ssvr_proto::EventKind, f32)>,
    }
    impl Model for Record {
        fn kind(&self) -> ModelKind {
            ModelKind::StickSlip
        }
        fn push(&mut self, e: &ssvr_proto::Event) -> Result<ssvr_proto::Pushed, ssvr_core::Error> {
            self.got.push((e.kind, self.noted));
            self.noted = f32::NAN;
            Ok(ssvr_proto::Pushed::Yes)
        }
        fn note_slip_start(&mut self, slip_accel: f32) {
            self.noted = slip_accel;
        }
        fn note_inputs(&mut self, _: usize, _: &[f32; ssvr_proto::CHANNELS], _: u8) {}
        fn predict_run(&mut self, _: &mut [Frame], _: usize) {}
        fn mu_estimate(&self) -> Option<ssvr_core::stick_slip::MuEstimate> {
            None
        }
        fn revised(&self, _: u64) -> Option<f32> {
            None
        }
    }

    let samples: Vec<Sample> = (0..2 * BATCH).map(sample).collect();
    let new = || {
        Pipeline::<Record, Script, ()>::new(
            Record {
                noted: f32::NAN,
                ..Record::default()
            },
            Script::default(),
            EventSource::Detector,
            0.05,
        )
    };
    let mut batched = new();
    let mut frames = [Frame::EMPTY; BATCH];
    for chunk in samples.chunks(BATCH) {
        batched.step_batch(chunk, &mut frames);
    }
    let mut single = new();
    for s in &samples {
        single.step(s);
    }
    use ssvr_proto::EventKind::{SlipStart, Stick};
    let want = [
        (SlipStart, 3.0),
        (Stick, f32::NAN),
        (SlipStart, 11.0),
        (Stick, f32::NAN),
        (SlipStart, 20.0),
    ];
    for got in [&batched.model().got, &single.model().got] {
        assert_eq!(got.len(), want.len(), "{got:?}");
        for ((k, a), (wk, wa)) in got.iter().zip(want) {
            assert_eq!(*k, wk);
            assert!(a == &wa || (a.is_nan() && wa.is_nan()), "{got:?}");
        }
    }
}

/// Predict mode without a rest, starting at rest with a table offset: the table's offset is
/// taken at the end of its start against the plan (`BaseTuning::note_table_start`), and the
/// model's response to it removed from its state, at the same sample whatever the batching
/// (the table noise-free: the offset found to f32's rounding, within 1e-5).
#[test]
fn a_table_start_batches_equal_single_steps() {
    let table = offsets_after_a_start([0.2, 0.2, 0.0], Mode::Predict)[0];
    assert!((table - 0.2).abs() < 1e-5, "table offset {table}");
}

/// Strong jump breakaways ([`sample_with_jumps`]) at every position of a batch: confirmed at
/// their second sample, with their sliding side a sample later
/// ([`EventDetector::late_slip_start_accel`]), which may fall in the next batch. The stick-slip
/// model's frames, counters and offsets are the same batched as one sample at a time, in both
/// modes; and every late side the detector gives reaches the model once, in order, among the
/// events (a detector that records its late sides and a model that records what it gets).
#[test]
fn strong_jump_breakaways_batches_equal_single_steps() {
    for mode in [Mode::Fuse, Mode::Predict] {
        compare_with::<StickSlipModel<H>, AccelerationDetector<64>>(
            ModelKind::StickSlip,
            EventSource::Detector,
            0.0,
            [0.0; 3],
            Signal::Jumps,
            mode,
        );
    }

    #[derive(Debug, Clone)]
    struct Watch {
        inner: AccelerationDetector<64>,
        k: usize,
        /// The samples that confirmed a slip start whose side comes a sample later.
        pending_at: Vec<usize>,
        /// The late sides, in order (bits).
        sides: Vec<u32>,
    }
    impl Watch {
        fn after(&mut self, e: Option<SlipEvent>) -> Option<SlipEvent> {
            if self.inner.side_pending() {
                self.pending_at.push(self.k);
            }
            let side = self.inner.late_slip_start_accel();
            if !side.is_nan() {
                self.sides.push(side.to_bits());
            }
            self.k += 1;
            e
        }
    }
    use ssvr_core::detect::displacement::SlipEvent;
    impl EventDetector for Watch {
        const INPUT: ssvr_proto::DetectorInput = AccelerationDetector::<64>::INPUT;
        fn from_plan(plan: &Plan) -> Result<Self, ssvr_proto::PlanError> {
            Ok(Self {
                inner: AccelerationDetector::<64>::from_plan(plan)?,
                k: 0,
                pending_at: Vec::new(),
                sides: Vec::new(),
            })
        }
        fn process(&mut self, x: f32) -> Option<SlipEvent> {
            let e = self.inner.process(x);
            self.after(e)
        }
        fn process_with_reference(&mut self, x: f32, table_accel: f32) -> Option<SlipEvent> {
            let e = self.inner.process_with_reference(x, table_accel);
            self.after(e)
        }
        fn max_age_samples(&self) -> usize {
            self.inner.max_age_samples()
        }
        fn offset(&self) -> f32 {
            self.inner.offset()
        }
        fn gain_mismatch(&self) -> f32 {
            self.inner.gain_mismatch()
        }
        fn slip_start_accel(&self) -> f32 {
            self.inner.slip_start_accel()
        }
        fn side_pending(&self) -> bool {
            self.inner.side_pending()
        }
        fn late_slip_start_accel(&self) -> f32 {
            self.inner.late_slip_start_accel()
        }
        fn event_step(&self, age: f32, stick: bool) -> ssvr_core::detect::EventStep {
            self.inner.event_step(age, stick)
        }
    }

    /// What the model got: an event's kind, or a late side (bits).
    #[derive(Debug, Clone, Copy, PartialEq)]
    enum Got {
        Event(ssvr_proto::EventKind),
        Late(u32),
    }
    #[derive(Debug, Clone, Default)]
    struct Record {
        got: Vec<Got>,
    }
    impl Model for Record {
        fn kind(&self) -> ModelKind {
            ModelKind::StickSlip
        }
        fn push(&mut self, e: &ssvr_proto::Event) -> Result<ssvr_proto::Pushed, ssvr_core::Error> {
            self.got.push(Got::Event(e.kind));
            Ok(ssvr_proto::Pushed::Yes)
        }
        fn note_late_slip_start(&mut self, slip_accel: f32) {
            self.got.push(Got::Late(slip_accel.to_bits()));
        }
        fn note_inputs(&mut self, _: usize, _: &[f32; ssvr_proto::CHANNELS], _: u8) {}
        fn predict_run(&mut self, _: &mut [Frame], _: usize) {}
        fn mu_estimate(&self) -> Option<ssvr_core::stick_slip::MuEstimate> {
            None
        }
        fn revised(&self, _: u64) -> Option<f32> {
            None
        }
    }

    let plan = Plan::new(specimen(), ModelKind::StickSlip).unwrap();
    let new = || {
        Pipeline::<Record, Watch, ()>::new(
            Record::default(),
            Watch::from_plan(&plan).unwrap(),
            EventSource::Detector,
            plan.disp_range_m(),
        )
    };
    let samples: Vec<Sample> = (0..20_000).map(sample_with_jumps).collect();
    let mut single = new();
    for s in &samples {
        single.step(s);
    }
    let mut batched = new();
    let mut frames = [Frame::EMPTY; BATCH];
    for chunk in samples.chunks(BATCH) {
        batched.step_batch(chunk, &mut frames);
    }
    let watch = single.detector();
    assert_eq!(watch.pending_at, batched.detector().pending_at);
    assert_eq!(watch.sides, batched.detector().sides);
    // Every breakaway but the first (the offsets' first samples) confirmed early, at every
    // position of a batch, and each gives its side.
    let positions: std::collections::BTreeSet<usize> =
        watch.pending_at.iter().map(|k| k % BATCH).collect();
    assert_eq!(positions.len(), BATCH, "{:?}", watch.pending_at);
    assert!(watch.pending_at.len() >= 18, "{:?}", watch.pending_at);
    assert_eq!(watch.sides.len(), watch.pending_at.len());
    for side in &watch.sides {
        let side = f32::from_bits(*side);
        assert!((side - 2.0).abs() < 0.1, "side {side}");
    }
    // The model gets each, once, in order, in batches as one sample at a time.
    assert_eq!(batched.model().got, single.model().got);
    let lates: Vec<u32> = single
        .model()
        .got
        .iter()
        .filter_map(|g| match g {
            Got::Late(bits) => Some(*bits),
            Got::Event(_) => None,
        })
        .collect();
    assert_eq!(lates, watch.sides);
}
