//! Predict mode's tuning from the base accelerometer ([`BaseTuning`]): predict mode never reads
//! the top accelerometer, but while the base slides the base accelerometer alone gives
//!
//! * **the sliding oscillator and the friction** ([`ssvr_core::sliding_id`]): ω = p·√M,
//!   ζ = ξ·√M and μ·g, free of the model's state. With the prior's M = 1 + m1/m2 they give f and
//!   ξ, adopted by the policy of the fuse mode's tuning ([`Adoption`]), and μ, adopted once known
//!   to [`MAX_REL_STD_MU`];
//! * **the top acceleration** by the momentum balance of the two masses,
//!   m1·ü1 + m2·ü2 = μ·(m1 + m2)·g·s (s the friction force's direction, the phase level):
//!   ü1 = (1 + r)·μ·g·s − r·ü2 with r = m2/m1. The model's sliding-phase observer corrects its
//!   state towards it (its error is r times the base accelerometer's, ~1/17 on the Table 1
//!   specimen), so each stuck phase starts from the right state.
//!
//! **Labels.** The samples are averaged over the identifier's blocks as they come (base and top:
//! a few instructions per sample). The detector reports events late (their age): a block waits
//! in a ring of blocks covering the detector's longest delay (at most [`BLOCKS`]) before it goes
//! to the identification, so that every event reported meanwhile labels it with its true phase;
//! a block with a sample within [`GUARD`] samples of an event is not used.
//!
//! **Batches.** The adoption checks fall on multiples of [`FIRST_CHECK_EVERY`] samples when the
//! samples come one at a time or in the firmware's batches of 16 (split at events): then the
//! host and the firmware are bit for bit equal. Batches of other lengths may check a few samples
//! later (as the fuse mode's [`Tuning`](super::Tuning) and the friction law's checks do).
//!
//! In **fuse** mode the same identification gives only the table accelerometer's offset (f, ξ
//! and μ come from the top accelerometer there), and the momentum balance gives the top
//! accelerometer's offset: over the sliding samples the measured top acceleration is fitted as
//! −r̂·ü2 + c·s + d (least squares, [`PagedNormal`]), d = r·b_table + b_top. Both offsets are
//! removed from the model's inputs once known (3σ), so a common offset of the table and the top
//! (indistinguishable from a constant table acceleration for the fixed-base dynamics) is
//! separated by the sliding phases.
//!
//! Coulomb friction only (a velocity-dependent law changes μ along the slide: its model keeps
//! the prior's law in predict mode). All in f32 but the adoption's f64 at a check: the firmware
//! and the host run this same code.

use super::tuning::{Adoption, OscillatorReport};
use ssvr_core::least_squares::PagedNormal;
use ssvr_core::oscillator_id::OscillatorEstimate;
use ssvr_core::sliding_id::{SlidingEstimate, SlidingIdentifier};
use ssvr_core::stick_slip::MuEstimate;
use ssvr_core::StructureParams;

mod blocks;
mod checks;
mod first_slides;
mod mass;
pub use first_slides::{SlipStart, PREDICT_BREAKAWAY_WEIGHT};
use mass::MassFit;
mod slot;
mod top;
mod units;

pub use slot::BaseSlot;
use top::OpenStart;
pub use top::{open_start_samples, MAX_TABLE_START_OFFSET, MIN_OPEN_START, OPEN_START_RAD};

