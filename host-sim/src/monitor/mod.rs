//! `host-sim monitor`: the firmware's raw defmt stream (probe-rs RTT, a serial dump, QEMU's
//! stdout) decoded as it arrives into `replay`'s CSV ([`crate::replay::CSV_HEADER`], rows by
//! [`crate::replay::csv_row`]).
//!
//! The input is read in chunks and fed to `defmt-decoder`'s stream decoder with the ELF's
//! interning table; each message is read by its typed fields ([`decode::message`]), each
//! `sample` becomes a `Frame` ([`decode::frame`]) and a row: `t_s` = the frame's index / the
//! rate of the firmware's `plan` message (or `--rate`), the measured channels the frame echoes,
//! its prediction, event and flags. Frames that arrive before the rate is known are held (up to
//! [`MAX_PENDING`]). The CSV is flushed every [`FLUSH_EVERY_ROWS`] rows and at the end.
//!
//! Transport damage is counted, reported once per kind ([`Note::Problem`]) and skipped: a
//! malformed defmt frame (the rzCOBS encoding resyncs at the next frame boundary), a `sample`
//! message without its typed fields, a frame whose index is neither the next one nor continued
//! by the following frame (a damaged index, dropped), indices skipped (frames lost) or going
//! back (a reset, kept), and a stream that ends inside a frame. A frame whose bytes were changed but still decode cannot be told
//! from a good one (defmt frames carry no checksum).

use crate::qemu::decode::{self, Message};
use crate::replay::{csv_row, Compare, EventCounts, VsMeasured};
use crate::run::{EventMark, PlotCollector, PlotData, PlotPoint, FLUSH_EVERY_ROWS};
use anyhow::{anyhow, bail, Result};
use serde::Serialize;
use ssvr_proto::stream::{FRAME, PLAN};
use ssvr_proto::{EventKind, Frame};
use std::collections::BTreeSet;
use std::io::{BufWriter, Read, Write};
use std::sync::atomic::{AtomicBool, Ordering};

/// Frames held while no rate is known (no `plan` message yet, no `--rate`); more is an error.
pub const MAX_PENDING: usize = 1 << 16;

/// Options of [`monitor`].
#[derive(Debug, Clone)]
pub struct MonitorOptions {
    /// Name of the input in messages and in the report.
    pub input_name: String,
    /// Name of the CSV output in messages and in the report.
    pub out_name: String,
    /// The sample rate (Hz) when given (`--rate`): used instead of the `plan` message's.
    pub rate_hz: Option<f64>,
    /// Keep the measured and predicted top acceleration for a plot.
    pub plot: bool,
}

/// What [`monitor`] counted (the live line and the final summary).
#[derive(Debug, Clone, Default, Serialize)]
pub struct MonitorReport {
    /// The input.
    pub input: String,
    /// The CSV output.
    pub out: String,
    /// Bytes read.
    pub bytes: u64,
    /// Rows written (one per good `sample` frame).
    pub samples: u64,
    /// The sample rate (Hz), once known.
    pub rate_hz: Option<f64>,
    /// Where it came from: `plan` (the firmware's message) or `--rate`.
    pub rate_from: Option<&'static str>,
    /// The plan digest the firmware reported.
    pub plan_digest: Option<u32>,
    /// Detected events.
    pub events: EventCounts,
    /// The firmware's last identified μ (its `mu` message; none for the rectangular model).
    pub mu_estimate: Option<f64>,
    /// Its standard deviation.
    pub mu_std: Option<f64>,
    /// The natural frequency (Hz) the firmware's model uses: identified online in fuse mode (its
    /// `osc` message; none for a model that does not identify it).
    pub natural_frequency_hz: Option<f64>,
    /// The damping ratio it uses.
    pub damping_ratio: Option<f64>,
    /// The velocity-dependent friction law the firmware's model uses (its `law` message:
    /// μ_slow, μ_fast, a in s/m; none for Coulomb friction).
    pub friction_law: Option<[f64; 3]>,
    /// The prediction against the top accelerometer the frames echo.
    pub vs_measured_top: Option<VsMeasured>,
    /// defmt frames that could not be decoded (corrupted in transit), skipped.
    pub malformed_frames: u64,
    /// `sample` messages without their typed fields, skipped.
    pub bad_samples: u64,
    /// Frame indices skipped by the stream (frames lost before the decoder).
    pub lost_frames: u64,
    /// Frames whose index is neither the next one nor continued by the frame after them (a
    /// damaged index), dropped.
    pub damaged_frames: u64,
    /// Frames whose index goes back and is continued by the next frame (a firmware reset),
    /// written.
    pub index_back: u64,
    /// The stream ended inside a frame (its bytes are not decoded).
    pub truncated_end: bool,
    /// Messages at level `warn` or `error` from the firmware.
    pub firmware_errors: u64,
}

