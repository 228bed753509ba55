//! The model as the pipeline runs it (`icount model`): the plan's model (`FromPlan`; in fuse
//! mode the stick-slip and fixed-base models identify f and ξ online, `ssvr_proto::Tuning`) on
//! batches of [`BATCH`] samples, `Model::note_inputs` on every sample then `Model::predict_run`
//! on the batch, as `Pipeline::step_batch` does without an event: the estimator's
//! `update_block`, μ identified (stick-slip, sliding), the oscillator identification
//! (`push_run`, a block every ~20 samples) and the adoption check (every
//! [`CHECK_EVERY`] samples), and the bookkeeping between them.
//!
//! The inputs are a steady oscillation of the plan's own top oscillator on its base
//! ([`Oscillation`]): finite, varying, and consistent with the prior's f and ξ, so the
//! identifier converges, its checks find an estimate known well enough and nothing to adopt (the
//! steady state; adoptions in the timed blocks are reported).

use super::Ticks;
use core::hint::black_box;
use ssvr_proto::model::CHECK_EVERY;
use ssvr_proto::{Event, EventKind, Frame, Model, ModelKind, Plan, BATCH, CHANNELS};

/// Batches timed in each state: ten adoption checks exactly ([`CHECK_EVERY`] samples each), so
/// the count does not depend on where the timed block starts among them.
pub const MODEL_BATCHES: u32 = 10 * CHECK_EVERY / BATCH as u32;
const _: () = assert!(CHECK_EVERY.is_multiple_of(BATCH as u32));
/// Longest warm-up (samples) waiting for the identifier's first estimate.
const MAX_WARMUP: u32 = 200_000;

/// The channels of a steady oscillation of the top oscillator on its base at 0.8 times the
/// prior's natural frequency: relative displacement δ = D·sin ωt, top acceleration
/// ü1 = −p²δ − 2ξpδ', base ü2 = ü1 − δ'' (D = 1/p²: ü1 of about 1 m/s²), the table's
/// acceleration that of the base (stuck), displacement 0. The phase advances by a rotation in
/// f32 (a few instructions per sample; the same in the loop timed alone).
#[derive(Clone, Copy)]
struct Oscillation {
    c: f32,
    s: f32,
    rot_c: f32,
    rot_s: f32,
    /// ü1 = top_s·sin + top_c·cos.
    top_s: f32,
    top_c: f32,
    /// δ'' = rel_s·sin.
    rel_s: f32,
}

impl Oscillation {
    fn new(plan: &Plan) -> Self {
        let st = plan.specimen.structure;
        let p = 2.0 * core::f64::consts::PI * st.natural_frequency_hz;
        let w = 0.8 * p;
        let th = w / plan.specimen.sample_rate_hz;
        let d = 1.0 / (p * p);
        Self {
            c: 1.0,
            s: 0.0,
            rot_c: (1.0 - th * th / 2.0) as f32,
            rot_s: (th - th * th * th / 6.0) as f32,
            top_s: (-d * p * p) as f32,
            top_c: (-d * 2.0 * st.damping_ratio * p * w) as f32,
            rel_s: (-d * w * w) as f32,
        }
    }

    /// The next batch of samples' channels (table, base, top, displacement).
    #[inline(always)]
    fn fill(&mut self, ch: &mut [[f32; CHANNELS]; BATCH]) {
        for x in ch.iter_mut() {
            let (c, s) = (
                self.c * self.rot_c - self.s * self.rot_s,
                self.s * self.rot_c + self.c * self.rot_s,
            );
            (self.c, self.s) = (c, s);
            let top = self.top_s * s + self.top_c * c;
            let base = top - self.rel_s * s;
            *x = [base, base, top, 0.0];
        }
    }
}

/// One batch through the model as `Pipeline::step_batch` drives it without an event.
#[inline(always)]
fn batch<M: Model>(
    m: &mut M,
    osc: &mut Oscillation,
    ch: &mut [[f32; CHANNELS]; BATCH],
    frames: &mut [Frame; BATCH],
) {
    osc.fill(ch);
    let m = black_box(m);
    for (i, (c, f)) in black_box(&*ch).iter().zip(frames.iter()).enumerate() {
        m.note_inputs(i, c, f.flags);
    }
    m.predict_run(frames, 0);
    black_box(&mut *frames);
}

/// Adoptions of f and ξ so far (0 without tuning).
fn adoptions<M: Model>(m: &M) -> u32 {
    m.oscillator().map_or(0, |o| o.adoptions)
}

/// Time the plan's model `model` (fresh from the plan) as the pipeline runs it in its steady
/// state, stuck and (stick-slip, rectangular) sliding after one slip start; emit
/// `icount model batch=.. updates=.. loop_ticks=.. stuck_ticks=.. slide_ticks=.. errors=..
/// tuning=.. adoptions=..`.
pub(super) fn model_runs<M: Model + Clone>(t: &mut Ticks, plan: &Plan, model: &M) {
    let blocks = MODEL_BATCHES;
    let mut osc = Oscillation::new(plan);
    let mut ch = [[0.0f32; CHANNELS]; BATCH];
    let mut frames = [Frame::EMPTY; BATCH];
    let loop_ticks = t.time(|| {
        for _ in 0..blocks {
            osc.fill(&mut ch);
            black_box(&mut ch);
            black_box(&mut frames);
        }
    });
    // Warm up: past the estimator's history, until the identifier has an estimate, then two
    // adoption checks with it; then time.
    let per_check = CHECK_EVERY / BATCH as u32;
    let time_blocks = |t: &mut Ticks, m: &mut M| {
        let (mut osc, mut ch, mut frames) = (Oscillation::new(plan), ch, frames);
        let mut warm = 0u32;
        while warm < 1000 + plan.history as u32
            || (m.oscillator().is_some_and(|o| o.estimate.is_none()) && warm < MAX_WARMUP)
        {
            for _ in 0..per_check {
                batch(m, &mut osc, &mut ch, &mut frames);
            }
            warm += CHECK_EVERY;
        }
        for _ in 0..2 * per_check {
            batch(m, &mut osc, &mut ch, &mut frames);
        }
        let before = adoptions(m);
        let ticks = t.time(|| {
            for _ in 0..blocks {
                batch(m, &mut osc, &mut ch, &mut frames);
            }
        });
        (ticks, adoptions(m).wrapping_sub(before))
    };
    let tuning = model.oscillator().is_some();
    let mut stuck = model.clone();
    let (stuck_ticks, mut adopted) = time_blocks(t, &mut stuck);
    let mut errors = 0u32;
    let slide_ticks = if plan.model == ModelKind::FixedBase {
        0
    } else {
        let mut slide = model.clone();
        let start = Event {
            kind: EventKind::SlipStart,
            level: 1,
            age_samples: 0.0,
        };
        errors += u32::from(slide.push(&start).is_err());
        let (ticks, a) = time_blocks(t, &mut slide);
        adopted += a;
        ticks
    };
    defmt::info!(
        "icount model batch={=u32} updates={=u32} loop_ticks={=u32} stuck_ticks={=u32} slide_ticks={=u32} errors={=u32} tuning={=bool} adoptions={=u32}",
        BATCH as u32,
        blocks * BATCH as u32,
        loop_ticks,
        stuck_ticks,
        slide_ticks,
        errors,
        tuning,
        adopted
    );
}
