//! Online identification of the top oscillator: its natural frequency f and damping ratio ξ
//! from the measured top and base accelerations ([`OscillatorIdentifier`]).
//!
//! **The relation.** The top mass is a free body on its spring and dashpot in every phase, stuck
//! or sliding: ü1 = −p²δ − 2ξpδ' with δ = u1 − u2 (p = 2πf), and δ'' = ü1 − ü2 is measured by
//! the top and base accelerometers. With A = ü1 and R = ü1 − ü2 (Laplace),
//! s²·A = −(p² + 2ξp·s)·R. Both sides are filtered by the same H(s) = λ·s/(s + λ)⁴ (λ: the prior's
//! p), which makes every term proper and removes constant offsets (the zero at s = 0: an offset
//! of either accelerometer, or between them, only adds a decaying transient):
//!
//! Y = λ s³/(s+λ)⁴·A,  Φ1 = λ³ s/(s+λ)⁴·R,  Φ2 = λ² s²/(s+λ)⁴·R,  −Y = θ1·Φ1 + θ2·Φ2,
//!
//! with θ1 = (p/λ)² and θ2 = 2ξp/λ (both of order 1; all three signals are accelerations). With
//! the scaled chain states ξk = (λ/(s+λ))^k·u (each of DC gain 1) the signals are binomial
//! differences: Φ1 = ξ3 − ξ4, Φ2 = ξ2 − 2ξ3 + ξ4, Y = ξ1 − 3ξ2 + 3ξ3 − ξ4 (of A's chain).
//!
//! **Discretisation.** The accelerations are averaged over blocks of `decimation` samples
//! (~500 Hz) and the chains advance exactly (matrix exponential of the Jordan block, computed in
//! f64 at construction) with the block average held over the block. Both sides see the same
//! operator, so the relation holds up to the aliasing of what lies above the decimated Nyquist
//! frequency (the structure's motion lies far below it).
//!
//! **The top accelerometer's gain.** A top accelerometer reading G·ü1 (the base's the reference)
//! turns the relation into s²·A = −(p² + 2ξp·s)·(R + (1 − G)·B) with B = A − R the base
//! acceleration: −Y = θ1·Φ1 + θ2·Φ2 + θ1·κ·Φ1(B) + θ2·κ·Φ2(B), κ = 1 − G. A second least squares
//! on the four regressors (Φ1(B) = Φ1(A) − Φ1, Φ2(B) = Φ2(A) − Φ2: the A chain's, no third
//! chain) gives a = (θ1, θ2, θ1·κ, θ2·κ) and G = 1 − a3/a1, with its standard deviation to
//! first order ([`OscillatorIdentifier::gain_estimate`]: a
//! [`PagedNormal`](crate::least_squares::PagedNormal), solved in f64 when asked). It separates
//! G from the oscillator when the base's motion spans frequencies around p (a record); a single
//! harmonic leaves the four regressors two sinusoids, and G unknown (singular or wide).
//!
//! **Estimation.** θ by recursive least squares in information form with forgetting ρ per
//! block (normal equations S·θ = c, solved each block: one division), the a-priori residual's
//! mean square tracked alongside. The standard deviations are the formal ones, σ²·S⁻¹, inflated
//! by √(blocks per filter time constant) for the correlation the filters put between blocks.
//! A sample flagged missing or saturated repeats the last valid pair.
//!
//! **Start.** The chains start in the steady state of the values before the first sample, the
//! first block's least-squares line extrapolated to its first sample (at rest: the offsets
//! alone), and skip twelve filter time constants of blocks; a run known to start at rest skips
//! four and drops its rows at twelve time constants ([`OscillatorIdentifier::starting_at_rest`]):
//! f̂ from ~0.1 s instead of ~0.3 s at 7 Hz.

use crate::error::{check, check_forgetting, check_sample_rate, Error, Param};
use crate::math::Real;

