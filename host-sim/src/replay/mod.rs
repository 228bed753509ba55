//! `host-sim replay`: a recorded test through the controller's pipeline, sample by sample.
//!
//! The scene ([`ReplayScene`]) gives the specimen as the controller knows it and a
//! `[recording]`: a CSV whose rows ([`reader::Reader`], streamed row by row) become the
//! pipeline's samples. The pipeline is `run`'s ([`crate::pipeline::plan_for_specimen`] and
//! [`crate::pipeline::build`]: the firmware's plan, detector and model), so a `run` CSV replayed
//! gives `run`'s predictions bit for bit. One CSV row ([`CSV_HEADER`]) per sample is written as
//! soon as it is computed, flushed every [`FLUSH_EVERY_ROWS`] rows; a set `stop` (Ctrl-C) keeps
//! the rows written.
//!
//! The model, without `--model`: stick-slip when the recording has a base accelerometer column
//! (its slip-acceleration detector needs it), else rectangular when it has a slip column (the
//! displacement reversal detector), else fixed-base. The mode, without `--mode`: fuse when the
//! recording has a top accelerometer column, else predict.

pub mod reader;
mod report;

pub use report::{summary_text, EventCounts, ReplayReport, VsMeasured};

use crate::model::Model;
use crate::pipeline;
use crate::run::{
    EventMark, Identified, Interrupted, Num, PlotCollector, PlotData, PlotPoint, FLUSH_EVERY_ROWS,
};
use anyhow::{anyhow, bail, Context, Result};
use reader::{Item, Reader};
use ssvr_proto::{flags, Channel, Frame, Mode, Step};
use ssvr_scene::ReplayScene;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// The CSV header of `replay` (one row per sample follows).
///
/// * `t_s`: the row's time (the time column, or k / rate_hz; t0 + n / rate for a sample the
///   recording skipped);
/// * `table_accel_m_s2`, `base_accel_m_s2`, `measured_top_accel_m_s2`, `rel_disp_m`: the
///   measured channels in SI units (`run`'s names; empty for a channel the recording has no
///   column for, `NaN` for an unreadable cell or a missing sample);
/// * `predicted_top_accel_m_s2`: the estimator's ü1 (f32);
/// * `detected_event` (`slip_start`, `reversal`, `stick` or empty), `event_age_samples` (the
///   detector's back-dating, empty without an event);
/// * `flags`: the pipeline's frame flags (`ssvr_proto::flags`: 1 NOT_FINITE, 4 MISSING, 16
///   EVENT_PUSHED, 128 DISP_INVALID, …).
pub const CSV_HEADER: &str = "t_s,table_accel_m_s2,base_accel_m_s2,measured_top_accel_m_s2,rel_disp_m,predicted_top_accel_m_s2,detected_event,event_age_samples,flags";

/// Options of [`replay`].
#[derive(Debug, Clone)]
pub struct ReplayOptions {
    /// Name of the CSV output in messages and in the report.
    pub out_name: String,
    /// The estimator model; `None`: chosen from the recording's columns (module doc).
    pub model: Option<Model>,
    /// What the model may read; `None`: fuse with a top column, else predict.
    pub mode: Option<Mode>,
    /// Keep the series of a time window for a plot: its start (s, the recording's time; `None`:
    /// the first row's) and length (s; infinite: to the end).
    pub plot_window: Option<(Option<f64>, f64)>,
}

impl ReplayOptions {
    /// Defaults: the given output name, the model and mode chosen from the columns.
    pub fn new(out_name: impl Into<String>) -> Self {
        Self {
            out_name: out_name.into(),
            model: None,
            mode: None,
            plot_window: None,
        }
    }
}

/// What [`replay`] returns.
#[derive(Debug, Clone)]
pub struct ReplayOutcome {
    /// The report.
    pub report: ReplayReport,
    /// Detected slip starts, reversals and sticks, in order, with the measured slip (m) at
    /// their detection.
    pub detected: Vec<(EventMark, f64)>,
    /// The plot series (when a window was asked for): measured and predicted top acceleration,
    /// the measured slip and the detected events.
    pub plot: Option<PlotData>,
}

/// The default CSV output: `<scene-stem>.replay.csv` next to the scene file.
pub fn default_out_path(scene: &ReplayScene) -> PathBuf {
    let stem = scene
        .source
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    scene.source.with_file_name(format!("{stem}.replay.csv"))
}

