//! The stick-slip aware estimator (beyond the paper): follows the measurement through stick phases
//! and identifies the friction coefficient online.
//!
//! The top-mass state z = (p²δ, pδ') (δ = u1 − u2, units m/s²) is continuous across every phase
//! change, and ü1 = −(z0 + 2ξ z1) in every phase. Only the governing equation changes:
//!
//! * **sliding** (friction level s = ±1): δ'' + 2aδ' + Mp²δ = −s·M·gμ (eq 25), a free vibration
//!   about z_eq = (−s·gμ, 0): z(τ) = Φs(τ)(z − z_eq) + z_eq, Φs = [[ecp, p·es], [−Mp·es, ecm]];
//! * **sticking**: the base moves with the table and the top mass is a fixed-base oscillator driven
//!   by the measured table acceleration, δ'' + 2ξpδ' + p²δ = −ü_g, with ü_g linear between samples
//!   (Nigam–Jennings): for ü_g = c0 + c1·t the particular solution is z_p = (−(c0 + c1 t) + 2ξc1/p,
//!   −c1/p), and z(τ) = Φf(τ)(z − z_p(0)) + z_p(τ) exactly.
//!
//! Per sample both maps are precomputed 2×2 matrices (plus input vectors); a phase change inside
//! a sample interval is integrated exactly in pieces with the kernel. Phase changes are reported
//! late by the detector: the last `H` samples (inputs, states and the phase of each interval) are
//! kept, and a late event re-simulates from the sample before it, so every later sample is right.
//! The history is a ring of `history` ≤ `H` slots (runtime length, [`StickSlipEstimator::with_history`];
//! `H` is the storage), 28 bytes per slot in f32: the table acceleration, the state, the measured
//! top acceleration, and the interval's phases packed in one byte (start phase, number of switches,
//! the phase after each switch: 2 bits each) next to the switch fractions.
//!
//! **Friction identification.** While the base slides, z = z_h + μ·z_u, where z_h is the free
//! evolution of the state at the start of the sliding episode and z_u the response to the friction
//! per unit μ: ü1 is linear in μ. On samples that are `H − 1` samples old (their phase is final) the
//! estimator runs both parts and updates μ̂ by recursive least squares with forgetting λ from the
//! measured top acceleration against the unit-μ prediction (in information form: one division per
//! sample); its standard deviation comes from the residual variance. With `use_identified_mu` the
//! model adopts μ̂ at the start of each sliding episode once it has enough samples.
//!
//! The coefficients ([`StickSlipCoefficients`]) are computed in f64 and rounded to `T`; in f32
//! they can also be restored from their bits (a build script computes them, the firmware image
//! then needs no f64 code).

use crate::error::{Error, Param};
use crate::free_vibration::Kernel;
use crate::math::{Real, Transcendentals};
use crate::structure::{Regime, Structure};
use core::marker::PhantomData;

/// Phase changes kept per sample interval.
pub const MAX_SWITCHES: usize = 2;

/// Contact phase: 0 stuck, +1 or −1 the friction level F/F0 while sliding (friction opposes slip).
pub type Phase = i8;

/// One sample interval's phases packed in a byte: bits 0–1 the phase at the start, bits 2–3 the
/// number of switches (≤ [`MAX_SWITCHES`]), bits 4–5 and 6–7 the phase after the first and the
/// second switch; a phase is coded in two bits as its two's complement (0 → 0b00, +1 → 0b01,
/// −1 → 0b11).
mod packed {
    use super::{Phase, MAX_SWITCHES};

    /// The code of a phase (−1, 0, 1).
    #[inline(always)]
    pub fn code(p: Phase) -> u8 {
        (p as u8) & 3
    }

    /// The phase of a code.
    #[inline(always)]
    pub fn phase(c: u8) -> Phase {
        ((c << 6) as i8) >> 6
    }

    /// The mark of the slot before sample 0 (no interval ends there): a switch count of 3.
    pub const NO_SAMPLE: u8 = 0x0C;

    /// A new interval: `start` throughout, no switch.
    #[inline(always)]
    pub fn new(start: Phase) -> u8 {
        code(start)
    }

    /// Number of switches.
    #[inline(always)]
    pub fn switches(b: u8) -> usize {
        ((b >> 2) & 3) as usize
    }

    /// Phase at the start.
    #[inline(always)]
    pub fn start(b: u8) -> Phase {
        phase(b & 3)
    }

    /// Phase after switch `j` (< `MAX_SWITCHES`).
    #[inline(always)]
    pub fn after(b: u8, j: usize) -> Phase {
        phase((b >> (4 + 2 * j)) & 3)
    }

