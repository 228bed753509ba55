//! The model's estimator timed alone: steady-state samples, samples with an event (age 0.5 and,
//! for the stick-slip model, the largest age), stuck samples, the prediction without the
//! identification, and the estimator's blocks as the pipeline runs them. What is measured
//! depends on the model's type ([`BenchModel`]).

use super::{Ticks, LONG_EVENTS, REVERSALS, UPDATES};
use core::hint::black_box;
use ssvr_core::recursion::Estimator32;
use ssvr_core::stick_slip::{StickSlipCoefficients, StickSlipConfig};
use ssvr_proto::model::StickSlipF32 as StickSlipEstimator;
use ssvr_proto::{Plan, RectangularModel, StickSlipModel, BATCH};

/// What the benchmark measures of a model's estimator: (steady-state update ticks, events
/// pushed, the ticks of their samples, rejected events), emitting the model's own messages.
pub trait BenchModel: Clone {
    /// Time the model's estimator.
    fn estimator_blocks(&self, t: &mut Ticks, plan: &Plan) -> (u32, u32, u32, u32);
}

impl BenchModel for RectangularModel {
    /// Steady sliding updates and samples with a reversal (±1 alternating, age 0.5).
    fn estimator_blocks(&self, t: &mut Ticks, _plan: &Plan) -> (u32, u32, u32, u32) {
        rectangular_blocks(t, self.estimator().clone())
    }
}

impl<
        const H: usize,
        const EVENTS: bool,
        F: ssvr_proto::model::FrictionSlot,
        B: ssvr_proto::model::BaseSlot,
    > BenchModel for StickSlipModel<H, EVENTS, F, B>
{
    /// The stick-slip model (events on) or the fixed-base model (events off).
    fn estimator_blocks(&self, t: &mut Ticks, plan: &Plan) -> (u32, u32, u32, u32) {
        let est = self.estimator().clone();
        if plan.model == ssvr_proto::ModelKind::StickSlip {
            stick_slip_blocks(t, plan, est)
        } else {
            fixed_base_blocks(t, plan, est)
        }
    }
}

/// The rectangular model: (steady-state update ticks, reversals, their ticks, rejected).
fn rectangular_blocks(t: &mut Ticks, mut est: Estimator32) -> (u32, u32, u32, u32) {
    // Enter the sliding state and let the response settle into its steady recursion.
    let mut errors: u32 = 0;
    if est.push_reversal(1.0, 0.0).is_err() {
        errors += 1;
    }
    for _ in 0..1000 {
        black_box(est.update());
    }
    let update_ticks = t.time(|| {
        for _ in 0..UPDATES {
            black_box(black_box(&mut est).update());
        }
    });
    let mut level = -1.0f32;
    let reversal_ticks = t.time(|| {
        for _ in 0..REVERSALS {
            let e = black_box(&mut est);
            if e.push_reversal(level, 0.5).is_err() {
                errors += 1;
            }
            black_box(e.update());
            level = -level;
        }
    });
    (update_ticks, REVERSALS, reversal_ticks, errors)
}

/// Inputs of the stick-slip benchmark: a table and a top acceleration (m/s²).
fn inputs() -> (f32, f32) {
    (black_box(0.75), black_box(-1.25))
}

/// Steady-state stuck updates of a fresh stick-slip estimator: its ticks (`icount stick_slip`).
fn stuck_block<const H: usize>(t: &mut Ticks, plan: &Plan, est: &StickSlipEstimator<H>) -> u32 {
    let mut e = est.clone();
    let (u, y) = inputs();
    for _ in 0..1000 + plan.history {
        black_box(e.update(u, y));
    }
    t.time(|| {
        for _ in 0..UPDATES {
            black_box(black_box(&mut e).update(u, y));
        }
    })
}

