//! "Model only what a scene needs": which estimator model a scene calls for. The models, their
//! settings and the pipeline that drives them are `ssvr_proto`'s (the firmware's own); here
//! [`choose_for`] picks the smallest model that serves the scene from a pre-test simulation of
//! what the controller knows: the prior specimen (`[estimator]`, else `[structure]`) on the
//! planned input, never the specimen's truth ([`choose`]: no slip phase → fixed-base; no stick
//! after the first fifth of the run → rectangular; otherwise stick-slip).

use crate::scene::Scene;
use crate::truth::{simulate, EventKind, Truth, TruthInput};
use anyhow::{anyhow, Result};
use ssvr_core::Structure;

/// An estimator model (`fixed-base`, `rectangular`, `stick-slip`).
pub use ssvr_proto::ModelKind as Model;

/// A mode's name on the command line (`--mode`: `fuse` or `predict`).
pub fn parse_mode(name: &str) -> Result<ssvr_proto::Mode, String> {
    ssvr_proto::Mode::from_name(name)
        .ok_or_else(|| format!("`{name}`: expected one of fuse, predict"))
}

/// A model's name on the command line (`--model`).
pub fn parse(name: &str) -> Result<Model, String> {
    Model::from_name(name)
        .ok_or_else(|| format!("`{name}`: expected one of fixed-base, rectangular, stick-slip"))
}

/// The model a scene calls for, from a simulation of the prior specimen (what the controller is
/// told) on the planned input (without the table's lag), with the reason in words.
pub fn choose_for(scene: &Scene) -> Result<(Model, String)> {
    let prior = crate::pipeline::specimen_of(scene);
    let structure = Structure::new(prior.structure)
        .map_err(|e| anyhow!("the prior specimen is invalid: {e}"))?;
    let table = scene.planned_motion();
    let input = TruthInput::new(&structure, &table, scene.duration_s)
        .with_static_friction(prior.static_friction_coefficient)
        .with_friction(scene.estimator.friction);
    let sim = simulate(&input).map_err(|e| anyhow!("the simulation of the prior failed: {e}"))?;
    let (model, why) = choose(&sim, scene.duration_s);
    // What the friction law adds (the stick-slip model follows a velocity-dependent one).
    let law = match (model, scene.estimator.friction) {
        (Model::StickSlip, ssvr_core::FrictionLaw::VelocityDependent { mu_slow, rate_s_m }) => {
            format!(
                "; velocity-dependent friction (mu {mu_slow} at rest to {} above ~{:.2} m/s): \
                 mu follows the measured slip speed",
                prior.structure.friction_coefficient,
                3.0 / rate_s_m
            )
        }
        _ => String::new(),
    };
    Ok((model, format!("{why} (simulation of the prior){law}")))
}

/// The smallest model that serves the simulated run, with the reason in words.
pub fn choose(truth: &Truth, duration_s: f64) -> (Model, String) {
    let events = truth.events();
    let slips = events
        .iter()
        .filter(|e| matches!(e.kind, EventKind::SlipStart { .. }))
        .count();
    if slips == 0 {
        return (
            Model::FixedBase,
            "the base never slides in the simulated run".into(),
        );
    }
    let settle = 0.2 * duration_s;
    let late_sticks = events
        .iter()
        .filter(|e| e.time_s > settle && matches!(e.kind, EventKind::Stick))
        .count();
    if late_sticks == 0 {
        (
            Model::Rectangular,
            format!("the base slides continuously after t = {settle:.3} s"),
        )
    } else {
        (
            Model::StickSlip,
            format!("the base sticks {late_sticks} time(s) after t = {settle:.3} s"),
        )
    }
}
