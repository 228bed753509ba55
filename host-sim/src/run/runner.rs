//! One run's state, sample by sample ([`Runner`]): the truth's sampler and the sensors, the
//! pipeline and its detected events, the ideal estimator fed the true events, the rectangular
//! model for comparison, the error statistics, the CSV row and the plot collection; each of the
//! per-sample steps of the module documentation of [`crate::run`] is one method.

use super::csv::{CsvWriter, Row};
use super::events::{frame_event, EventMark};
use super::plot::{PlotCollector, PlotPoint};
use super::stats::{Errors, Predictions, Revision};
use super::StickPolicy;
use crate::pipeline::{self, sample_of};
use crate::scene::Scene;
use crate::sensors::SensorModel;
use crate::truth::{self, Phase, Sampler, Truth};
use anyhow::{anyhow, bail, Result};
use ssvr_core::recursion::Estimator32;
use ssvr_proto::{flags, Event, Frame, Model, Plan, Sample, Step};
use std::io::Write;

/// A run in progress.
pub(super) struct Runner<'a> {
    scene: &'a Scene,
    label: &'a str,
    rate: f64,
    zero_at_stick: bool,
    /// The firmware's pipeline for this scene and model: the same plan, detector, model and step.
    pub pipe: Box<dyn Step>,
    /// The same model fed the truth's own events at their exact times.
    ideal: Box<dyn Model>,
    /// The rectangular model on the same detected events, for comparison.
    rect: Estimator32,
    sensors: SensorModel,
    sampler: Sampler<'a>,
    events: &'a [truth::Event],
    /// The next true event not yet given to the ideal estimator.
    next_true: usize,
    /// Detected slip starts, reversals and sticks, in order.
    pub detected: Vec<EventMark>,
    /// The errors against the truth.
    pub errors: Errors,
    /// The revised predictions' errors.
    pub revision: Revision,
    /// The plot window's series (when asked for).
    pub plot: Option<PlotCollector>,
}

impl<'a> Runner<'a> {
    /// Set up the run of `scene` on its simulated `truth` with the pipeline of `plan`.
    pub fn new(
        scene: &'a Scene,
        label: &'a str,
        truth: &'a Truth,
        plan: &Plan,
        on_stick: StickPolicy,
        plot_window: Option<(f64, f64)>,
    ) -> Result<Self> {
        let rate = scene.rate_hz;
        let zero_at_stick = on_stick == StickPolicy::Zero;
        let pipe_opts = pipeline::Options {
            zero_at_stick,
            ..pipeline::Options::default()
        };
        let pipe = pipeline::build(plan, pipe_opts).map_err(|e| anyhow!("{label}: {e}"))?;
        let ideal = pipeline::model(plan, pipe_opts).map_err(|e| anyhow!("{label}: {e}"))?;
        let rect = Estimator32::new(&scene.structure, rate)
            .map_err(|e| anyhow!("{label}: estimator: {e}"))?;
        Ok(Self {
            scene,
            label,
            rate,
            zero_at_stick,
            pipe,
            ideal,
            rect,
            sensors: SensorModel::new(&scene.sensors),
            sampler: truth.sampler(),
            events: truth.events(),
            next_true: 0,
            detected: Vec::new(),
            errors: Errors::default(),
            revision: Revision::new(plan.history),
            plot: plot_window.map(|w| PlotCollector::new(w, rate, scene.samples)),
        })
    }

