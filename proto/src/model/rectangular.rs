//! The rectangular model: the paper's rectangular friction (eq 36) as the O(1) Duhamel
//! recursion. Slip starts and reversals are pushed as `push_reversal(level, age)`; a stick is
//! not pushed (the model knows only the two sliding levels ±F0 and keeps its level), unless
//! `zero_at_stick` (then level 0).

use super::{FromPlan, Model, ModelKind, Pushed};
use crate::channel::CHANNELS;
use crate::event::Event;
use crate::frame::Frame;
use crate::plan::{Plan, PlanError};
use ssvr_core::recursion::Estimator32;
use ssvr_core::stick_slip::MuEstimate;
use ssvr_core::{Error, Structure};

/// The rectangular model.
#[derive(Debug, Clone)]
pub struct RectangularModel {
    est: Estimator32,
    zero_at_stick: bool,
}

impl RectangularModel {
    /// The model on an estimator; sticks keep the level.
    pub fn new(est: Estimator32) -> Self {
        Self {
            est,
            zero_at_stick: false,
        }
    }

    /// Push level 0 at a stick (the generalised eq 36 with a zero level while stuck) instead of
    /// keeping the level.
    pub fn with_zero_at_stick(mut self, zero: bool) -> Self {
        self.zero_at_stick = zero;
        self
    }

    /// The recursion.
    pub fn estimator(&self) -> &Estimator32 {
        &self.est
    }
}

impl FromPlan for RectangularModel {
    fn from_plan(plan: &Plan) -> Result<Self, PlanError> {
        if plan.model != ModelKind::Rectangular {
            return Err(PlanError::Model);
        }
        let structure = Structure::new(plan.specimen.structure).map_err(PlanError::Core)?;
        Estimator32::new(&structure, plan.specimen.sample_rate_hz)
            .map(Self::new)
            .map_err(PlanError::Core)
    }
}

impl Model for RectangularModel {
    fn kind(&self) -> ModelKind {
        ModelKind::Rectangular
    }

    #[inline]
    fn push(&mut self, e: &Event) -> Result<Pushed, Error> {
        if e.is_stick() {
            if !self.zero_at_stick {
                return Ok(Pushed::No);
            }
            self.est.push_reversal(0.0, e.age_samples)?;
        } else {
            self.est.push_reversal(f32::from(e.level), e.age_samples)?;
        }
        Ok(Pushed::Yes)
    }

    #[inline(always)]
    fn note_inputs(&mut self, _i: usize, _channels: &[f32; CHANNELS], _flags: u8) {}

    #[inline(always)]
    fn predict_run(&mut self, frames: &mut [Frame], _from: usize) {
        for f in frames.iter_mut() {
            f.prediction = self.est.update();
        }
    }

    fn mu_estimate(&self) -> Option<MuEstimate> {
        None
    }

    fn revised(&self, _sample: u64) -> Option<f32> {
        None
    }
}
