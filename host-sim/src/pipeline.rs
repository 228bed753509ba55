//! The host's side of the one pipeline (`ssvr_proto::Pipeline`): the plan of a scene and a model
//! ([`plan_for`]: the same `Plan::new` the firmware's build runs), the pipeline built from it
//! whatever its model and ring ([`build`]: the firmware's model and detector types, picked at
//! run time), and a measured sensor frame as the pipeline's sample ([`sample_of`]).
//! `host-sim run` predicts with it, and `host-sim qemu` checks the firmware's frames against it.

use crate::scene::Scene;
use crate::sensors::{SensorFrame, FLAG_ACCEL_SATURATED, FLAG_DISP_SATURATED, FLAG_MISSING};
use anyhow::{anyhow, bail, Result};
use ssvr_core::detect::displacement::SlipEvent;
use ssvr_proto::pipeline::{model_inputs, slip_start_input};
use ssvr_proto::plan::MAX_HISTORY;
use ssvr_proto::{
    flags, AccelerationDetector, DetectorPlan, DisplacementDetector, EventDetector, EventSource,
    FixedBaseModel, FromPlan, Mode, ModelKind, Pipeline, Plan, RectangularModel, Sample, Specimen,
    Step, StickSlipLawModel, StickSlipModel,
};

/// What the controller is told of a scene's specimen and sensors (`ssvr_scene::Specimen::prior`,
/// the same as the firmware's build script reads).
pub fn specimen_of(scene: &Scene) -> Specimen {
    crate::scene::Specimen::from(scene).prior()
}

/// The plan of a scene and a model in the fuse mode (what the firmware built for them runs).
pub fn plan_for(scene: &Scene, model: ModelKind) -> Result<Plan> {
    plan_for_mode(scene, model, Mode::Fuse)
}

/// The plan of a scene, a model and a mode (with the scene's rest before the input, whose
/// accelerometer readings the pipeline zeroes, and, without a rest, its planned input's
/// start).
pub fn plan_for_mode(scene: &Scene, model: ModelKind, mode: Mode) -> Result<Plan> {
    let input = scene.input_motion();
    Ok(
        plan_for_specimen(&crate::scene::Specimen::from(scene), model, mode)?
            .with_planned_input(|t| input.accel(t)),
    )
}

/// The plan of a specimen (its prior, rate and rest before the input), a model and a mode:
/// [`plan_for_mode`] of a scene, and `host-sim replay`'s plan of a recording's specimen.
pub fn plan_for_specimen(
    specimen: &crate::scene::Specimen,
    model: ModelKind,
    mode: Mode,
) -> Result<Plan> {
    Ok(Plan::new(specimen.prior(), model)
        .map_err(|e| anyhow!("no {} pipeline for the scene: {e}", model.name()))?
        .with_mode(mode)
        .with_rest(specimen.start_s))
}

/// Options of a host pipeline beyond the plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Options {
    /// Where the events come from.
    pub source: EventSource,
    /// The rectangular model pushes level 0 at a stick instead of keeping its level.
    pub zero_at_stick: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            source: EventSource::Detector,
            zero_at_stick: false,
        }
    }
}

/// The pipeline of `plan`'s model (a [`model`]) and detector `D`.
fn with_model<D: EventDetector + 'static>(plan: &Plan, opts: Options) -> Result<Box<dyn Step>> {
    let m = model(plan, opts)?;
    let d = D::from_plan(plan).map_err(|e| anyhow!("detector: {e}"))?;
    let p: Pipeline<_, _> = Pipeline::new(m, d, opts.source, plan.disp_range_m())
        .with_rest(plan.rest_samples)
        .with_table_gain(plan);
    Ok(Box::new(p))
}

