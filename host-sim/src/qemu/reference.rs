//! The full-precision references the firmware's predictions are measured against, fed the
//! firmware's own frames one by one (at sample k, the events it had pushed up to k):
//!
//! * rectangular model: the closed form (`DuhamelClosedForm`, f64) of the detected train
//!   ([`DetectedTrain`]: event times t = (k − age)/rate in f64, levels re-accumulated in time
//!   order);
//! * stick-slip and fixed-base models: the stick-slip estimator in f64 (libm transcendentals,
//!   the plan's history and settings) fed the same events (same clamped ages) and the same
//!   measured accelerations.

use crate::scene::Scene;
use anyhow::{anyhow, Result};
use ssvr_core::closed_form::duhamel::{DuhamelClosedForm, Reversal, ReversalTrain};
use ssvr_core::math::Libm;
use ssvr_core::oscillator_id::TopGainFit;
use ssvr_core::stick_slip::{SlidingPhase, StickSlipCoefficients, StickSlipEstimator};
use ssvr_core::Structure;
use ssvr_proto::model::SlipStart;
use ssvr_proto::model::{
    BaseSlot, BaseTuning, Breakaways, FrictionSlot, Mode, SlipFriction, Tuning,
};
use ssvr_proto::plan::MAX_HISTORY;
use ssvr_proto::zeroing::Zeroing;
use ssvr_proto::{flags, EventKind, Frame, ModelKind as Model, Plan, Sample};

/// The friction train the estimator was given, as the firmware's frames report it, for the
/// closed form: events pushed and accepted (flag `REVERSAL`), at t = (k − age)/rate (f64). Kept
/// sorted by time with levels re-accumulated from the pushed jumps, so that the closed form sums
/// exactly the steps the estimator superposed even if a detection back-dates an event before an
/// earlier-pushed one.
#[derive(Debug, Clone, Default)]
pub struct DetectedTrain {
    /// (time, jump) in time order; jumps at equal times merged.
    steps: Vec<(f64, f64)>,
    /// The train for `DuhamelClosedForm` (levels = running sums of the jumps).
    reversals: Vec<Reversal>,
    /// Level after the last push (push order: what the estimator's `level` is).
    level: f64,
    /// Events pushed whose time is before an earlier-pushed event's time.
    pub out_of_order: usize,
    /// Pushed events that changed the level.
    pub level_changes: usize,
}

impl DetectedTrain {
    /// Add the event of sample `k` (if the frame pushed one).
    pub fn push_frame(&mut self, k: u64, f: &Frame, rate_hz: f64) {
        let Some(e) = f.event.filter(|e| !e.is_stick()) else {
            return;
        };
        if f.flags & flags::EVENT_PUSHED == 0 {
            return;
        }
        let level = f64::from(e.level);
        let jump = level - self.level;
        self.level = level;
        if jump == 0.0 {
            return;
        }
        self.level_changes += 1;
        let t = (k as f64 - f64::from(e.age_samples)) / rate_hz;
        let i = self.steps.partition_point(|&(ts, _)| ts < t);
        if i < self.steps.len() {
            self.out_of_order += 1;
        }
        match self.steps.get_mut(i) {
            Some(s) if s.0 == t => s.1 += jump,
            _ => self.steps.insert(i, (t, jump)),
        }
        self.reversals.truncate(i);
        let mut acc = self.reversals.last().map_or(0.0, |r| r.level);
        for &(time_s, d) in &self.steps[i..] {
            acc += d;
            self.reversals.push(Reversal { time_s, level: acc });
        }
    }

    /// The train so far.
    pub fn train(&self) -> ReversalTrain<'_> {
        ReversalTrain::Explicit(&self.reversals)
    }
}

