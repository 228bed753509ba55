//! The estimator's state ([`StickSlipEstimator`]): its storage layout, construction and accessors.

use super::coefficients::StickSlipCoefficients;
use super::config::{StickSlipConfig, MAX_IDENTIFY_EVERY};
use super::identify::{Ident, Pending};
use super::maps::{powi, SlideMap, StuckMap};
use super::observer::{observer_gain, sliding_observer_gain};
use super::packed::{self, MAX_SWITCHES};
use super::phase::{Level, SlidingPhase};
use super::retune::block_maps;
use super::rls::{MuEstimate, Rls};
use crate::error::{Error, Param};
use crate::math::{Real, Transcendentals};
use crate::structure::Structure;
use core::marker::PhantomData;

/// One sample of the history (16 bytes in f32), written by every update.
#[derive(Debug, Clone, Copy)]
pub(super) struct Slot<T> {
    /// Table acceleration at the sample (a non-finite one replaced by the previous).
    pub(super) u: T,
    /// Measured top acceleration at the sample (NaN: none).
    pub(super) y: T,
    /// State at the sample.
    pub(super) z: [T; 2],
}

/// Which path the next interval takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub(super) enum Mode {
    /// Plain sliding: the hot path with the precomputed forcing.
    Slide = 0,
    /// Plain stuck: the hot path of the fixed-base map.
    Stuck = 1,
    /// Anything else (sample 0, a switch inside the interval, a phase change at its end): the
    /// general path.
    Cold = 2,
}

/// The stick-slip aware estimator with up to `H` samples of history (the longest back-dating):
/// `H` slots of storage, of which [`Self::history`] are the history.
#[derive(Debug, Clone)]
#[repr(C)]
pub struct StickSlipEstimator<T: Real, M: Transcendentals<T>, const H: usize> {
    // The hot path's fields first (small offsets).
    /// The slot before sample k's (the next update's), wrapping: sample k goes to slot
    /// `at + 1` (`first ..= H − 1`).
    pub(super) at: usize,
    /// [`Self::update`] takes the inline sliding path while `at` is below this: `mark − 2` in
    /// [`MODE_SLIDE`] (the sample before the mark is not stored inline), else 0.
    pub(super) fast_until: usize,
    /// The same for the inline stuck path ([`MODE_STUCK`]).
    pub(super) stuck_until: usize,
    /// Forcing per interval in the current sliding phase: ±g·μ_use times `c.force_s`.
    pub(super) drive: [T; 2],
    /// Measurement correction of a stuck sample: the state += `gain`·(prediction − measured).
    pub(super) gain: [T; 2],
    /// The same of a sliding sample.
    pub(super) slide_gain: [T; 2],
    /// The sliding interval's map with the correction (a finite measured top acceleration at
    /// its start; without: `c.phi_s` and `drive`).
    pub(super) slide: SlideMap<T>,
    /// The sliding observer's gain and map, wide (until μ̂ is adopted and, if held, f and ξ are known) and narrow.
    pub(super) slides: [([T; 2], SlideMap<T>); 2],
    /// The narrow one is in use.
    pub(super) slide_narrow: bool,
    /// μ̂ has been adopted at least once ([`StickSlipEstimator::mu_adopted`]).
    pub(super) mu_adopted: bool,
    /// The wide sliding observer is kept even once μ̂ is adopted
    /// ([`StickSlipEstimator::hold_wide`]: f and ξ not yet known).
    pub(super) hold_wide: bool,
    /// The stuck interval's map with the correction (a finite measured top acceleration at its
    /// start) and without.
    pub(super) closed: StuckMap<T>,
    pub(super) open: StuckMap<T>,
    pub(super) c: StickSlipCoefficients<T>,
    /// [`MODE_SLIDE`], [`MODE_STUCK`] or [`MODE_COLD`]: how to step interval k − 1 → k.
    pub(super) mode: Mode,
    /// The current phase (of interval k − 1 → k on, once a pending change is applied).
    pub(super) phase: Level,
    /// The slow path ([`Self::at_mark`]) runs after storing the sample of slot `mark − 1`
    /// (≤ `H`: the ring's wrap).
    pub(super) mark: usize,
    /// The identification's next block is processed at the mark `id_mark` (`usize::MAX`: not in
    /// this pass of the ring; `id_carry`, counted as if the pass went on, then says when).
    pub(super) id_mark: usize,
    /// See `id_mark` (`usize::MAX`: identification off).
    pub(super) id_carry: usize,
    /// The ring is slots `first .. H` (`P = H − first` slots); with `first` = 1, slot 0 holds a
    /// copy of slot H − 1, the sample before the one in slot 1 after the wrap.
    pub(super) first: usize,
    /// Slot offset (from `first`) of sample 0: aligns the wrap with the identification blocks.
    pub(super) shift: usize,
    /// Slots of the ring (P = H − first) times the passes before the current one: sample k is
    /// in slot `first + (k + shift − origin)`.
    pub(super) origin: u64,
    /// History length in use (2 ..= H).
    pub(super) len: usize,
    /// Every interval from this one on is in `phase`, without a switch; the phase bytes of the
    /// earlier ones (within the history) are in `iv`.
    pub(super) plain_from: u64,
    pub(super) mu_use: T,
    /// g·μ_use.
    pub(super) gmu: T,
    pub(super) cfg: StickSlipConfig,
    pub(super) id: Ident<T>,
    pub(super) slots: [Slot<T>; H],
    /// The phases of the interval from each slot's sample to the next ([`packed`]).
    pub(super) iv: [u8; H],
    /// Their switch fractions (the first `packed::switches(iv)` are valid).
    pub(super) fr: [[T; MAX_SWITCHES]; H],
    pub(super) _m: PhantomData<M>,
}

