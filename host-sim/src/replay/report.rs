//! The report of `host-sim replay` (`--json`, and the summary printed without it).

use crate::run::Identified;
use serde::Serialize;

/// Detected friction events.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct EventCounts {
    /// Slip starts.
    pub slip_starts: usize,
    /// Reversals.
    pub reversals: usize,
    /// Sticks.
    pub sticks: usize,
}

/// The prediction against the recorded top acceleration (samples where both are finite and the
/// sample is neither missing nor saturated).
#[derive(Debug, Clone, Serialize)]
pub struct VsMeasured {
    /// Samples compared.
    pub samples_compared: u64,
    /// max |predicted − measured| (m/s²).
    pub max_err_m_s2: f64,
    /// RMS of predicted − measured (m/s²).
    pub rms_err_m_s2: f64,
    /// The RMS error in % of the measured peak.
    pub rms_err_pct_of_peak: f64,
    /// max |measured| (m/s²).
    pub peak_measured_m_s2: f64,
    /// max |predicted| (m/s²).
    pub peak_predicted_m_s2: f64,
}

/// The JSON report of `host-sim replay`.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayReport {
    /// Scene name.
    pub scene: String,
    /// The scene file.
    pub scene_file: String,
    /// The recording's CSV.
    pub recording: String,
    /// The CSV output.
    pub out: String,
    /// Samples through the pipeline (rows of the output).
    pub samples: u64,
    /// Samples flagged MISSING or NOT_FINITE (skipped by the time column, unreadable cells).
    pub flagged_samples: u64,
    /// Data rows of the recording.
    pub rows: u64,
    /// Unreadable channel cells (empty, NaN, text).
    pub bad_cells: u64,
    /// Rows with an unreadable time cell (their sample is MISSING).
    pub bad_times: u64,
    /// Samples inserted MISSING where the time column skipped them.
    pub gap_samples: u64,
    /// Rows dropped: their time step was shorter than half a sample.
    pub dropped_rows: u64,
    /// The sample rate (Hz).
    pub rate_hz: f64,
    /// Where the rate came from: `rate_hz` or `time_column`.
    pub rate_from: &'static str,
    /// The rest before the input the offsets were zeroed on (s).
    pub start_s: f64,
    /// The model.
    pub model: &'static str,
    /// The mode.
    pub mode: &'static str,
    /// Why this model.
    pub model_reason: String,
    /// The specimen's parameters and the sensors' offsets as the estimator ends (as in `run`).
    pub identified: Identified,
    /// Detected friction events.
    pub events: EventCounts,
    /// The prediction against the recorded top acceleration (absent without a top column).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vs_measured_top: Option<VsMeasured>,
    /// Wall-clock time (s).
    pub runtime_s: f64,
}

/// The human summary.
pub fn summary_text(r: &ReplayReport) -> String {
    let mut s = format!(
        "replay {} ({}): {} samples at {} Hz ({}), {} flagged ({} unreadable cells, {} skipped \
         samples, {} dropped rows)\n  model {} ({}), mode {}\n  events: {} slip starts, {} \
         reversals, {} sticks\n",
        r.scene,
        r.recording,
        r.samples,
        r.rate_hz,
        r.rate_from,
        r.flagged_samples,
        r.bad_cells,
        r.gap_samples,
        r.dropped_rows,
        r.model,
        r.model_reason,
        r.mode,
        r.events.slip_starts,
        r.events.reversals,
        r.events.sticks,
    );
    if let Some(v) = &r.vs_measured_top {
        s += &format!(
            "  vs measured top: max {:.4} m/s², RMS {:.4} m/s² ({:.3} % of peak {:.4} m/s²); \
             predicted peak {:.4} m/s²\n",
            v.max_err_m_s2,
            v.rms_err_m_s2,
            v.rms_err_pct_of_peak,
            v.peak_measured_m_s2,
            v.peak_predicted_m_s2
        );
    }
    s += &format!("  out: {}\n", r.out);
    s
}