    /// Phase at the end.
    pub fn end(b: u8) -> Phase {
        match switches(b) {
            0 => start(b),
            n => after(b, n.min(MAX_SWITCHES) - 1),
        }
    }

    /// Add a switch to `phase` at fraction `f` (after the others); more than `MAX_SWITCHES`
    /// inside one sample: the last one wins.
    pub fn add<T: Copy>(b: &mut u8, fr: &mut [T; MAX_SWITCHES], f: T, phase: Phase) {
        let n = switches(*b);
        let j = if n < MAX_SWITCHES {
            n
        } else {
            MAX_SWITCHES - 1
        };
        fr[j] = f;
        let shift = 4 + 2 * j;
        let count = (j + 1) as u8;
        *b = (*b & !(0x0C | (3 << shift))) | (count << 2) | (code(phase) << shift);
    }
}

/// One slot of the history: sample k's inputs and state, and the interval from k to k + 1
/// (28 bytes in f32).
#[derive(Debug, Clone, Copy)]
struct Slot<T> {
    /// Table acceleration at the sample.
    u: T,
    /// State at the sample.
    z: [T; 2],
    /// Measured top acceleration at the sample (NaN: none).
    y: T,
    /// Fractions of the interval's switches (the first `packed::switches(iv)` are valid).
    fr: [T; MAX_SWITCHES],
    /// The interval's phases ([`packed`]).
    iv: u8,
}

/// Settings of the estimator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StickSlipConfig {
    /// Identify μ online.
    pub identify_mu: bool,
    /// Let the model adopt the identified μ (at the start of each sliding episode).
    pub use_identified_mu: bool,
    /// RLS forgetting factor λ in (0, 1].
    pub forgetting: f64,
    /// RLS samples before μ̂ is adopted.
    pub min_samples: u32,
}

impl StickSlipConfig {
    /// The defaults (also [`Default`]): identify μ, do not adopt it, λ = 0.9999, 2000 samples.
    pub const DEFAULT: Self = Self {
        identify_mu: true,
        use_identified_mu: false,
        forgetting: 0.9999,
        min_samples: 2000,
    };
}

impl Default for StickSlipConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The history (samples) that accepts events up to `max_age_samples` old: `max_age_samples + 2`
/// (an event `a` samples old lies in the interval `⌊a⌋ + 1` samples back, whose start sample must
/// still be kept).
pub const fn history_for_age(max_age_samples: usize) -> usize {
    max_age_samples + 2
}

/// The identified friction coefficient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MuEstimate {
    /// μ̂.
    pub mu: f64,
    /// Standard deviation of μ̂.
    pub std: f64,
    /// Samples used.
    pub samples: u32,
}

#[derive(Debug, Clone, Copy)]
/// Recursive least squares for one parameter with forgetting λ, in information form:
/// a = λa + φ², b = λb + φ·t, μ̂ = b/a (the classic RLS gain form in exact arithmetic, P = 1/a;
/// one division per sample instead of two). `e2` tracks the a-priori residual's mean square.
struct Rls<T> {
    mu: T,
    a: T,
    b: T,
    lambda: T,
    e2: T,
    n: u32,
}

/// The estimator's coefficients for one structure and sample rate, in precision `T`: computed
/// in f64 and rounded ([`Self::new`]), or, in f32, restored from their bits
/// ([`StickSlipCoefficients::from_bits`]) — e.g. computed by a build script, so that a firmware
/// image needs no f64 start-up code.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StickSlipCoefficients<T> {
    // `phi_s` and `phi_f` hold Φ − I.
    phi_s: [T; 4],
    force_s: [T; 2],
    phi_f: [T; 4],
    /// B0 + B1 (applies to u0).
    b0: [T; 2],
    /// B1 (applies to u1 − u0).
    b1: [T; 2],
    ks: Kernel<T>,
    kf: Kernel<T>,
    p: T,
    two_xi: T,
    mp: T,
    g: T,
    dt: T,
    rate: T,
    /// The structure's μ (the model's μ until μ̂ is adopted).
    mu: T,
}

