//! Sensing friction reversals from the sampled base-to-table displacement (the slip).
//!
//! The slip x(t) has a local extremum at every reversal of sliding and is constant while the base
//! sticks. The detector tracks the running extremum in the current sliding direction and, with
//! hysteresis `h` against sensor noise, declares
//!
//! * a **reversal** once x has come back by more than `h` from the extremum,
//! * a **stick** once x has stayed within `h` of the extremum for `stick_samples`,
//! * a **slip start** once x leaves the stuck value by more than `h`.
//!
//! Event times are sub-sample: near a reversal the slip is a parabola on each side of the vertex
//! (constant friction, slowly varying spring force), so the vertex is located by least-squares
//! parabola fits on the samples before and after the extremum (up to `fit_half` samples each side),
//! averaged by point count. A slip start from rest is x − x_s ∝ (t − t_s)², so √|x − x_s| is fitted
//! by a line. The event is reported late (after the hysteresis is crossed) with its exact age in
//! samples, which the estimator back-dates. Fixed-size ring buffer of `N` samples; no heap, no
//! panics.

use super::ring::{rel, slot};
use super::search::{golden_min, grid_min};
use crate::error::{check, Error, Param};

/// The events this detector reports (defined in [`crate::detect`]).
pub use super::SlipEvent;

/// Detector settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectorConfig {
    /// Hysteresis h (m): a few times the displacement noise RMS.
    pub hysteresis_m: f32,
    /// Samples on each side of an extremum used to locate it.
    pub fit_half: usize,
    /// Samples within `h` of the extremum after which the base is declared stuck.
    pub stick_samples: usize,
    /// Breakaway shape: with static = kinetic friction the slip starts with zero acceleration
    /// (x ∝ u³ or u⁴: the best of u², u³, u⁴ is fitted); with static > kinetic it starts with a
    /// finite one (x ∝ u²).
    pub cubic_breakaway: bool,
}

impl DetectorConfig {
    /// Defaults for a displacement noise RMS and sample rate: h = 8σ (at least 1 µm), fits over
    /// 2 ms, stick after the slip has stalled within h for 10 ms.
    pub fn for_noise(noise_rms_m: f64, sample_rate_hz: f64) -> Result<Self, Error> {
        check(
            Param::SampleRate,
            sample_rate_hz,
            sample_rate_hz > 0.0,
            "> 0 Hz",
        )?;
        check(Param::NoiseRms, noise_rms_m, noise_rms_m >= 0.0, ">= 0 m")?;
        let fit = libm::round(2e-3 * sample_rate_hz).clamp(2.0, 64.0) as usize;
        let stick = libm::round(10e-3 * sample_rate_hz).clamp(3.0, 1e6) as usize;
        Ok(Self {
            hysteresis_m: (8.0 * noise_rms_m).max(1e-6) as f32,
            fit_half: fit,
            stick_samples: stick,
            cubic_breakaway: true,
        })
    }
}

impl DetectorConfig {
    /// The longest back-dating (samples) of this detector's events in the usual course, with a
    /// ring of `ring` samples: `max(stick_samples + 2·fit_half + 2, ring)`. A stick is reported
    /// `stick_samples` after its stall began, its time fitted at most `fit_half + 1` samples
    /// before that; a reversal's vertex lies within the stall window, fitted within
    /// `fit_half + 2` samples of it; a slip start lies within the ring. (A reversal whose stall
    /// reference was renewed after the vertex can be up to `stick_samples` older: a consumer
    /// with this much history clamps such an age.)
    pub fn max_age_samples(&self, ring: usize) -> usize {
        (self.stick_samples + 2 * self.fit_half + 2).max(ring)
    }

    /// The smallest power-of-two ring the detector accepts, `2·fit_half + 2` samples: enough to
    /// locate slip starts and reversals (their fits look `2·fit_half` samples around the
    /// extremum).
    pub fn min_ring(&self) -> usize {
        (2 * self.fit_half + 2).next_power_of_two()
    }

    /// The power-of-two ring that also holds a stick's fit window, `stick_samples + fit_half + 8`
    /// samples back (at least [`Self::min_ring`]): a stick is reported `stick_samples` after its
    /// stall began and its time is searched up to `fit_half` samples before that. With a shorter
    /// ring the fit sees only the ring and stick times come out late by up to a few ms; the
    /// stick-slip estimator, which follows the stick phases, needs them right.
    pub fn ring_for_sticks(&self) -> usize {
        (self.stick_samples + self.fit_half + 8)
            .max(2 * self.fit_half + 2)
            .next_power_of_two()
    }

