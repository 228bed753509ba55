//! The stick-slip model (and the fixed-base model: the same estimator, no event pushed): the
//! stick-slip estimator `StickSlipEstimator<f32, F32Poly, H>`, driven by the measured table
//! acceleration and, for the friction identification and the stuck-phase observer, the measured
//! top acceleration (NaN, i.e. not used, when the sample is saturated or missing). Slip starts
//! and reversals are pushed as `push_event(level, age)`, sticks as `push_event(0, age)`; an age
//! beyond the plan's longest back-dating is clamped to it. A run of samples is predicted with
//! `update_block` (bit for bit `update` on each sample).

use super::base_tuning::{BaseSlot, BaseTuning, SlipStart};
use super::friction::{FrictionReport, FrictionSlot, SlipFriction};
use super::tuning::{OscillatorReport, Tuning};
use super::{Breakaways, FromPlan, Mode, Model, ModelKind, Pushed, StaticFriction};
use crate::channel::{Channel, CHANNELS};
use crate::event::{Event, EventKind};
use crate::flags;
use crate::frame::Frame;
use crate::pipeline::BATCH;
use crate::plan::{Plan, PlanError};
use ssvr_core::detect::EventStep;
use ssvr_core::math::F32Poly;
use ssvr_core::stick_slip::{MuEstimate, SlidingPhase, StickSlipCoefficients, StickSlipEstimator};
use ssvr_core::Error;

mod base_runs;

/// The stick-slip estimator in f32 with storage for `H` samples of history.
pub type StickSlipF32<const H: usize> = StickSlipEstimator<f32, F32Poly, H>;

/// The stick-slip model (`EVENTS` true: events pushed) or, with `EVENTS` false, the fixed-base
/// model ([`FixedBaseModel`]: no event pushed, so the image holds no event code). `F` keeps a
/// velocity-dependent friction law ([`FrictionSlot`]; `()` for the fixed-base model), `B` the
/// predict mode's tuning from the base accelerometer ([`BaseSlot`]; `()` for the fixed-base
/// model and under a velocity-dependent law).
///
/// (`repr(C)`: the fields in the order written, the estimator's state first and the base
/// tuning, whose cold part is large, last; the small fields together, with no padding between
/// them, for the fixed-base image's 8 KiB of RAM (8 184 B). The M4F's loads reach ±1020 B from a
/// base register for floats, so where the compiler puts the per-sample fields moves the
/// per-sample count: with rustc's own order a base tuning 40 B larger took the fuse mode from
/// 251.7 to 266.0 instructions; laid out so, 252.0; docs/PERFORMANCE.md.)
#[derive(Debug, Clone)]
#[repr(C)]
pub struct StickSlipModel<
    const H: usize,
    const EVENTS: bool = true,
    F: FrictionSlot = (),
    B: BaseSlot = Option<BaseTuning>,
> {
    est: StickSlipF32<H>,
    /// f and ξ identified and adopted online (fuse mode), with the top accelerometer's gain
    /// beside a [`BaseTuning`] (which corrects the top by it).
    tuning: Option<Tuning<B::TopGain>>,
    /// The batch's noted inputs (`note_inputs`), used up by its runs: the table acceleration
    /// (a steady run with a base tuning leaves it less the table offset in use),
    table: [f32; BATCH],
    /// the measured top acceleration (NaN when unusable or in predict mode; such a run leaves
    /// the model's top input),
    top: [f32; BATCH],
    /// and the base acceleration (NaN when the sample is saturated or missing, for a base tuning
    /// or a friction law; such a run leaves its predictions).
    base: [f32; BATCH],
    max_age: f32,
    breakaways: Breakaways,
    /// The slip acceleration on the sliding side of the slip start to push (the detector's,
    /// noted with its sample).
    start_accel: f32,
    /// A slip start pushed without its sliding side (it comes a sample later:
    /// `Model::note_late_slip_start`; NaN: none): the force that held the base at it
    /// ([`StickSlipEstimator::slide_demand`](ssvr_core::stick_slip::StickSlipEstimator::slide_demand)).
    late_demand: f32,
    /// The base's step at the event about to be pushed (`Model::note_event_step`).
    event_step: EventStep,
    /// Fuse mode: the breakaway coefficients read the measured top acceleration (else the
    /// model's own).
    fuse: bool,
    /// A velocity-dependent friction law (None: Coulomb).
    friction: F,
    /// The identification from the sliding base ([`BaseTuning`]): predict mode's f, ξ, μ and
    /// top acceleration of the sliding samples by the momentum balance, either mode's offsets
    /// (and fuse mode's top gain).
    base_tuning: B,
}