    /// Sample `k`: truth, sensors, the pipeline, the ideal and comparison estimators, the
    /// statistics, the CSV row and the plot.
    pub fn sample<W: Write>(&mut self, k: u64, csv: &mut CsvWriter<W>) -> Result<()> {
        let label = self.label;
        let t = self.scene.time(k);
        let s = self
            .sampler
            .sample(t)
            .ok_or_else(|| anyhow!("{label}: no truth sample at t = {t} s (sample {k})"))?;
        let f = self.sensors.measure(k, &s);
        let sample = sample_of(&f);

        let (frame, pushed) = self.pipeline_step(t, &sample)?;
        let rect_pred = self.comparison_step(t, frame.event)?;
        let ideal_pred = self.ideal_step(t, &sample)?;

        let truth_top = s.top_accel_m_s2;
        let predictions = Predictions {
            predicted: frame.prediction,
            rectangular: rect_pred,
            ideal: ideal_pred,
            measured: f.top_accel_m_s2,
        };
        self.errors.add(t, truth_top, &predictions);
        self.revision
            .add(self.pipe.as_ref(), self.scene, k, truth_top);

        csv.row(&Row {
            t,
            measured: &f,
            pushed,
            event: frame.event,
            predicted: frame.prediction,
            truth_top,
            ideal: ideal_pred,
            truth_slip_m: s.slip_m,
            truth_dir: match s.phase {
                Phase::Stuck => 0,
                Phase::SlidingPos => 1,
                Phase::SlidingNeg => -1,
            },
        })?;

        if let Some(p) = self.plot.as_mut() {
            p.push(
                t,
                &PlotPoint {
                    measured: f.top_accel_m_s2 as f64,
                    predicted: frame.prediction as f64,
                    truth: truth_top,
                    slip_measured: f.disp_m as f64,
                    slip_truth: s.slip_m,
                },
            );
        }
        Ok(())
    }

    /// The pipeline's step (detector, its event to the model, the prediction) and its event's
    /// bookkeeping: the event recorded, and the level pushed (0 without a pushed slip start or
    /// reversal).
    fn pipeline_step(&mut self, t: f64, sample: &Sample) -> Result<(Frame, i32)> {
        let frame = self.pipe.step(sample);
        let mut pushed = 0i32;
        if let Some(e) = frame.event {
            let stick = e.is_stick();
            let mark = EventMark {
                time_s: t - e.age_samples as f64 / self.rate,
                detected_at_s: t,
                level: f64::from(e.level),
                stick,
            };
            if frame.flags & flags::EVENT_REJECTED != 0 {
                bail!(
                    "{}: the estimator rejected the event {e:?} at t = {t} s",
                    self.label
                );
            }
            if frame.flags & flags::EVENT_PUSHED != 0 && !stick {
                pushed = i32::from(e.level);
            }
            self.detected.push(mark);
        }
        Ok((frame, pushed))
    }

    /// The rectangular model on the same detected event (a stick only with `on_stick = zero`),
    /// then its prediction.
    fn comparison_step(&mut self, t: f64, event: Option<Event>) -> Result<f32> {
        if let Some(e) = event {
            let stick = e.is_stick();
            if !stick || self.zero_at_stick {
                let level = if stick { 0.0 } else { f32::from(e.level) };
                self.rect
                    .push_reversal(level, e.age_samples)
                    .map_err(|err| {
                        anyhow!(
                            "{}: estimator rejected the event {e:?} at t = {t} s: {err}",
                            self.label
                        )
                    })?;
            }
        }
        Ok(self.rect.update())
    }

    /// The ideal estimator: the truth's own slip starts, reversals and sticks up to `t`, at their
    /// exact ages, then its prediction.
    fn ideal_step(&mut self, t: f64, sample: &Sample) -> Result<f32> {
        let label = self.label;
        while let Some(ev) = self.events.get(self.next_true).filter(|ev| ev.time_s <= t) {
            let e = frame_event(ev, t, self.rate);
            self.ideal.push(&e).map_err(|err| {
                anyhow!(
                    "{label}: ideal estimator rejected the true event at t = {} s: {err}",
                    ev.time_s
                )
            })?;
            self.next_true += 1;
        }
        let (pred, _) =
            pipeline::model_step(self.ideal.as_mut(), None, sample, self.pipe.offsets())
                .map_err(|err| anyhow!("{label}: ideal estimator at t = {t} s: {err}"))?;
        Ok(pred)
    }

    /// After the last sample: the last samples' revised predictions.
    pub fn finish(&mut self) {
        self.revision.finish(self.pipe.as_ref(), self.scene);
    }
}