/// The pipeline of a plan at sample 0: the firmware's model and detector types (the stick-slip
/// estimator with the host's storage of [`MAX_HISTORY`] samples and the plan's history: the
/// same results as the firmware's storage), the ring picked from the plan.
pub fn build(plan: &Plan, opts: Options) -> Result<Box<dyn Step>> {
    macro_rules! rings {
        ($det:ident, $($n:literal)*) => {
            match plan.ring {
                $($n => with_model::<$det<$n>>(plan, opts),)*
                n => bail!("no host detector with a ring of {n} samples"),
            }
        };
    }
    match plan.detector {
        DetectorPlan::Displacement(_) => rings!(DisplacementDetector, 8 16 32 64 128 256 512 1024),
        DetectorPlan::SlipAcceleration(_) => {
            rings!(AccelerationDetector, 8 16 32 64 128 256 512 1024)
        }
    }
}

/// A measured frame as the pipeline's sample: a saturated accelerometer is `SATURATED`, a
/// saturated displacement `SATURATED | DISP_INVALID` (as the sensor log records them), a dropped
/// frame `MISSING`.
pub fn sample_of(f: &SensorFrame) -> Sample {
    let mut fl = 0;
    if f.flags & FLAG_ACCEL_SATURATED != 0 {
        fl |= flags::SATURATED;
    }
    if f.flags & FLAG_DISP_SATURATED != 0 {
        fl |= flags::SATURATED | flags::DISP_INVALID;
    }
    if f.flags & FLAG_MISSING != 0 {
        fl |= flags::MISSING;
    }
    Sample {
        channels: [
            f.table_accel_m_s2,
            f.base_accel_m_s2,
            f.top_accel_m_s2,
            f.disp_m,
        ],
        flags: fl,
        reversal: None,
    }
}

/// The model of a plan, at rest: the firmware's model type (the stick-slip estimator with the
/// host's storage of [`MAX_HISTORY`] samples). The pipeline drives it, and alone it takes other
/// events than the detector's (the truth's own in `host-sim run`'s "ideal" estimator).
pub fn model(plan: &Plan, opts: Options) -> Result<Box<dyn ssvr_proto::Model>> {
    Ok(match plan.model {
        ModelKind::Rectangular => Box::new(
            RectangularModel::from_plan(plan)
                .map_err(|e| anyhow!("estimator: {e}"))?
                .with_zero_at_stick(opts.zero_at_stick),
        ),
        // A velocity-dependent law: the model that follows it (as the firmware's build picks).
        ModelKind::StickSlip if plan.follows_law() => Box::new(
            StickSlipLawModel::<MAX_HISTORY>::from_plan(plan)
                .map_err(|e| anyhow!("estimator: {e}"))?,
        ),
        ModelKind::StickSlip => Box::new(
            StickSlipModel::<MAX_HISTORY>::from_plan(plan)
                .map_err(|e| anyhow!("estimator: {e}"))?,
        ),
        ModelKind::FixedBase => Box::new(
            FixedBaseModel::<MAX_HISTORY>::from_plan(plan)
                .map_err(|e| anyhow!("estimator: {e}"))?,
        ),
    })
}

/// Drive a model alone one sample at a time: push `event` (if any), then predict the sample
/// `s`, less the accelerometers' `offsets` (table, base, top: the pipeline's, so that the model
/// sees what the pipeline's model sees; the pipeline's steps 3–4 without a detector). Returns
/// the prediction and whether the model used the event.
pub fn model_step(
    model: &mut dyn ssvr_proto::Model,
    event: Option<&ssvr_proto::Event>,
    s: &Sample,
    offsets: [f32; 3],
) -> Result<(f32, bool), ssvr_core::Error> {
    let mut frame = ssvr_proto::Frame {
        channels: s.channels,
        flags: s.flags,
        ..ssvr_proto::Frame::EMPTY
    };
    let used = match event {
        Some(e) => model.push(e)? != ssvr_proto::Pushed::No,
        None => false,
    };
    let mut channels = s.channels;
    for (c, o) in channels.iter_mut().zip(offsets) {
        *c -= o;
    }
    model.note_inputs(0, &channels, s.flags);
    model.predict_run(core::slice::from_mut(&mut frame), 0);
    Ok((frame.prediction, used))
}

