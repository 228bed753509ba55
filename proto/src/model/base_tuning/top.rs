//! Fuse mode: the top accelerometer's offset and gain relative to the base's, from the momentum
//! balance's fit over the sliding blocks (the module's last paragraph), and before it, the top
//! offset from the run's first samples ([`OpenStart`]). Predict mode without a rest: the table
//! accelerometer's offset from the same first samples against the planned input
//! ([`BaseTuning::note_table_start`]).

use super::{BaseTuning, MAX_GAIN_ERROR};
use crate::table_start::{start_offset, LineFit, MeasuredStart};
use ssvr_core::oscillator_id::GainEstimate;
use ssvr_core::sliding_id::SlidingEstimate;
use ssvr_core::StructureParams;

/// The bias of the top accelerometer's gain from the oscillator identifier's fit
/// ([`BaseTuning::adopt_stuck_gain`]), added to its σ (in quadrature): its discretisation leaves
/// it ~1.3e-3 low at 7 Hz and 10 kHz (the `core` test, 6σ after 4 s).
pub const STUCK_GAIN_BIAS: f64 = 1.5e-3;
/// Standard deviations (with the bias) by which the fit's gain must differ from the one in use:
/// its σ leaves out the noise in its regressors (the base's filtered signals) and the slides'
/// discretisation too. On the stick-slip hard cases (`host-sim/tests/run.rs`: relative motion
/// undamped; accelerometer noise 0.2 m/s²) a right gain came out 1.0 % and 1.6 % off, at 5.5σ
/// and 3.9σ of its own σ (4.3σ and 3.6σ with the bias), and with 3σ was taken (μ̂ 0.7 % off),
/// the momentum balance's, better known, then taken back and forth.
pub const STUCK_GAIN_SIGMAS: f64 = 5.0;

/// The open-loop start's length in radians of the prior's p: the model's response to a table
/// offset b_t from rest, b_t·(2ξ·p·t + (½ − 2ξ²)(p·t)² + …), has grown to ~1.5e-2·b_t by its end
/// (ξ = 0.05), and its mean over the start to ~6e-3·b_t (the damping's share the larger: the
/// pipeline measured 6.05e-3·b_t in the top offset on the default scene).
pub const OPEN_START_RAD: f64 = 0.1;
/// The longest open-loop start in radians of the prior's p: where [`OPEN_START_RAD`] holds fewer
/// than [`MIN_OPEN_START`] samples (below ~4.4 kHz at 7 Hz) but this holds them (from ~0.9 kHz
/// on), the start is [`MIN_OPEN_START`] samples long, and the model's response to a table offset
/// (up to b_t·(p·t)²/2 ≈ 0.1·b_t at 1 kHz) is fitted with the top's offset (`OpenStart`'s
/// curved start).
pub const MAX_OPEN_START_RAD: f64 = 0.5;

/// Fewest samples of an open-loop start: with fewer, σ comes from a handful of differences and
/// pure noise was taken for an offset (a scratch test: 21 % of starts at 1 kHz with 2 samples,
/// 6 % at 2 kHz with 4), and the halves' test cannot see a trend. At 7 Hz: from 4.4 kHz on.
pub const MIN_OPEN_START: u32 = 10;

/// How far apart (in their standard deviations) the means of the open-loop start's two halves
/// may be for a start at rest: the model's response to a table offset b_t separates them by
/// ~2.5e-3·b_t (1.2e-3 m/s² at 0.05 g), with the prior's f 8 % off a little more; 3σ rejected
/// the start of the scorecard's combined row (7.0e-3 apart, 3σ = 6.8e-3), while a steady
/// oscillation of 1 m/s² at 5.6 Hz is 4e-2 apart.
pub const LEVEL_SIGMAS: f64 = 5.0;

