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
//!
//! **Friction identification.** While the base slides, z = z_h + μ·z_u, where z_h is the free
//! evolution of the state at the start of the sliding episode and z_u the response to the friction
//! per unit μ: ü1 is linear in μ. On samples that are `H − 1` samples old (their phase is final) the
//! estimator runs both parts and updates μ̂ by recursive least squares with forgetting λ from the
//! measured top acceleration against the unit-μ prediction; its standard deviation comes from the
//! residual variance. With `use_identified_mu` the model adopts μ̂ at the start of each sliding
//! episode once it has enough samples.

use crate::error::{Error, Param};
use crate::free_vibration::Kernel;
use crate::math::{Real, Transcendentals};
use crate::structure::Structure;
use core::marker::PhantomData;

/// Phase changes kept per sample interval.
pub const MAX_SWITCHES: usize = 2;

/// Contact phase: 0 stuck, +1 or −1 the friction level F/F0 while sliding (friction opposes slip).
pub type Phase = i8;

#[derive(Debug, Clone, Copy, PartialEq)]
struct Interval<T> {
    /// Phase at the start of the interval.
    start: Phase,
    /// Number of switches.
    n: u8,
    /// (fraction of the interval in (0, 1), new phase), increasing fractions.
    sw: [(T, Phase); MAX_SWITCHES],
}

impl<T: Real> Interval<T> {
    fn new(start: Phase) -> Self {
        Self {
            start,
            n: 0,
            sw: [(T::ZERO, 0); MAX_SWITCHES],
        }
    }
    fn end(&self) -> Phase {
        match self.n {
            0 => self.start,
            n => self.sw[(n as usize).min(MAX_SWITCHES) - 1].1,
        }
    }
    fn add(&mut self, f: T, phase: Phase) {
        let n = self.n as usize;
        if n < MAX_SWITCHES {
            self.sw[n] = (f, phase);
            self.n += 1;
        } else {
            // More changes inside one sample than kept: the last one wins.
            self.sw[MAX_SWITCHES - 1] = (f, phase);
        }
    }
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

impl Default for StickSlipConfig {
    fn default() -> Self {
        Self {
            identify_mu: true,
            use_identified_mu: false,
            forgetting: 0.9999,
            min_samples: 2000,
        }
    }
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
struct Rls<T> {
    mu: T,
    p: T,
    lambda: T,
    e2: T,
    n: u32,
}

/// The stick-slip aware estimator with `H` samples of history (the longest back-dating).
#[derive(Debug, Clone)]
pub struct StickSlipEstimator<T: Real, M: Transcendentals<T>, const H: usize> {
    // Coefficients (computed once, f64 → T). `phi_s` and `phi_f` hold Φ − I.
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
    cfg: StickSlipConfig,
    // State.
    mu_use: T,
    phase: Phase,
    k: u64,
    u: [T; H],
    z: [[T; 2]; H],
    y: [T; H],
    iv: [Interval<T>; H],
    // Identification (on delayed, final samples).
    rls: Rls<T>,
    zh: [T; 2],
    zu: [T; 2],
    episode: bool,
    _m: PhantomData<M>,
}

#[inline]
fn mat<T: Real>(m: &[T; 4], z: [T; 2]) -> [T; 2] {
    [m[0] * z[0] + m[1] * z[1], m[2] * z[0] + m[3] * z[1]]
}

impl<T: Real, M: Transcendentals<T>, const H: usize> StickSlipEstimator<T, M, H> {
    /// Build the estimator for `structure` sampled at `sample_rate_hz`, the base stuck, at rest.
    pub fn new(
        structure: &Structure,
        sample_rate_hz: f64,
        cfg: StickSlipConfig,
    ) -> Result<Self, Error> {
        crate::error::check(
            Param::SampleRate,
            sample_rate_hz,
            sample_rate_hz > 0.0,
            "sample rate > 0 Hz",
        )?;
        crate::error::check(
            Param::EventTime,
            cfg.forgetting,
            cfg.forgetting > 0.0 && cfg.forgetting <= 1.0,
            "forgetting factor in (0, 1]",
        )?;
        if H < 2 {
            return Err(Error::OutOfRange {
                param: Param::EventTime,
                value: H as f64,
                expected: "a history of at least 2 samples",
            });
        }
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
            cfg,
            mu_use: t(structure.mu()),
            phase: 0,
            k: 0,
            u: [T::ZERO; H],
            z: [[T::ZERO; 2]; H],
            y: [T::ZERO; H],
            iv: [Interval::new(0); H],
            rls: Rls {
                mu: t(structure.mu()),
                p: T::ONE,
                lambda: t(cfg.forgetting),
                e2: t(1e-4),
                n: 0,
            },
            zh: [T::ZERO; 2],
            zu: [T::ZERO; 2],
            episode: false,
            _m: PhantomData,
        })
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
            let var = (self.rls.p * self.rls.e2).to_f64();
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