/// The identified oscillator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OscillatorEstimate {
    /// Natural frequency f (Hz).
    pub natural_frequency_hz: f64,
    /// Its standard deviation (Hz).
    pub natural_frequency_std_hz: f64,
    /// Damping ratio ξ.
    pub damping_ratio: f64,
    /// Its standard deviation.
    pub damping_ratio_std: f64,
    /// Blocks (least-squares updates) used.
    pub blocks: u32,
}

/// Identifies f and ξ of the top oscillator from the top and base accelerations (see the module
/// documentation). Per sample: two additions and a count; per block of `decimation` samples:
/// the two filter chains and one least-squares update.
#[derive(Debug, Clone)]
pub struct OscillatorIdentifier<T, G = ()> {
    decimation: u32,
    count: u32,
    sum_a: T,
    sum_r: T,
    last: (T, T),
    /// The last finite block averages.
    last_block: (T, T),
    /// Chain maps: ξ ← E·(Σ taylor terms)·ξ + gamma·u; `phi[d]` = e^{−λh}(λh)^d/d!.
    /// (During the first block the chains, not started yet, hold in `xa[0]` and `xr[0]` the
    /// block's Σk·a and Σk·r, k the sample's index in it, for their start:
    /// [`Self::start_values`].)
    phi: [T; N],
    gamma: [T; N],
    inv_n: T,
    xa: [T; N],
    xr: [T; N],
    /// Normal equations: S = [[s11, s12], [s12, s22]], c, with forgetting `rho`.
    s: [T; 3],
    c: [T; 2],
    rho: T,
    theta: [T; 2],
    /// Mean square of the a-priori residual (smoothing `alpha`).
    e2: T,
    alpha: T,
    /// Blocks skipped before the filters have settled.
    warmup: u32,
    /// A start at rest's rows are to be dropped at twelve filter time constants
    /// ([`Self::restart`]); the gain fit's rows begin there.
    restart_due: bool,
    /// Blocks seen.
    started: u32,
    blocks: u32,
    lambda: f64,
    /// Correlation inflation of the variances (blocks per filter time constant).
    inflation: f64,
    /// The top accelerometer's gain fit ([`TopGainFit`], with the top's scale for the
    /// oscillator's rows: [`Self::set_top_scale`]), or `()`: none.
    gain: G,
}

/// Length of the filter chains.
const N: usize = 5;
/// Decimated rate the identifier aims at (Hz).
const DECIMATED_RATE_HZ: f64 = 500.0;
/// Blocks skipped at a start at rest ([`OscillatorIdentifier::starting_at_rest`]): their
/// filtered signals still hold what the start's extrapolation missed.
pub const WARMUP_AT_REST: u32 = 4;
/// Blocks back a jump's correction reaches ([`OscillatorIdentifier::jump`]; older: left
/// uncorrected).
pub const JUMP_BLOCKS: u32 = 8;
/// Largest decimation (samples per block).
pub const MAX_DECIMATION: u32 = 64;
/// Fewest samples per block for the top's gain: the point samples' average stands for the
/// block's continuous average less well at lower rates, and the gain fit takes that for a gain.
/// Measured on the RK4 record (`tests.rs`), G comes out 1.3e-3, 1.9e-3, 3.5e-3 and 6.4e-3 low at
/// 10, 5, 2 and 1 kHz (3–6σ), and 4 % low on the default scene's slides at 1 kHz: from 5 kHz
/// (10 samples per block at the identifier's ~500 Hz) on only.
pub const MIN_GAIN_DECIMATION: u32 = 10;

