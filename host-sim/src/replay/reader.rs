//! A recording's CSV, row by row ([`Reader`]): the header's columns, the sample rate, and each row
//! as the pipeline's [`Sample`] on the sample grid, with the missing-sample path for what the
//! file lacks.
//!
//! Rules (the README's `host-sim replay` section states them for users):
//!
//! * The columns are found by exact name in the header (line 1; surrounding spaces ignored); a
//!   named column that is not there is an error naming the file, line 1 and the column.
//! * The rate: `[recording] rate_hz` (row k at t_k = k / rate_hz), else from the time column: the
//!   median of the first [`RATE_STEPS`] steps, snapped to the nearest whole hertz when within
//!   1 ppm of it.
//! * The grid: t0 is the first row's time; a row at t goes to sample n = round((t − t0)·rate).
//!   A time step that skips samples (more than 1.5 samples long) inserts the skipped samples as
//!   `MISSING`; a row that lands on a sample already taken (a step shorter than half a sample) is
//!   dropped and counted. A time that does not increase is an error naming the line and column.
//! * A data cell that is empty, NaN or not a number is NaN in its channel: the pipeline flags the
//!   sample `NOT_FINITE` (an unreadable time cell: the row takes the next sample, `MISSING`).
//! * A channel without a column: the base accelerometer reads the table's (a base that never
//!   slides), the top accelerometer and the displacement 0 (never read by the model then).

use anyhow::{anyhow, bail, Result};
use ssvr_proto::{flags, Channel, Sample};
use ssvr_scene::{Recording, Timebase};
use std::collections::VecDeque;
use std::fs::File;
use std::io::BufReader;

/// Steps of the time column whose median sets the rate.
pub const RATE_STEPS: usize = 32;

/// One sample of the grid.
#[derive(Debug, Clone)]
pub struct Item {
    /// Its time (s): the row's own, or t0 + n / rate for an inserted missing sample.
    pub t: f64,
    /// The sample (channels in SI, flags of the acquisition).
    pub sample: Sample,
    /// Its channels as read (NaN where a cell was unreadable or the sample is missing); the
    /// absent channels are None.
    pub measured: [Option<f32>; 4],
}

/// A row as parsed (before it is placed on the grid).
struct Row {
    line: u64,
    /// The time cell: Some(finite) or None (unreadable); None for a rate-based file too.
    time: Option<f64>,
    channels: [Option<f32>; 4],
}

/// Counters of the rows read.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    /// Data rows read.
    pub rows: u64,
    /// Data cells (of the named channel columns) that were empty, NaN or not a number.
    pub bad_cells: u64,
    /// Rows whose time cell was unreadable.
    pub bad_times: u64,
    /// Samples inserted where a time step skipped them.
    pub gap_samples: u64,
    /// Rows dropped because their time step was shorter than half a sample.
    pub dropped_rows: u64,
}

/// The recording's CSV, streamed.
pub struct Reader {
    rdr: csv::Reader<BufReader<File>>,
    name: String,
    time_col: Option<(usize, String)>,
    cols: [Option<usize>; 4],
    factors: [f64; 4],
    /// The sample rate (Hz).
    pub rate_hz: f64,
    /// Where the rate came from: `rate_hz` or `time_column`.
    pub rate_from: &'static str,
    /// The first row's time (s).
    pub t0: f64,
    /// The file's size in bytes.
    pub size: u64,
    ahead: VecDeque<Row>,
    record: csv::StringRecord,
    /// The next sample index on the grid.
    next: u64,
    /// The last row's time and line (the time column's monotonicity).
    last_time: Option<(f64, u64)>,
    /// Samples of a gap still to emit before the row held.
    pending: Option<(u64, Row)>,
    /// The counters.
    pub counts: Counts,
}

fn position_line(r: &csv::StringRecord) -> u64 {
    r.position().map_or(0, |p| p.line())
}

