//! The estimator model compiled in: `SSVR_MODEL` at build time (build.rs sets the cfg
//! `ssvr_model`; default `rectangular`). Only that model's code is in the image.
//!
//! * **rectangular**: the paper's rectangular friction, `Estimator32` (the O(1) Duhamel
//!   recursion); slip starts and reversals are pushed as `push_reversal(level, age)`, sticks are
//!   reported, not pushed (the model keeps its level);
//! * **stick-slip**: `StickSlipEstimator<f32, F32Poly, HISTORY>`, driven by the measured table
//!   acceleration (and the measured top acceleration for the friction identification): slip
//!   starts and reversals are pushed as `push_event(level, age)`, sticks as `push_event(0, age)`;
//!   an age beyond the history (`MAX_EVENT_AGE_SAMPLES`, the detector's usual longest
//!   back-dating) is clamped to it;
//! * **fixed-base**: the same estimator, no event pushed (the base never slides).
//!
//! host-sim's `qemu_cmd::HostPipeline` mirrors these functions line by line.

#[cfg(not(ssvr_model = "rectangular"))]
use super::pipeline::{flags, BATCH};
use super::pipeline::{Event, EventKind, FrameOut};
use super::scene;
use ssvr_core::Error;

/// The model's name (`fixed-base`, `rectangular`, `stick-slip`).
pub const NAME: &str = scene::MODEL;

/// The estimator of the model.
#[cfg(ssvr_model = "rectangular")]
pub type Estimator = ssvr_core::recursion::Estimator32;
/// The estimator of the model: a history of `scene::HISTORY` samples in the storage that makes
/// its steady state cheapest (`storage_for`: a multiple of the identification block plus one).
#[cfg(not(ssvr_model = "rectangular"))]
pub type Estimator = ssvr_core::stick_slip::StickSlipEstimator<
    f32,
    ssvr_core::math::F32Poly,
    { ssvr_core::stick_slip::storage_for(scene::HISTORY, scene::STICK_SLIP.identify_every) },
>;

/// The largest event age pushed (samples); older events are clamped to it.
#[cfg(ssvr_model = "stick_slip")]
pub const MAX_AGE: f32 = scene::MAX_EVENT_AGE_SAMPLES as f32;

/// Index of the table acceleration channel.
#[cfg(not(ssvr_model = "rectangular"))]
const TABLE: usize = 0;
/// Index of the top acceleration channel.
#[cfg(not(ssvr_model = "rectangular"))]
const TOP: usize = 2;

/// The estimator for the compiled-in scene, at rest. The rectangular model computes its tables
/// from the structure (f64, at start-up); the stick-slip estimator restores its coefficients,
/// computed by build.rs (`scene::STICK_SLIP_COEFFICIENTS`).
pub fn new() -> Result<Estimator, Error> {
    #[cfg(ssvr_model = "rectangular")]
    {
        let structure = ssvr_core::Structure::new(scene::STRUCTURE)?;
        Estimator::new(&structure, scene::SAMPLE_RATE_HZ)
    }
    #[cfg(not(ssvr_model = "rectangular"))]
    {
        with_config(scene::STICK_SLIP)
    }
}

/// The stick-slip estimator of the compiled-in scene with other settings (the benchmark's
/// prediction-only run).
#[cfg(not(ssvr_model = "rectangular"))]
pub fn with_config(cfg: ssvr_core::stick_slip::StickSlipConfig) -> Result<Estimator, Error> {
    let c =
        ssvr_core::stick_slip::StickSlipCoefficients::from_bits(&scene::STICK_SLIP_COEFFICIENTS)
            .ok_or(Error::NotFinite(ssvr_core::Param::SampleRate))?;
    Estimator::from_coefficients(c, cfg, scene::HISTORY)
}

/// What [`push`] did with an event (each model uses some of these).
#[allow(dead_code)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pushed {
    /// The model does not use this event (a stick for the rectangular model, every event for
    /// the fixed-base model).
    No,
    /// Pushed.
    Yes,
    /// Pushed with its age clamped to [`MAX_AGE`] (stick-slip model).
    Clamped,
}

/// Give a friction event to the estimator (before the sample's [`update`]).
#[cfg(ssvr_model = "rectangular")]
pub fn push(est: &mut Estimator, e: &Event) -> Result<Pushed, Error> {
    if e.kind == EventKind::Stick {
        return Ok(Pushed::No);
    }
    est.push_reversal(f32::from(e.level), e.age_samples)?;
    Ok(Pushed::Yes)
}

/// Give a friction event to the estimator (before the sample's [`update`]).
#[cfg(ssvr_model = "stick_slip")]
pub fn push(est: &mut Estimator, e: &Event) -> Result<Pushed, Error> {
    let phase = if e.kind == EventKind::Stick {
        0
    } else {
        e.level
    };
    if e.age_samples > MAX_AGE {
        est.push_event(phase, MAX_AGE)?;
        Ok(Pushed::Clamped)
    } else {
        est.push_event(phase, e.age_samples)?;
        Ok(Pushed::Yes)
    }
}

