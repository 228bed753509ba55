//! Where the stick-slip model keeps its [`BaseTuning`] ([`BaseSlot`]).

use super::BaseTuning;
use ssvr_core::oscillator_id::{GainRows, TopGainFit};

/// Where the stick-slip model keeps a [`BaseTuning`]: `Option<BaseTuning>` (the Coulomb
/// stick-slip model, either mode), or `()` (the fixed-base model and the model of a
/// velocity-dependent law: no code, no storage).
pub trait BaseSlot: Clone + core::fmt::Debug {
    /// Whether it can hold a tuning.
    const TUNES: bool;
    /// The fuse mode tuning's fit of the top accelerometer's gain: the tuning corrects the top
    /// by it (`()`: no fit, no storage).
    type TopGain: GainRows<f32>;
    /// No tuning.
    fn none() -> Self;
    /// The slot of a plan.
    fn of_plan(plan: &crate::plan::Plan) -> Self;
    /// The tuning, if any.
    fn get(&self) -> Option<&BaseTuning>;
    /// The tuning, if any.
    fn get_mut(&mut self) -> Option<&mut BaseTuning>;
}

impl BaseSlot for () {
    const TUNES: bool = false;
    type TopGain = ();
    fn none() -> Self {}
    fn of_plan(_: &crate::plan::Plan) -> Self {}
    #[inline(always)]
    fn get(&self) -> Option<&BaseTuning> {
        None
    }
    #[inline(always)]
    fn get_mut(&mut self) -> Option<&mut BaseTuning> {
        None
    }
}

impl BaseSlot for Option<BaseTuning> {
    const TUNES: bool = true;
    type TopGain = TopGainFit<f32>;
    fn none() -> Self {
        None
    }
    fn of_plan(plan: &crate::plan::Plan) -> Self {
        BaseTuning::new(
            plan.specimen.structure,
            plan.specimen.sample_rate_hz,
            plan.rest_samples > 0,
            plan.mode == crate::model::Mode::Fuse,
            plan.max_age,
        )
        .map(|b| {
            b.with_static_friction(plan.specimen.static_friction_coefficient)
                .with_planned_start(plan.planned_start)
        })
    }
    #[inline(always)]
    fn get(&self) -> Option<&BaseTuning> {
        self.as_ref()
    }
    #[inline(always)]
    fn get_mut(&mut self) -> Option<&mut BaseTuning> {
        self.as_mut()
    }
}