/// Most blocks that wait for late events before they are used: as many as cover the detector's
/// longest reporting delay (the plan's `max_age`) and [`GUARD`], plus one, up to this many (at
/// low rates, blocks of one sample, fewer than the delay: see [`BaseTuning::new`]).
pub const BLOCKS: usize = 32;
/// Samples either side of an event's time that are not used.
pub const GUARD: f32 = 2.0;
/// Forgetting per identification row (a memory of ~10⁵ rows: tens of seconds of sliding).
pub const FORGETTING_PER_ROW: f64 = 0.99999;
/// Samples between two adoption checks until μ̂ (fuse mode: a top offset) is first adopted,
/// for at most [`FAST_CHECKS`] estimates: an early adoption shortens the time a wrong prior's μ
/// is in use. A multiple of the firmware's batch, so that a check falls on a batch's end
/// (module documentation: **Batches**). Measured on the scorecard (predict mode): 128 → 32 took
/// ξ × 2 / × 0.5 on the default scene from 0.46 / 0.25 to 0.30 / 0.15 % RMS and μ ± 25 % from
/// 1.50 to 1.24 %; 16 changed little and took Table 2 test 2's gain errors from 0.13 to 0.42 %.
/// An adoption while sliding shifts the model's state with the momentum balance's top
/// ([`BaseTuning::top_shift`]): without, an adoption in a slide's last milliseconds left the
/// sliding observer's transient in the state at the stick, which the open-loop stuck phase
/// grew into a free oscillation (104 % of the peak on the default scene).
pub const FIRST_CHECK_EVERY: u32 = 32;
/// … and once it is: a check solves 4×4 normal equations in f64 (thousands of M4F
/// instructions), and the estimate changes slowly. A check without a new row since the last
/// one solves nothing.
pub const CHECK_EVERY: u32 = 1024;
/// Estimates made [`FIRST_CHECK_EVERY`] samples apart at most (1 536 samples; 16 were 2 048 at
/// 128 apart).
pub const FAST_CHECKS: u8 = 48;
const _: () = assert!(FIRST_CHECK_EVERY.is_multiple_of(crate::pipeline::BATCH as u32));
const _: () = assert!(CHECK_EVERY.is_multiple_of(FIRST_CHECK_EVERY));
/// Largest top-accelerometer gain error (relative to the base's) taken for one: beyond it the
/// fit is wrong data, not a gain.
pub const MAX_GAIN_ERROR: f64 = 0.1;
/// Largest relative standard deviation of μ̂ for adoption (a μ known to 2 % is far better than
/// a prior 10–25 % off, and later checks refine it).
pub const MAX_REL_STD_MU: f64 = 2e-2;
/// Largest relative standard deviation of μ̂ for the offset of the same fit to be adopted: the
/// offset has its own 3σ test, and a μ̂ known to 5 % tells a fit from wrong data (with
/// [`MAX_REL_STD_MU`] the offset waited for it: Table 2 test 2 with everything combined, fuse
/// mode, 1.13 % RMS, 0.26 % with 5 %; no other row of the scorecard changed).
pub const MAX_REL_STD_MU_OFFSET: f64 = 5e-2;
/// Smallest relative change of μ worth adopting.
pub const MIN_REL_CHANGE_MU: f64 = 1e-4;

