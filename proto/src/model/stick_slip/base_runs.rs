//! The stick-slip model's runs with a [`BaseTuning`] (predict mode's tuning from the base
//! accelerometer, either mode's offsets): the steady and open-loop-start runs, and the checks
//! and adoptions after them.

use super::StickSlipModel;
use crate::flags;
use crate::frame::Frame;
use crate::model::base_tuning::{BaseSlot, BaseTuning};
use crate::model::friction::FrictionSlot;
use crate::model::stick_slip::StickSlipF32;
use crate::pipeline::BATCH;

impl<const H: usize, const EVENTS: bool, F: FrictionSlot, B: BaseSlot>
    StickSlipModel<H, EVENTS, F, B>
{
    /// [`Model::predict_run`] with a [`BaseTuning`]: the table input less its identified offset;
    /// in predict mode the sliding samples' top acceleration from the base accelerometer (the
    /// momentum balance) for the sliding observer and the adoptions of f, ξ and μ; in fuse mode
    /// the measured top less its identified offset, and the top accelerometer's tuning.
    ///
    /// (A steady run, past the open-loop start, works in the batch's own input arrays: the
    /// identifications read the measured samples first, then the model's inputs replace them
    /// and its predictions the base's; no array on the stack to clear (~10 instructions per
    /// sample), no pass of its own for the flags. The open-loop start's runs keep the measured
    /// samples beside the inputs: [`Self::predict_open_run`].)
    #[inline(always)]
    pub(super) fn predict_run_base(&mut self, frames: &mut [Frame], from: usize) {
        // (Without a rest: a run is split at the open-loop start's end, where the top offset
        // (fuse mode) or the table's (predict mode) may be adopted, so that every batching
        // adopts it at the same sample.)
        let open = self.base_tuning.get().map_or(0, BaseTuning::open_start);
        if open > 0 {
            if open < frames.len() {
                let (first, rest) = frames.split_at_mut(open);
                self.predict_open_run(first, from);
                self.predict_run_base(rest, from + open);
            } else {
                self.predict_open_run(frames, from);
            }
            return;
        }
        let to = from + frames.len();
        let level = self.est.phase().level();
        let (Some(bt), Some(table), Some(base), Some(top)) = (
            self.base_tuning.get_mut(),
            self.table.get_mut(from..to),
            self.base.get_mut(from..to),
            self.top.get_mut(from..to),
        ) else {
            return;
        };
        // The identifications read the measured samples (nothing they do changes the model's
        // inputs or its state before the checks below).
        bt.push_run(base, top);
        if let Some(t) = &mut self.tuning {
            t.push_run(top, base);
        }
        bt.inputs_in_place(table, top, base, level);
        if self.est.update_block(table, top, base).is_ok() {
            for (f, &p) in frames.iter_mut().zip(base.iter()) {
                f.prediction = p;
            }
        }
        self.after_run(frames.len(), level);
    }

    /// [`Self::predict_run_base`] over a run in the open-loop start (its first runs only): the
    /// measured samples kept beside the model's inputs for the start's notes.
    #[cold]
    #[inline(never)]
    pub(super) fn predict_open_run(&mut self, frames: &mut [Frame], from: usize) {
        let to = from + frames.len();
        let (Some(bt), Some(table), Some(base), Some(measured)) = (
            self.base_tuning.get_mut(),
            self.table.get(from..to),
            self.base.get(from..to),
            self.top.get(from..to),
        ) else {
            return;
        };
        let level = self.est.phase().level();
        let (fuse, n) = (self.fuse, frames.len());
        // The model's inputs beside the measured samples (the steady runs' way, on copies).
        let (mut top, mut u) = ([0.0f32; BATCH], [0.0f32; BATCH]);
        for ((y, u), (&m, &t)) in top
            .iter_mut()
            .zip(u.iter_mut())
            .zip(measured.iter().zip(table))
        {
            (*y, *u) = (m, t);
        }
        // (The table's offset from the start's first sample, provisionally.)
        if let (Some(&t), Some(f)) = (table.first(), frames.first()) {
            bt.begin_table_start(if f.flags & flags::ACCEL_UNUSABLE == 0 {
                t
            } else {
                f32::NAN
            });
        }
        if let (Some(y), Some(u)) = (top.get_mut(..n), u.get_mut(..n)) {
            bt.inputs_in_place(u, y, base, level);
        }
        if fuse {
            // (No stuck-phase observer in the open-loop start.)
            top.fill(f32::NAN);
        }
        // (Sample by sample, bit for bit `update_block`: the image holds one block loop.)
        let mut out = [0.0f32; BATCH];
        for (((f, o), &u), &y) in frames.iter_mut().zip(out.iter_mut()).zip(&u).zip(&top) {
            *o = self.est.update_one(u, y);
            f.prediction = *o;
        }
        if fuse {
            bt.note_open_start(measured, out.get(..n).unwrap_or(&[]));
        }
        bt.push_run(base, measured);
        if let Some(t) = &mut self.tuning {
            t.push_run(measured, base);
        }
        table_start(bt, &mut self.est, table, frames);
        self.after_run(n, level);
    }

    /// The base tuning's check that was due after a run begun in phase `level`: its adoptions.
    #[inline(never)]
    pub(super) fn base_check(&mut self, level: i8) {
        let Some(bt) = self.base_tuning.get_mut() else {
            return;
        };
        let before = bt.mu_for(level);
        let (c, mu) = bt.check_due();
        if let Some(c) = c {
            self.est.retune(c);
        }
        if let Some(mu) = mu {
            self.friction_adopted(mu, level, before);
        }
    }

    /// The base tuning's friction coefficient `mu` adopted in phase `level`, `before` the one
    /// in use until then: the estimator's friction, and in predict mode while sliding the
    /// momentum balance's top, which jumps with μ (the state alike).
    #[inline(never)]
    pub(super) fn friction_adopted(&mut self, mu: f32, level: i8, before: f32) {
        self.est.set_friction(mu);
        if let Some(bt) = self.base_tuning.get() {
            let d = bt.top_shift(level, before);
            if d != 0.0 {
                self.est.shift_top(d);
            }
        }
    }

    /// The checks after a run of `n` samples begun in phase `level`: the base tuning's
    /// adoptions (f and ξ, μ, the top's offset and gain) and, in fuse mode, the oscillator
    /// identification's. (Out of line: once per run, and one copy for both kinds of run.)
    #[inline(never)]
    pub(super) fn after_run(&mut self, n: usize, level: i8) {
        let Some(bt) = self.base_tuning.get_mut() else {
            return;
        };
        // (The run's top scale: a change from the check's adoptions reaches the tuning from the
        // next run, batches and single steps alike.)
        let scale = bt.top_scale();
        if bt.due(n as u32) {
            self.base_check(level);
        }
        let Some(bt) = self.base_tuning.get_mut() else {
            return;
        };
        // (The identification reads the measured top as it is: its offsets filtered out, its
        // gain the one to find; f and ξ are fitted on it scaled by the gain correction in use.)
        if let Some(t) = &mut self.tuning {
            // (Fuse mode: M from the momentum balance, with the f and ξ in use; at the check
            // that found it, in batches as one sample at a time. Deferring it to a run that
            // starts stuck made the batches' runs decide, and the firmware left the host.)
            if let Some(m1) = bt.take_m1() {
                if let Some(c) = t.with_m1(m1) {
                    bt.set_m1(m1);
                    self.est.retune(c);
                }
            }
            if let Some(c) = t.check(n as u32) {
                self.est.retune(c);
            }
            self.est.hold_wide(!t.known());
            if let Some(g) = t.take_gain() {
                bt.adopt_stuck_gain(g);
            }
            if bt.top_scale() != scale {
                t.set_top_scale(bt.top_scale());
            }
        }
    }
}

/// The table's start (either mode without a rest, with a planned start) over a run's `table`
/// inputs, its flagged samples left out
/// ([`BaseTuning::note_table_start`]): an offset found at its end is removed from the next run
/// on (as from the next sample one at a time), and the model's response to it so far from the
/// estimator's state. Out of line: it runs on the run's first samples only.
#[cold]
#[inline(never)]
fn table_start<const H: usize>(
    bt: &mut BaseTuning,
    est: &mut StickSlipF32<H>,
    table: &[f32],
    frames: &[Frame],
) {
    let mut t = [f32::NAN; BATCH];
    for ((t, &u), f) in t.iter_mut().zip(table).zip(frames) {
        if f.flags & flags::ACCEL_UNUSABLE == 0 {
            *t = u;
        }
    }
    let n = frames.len().min(table.len()).min(BATCH);
    if let Some((b, intervals)) = bt.note_table_start(t.get(..n).unwrap_or(&[])) {
        est.remove_input_offset(b, intervals);
    }
}