/// Fuse mode without a rest: the top accelerometer's offset from the run's first samples.
/// While the base sticks, a constant offset b_t of the table accelerometer is a constant table
/// acceleration for the fixed-base dynamics (the model's top acceleration comes out b_t high once
/// its transient has decayed) and the top accelerometer reads b_top high: after the transient
/// only their difference is observable, until the sliding phases separate them (El Centro sticks
/// for 2 s). The transient separates them: the specimen starts at rest, as the model does, and
/// over the first p·t ≤ [`OPEN_START_RAD`] the model's response to b_t is below ~1.5e-2·b_t,
/// while the top accelerometer reads b_top from the first sample. So the model runs open loop
/// (no stuck-phase observer: its prediction does not follow the measurement) for those samples,
/// and the mean of measured − predicted is b_top, to the sensor noise over √n
/// (n = 22 at 7 Hz and 10 kHz). The model's error in f or ξ is a fraction (p·t)² of the top's
/// small response then. A start that is not at rest shows a trend in the residual and gives no
/// offset ([`LEVEL_SIGMAS`]). Without a rest and with a planned start, either mode runs the
/// same start on the measured table acceleration against the planned input's line, for a table
/// any lag late, which gives the table's offset ([`BaseTuning::note_table_start`],
/// [`crate::table_start`]); without one (a replay), fuse mode leaves the table's offset to the
/// stuck-phase observer (κ·b_t ≈ b_t/35 stays) until the sliding phases separate the two.
#[derive(Debug, Clone)]
pub(super) struct OpenStart {
    /// Samples of the start still to come (0: none, or done); its length.
    left: u32,
    len: u32,
    /// The samples whose statistics are kept (the first `cap`: all for the top's start, at
    /// most `table_start::LAGS − 1` for the table's), and the index of its second half's first.
    cap: u32,
    cap_half: u32,
    /// Σ r (r = measured − predicted; predict mode's table start: the measured table) and its
    /// count, over the start and its first half; Σ k, Σ k², Σ k·r (k: the sample's index in
    /// the start) for the table's line, Σ k over the first half.
    sum: f32,
    n: u32,
    sum_first: f32,
    n_first: u32,
    sum_k_first: f32,
    sum_k: f32,
    sum_k2: f32,
    sum_kr: f32,
    /// A curved start's (longer than [`OPEN_START_RAD`]; 0 for the others): the model's response
    /// to a unit table offset at sample k from rest, 2ξθ·k + (½ − 2ξ²)θ²·k² + O(θ³k³) (θ = p/rate,
    /// the prior's p and ξ), as `curve`·(k² + `lin`·k); Σ k³, Σ k⁴, Σ k²·r, Σ r², and Σ k² over
    /// the first half.
    curve: f64,
    lin: f64,
    sum_k3: f32,
    sum_k4: f32,
    sum_r2: f32,
    sum_k2r: f32,
    sum_k2_first: f32,
    /// Σ of the consecutive differences of r and of their squares (the noise, free of a
    /// smooth trend), their count, and the last r.
    sum_d: f32,
    sum_d2: f32,
    n_d: u32,
    last: f32,
}

impl OpenStart {
    /// The start of the prior `params` at `rate` (`on`: fuse mode without a rest, or predict
    /// mode's table start); at least [`MIN_OPEN_START`] samples, or none.
    pub(super) fn new(on: bool, params: &StructureParams, rate: f64) -> Self {
        let left = if on {
            open_start_samples(params, rate)
        } else {
            0
        };
        let theta = 2.0 * core::f64::consts::PI * params.natural_frequency_hz / rate;
        let curved = left as f64 * theta > OPEN_START_RAD;
        let xi = params.damping_ratio;
        let quad = theta * theta * (0.5 - 2.0 * xi * xi);
        let curved = curved && quad > 0.0;
        Self {
            left,
            len: left,
            cap: left,
            cap_half: left - left / 2,
            curve: if curved { quad } else { 0.0 },
            lin: if curved { 2.0 * xi * theta / quad } else { 0.0 },
            sum_k3: 0.0,
            sum_k4: 0.0,
            sum_r2: 0.0,
            sum_k2r: 0.0,
            sum_k2_first: 0.0,
            sum: 0.0,
            n: 0,
            sum_first: 0.0,
            n_first: 0,
            sum_k_first: 0.0,
            sum_k: 0.0,
            sum_k2: 0.0,
            sum_kr: 0.0,
            sum_d: 0.0,
            sum_d2: 0.0,
            n_d: 0,
            last: f32::NAN,
        }
    }