    /// The breakaway shape for static and kinetic friction coefficients (cubic when μs = μ).
    pub fn with_friction(mut self, mu_static: f64, mu_kinetic: f64) -> Self {
        self.cubic_breakaway = mu_static <= mu_kinetic;
        self
    }
}

/// The reversal/stick detector with a ring buffer of `N` samples (N ≥ 2·fit_half + 2).
#[derive(Debug, Clone)]
pub struct ReversalDetector<const N: usize> {
    cfg: DetectorConfig,
    ring: [f32; N],
    /// Index of the next sample (samples seen so far).
    k: u64,
    /// Current slip direction: +1, −1, or 0 while stuck.
    direction: i8,
    /// Extremum (sliding) or stuck value (stuck).
    ext: f32,
    /// Sample index of the extremum, or of the stick.
    ext_k: u64,
    /// Stall detection while sliding: reference value and the sample it was set.
    stall_ref: f32,
    stall_k: u64,
    /// Measured slip acceleration (base − table, m/s²), when provided.
    accel: [f32; N],
    /// Whether every sample so far came with a slip acceleration.
    has_accel: bool,
}

impl<const N: usize> ReversalDetector<N> {
    /// A detector that starts stuck at the first sample's value.
    pub fn new(cfg: DetectorConfig) -> Result<Self, Error> {
        check(
            Param::Hysteresis,
            cfg.hysteresis_m as f64,
            cfg.hysteresis_m > 0.0,
            "hysteresis > 0 m",
        )?;
        if cfg.fit_half < 2 || 2 * cfg.fit_half + 2 > N {
            return Err(Error::OutOfRange {
                param: Param::FitHalf,
                value: cfg.fit_half as f64,
                expected: "2 <= fit_half, 2*fit_half + 2 <= buffer length",
            });
        }
        if cfg.stick_samples == 0 {
            return Err(Error::OutOfRange {
                param: Param::StickSamples,
                value: cfg.stick_samples as f64,
                expected: "stick_samples >= 1",
            });
        }
        Ok(Self {
            cfg,
            ring: [0.0; N],
            k: 0,
            direction: 0,
            ext: 0.0,
            ext_k: 0,
            stall_ref: 0.0,
            stall_k: 0,
            accel: [0.0; N],
            has_accel: true,
        })
    }

    /// The current slip direction (+1, −1, 0 stuck).
    pub fn direction(&self) -> i8 {
        self.direction
    }

    /// Samples processed.
    pub fn samples(&self) -> u64 {
        self.k
    }

    /// The settings.
    pub fn config(&self) -> &DetectorConfig {
        &self.cfg
    }

    fn at(&self, i: u64) -> f32 {
        self.ring[slot::<N>(i)]
    }

    /// Process one displacement sample (m) and the measured slip acceleration, base minus table
    /// accelerometer (m/s²). With the acceleration, event times come from the slip velocity's zero
    /// (see [`Self::process`]): much sharper for slow breakaways and sticks.
    pub fn process_with_accel(&mut self, x: f32, slip_accel: f32) -> Option<SlipEvent> {
        let k = self.k;
        let a = if slip_accel.is_finite() {
            slip_accel
        } else if k > 0 {
            self.accel[slot::<N>(k - 1)]
        } else {
            0.0
        };
        self.accel[slot::<N>(k)] = a;
        self.step(x)
    }

    /// Process one displacement sample (m). A non-finite sample is skipped (the detector keeps
    /// time; its slot repeats the previous value).
    pub fn process(&mut self, x: f32) -> Option<SlipEvent> {
        self.has_accel = false;
        self.step(x)
    }