impl<T: Real, G: GainRows<T>> OscillatorIdentifier<T, G> {
    /// An identifier for samples at `sample_rate_hz`, its filters tuned to the prior's natural
    /// frequency `prior_frequency_hz`, forgetting `forgetting` per sample in (0, 1].
    pub fn new(
        sample_rate_hz: f64,
        prior_frequency_hz: f64,
        forgetting: f64,
    ) -> Result<Self, Error> {
        check_sample_rate(sample_rate_hz)?;
        check(
            Param::NaturalFrequency,
            prior_frequency_hz,
            prior_frequency_hz > 0.0 && prior_frequency_hz < sample_rate_hz / 8.0,
            "0 < natural frequency < sample rate / 8",
        )?;
        check_forgetting(forgetting)?;
        let d = libm::floor(sample_rate_hz / DECIMATED_RATE_HZ).clamp(1.0, MAX_DECIMATION as f64);
        let decimation = d as u32;
        let h = d / sample_rate_hz;
        let lambda = 2.0 * core::f64::consts::PI * prior_frequency_hz;
        let x = lambda * h;
        let e = libm::exp(-x);
        // φ_d = e^{−x} x^d / d!; γ_k = x^k/(k−1)! Σ_m (−x)^m/m!/(k + m) (k = 1..4), the scaled
        // chain's response to a unit input held over the block, by its series for x < 1 (no
        // cancellation) and in closed form otherwise.
        let mut phi = [0.0f64; N];
        let mut term = e;
        for (dd, v) in phi.iter_mut().enumerate() {
            *v = term;
            term *= x / (dd as f64 + 1.0);
        }
        let mut gamma = [0.0f64; N];
        for (k1, g) in gamma.iter_mut().enumerate() {
            let k = k1 as f64 + 1.0;
            if x < 1.0 {
                let mut fact = 1.0; // (k−1)!
                for j in 1..=k1 {
                    fact *= j as f64;
                }
                let (mut sum, mut t) = (0.0, 1.0);
                for m in 0..40 {
                    sum += t / (k + m as f64);
                    t *= -x / (m as f64 + 1.0);
                }
                *g = powi(x, k1 as u32 + 1) / fact * sum;
            } else {
                // 1 − e^{−x} Σ_{j<k} x^j/j!
                let (mut sum, mut t) = (0.0, 1.0);
                for j in 0..k1 + 1 {
                    sum += t;
                    t *= x / (j as f64 + 1.0);
                }
                *g = 1.0 - e * sum;
            }
        }
        let blocks_per_tau = libm::fmax(1.0, 1.0 / x);
        Ok(Self {
            decimation,
            count: 0,
            sum_a: T::ZERO,
            sum_r: T::ZERO,
            last: (T::ZERO, T::ZERO),
            last_block: (T::ZERO, T::ZERO),
            phi: phi.map(T::from_f64),
            gamma: gamma.map(T::from_f64),
            inv_n: T::from_f64(1.0 / d),
            xa: [T::ZERO; N],
            xr: [T::ZERO; N],
            s: [T::ZERO; 3],
            c: [T::ZERO; 2],
            rho: T::from_f64(powi(forgetting, decimation)),
            theta: [T::ONE, T::ZERO],
            e2: T::ZERO,
            alpha: T::from_f64(libm::fmin(1.0, 1.0 / (5.0 * blocks_per_tau))),
            // The chains start at the values extrapolated to the first sample
            // (`start_values`): a start at rest, with constant offsets, then starts no
            // transient. Twelve filter time constants let what a start not at rest gives
            // decay; a start at rest needs a few blocks ([`Self::starting_at_rest`]).
            warmup: default_warmup(blocks_per_tau),
            restart_due: false,
            started: 0,
            blocks: 0,
            lambda,
            inflation: blocks_per_tau,
            gain: G::new(powi(forgetting, decimation)),
        })
    }

    /// The identifier for a run that starts at rest: before its first sample the top and the
    /// base read constants (their offsets), and the input starts smoothly (a table's, from rest;
    /// not a jump at the first sample). The chains then start where the first block's line
    /// extrapolates to its first sample, with no transient, and only [`WARMUP_AT_REST`] blocks
    /// are skipped instead of twelve filter time constants: the first estimate comes ~0.25 s
    /// sooner at 7 Hz. At twelve time constants the rows so far are dropped, so that a run
    /// that does not start at rest (a jump at the first sample, a steady oscillation from it)
    /// ends up as without the assumption, bit for bit, and the gain fit starts there. A missing
    /// sample in the first block falls back to the default start and warm-up.
    #[must_use]
    pub fn starting_at_rest(mut self) -> Self {
        if self.started == 0 {
            self.warmup = WARMUP_AT_REST;
            self.restart_due = true;
        }
        self
    }