    /// Keep the statistics of the start's first `max` samples only (the table's start: its
    /// lag is tried whole sample by whole sample over them; a table later than them is at rest
    /// there, reading its offset). The start itself, the model's open loop, keeps its length.
    pub(super) fn keep_first(&mut self, max: u32) {
        self.cap = self.len.min(max);
        self.cap_half = self.cap - self.cap / 2;
    }

    /// No start (none to come; [`Self::arm`] brings it back before its first sample).
    pub(super) fn off(&mut self) {
        self.left = 0;
    }

    /// The start to come, of its length (none if it had none).
    pub(super) fn arm(&mut self) {
        self.left = self.len;
    }

    /// The start's length (samples).
    pub(super) fn len(&self) -> u32 {
        self.len
    }

    /// Samples of the start still to come.
    pub(super) fn left(&self) -> u32 {
        self.left
    }

    /// Add the start's next samples r = `a` − `b` (`a` alone without `b`; a missing one not
    /// finite); returns whether the start ended with them.
    pub(super) fn note(&mut self, a: &[f32], b: Option<&[f32]>) -> bool {
        if self.left == 0 {
            return false;
        }
        let len = b.map_or(a.len(), |b| b.len().min(a.len()));
        let r = (0..len).map(|i| {
            let x = a.get(i).copied().unwrap_or(f32::NAN);
            match b {
                Some(b) => x - b.get(i).copied().unwrap_or(f32::NAN),
                None => x,
            }
        });
        for r in r {
            if self.left == 0 {
                break;
            }
            let at = self.len - self.left;
            if r.is_finite() && at < self.cap {
                if self.last.is_finite() {
                    let d = r - self.last;
                    (self.sum_d, self.sum_d2, self.n_d) =
                        (self.sum_d + d, self.sum_d2 + d * d, self.n_d + 1);
                }
                let k = at as f32;
                let k2 = k * k;
                (self.sum, self.n) = (self.sum + r, self.n + 1);
                (self.sum_k, self.sum_k2, self.sum_kr) =
                    (self.sum_k + k, self.sum_k2 + k2, self.sum_kr + k * r);
                (self.sum_k3, self.sum_k4) = (self.sum_k3 + k2 * k, self.sum_k4 + k2 * k2);
                (self.sum_k2r, self.sum_r2) = (self.sum_k2r + k2 * r, self.sum_r2 + r * r);
                if at < self.cap_half {
                    (self.sum_first, self.n_first, self.sum_k_first) =
                        (self.sum_first + r, self.n_first + 1, self.sum_k_first + k);
                    self.sum_k2_first += k2;
                }
            }
            self.last = r;
            self.left -= 1;
        }
        self.left == 0
    }

    /// The noise of one sample from the consecutive differences (free of a smooth trend; with
    /// `trend`, of a line's too: their mean left out).
    fn noise(&self, trend: bool) -> Option<f64> {
        let n_d = self.n_d as f64;
        let ss = if trend {
            if self.n_d < 2 {
                return None;
            }
            let m = self.sum_d as f64 / n_d;
            (self.sum_d2 as f64 - n_d * m * m) / (n_d - 1.0)
        } else {
            if self.n_d == 0 {
                return None;
            }
            self.sum_d2 as f64 / n_d
        };
        Some(libm::sqrt(libm::fmax(ss, 0.0) / 2.0))
    }

    /// The offset and its standard deviation, if the start was at rest: the residual a
    /// constant within its noise (the two halves' means within [`LEVEL_SIGMAS`] of each other;
    /// a specimen already moving shows its motion's trend there, as the firmware's benchmark of
    /// a steady oscillation does), and the constant 3σ from 0. The noise is that of the
    /// differences of consecutive residuals, free of a smooth trend.
    fn offset(&self) -> Option<(f64, f64)> {
        let (n, n1) = (self.n as f64, self.n_first as f64);
        let n2 = n - n1;
        if n1 < 1.0 || n2 < 1.0 {
            return None;
        }
        if self.curve > 0.0 {
            return self.curved_offset();
        }
        let noise = self.noise(false)?;
        let (m1, m2) = (
            self.sum_first as f64 / n1,
            (self.sum - self.sum_first) as f64 / n2,
        );
        let mean = self.sum as f64 / n;
        let sd = noise / libm::sqrt(n);
        let level = libm::fabs(m1 - m2) <= LEVEL_SIGMAS * noise * libm::sqrt(1.0 / n1 + 1.0 / n2);
        (level && sd > 0.0 && libm::fabs(mean) > 3.0 * sd).then_some((mean, sd))
    }