/// The estimator's inputs of a sample: the table acceleration, and the top acceleration (NaN
/// when the sample is saturated or missing, or in predict mode: `fuse` false).
#[inline(always)]
fn inputs(channels: &[f32; CHANNELS], f: u8, fuse: bool) -> (f32, f32) {
    let top = if fuse && f & flags::ACCEL_UNUSABLE == 0 {
        channels[Channel::TopAccel.index()]
    } else {
        f32::NAN
    };
    (channels[Channel::TableAccel.index()], top)
}

/// The stick-slip model following a velocity-dependent friction law (a plan whose specimen has
/// one): μ per sliding sample from the slip speed, the law identified online in fuse mode.
pub type StickSlipLawModel<const H: usize> = StickSlipModel<H, true, Option<SlipFriction>, ()>;

/// The fixed-base model: the stick-slip estimator held stuck, no event pushed.
pub type FixedBaseModel<const H: usize> = StickSlipModel<H, false, (), ()>;

impl<const H: usize, const EVENTS: bool, F: FrictionSlot, B: BaseSlot>
    StickSlipModel<H, EVENTS, F, B>
{
    /// The model on an estimator; events older than `max_age` samples are pushed with that age.
    pub fn new(est: StickSlipF32<H>, max_age: f32) -> Self {
        Self {
            est,
            max_age,
            table: [0.0; BATCH],
            top: [0.0; BATCH],
            base: [0.0; BATCH],
            tuning: None,
            fuse: true,
            breakaways: Breakaways::default(),
            start_accel: f32::NAN,
            late_demand: f32::NAN,
            event_step: EventStep::UNKNOWN,
            friction: F::none(),
            base_tuning: B::none(),
        }
    }

    /// The model identifying f and ξ online and adopting them ([`Tuning`]).
    pub fn with_tuning(mut self, tuning: Option<Tuning<B::TopGain>>) -> Self {
        self.tuning = tuning;
        self
    }

    /// The estimator.
    pub fn estimator(&self) -> &StickSlipF32<H> {
        &self.est
    }
}

impl<const H: usize, const EVENTS: bool, F: FrictionSlot, B: BaseSlot> FromPlan
    for StickSlipModel<H, EVENTS, F, B>
{
    /// The estimator restored from the plan's coefficients (computed in f64 and rounded to f32
    /// when the plan was made: the firmware needs no f64 start-up code), with the plan's
    /// settings and history.
    fn from_plan(plan: &Plan) -> Result<Self, PlanError> {
        let want = if EVENTS {
            ModelKind::StickSlip
        } else {
            ModelKind::FixedBase
        };
        if plan.model != want {
            return Err(PlanError::Model);
        }
        // A stick-slip plan with a velocity-dependent law needs the model that follows it.
        let law = !plan
            .specimen
            .friction
            .is_coulomb(plan.specimen.structure.friction_coefficient);
        if EVENTS && law != F::FOLLOWS_LAW {
            return Err(PlanError::Model);
        }
        // A Coulomb predict-mode plan needs the model that tunes from the base accelerometer.
        if EVENTS && !law && plan.mode == Mode::Predict && !B::TUNES {
            return Err(PlanError::Model);
        }
        let c = StickSlipCoefficients::from_bits(&plan.coefficients).ok_or(PlanError::Words)?;
        let est = StickSlipF32::<H>::from_coefficients(c, plan.stick_slip, plan.history)
            .map_err(PlanError::Core)?;
        let tuning = match plan.mode {
            Mode::Fuse => Tuning::new(plan.specimen.structure, plan.specimen.sample_rate_hz)
                .map(|t| t.after_rest(plan.rest_samples)),
            Mode::Predict => None,
        };
        let mut m = Self::new(est, plan.max_age as f32).with_tuning(tuning);
        m.fuse = plan.mode == Mode::Fuse;
        m.friction = F::of_plan(plan);
        m.base_tuning = B::of_plan(plan);
        // (Fuse mode, Coulomb friction, with the base tuning whose runs release it: the wide
        // sliding observer until f and ξ are known.)
        let hold = m.tuning.is_some() && m.base_tuning.get().is_some() && !law;
        m.est.hold_wide(hold);
        Ok(m)
    }
}