    /// Blocks of the default warm-up (twelve filter time constants).
    fn default_warmup(&self) -> u32 {
        default_warmup(self.inflation)
    }

    /// Scale the top acceleration by `scale` in the oscillator's rows from the next block on (1
    /// by default; kept by the gain fit: without one, always 1): the model's correction of the top accelerometer's gain, so that f and ξ are
    /// fitted on the corrected top (a top gain 2 % off biased ξ by ∓2 % on the `tests.rs`
    /// record), while the gain fit keeps the measurements as they are. The same as scaling the
    /// input, the chains being linear.
    pub fn set_top_scale(&mut self, scale: T) {
        if scale.is_finite() && scale > T::ZERO {
            self.gain.set_scale(scale);
        }
    }

    /// Samples per block.
    pub fn decimation(&self) -> u32 {
        self.decimation
    }

    /// One sample: the top and base accelerations, `valid` false when the sample is missing or
    /// saturated (the last valid pair is then repeated; a block whose average is not finite
    /// repeats the previous block's).
    #[inline(always)]
    pub fn push(&mut self, top: T, base: T, valid: bool) {
        if valid {
            self.last = (top, top - base);
        }
        if self.started == 0 {
            if !valid {
                self.first_block_gap();
            }
            let k = T::from_f64(self.count as f64);
            self.xa[0] += k * self.last.0;
            self.xr[0] += k * self.last.1;
        }
        self.sum_a += self.last.0;
        self.sum_r += self.last.1;
        self.count += 1;
        if self.count >= self.decimation {
            self.block();
        }
    }

    /// A run of samples: the top and base accelerations, a sample whose top or base is not
    /// finite being missing (as [`Self::push`] with `valid` false). The same results as
    /// [`Self::push`] on each sample, bit for bit; the firmware's batches use it: the run is
    /// taken in parts up to the end of each block (`push_part`).
    #[inline(always)]
    pub fn push_run(&mut self, top: &[T], base: &[T]) {
        let (mut top, mut base) = (top, base);
        loop {
            // (`count` < `decimation` between calls: a full block is processed at once.)
            let room = self.decimation.saturating_sub(self.count).max(1) as usize;
            let n = room.min(top.len()).min(base.len());
            let (Some((t, t_rest)), Some((b, b_rest))) =
                (top.split_at_checked(n), base.split_at_checked(n))
            else {
                return;
            };
            if n == 0 {
                return;
            }
            self.push_part(t, b);
            if self.count < self.decimation {
                // The block is not full: the run is done.
                return;
            }
            self.block();
            (top, base) = (t_rest, b_rest);
        }
    }

    /// Samples of one block (as many tops as bases): summed without testing each sample, then
    /// the relative accelerations' sum tested once. If it is finite, every sample was (an
    /// infinite or NaN term leaves the sum infinite or NaN), so each was valid and the sums are
    /// those of [`Self::push`], same additions in the same order; otherwise (a missing sample,
    /// or an overflow) the part is redone sample by sample ([`Self::push_each`]).
    #[inline(always)]
    fn push_part(&mut self, top: &[T], base: &[T]) {
        if self.started == 0 {
            self.first_moments(top, base);
        }
        let (mut sa, mut sr) = (self.sum_a, self.sum_r);
        for (&y, &b) in top.iter().zip(base) {
            sa += y;
            sr += y - b;
        }
        if sr.is_finite() {
            if let (Some(&y), Some(&b)) = (top.last(), base.last()) {
                self.last = (y, y - b);
            }
            (self.sum_a, self.sum_r) = (sa, sr);
        } else {
            self.push_each(top, base);
        }
        self.count += top.len() as u32;
    }