    /// A curved start's offset (fuse mode below ~4.4 kHz at 7 Hz): over its
    /// [`MIN_OPEN_START`] samples the model's response to the table accelerometer's offset b_t
    /// has grown to ~0.1·b_t (at 1 kHz), so measured − predicted is b_top − b_t·c·g_k plus noise,
    /// g_k = k² + l·k (c, l: the start's `curve` and `lin`, the prior's ξ in the linear term),
    /// and the least squares on 1 and g give b_top, b_t and the noise from their residual
    /// (n − 2 degrees of freedom; the consecutive differences would carry the response's
    /// growth). b_top's σ is ~1.5 times a mean's. Taken when 3σ from 0, with at least 8 samples
    /// (a missing one or two), the residual's two halves level within [`LEVEL_SIGMAS`] and b_t
    /// within [`MAX_TABLE_START_OFFSET`] and 3 of its σ. Over 10 samples g soaks up most of a
    /// linear trend: a specimen already moving is told from an offset by the b_t it would
    /// need (a steady oscillation of 1 m/s² at 5.6 Hz: −3.4 m/s²) more than by the halves.
    fn curved_offset(&self) -> Option<(f64, f64)> {
        let (n, n1) = (self.n as f64, self.n_first as f64);
        let n2 = n - n1;
        if self.n < MIN_OPEN_START - 2 || n1 < 1.0 || n2 < 1.0 {
            return None;
        }
        let l = self.lin;
        let (s1, s2) = (self.sum_k as f64, self.sum_k2 as f64);
        let (s3, s4) = (self.sum_k3 as f64, self.sum_k4 as f64);
        let sg = s2 + l * s1;
        let sgg = s4 + 2.0 * l * s3 + l * l * s2;
        let (r, rg) = (
            self.sum as f64,
            self.sum_k2r as f64 + l * self.sum_kr as f64,
        );
        let det = n * sgg - sg * sg;
        if det.is_nan() || det <= 0.0 {
            return None;
        }
        let b = (sgg * r - sg * rg) / det;
        let c = (n * rg - sg * r) / det;
        let rss = self.sum_r2 as f64 - b * r - c * rg;
        let noise = libm::sqrt(libm::fmax(rss, 0.0) / (n - 2.0));
        let sd = noise * libm::sqrt(sgg / det);
        let g_first = self.sum_k2_first as f64 + l * self.sum_k_first as f64;
        let m1 = (self.sum_first as f64 - c * g_first) / n1;
        let m2 = ((self.sum - self.sum_first) as f64 - c * (sg - g_first)) / n2;
        let level = libm::fabs(m1 - m2) <= LEVEL_SIGMAS * noise * libm::sqrt(1.0 / n1 + 1.0 / n2);
        let table = -c / self.curve;
        let table_sd = noise * libm::sqrt(n / det) / self.curve;
        let plausible = libm::fabs(table) <= MAX_TABLE_START_OFFSET + 3.0 * table_sd;
        (level && plausible && sd > 0.0 && libm::fabs(b) > 3.0 * sd).then_some((b, sd))
    }

