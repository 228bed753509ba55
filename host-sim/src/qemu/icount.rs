//! The instruction counts the QEMU image measures after the replay (SysTick under
//! `-icount shift=0`, `firmware/src/bench/`), from its `icount` messages' typed fields.

use super::decode::Message;

/// Instruction counts the QEMU image measures after the replay (see `firmware/README.md`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InstructionCounts {
    /// Instructions of the calibration loop.
    pub calibration_instructions: u32,
    /// SysTick ticks they took.
    pub calibration_ticks: u32,
    /// Executed instructions per SysTick tick (40 on mps2-an386 with `-icount shift=0`).
    pub instructions_per_tick: f64,
    /// Instructions of one steady-state update of the model's estimator, loop overhead removed
    /// (rectangular: `update()` while sliding; stick-slip: `update(table, top)` while sliding, μ
    /// identified; fixed-base: `update(table, top)` stuck).
    pub instructions_per_sample: f64,
    /// Extra instructions of a sample with a reversal (`push_reversal(±1, 0.5)` or
    /// `push_event(±1, 0.5)` + its effect on the update), over a steady-state sample; `None`
    /// for the fixed-base model (it pushes no event).
    pub instructions_per_reversal: Option<f64>,
    /// Stick-slip and fixed-base models: instructions of a steady-state stuck update.
    pub instructions_per_sample_stuck: Option<f64>,
    /// Stick-slip model: extra instructions of a sample with an event [`Self::max_event_age`]
    /// samples old (the whole history re-simulated), over a steady-state sample.
    pub instructions_per_event_max_age: Option<f64>,
    /// The age of those events (samples).
    pub max_event_age: Option<f64>,
    /// Stick-slip model: instructions of a steady-state sliding update without the μ
    /// identification (the prediction alone).
    pub instructions_per_sample_without_identification: Option<f64>,
    /// Stick-slip and fixed-base models: the estimator's block size in the pipeline
    /// (`update_block`, `icount block`).
    pub block_size: Option<u32>,
    /// Stick-slip model: instructions per sliding sample (μ identified) in blocks of
    /// [`Self::block_size`].
    pub instructions_per_sample_in_blocks: Option<f64>,
    /// Stick-slip and fixed-base models: instructions per stuck sample in blocks.
    pub instructions_per_sample_stuck_in_blocks: Option<f64>,
    /// Instructions per steady-state stuck sample of the plan's model as the pipeline runs it
    /// (`icount model`): `note_inputs` on each sample of a batch of `ssvr_proto::BATCH`, then
    /// `predict_run` on the batch (the estimator's `update_block` and, in fuse mode, the
    /// identification of f and ξ and its adoption checks), the input generator removed.
    pub model_instructions_per_sample_stuck: Option<f64>,
    /// The same, sliding after one slip start (stick-slip: μ identified; rectangular: level +1);
    /// `None` for the fixed-base model (it pushes no event).
    pub model_instructions_per_sample_sliding: Option<f64>,
    /// Whether the model timed identifies f and ξ (`icount model tuning`: fuse mode, stick-slip
    /// and fixed-base models).
    pub model_tuning: Option<bool>,
    /// Adoptions of f and ξ while the model was timed (0 in the steady state).
    pub model_adoptions: Option<u32>,
    /// Updates timed in the steady-state block.
    pub updates: u32,
    /// SysTick ticks of the steady-state block.
    pub update_ticks: u32,
    /// SysTick ticks of the same loop without the update.
    pub loop_ticks: u32,
    /// Samples with a reversal timed.
    pub reversals: u32,
    /// SysTick ticks of the reversal block.
    pub reversal_ticks: u32,
    /// Reversals the estimator rejected during the benchmark.
    pub reversal_errors: u32,
    /// Instructions of the reversal detector per sample in its steady state (sliding, a new
    /// extremum every sample), generator loop removed.
    pub detector_instructions_per_sample: Option<f64>,
    /// Extra instructions of a sample where the detector reports a reversal (vertex fits).
    pub detector_instructions_per_reversal: Option<f64>,
    /// Instructions per sample of the firmware's whole step in batches of 16 (flags, detector,
    /// estimator, frames; no I/O) in the steady sliding state.
    pub pipeline_instructions_per_sample: Option<f64>,
    /// Extra instructions of the detector for a stick and the slip start that ends it (their kink
    /// fits), over sliding samples.
    pub detector_instructions_per_stick: Option<f64>,
}