/// What [`monitor`] tells its caller while it runs.
#[derive(Debug)]
pub enum Note<'a> {
    /// The counters, at each flush and at the end (the live line).
    Live(&'a MonitorReport),
    /// A problem seen for the first time (a kind of damage), or a firmware warning or error.
    Problem(String),
}

/// What [`monitor`] returns.
#[derive(Debug, Clone)]
pub struct MonitorOutcome {
    /// The counters.
    pub report: MonitorReport,
    /// The plot's series when a plot was asked for.
    pub plot: Option<PlotSeries>,
}

/// What a plot of the monitored run needs: every row's time, measured and predicted top
/// acceleration (16 bytes per sample, kept in memory), and the detected events.
#[derive(Debug, Clone, Default)]
pub struct PlotSeries {
    /// (t (s), measured top, predicted top) of every row.
    pub points: Vec<(f64, f32, f32)>,
    /// The detected events, with the measured slip (m) at their detection.
    pub detected: Vec<(EventMark, f64)>,
}

/// The running state of [`monitor`].
struct State<'n, W: Write> {
    report: MonitorReport,
    out: BufWriter<W>,
    since_flush: u64,
    pending: Vec<Frame>,
    last_index: Option<u32>,
    held: Option<Frame>,
    compare: Compare,
    seen: BTreeSet<&'static str>,
    plot: Option<PlotSeries>,
    note: &'n mut dyn FnMut(Note<'_>),
}