    /// The table's start: the table accelerometer's offset and its standard
    /// deviation from the least-squares line through the measured table acceleration against
    /// the `planned` line (its value at the input's first sample and its `rise` per sample: the
    /// same fit through the planned input, so a record's first acceleration and the line's miss
    /// of a sine's start cancel), for a table that follows the plan any lag late
    /// ([`start_offset`]); taken when 3σ from 0 and at most [`MAX_TABLE_START_OFFSET`]. A
    /// missing sample leaves the measured line through the others: the planned input's
    /// curvature over the start (its own, not p's: 0.1 rad of p, or 10 samples below ~4.4 kHz)
    /// then moves it by far less than the noise on the scorecard's inputs.
    fn line_offset(&self, planned: f64, rise: f64) -> Option<(f64, f64)> {
        if self.n < MIN_OPEN_START {
            return None;
        }
        let measured = LineFit::new([
            self.n as f64,
            self.sum_k as f64,
            self.sum_k2 as f64,
            self.sum as f64,
            self.sum_kr as f64,
        ])?;
        let start = MeasuredStart {
            line: measured,
            first_mean: self.sum_first as f64 / self.n_first as f64,
            first_mean_k: self.sum_k_first as f64 / self.n_first as f64,
            first_n: self.cap_half as f64,
            n: self.cap as f64,
            noise: self.noise(true)?,
        };
        let (b, sd) = start_offset(&start, planned, rise)?;
        (sd > 0.0 && libm::fabs(b) > 3.0 * sd && libm::fabs(b) <= MAX_TABLE_START_OFFSET)
            .then_some((b, sd))
    }
}

/// The open-loop start's length at `rate` for the prior `params`: its first [`OPEN_START_RAD`]
/// of p, at most 10⁴ samples; none (0) below [`MIN_OPEN_START`] (too few samples to tell a
/// level from noise or a trend).
pub fn open_start_samples(params: &StructureParams, rate: f64) -> u32 {
    let p = 2.0 * core::f64::consts::PI * params.natural_frequency_hz;
    let n = libm::floor(OPEN_START_RAD * rate / p);
    let coarse = libm::floor(MAX_OPEN_START_RAD * rate / p);
    if n.is_finite() && n >= MIN_OPEN_START as f64 {
        n.min(1e4) as u32
    } else if coarse.is_finite() && coarse >= MIN_OPEN_START as f64 {
        MIN_OPEN_START
    } else {
        0
    }
}

/// The uncertainty of the table accelerometer's offset before any estimate of it (m/s²): 0.05 g,
/// the largest the goals cover ([`BaseTuning::adopt_top`]).
pub const UNKNOWN_TABLE_OFFSET_SD: f64 = 0.05 * 9.80665;

/// Largest table offset the table's start takes (m/s²): 0.1 g, twice the largest a lab
/// accelerometer is expected to show (a table that does not follow the plan at its start is
/// not taken for an offset beyond it).
pub const MAX_TABLE_START_OFFSET: f64 = 0.1 * 9.80665;

impl BaseTuning {
    /// The top accelerometer's offset in use (m/s², fuse mode; 0 in predict mode).
    #[inline(always)]
    pub fn top_offset(&self) -> f32 {
        self.top_offset
    }

    /// The top accelerometer's gain correction in use, 1/G (fuse mode; 1 in predict mode).
    #[inline(always)]
    pub fn top_scale(&self) -> f32 {
        self.top_scale
    }

    /// The measured top acceleration `m` corrected by the offset and gain in use (fuse mode).
    #[inline(always)]
    pub fn top_corrected(&self, m: f32) -> f32 {
        (m - self.top_offset) * self.top_scale
    }

    /// How many of the next samples are in the open-loop start (`OpenStart`; fuse mode: the
    /// model's top input NaN, [`Self::note_open_start`]; predict mode: the table's start,
    /// [`Self::note_table_start`]).
    #[inline(always)]
    pub fn open_start(&self) -> usize {
        self.start.left().max(self.table_start.left()) as usize
    }

    /// The open-loop start's `measured` top accelerations and the model's predictions `pred` of
    /// them (the run's first [`Self::open_start`] samples): at its end, the top offset is their
    /// mean difference, known to its standard error.
    #[inline(never)]
    pub fn note_open_start(&mut self, measured: &[f32], pred: &[f32]) {
        if !self.start.note(measured, Some(pred)) {
            return;
        }
        // Adopted like the momentum balance's (3σ from the prior's 0), which later replaces it
        // when better known or different.
        if let Some((mean, sd)) = self.start.offset() {
            self.top_offset = mean as f32;
            self.top_offset_std_use = sd;
        }
    }