/// The model and mode for the recording's columns (`present`: table, base, top, displacement),
/// with the model's reason; a choice the columns cannot serve is an error.
pub fn choose(
    present: [bool; 4],
    model: Option<Model>,
    mode: Option<Mode>,
) -> Result<(Model, String, Mode)> {
    let base = present[Channel::BaseAccel.index()];
    let top = present[Channel::TopAccel.index()];
    let slip = present[Channel::Displacement.index()];
    let (model, why) = match model {
        Some(m) => (m, "chosen with --model".to_string()),
        None if base => (
            Model::StickSlip,
            "the recording has a base accelerometer (the slip-acceleration detector)".into(),
        ),
        None if slip => (
            Model::Rectangular,
            "the recording has a slip column but no base accelerometer (the displacement \
             reversal detector)"
                .into(),
        ),
        None => (
            Model::FixedBase,
            "the recording has neither a base accelerometer nor a slip column".into(),
        ),
    };
    if model == Model::StickSlip && !base {
        bail!("the stick-slip model's detector needs [recording] base_accel_column");
    }
    if model == Model::Rectangular && !slip {
        bail!("the rectangular model's detector needs [recording] slip_column");
    }
    let mode = match mode {
        Some(Mode::Fuse) if !top => {
            bail!("--mode fuse reads the top accelerometer: [recording] top_accel_column")
        }
        Some(m) => m,
        None if top => Mode::Fuse,
        None => Mode::Predict,
    };
    Ok((model, why, mode))
}

/// One row of [`CSV_HEADER`], without its newline: the time `t` (s), the `measured` channels
/// (table, base, top, displacement; empty cells for `None`) and the frame's prediction, event
/// and flags. `replay` and `monitor` both write their rows with it.
pub fn csv_row(t: f64, measured: &[Option<f32>; 4], frame: &Frame) -> String {
    let mut line = format!("{}", Num(t));
    for m in measured {
        line.push(',');
        if let Some(v) = m {
            line.push_str(&Num(*v).to_string());
        }
    }
    line.push_str(&format!(",{},", Num(frame.prediction)));
    if let Some(e) = frame.event {
        line.push_str(&format!("{},{}", e.kind.name(), e.age_samples));
    } else {
        line.push(',');
    }
    line.push_str(&format!(",{}", frame.flags));
    line
}

/// The running comparison of the prediction with the measured top acceleration (samples
/// neither missing nor saturated, both finite).
#[derive(Debug, Default)]
pub(crate) struct Compare {
    n: u64,
    sum_sq: f64,
    max_err: f64,
    peak_measured: f64,
    peak_predicted: f64,
}

impl Compare {
    pub(crate) fn add(&mut self, measured: f32, predicted: f32, fl: u8) {
        let (m, p) = (f64::from(measured), f64::from(predicted));
        if p.is_finite() {
            self.peak_predicted = self.peak_predicted.max(p.abs());
        }
        if fl & (flags::MISSING | flags::SATURATED) != 0 || !m.is_finite() || !p.is_finite() {
            return;
        }
        let e = (p - m).abs();
        self.n += 1;
        self.sum_sq += e * e;
        self.max_err = self.max_err.max(e);
        self.peak_measured = self.peak_measured.max(m.abs());
    }

    pub(crate) fn report(&self) -> VsMeasured {
        let rms = if self.n > 0 {
            (self.sum_sq / self.n as f64).sqrt()
        } else {
            0.0
        };
        VsMeasured {
            samples_compared: self.n,
            max_err_m_s2: self.max_err,
            rms_err_m_s2: rms,
            rms_err_pct_of_peak: if self.peak_measured > 0.0 {
                100.0 * rms / self.peak_measured
            } else {
                0.0
            },
            peak_measured_m_s2: self.peak_measured,
            peak_predicted_m_s2: self.peak_predicted,
        }
    }
}

/// The buffered CSV output.
struct Out<W: Write> {
    out: BufWriter<W>,
    name: String,
    rows: u64,
}

impl<W: Write> Out<W> {
    fn io(&self, e: std::io::Error) -> anyhow::Error {
        anyhow!(e).context(format!("writing {}", self.name))
    }

    fn header(&mut self) -> Result<()> {
        writeln!(self.out, "{CSV_HEADER}").map_err(|e| self.io(e))
    }

    fn row(&mut self, item: &Item, frame: &Frame) -> Result<()> {
        writeln!(self.out, "{}", csv_row(item.t, &item.measured, frame)).map_err(|e| self.io(e))?;
        self.rows += 1;
        Ok(())
    }

    fn flush(&mut self) -> Result<()> {
        self.out.flush().map_err(|e| self.io(e))
    }
}