/// The identification from the sliding base of either mode (module documentation).
///
/// (`repr(C)`: the fields the samples' path reads first, in the order written, the large
/// identifiers and rings after them: see [`StickSlipModel`](super::StickSlipModel).)
#[derive(Debug, Clone)]
#[repr(C)]
pub struct BaseTuning {
    /// The block being summed.
    cur: Block,
    cur_n: u32,
    /// Samples per block, and its inverse.
    d: u32,
    inv_d: f32,
    skip: u8,
    /// The phase level of the samples to come, and how many of them the guard drops.
    level: i8,
    /// The table accelerometer's offset in use (m/s²): what the identification finds on the
    /// base accelerometer, whose offset relative to the table's the detector removes.
    offset: f32,
    r: f32,
    g: f32,
    /// The friction coefficient of each direction of the friction force (s = +1, −1) in use:
    /// μ, or until the base has slid both ways without a rest (and without the table's offset
    /// from its start), that direction's one-way estimate (the offset in it), with its standard
    /// deviation (0: the prior's;
    /// `FROM_BREAKAWAY`: a slip start's breakaway, [`Self::slip_start`]).
    mu_dir: [f32; 2],
    mu_use: f32,
    /// The top accelerometer's offset in use (m/s²) and its standard deviation.
    top_offset: f32,
    /// 1/G of the top accelerometer's gain G relative to the base's in use, and G's standard
    /// deviation.
    top_scale: f32,
    countdown: u32,
    /// Fuse mode: only the offsets (the top accelerometer's from `top_fit`) and M.
    fuse: bool,
    zeroed: bool,
    /// The table's offset is known: zeroed on a rest, or found at the table's start
    /// (a fit from one direction of sliding then takes the offset in use as right).
    offset_known: bool,
    /// μ is known from both directions (adopted, or the one in use confirmed).
    mu_known: bool,
    id: SlidingIdentifier<f32>,
    /// Without a rest, the first samples ([`OpenStart`]): fuse mode's top offset (none in
    /// predict mode),
    start: OpenStart,
    /// and, with a planned start, the table's offset against it (either mode).
    table_start: OpenStart,
    /// The blocks waiting for late events (`at`: the slot of the next, `filled` of them), in
    /// the first `wait` slots: the blocks that cover the detector's longest delay.
    ring: [Block; BLOCKS],
    wait: usize,
    at: usize,
    filled: usize,
    adoption: Adoption,
    /// √M of the prior; r = m2/m1; g.
    root_m: f64,
    prior_mu: f64,
    mu_dir_std: [f64; 2],
    /// The standard deviation of the μ in use (0: the prior's, replaced only by a μ̂ that
    /// differs from it significantly).
    mu_std_use: f64,
    /// The same for the offset in use (the prior's: 0).
    offset_std_use: f64,
    mu_adoptions: u32,
    /// Rows the identifier had at the last estimate.
    rows_seen: u32,
    /// Estimates left at the first checks' interval.
    fast_checks: u8,
    last: Option<SlidingEstimate>,
    /// The measured top acceleration against (base, s, 1) while sliding.
    top_fit: PagedNormal<f32, 3, 10>,
    top_offset_std_use: f64,
    top_gain_std_use: f64,
    /// M from the slip starts' residuals (predict mode) or the momentum balance (fuse mode;
    /// [`Self::m1_in_use`]), and the prior's √M.
    mass: MassFit,
    prior_root_m: f32,
    /// What is removed from the base's blocks before the sliding identification: predict
    /// mode's table offset from the table's start (its fits' offsets are then what is left).
    id_shift: f32,
    /// The plan's table acceleration at the input's start and its rise per sample
    /// ([`Self::with_planned_start`]).
    planned_start: f32,
    planned_rise: f32,
    /// The prior's μ/μs: a slip start's breakaway coefficient times it is the slide's μ
    /// ([`Self::slip_start`]).
    mu_per_mu_s: f32,
    /// The slip starts' kinetic coefficients from their sliding sides (fuse mode: their mean).
    slides: super::Breakaways,
}

/// A block of samples: base and top sums (averages once closed), its phase level (0: not to
/// use) and its first sample's index.
#[derive(Debug, Clone, Copy, Default)]
struct Block {
    base: f32,
    top: f32,
    level: i8,
    start: u32,
}