    /// Either mode without a rest, with a planned start, before the model runs the start's
    /// first sample, on a curved start (below ~4.4 kHz at 7 Hz: its 10 samples span more than
    /// [`OPEN_START_RAD`] of p, and the model's response to the table's offset b_t grows to
    /// ~0.1·b_t over them at 1 kHz, 2.5 % of the default scene's peak with 0.05 g): the table's
    /// offset in use taken provisionally as that sample `first` less the planned line's start
    /// (a table at rest reads its offset there whatever its lag; one that follows a record
    /// starting at a0 at once reads a0 more, as the plan's line), so that the model does not
    /// integrate the whole offset over the start, whose end replaces it
    /// ([`Self::note_table_start`]). On a shorter start the response stays below ~1.5e-2·b_t
    /// and nothing is done: there, unbiased by it, the top's offset from the start stayed 1.3σ
    /// off on Table 2 test 2 until the momentum balance knew it twice as well (8 s: 0.019 →
    /// 0.040 % RMS at 10 kHz), where biased it was replaced at once. NaN (a missing or flagged
    /// sample), or beyond [`MAX_TABLE_START_OFFSET`]: none. At the start's later samples,
    /// nothing.
    #[inline(never)]
    pub fn begin_table_start(&mut self, first: f32) {
        let s = &self.table_start;
        if s.left() == 0 || s.left() != s.len() || s.curve <= 0.0 {
            return;
        }
        let b = first - self.planned_start;
        if b.is_finite() && f64::from(libm::fabsf(b)) <= MAX_TABLE_START_OFFSET {
            self.offset = b;
        }
    }

    /// Either mode without a rest, with a planned start: the run's first [`Self::open_start`]
    /// samples of the table acceleration `table` (the model's input, before any offset is removed;
    /// NaN: a missing or flagged sample). At the start's end, a table offset found is taken as the
    /// offset in use, known from then on: it is removed from the base's samples before the sliding
    /// identification, whose fits from one direction of sliding then give μ itself instead of μ and
    /// the offset as one constant (`offset_known`), and later estimates from both directions
    /// replace it like any other; none found, the provisional one ([`Self::begin_table_start`]) is
    /// dropped. Returns the change of the offset in use at the start's end (the offset taken less
    /// the provisional one) and the intervals the model has integrated it over (the start's samples
    /// less one), for
    /// [`StickSlipEstimator::remove_input_offset`](ssvr_core::stick_slip::StickSlipEstimator::remove_input_offset).
    #[inline(never)]
    pub fn note_table_start(&mut self, table: &[f32]) -> Option<(f32, u32)> {
        if !self.table_start.note(table, None) {
            return None;
        }
        // (Nothing else sets the offset before the start's end: the first check comes after
        // it.)
        let provisional = self.offset;
        let intervals = self.table_start.len().saturating_sub(1);
        let Some((b, sd)) = self
            .table_start
            .line_offset(self.planned_start as f64, self.planned_rise as f64)
        else {
            self.offset = 0.0;
            return (provisional != 0.0).then_some((-provisional, intervals));
        };
        self.offset = b as f32;
        self.id_shift = self.offset;
        self.offset_std_use = sd;
        self.offset_known = true;
        Some((self.offset - provisional, intervals))
    }