impl<const H: usize, const EVENTS: bool, F: FrictionSlot, B: BaseSlot> Model
    for StickSlipModel<H, EVENTS, F, B>
{
    fn kind(&self) -> ModelKind {
        if EVENTS {
            ModelKind::StickSlip
        } else {
            ModelKind::FixedBase
        }
    }

    #[inline]
    fn push(&mut self, e: &Event) -> Result<Pushed, Error> {
        if !EVENTS {
            return Ok(Pushed::No);
        }
        let phase = if e.is_stick() { 0 } else { e.level };
        if let Some(f) = self.friction.get_mut() {
            if e.is_stick() {
                f.stick();
            } else {
                // The late event re-simulates the intervals since it with this coefficient.
                self.est.set_friction(f.since_slip_start());
            }
        }
        if e.kind == EventKind::SlipStart {
            self.late_demand = f32::NAN;
        }
        if e.kind == EventKind::SlipStart && e.age_samples <= self.max_age {
            let at = SlipStart::of(
                &self.est,
                (phase, e.age_samples),
                self.fuse,
                self.start_accel,
                &mut self.breakaways,
            );
            // The first slides' friction from the slip start, before any estimate: the
            // momentum balance on its sliding side (else the breakaway's).
            if let Some(b) = self.base_tuning.get_mut() {
                if let Some(m) = b.slip_start(&at) {
                    self.est.set_friction(m);
                }
            }
            self.late_demand = if self.start_accel.is_nan() {
                self.est
                    .slide_demand(e.age_samples, self.fuse)
                    .unwrap_or(f32::NAN)
            } else {
                f32::NAN
            };
            self.start_accel = f32::NAN;
        }
        // Predict mode without a rest: each direction's friction until both are known.
        if let Some(mu) = self
            .base_tuning
            .get()
            .and_then(|b| b.mu_at_event(phase, e.age_samples))
        {
            self.est.set_friction(mu);
        }
        let pushed = if e.age_samples > self.max_age {
            self.est.push_event(phase, self.max_age)?;
            Pushed::Clamped
        } else {
            self.est.push_event(phase, e.age_samples)?;
            Pushed::Yes
        };
        // Only an event the estimator took (the f64 reference sees the pushed ones only).
        if let Some(b) = self.base_tuning.get_mut() {
            b.event(phase, e.age_samples);
        }
        if let Some(t) = &mut self.tuning {
            t.jump(e.age_samples, self.event_step);
        }
        self.event_step = EventStep::UNKNOWN;
        Ok(pushed)
    }

    fn note_slip_start(&mut self, slip_accel: f32) {
        self.start_accel = slip_accel;
    }

    #[cold]
    fn note_late_slip_start(&mut self, slip_accel: f32) {
        let demand = core::mem::replace(&mut self.late_demand, f32::NAN);
        let (false, Some(b)) = (demand.is_nan(), self.base_tuning.get_mut()) else {
            return;
        };
        // (The identifications' part of a slip start's sliding side, and in predict mode the
        // slide's friction from it: it came from the breakaway until now.)
        let Some(mu_k) = self.est.coefficient_of(demand, slip_accel) else {
            return;
        };
        // (The slide re-run from its start with it, as if it had come with the slip start;
        // the last sample's momentum-balance top, which the next interval reads, moved with
        // it. Not an adoption's shift of the state's top: the state came through the slip
        // start from the stuck phase.)
        let level = self.est.phase().level();
        let before = b.mu_for(level);
        if let Some(mu) = b.late_slide_side(mu_k) {
            self.est
                .set_friction_since_event(mu, b.top_shift(level, before));
        }
    }

    fn note_event_step(&mut self, step: EventStep) {
        self.event_step = step;
    }

    #[cold]
    #[inline(never)]
    fn rescale_units(&mut self, c: f32) {
        self.breakaways.rescale(c);
        let Some(bt) = self.base_tuning.get_mut() else {
            return;
        };
        let level = self.est.phase().level();
        let before = bt.mu_for(level);
        bt.rescale(c);
        let mu = bt.mu_for(level);
        if mu != before {
            // (As an adoption: predict mode's momentum-balance top shifts with μ while sliding.)
            self.friction_adopted(mu, level, before);
        }
    }

    #[inline(always)]
    fn note_inputs(&mut self, i: usize, channels: &[f32; CHANNELS], flags: u8) {
        if let (Some(u), Some(y)) = (self.table.get_mut(i), self.top.get_mut(i)) {
            (*u, *y) = inputs(channels, flags, self.fuse);
            if let Some(b) = self.base.get_mut(i) {
                // (NaN when flagged, for the readers that need it: the base tuning and a
                // friction law leave such a sample out by it. A model without either, the
                // fixed-base one, has the oscillator identification as its only reader, which
                // leaves it out by its NaN top already.)
                *b = if !(B::TUNES || F::FOLLOWS_LAW) || flags & flags::ACCEL_UNUSABLE == 0 {
                    channels[Channel::BaseAccel.index()]
                } else {
                    f32::NAN
                };
            }
        }
    }

    #[inline(always)]
    fn predict_run(&mut self, frames: &mut [Frame], from: usize) {
        let to = from + frames.len();
        if let Some(fr) = self.friction.get_mut() {
            // Sample by sample: the friction coefficient changes with the slip speed.
            let (Some(table), Some(top), Some(base)) = (
                self.table.get(from..to),
                self.top.get(from..to),
                self.base.get(from..to),
            ) else {
                return;
            };
            if self.est.phase() == SlidingPhase::Stuck {
                // A run is in one phase (events start runs): stuck throughout, in blocks.
                // (A flagged sample's base is NaN: `note_inputs`.)
                for (&b, &u) in base.iter().zip(table) {
                    fr.stuck_sample(b, u);
                }
                let mut out = [0.0f32; BATCH];
                if let Some(pred) = out.get_mut(..frames.len()) {
                    if self.est.update_block(table, top, pred).is_ok() {
                        for (f, &p) in frames.iter_mut().zip(pred.iter()) {
                            f.prediction = p;
                        }
                    }
                }
            } else {
                for (((f, &u), &y), &b) in frames.iter_mut().zip(table).zip(top).zip(base) {
                    // A saturated or missing base sample (NaN) holds the slip acceleration.
                    if let Some(mu) = fr.sample(b, u, y, true) {
                        self.est.set_friction(mu);
                    }
                    f.prediction = self.est.update(u, y);
                }
            }
            fr.check(frames.len() as u32);
            if let Some(t) = &mut self.tuning {
                t.push_run(top, base);
                if let Some(c) = t.check(frames.len() as u32) {
                    self.est.retune(c);
                }
            }
            return;
        }
        if self.base_tuning.get().is_some() {
            self.predict_run_base(frames, from);
            return;
        }
        // The run's predictions (on the stack: static RAM is the board's budget).
        let mut out = [0.0f32; BATCH];
        let (Some(table), Some(top), Some(pred)) = (
            self.table.get(from..to),
            self.top.get(from..to),
            out.get_mut(..frames.len()),
        ) else {
            return;
        };
        if self.est.update_block(table, top, pred).is_ok() {
            for (f, &p) in frames.iter_mut().zip(pred.iter()) {
                f.prediction = p;
            }
        } else {
            // (Not reached: the slices are equally long.)
            for ((f, &u), &y) in frames.iter_mut().zip(table).zip(top) {
                f.prediction = self.est.update(u, y);
            }
        }
        if let (Some(t), Some(base)) = (&mut self.tuning, self.base.get(from..to)) {
            t.push_run(top, base);
            if let Some(c) = t.check(frames.len() as u32) {
                self.est.retune(c);
            }
        }
    }

    fn mu_estimate(&self) -> Option<MuEstimate> {
        match self.base_tuning.get() {
            Some(b) if !self.fuse => b.mu_estimate(),
            _ => self.est.mu_estimate(),
        }
    }

    fn revised(&self, sample: u64) -> Option<f32> {
        self.est.prediction_at(sample)
    }

    fn oscillator(&self) -> Option<OscillatorReport> {
        match self.base_tuning.get() {
            Some(b) if !self.fuse => Some(b.report()),
            _ => self.tuning.as_ref().map(Tuning::report),
        }
    }

    fn friction_law(&self) -> Option<FrictionReport> {
        self.friction.get().map(SlipFriction::report)
    }

    fn offsets(&self) -> [f32; 3] {
        // The base channel reads the table's offset too once the detector has removed their
        // difference.
        self.base_tuning
            .get()
            .map_or([0.0; 3], |b| [b.offset(), b.offset(), b.top_offset()])
    }

    fn static_friction(&self) -> Option<StaticFriction> {
        if EVENTS {
            self.breakaways.report()
        } else {
            None
        }
    }
}