    fn step(&mut self, x: f32) -> Option<SlipEvent> {
        let k = self.k;
        let x = if x.is_finite() {
            x
        } else if k > 0 {
            self.at(k - 1)
        } else {
            0.0
        };
        self.ring[slot::<N>(k)] = x;
        self.k += 1;
        if k == 0 {
            self.ext = x;
            self.ext_k = 0;
            return None;
        }
        let h = self.cfg.hysteresis_m;
        let d = self.direction as f32;
        if self.direction == 0 {
            let dev = x - self.ext;
            if libm::fabsf(dev) > h {
                let direction = if dev > 0.0 { 1 } else { -1 };
                // Search the kink around the last sample still within h/4 of the stuck value (a
                // slow, cubic breakaway takes many samples to leave the hysteresis band).
                let l = self.cfg.fit_half as u64;
                let oldest = k.saturating_sub(N as u64 - 1);
                let mut i0 = k;
                while i0 > oldest && libm::fabsf(self.at(i0) - self.ext) > 0.25 * h {
                    i0 -= 1;
                }
                let lo = i0.saturating_sub(2 * l).max(oldest);
                let (a, b) = (
                    rel(i0.saturating_sub(l).max(lo), k),
                    rel((i0 + l).min(k), k),
                );
                // The breakaway's shape depends on how the friction demand crosses the limit:
                // u² (μs > μ: a finite jump), u³ (a linear crossing), u⁴ (a tangent one).
                let powers: &[i32] = if self.cfg.cubic_breakaway {
                    &[2, 3, 4]
                } else {
                    &[2]
                };
                let mut best = f32::INFINITY;
                let t0 = if self.has_accel {
                    self.zero_velocity_fit(lo, k, (a, b)).0
                } else {
                    // The power with the best coarse fit, then refined.
                    let mut power = 2;
                    for &pw in powers {
                        let (_, r) = self.kink_fit(lo, k, (a, b), false, pw, false);
                        if r < best {
                            best = r;
                            power = pw;
                        }
                    }
                    self.kink_fit(lo, k, (a, b), false, power, true).0
                };
                self.direction = direction;
                self.ext = x;
                self.ext_k = k;
                self.stall_ref = x;
                self.stall_k = k;
                return Some(SlipEvent::SlipStart {
                    direction,
                    age_samples: (-t0).max(0.0),
                });
            }
            return None;
        }
        // Stall: the slip has stayed within h of one value (noise cannot renew this reference the
        // way it renews the running extremum).
        if libm::fabsf(x - self.stall_ref) > h {
            self.stall_ref = x;
            self.stall_k = k;
        }
        if d * (x - self.ext) > 0.0 {
            self.ext = x;
            self.ext_k = k;
        } else if d * (self.ext - x) > h {
            let te = self.vertex_time(k);
            let direction = -self.direction;
            self.direction = direction;
            self.ext = x;
            self.ext_k = k;
            self.stall_ref = x;
            self.stall_k = k;
            return Some(SlipEvent::Reversal {
                direction,
                age_samples: (-te).max(0.0),
            });
        }
        if k - self.stall_k >= self.cfg.stick_samples as u64 {
            let te = self.stick_time(k);
            self.direction = 0;
            // Stuck value: mean of the samples of the stall (within the ring).
            let n = (k - self.stall_k).clamp(1, N as u64 - 1);
            let mut sum = 0.0f32;
            for i in (k - n + 1)..=k {
                sum += self.at(i);
            }
            self.ext = sum / n as f32;
            self.ext_k = k;
            return Some(SlipEvent::Stick {
                age_samples: (-te).max(0.0),
            });
        }
        None
    }

    /// Vertex time (samples, relative to the current sample k) of the extremum at `ext_k`, from parabola fits on each
    /// side; the current sample is `k`.
    fn vertex_time(&self, k: u64) -> f32 {
        let e = self.ext_k;
        let l = self.cfg.fit_half as u64;
        let oldest = k.saturating_sub(N as u64 - 1);
        if self.has_accel {
            let lo = e.saturating_sub(2 * l).max(oldest);
            let (a, b) = (rel(e.saturating_sub(l).max(lo), k), rel((e + l).min(k), k));
            return self.zero_velocity_fit(lo, k, (a, b)).0;
        }
        let lo = e.saturating_sub(l).max(oldest);
        let hi = (e + l).min(k);
        let left = fit_vertex(|i| self.at(i), lo, e + 1.min(k - e), k);
        let right = fit_vertex(|i| self.at(i), e.saturating_sub(1).max(oldest), hi, k);
        let er = rel(e, k);
        let guard =
            |v: Option<(f32, u64)>| v.filter(|(t, _)| libm::fabsf(*t - er) <= 2.0 + l as f32);
        match (guard(left), guard(right)) {
            (Some((a, na)), Some((b, nb))) => (a * na as f32 + b * nb as f32) / (na + nb) as f32,
            (Some((a, _)), None) | (None, Some((a, _))) => a,
            (None, None) => er,
        }
    }

    /// Stick time (samples relative to the current sample k): the slip x = x_s − c·(t_s − t)² before t_s and x_s after
    /// (constant deceleration to rest), fitted around the start of the stall.
    fn stick_time(&self, k: u64) -> f32 {
        let l = self.cfg.fit_half as u64;
        let lo = self.stall_k.saturating_sub(2 * l);
        let (a, b) = (
            rel(self.stall_k.saturating_sub(l).max(lo), k),
            rel((self.stall_k + l).min(k), k),
        );
        if self.has_accel {
            return self.zero_velocity_fit(lo, k, (a, b)).0;
        }
        self.kink_fit(lo, k, (a, b), true, 2, true).0
    }

