//! The error statistics of a run against the truth's ü1: one running [`ErrStats`] per prediction
//! ([`Errors`]: the estimator, the rectangular comparison, the ideal estimator and the top
//! accelerometer), and the revised predictions compared once final ([`Revision`]).

use crate::scene::Scene;
use ssvr_proto::Step;
use std::collections::VecDeque;

/// Running error statistics of a prediction against the truth.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct ErrStats {
    /// max |value − truth|.
    pub max: f64,
    /// Time of that maximum (s).
    pub at: f64,
    sum_sq: f64,
    /// max |value|.
    pub peak: f64,
}

impl ErrStats {
    /// Add a sample at `t`.
    pub fn add(&mut self, t: f64, value: f64, truth: f64) {
        let e = (value - truth).abs();
        if e > self.max || e.is_nan() {
            self.max = e;
            self.at = t;
        }
        self.sum_sq += e * e;
        self.peak = self.peak.max(value.abs());
    }

    /// The RMS error over `n` samples.
    pub fn rms(&self, n: u64) -> f64 {
        if n == 0 {
            0.0
        } else {
            (self.sum_sq / n as f64).sqrt()
        }
    }
}

/// The errors of every sample's predictions against the truth's ü1.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Errors {
    /// The estimator (the pipeline's prediction).
    pub predicted: ErrStats,
    /// The rectangular model on the same detected events.
    pub rectangular: ErrStats,
    /// The estimator fed the true events.
    pub ideal: ErrStats,
    /// The top accelerometer.
    pub measured: ErrStats,
    /// Peak |truth ü1| over the samples.
    pub truth_peak: f64,
}

/// The predictions of one sample at `t`.
pub(super) struct Predictions {
    pub predicted: f32,
    pub rectangular: f32,
    pub ideal: f32,
    pub measured: f32,
}

impl Errors {
    /// Add the sample at `t` with the true ü1 `truth`.
    pub fn add(&mut self, t: f64, truth: f64, p: &Predictions) {
        self.predicted.add(t, p.predicted as f64, truth);
        self.rectangular.add(t, p.rectangular as f64, truth);
        self.ideal.add(t, p.ideal as f64, truth);
        // (A dropped frame has no measurement: NaN, not part of the accelerometer's error.)
        if p.measured.is_finite() {
            self.measured.add(t, p.measured as f64, truth);
        }
        self.truth_peak = self.truth_peak.max(truth.abs());
    }
}

/// Revised predictions: each sample once every event that can reach back to it is known (the
/// detector's stick window plus its fits), compared with the truth kept for that long.
/// The oldest sample the stick-slip model keeps is `history − 1` back; an event is back-dated
/// by at most `max_age` = history − 2 samples, so that sample is final.
#[derive(Debug, Clone, Default)]
pub(super) struct Revision {
    /// Samples after which a prediction is final.
    pub delay: u64,
    /// The revised predictions' errors.
    pub err: ErrStats,
    /// Samples without a revised prediction.
    pub missing: u64,
    truth: VecDeque<f64>,
}

impl Revision {
    /// For a model keeping `history` samples.
    pub fn new(history: usize) -> Self {
        Self {
            delay: history.saturating_sub(1) as u64,
            ..Self::default()
        }
    }

    fn compare(&mut self, pipe: &dyn Step, scene: &Scene, d: u64, want: f64) {
        match pipe.revised(d) {
            Some(r) => self.err.add(scene.time(d), r as f64, want),
            None => self.missing += 1,
        }
    }

    /// After sample `k` with the true ü1 `truth`: compare the sample `delay` back, now final.
    pub fn add(&mut self, pipe: &dyn Step, scene: &Scene, k: u64, truth: f64) {
        self.truth.push_back(truth);
        if k >= self.delay {
            let want = self.truth.pop_front().unwrap_or(f64::NAN);
            self.compare(pipe, scene, k - self.delay, want);
        }
    }

    /// After the last sample: the last samples, revised by everything seen.
    pub fn finish(&mut self, pipe: &dyn Step, scene: &Scene) {
        let first = scene.samples.saturating_sub(self.truth.len() as u64);
        let last = std::mem::take(&mut self.truth);
        for (i, want) in last.into_iter().enumerate() {
            self.compare(pipe, scene, first + i as u64, want);
        }
    }
}