/// The full-precision reference of a model, fed the firmware's frames one by one.
pub enum Reference {
    /// The closed form on the detected train (rectangular model).
    ClosedForm {
        /// The closed form of the structure.
        cf: DuhamelClosedForm,
        /// The train the firmware pushed so far.
        train: Box<DetectedTrain>,
    },
    /// The stick-slip estimator in f64 on the detected events (stick-slip, fixed-base).
    StickSlip {
        /// The accelerometers zeroed on the rest as the pipeline zeroes them (the same code).
        zeroing: Zeroing,
        /// The estimator in f64.
        est: Box<StickSlipEstimator<f64, Libm, MAX_HISTORY>>,
        /// The plan's longest back-dating (older events are clamped to it, as the firmware does).
        max_age: f32,
        /// Last pushed phase, latest pushed event time.
        last: (i8, f64),
        /// Pushed events that changed the phase.
        level_changes: usize,
        /// Pushed events older than an earlier-pushed one.
        out_of_order: usize,
        /// A velocity-dependent law: the firmware's own slip-speed and law code (f32) sets the
        /// f64 estimator's friction per sample, so the reference measures the estimator's
        /// arithmetic.
        friction: Option<Box<SlipFriction>>,
        /// The pipeline's preparation of the inputs (the base's offset and gain against the
        /// table, the table's gain against the displacement).
        inputs: crate::pipeline::InputTracker,
        /// Predict mode (the top accelerometer is not read).
        predict: bool,
        /// Predict mode's tuning from the base accelerometer: the firmware's own code (f32)
        /// gives the sliding samples' top acceleration and the adoptions, applied to the f64
        /// estimator (coefficients re-derived in f64).
        base_tuning: Option<Box<BaseTuning>>,
        /// Fuse mode beside a [`BaseTuning`]: the firmware's own tuning (f32) of f, ξ and the
        /// top accelerometer's gain from the measured top and base, its adoptions applied to
        /// the f64 estimator and the base tuning's top correction.
        tuning: Option<Box<Tuning<TopGainFit<f32>>>>,
        /// The prior, with the f and ξ in use.
        prior: ssvr_core::StructureParams,
        /// The slip starts' breakaway coefficients (the firmware's code).
        breakaways: Breakaways,
        /// The sliding side of the latest slip start its own detector found (the pipeline's).
        start_accel: f32,
        /// A slip start pushed without its sliding side: the force that held the base
        /// (the firmware model's `late_demand`).
        late_demand: Option<f64>,
    },
}

impl Reference {
    /// The reference of a plan's model for a scene: the structure the controller is told (the
    /// plan's prior), as the firmware's model.
    pub fn new(scene: &Scene, plan: &Plan) -> Result<Self> {
        let prior = Structure::new(plan.specimen.structure)
            .map_err(|e| anyhow!("the prior specimen is invalid: {e}"))?;
        let mut r = match plan.model {
            Model::Rectangular => Reference::ClosedForm {
                cf: DuhamelClosedForm::new(&prior),
                train: Box::default(),
            },
            Model::StickSlip | Model::FixedBase => Reference::StickSlip {
                zeroing: Zeroing::new(plan.rest_samples),
                est: Box::new(
                    StickSlipEstimator::with_history(
                        &prior,
                        scene.rate_hz,
                        plan.stick_slip,
                        plan.history,
                    )
                    .map_err(|e| {
                        anyhow!("the f64 stick-slip estimator rejects the scene: {e:?}")
                    })?,
                ),
                max_age: plan.max_age as f32,
                last: (0, f64::NEG_INFINITY),
                level_changes: 0,
                out_of_order: 0,
                // The law the firmware's model keeps (`StickSlipLawModel`'s slot).
                friction: if plan.model == Model::StickSlip && plan.follows_law() {
                    <Option<SlipFriction> as FrictionSlot>::of_plan(plan).map(Box::new)
                } else {
                    None
                },
                inputs: crate::pipeline::input_tracker(plan)?,
                predict: plan.mode == Mode::Predict,
                base_tuning: if plan.model == Model::StickSlip && !plan.follows_law() {
                    <Option<BaseTuning> as BaseSlot>::of_plan(plan).map(Box::new)
                } else {
                    None
                },
                tuning: if plan.model == Model::StickSlip
                    && !plan.follows_law()
                    && plan.mode == Mode::Fuse
                {
                    Tuning::new(plan.specimen.structure, plan.specimen.sample_rate_hz)
                        .map(|t| Box::new(t.after_rest(plan.rest_samples)))
                } else {
                    None
                },
                prior: plan.specimen.structure,
                breakaways: Breakaways::default(),
                start_accel: f32::NAN,
                late_demand: None,
            },
        };
        // (The firmware's fuse mode: the wide sliding observer until f and ξ are known.)
        if let Reference::StickSlip {
            est,
            tuning: Some(_),
            base_tuning: Some(_),
            ..
        } = &mut r
        {
            est.hold_wide(true);
        }
        Ok(r)
    }