    /// The time t_e at which the slip velocity is zero (a reversal, a stick or a breakaway), from
    /// the displacement and the measured slip acceleration a over samples lo..=hi: since
    /// v(t_e) = 0, x(t) = x_e + c·∫_{t_e}^{t} (t − σ) a(σ) dσ on both sides (a ≈ 0 while stuck),
    /// fitted by least squares for (x_e, c) (c ≈ Δt² absorbs the units and any accelerometer gain
    /// error); t_e on a one-sample grid over [a, b], refined by golden-section search.
    fn zero_velocity_fit(&self, lo: u64, hi: u64, (a, b): (f32, f32)) -> (f32, f32) {
        let lo = lo.max(hi.saturating_sub(N as u64 - 1));
        let n = (hi - lo) as usize;
        // Prefix integrals (trapezoid, a linear between samples, σ in samples from lo):
        // s0[i] = ∫_lo^i a, s1[i] = ∫_lo^i σ a.
        let acc = |i: u64| self.accel[slot::<N>(i)];
        let at_window = |i: usize| acc(lo + i as u64);
        let mut s0 = [0.0f32; N];
        let mut s1 = [0.0f32; N];
        for j in 0..n.min(N - 1) {
            let (aj, an) = (at_window(j), at_window(j + 1));
            s0[j + 1] = s0[j] + 0.5 * (aj + an);
            s1[j + 1] = s1[j] + j as f32 * 0.5 * (aj + an) + aj / 6.0 + an / 3.0;
        }
        // ∫ and ∫σ· of the linear a(σ) = α + β(σ − σ0) over [p, q].
        let lin = |alpha: f32, beta: f32, s0_: f32, p: f32, q: f32| {
            let i0 = alpha * (q - p) + beta * ((q - s0_) * (q - s0_) - (p - s0_) * (p - s0_)) / 2.0;
            let i1 = alpha * (q * q - p * p) / 2.0
                + beta * ((q * q * q - p * p * p) / 3.0 - s0_ * (q * q - p * p) / 2.0);
            (i0, i1)
        };
        let last = n.min(N - 1);
        let x0 = self.at(hi);
        // Times relative to hi (t_e, a and b too).
        let lo_f = rel(lo, hi);
        let resid = |te: f32| {
            // The acceleration jumps at t_e (inside sample interval j): extrapolate each side's
            // samples linearly up to t_e instead of interpolating across the jump.
            let u = te - lo_f;
            let j = (libm::floorf(u).max(0.0) as usize).min(last.saturating_sub(1));
            let f = u - j as f32;
            let (jf, te_w) = (j as f32, j as f32 + f);
            let aj = at_window(j);
            let left_slope = if j > 0 { aj - at_window(j - 1) } else { 0.0 };
            let an = at_window(j + 1);
            let right_slope = if j + 2 <= last {
                at_window(j + 2) - an
            } else {
                0.0
            };
            let (l0, l1) = lin(aj, left_slope, jf, jf, te_w);
            let (r0, r1) = lin(an, right_slope, jf + 1.0, te_w, jf + 1.0);
            // Prefix integrals of the modified acceleration at t_e and at the samples.
            let (e0, e1) = (s0[j] + l0, s1[j] + l1);
            let trap = (s0[j + 1] - s0[j], s1[j + 1] - s1[j]);
            let p = |i: usize| {
                if i <= j {
                    (s0[i], s1[i])
                } else {
                    (s0[i] - trap.0 + l0 + r0, s1[i] - trap.1 + l1 + r1)
                }
            };
            let g = |i: usize| {
                // ∫_{t_e}^{t_i} (t_i − σ) a dσ = t_i (P0(t_i) − P0(t_e)) − (P1(t_i) − P1(t_e)).
                let (p0, p1) = p(i);
                i as f32 * (p0 - e0) - (p1 - e1)
            };
            let (mut m, mut sg, mut sgg, mut sy, mut sgy) = (0.0f32, 0.0, 0.0, 0.0, 0.0);
            for i in 0..=n.min(N - 1) {
                let gi = g(i);
                let y = self.at(lo + i as u64) - x0;
                m += 1.0;
                sg += gi;
                sgg += gi * gi;
                sy += y;
                sgy += gi * y;
            }
            let det = m * sgg - sg * sg;
            if det == 0.0 || det.is_nan() {
                return f32::INFINITY;
            }
            let c = (m * sgy - sg * sy) / det;
            let xe = (sy - c * sg) / m;
            let mut r = 0.0f32;
            for i in 0..=n.min(N - 1) {
                let e = self.at(lo + i as u64) - x0 - xe - c * g(i);
                r += e * e;
            }
            r
        };
        let (a, b) = (a.max(lo_f), b.min(0.0));
        let (best, _) = grid_min(&resid, (a, b), 1.0);
        let te = golden_min(&resid, ((best - 1.0).max(lo_f), (best + 1.0).min(0.0)), 14);
        (te, resid(te))
    }