    /// [`Self::push`] on each sample of a part (its count aside): a sample whose relative
    /// acceleration is not finite repeats the last valid pair.
    #[cold]
    #[inline(never)]
    fn push_each(&mut self, top: &[T], base: &[T]) {
        let (mut sa, mut sr, mut last) = (self.sum_a, self.sum_r, self.last);
        for (&y, &b) in top.iter().zip(base) {
            let r = y - b;
            if r.is_finite() {
                last = (y, r);
            }
            sa += last.0;
            sr += last.1;
        }
        (self.sum_a, self.sum_r, self.last) = (sa, sr, last);
    }

    /// The first block's Σk·a and Σk·r over a part ([`Self::push_each`]'s values: a missing
    /// sample repeats the last valid pair).
    #[cold]
    #[inline(never)]
    fn first_moments(&mut self, top: &[T], base: &[T]) {
        let (mut last, mut k, mut gap) = (self.last, self.count as f64, false);
        for (&y, &b) in top.iter().zip(base) {
            let r = y - b;
            if r.is_finite() {
                last = (y, r);
            } else {
                gap = true;
            }
            let kt = T::from_f64(k);
            self.xa[0] += kt * last.0;
            self.xr[0] += kt * last.1;
            k += 1.0;
        }
        if gap {
            self.first_block_gap();
        }
    }

    /// A missing sample in the first block (or its sums overflowing): the samples before the
    /// first valid one repeat (0, 0), not the offsets, and the line through the block would
    /// carry them to its start (one missing first sample took f̂ 7 % off at 0.1 s). The chains
    /// start at the block's average then (its Σk sums poisoned), with the default warm-up, as
    /// without [`Self::starting_at_rest`].
    #[cold]
    #[inline(never)]
    fn first_block_gap(&mut self) {
        let nan = T::from_f64(f64::NAN);
        (self.xa[0], self.xr[0]) = (nan, nan);
        self.warmup = self.default_warmup();
        self.restart_due = false;
    }

    /// The chains' start: the first block's top and relative accelerations `(ua, ur)` (its
    /// averages) extrapolated to its first sample by the least-squares line through its samples.
    /// A specimen starting at rest has only the sensors' offsets before the input, and the
    /// input's first samples (a sine's start, a record's) are nearly linear. The block's
    /// average is the motion's value half a block in, which the chains took for the past: with
    /// a short warm-up the default scene's first estimates of f came out 0.7 % and 0.3 % low
    /// at 0.2 and 0.3 s (noise-free; 7.0005 ± 0.0010 Hz at 0.1 s with this start). The first
    /// sample alone is noisy, and its noise, too, is taken for the past (Table 2 test 2's first
    /// f̂ 8σ off). An input that jumps at its start (no real table's) leaves a transient.
    fn start_values(&self, ua: T, ur: T) -> (T, T) {
        let n = self.decimation as f64;
        if n < 3.0 {
            return (ua, ur);
        }
        let k_mean = 0.5 * (n - 1.0);
        let s_kk = n * (n * n - 1.0) / 12.0;
        let at_start = |mean: T, sum_k: T| {
            let (m, sk) = (mean.to_f64(), sum_k.to_f64());
            let slope = (sk - n * k_mean * m) / s_kk;
            T::from_f64(m - slope * k_mean)
        };
        let (a0, r0) = (at_start(ua, self.xa[0]), at_start(ur, self.xr[0]));
        if a0.is_finite() && r0.is_finite() {
            (a0, r0)
        } else {
            (ua, ur)
        }
    }