    /// Fuse mode: the top accelerometer's offset and gain (relative to the base's) from the
    /// momentum balance's fit, each adopted when it differs significantly from the one in use or
    /// is known twice as well. With t = G·ü1 + b_top and ü1 = (1 + r)·μ·g·s − r·(ü2 − b_table):
    /// θ = (−G·r, G·(1 + r)·μ·g, G·r·b_table + b_top), so b_top = θ2 + θ0·b_table and, with μ·g
    /// from the sliding base (`e`), G = θ1/(μ·g) + θ0: neither needs the prior's masses.
    pub(super) fn adopt_top(&mut self, e: Option<&SlidingEstimate>) {
        let Some(f) = self.top_fit.solve::<3>() else {
            return;
        };
        let b = f.theta[2] + f.theta[0] * self.offset as f64;
        // (The table's offset in use enters b through θ0 = −G·r: while it is not known, its
        // uncertainty is that of any lab offset, and b's is at least |θ0| of it. On Table 2
        // test 2, r = ½, a table 0.05 g off had the top's offset taken 0.245 m/s² off below
        // 10 kHz, where the top's fit came before the table's.)
        let table_sd = if self.offset_known || self.offset_std_use > 0.0 {
            self.offset_std_use
        } else if let Some(e) = e.filter(|e| e.offset_std.is_finite() && e.offset_std > 0.0) {
            // (The sliding fit's estimate of it, and how far the 0 in use is from it.)
            let off = e.offset + self.id_shift as f64 - self.offset as f64;
            libm::fmin(libm::hypot(e.offset_std, off), UNKNOWN_TABLE_OFFSET_SD)
        } else {
            UNKNOWN_TABLE_OFFSET_SD
        };
        let var_b = f.cov[2][2] + f.theta[0] * f.theta[0] * table_sd * table_sd;
        let sd = libm::sqrt(libm::fmax(var_b, 0.0));
        let change = libm::fabs(b - self.top_offset as f64);
        if sd > 0.0 && (change > 3.0 * sd || sd < 0.5 * self.top_offset_std_use) {
            self.top_offset = b as f32;
            self.top_offset_std_use = sd;
        }
        let Some(e) = e else {
            return;
        };
        let fa = e.friction_accel;
        let gain = f.theta[1] / fa + f.theta[0];
        let rel_fa = e.friction_accel_std / fa;
        let var = f.cov[1][1] / (fa * fa)
            + f.cov[0][0]
            + 2.0 * f.cov[0][1] / fa
            + (f.theta[1] / fa) * (f.theta[1] / fa) * rel_fa * rel_fa;
        let sd = libm::sqrt(libm::fmax(var, 0.0));
        let differs = self.gain_differs(gain, 3.0 * sd);
        self.take_top_gain(gain, sd, differs);
        // M from r = −θ0/G (G this fit's: a gain in use not yet right would be r's error; θ0's
        // covariance with G left out: it moved σ_r by under 0.5 %, σ_r being μ·g's).
        if libm::fabs(gain - 1.0) < MAX_GAIN_ERROR {
            let r = -f.theta[0] / gain;
            let var_r = f.cov[0][0] / (gain * gain) + (r / gain) * (r / gain) * var;
            self.fuse_mass(r, libm::sqrt(libm::fmax(var_r, 0.0)));
        }
    }

    /// Fuse mode: the top accelerometer's gain relative to the base's from the stuck and sliding
    /// phases alike, by the oscillator identifier's fit with the base's filtered signals
    /// ([`GainEstimate`]): it comes before any slide on a record (El Centro sticks for 2 s), not
    /// on a single harmonic (none then). Its σ taken with its bias, `STUCK_GAIN_BIAS`, it is
    /// adopted when it differs from the gain in use by `STUCK_GAIN_SIGMAS` of it and is known at
    /// least as well, or when it is known twice as well.
    pub fn adopt_stuck_gain(&mut self, e: GainEstimate) {
        // (Its bias in its σ: no better-known gain is replaced for a spurious precision.)
        let sd = libm::hypot(e.gain_std, STUCK_GAIN_BIAS);
        let better = self.top_gain_std_use == 0.0 || sd <= self.top_gain_std_use;
        let differs = self.gain_differs(e.gain, STUCK_GAIN_SIGMAS * sd);
        self.take_top_gain(e.gain, sd, differs && better);
    }

    /// Whether `gain` differs from the one in use by more than `by`.
    fn gain_differs(&self, gain: f64, by: f64) -> bool {
        libm::fabs(gain - 1.0 / self.top_scale as f64) > by
    }

    /// The top gain `gain` ± `sd` adopted when plausible and it `differs` significantly from the
    /// one in use, or is known twice as well.
    fn take_top_gain(&mut self, gain: f64, sd: f64, differs: bool) {
        let plausible = libm::fabs(gain - 1.0) < MAX_GAIN_ERROR;
        if plausible && sd > 0.0 && (differs || sd < 0.5 * self.top_gain_std_use) {
            self.top_scale = (1.0 / gain) as f32;
            self.top_gain_std_use = sd;
        }
    }
}

#[cfg(test)]
mod tests;