/// Give a friction event to the estimator: the fixed-base model ignores every event.
#[cfg(ssvr_model = "fixed_base")]
pub fn push(_est: &mut Estimator, _e: &Event) -> Result<Pushed, Error> {
    let _ = EventKind::Stick;
    Ok(Pushed::No)
}

/// The estimator's inputs of a sample: the table acceleration and the top acceleration (NaN,
/// i.e. not used, when the sample is saturated or missing; a non-finite value is skipped
/// anyway). `channels`: table accel, base accel, top accel, displacement.
#[cfg(not(ssvr_model = "rectangular"))]
#[inline(always)]
fn inputs(channels: &[f32; 4], f: u8) -> (f32, f32) {
    let top = if f & (flags::SATURATED | flags::MISSING) == 0 {
        channels[TOP]
    } else {
        f32::NAN
    };
    (channels[TABLE], top)
}

/// Room for a run's estimator inputs and outputs (the stick-slip estimator's `update_block`;
/// nothing for the rectangular model).
#[derive(Debug, Clone)]
pub struct RunBuffers {
    #[cfg(not(ssvr_model = "rectangular"))]
    table: [f32; BATCH],
    #[cfg(not(ssvr_model = "rectangular"))]
    top: [f32; BATCH],
    #[cfg(not(ssvr_model = "rectangular"))]
    pred: [f32; BATCH],
}

impl RunBuffers {
    /// Zeroed.
    pub const fn new() -> Self {
        Self {
            #[cfg(not(ssvr_model = "rectangular"))]
            table: [0.0; BATCH],
            #[cfg(not(ssvr_model = "rectangular"))]
            top: [0.0; BATCH],
            #[cfg(not(ssvr_model = "rectangular"))]
            pred: [0.0; BATCH],
        }
    }
}

/// Keep the estimator's inputs of sample `i` of a batch (its `frame`: channels and flags) for
/// [`predict_run`] (the stick-slip estimator; the rectangular model needs none).
#[inline(always)]
pub fn note_inputs(buf: &mut RunBuffers, i: usize, frame: &FrameOut) {
    #[cfg(ssvr_model = "rectangular")]
    let _ = (buf, i, frame);
    #[cfg(not(ssvr_model = "rectangular"))]
    if let (Some(u), Some(y)) = (buf.table.get_mut(i), buf.top.get_mut(i)) {
        (*u, *y) = inputs(&frame.channels, frame.flags);
    }
}

/// The predictions of `frames`, samples `from ..` of the batch, a run without events after its
/// first sample: the rectangular `update()` per frame, or the stick-slip estimator's
/// `update_block` on the inputs kept by [`note_inputs`] (bit for bit its `update(table, top)`
/// per sample).
#[inline(always)]
pub fn predict_run(
    est: &mut Estimator,
    frames: &mut [FrameOut],
    buf: &mut RunBuffers,
    from: usize,
) {
    #[cfg(ssvr_model = "rectangular")]
    {
        let _ = (buf, from);
        for f in frames.iter_mut() {
            f.prediction = est.update();
        }
    }
    #[cfg(not(ssvr_model = "rectangular"))]
    {
        let to = from + frames.len();
        let (Some(table), Some(top), Some(pred)) = (
            buf.table.get(from..to),
            buf.top.get(from..to),
            buf.pred.get_mut(from..to),
        ) else {
            return;
        };
        if est.update_block(table, top, pred).is_ok() {
            for (f, &p) in frames.iter_mut().zip(pred.iter()) {
                f.prediction = p;
            }
        } else {
            // (Not reached: the slices are equally long.)
            for f in frames.iter_mut() {
                let (u, y) = inputs(&f.channels, f.flags);
                f.prediction = est.update(u, y);
            }
        }
    }
}

/// The identified friction coefficient: (μ̂, std, samples used); `None` for the rectangular
/// model or before any sliding sample was used.
pub fn mu_estimate(est: &Estimator) -> Option<(f64, f64, u32)> {
    #[cfg(ssvr_model = "rectangular")]
    {
        let _ = est;
        None
    }
    #[cfg(not(ssvr_model = "rectangular"))]
    {
        est.mu_estimate().map(|m| (m.mu, m.std, m.blocks))
    }
}

/// Report the model (`model name=.. history=.. max_age=.. config=..`; the history and the
/// settings are those of the stick-slip estimator, also reported for the rectangular model).
#[cfg_attr(not(feature = "qemu"), allow(dead_code))]
pub fn emit() {
    defmt::info!(
        "model name={=str} history={=u32} max_age={=u32} config={=str}",
        NAME,
        scene::HISTORY as u32,
        scene::MAX_EVENT_AGE_SAMPLES as u32,
        scene::STICK_SLIP_DEBUG
    );
}

/// Report the identified friction coefficient `mu` ([`mu_estimate`]): `mu estimate=.. std=..
/// samples=..`, or `mu none` when there is none yet; nothing for the rectangular model.
pub fn emit_mu(mu: Option<(f64, f64, u32)>) {
    if cfg!(ssvr_model = "rectangular") {
        return;
    }
    match mu {
        Some((mu, std, n)) => {
            defmt::info!("mu estimate={=f64} std={=f64} samples={=u32}", mu, std, n)
        }
        None => defmt::info!("mu none"),
    }
}