/// The sliding observer's gain and map, wide and narrow.
pub(super) fn sliding_observers<T: Real, M: Transcendentals<T>>(
    c: &StickSlipCoefficients<T>,
    cfg: &StickSlipConfig,
) -> [([T; 2], SlideMap<T>); 2] {
    let on = (cfg.sliding_observer, cfg.cap_sliding_observer);
    [true, false].map(|wide| {
        let g = sliding_observer_gain::<T, M>(c, on, wide);
        (g, SlideMap::closed(c, g))
    })
}

/// Never called: marks the branch that calls it as unlikely.
#[cold]
#[inline(never)]
pub(super) fn unlikely() {}

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// Build the estimator for `structure` sampled at `sample_rate_hz`, the base stuck, at rest,
    /// with a history of `H` samples.
    pub fn new(
        structure: &Structure,
        sample_rate_hz: f64,
        cfg: StickSlipConfig,
    ) -> Result<Self, Error> {
        Self::with_history(structure, sample_rate_hz, cfg, H)
    }

    /// [`Self::new`] with a history of `history` samples (2 ..= `H`): events up to `history − 2`
    /// samples old are accepted, and μ is identified on blocks of samples once they are
    /// `history − 2` samples old. The same `history` gives the same results whatever the
    /// storage `H` (a storage of `history + 1` samples or more, and a multiple of
    /// [`StickSlipConfig::identify_every`] plus one, makes the steady state cheaper:
    /// [`storage_for`](super::storage_for)).
    pub fn with_history(
        structure: &Structure,
        sample_rate_hz: f64,
        cfg: StickSlipConfig,
        history: usize,
    ) -> Result<Self, Error> {
        Self::from_coefficients(
            StickSlipCoefficients::new(structure, sample_rate_hz)?,
            cfg,
            history,
        )
    }

    /// The estimator from its coefficients ([`StickSlipCoefficients`]), with a history of
    /// `history` samples (2 ..= `H`), the base stuck, at rest.
    pub fn from_coefficients(
        c: StickSlipCoefficients<T>,
        cfg: StickSlipConfig,
        history: usize,
    ) -> Result<Self, Error> {
        crate::error::check_forgetting(cfg.forgetting)?;
        if cfg.identify_every == 0 || cfg.identify_every > MAX_IDENTIFY_EVERY {
            return Err(Error::OutOfRange {
                param: Param::IdentifyEvery,
                value: cfg.identify_every as f64,
                expected: "identify_every in 1 ..= MAX_IDENTIFY_EVERY samples",
            });
        }
        if history < 2 || history > H {
            return Err(Error::OutOfRange {
                param: Param::History,
                value: history as f64,
                expected: "a history of at least 2 samples, at most the storage H",
            });
        }
        crate::error::check(
            Param::ObserverBandwidth,
            cfg.observer_bandwidth,
            cfg.observer_bandwidth >= 0.0 && cfg.observer_bandwidth <= 10.0,
            "observer bandwidth in [0, 10] × p",
        )?;
        let gain = observer_gain::<T, M>(&c, cfg.observer_bandwidth);
        let slides = sliding_observers::<T, M>(&c, &cfg);
        let n = cfg.identify_every;
        let (block_phi, block_force) = block_maps(&c, n);
        let alpha = if n == 1 {
            1e-3
        } else {
            1.0 - powi(1.0 - 1e-3, n)
        };
        let every = n as usize;
        // The ring: all the storage, after a copy slot if there is room for one.
        let first = usize::from(history < H);
        let ring = H - first;
        // Blocks are processed with samples k ≡ history − 2 (mod n), each right after storing
        // it; with n | P, sample 0 at slot offset (1 − history) mod n puts those samples in the
        // last slot of every n: the wrap comes with a block.
        let whole_blocks = ring / every * every == ring;
        let shift = if whole_blocks {
            (every - (history - 1) % every) % every
        } else {
            0
        };
        // The first block (intervals 0 .. n) is processed with sample n + history − 2: after
        // storing it at offset n + history − 2 + shift, the mark first + offset + 1.
        let id_carry = if cfg.identify_mu {
            first + every + history - 1 + shift
        } else {
            usize::MAX
        };
        let mut est = Self {
            at: (first + shift).wrapping_sub(1),
            fast_until: 0,
            stuck_until: 0,
            drive: [T::ZERO; 2],
            gain,
            slide_gain: slides[0].0,
            slide: slides[0].1,
            slides,
            slide_narrow: false,
            mu_adopted: false,
            hold_wide: false,
            closed: StuckMap::closed(&c, gain),
            open: StuckMap::open(&c),
            c,
            mode: Mode::Cold,
            phase: 0,
            mark: H,
            id_mark: usize::MAX,
            id_carry,
            first,
            shift,
            origin: 0,
            len: history,
            plain_from: 0,
            mu_use: c.mu,
            gmu: c.g * c.mu,
            cfg,
            id: Ident {
                every: every as u64,
                full: u32::MAX >> (32 - n),
                pend: Pending {
                    from: 0,
                    other: u32::MAX >> (32 - n),
                    neg: 0,
                    end: 0,
                    sign: 0,
                },
                block_phi,
                block_force,
                zh: [T::ZERO; 2],
                zu: [T::ZERO; 2],
                // Sample 0, at rest: the start of the first block.
                z_start: [T::ZERO; 2],
                episode: false,
                rls: Rls {
                    mu: c.mu,
                    // P0 = 1: a0 = 1, b0 = μ0.
                    a: T::ONE,
                    b: c.mu,
                    lambda: T::from_f64(powi(cfg.forgetting, n)),
                    e2: T::from_f64(1e-4),
                    alpha: T::from_f64(alpha),
                    n: 0,
                },
            },
            slots: [Slot {
                u: T::ZERO,
                y: T::ZERO,
                z: [T::ZERO; 2],
            }; H],
            iv: [packed::new(0); H],
            fr: [[T::ZERO; MAX_SWITCHES]; H],
            _m: PhantomData,
        };
        if est.id_carry <= H {
            est.id_mark = est.id_carry;
        }
        est.mark = est.id_mark.min(H);
        Ok(est)
    }

    /// The coefficients.
    pub fn coefficients(&self) -> &StickSlipCoefficients<T> {
        &self.c
    }

    /// The history length in samples (events up to `history − 2` samples old are accepted).
    pub fn history(&self) -> usize {
        self.len
    }

    /// The settings.
    pub fn config(&self) -> &StickSlipConfig {
        &self.cfg
    }

    /// The current phase.
    pub fn phase(&self) -> SlidingPhase {
        match self.phase {
            ..0 => SlidingPhase::Negative,
            0 => SlidingPhase::Stuck,
            _ => SlidingPhase::Positive,
        }
    }

    /// The μ the model uses now.
    pub fn mu_used(&self) -> f64 {
        self.mu_use.to_f64()
    }

    /// Whether the model has adopted the identified μ̂ at least once (with
    /// [`StickSlipConfig::use_identified_mu`]): until then it uses the μ it was built or last
    /// set with. A large [`Self::retune`] restarts the least squares but keeps this: the μ̂ in
    /// use stays until the next adoption.
    pub fn mu_adopted(&self) -> bool {
        self.mu_adopted
    }

    /// Keep the wide sliding observer (`hold`: the natural frequency and damping ratio in use
    /// are a prior not yet confirmed by their identification) even once μ̂ is adopted: it
    /// narrows at the first adoption of μ̂ after the release (the next identification block
    /// that adopts it, mid-slide or at a slide's start). Holding does not widen an observer
    /// already narrow (a large [`Self::retune`] does). With f
    /// and ξ wrong, the narrow observer lets their error grow while sliding: on the robustness
    /// scorecard's combined row (f told 8 % high, ξ ×2, the first slide at 48 ms) μ̂ adopted
    /// mid-slide took the max error from 1.7 % to 2.2 % of the peak.
    pub fn hold_wide(&mut self, hold: bool) {
        self.hold_wide = hold;
    }

    /// The identified μ, with its standard deviation (None before any identification block was
    /// used).
    pub fn mu_estimate(&self) -> Option<MuEstimate> {
        let r = &self.id.rls;
        (r.n > 0).then(|| {
            let var = (r.e2 / r.a).to_f64();
            MuEstimate {
                mu: r.mu.to_f64(),
                std: libm::sqrt(var.max(0.0)),
                blocks: r.n,
            }
        })
    }

    /// Index of the sample the next [`Self::update`] returns.
    pub fn sample_index(&self) -> u64 {
        let pos = self.at.wrapping_add(1);
        (self.origin + (pos - self.first) as u64).saturating_sub(self.shift as u64)
    }

    /// The prediction of an earlier sample as revised by the events pushed since (the history
    /// re-simulated from each late event): `None` outside the kept history. A sample older than the
    /// longest detection latency is final.
    pub fn prediction_at(&self, sample: u64) -> Option<T> {
        let k = self.sample_index();
        if sample >= k || k - sample > self.len as u64 {
            return None;
        }
        let z = self.slots.get(self.slot_of(sample))?.z;
        Some(z[0])
    }
}