/// Steady-state samples of the estimator in blocks of [`BATCH`] (`update_block`, as the
/// pipeline runs it): stuck, and sliding with μ identified (stick-slip model; fixed-base: 0).
/// Emits `icount block batch=.. updates=.. loop_ticks=.. stuck_ticks=.. slide_ticks=..`.
fn block_runs<const H: usize>(t: &mut Ticks, plan: &Plan, est: &StickSlipEstimator<H>) {
    let blocks = UPDATES / BATCH as u32;
    let (u, y) = inputs();
    let (table, top) = ([u; BATCH], [y; BATCH]);
    let mut out = [0.0f32; BATCH];
    let loop_ticks = t.time(|| {
        for i in 0..blocks {
            black_box(i);
            black_box(&mut out);
        }
    });
    // Warm up (past the history and the first identification blocks), then time.
    let warmup = (1000 + plan.history) / BATCH + 1;
    let time_blocks = |t: &mut Ticks, e: &mut StickSlipEstimator<H>, out: &mut [f32; BATCH]| {
        let mut errors = 0u32;
        for _ in 0..warmup {
            errors += u32::from(e.update_block(&table, &top, out).is_err());
        }
        let ticks = t.time(|| {
            for _ in 0..blocks {
                let e = black_box(&mut *e);
                errors += u32::from(
                    e.update_block(black_box(&table), black_box(&top), out)
                        .is_err(),
                );
                black_box(&mut *out);
            }
        });
        (ticks, errors)
    };
    let mut stuck = est.clone();
    let (stuck_ticks, mut errors) = time_blocks(t, &mut stuck, &mut out);
    let slide_ticks = if plan.model == ssvr_proto::ModelKind::StickSlip {
        let mut slide = est.clone();
        errors += u32::from(slide.push_event(1, 0.0).is_err());
        let (ticks, e) = time_blocks(t, &mut slide, &mut out);
        errors += e;
        ticks
    } else {
        0
    };
    defmt::info!(
        "icount block batch={=u32} updates={=u32} loop_ticks={=u32} stuck_ticks={=u32} slide_ticks={=u32} errors={=u32}",
        BATCH as u32,
        blocks * BATCH as u32,
        loop_ticks,
        stuck_ticks,
        slide_ticks,
        errors
    );
}

/// The stick-slip model: steady sliding samples (μ identified on every block: the history is full
/// and the delayed samples slide), events at age 0.5, events at the largest age; and the stuck
/// samples (`icount stick_slip`).
fn stick_slip_blocks<const H: usize>(
    t: &mut Ticks,
    plan: &Plan,
    est: StickSlipEstimator<H>,
) -> (u32, u32, u32, u32) {
    let max_age = plan.max_age as f32;
    block_runs(t, plan, &est);
    let stuck_ticks = stuck_block(t, plan, &est);
    let mut est = est;
    let (u, y) = inputs();
    let mut errors: u32 = 0;
    if est.push_event(1, 0.0).is_err() {
        errors += 1;
    }
    for _ in 0..1000 + plan.history {
        black_box(est.update(u, y));
    }
    let update_ticks = t.time(|| {
        for _ in 0..UPDATES {
            black_box(black_box(&mut est).update(u, y));
        }
    });
    let mut level: i8 = -1;
    let reversal_ticks = t.time(|| {
        for _ in 0..REVERSALS {
            let e = black_box(&mut est);
            if e.push_event(level, 0.5).is_err() {
                errors += 1;
            }
            black_box(e.update(u, y));
            level = -level;
        }
    });
    // The prediction alone: the same estimator without the identification.
    let bare_config = StickSlipConfig {
        identify_mu: false,
        ..plan.stick_slip
    };
    let mut bare = StickSlipCoefficients::from_bits(&plan.coefficients)
        .and_then(|c| StickSlipEstimator::<H>::from_coefficients(c, bare_config, plan.history).ok())
        .unwrap_or_else(|| est.clone());
    if bare.push_event(1, 0.0).is_err() {
        errors += 1;
    }
    for _ in 0..1000 + plan.history {
        black_box(bare.update(u, y));
    }
    let predict_ticks = t.time(|| {
        for _ in 0..UPDATES {
            black_box(black_box(&mut bare).update(u, y));
        }
    });
    let age = black_box(max_age);
    let long_event_ticks = t.time(|| {
        for _ in 0..LONG_EVENTS {
            let e = black_box(&mut est);
            if e.push_event(level, age).is_err() {
                errors += 1;
            }
            black_box(e.update(u, y));
            level = -level;
        }
    });
    defmt::info!(
        "icount stick_slip stuck_updates={=u32} stuck_ticks={=u32} long_events={=u32} long_event_ticks={=u32} max_age={=f32} predict_updates={=u32} predict_ticks={=u32}",
        UPDATES,
        stuck_ticks,
        LONG_EVENTS,
        long_event_ticks,
        max_age,
        UPDATES,
        predict_ticks
    );
    (update_ticks, REVERSALS, reversal_ticks, errors)
}

/// The fixed-base model: steady stuck samples (no event is ever pushed).
fn fixed_base_blocks<const H: usize>(
    t: &mut Ticks,
    plan: &Plan,
    est: StickSlipEstimator<H>,
) -> (u32, u32, u32, u32) {
    block_runs(t, plan, &est);
    let stuck_ticks = stuck_block(t, plan, &est);
    defmt::info!(
        "icount stick_slip stuck_updates={=u32} stuck_ticks={=u32} long_events={=u32} long_event_ticks={=u32} max_age={=f32} predict_updates={=u32} predict_ticks={=u32}",
        UPDATES,
        stuck_ticks,
        0u32,
        0u32,
        0.0f32,
        0u32,
        0u32
    );
    (stuck_ticks, 0, 0, 0)
}