/// Extract the instruction counts from the `icount` messages. Computed on the host from the raw
/// ticks in f64 (the firmware's own f32 summary is a cross-check).
pub fn instruction_counts(frames: &[Message]) -> Option<InstructionCounts> {
    let find = |topic: &str| frames.iter().find(|m| m.is("icount", Some(topic)));
    let cal = find("calibration")?;
    let raw = find("raw")?;
    let calibration_instructions: u32 = cal.u32("instructions")?;
    let calibration_ticks: u32 = cal.u32("ticks")?;
    if calibration_ticks == 0 {
        return None;
    }
    let ipt = f64::from(calibration_instructions) / f64::from(calibration_ticks);
    let updates: u32 = raw.u32("updates")?;
    let update_ticks: u32 = raw.u32("update_ticks")?;
    let loop_ticks: u32 = raw.u32("loop_ticks")?;
    let reversals: u32 = raw.u32("reversals")?;
    let reversal_ticks: u32 = raw.u32("reversal_ticks")?;
    let reversal_errors: u32 = raw.u32("reversal_errors")?;
    if updates == 0 {
        return None;
    }
    let overhead = f64::from(loop_ticks) * ipt / f64::from(updates);
    let per_sample = f64::from(update_ticks) * ipt / f64::from(updates) - overhead;
    let per_reversal = (reversals > 0)
        .then(|| f64::from(reversal_ticks) * ipt / f64::from(reversals) - overhead - per_sample);
    let ss = find("stick_slip");
    let stuck = ss.and_then(|m| {
        let n: u32 = m.u32("stuck_updates")?;
        let ticks: u32 = m.u32("stuck_ticks")?;
        (n > 0).then(|| f64::from(ticks) * ipt / f64::from(n) - overhead)
    });
    let predict = ss.and_then(|m| {
        let n: u32 = m.u32("predict_updates")?;
        let ticks: u32 = m.u32("predict_ticks")?;
        (n > 0).then(|| f64::from(ticks) * ipt / f64::from(n) - overhead)
    });
    let long = ss.and_then(|m| {
        let n: u32 = m.u32("long_events")?;
        let ticks: u32 = m.u32("long_event_ticks")?;
        let age: f64 = m.f64("max_age")?;
        (n > 0).then(|| {
            (
                f64::from(ticks) * ipt / f64::from(n) - overhead - per_sample,
                age,
            )
        })
    });
    let blk = find("block");
    let block_size = blk.and_then(|m| m.u32("batch"));
    let in_blocks = |field: &str| {
        blk.and_then(|m| {
            let n: u32 = m.u32("updates")?;
            let lp: u32 = m.u32("loop_ticks")?;
            let ticks: u32 = m.u32(field)?;
            // A block the estimator refused (never expected) voids the figures.
            let errors: u32 = m.u32("errors")?;
            (n > 0 && ticks > 0 && errors == 0)
                .then(|| (f64::from(ticks) - f64::from(lp)) * ipt / f64::from(n))
        })
    };
    // The model as the pipeline runs it: the same arithmetic as the estimator's blocks.
    let mdl = find("model");
    let model_per_sample = |field: &str| {
        mdl.and_then(|m| {
            let n: u32 = m.u32("updates")?;
            let lp: u32 = m.u32("loop_ticks")?;
            let ticks: u32 = m.u32(field)?;
            let errors: u32 = m.u32("errors")?;
            (n > 0 && ticks > 0 && errors == 0)
                .then(|| (f64::from(ticks) - f64::from(lp)) * ipt / f64::from(n))
        })
    };
    let det = find("detector");
    let pipe = find("pipeline");
    let per = |ticks: u32, n: u32| f64::from(ticks) * ipt / f64::from(n);
    let detector = det.and_then(|d| {
        let n: u32 = d.u32("samples")?;
        let lp: u32 = d.u32("loop_ticks")?;
        let ramp: u32 = d.u32("ramp_ticks")?;
        let tri: u32 = d.u32("triangle_ticks")?;
        let revs: u32 = d.u32("reversals")?;
        if n == 0 || revs == 0 {
            return None;
        }
        Some((
            per(ramp, n) - per(lp, n),
            (f64::from(tri) - f64::from(ramp)) * ipt / f64::from(revs),
        ))
    });
    let stick = find("detector_stick").and_then(|m| {
        let ramp: u32 = m.u32("ramp_ticks")?;
        let stair: u32 = m.u32("stair_ticks")?;
        let sticks: u32 = m.u32("sticks")?;
        (sticks > 0).then(|| (f64::from(stair) - f64::from(ramp)) * ipt / f64::from(sticks))
    });
    let pipeline = pipe.and_then(|p| {
        let n: u32 = p.u32("samples")?;
        let lp: u32 = p.u32("loop_ticks")?;
        let step: u32 = p.u32("step_ticks")?;
        (n > 0).then(|| per(step, n) - per(lp, n))
    });
    Some(InstructionCounts {
        calibration_instructions,
        calibration_ticks,
        instructions_per_tick: ipt,
        instructions_per_sample: per_sample,
        instructions_per_reversal: per_reversal,
        instructions_per_sample_stuck: stuck,
        instructions_per_event_max_age: long.map(|l| l.0),
        max_event_age: long.map(|l| l.1),
        instructions_per_sample_without_identification: predict,
        block_size,
        instructions_per_sample_in_blocks: in_blocks("slide_ticks"),
        instructions_per_sample_stuck_in_blocks: in_blocks("stuck_ticks"),
        model_instructions_per_sample_stuck: model_per_sample("stuck_ticks"),
        model_instructions_per_sample_sliding: model_per_sample("slide_ticks"),
        model_tuning: mdl.and_then(|m| m.bool("tuning")),
        model_adoptions: mdl.and_then(|m| m.u32("adoptions")),
        updates,
        update_ticks,
        loop_ticks,
        reversals,
        reversal_ticks,
        reversal_errors,
        detector_instructions_per_sample: detector.map(|d| d.0),
        detector_instructions_per_reversal: detector.map(|d| d.1),
        pipeline_instructions_per_sample: pipeline,
        detector_instructions_per_stick: stick,
    })
}