impl Reader {
    /// Open the recording's file, read its header and set the rate. Errors name the file (and
    /// the line and column).
    pub fn open(rec: &Recording) -> Result<Reader> {
        let name = rec.file.display().to_string();
        let file =
            File::open(&rec.file).map_err(|e| anyhow!("{name}: cannot read the recording: {e}"))?;
        let size = file.metadata().map(|m| m.len()).unwrap_or(0);
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(true)
            .flexible(true)
            .trim(csv::Trim::All)
            .from_reader(BufReader::with_capacity(1 << 16, file));
        let headers = rdr
            .headers()
            .map_err(|e| anyhow!("{name}:1: cannot read the CSV header: {e}"))?
            .clone();
        let find = |key: &str, col: &str| -> Result<usize> {
            headers.iter().position(|h| h == col.trim()).ok_or_else(|| {
                let have: Vec<String> = headers.iter().map(|h| format!("`{h}`")).collect();
                anyhow!(
                    "{name}:1: no column `{col}` ([recording] {key}) in the header (columns: {})",
                    have.join(", ")
                )
            })
        };
        let time_col = match &rec.time {
            Timebase::Column(c) => Some((find("time_column", c)?, c.clone())),
            Timebase::Rate(_) => None,
        };
        let opt = |key: &str, c: &Option<String>| c.as_ref().map(|c| find(key, c)).transpose();
        let mut cols = [None; 4];
        cols[Channel::TableAccel.index()] =
            Some(find("table_accel_column", &rec.table_accel_column)?);
        cols[Channel::BaseAccel.index()] = opt("base_accel_column", &rec.base_accel_column)?;
        cols[Channel::TopAccel.index()] = opt("top_accel_column", &rec.top_accel_column)?;
        cols[Channel::Displacement.index()] = opt("slip_column", &rec.slip_column)?;
        let a = rec.accel_units.factor();
        let mut factors = [a; 4];
        factors[Channel::Displacement.index()] = rec.slip_units.factor();
        let mut r = Reader {
            rdr,
            name,
            time_col,
            cols,
            factors,
            rate_hz: f64::NAN,
            rate_from: "rate_hz",
            t0: 0.0,
            size,
            ahead: VecDeque::new(),
            record: csv::StringRecord::new(),
            next: 0,
            last_time: None,
            pending: None,
            counts: Counts::default(),
        };
        match rec.time {
            Timebase::Rate(rate) => r.rate_hz = rate,
            Timebase::Column(_) => r.rate_from_times()?,
        }
        Ok(r)
    }

    /// The file's name in messages.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Bytes read so far (for a progress bar).
    pub fn position(&self) -> u64 {
        self.rdr.position().byte()
    }

    /// An estimate of the samples in the file (for a plot's decimation): its size over the
    /// bytes per row of the rows read so far (40 bytes a row before any).
    pub fn estimated_samples(&self) -> u64 {
        let (pos, rows) = (self.position(), self.counts.rows);
        if rows > 0 && pos > 0 {
            (self.size as f64 * rows as f64 / pos as f64) as u64
        } else {
            self.size / 40
        }
    }

    /// Which channels have a column.
    pub fn present(&self) -> [bool; 4] {
        self.cols.map(|c| c.is_some())
    }