impl<W: Write> State<'_, W> {
    fn problem(&mut self, kind: &'static str, text: String) {
        if self.seen.insert(kind) {
            (self.note)(Note::Problem(format!(
                "{text} (further ones are counted, not shown)"
            )));
        }
    }

    fn io(&self, e: std::io::Error) -> anyhow::Error {
        anyhow!(e).context(format!("writing {}", self.report.out))
    }

    fn flush(&mut self) -> Result<()> {
        self.out.flush().map_err(|e| self.io(e))?;
        self.report.vs_measured_top = Some(self.compare.report());
        (self.note)(Note::Live(&self.report));
        Ok(())
    }

    fn message(&mut self, m: &Message) -> Result<()> {
        if m.name == FRAME {
            match decode::frame(m) {
                Some(f) => match self.report.rate_hz {
                    Some(rate) => self.frame(&f, rate)?,
                    None if self.pending.len() < MAX_PENDING => self.pending.push(f),
                    None => bail!(
                        "{}: no `plan` message in the first {MAX_PENDING} frames: give the \
                         sample rate with --rate",
                        self.report.input
                    ),
                },
                None => {
                    self.report.bad_samples += 1;
                    let text = format!("a `sample` message without its fields: {}", m.text);
                    self.problem("bad sample", text);
                }
            }
        } else if m.name == PLAN {
            self.report.plan_digest = m.u32("digest");
            match (self.report.rate_hz, m.f64("rate_hz")) {
                (None, Some(r)) if r.is_finite() && r > 0.0 => {
                    self.report.rate_hz = Some(r);
                    self.report.rate_from = Some("plan");
                    for f in std::mem::take(&mut self.pending) {
                        self.frame(&f, r)?;
                    }
                }
                (Some(given), Some(r)) if given != r => {
                    let text = format!("the firmware's plan runs at {r} Hz, --rate says {given}");
                    self.problem("rate", text);
                }
                _ => {}
            }
        } else if m.name == "mu" {
            if let (Some(mu), Some(sd)) = (m.f64("estimate"), m.f64("std")) {
                self.report.mu_estimate = Some(mu);
                self.report.mu_std = Some(sd);
            }
        } else if m.name == "law" {
            if let (Some(a), Some(b), Some(c)) =
                (m.f64("mu_slow"), m.f64("mu_fast"), m.f64("rate_s_m"))
            {
                self.report.friction_law = Some([a, b, c]);
            }
        } else if m.name == "osc" {
            if let (Some(f), Some(xi)) = (m.f64("f_hz"), m.f64("xi")) {
                self.report.natural_frequency_hz = Some(f);
                self.report.damping_ratio = Some(xi);
            }
        } else if matches!(m.level.as_deref(), Some("warn" | "error")) {
            self.report.firmware_errors += 1;
            (self.note)(Note::Problem(format!("firmware: {m}")));
        }
        Ok(())
    }

    /// A frame in index order: one whose index is not the next is held until the frame after
    /// it tells a real jump (that frame continues from it: frames were lost) from a damaged
    /// index (it continues from the last written frame: the held one is dropped).
    fn frame(&mut self, f: &Frame, rate: f64) -> Result<()> {
        if let Some(held) = self.held.take() {
            if u64::from(f.index) == u64::from(held.index) + 1 {
                self.row(&held, rate)?;
            } else {
                self.report.damaged_frames += 1;
                let last = self.last_index.map_or(-1, i64::from);
                let text = format!(
                    "a frame with index {} between {last} and {} (a damaged index), dropped",
                    held.index, f.index
                );
                self.problem("damaged", text);
                // It took the slot between them: not counted again as lost.
                if i64::from(f.index) == last + 2 {
                    self.last_index = u32::try_from(last + 1).ok();
                }
            }
        }
        match self.last_index {
            Some(last) if u64::from(f.index) != u64::from(last) + 1 => self.held = Some(*f),
            _ => self.row(f, rate)?,
        }
        Ok(())
    }

    /// Write a frame's row.
    fn row(&mut self, f: &Frame, rate: f64) -> Result<()> {
        if let Some(last) = self.last_index {
            let (i, l) = (u64::from(f.index), u64::from(last));
            if i > l + 1 {
                self.report.lost_frames += i - l - 1;
                let text = format!("frames lost: index {last} then {}", f.index);
                self.problem("lost", text);
            } else if i <= l {
                self.report.index_back += 1;
                let text = format!("index {} after {last} (a reset?)", f.index);
                self.problem("back", text);
            }
        }
        self.last_index = Some(f.index);
        let t = f64::from(f.index) / rate;
        let [_, _, top, _] = f.channels;
        self.compare.add(top, f.prediction, f.flags);
        if let Some(e) = f.event {
            let n = &mut self.report.events;
            match e.kind {
                EventKind::SlipStart => n.slip_starts += 1,
                EventKind::Reversal => n.reversals += 1,
                EventKind::Stick => n.sticks += 1,
                EventKind::Log => {}
            }
        }
        if let Some(p) = self.plot.as_mut() {
            p.points.push((t, top, f.prediction));
            if let Some(e) = f.event {
                let mark = EventMark {
                    time_s: t - f64::from(e.age_samples) / rate,
                    detected_at_s: t,
                    level: f64::from(e.level),
                    stick: e.is_stick(),
                };
                p.detected.push((mark, f64::from(f.channels[3])));
            }
        }
        let line = csv_row(t, &f.channels.map(Some), f);
        writeln!(self.out, "{line}").map_err(|e| self.io(e))?;
        self.report.samples += 1;
        self.since_flush += 1;
        if self.since_flush == FLUSH_EVERY_ROWS {
            self.since_flush = 0;
            self.flush()?;
        }
        Ok(())
    }
}

