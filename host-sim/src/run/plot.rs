//! The series of a run's plot window ([`PlotData`]): collected sample by sample
//! ([`PlotCollector`]), each min/max decimated to at most 2·[`PLOT_BUCKETS`] points
//! ([`Decimator`]), with the detected and true events in the window.

use super::events::EventMark;
use crate::truth::Truth;

/// Number of min/max buckets of a decimated plot series (each bucket gives at most two points).
pub const PLOT_BUCKETS: u64 = 2500;

/// Default length of the plot window (s).
pub const DEFAULT_PLOT_WINDOW_S: f64 = 2.0;

/// One decimated series of a plot: (t, value) points in time order.
pub type Series = Vec<(f64, f64)>;

/// The series of the plot window (min/max decimated to at most 2·[`PLOT_BUCKETS`] points each).
#[derive(Debug, Clone, Default)]
pub struct PlotData {
    /// Window (s).
    pub window: (f64, f64),
    /// Measured ü1.
    pub measured: Series,
    /// Predicted ü1.
    pub predicted: Series,
    /// True ü1.
    pub truth: Series,
    /// Measured slip (m).
    pub slip_measured: Series,
    /// True slip (m).
    pub slip_truth: Series,
    /// Detected events in the window, with the true slip at their back-dated time (m).
    pub detected: Vec<(EventMark, f64)>,
    /// True events in the window, with the true slip at their time (m).
    pub true_events: Vec<(EventMark, f64)>,
    /// Scene name.
    pub scene: String,
}

/// Min/max decimation of one series into fixed buckets of `bucket` samples.
#[derive(Debug, Clone)]
pub(crate) struct Decimator {
    bucket: u64,
    n: u64,
    lo: (f64, f64),
    hi: (f64, f64),
    out: Series,
}

impl Decimator {
    pub fn new(bucket: u64) -> Self {
        Self {
            bucket: bucket.max(1),
            n: 0,
            lo: (0.0, f64::INFINITY),
            hi: (0.0, f64::NEG_INFINITY),
            out: Vec::new(),
        }
    }

    pub fn push(&mut self, t: f64, v: f64) {
        if !v.is_finite() {
            return;
        }
        if v < self.lo.1 {
            self.lo = (t, v);
        }
        if v > self.hi.1 {
            self.hi = (t, v);
        }
        self.n += 1;
        if self.n >= self.bucket {
            self.emit();
        }
    }

    fn emit(&mut self) {
        if self.n == 0 {
            return;
        }
        let (a, b) = if self.lo.0 <= self.hi.0 {
            (self.lo, self.hi)
        } else {
            (self.hi, self.lo)
        };
        self.out.push(a);
        if b != a {
            self.out.push(b);
        }
        self.n = 0;
        self.lo = (0.0, f64::INFINITY);
        self.hi = (0.0, f64::NEG_INFINITY);
    }

    pub fn finish(mut self) -> Series {
        self.emit();
        self.out
    }
}

/// One sample's values of the plotted series.
pub(crate) struct PlotPoint {
    /// Measured ü1.
    pub measured: f64,
    /// Predicted ü1.
    pub predicted: f64,
    /// True ü1.
    pub truth: f64,
    /// Measured slip (m).
    pub slip_measured: f64,
    /// True slip (m).
    pub slip_truth: f64,
}

/// The plot window's series, collected sample by sample.
pub(crate) struct PlotCollector {
    window: (f64, f64),
    measured: Decimator,
    predicted: Decimator,
    truth: Decimator,
    slip_measured: Decimator,
    slip_truth: Decimator,
}

impl PlotCollector {
    /// For the window `(from, to)` (s) of a run of `samples` samples at `rate` Hz.
    pub fn new((from, to): (f64, f64), rate: f64, samples: u64) -> Self {
        let first = (from * rate).ceil().max(0.0);
        let last = (to * rate).floor().min(samples.saturating_sub(1) as f64);
        let n = (last - first + 1.0).max(1.0) as u64;
        let bucket = n.div_ceil(PLOT_BUCKETS).max(1);
        let bucket = if bucket <= 2 { 1 } else { bucket };
        Self {
            window: (from, to),
            measured: Decimator::new(bucket),
            predicted: Decimator::new(bucket),
            truth: Decimator::new(bucket),
            slip_measured: Decimator::new(bucket),
            slip_truth: Decimator::new(bucket),
        }
    }

    /// The sample at `t` (ignored outside the window).
    pub fn push(&mut self, t: f64, p: &PlotPoint) {
        if t >= self.window.0 && t <= self.window.1 {
            self.measured.push(t, p.measured);
            self.predicted.push(t, p.predicted);
            self.truth.push(t, p.truth);
            self.slip_measured.push(t, p.slip_measured);
            self.slip_truth.push(t, p.slip_truth);
        }
    }

    /// The series of a replay (no truth: its series are empty), with the `detected` events in
    /// the window, each with the measured slip at its detection (m).
    pub fn finish_measured(self, detected: &[(EventMark, f64)], scene: &str) -> PlotData {
        let (from, to) = self.window;
        PlotData {
            window: self.window,
            measured: self.measured.finish(),
            predicted: self.predicted.finish(),
            truth: Vec::new(),
            slip_measured: self.slip_measured.finish(),
            slip_truth: Vec::new(),
            detected: detected
                .iter()
                .filter(|(e, _)| e.time_s >= from && e.time_s <= to)
                .copied()
                .collect(),
            true_events: Vec::new(),
            scene: scene.to_string(),
        }
    }

    /// The series, with the events of `detected` and `true_events` in the window.
    pub fn finish(
        self,
        truth: &Truth,
        detected: &[EventMark],
        true_events: &[EventMark],
        scene: &str,
    ) -> PlotData {
        let (from, to) = self.window;
        let slip_at = |t: f64| truth.sample(t).map_or(0.0, |s| s.slip_m);
        let in_window = |v: &[EventMark]| {
            v.iter()
                .filter(|e| e.time_s >= from && e.time_s <= to)
                .map(|e| (*e, slip_at(e.time_s.max(0.0))))
                .collect::<Vec<_>>()
        };
        PlotData {
            window: self.window,
            measured: self.measured.finish(),
            predicted: self.predicted.finish(),
            truth: self.truth.finish(),
            slip_measured: self.slip_measured.finish(),
            slip_truth: self.slip_truth.finish(),
            detected: in_window(detected),
            true_events: in_window(true_events),
            scene: scene.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_extremes_in_time_order() {
        let mut d = Decimator::new(4);
        for (i, v) in [0.0, 3.0, -2.0, 1.0, 5.0, 4.0, 6.0].iter().enumerate() {
            d.push(i as f64, *v);
        }
        let s = d.finish();
        assert_eq!(s, vec![(1.0, 3.0), (2.0, -2.0), (5.0, 4.0), (6.0, 6.0)]);
        let mut one = Decimator::new(1);
        one.push(0.0, 1.0);
        one.push(1.0, 2.0);
        assert_eq!(one.finish(), vec![(0.0, 1.0), (1.0, 2.0)]);
    }
}