impl<T: Real> StickSlipCoefficients<T> {
    /// The coefficients of `structure` sampled at `sample_rate_hz` (computed in f64).
    pub fn new(structure: &Structure, sample_rate_hz: f64) -> Result<Self, Error> {
        crate::error::check(
            Param::SampleRate,
            sample_rate_hz,
            sample_rate_hz > 0.0,
            "sample rate > 0 Hz",
        )?;
        let dt = 1.0 / sample_rate_hz;
        let (p, xi, m) = (structure.p(), structure.xi(), structure.mass_ratio());
        let ks64 = Kernel::<f64>::new(structure);
        let kf64 = Kernel::<f64>::fixed_base(structure);
        let fs = ks64.eval::<crate::math::Libm>(dt);
        let ff = kf64.eval::<crate::math::Libm>(dt);
        let phi_s = [fs.ecp, p * fs.es, -m * p * fs.es, fs.ecm];
        let phi_f = [ff.ecp, p * ff.es, -p * ff.es, ff.ecm];
        // Fixed-base input map: z1 = Φf (z0 − zp(0)) + zp(Δt), c1 = (u1 − u0)/Δt.
        let affine = |u0: f64, u1: f64| {
            let c1 = (u1 - u0) / dt;
            let zp0 = [-u0 + 2.0 * xi * c1 / p, -c1 / p];
            let zp1 = [-u1 + 2.0 * xi * c1 / p, -c1 / p];
            [
                -(phi_f[0] * zp0[0] + phi_f[1] * zp0[1]) + zp1[0],
                -(phi_f[2] * zp0[0] + phi_f[3] * zp0[1]) + zp1[1],
            ]
        };
        let (b0, b1) = (affine(1.0, 0.0), affine(0.0, 1.0));
        let t = |x: f64| T::from_f64(x);
        // Per-sample maps in increment form, Φ − I (the diagonal as −(1 − e^{-aτ}C ∓ …)
        // computed in f64): fine sampling keeps its relative accuracy in f32.
        let t4 = |a: [f64; 4]| [t(a[0] - 1.0), t(a[1]), t(a[2]), t(a[3] - 1.0)];
        Ok(Self {
            phi_s: t4(phi_s),
            force_s: [t(-(1.0 - fs.ecp)), t(-m * p * fs.es)],
            phi_f: t4(phi_f),
            // Input map as Bsum·u0 + B1·(u1 − u0): B0 ≈ −B1 are large at fine sampling and
            // would cancel; their sum (the per-sample gain) is small and computed in f64.
            b0: [t(b0[0] + b1[0]), t(b0[1] + b1[1])],
            b1: [t(b1[0]), t(b1[1])],
            ks: Kernel::new(structure),
            kf: Kernel::fixed_base(structure),
            p: t(p),
            two_xi: t(2.0 * xi),
            mp: t(m * p),
            g: t(structure.g()),
            dt: t(dt),
            rate: t(sample_rate_hz),
            mu: t(structure.mu()),
        })
    }
}

fn regime_code(r: Regime) -> u32 {
    match r {
        Regime::Underdamped => 0,
        Regime::Critical => 1,
        Regime::Overdamped => 2,
    }
}

impl StickSlipCoefficients<f32> {
    /// Length of [`Self::to_bits`].
    pub const BITS: usize = 35;

    /// The coefficients as words: the f32 values' bits (21 scalars, then each kernel's 5
    /// values), the kernels' regimes (0 underdamped, 1 critical, 2 overdamped) and flags.
    pub fn to_bits(&self) -> [u32; Self::BITS] {
        let mut v = [0u32; Self::BITS];
        let scalars = [
            self.phi_s[0],
            self.phi_s[1],
            self.phi_s[2],
            self.phi_s[3],
            self.force_s[0],
            self.force_s[1],
            self.phi_f[0],
            self.phi_f[1],
            self.phi_f[2],
            self.phi_f[3],
            self.b0[0],
            self.b0[1],
            self.b1[0],
            self.b1[1],
            self.p,
            self.two_xi,
            self.mp,
            self.g,
            self.dt,
            self.rate,
            self.mu,
        ];
        let (rs, cs, os) = self.ks.to_parts();
        let (rf, cf, of) = self.kf.to_parts();
        for (d, x) in v.iter_mut().zip(scalars.iter().chain(&cs).chain(&cf)) {
            *d = x.to_bits();
        }
        v[31] = regime_code(rs);
        v[32] = regime_code(rf);
        v[33] = u32::from(os);
        v[34] = u32::from(of);
        v
    }

    /// The coefficients from [`Self::to_bits`]; `None` for an invalid regime or flag word.
    pub fn from_bits(v: &[u32; Self::BITS]) -> Option<Self> {
        let f = |i: usize| f32::from_bits(v[i]);
        let regime = |w: u32| match w {
            0 => Some(Regime::Underdamped),
            1 => Some(Regime::Critical),
            2 => Some(Regime::Overdamped),
            _ => None,
        };
        let flag = |w: u32| match w {
            0 => Some(false),
            1 => Some(true),
            _ => None,
        };
        let kernel = |at: usize, r: u32, o: u32| {
            Some(Kernel::from_parts(
                regime(r)?,
                [f(at), f(at + 1), f(at + 2), f(at + 3), f(at + 4)],
                flag(o)?,
            ))
        };
        Some(Self {
            phi_s: [f(0), f(1), f(2), f(3)],
            force_s: [f(4), f(5)],
            phi_f: [f(6), f(7), f(8), f(9)],
            b0: [f(10), f(11)],
            b1: [f(12), f(13)],
            p: f(14),
            two_xi: f(15),
            mp: f(16),
            g: f(17),
            dt: f(18),
            rate: f(19),
            mu: f(20),
            ks: kernel(21, v[31], v[33])?,
            kf: kernel(26, v[32], v[34])?,
        })
    }
}