/// The pipeline's preparation of a sample's zeroed channels for its model, run apart from the
/// pipeline: the plan's detector (the same code and ring) fed each sample's channels and flags,
/// the base read in the table's units and the accelerometers divided by the table's gain
/// identified against the displacement ([`ssvr_proto::pipeline::model_inputs`]). The f64
/// reference of `host-sim qemu` reads its inputs through it.
pub type InputTracker = Box<dyn FnMut(&mut [f32; ssvr_proto::CHANNELS], u8) -> Tracked>;

/// What [`InputTracker`] found at a sample besides the model's inputs: its detector's event's
/// base step ([`EventDetector::event_step`]; NaN without an event) and a slip start's sliding
/// side at its start (the pipeline notes both for the model).
#[derive(Debug, Clone, Copy)]
pub struct Tracked {
    /// A slip start's sliding side at its start, in the model's units.
    pub start_accel: Option<f32>,
    /// The base accelerometer's step and kink at the sample's event (m/s², in the model's
    /// units; unknown without an event).
    pub event_step: ssvr_core::detect::EventStep,
    /// The sliding side of the slip start of the sample before, confirmed at its second sample
    /// ([`EventDetector::late_slip_start_accel`]; NaN at any other sample), in the model's
    /// units.
    pub late_start_accel: f32,
    /// The factor the accelerometers' units changed by at this sample (the table's gain
    /// adopted: `Model::rescale_units`), else 1.
    pub units: f32,
}

/// [`InputTracker`] of a plan.
pub fn input_tracker(plan: &Plan) -> Result<InputTracker> {
    fn make<D: EventDetector + 'static>(plan: &Plan) -> Result<InputTracker> {
        let mut d = D::from_plan(plan).map_err(|e| anyhow!("detector: {e}"))?;
        let mut gain = ssvr_proto::table_gain::TableGain::of_plan(plan, d.max_age_samples());
        let mut index = 0u32;
        Ok(Box::new(move |ch, f| {
            let table = ch[ssvr_proto::Channel::TableAccel.index()];
            let event = d.process_with_reference(D::INPUT.of(ch, f), table);
            let tracked = (d.base_offset(), d.gain_mismatch());
            model_inputs(ch, f, tracked, gain.as_mut(), index, event.as_ref());
            index = index.wrapping_add(1);
            // (The table's gain adopted at this sample: its units' factor.)
            let units = gain
                .as_mut()
                .and_then(ssvr_proto::table_gain::TableGain::take_change)
                .map_or(1.0, |(_, c)| c);
            // A slip start's sliding side at its start (the pipeline notes it for the model).
            let inverse = gain
                .as_ref()
                .map_or(1.0, ssvr_proto::table_gain::TableGain::inverse);
            Tracked {
                start_accel: matches!(event, Some(SlipEvent::SlipStart { .. }))
                    .then(|| slip_start_input(d.slip_start_accel(), tracked.1, inverse)),
                event_step: event
                    .as_ref()
                    .map_or(ssvr_core::detect::EventStep::UNKNOWN, |e| {
                        let e = ssvr_proto::Event::from_detector(e);
                        let stick = e.kind == ssvr_proto::EventKind::Stick;
                        d.event_step(e.age_samples, stick)
                            .scaled(slip_start_input(1.0, tracked.1, inverse))
                    }),
                late_start_accel: slip_start_input(d.late_slip_start_accel(), tracked.1, inverse),
                units,
            }
        }))
    }
    macro_rules! rings {
        ($det:ident, $($n:literal)*) => {
            match plan.ring {
                $($n => make::<$det<$n>>(plan),)*
                n => bail!("no host detector with a ring of {n} samples"),
            }
        };
    }
    match plan.detector {
        DetectorPlan::Displacement(_) => rings!(DisplacementDetector, 8 16 32 64 128 256 512 1024),
        DetectorPlan::SlipAcceleration(_) => {
            rings!(AccelerationDetector, 8 16 32 64 128 256 512 1024)
        }
    }
}