/// Decode the defmt stream `input` with `table` (the firmware ELF's) into the CSV `w`, until
/// the end of the input or `stop` (checked after each chunk read). `note` gets the live
/// counters and the problems. Errors: reading or writing fails, the encoding is raw and a frame
/// is malformed (it cannot resync), or no rate is known (module doc).
pub fn monitor<R: Read, W: Write>(
    table: &defmt_decoder::Table,
    mut input: R,
    w: W,
    opts: &MonitorOptions,
    stop: &AtomicBool,
    note: &mut dyn FnMut(Note<'_>),
) -> Result<MonitorOutcome> {
    let mut st = State {
        report: MonitorReport {
            input: opts.input_name.clone(),
            out: opts.out_name.clone(),
            rate_hz: opts.rate_hz,
            rate_from: opts.rate_hz.map(|_| "--rate"),
            ..MonitorReport::default()
        },
        out: BufWriter::with_capacity(1 << 16, w),
        since_flush: 0,
        pending: Vec::new(),
        last_index: None,
        held: None,
        compare: Compare::default(),
        seen: BTreeSet::new(),
        plot: opts.plot.then(PlotSeries::default),
        note,
    };
    writeln!(st.out, "{}", crate::replay::CSV_HEADER).map_err(|e| st.io(e))?;
    let recover = table.encoding().can_recover();
    let mut decoder = table.new_stream_decoder();
    let mut buf = vec![0u8; 1 << 16];
    let mut last_byte = 0u8;
    loop {
        let n = match input.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(anyhow!(e).context(format!("reading {}", opts.input_name))),
        };
        let data = buf.get(..n).unwrap_or_default();
        last_byte = data.last().copied().unwrap_or(last_byte);
        // Small pieces: the stream decoder drains its buffer from the front (see `decode`).
        for chunk in data.chunks(4096) {
            decoder.received(chunk);
            loop {
                let m = match decoder.decode() {
                    Ok(f) => decode::message(&f),
                    Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
                    Err(defmt_decoder::DecodeError::Malformed) if recover => {
                        st.report.malformed_frames += 1;
                        let text = format!(
                            "a malformed defmt frame near byte {} of {} (after {} rows), skipped",
                            st.report.bytes, opts.input_name, st.report.samples
                        );
                        st.problem("malformed", text);
                        continue;
                    }
                    Err(defmt_decoder::DecodeError::Malformed) => bail!(
                        "{}: a malformed defmt frame after {} rows; the ELF's defmt encoding \
                         is raw, which cannot resync",
                        opts.input_name,
                        st.report.samples
                    ),
                };
                st.message(&m)?;
            }
            st.report.bytes += chunk.len() as u64;
        }
        if stop.load(Ordering::Relaxed) {
            break;
        }
    }
    // defmt's rzCOBS frames end with a zero byte: anything else is a frame cut off.
    if recover && last_byte != 0 {
        st.report.truncated_end = true;
        let text = format!("{} ends inside a frame (not decoded)", opts.input_name);
        st.problem("truncated", text);
    }
    if let (Some(f), Some(rate)) = (st.held.take(), st.report.rate_hz) {
        st.row(&f, rate)?;
    }
    if st.report.rate_hz.is_none() && !st.pending.is_empty() {
        st.out.flush().map_err(|e| st.io(e))?;
        bail!(
            "{}: {} frames but no `plan` message: give the sample rate with --rate",
            opts.input_name,
            st.pending.len()
        );
    }
    st.flush()?;
    Ok(MonitorOutcome {
        report: st.report,
        plot: st.plot,
    })
}