    /// Read ahead the first rows and set t0 and the rate from the time column.
    fn rate_from_times(&mut self) -> Result<()> {
        self.rate_from = "time_column";
        let mut steps = Vec::with_capacity(RATE_STEPS);
        let mut prev: Option<f64> = None;
        while steps.len() < RATE_STEPS {
            let Some(row) = self.parse_row()? else {
                break;
            };
            if self.ahead.is_empty() {
                let Some(t) = row.time else {
                    bail!(
                        "{}:{}: the first row's time (column `{}`) is not a number",
                        self.name,
                        row.line,
                        self.time_name()
                    );
                };
                self.t0 = t;
            }
            if let (Some(a), Some(b)) = (prev, row.time) {
                steps.push(b - a);
            }
            prev = row.time;
            self.ahead.push_back(row);
        }
        if steps.is_empty() {
            bail!(
                "{}: the time column `{}` needs at least two rows with times to set the sample \
                 rate (or give [recording] rate_hz)",
                self.name,
                self.time_name()
            );
        }
        steps.sort_by(f64::total_cmp);
        let step = steps[steps.len() / 2];
        let rate = 1.0 / step;
        let whole = rate.round();
        self.rate_hz = if (rate - whole).abs() <= 1e-6 * rate {
            whole
        } else {
            rate
        };
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            bail!(
                "{}: the time column `{}` gives no sample rate (median step {step} s)",
                self.name,
                self.time_name()
            );
        }
        Ok(())
    }

    fn time_name(&self) -> &str {
        self.time_col.as_ref().map_or("", |(_, n)| n.as_str())
    }

    /// The next row of the file, parsed and checked (increasing time), or None at the end.
    fn parse_row(&mut self) -> Result<Option<Row>> {
        let more = self.rdr.read_record(&mut self.record).map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            anyhow!("{}:{line}: cannot read the CSV: {e}", self.name)
        })?;
        if !more {
            return Ok(None);
        }
        // The csv crate's line is one short after CRLF line ends (a Windows logger's); the
        // header plus the rows read is right unless blank lines were skipped: the larger.
        let line = position_line(&self.record).max(self.counts.rows + 2);
        self.counts.rows += 1;
        let time = match &self.time_col {
            Some((i, _)) => {
                let t = self
                    .record
                    .get(*i)
                    .and_then(|c| c.parse::<f64>().ok())
                    .filter(|t| t.is_finite());
                if t.is_none() {
                    self.counts.bad_times += 1;
                }
                t
            }
            None => None,
        };
        if let Some(t) = time {
            if let Some((last, last_line)) = self.last_time {
                if t <= last {
                    bail!(
                        "{}:{line}: column `{}`: the time {t} s does not increase (line \
                         {last_line}: {last} s)",
                        self.name,
                        self.time_name()
                    );
                }
            }
            self.last_time = Some((t, line));
        }
        let mut channels = [None; 4];
        for (c, (col, factor)) in channels.iter_mut().zip(self.cols.iter().zip(self.factors)) {
            if let Some(i) = col {
                let cell = self.record.get(*i).unwrap_or("");
                let v = if factor == 1.0 {
                    // Exact for values written as f32 (a `run` CSV): no double rounding.
                    cell.parse::<f32>().ok()
                } else {
                    cell.parse::<f64>().ok().map(|v| (v * factor) as f32)
                };
                let v = v.filter(|v| v.is_finite());
                if v.is_none() {
                    self.counts.bad_cells += 1;
                }
                *c = Some(v.unwrap_or(f32::NAN));
            }
        }
        Ok(Some(Row {
            line,
            time,
            channels,
        }))
    }

    /// The sample of the grid for `row` (taken from the file) at index `n`.
    fn item_of(&self, row: &Row, n: u64, missing: bool) -> Item {
        let mut ch = row.channels;
        // The absent channels: the base reads the table, top and displacement 0.
        let table = ch[Channel::TableAccel.index()];
        let mut channels = [0.0f32; 4];
        for (i, c) in channels.iter_mut().enumerate() {
            *c = ch[i].unwrap_or(0.0);
        }
        if ch[Channel::BaseAccel.index()].is_none() {
            channels[Channel::BaseAccel.index()] = table.unwrap_or(0.0);
        }
        let mut fl = 0;
        if missing {
            fl |= flags::MISSING;
            for c in ch.iter_mut().flatten() {
                *c = f32::NAN;
            }
            channels = [f32::NAN; 4];
        }
        Item {
            t: row.time.unwrap_or_else(|| self.grid_time(n)),
            sample: Sample {
                channels,
                flags: fl,
                reversal: None,
            },
            measured: ch,
        }
    }

    fn grid_time(&self, n: u64) -> f64 {
        self.t0 + n as f64 / self.rate_hz
    }

    /// The next sample of the grid, or None at the end of the file.
    pub fn next_item(&mut self) -> Result<Option<Item>> {
        loop {
            if let Some((n, row)) = self.pending.take() {
                if self.next < n {
                    let gap = Row {
                        line: row.line,
                        time: None,
                        channels: row.channels.map(|c| c.map(|_| f32::NAN)),
                    };
                    let item = self.item_of(&gap, self.next, true);
                    self.next += 1;
                    self.counts.gap_samples += 1;
                    self.pending = Some((n, row));
                    return Ok(Some(item));
                }
                let item = self.item_of(&row, n, false);
                self.next = n + 1;
                return Ok(Some(item));
            }
            let row = match self.ahead.pop_front() {
                Some(r) => r,
                None => match self.parse_row()? {
                    Some(r) => r,
                    None => return Ok(None),
                },
            };
            if self.time_col.is_none() {
                // Rate-based: row k is sample k.
                let item = self.item_of(&row, self.next, false);
                self.next += 1;
                return Ok(Some(item));
            }
            let Some(t) = row.time else {
                // An unreadable time: the row takes the next sample, missing.
                let n = self.next;
                let mut item = self.item_of(&row, n, true);
                item.t = self.grid_time(n);
                self.next += 1;
                return Ok(Some(item));
            };
            let slot = ((t - self.t0) * self.rate_hz).round();
            if !(0.0..9.0e15).contains(&slot) {
                bail!(
                    "{}:{}: column `{}`: the time {t} s is off the recording's grid",
                    self.name,
                    row.line,
                    self.time_name()
                );
            }
            let n = slot as u64;
            if n < self.next {
                self.counts.dropped_rows += 1;
                continue;
            }
            self.pending = Some((n, row));
        }
    }
}