impl BaseTuning {
    /// The tuning of the prior `params` at `rate` (`None` if the identifier cannot be set up);
    /// `zeroed`: the accelerometers are zeroed on a rest before the input (an estimate from one
    /// direction of sliding may then take the offset as 0); `max_age`: the detector's longest
    /// reporting delay (samples).
    pub fn new(
        params: StructureParams,
        rate: f64,
        zeroed: bool,
        fuse: bool,
        max_age: usize,
    ) -> Option<Self> {
        let m = 1.0 + params.m1_kg / params.m2_kg;
        let root_m = libm::sqrt(m);
        let omega = 2.0 * core::f64::consts::PI * params.natural_frequency_hz * root_m;
        let id = SlidingIdentifier::new(rate, omega, FORGETTING_PER_ROW).ok()?;
        let d = id.decimation() as usize;
        // (At the lowest rates the ring may be shorter than the delay: a late slip start then
        // finds its first blocks gone, labelled stuck: lost, never mislabelled.)
        let wait = max_age
            .saturating_add(GUARD as usize + 1)
            .div_ceil(d.max(1))
            .saturating_add(1);
        Some(Self {
            ring: [Block::default(); BLOCKS],
            wait: wait.clamp(2, BLOCKS),
            cur: Block {
                level: 1,
                ..Block::default()
            },
            cur_n: 0,
            d: id.decimation(),
            inv_d: 1.0 / id.decimation() as f32,
            at: 0,
            filled: 0,
            level: 0,
            skip: 0,
            adoption: Adoption::new(params, rate),
            root_m,
            r: (params.m2_kg / params.m1_kg) as f32,
            g: params.gravity_m_s2 as f32,
            prior_mu: params.friction_coefficient,
            mu_use: params.friction_coefficient as f32,
            mu_dir: [params.friction_coefficient as f32; 2],
            mu_dir_std: [0.0; 2],
            mu_known: false,
            mu_per_mu_s: 1.0,
            slides: super::Breakaways::default(),
            mu_std_use: 0.0,
            offset_std_use: 0.0,
            mu_adoptions: 0,
            rows_seen: 0,
            fast_checks: FAST_CHECKS,
            offset: 0.0,
            countdown: FIRST_CHECK_EVERY,
            last: None,
            zeroed,
            offset_known: zeroed,
            id_shift: 0.0,
            planned_start: f32::NAN,
            planned_rise: 0.0,
            fuse,
            top_fit: PagedNormal::new(FORGETTING_PER_ROW),
            top_offset: 0.0,
            top_offset_std_use: 0.0,
            start: {
                let mut start = OpenStart::new(!zeroed, &params, rate);
                if !fuse {
                    start.off();
                }
                start
            },
            table_start: {
                // (Armed by a planned start: `with_planned_start`.)
                let mut start = OpenStart::new(!zeroed, &params, rate);
                start.off();
                // (The table's statistics over its first samples only: every whole lag of the
                // table is tried over them, `table_start::LAGS`.)
                start.keep_first(crate::table_start::LAGS as u32 - 1);
                start
            },
            top_scale: 1.0,
            top_gain_std_use: 0.0,
            mass: MassFit::default(),
            prior_root_m: root_m as f32,
            id,
        })
    }

    /// Predict mode: the planned table acceleration's line at the input's start,
    /// [`Plan::planned_start`](crate::Plan::planned_start) (`None`: not planned). The table's
    /// start ([`Self::note_table_start`]) needs it: without a plan a start that is not at rest
    /// cannot be told from an offset (El Centro's record starts at 0.06 m/s²), and there is
    /// none.
    pub fn with_planned_start(mut self, planned: Option<crate::PlannedStart>) -> Self {
        (self.planned_start, self.planned_rise) = match planned {
            Some(p) => (p.accel_m_s2, p.rise_per_sample_m_s2),
            None => (f32::NAN, 0.0),
        };
        if self.planned_start.is_finite() && self.planned_rise.is_finite() {
            self.table_start.arm();
        } else {
            self.table_start.off();
        }
        self
    }

    /// The change of [`Self::top_of`] in phase `level` when its friction coefficient went from
    /// `before` to the one in use (0 when stuck): what the model's state is shifted by at an
    /// adoption while sliding
    /// ([`StickSlipEstimator::shift_top`](ssvr_core::stick_slip::StickSlipEstimator::shift_top)).
    #[inline(always)]
    pub fn top_shift(&self, level: i8, before: f32) -> f32 {
        if level == 0 || self.fuse {
            return 0.0;
        }
        (1.0 + self.r) * (self.mu_for(level) - before) * self.g * sign(level)
    }

    /// The top acceleration of a sliding sample from its base acceleration `base` (NaN when
    /// stuck: `level` 0).
    #[inline(always)]
    pub fn top_of(&self, base: f32, level: i8) -> f32 {
        if level == 0 {
            return f32::NAN;
        }
        (1.0 + self.r) * self.mu_for(level) * self.g * sign(level) - self.r * (base - self.offset)
    }