    #[inline(never)]
    fn block(&mut self) {
        let (mut ua, mut ur) = (self.sum_a * self.inv_n, self.sum_r * self.inv_n);
        (self.sum_a, self.sum_r, self.count) = (T::ZERO, T::ZERO, 0);
        let finite = ua.is_finite() && ur.is_finite();
        if finite {
            self.last_block = (ua, ur);
        } else {
            (ua, ur) = self.last_block;
            self.last = self.last_block;
        }
        if self.blocks == 0 && self.started == 0 {
            // The first block: the chains in the steady state of the values before it (its
            // average if it is not finite: an overflow).
            let (a0, r0) = if finite {
                self.start_values(ua, ur)
            } else {
                self.first_block_gap();
                (ua, ur)
            };
            (self.xa, self.xr) = ([a0; N], [r0; N]);
        }
        self.started = self.started.saturating_add(1);
        advance(&mut self.xa, &self.phi, &self.gamma, ua);
        advance(&mut self.xr, &self.phi, &self.gamma, ur);
        if self.warmup > 0 {
            self.warmup -= 1;
            return;
        }
        if self.restart_due && self.started > self.default_warmup() {
            self.restart();
        }
        let [_, a2, a3, a4, a5] = self.xa;
        let [_, _, r3, r4, r5] = self.xr;
        let t = -(a2 - T::from_f64(3.0) * (a3 - a4) - a5);
        let (f1, f2) = (r4 - r5, r3 - (r4 + r4) + r5);
        // The A chain's Φ1, Φ2 (those of the base: Φ(A) − Φ(R)).
        let (g1, g2) = (a4 - a5, a3 - (a4 + a4) + a5);
        // The gain fit's row: the measurements as they are.
        let x = [f1, f2, g1 - f1, g2 - f2];
        let t_raw = t;
        // The oscillator's row with the top scaled by `scale` (chains are linear: A's scaled, R's
        // plus (scale − 1) times A's).
        let scale = self.gain.scale();
        let k = scale - T::ONE;
        let (t, f1, f2) = (t * scale, f1 + k * g1, f2 + k * g2);
        let e = t - (self.theta[0] * f1 + self.theta[1] * f2);
        let rho = self.rho;
        let s = [
            rho * self.s[0] + f1 * f1,
            rho * self.s[1] + f1 * f2,
            rho * self.s[2] + f2 * f2,
        ];
        let c = [rho * self.c[0] + f1 * t, rho * self.c[1] + f2 * t];
        let det = s[0] * s[2] - s[1] * s[1];
        let theta = [
            (s[2] * c[0] - s[1] * c[1]) / det,
            (s[0] * c[1] - s[1] * c[0]) / det,
        ];
        let e2 = self.e2 + (e * e - self.e2) * self.alpha;
        // (Written out: the firmware, built for size, would loop over the five.)
        let finite = s[0].is_finite()
            && s[1].is_finite()
            && s[2].is_finite()
            && c[0].is_finite()
            && c[1].is_finite()
            && e2.is_finite();
        if finite {
            if !self.restart_due {
                self.gain.row(x, t_raw, e, self.alpha);
            }
            (self.s, self.c, self.e2) = (s, c, e2);
            self.blocks = self.blocks.saturating_add(1);
            // Too little excitation yet (a singular system): keep the last θ.
            if theta[0].is_finite() && theta[1].is_finite() && theta[0] > T::ZERO {
                self.theta = theta;
            }
        }
    }

    /// A start at rest's least squares dropped at twelve filter time constants, where the
    /// default warm-up ends ([`Self::starting_at_rest`]): what a start not at rest left in its
    /// rows (a steady oscillation from the first sample, as the firmware's benchmark feeds)
    /// would bias the estimate for the forgetting's memory; from here on the rows are those of
    /// an identifier without the assumption (its θ and residual's mean square restart too).
    #[cold]
    #[inline(never)]
    fn restart(&mut self) {
        (self.s, self.c, self.blocks) = ([T::ZERO; 3], [T::ZERO; 2], 0);
        self.restart_due = false;
        (self.theta, self.e2) = ([T::ONE, T::ZERO], T::ZERO);
    }

