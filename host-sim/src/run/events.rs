//! Friction events of a run, detected and true ([`EventMark`]), the friction level of a true event
//! ([`level_of`]), and the detection statistics: detected slip starts/reversals matched to the
//! true ones ([`match_events`], [`DetectionStats`]; the rule is in the module documentation of
//! [`crate::run`]).

use crate::truth::{self, EventKind};
use serde::Serialize;
use ssvr_proto::{Event, EventKind as FrameEventKind};

/// Default half-width of the window in which a detected event is matched to a true one (s).
pub const DEFAULT_MATCH_TOLERANCE_S: f64 = 0.02;

/// A slip start or reversal, detected or true.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventMark {
    /// Event time (s): true, or back-dated for a detection.
    pub time_s: f64,
    /// Sample time at which it was detected (s); the true time for a true event.
    pub detected_at_s: f64,
    /// Friction level after it (−1 or 1; 0 for a stick).
    pub level: f64,
    /// A stick (else a slip start or reversal).
    pub stick: bool,
}

/// Detection figures (matching: see the module documentation).
#[derive(Debug, Clone, Serialize)]
pub struct DetectionStats {
    /// Detected events matched to a true one.
    pub matched: usize,
    /// True slip starts/reversals with no detection.
    pub missed: usize,
    /// Detections with no true event.
    #[serde(rename = "false")]
    pub false_: usize,
    /// Mean latency (ms): sample of detection − true event time.
    pub latency_mean_ms: Option<f64>,
    /// Largest latency (ms).
    pub latency_max_ms: Option<f64>,
    /// Mean of the back-dated event time − true time (ms).
    pub timing_err_mean_ms: Option<f64>,
    /// RMS of the back-dated event time − true time (ms).
    pub timing_err_rms_ms: Option<f64>,
    /// Largest |back-dated event time − true time| (ms).
    pub timing_err_max_ms: Option<f64>,
    /// Half-width of the matching window (ms).
    pub match_tolerance_ms: f64,
}

/// The friction level after a true event (−1 or 1; 0 for a stick) and whether it is a stick.
pub(super) fn level_of(kind: EventKind) -> (f64, bool) {
    match kind {
        EventKind::SlipStart { direction } => (-direction.sign(), false),
        EventKind::Reversal { new_direction } => (-new_direction.sign(), false),
        EventKind::Stick => (0.0, true),
    }
}

/// A true event as the pipeline's event seen at sample time `t_s`: its level, back-dated by the
/// exact age in samples.
pub(super) fn frame_event(ev: &truth::Event, t_s: f64, rate_hz: f64) -> Event {
    let (level, stick) = level_of(ev.kind);
    Event {
        kind: if stick {
            FrameEventKind::Stick
        } else {
            FrameEventKind::Reversal
        },
        level: level as i8,
        age_samples: ((t_s - ev.time_s) * rate_hz) as f32,
    }
}

/// The true events up to `last_t_s` (the last sample), in order.
pub(super) fn true_marks(events: &[truth::Event], last_t_s: f64) -> Vec<EventMark> {
    events
        .iter()
        .filter(|e| e.time_s <= last_t_s)
        .map(|e| {
            let (level, stick) = level_of(e.kind);
            EventMark {
                time_s: e.time_s,
                detected_at_s: e.time_s,
                level,
                stick,
            }
        })
        .collect()
}

/// How many of `v` are sticks (`stick`) or slip starts/reversals (`!stick`).
pub(super) fn count(v: &[EventMark], stick: bool) -> usize {
    v.iter().filter(|e| e.stick == stick).count()
}

/// Match detected slip starts/reversals to true ones (see the module documentation); sticks in
/// either list are ignored.
pub fn match_events(detected: &[EventMark], truth: &[EventMark], tol_s: f64) -> DetectionStats {
    let truth: Vec<&EventMark> = truth.iter().filter(|e| !e.stick).collect();
    let mut used = vec![false; truth.len()];
    let (mut matched, mut false_) = (0usize, 0usize);
    let (mut lat_sum, mut lat_max) = (0.0f64, f64::NEG_INFINITY);
    let (mut te_sum, mut te_sq, mut te_max) = (0.0f64, 0.0f64, 0.0f64);
    for d in detected.iter().filter(|e| !e.stick) {
        let lo = truth.partition_point(|e| e.time_s < d.time_s - tol_s);
        let hi = truth.partition_point(|e| e.time_s <= d.time_s + tol_s);
        let best = (lo..hi)
            .filter(|&i| !used[i] && truth[i].level == d.level)
            .min_by(|&a, &b| {
                let da = (truth[a].time_s - d.time_s).abs();
                let db = (truth[b].time_s - d.time_s).abs();
                da.total_cmp(&db)
            });
        match best {
            Some(i) => {
                used[i] = true;
                matched += 1;
                let lat = d.detected_at_s - truth[i].time_s;
                lat_sum += lat;
                lat_max = lat_max.max(lat);
                let te = d.time_s - truth[i].time_s;
                te_sum += te;
                te_sq += te * te;
                te_max = te_max.max(te.abs());
            }
            None => false_ += 1,
        }
    }
    let ms = |x: f64| (matched > 0).then_some(1e3 * x);
    let m = matched.max(1) as f64;
    DetectionStats {
        matched,
        missed: truth.len() - matched,
        false_,
        latency_mean_ms: ms(lat_sum / m),
        latency_max_ms: ms(lat_max),
        timing_err_mean_ms: ms(te_sum / m),
        timing_err_rms_ms: ms((te_sq / m).sqrt()),
        timing_err_max_ms: ms(te_max),
        match_tolerance_ms: 1e3 * tol_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mark(t: f64, at: f64, level: f64) -> EventMark {
        EventMark {
            time_s: t,
            detected_at_s: at,
            level,
            stick: false,
        }
    }

    #[test]
    fn matching_counts_missed_false_and_timing() {
        let truth = [
            mark(0.10, 0.10, -1.0),
            mark(0.20, 0.20, 1.0),
            mark(0.30, 0.30, -1.0),
            EventMark {
                time_s: 0.35,
                detected_at_s: 0.35,
                level: 0.0,
                stick: true,
            },
        ];
        let detected = [
            mark(0.1001, 0.103, -1.0), // matched, +0.1 ms, latency 3 ms
            mark(0.1999, 0.205, 1.0),  // matched, −0.1 ms, latency 5 ms
            mark(0.25, 0.26, 1.0),     // false: no true event within 20 ms
            mark(0.301, 0.302, 1.0),   // false: wrong level
        ];
        let d = match_events(&detected, &truth, 0.02);
        assert_eq!((d.matched, d.missed, d.false_), (2, 1, 2));
        assert!((d.latency_mean_ms.unwrap() - 4.0).abs() < 1e-9);
        assert!((d.latency_max_ms.unwrap() - 5.0).abs() < 1e-9);
        assert!((d.timing_err_max_ms.unwrap() - 0.1).abs() < 1e-9);
        assert!(d.timing_err_mean_ms.unwrap().abs() < 1e-9);
        let none = match_events(&[], &truth, 0.02);
        assert_eq!((none.matched, none.missed, none.false_), (0, 3, 0));
        assert_eq!(none.latency_mean_ms, None);
    }
}