    /// The prediction of an earlier sample as revised by the events pushed since (the history
    /// re-simulated from each late event): `None` outside the kept history. A sample older than the
    /// longest detection latency is final.
    pub fn prediction_at(&self, sample: u64) -> Option<T> {
        if sample >= self.k || self.k - sample > H as u64 {
            return None;
        }
        let z = self.z[Self::slot(sample)];
        Some(-(z[0] + self.two_xi * z[1]))
    }

    /// One piece of an interval: from fraction `fa` to `fb` in `phase`, with table accelerations
    /// `u0`, `u1` at the interval's ends; `mu` scales the friction (0: free vibration only).
    fn piece(&self, z: [T; 2], phase: Phase, (fa, fb): (T, T), (u0, u1): (T, T), mu: T) -> [T; 2] {
        let tau = (fb - fa) * self.dt;
        if phase == 0 {
            let c1 = (u1 - u0) * self.rate;
            let c0 = u0 + fa * (u1 - u0);
            let lin = self.two_xi * c1 / self.p;
            let zp0 = [-c0 + lin, -(c1 / self.p)];
            let zpt = [-(c0 + c1 * tau) + lin, -(c1 / self.p)];
            let f = self.kf.eval::<M>(tau);
            let m = [f.ecp, self.p * f.es, -(self.p * f.es), f.ecm];
            let w = mat(&m, [z[0] - zp0[0], z[1] - zp0[1]]);
            [w[0] + zpt[0], w[1] + zpt[1]]
        } else {
            let v = -(T::from_f64(phase as f64) * self.g * mu);
            let f = self.ks.eval::<M>(tau);
            let m = [f.ecp, self.p * f.es, -(self.mp * f.es), f.ecm];
            let w = mat(&m, [z[0] - v, z[1]]);
            [w[0] + v, w[1]]
        }
    }

    /// State at the end of an interval from its start.
    #[inline]
    fn step(&self, z: [T; 2], u0: T, u1: T, iv: &Interval<T>, mu: T) -> [T; 2] {
        if iv.n == 0 {
            if iv.start == 0 {
                let w = mat(&self.phi_f, z);
                let du = u1 - u0;
                [
                    z[0] + (w[0] + self.b0[0] * u0 + self.b1[0] * du),
                    z[1] + (w[1] + self.b0[1] * u0 + self.b1[1] * du),
                ]
            } else {
                let w = mat(&self.phi_s, z);
                let f = T::from_f64(iv.start as f64) * self.g * mu;
                [
                    z[0] + (w[0] + f * self.force_s[0]),
                    z[1] + (w[1] + f * self.force_s[1]),
                ]
            }
        } else {
            let (mut z, mut ph, mut fa) = (z, iv.start, T::ZERO);
            for &(fs, next) in iv.sw.iter().take(iv.n as usize) {
                z = self.piece(z, ph, (fa, fs), (u0, u1), mu);
                ph = next;
                fa = fs;
            }
            self.piece(z, ph, (fa, T::ONE), (u0, u1), mu)
        }
    }

    #[inline]
    fn slot(k: u64) -> usize {
        (k % H as u64) as usize
    }