    /// Fit of a power law joined to a constant at t_s, x = x_s + c·u^power with u the time past
    /// the kink (`before`: before t_s, a stick; else after it, a slip start), by least squares
    /// over samples lo..=hi (within the ring). t_s is searched on a one-sample grid over [a, b],
    /// then refined by golden-section search. Returns (t_s, residual).
    fn kink_fit(
        &self,
        lo: u64,
        hi: u64,
        (a, b): (f32, f32),
        before: bool,
        power: i32,
        refine: bool,
    ) -> (f32, f32) {
        let lo = lo.max(hi.saturating_sub(N as u64 - 1));
        let x0 = self.at(hi);
        // Times relative to hi (t_s, a and b too).
        let reg = |ts: f32, i: u64| {
            let ti = rel(i, hi);
            let u = if before { ts - ti } else { ti - ts };
            if u > 0.0 {
                // Integer powers by multiplication (powf is ~100× slower on the M4F).
                let u2 = u * u;
                match power {
                    2 => u2,
                    3 => u2 * u,
                    _ => u2 * u2,
                }
            } else {
                0.0
            }
        };
        let resid = |ts: f32| {
            // Linear least squares for (x_s, c) with regressors 1 and u^power.
            let (mut n, mut sg, mut sgg, mut sy, mut sgy) = (0.0f32, 0.0, 0.0, 0.0, 0.0);
            for i in lo..=hi {
                let g = reg(ts, i);
                let y = self.at(i) - x0;
                n += 1.0;
                sg += g;
                sgg += g * g;
                sy += y;
                sgy += g * y;
            }
            let det = n * sgg - sg * sg;
            if det == 0.0 || det.is_nan() {
                return f32::INFINITY;
            }
            let c = (n * sgy - sg * sy) / det;
            let xs = (sy - c * sg) / n;
            let mut r = 0.0f32;
            for i in lo..=hi {
                let e = self.at(i) - x0 - xs - c * reg(ts, i);
                r += e * e;
            }
            r
        };
        // A coarse grid (every 3 samples; the residual is smooth in t_s), then golden-section
        // refinement over ±3 samples around its best point (`refine`).
        let (best, best_r) = grid_min(&resid, (a, b), 3.0);
        if !refine {
            return (best, best_r);
        }
        let ts = golden_min(&resid, (best - 3.0, best + 3.0), 16);
        (ts, resid(ts))
    }
}

/// Least-squares parabola through samples lo..=hi (at least 3); returns (vertex time relative to
/// sample k, points).
fn fit_vertex(at: impl Fn(u64) -> f32, lo: u64, hi: u64, k: u64) -> Option<(f32, u64)> {
    if hi < lo + 2 {
        return None;
    }
    let n = hi - lo + 1;
    // Times relative to sample k.
    let c = (rel(lo, k) + rel(hi, k)) / 2.0;
    let y0 = at(lo);
    let (mut s0, mut s1, mut s2, mut s3, mut s4) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    let (mut sy, mut suy, mut su2y) = (0.0f32, 0.0f32, 0.0f32);
    for i in lo..=hi {
        let u = rel(i, k) - c;
        let y = at(i) - y0;
        let u2 = u * u;
        s0 += 1.0;
        s1 += u;
        s2 += u2;
        s3 += u2 * u;
        s4 += u2 * u2;
        sy += y;
        suy += u * y;
        su2y += u2 * y;
    }
    // Normal equations [[s0 s1 s2][s1 s2 s3][s2 s3 s4]] (c0 c1 c2) = (sy suy su2y), Cramer's rule.
    let det3 = |a: [f32; 9]| {
        a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6])
            + a[2] * (a[3] * a[7] - a[4] * a[6])
    };
    let m = [s0, s1, s2, s1, s2, s3, s2, s3, s4];
    let d = det3(m);
    if d.is_nan() || d == 0.0 {
        return None;
    }
    let c1 = det3([s0, sy, s2, s1, suy, s3, s2, su2y, s4]) / d;
    let c2 = det3([s0, s1, sy, s1, s2, suy, s2, s3, su2y]) / d;
    if c2.is_nan() || c2 == 0.0 {
        return None;
    }
    let v = c - c1 / (2.0 * c2);
    v.is_finite().then_some((v, n))
}

#[cfg(test)]
mod tests;