    /// What it is, in words (the report's `reference`).
    pub fn name(&self) -> &'static str {
        match self {
            Reference::ClosedForm { .. } => "closed form (f64) on the detected train",
            Reference::StickSlip { .. } => {
                "stick-slip estimator in f64 (libm) on the detected events and measured inputs"
            }
        }
    }

    /// The reference's ü1 at sample k of frame `f` (log sample `s`).
    pub fn step(&mut self, k: u64, f: &Frame, s: &Sample, rate: f64) -> Result<f64> {
        match self {
            Reference::ClosedForm { cf, train } => {
                train.push_frame(k, f, rate);
                let t = k as f64 / rate;
                Ok(cf.evaluate(&train.train(), t, usize::MAX).accel_m_s2)
            }
            Reference::StickSlip {
                zeroing,
                est,
                max_age,
                last,
                level_changes,
                out_of_order,
                friction,
                inputs,
                predict,
                base_tuning,
                tuning,
                prior,
                breakaways,
                start_accel,
                late_demand,
            } => {
                let mut channels = s.channels;
                zeroing.apply(k as u32, &mut channels, f.flags);
                let tracked = inputs(&mut channels, f.flags);
                if tracked.units != 1.0 {
                    // (The table's gain adopted: the model's rescaling, the firmware's code.)
                    breakaways.rescale(tracked.units);
                    if let Some(b) = base_tuning.as_mut() {
                        let level = est.phase().level();
                        let before = b.mu_for(level);
                        b.rescale(tracked.units);
                        let mu = b.mu_for(level);
                        if mu != before {
                            est.set_friction(f64::from(mu));
                            let d = b.top_shift(level, before);
                            if d != 0.0 {
                                est.shift_top(f64::from(d));
                            }
                        }
                    }
                }
                if let Some(a) = tracked.start_accel {
                    *start_accel = a;
                }
                // (A slip start's sliding side a sample late, before this sample's event: the
                // pipeline's order.)
                if tracked.late_start_accel.is_finite() {
                    if let (Some(d), Some(b)) = (late_demand.take(), base_tuning.as_mut()) {
                        if let Some(mu) = est.coefficient_of(d, f64::from(tracked.late_start_accel))
                        {
                            // (Predict mode: the slide's friction from its sliding side.)
                            let level = est.phase().level();
                            let before = b.mu_for(level);
                            if let Some(mu) = b.late_slide_side(mu as f32) {
                                let d = b.top_shift(level, before);
                                est.set_friction_since_event(f64::from(mu), f64::from(d));
                            }
                        }
                    }
                }
                if let Some(e) = f.event.filter(|_| f.flags & flags::EVENT_PUSHED != 0) {
                    let phase = if e.is_stick() { 0 } else { e.level };
                    if let Some(fr) = friction.as_mut() {
                        if phase == 0 {
                            fr.stick();
                        } else {
                            est.set_friction(f64::from(fr.since_slip_start()));
                        }
                    }
                    if e.kind == EventKind::SlipStart {
                        *late_demand = None;
                    }
                    if let Some(b) = base_tuning.as_mut() {
                        // The first slides' friction from the breakaway (the firmware's code).
                        let age = e.age_samples;
                        if e.kind == EventKind::SlipStart && age <= *max_age {
                            let at = SlipStart::of(
                                est.as_ref(),
                                (phase, age),
                                !*predict,
                                *start_accel,
                                breakaways,
                            );
                            if let Some(m) = b.slip_start(&at) {
                                est.set_friction(f64::from(m));
                            }
                            *late_demand = if start_accel.is_nan() {
                                est.slide_demand(f64::from(age), !*predict)
                            } else {
                                None
                            };
                        }
                        if let Some(mu) = b.mu_at_event(phase, e.age_samples) {
                            est.set_friction(f64::from(mu));
                        }
                        b.event(phase, e.age_samples);
                    }
                    if let Some(t) = tuning.as_mut() {
                        // (The base's jump at its time in the identifier's blocks.)
                        t.jump(e.age_samples, tracked.event_step);
                    }
                    let age = e.age_samples.min(*max_age);
                    est.push_event(phase, f64::from(age)).map_err(|err| {
                        anyhow!("the f64 reference rejects the event of sample {k}: {err:?}")
                    })?;
                    let t = (k as f64 - f64::from(age)) / rate;
                    if t < last.1 {
                        *out_of_order += 1;
                    }
                    if phase != last.0 {
                        *level_changes += 1;
                    }
                    *last = (phase, last.1.max(t));
                }
                let valid = f.flags & flags::ACCEL_UNUSABLE == 0;
                let top = if valid && !*predict {
                    f64::from(channels[ssvr_proto::Channel::TopAccel.index()])
                } else {
                    f64::NAN
                };
                let table = channels[ssvr_proto::Channel::TableAccel.index()];
                if let Some(b) = base_tuning.as_mut() {
                    let base = if valid {
                        channels[ssvr_proto::Channel::BaseAccel.index()]
                    } else {
                        f32::NAN
                    };
                    // (Without a rest, with a planned start: the table's offset from the start's
                    // first sample, provisionally.)
                    b.begin_table_start(if valid { table } else { f32::NAN });
                    // (Fuse mode without a rest: the open-loop start, for the top offset.)
                    let open = !*predict && b.open_start() > 0;
                    let y_in = if *predict {
                        b.top_of(base, est.phase().level())
                    } else if open {
                        f32::NAN
                    } else {
                        b.top_corrected(top as f32)
                    };
                    let y = est.update(f64::from(table - b.offset()), f64::from(y_in));
                    if open {
                        b.note_open_start(&[top as f32], &[y as f32]);
                    }
                    b.push_run(&[base], &[top as f32]);
                    // (Without a rest, with a planned start: the table's start, for its
                    // offset, its flagged samples left out, and the model's response to it so
                    // far.)
                    if b.open_start() > 0 {
                        let t = if valid { table } else { f32::NAN };
                        if let Some((off, intervals)) = b.note_table_start(&[t]) {
                            est.remove_input_offset(f64::from(off), intervals);
                        }
                    }
                    let level = est.phase().level();
                    let before = b.mu_for(level);
                    let scale = b.top_scale();
                    let (c, mu) = b.check(1);
                    if c.is_some() {
                        // (Predict mode: the m1 the slip starts found, with f and ξ.)
                        prior.m1_kg = b.m1_in_use();
                        retune(est, prior, b.in_use(), rate)?;
                    }
                    if let Some(mu) = mu {
                        est.set_friction(f64::from(mu));
                        let d = b.top_shift(level, before);
                        if d != 0.0 {
                            est.shift_top(f64::from(d));
                        }
                    }
                    if let Some(t) = tuning.as_mut() {
                        // (Fuse mode: M from the momentum balance, with the f and ξ in use.)
                        if let Some(m1) = b.take_m1() {
                            if t.with_m1(m1).is_some() {
                                b.set_m1(m1);
                                prior.m1_kg = m1;
                                retune(est, prior, t.in_use(), rate)?;
                            }
                        }
                        let raw_base = channels[ssvr_proto::Channel::BaseAccel.index()];
                        t.push_run(&[top as f32], &[raw_base]);
                        if t.check(1).is_some() {
                            retune(est, prior, t.in_use(), rate)?;
                        }
                        est.hold_wide(!t.known());
                        if let Some(g) = t.take_gain() {
                            b.adopt_stuck_gain(g);
                        }
                        if b.top_scale() != scale {
                            t.set_top_scale(b.top_scale());
                        }
                    }
                    return Ok(y);
                }
                if let Some(fr) = friction {
                    let sliding = est.phase() != SlidingPhase::Stuck;
                    let base = if f.flags & flags::ACCEL_UNUSABLE == 0 {
                        channels[ssvr_proto::Channel::BaseAccel.index()]
                    } else {
                        f32::NAN
                    };
                    if let Some(mu) = fr.sample(base, table, top as f32, sliding) {
                        est.set_friction(f64::from(mu));
                    }
                    fr.check(1);
                }
                Ok(est.update(f64::from(table), top))
            }
        }
    }

    /// (pushed events that changed the level, events pushed out of time order).
    pub fn level_changes_and_order(&self) -> (usize, usize) {
        match self {
            Reference::ClosedForm { train, .. } => (train.level_changes, train.out_of_order),
            Reference::StickSlip {
                level_changes,
                out_of_order,
                ..
            } => (*level_changes, *out_of_order),
        }
    }
}

/// The f64 estimator retuned to the f and ξ a firmware tuning adopted (`in_use`: f, ξ,
/// adoptions), its coefficients re-derived in f64 from the prior with them.
fn retune(
    est: &mut StickSlipEstimator<f64, Libm, MAX_HISTORY>,
    prior: &mut ssvr_core::StructureParams,
    (f, xi, _): (f64, f64, u32),
    rate: f64,
) -> Result<()> {
    prior.natural_frequency_hz = f;
    prior.damping_ratio = xi;
    let c = Structure::new(*prior)
        .and_then(|s| StickSlipCoefficients::<f64>::new(&s, rate))
        .map_err(|e| anyhow!("the adopted f, ξ are invalid: {e:?}"))?;
    est.retune(c);
    Ok(())
}