    /// Process sample k: `table_accel` is the measured table acceleration (m/s²), `measured_top`
    /// the measured top acceleration (for μ identification; NaN to skip). A non-finite table
    /// acceleration is replaced by the previous one (flag it upstream). Returns the predicted ü1.
    pub fn update(&mut self, table_accel: T, measured_top: T) -> T {
        let k = self.k;
        let idx = Self::slot(k);
        let z = if k == 0 {
            [T::ZERO; 2]
        } else {
            let prev = Self::slot(k - 1);
            let u0 = self.u[prev];
            let u1 = if table_accel.is_finite() {
                table_accel
            } else {
                u0
            };
            self.step(self.z[prev], u0, u1, &self.iv[prev], self.mu_use)
        };
        let u = if table_accel.is_finite() {
            table_accel
        } else if k > 0 {
            self.u[Self::slot(k - 1)]
        } else {
            T::ZERO
        };
        self.u[idx] = u;
        self.z[idx] = z;
        self.y[idx] = measured_top;
        self.iv[idx] = Interval::new(self.phase);
        // Sample d = k + 2 − H: its interval (from d − 1, the oldest sample kept) can no longer be
        // changed by a late event (events reach back to interval k + 1 − H + 1 at most).
        if self.cfg.identify_mu && k + 2 > H as u64 {
            self.identify(k + 2 - H as u64);
        }
        self.k += 1;
        -(z[0] + self.two_xi * z[1])
    }

    /// A phase change detected late: the base entered `phase` (0 stuck, ±1 friction level)
    /// `age_samples` ≥ 0 sample intervals before the sample the next [`Self::update`] returns.
    /// Push events in chronological order. Events older than the history are an error.
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
        let age = age_samples.to_f64();
        let whole = libm::floor(age);
        let frac = age - whole;
        if age == 0.0 || k == 0 {
            self.phase = phase;
            return Ok(());
        }
        // The event lies in interval i (from sample i to i + 1) at fraction f, or at sample i.
        let (i, f) = if frac == 0.0 {
            (k as f64 - whole, 0.0)
        } else {
            (k as f64 - whole - 1.0, 1.0 - frac)
        };
        let oldest = (k as f64 - H as f64 + 1.0).max(0.0);
        if i < oldest {
            return Err(Error::OutOfRange {
                param: Param::EventTime,
                value: age,
                expected: "an age within the estimator's history",
            });
        }
        let i = i as u64;
        let last = k - 1;
        let si = Self::slot(i);
        if f == 0.0 {
            self.iv[si] = Interval::new(phase);
        } else {
            self.iv[si].add(T::from_f64(f), phase);
        }
        for j in (i + 1)..=last {
            self.iv[Self::slot(j)] = Interval::new(phase);
        }
        for j in i..last {
            let (a, b) = (Self::slot(j), Self::slot(j + 1));
            self.z[b] = self.step(self.z[a], self.u[a], self.u[b], &self.iv[a], self.mu_use);
        }
        self.phase = phase;
        Ok(())
    }

    /// Friction identification on sample d (its interval from d − 1 is final).
    fn identify(&mut self, d: u64) {
        if d == 0 {
            return;
        }
        let (a, b) = (Self::slot(d - 1), Self::slot(d));
        let iv = self.iv[a];
        let sliding_throughout = iv.n == 0 && iv.start != 0;
        if self.episode && sliding_throughout {
            self.zh = self.step(self.zh, self.u[a], self.u[b], &iv, T::ZERO);
            self.zu = self.step(self.zu, self.u[a], self.u[b], &iv, T::ONE);
            let phi = -(self.zu[0] + self.two_xi * self.zu[1]);
            let y = self.y[b];
            if y.is_finite() {
                let target = y + (self.zh[0] + self.two_xi * self.zh[1]);
                let r = &mut self.rls;
                let e = target - r.mu * phi;
                let den = r.lambda + phi * phi * r.p;
                let gain = r.p * phi / den;
                r.mu += gain * e;
                r.p = (r.p - gain * phi * r.p) / r.lambda;
                r.e2 = r.e2 + (e * e - r.e2) * T::from_f64(1e-3);
                r.n = r.n.saturating_add(1);
            }
        } else if iv.end() != 0 {
            // A sliding episode starts at sample d: z = z_h + μ·z_u with z_u = 0.
            if self.cfg.use_identified_mu && self.rls.n >= self.cfg.min_samples {
                self.mu_use = self.rls.mu;
            }
            self.zh = self.z[b];
            self.zu = [T::ZERO; 2];
            self.episode = true;
        } else {
            self.episode = false;
        }
    }
}