/// Replay the scene's recording, streaming the CSV to `w` (flushed every [`FLUSH_EVERY_ROWS`]
/// rows, at the end and before returning any error). `stop` is checked at each flush: when set,
/// an [`Interrupted`] error is returned with the rows written. `progress` is told the bytes read
/// (of [`reader::Reader::size`]) at each flush.
pub fn replay<W: Write>(
    scene: &ReplayScene,
    w: W,
    opts: &ReplayOptions,
    stop: &AtomicBool,
    progress: &dyn Fn(u64, u64),
) -> Result<ReplayOutcome> {
    let label = scene.source.display().to_string();
    let mut rdr = Reader::open(&scene.recording)?;
    let (model, model_reason, mode) =
        choose(rdr.present(), opts.model, opts.mode).map_err(|e| anyhow!("{label}: {e}"))?;
    let specimen = scene.specimen(rdr.rate_hz);
    let plan =
        pipeline::plan_for_specimen(&specimen, model, mode).map_err(|e| anyhow!("{label}: {e}"))?;
    let mut pipe = pipeline::build(&plan, pipeline::Options::default())
        .map_err(|e| anyhow!("{label}: {e}"))?;

    let mut out = Out {
        out: BufWriter::with_capacity(1 << 16, w),
        name: opts.out_name.clone(),
        rows: 0,
    };
    out.header()?;
    let mut state = Loop {
        plot: opts.plot_window.map(|(from, len)| {
            let from = from.unwrap_or(rdr.t0);
            PlotCollector::new((from, from + len), rdr.rate_hz, rdr.estimated_samples())
        }),
        ..Loop::default()
    };
    let result = samples(
        &mut rdr,
        pipe.as_mut(),
        &mut out,
        &mut state,
        stop,
        progress,
    );
    let flushed = out.flush();
    result?;
    flushed?;

    let top = rdr.present()[Channel::TopAccel.index()];
    let count = |k: &str| state.kinds.iter().filter(|n| **n == k).count();
    let report = ReplayReport {
        scene: scene.name.clone(),
        scene_file: label,
        recording: rdr.name().to_string(),
        out: opts.out_name.clone(),
        samples: state.samples,
        flagged_samples: state.flagged,
        rows: rdr.counts.rows,
        bad_cells: rdr.counts.bad_cells,
        bad_times: rdr.counts.bad_times,
        gap_samples: rdr.counts.gap_samples,
        dropped_rows: rdr.counts.dropped_rows,
        rate_hz: rdr.rate_hz,
        rate_from: rdr.rate_from,
        start_s: scene.recording.start_s,
        model: model.name(),
        mode: mode.name(),
        model_reason,
        identified: Identified::of(&plan, &*pipe, model == Model::StickSlip),
        events: EventCounts {
            slip_starts: count("slip_start"),
            reversals: count("reversal"),
            sticks: count("stick"),
        },
        vs_measured_top: top.then(|| state.compare.report()),
        runtime_s: 0.0,
    };
    let plot = state
        .plot
        .map(|p| p.finish_measured(&state.detected, &scene.name));
    Ok(ReplayOutcome {
        report,
        detected: state.detected,
        plot,
    })
}

/// The sample loop's running state.
#[derive(Default)]
struct Loop {
    samples: u64,
    flagged: u64,
    compare: Compare,
    kinds: Vec<&'static str>,
    detected: Vec<(EventMark, f64)>,
    plot: Option<PlotCollector>,
}

/// Every sample of the recording through the pipeline into the CSV.
fn samples<W: Write>(
    rdr: &mut Reader,
    pipe: &mut dyn Step,
    out: &mut Out<W>,
    state: &mut Loop,
    stop: &AtomicBool,
    progress: &dyn Fn(u64, u64),
) -> Result<()> {
    let rate = rdr.rate_hz;
    let mut since_flush = 0u64;
    while let Some(item) = rdr.next_item()? {
        if since_flush == FLUSH_EVERY_ROWS {
            since_flush = 0;
            out.flush()?;
            progress(rdr.position(), rdr.size);
            if stop.load(Ordering::Relaxed) {
                return Err(Interrupted {
                    out: out.name.clone(),
                    rows: out.rows,
                }
                .into());
            }
        }
        let frame = pipe.step(&item.sample);
        state.samples += 1;
        since_flush += 1;
        if frame.flags & (flags::MISSING | flags::NOT_FINITE) != 0 {
            state.flagged += 1;
        }
        if let Some(m) = item.measured[Channel::TopAccel.index()] {
            state.compare.add(m, frame.prediction, frame.flags);
        }
        if let Some(e) = frame.event {
            state.kinds.push(e.kind.name());
            let slip = item.measured[Channel::Displacement.index()].map_or(0.0, f64::from);
            state.detected.push((
                EventMark {
                    time_s: item.t - f64::from(e.age_samples) / rate,
                    detected_at_s: item.t,
                    level: f64::from(e.level),
                    stick: e.is_stick(),
                },
                slip,
            ));
        }
        if let Some(p) = state.plot.as_mut() {
            let top = item.measured[Channel::TopAccel.index()];
            let slip = item.measured[Channel::Displacement.index()];
            p.push(
                item.t,
                &PlotPoint {
                    measured: top.map_or(f64::NAN, f64::from),
                    predicted: f64::from(frame.prediction),
                    truth: f64::NAN,
                    slip_measured: slip.map_or(f64::NAN, f64::from),
                    slip_truth: f64::NAN,
                },
            );
        }
        out.row(&item, &frame)?;
    }
    progress(rdr.size, rdr.size);
    Ok(())
}

/// Create the CSV file and replay into it. Errors name the file.
pub fn replay_to_file(
    scene: &ReplayScene,
    path: &Path,
    opts: &ReplayOptions,
    stop: &AtomicBool,
    progress: &dyn Fn(u64, u64),
) -> Result<ReplayOutcome> {
    let file = std::fs::File::create(path)
        .with_context(|| format!("cannot create the output file {}", path.display()))?;
    replay(scene, file, opts, stop, progress)
}