/// The live line: samples, events, μ, the prediction against the measured top.
pub fn live_line(r: &MonitorReport) -> String {
    let t = r.rate_hz.map_or_else(String::new, |rate| {
        format!(" ({:.1} s)", r.samples as f64 / rate)
    });
    let e = &r.events;
    let mu = match r.friction_law {
        Some([slow, fast, a]) => format!("{slow:.4} -> {fast:.4} (a {a:.1} s/m)"),
        None => r
            .mu_estimate
            .map_or_else(|| "-".to_string(), |m| format!("{m:.5}")),
    };
    let f = r
        .natural_frequency_hz
        .map_or_else(|| "-".to_string(), |f| format!("{f:.4} Hz"));
    let vs = r.vs_measured_top.as_ref().map_or_else(
        || "-".to_string(),
        |v| {
            format!(
                "{:.4} m/s² ({:.2} % of peak)",
                v.rms_err_m_s2, v.rms_err_pct_of_peak
            )
        },
    );
    let lost = r.malformed_frames + r.bad_samples + r.damaged_frames + r.lost_frames;
    format!(
        "monitor: {} samples{t}, events {}/{}/{} (slip starts/reversals/sticks), mu {mu}, \
         f {f}, pred-vs-top rms {vs}, lost {lost}",
        r.samples, e.slip_starts, e.reversals, e.sticks
    )
}

/// The final summary (several lines).
pub fn summary_text(r: &MonitorReport) -> String {
    let mut s = format!("{}\n", live_line(r));
    let rate = match (r.rate_hz, r.rate_from) {
        (Some(h), Some(from)) => format!("{h} Hz (from {from})"),
        _ => "unknown".to_string(),
    };
    s += &format!(
        "  input {} ({} bytes) -> {}; rate {rate}; plan digest {}\n",
        r.input,
        r.bytes,
        r.out,
        r.plan_digest
            .map_or_else(|| "-".to_string(), |d| format!("{d:#010x}"))
    );
    s += &format!(
        "  transport: {} malformed frames, {} sample messages without fields, {} with a damaged \
         index, {} frames lost (index gaps), {} indices going back{}; {} firmware \
         warnings/errors\n",
        r.malformed_frames,
        r.bad_samples,
        r.damaged_frames,
        r.lost_frames,
        r.index_back,
        if r.truncated_end {
            ", the stream ends inside a frame"
        } else {
            ""
        },
        r.firmware_errors
    );
    s
}

impl PlotSeries {
    /// The figure's data (`replay`'s figure: measured and predicted top acceleration, the
    /// detected events; no truth, no slip) over the whole run.
    pub fn plot_data(&self, rate_hz: f64, name: &str) -> PlotData {
        let from = self.points.first().map_or(0.0, |p| p.0);
        let to = self.points.last().map_or(0.0, |p| p.0);
        let samples = (to * rate_hz).round().max(0.0) as u64 + 1;
        let mut c = PlotCollector::new((from, to), rate_hz, samples);
        for &(t, m, p) in &self.points {
            c.push(
                t,
                &PlotPoint {
                    measured: f64::from(m),
                    predicted: f64::from(p),
                    truth: f64::NAN,
                    slip_measured: f64::NAN,
                    slip_truth: f64::NAN,
                },
            );
        }
        c.finish_measured(&self.detected, name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The live line shows the friction law in use when the firmware reports one, else μ̂.
    #[test]
    fn live_line_shows_the_law_or_mu() {
        let mut r = MonitorReport {
            mu_estimate: Some(0.167_97),
            ..MonitorReport::default()
        };
        assert!(live_line(&r).contains("mu 0.16797,"), "{}", live_line(&r));
        r.friction_law = Some([0.1198, 0.19996, 30.04]);
        let line = live_line(&r);
        assert!(line.contains("mu 0.1198 -> 0.2000 (a 30.0 s/m)"), "{line}");
    }
}