    /// The model's inputs of a run in phase `level`, in place of its measured samples: the
    /// table acceleration `table` less the offset in use ([`Self::offset`]), and the top `top`:
    /// in fuse mode the measured top corrected ([`Self::top_corrected`]), in predict mode
    /// [`Self::top_of`] the run's base samples `base`. The same numbers as those calls, with
    /// the run's constants read once, in one pass (a call per sample cost the M4F ~6
    /// instructions per sample more).
    #[inline(always)]
    pub fn inputs_in_place(&self, table: &mut [f32], top: &mut [f32], base: &[f32], level: i8) {
        let off = self.offset;
        let samples = table.iter_mut().zip(top.iter_mut());
        if self.fuse {
            let (o, s) = (self.top_offset, self.top_scale);
            for (u, y) in samples {
                *u -= off;
                *y = (*y - o) * s;
            }
        } else if level == 0 {
            for (u, y) in samples {
                *u -= off;
                *y = f32::NAN;
            }
        } else {
            let c = (1.0 + self.r) * self.mu_for(level) * self.g * sign(level);
            let r = self.r;
            for ((u, y), &b) in samples.zip(base) {
                *u -= off;
                *y = c - r * (b - off);
            }
        }
    }

    /// Predict mode: the friction coefficient to set at an event into phase `level`, `age`
    /// samples old (`None` when stuck, for an event the estimator rejects, and in fuse mode,
    /// whose μ comes from the top accelerometer).
    #[inline(always)]
    pub fn mu_at_event(&self, level: i8, age: f32) -> Option<f32> {
        (!self.fuse && level != 0 && takes(level, age)).then(|| self.mu_for(level))
    }

    /// The friction coefficient in use for phase `level`: μ, or while only one direction has
    /// slid without a rest, that direction's one-way estimate (the table offset in it: what the
    /// model's stuck phases carry too, so the top's prediction is off by that offset alone
    /// instead of by the prior's error in μ; once the table's start against the plan found the
    /// offset, a one-way fit gives μ itself, for both directions).
    #[inline(always)]
    pub fn mu_for(&self, level: i8) -> f32 {
        match level {
            1.. => self.mu_dir[0],
            ..=-1 => self.mu_dir[1],
            0 => self.mu_use,
        }
    }

    /// The table (and base) accelerometer's offset in use (m/s²), to remove from the model's
    /// table input.
    #[inline(always)]
    pub fn offset(&self) -> f32 {
        self.offset
    }

    /// The last check's oscillator estimate.
    pub fn estimate(&self) -> Option<OscillatorEstimate> {
        self.last.as_ref().map(|e| self.oscillator(e))
    }

    /// The last check's friction coefficient.
    pub fn mu_estimate(&self) -> Option<MuEstimate> {
        self.last.as_ref().map(|e| MuEstimate {
            mu: e.friction_accel / self.g as f64,
            std: e.friction_accel_std / self.g as f64,
            blocks: e.rows as u32,
        })
    }

    /// The f (Hz) and ξ in use, and how many times they were adopted.
    pub fn in_use(&self) -> (f64, f64, u32) {
        self.adoption.in_use()
    }
}

impl BaseTuning {
    /// The report of [`Model::oscillator`](super::Model::oscillator).
    pub fn report(&self) -> OscillatorReport {
        self.adoption.report(self.estimate())
    }
}

#[cfg(test)]
pub(super) use crate::test_params;

/// Whether the estimator takes an event into phase `level`, `age` samples old: a level in
/// −1..=1, an age finite and ≥ 0 (`StickSlipEstimator::push_event`'s test).
#[inline(always)]
fn takes(level: i8, age: f32) -> bool {
    (-1..=1).contains(&level) && age.is_finite() && age >= 0.0
}

/// The friction force's direction of a sliding phase level (±1).
#[inline(always)]
fn sign(level: i8) -> f32 {
    if level > 0 {
        1.0
    } else {
        -1.0
    }
}