/// The stick-slip aware estimator with up to `H` samples of history (the longest back-dating):
/// `H` slots of storage, of which [`Self::history`] are used.
#[derive(Debug, Clone)]
pub struct StickSlipEstimator<T: Real, M: Transcendentals<T>, const H: usize> {
    c: StickSlipCoefficients<T>,
    cfg: StickSlipConfig,
    // State.
    mu_use: T,
    /// g·μ_use.
    gmu: T,
    phase: Phase,
    k: u64,
    /// History length in use (2 ..= H).
    len: usize,
    /// Slot of sample k (k mod len).
    pos: usize,
    /// Slot of sample k − 1 (k ≥ 1), or the slot marked [`packed::NO_SAMPLE`] (k = 0).
    prev: usize,
    /// Identify on the delayed sample (μ identification on, and the history is full).
    ident: bool,
    hist: [Slot<T>; H],
    // Identification (on delayed, final samples).
    rls: Rls<T>,
    zh: [T; 2],
    zu: [T; 2],
    episode: bool,
    _m: PhantomData<M>,
}

#[inline(always)]
fn mat<T: Real>(m: &[T; 4], z: [T; 2]) -> [T; 2] {
    [m[0] * z[0] + m[1] * z[1], m[2] * z[0] + m[3] * z[1]]
}

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
    /// samples old are accepted, and μ is identified on samples `history − 2` samples old. The
    /// same `history` gives the same results whatever the storage `H`.
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
        crate::error::check(
            Param::EventTime,
            cfg.forgetting,
            cfg.forgetting > 0.0 && cfg.forgetting <= 1.0,
            "forgetting factor in (0, 1]",
        )?;
        if history < 2 || history > H {
            return Err(Error::OutOfRange {
                param: Param::EventTime,
                value: history as f64,
                expected: "a history of at least 2 samples, at most the storage H",
            });
        }
        let mut hist = [Slot {
            u: T::ZERO,
            z: [T::ZERO; 2],
            y: T::ZERO,
            fr: [T::ZERO; MAX_SWITCHES],
            iv: packed::new(0),
        }; H];
        // Sample 0 has no interval before it: the slot before it is marked.
        if let Some(s) = hist.get_mut(history - 1) {
            s.iv = packed::NO_SAMPLE;
        }
        Ok(Self {
            c,
            cfg,
            mu_use: c.mu,
            gmu: c.g * c.mu,
            phase: 0,
            k: 0,
            len: history,
            pos: 0,
            prev: history - 1,
            ident: false,
            hist,
            rls: Rls {
                mu: c.mu,
                // P0 = 1: a0 = 1, b0 = μ0.
                a: T::ONE,
                b: c.mu,
                lambda: T::from_f64(cfg.forgetting),
                e2: T::from_f64(1e-4),
                n: 0,
            },
            zh: [T::ZERO; 2],
            zu: [T::ZERO; 2],
            episode: false,
            _m: PhantomData,
        })
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

    /// The current phase (0 stuck, ±1 friction level while sliding).
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The μ the model uses now.
    pub fn mu_used(&self) -> f64 {
        self.mu_use.to_f64()
    }

    /// The identified μ, with its standard deviation (None before any sliding sample was used).
    pub fn mu_estimate(&self) -> Option<MuEstimate> {
        (self.rls.n > 0).then(|| {
            let var = (self.rls.e2 / self.rls.a).to_f64();
            MuEstimate {
                mu: self.rls.mu.to_f64(),
                std: libm::sqrt(var.max(0.0)),
                samples: self.rls.n,
            }
        })
    }

    /// Index of the sample the next [`Self::update`] returns.
    pub fn sample_index(&self) -> u64 {
        self.k
    }

    /// The slot `back` (1 ..= history) samples before sample k.
    #[inline(always)]
    fn slot_back(&self, back: usize) -> usize {
        if back <= self.pos {
            self.pos - back
        } else {
            self.pos + self.len - back
        }
    }

    /// The prediction of an earlier sample as revised by the events pushed since (the history
    /// re-simulated from each late event): `None` outside the kept history. A sample older than the
    /// longest detection latency is final.
    pub fn prediction_at(&self, sample: u64) -> Option<T> {
        if sample >= self.k || self.k - sample > self.len as u64 {
            return None;
        }
        let z = self.hist.get(self.slot_back((self.k - sample) as usize))?.z;
        Some(-(z[0] + self.c.two_xi * z[1]))
    }

    /// One piece of an interval: from fraction `fa` to `fb` in `phase`, with table accelerations
    /// `u0`, `u1` at the interval's ends; `mu` scales the friction (0: free vibration only).
    fn piece(&self, z: [T; 2], phase: Phase, (fa, fb): (T, T), (u0, u1): (T, T), mu: T) -> [T; 2] {
        let c = &self.c;
        let tau = (fb - fa) * c.dt;
        if phase == 0 {
            let c1 = (u1 - u0) * c.rate;
            let c0 = u0 + fa * (u1 - u0);
            let lin = c.two_xi * c1 / c.p;
            let zp0 = [-c0 + lin, -(c1 / c.p)];
            let zpt = [-(c0 + c1 * tau) + lin, -(c1 / c.p)];
            let f = c.kf.eval::<M>(tau);
            let m = [f.ecp, c.p * f.es, -(c.p * f.es), f.ecm];
            let w = mat(&m, [z[0] - zp0[0], z[1] - zp0[1]]);
            [w[0] + zpt[0], w[1] + zpt[1]]
        } else {
            let v = -(T::from_f64(phase as f64) * c.g * mu);
            let f = c.ks.eval::<M>(tau);
            let m = [f.ecp, c.p * f.es, -(c.mp * f.es), f.ecm];
            let w = mat(&m, [z[0] - v, z[1]]);
            [w[0] + v, w[1]]
        }
    }

    /// An interval with switches, piece by piece.
    #[inline(never)]
    fn step_switched(
        &self,
        z: [T; 2],
        (u0, u1): (T, T),
        iv: u8,
        fr: &[T; MAX_SWITCHES],
        mu: T,
    ) -> [T; 2] {
        let (mut z, mut ph, mut fa) = (z, packed::start(iv), T::ZERO);
        for (j, &fs) in fr.iter().enumerate().take(packed::switches(iv)) {
            z = self.piece(z, ph, (fa, fs), (u0, u1), mu);
            ph = packed::after(iv, j);
            fa = fs;
        }
        self.piece(z, ph, (fa, T::ONE), (u0, u1), mu)
    }

    /// The fixed-base (stuck) map over one whole interval.
    #[inline(always)]
    fn step_stuck(&self, z: [T; 2], u0: T, u1: T) -> [T; 2] {
        let c = &self.c;
        let w = mat(&c.phi_f, z);
        let du = u1 - u0;
        [
            z[0] + (w[0] + c.b0[0] * u0 + c.b1[0] * du),
            z[1] + (w[1] + c.b0[1] * u0 + c.b1[1] * du),
        ]
    }

    /// The sliding map without friction (the free vibration).
    #[inline(always)]
    fn step_free(&self, z: [T; 2]) -> [T; 2] {
        let w = mat(&self.c.phi_s, z);
        [z[0] + w[0], z[1] + w[1]]
    }

    /// The sliding map over one whole interval with the friction force `f` = ±g·μ.
    #[inline(always)]
    fn step_sliding(&self, z: [T; 2], f: T) -> [T; 2] {
        let c = &self.c;
        let w = mat(&c.phi_s, z);
        [
            z[0] + (w[0] + f * c.force_s[0]),
            z[1] + (w[1] + f * c.force_s[1]),
        ]
    }

    /// State at the end of an interval (phases `iv`, switch fractions `fr`) from its start, the
    /// friction scaled by `mu` (`gmu` = g·`mu`).
    #[inline(always)]
    fn step(
        &self,
        z: [T; 2],
        (u0, u1): (T, T),
        iv: u8,
        fr: &[T; MAX_SWITCHES],
        (mu, gmu): (T, T),
    ) -> [T; 2] {
        if packed::switches(iv) != 0 {
            return self.step_switched(z, (u0, u1), iv, fr, mu);
        }
        match iv & 3 {
            0 => self.step_stuck(z, u0, u1),
            // (±1·g)·μ = ±(g·μ) exactly.
            1 => self.step_sliding(z, gmu),
            _ => self.step_sliding(z, -gmu),
        }
    }

    /// Process sample k: `table_accel` is the measured table acceleration (m/s²), `measured_top`
    /// the measured top acceleration (for μ identification; NaN to skip). A non-finite table
    /// acceleration is replaced by the previous one (flag it upstream). Returns the predicted ü1.
    #[inline]
    pub fn update(&mut self, table_accel: T, measured_top: T) -> T {
        let Some(s) = self.hist.get(self.prev) else {
            return T::ZERO;
        };
        // A switch inside the last interval, or sample 0 (the slot before it holds the
        // [`packed::NO_SAMPLE`] mark): the cold path.
        if s.iv & 0x0C != 0 {
            return self.update_cold(table_accel, measured_top);
        }
        let u0 = s.u;
        let u = if table_accel.is_finite() {
            table_accel
        } else {
            u0
        };
        let z = match s.iv & 3 {
            0 => self.step_stuck(s.z, u0, u),
            // (±1·g)·μ = ±(g·μ) exactly.
            1 => self.step_sliding(s.z, self.gmu),
            _ => self.step_sliding(s.z, -self.gmu),
        };
        self.store(u, z, measured_top)
    }

    /// [`Self::update`] of sample 0 (at rest) or after an interval with switches.
    #[cold]
    #[inline(never)]
    fn update_cold(&mut self, table_accel: T, measured_top: T) -> T {
        let Some(s) = self.hist.get(self.prev) else {
            return T::ZERO;
        };
        if s.iv & 0x0C == packed::NO_SAMPLE {
            let u = if table_accel.is_finite() {
                table_accel
            } else {
                T::ZERO
            };
            return self.store(u, [T::ZERO; 2], measured_top);
        }
        let u0 = s.u;
        let u = if table_accel.is_finite() {
            table_accel
        } else {
            u0
        };
        let z = self.step_switched(s.z, (u0, u), s.iv, &s.fr, self.mu_use);
        self.store(u, z, measured_top)
    }

    /// Store sample k with its table acceleration `u` and state `z`, identify on the delayed
    /// sample, advance; returns the prediction.
    #[inline(always)]
    fn store(&mut self, u: T, z: [T; 2], measured_top: T) -> T {
        let idx = self.pos;
        let len = self.len;
        let phase = self.phase;
        if let Some(s) = self.hist.get_mut(idx) {
            s.u = u;
            s.z = z;
            s.y = measured_top;
            s.iv = packed::new(phase);
        }
        // Sample d = k + 2 − history (slot idx + 2): its interval (from d − 1, the oldest sample
        // kept, slot idx + 1) can no longer be changed by a late event (events reach back to
        // interval k + 1 − history + 1 at most). From k = history − 1 on.
        let next = if idx + 1 >= len {
            self.ident = self.cfg.identify_mu;
            0
        } else {
            idx + 1
        };
        if self.ident {
            let b = if next + 1 >= len { 0 } else { next + 1 };
            self.identify(next, b);
        }
        self.k += 1;
        self.prev = idx;
        self.pos = next;
        -(z[0] + self.c.two_xi * z[1])
    }

    /// A phase change detected late: the base entered `phase` (0 stuck, ±1 friction level)
    /// `age_samples` ≥ 0 sample intervals before the sample the next [`Self::update`] returns.
    /// Push events in chronological order. Events older than the history (`history − 2`
    /// samples; older ones may be accepted when they fall on a sample) are an error.
    pub fn push_event(&mut self, phase: Phase, age_samples: T) -> Result<(), Error> {
        if !(-1..=1).contains(&phase) {
            return Err(Error::OutOfRange {
                param: Param::ReversalSign,
                value: phase as f64,
                expected: "a phase of -1, 0 or 1",
            });
        }
        if !age_samples.is_finite() || age_samples < T::ZERO {
            return Err(Error::OutOfRange {
                param: Param::EventTime,
                value: age_samples.to_f64(),
                expected: "a finite age >= 0 samples",
            });
        }
        let k = self.k;
        if age_samples == T::ZERO || k == 0 {
            self.phase = phase;
            return Ok(());
        }
        // The event lies in interval i (from sample i to i + 1) at fraction f, or at sample i:
        // `back` = k − i samples before sample k.
        let whole = age_samples.floor();
        let frac = age_samples - whole;
        let (back, f) = if frac == T::ZERO {
            (whole.to_usize_sat(), T::ZERO)
        } else {
            (whole.to_usize_sat().saturating_add(1), T::ONE - frac)
        };
        // i ≥ max(k − history + 1, 0).
        let limit = if k < self.len as u64 {
            k as usize
        } else {
            self.len - 1
        };
        if back > limit {
            return Err(Error::OutOfRange {
                param: Param::EventTime,
                value: age_samples.to_f64(),
                expected: "an age within the estimator's history",
            });
        }
        let mut si = self.slot_back(back);
        let code = packed::new(phase);
        if let Some(s) = self.hist.get_mut(si) {
            if f == T::ZERO {
                s.iv = code;
            } else {
                packed::add(&mut s.iv, &mut s.fr, f, phase);
            }
        }
        // Re-simulate intervals i .. k − 1 with the new phases (interval i + 1 onwards: `phase`).
        let mu = (self.mu_use, self.gmu);
        for _ in 1..back {
            let sb = if si + 1 >= self.len { 0 } else { si + 1 };
            let (Some(a), Some(b)) = (self.hist.get(si), self.hist.get(sb)) else {
                break;
            };
            let z = self.step(a.z, (a.u, b.u), a.iv, &a.fr, mu);
            if let Some(b) = self.hist.get_mut(sb) {
                b.z = z;
                b.iv = code;
            }
            si = sb;
        }
        self.phase = phase;
        Ok(())
    }

    /// Friction identification on sample d (slot `b`; its interval from d − 1, slot `a`, is
    /// final).
    #[inline(always)]
    fn identify(&mut self, a: usize, b: usize) {
        let (Some(sa), Some(sb)) = (self.hist.get(a), self.hist.get(b)) else {
            return;
        };
        let iv = sa.iv;
        // Sliding throughout: no switch, a sliding start phase.
        if self.episode && iv & 0x0F != 0 && iv & 0x0C == 0 {
            let y = sb.y;
            // z_h: free vibration (μ = 0); z_u: the response per unit μ (force ±g).
            let g = if iv & 3 == 1 { self.c.g } else { -self.c.g };
            let zh = self.step_free(self.zh);
            let zu = self.step_sliding(self.zu, g);
            self.zh = zh;
            self.zu = zu;
            if y.is_finite() {
                let phi = -(zu[0] + self.c.two_xi * zu[1]);
                let target = y + (zh[0] + self.c.two_xi * zh[1]);
                let r = &mut self.rls;
                let e = target - r.mu * phi;
                r.a = r.lambda * r.a + phi * phi;
                r.b = r.lambda * r.b + phi * target;
                r.mu = r.b / r.a;
                r.e2 = r.e2 + (e * e - r.e2) * T::from_f64(1e-3);
                r.n = r.n.saturating_add(1);
            }
        } else if packed::end(iv) != 0 {
            // A sliding episode starts at sample d: z = z_h + μ·z_u with z_u = 0.
            let zb = sb.z;
            if self.cfg.use_identified_mu && self.rls.n >= self.cfg.min_samples {
                self.mu_use = self.rls.mu;
                self.gmu = self.c.g * self.mu_use;
            }
            self.zh = zb;
            self.zu = [T::ZERO; 2];
            self.episode = true;
        } else {
            self.episode = false;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{F32Poly, Libm};
    use crate::structure::StructureParams;

    fn structure(mu: f64, xi: f64) -> Structure {
        Structure::new(StructureParams {
            m1_kg: 29.5,
            m2_kg: 1.75,
            natural_frequency_hz: 7.0,
            damping_ratio: xi,
            friction_coefficient: mu,
            gravity_m_s2: 9.80665,
        })
        .unwrap()
    }

    /// Table acceleration and measured top acceleration of sample k.
    fn inputs(k: u64) -> (f32, f32) {
        let t = k as f32 * 1e-4;
        (2.0 * (43.9 * t).sin(), 1.5 * (40.0 * t).cos())
    }

    /// (sample, phase, age) events: slip, stick, slip back, old stick, slip.
    const EVENTS: [(u64, i8, f32); 6] = [
        (40, 1, 0.25),
        (300, 0, 100.5),
        (330, -1, 3.75),
        (700, 0, 60.0),
        (705, 1, 0.0),
        (720, 1, 2.5),
    ];

    fn drive<const H: usize>(
        est: &mut StickSlipEstimator<f32, F32Poly, H>,
        n: u64,
    ) -> std::vec::Vec<u32> {
        (0..n)
            .map(|k| {
                for &(_, p, a) in EVENTS.iter().filter(|e| e.0 == k) {
                    est.push_event(p, a).unwrap();
                }
                let (u, y) = inputs(k);
                est.update(u, y).to_bits()
            })
            .collect()
    }

    #[test]
    fn coefficients_round_trip_through_their_bits() {
        for xi in [0.05, 0.0, 0.99, 0.5] {
            let s = structure(0.2, xi);
            let c = StickSlipCoefficients::<f32>::new(&s, 1e4).unwrap();
            let back = StickSlipCoefficients::<f32>::from_bits(&c.to_bits()).unwrap();
            assert_eq!(back.to_bits(), c.to_bits());
            let mut bad = c.to_bits();
            bad[31] = 3;
            assert!(StickSlipCoefficients::<f32>::from_bits(&bad).is_none());
        }
        let s = structure(0.2, 0.05);
        let cfg = StickSlipConfig::DEFAULT;
        let mut a = StickSlipEstimator::<f32, F32Poly, 200>::new(&s, 1e4, cfg).unwrap();
        let c = StickSlipCoefficients::<f32>::from_bits(&a.coefficients().to_bits()).unwrap();
        let mut b =
            StickSlipEstimator::<f32, F32Poly, 200>::from_coefficients(c, cfg, 200).unwrap();
        assert_eq!(drive(&mut a, 3000), drive(&mut b, 3000));
    }

    #[test]
    fn the_history_length_not_the_storage_decides() {
        let s = structure(0.2, 0.05);
        let cfg = StickSlipConfig {
            use_identified_mu: true,
            min_samples: 100,
            ..StickSlipConfig::DEFAULT
        };
        let mut a = StickSlipEstimator::<f32, F32Poly, 144>::new(&s, 1e4, cfg).unwrap();
        let mut b =
            StickSlipEstimator::<f32, F32Poly, 512>::with_history(&s, 1e4, cfg, 144).unwrap();
        assert_eq!(b.history(), 144);
        assert_eq!(drive(&mut a, 5000), drive(&mut b, 5000));
        let (ma, mb) = (a.mu_estimate().unwrap(), b.mu_estimate().unwrap());
        assert_eq!((ma.mu, ma.std, ma.samples), (mb.mu, mb.std, mb.samples));
        for d in 0..150 {
            assert_eq!(
                a.prediction_at(4999 - d).map(f32::to_bits),
                b.prediction_at(4999 - d).map(f32::to_bits)
            );
        }
        assert!(a.prediction_at(5000 - 145).is_none() && a.prediction_at(5000).is_none());
        assert!(StickSlipEstimator::<f32, F32Poly, 64>::with_history(&s, 1e4, cfg, 65).is_err());
        assert!(StickSlipEstimator::<f32, F32Poly, 64>::with_history(&s, 1e4, cfg, 1).is_err());
    }

    #[test]
    fn events_within_the_history_are_accepted() {
        let s = structure(0.2, 0.05);
        let mut e =
            StickSlipEstimator::<f64, Libm, 64>::new(&s, 1e4, StickSlipConfig::DEFAULT).unwrap();
        for k in 0..10 {
            e.update(0.1, f64::NAN);
            // Back to sample 0, not before it (the next sample is k + 1).
            assert!(e.push_event(1, k as f64 + 1.5).is_err());
            assert!(e.push_event(1, k as f64 + 1.0).is_ok());
            assert!(e.push_event(1, k as f64 + 0.5).is_ok());
        }
        for _ in 0..100 {
            e.update(0.1, f64::NAN);
        }
        // history 64: an age < 63 samples, or exactly 63 (on a sample), is accepted.
        for age in [0.0, 0.5, 1.0, 61.5, 62.0, 62.75, 63.0] {
            assert!(e.push_event(0, age).is_ok(), "{age}");
        }
        for age in [63.5, 64.0, 1e9, f64::INFINITY, f64::NAN, -1.0] {
            assert!(e.push_event(0, age).is_err(), "{age}");
        }
        assert!(e.push_event(2, 1.0).is_err());
    }

    #[test]
    fn identifies_mu_from_a_sliding_response() {
        // The measured top acceleration: the model itself with μ = 0.2, sliding back and forth;
        // the estimator starts from μ = 0.25.
        let (truth_s, model_s) = (structure(0.2, 0.05), structure(0.25, 0.05));
        let cfg = StickSlipConfig {
            identify_mu: false,
            ..StickSlipConfig::DEFAULT
        };
        let mut truth = StickSlipEstimator::<f64, Libm, 64>::new(&truth_s, 1e4, cfg).unwrap();
        let mut est =
            StickSlipEstimator::<f64, Libm, 64>::new(&model_s, 1e4, StickSlipConfig::DEFAULT)
                .unwrap();
        for k in 0..40_000u64 {
            if k % 700 == 0 {
                let p = if (k / 700) % 2 == 0 { 1 } else { -1 };
                truth.push_event(p, 0.0).unwrap();
                est.push_event(p, 0.0).unwrap();
            }
            let t = k as f64 * 1e-4;
            let u = 2.0 * (43.9 * t).sin();
            let y = truth.update(u, f64::NAN);
            est.update(u, y);
        }
        let m = est.mu_estimate().unwrap();
        assert!((m.mu - 0.2).abs() < 1e-6, "{m:?}");
        assert!(m.std >= 0.0 && m.std < 1e-3, "{m:?}");
        assert_eq!(est.mu_used(), 0.25);
    }
}