    /// The top accelerometer's gain (module documentation), solved in f64 (`None` without a
    /// [`TopGainFit`], below [`MIN_GAIN_DECIMATION`] samples per block, before the first usable
    /// blocks, or when the base's motion does not
    /// separate it: a singular system, or a standard deviation above 0.1). The variance is the
    /// residual's mean square (that of the fit of the last call: it needs `&mut`) inflated as
    /// [`Self::estimate`]'s.
    pub fn gain_estimate(&mut self) -> Option<GainEstimate> {
        if self.blocks < 8 || self.decimation < MIN_GAIN_DECIMATION {
            return None;
        }
        self.gain.estimate(self.inflation)
    }

    /// The estimate (`None` before any usable block).
    pub fn estimate(&self) -> Option<OscillatorEstimate> {
        if self.blocks < 2 {
            return None;
        }
        let [s11, s12, s22] = self.s.map(T::to_f64);
        let det = s11 * s22 - s12 * s12;
        let (t1, t2) = (self.theta[0].to_f64(), self.theta[1].to_f64());
        if !(det > 0.0 && t1 > 0.0) {
            return None;
        }
        let var = self.e2.to_f64() * self.inflation;
        let (v11, v22, v12) = (var * s22 / det, var * s11 / det, -var * s12 / det);
        let r = libm::sqrt(t1);
        let p = self.lambda * r;
        let xi = t2 / (2.0 * r);
        // f = λ√θ1/2π: σf = f·σθ1/(2θ1); ξ = θ2/(2√θ1): linearised.
        let f = p / (2.0 * core::f64::consts::PI);
        let df1 = -t2 / (4.0 * t1 * r);
        let df2 = 1.0 / (2.0 * r);
        let var_xi = df1 * df1 * v11 + 2.0 * df1 * df2 * v12 + df2 * df2 * v22;
        Some(OscillatorEstimate {
            natural_frequency_hz: f,
            natural_frequency_std_hz: f * libm::sqrt(libm::fmax(v11, 0.0)) / (2.0 * t1),
            damping_ratio: xi,
            damping_ratio_std: libm::sqrt(libm::fmax(var_xi, 0.0)),
            blocks: self.blocks,
        })
    }
}

/// Blocks of the default warm-up for `blocks_per_tau` blocks per filter time constant: twelve
/// of them (a jump of the input at the first sample leaves t⁴e^{−λt}/24, 5e-3 of it), and
/// [`WARMUP_AT_REST`].
fn default_warmup(blocks_per_tau: f64) -> u32 {
    (12.0 * blocks_per_tau) as u32 + WARMUP_AT_REST
}

/// `x^n` by repeated multiplication (n is small; no `pow` in the firmware image).
fn powi(x: f64, n: u32) -> f64 {
    (0..n).fold(1.0, |acc, _| acc * x)
}

/// One block of the scaled chain: ξ ← Φ·ξ + γ·u (Φ lower-triangular Toeplitz).
#[inline(always)]
fn advance<T: Real>(x: &mut [T; N], phi: &[T; N], gamma: &[T; N], u: T) {
    let [x1, x2, x3, x4, x5] = *x;
    // ξk' = −λξk + λξ(k−1), ξ0 = u: the block map couples ξk to ξj (j ≤ k) by φ(k−j).
    *x = [
        phi[0] * x1 + gamma[0] * u,
        phi[0] * x2 + phi[1] * x1 + gamma[1] * u,
        phi[0] * x3 + phi[1] * x2 + phi[2] * x1 + gamma[2] * u,
        phi[0] * x4 + phi[1] * x3 + phi[2] * x2 + phi[3] * x1 + gamma[3] * u,
        phi[0] * x5 + phi[1] * x4 + phi[2] * x3 + phi[3] * x2 + phi[4] * x1 + gamma[4] * u,
    ];
}

mod gain;
mod jump;
pub use gain::{GainEstimate, GainRows, TopGainFit};

#[cfg(test)]
mod tests;
