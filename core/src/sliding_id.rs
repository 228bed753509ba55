//! Online identification of the sliding oscillator from the base accelerometer alone
//! ([`SlidingIdentifier`]): its circular frequency ω = p·√M, its damping ratio ζ = ξ·√M
//! (M = 1 + m1/m2), the kinetic friction acceleration μ·g and the accelerometer's offset.
//!
//! **The relation.** While the base slides one way (Coulomb friction, constant force), the two
//! masses are an autonomous system: the relative coordinate is a free oscillator at ω, ζ about
//! the equilibrium in which both masses decelerate together at the friction acceleration. The
//! base acceleration is then exactly
//!
//! ü2(t) = μ·g·s + b + e^(−ζωt)·(A·cos ω_d t + B·sin ω_d t),
//!
//! with s = ±1 the direction of the friction force (the estimator's phase level) and b the
//! accelerometer's offset. No model state enters, so what is identified does not follow the
//! model's errors.
//!
//! **Discretisation.** The samples are averaged over blocks of `decimation` samples, about
//! [`OMEGA_H`] radians of the prior's sliding oscillator each:
//! the averages of consecutive blocks of one episode are the same damped sinusoid plus the same
//! constant, so three of them satisfy, exactly,
//!
//! Y_k − 2·Y_(k−1) + Y_(k−2) = −α·Y_(k−1) − β·(Y_(k−1) − Y_(k−2)) + γ·s + δ,
//!
//! with α = 1 − a1 − a2, β = 1 + a2 (a1 = 2·e^(−ζωh)·cos ω_d h, a2 = −e^(−2ζωh), h the block's
//! duration), μ·g = γ/α and b = δ/α. The second difference form keeps the regressors apart in
//! f32 (α ~ (ωh)², β ~ 2ζωh).
//!
//! **Estimation.** Least squares on every row whose three blocks lie in one sliding episode
//! ([`PagedNormal`]: products summed in f32 over pages, the pages in f64, with forgetting). The
//! estimate solves the 4×4 normal equations in f64; the standard deviations are the formal
//! ones, σ²·S⁻¹, carried to ω, ζ, μ·g and the offset to first order.

use crate::error::{check, check_forgetting, check_sample_rate, Error, Param};
use crate::least_squares::PagedNormal;
use crate::math::Real;
/// The block duration the identifier aims at, in radians of the prior's sliding oscillator
/// (ω·h). The error of μ·g = γ/α falls as h^(−3/2) (α grows as h², the noise of a block average
/// falls as h^(−1/2), the rows as 1/h): 0.25 rad leaves ~25 blocks per period, and episodes of
/// a few tens of samples still hold three blocks at 10 kHz.
pub const OMEGA_H: f64 = 0.25;
/// Largest decimation (samples per block).
pub const MAX_DECIMATION: u32 = 64;
/// Rows needed before an estimate.
pub const MIN_ROWS: f64 = 8.0;

/// The identified sliding oscillator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlidingEstimate {
    /// Circular frequency ω = p·√M of the sliding oscillator (rad/s).
    pub omega: f64,
    /// Its standard deviation (rad/s).
    pub omega_std: f64,
    /// Damping ratio ζ = ξ·√M of the sliding oscillator.
    pub damping_ratio: f64,
    /// Its standard deviation.
    pub damping_ratio_std: f64,
    /// Kinetic friction acceleration μ·g (m/s²).
    pub friction_accel: f64,
    /// Its standard deviation (m/s²).
    pub friction_accel_std: f64,
    /// The accelerometer's offset (m/s²): what remains of it after the corrections upstream.
    pub offset: f64,
    /// Its standard deviation (m/s²; 0 while one direction of sliding is seen: the offset is
    /// then taken as 0).
    pub offset_std: f64,
    /// Rows (block triples) used, with forgetting.
    pub rows: f64,
    /// 0, or the direction s (±1) of the only sliding seen when the offset is not known: the
    /// friction and the offset are then one constant, and `friction_accel` is the friction
    /// acceleration of that direction with the offset in it, μ·g + s·b (`offset` 0). It is what
    /// the base's mean acceleration is while it slides that way.
    pub one_way: i8,
}

/// Identifies the sliding oscillator and the friction from the base acceleration (see the
/// module documentation). Per sample: an addition and a count; per block: one row of products.
#[derive(Debug, Clone)]
pub struct SlidingIdentifier<T> {
    decimation: u32,
    inv_n: T,
    /// The block being summed: its samples, their sum and their phase level.
    count: u32,
    sum: T,
    level: i8,
    /// The episode's last two block averages (newest first) and how many of them are valid.
    prev: [T; 2],
    prev_n: u8,
    /// The normal equations of (Y_(k−1), Y_(k−1) − Y_(k−2), s, 1).
    normal: PagedNormal<T, 4, 15>,
    /// Block duration (s).
    h: f64,
    /// The directions with rows: bit 0 s = +1, bit 1 s = −1.
    directions: u8,
}

impl<T: Real> SlidingIdentifier<T> {
    /// An identifier for samples at `sample_rate_hz`, its blocks sized for the prior's sliding
    /// oscillator `prior_omega` (rad/s), forgetting `forgetting` per row in (0, 1].
    pub fn new(sample_rate_hz: f64, prior_omega: f64, forgetting: f64) -> Result<Self, Error> {
        check_sample_rate(sample_rate_hz)?;
        check(
            Param::NaturalFrequency,
            prior_omega,
            prior_omega > 0.0 && prior_omega.is_finite(),
            "sliding circular frequency > 0",
        )?;
        check_forgetting(forgetting)?;
        let d =
            libm::floor(OMEGA_H * sample_rate_hz / prior_omega).clamp(1.0, MAX_DECIMATION as f64);
        Ok(Self {
            decimation: d as u32,
            inv_n: T::from_f64(1.0 / d),
            count: 0,
            sum: T::ZERO,
            level: 0,
            prev: [T::ZERO; 2],
            prev_n: 0,
            normal: PagedNormal::new(forgetting),
            h: d / sample_rate_hz,
            directions: 0,
        })
    }

    /// Samples per block.
    pub fn decimation(&self) -> u32 {
        self.decimation
    }

    /// Whether rows of both directions of sliding are in (the friction and the offset then
    /// separate).
    pub fn both_ways(&self) -> bool {
        self.directions == 3
    }

    /// Rows ever added (wrapping): an estimate changes only when it does.
    pub fn rows_added(&self) -> u32 {
        self.normal.added()
    }

    /// One sample of the base acceleration `y` with its phase `level`: ±1 for a sample inside
    /// a sliding episode (the direction of the friction force), 0 for anything else (stuck, a
    /// phase change within the sample's interval, or a sample not to use). A level 0, a change
    /// of level or a non-finite sample ends the episode.
    #[inline(always)]
    pub fn push(&mut self, y: T, level: i8) {
        if !self.enter(y, level) {
            return;
        }
        self.sum += y;
        self.count += 1;
        if self.count >= self.decimation {
            let avg = self.sum * self.inv_n;
            (self.count, self.sum) = (0, T::ZERO);
            self.row(avg);
        }
    }

    /// One block's average `y` of [`Self::decimation`] consecutive samples (for a caller that
    /// forms the blocks itself) with its phase `level` (0: a block not to use); as [`Self::push`]
    /// on its samples, the episode ending at a level 0, a change of level or a non-finite
    /// average.
    #[inline(never)]
    pub fn push_block(&mut self, y: T, level: i8) {
        if self.enter(y, level) {
            self.row(y);
        }
    }

    /// A value `y` of phase `level` in the episode: a level 0, a change of level or a
    /// non-finite value ends it; whether the value is to be used (it starts a new episode on a
    /// change of level).
    #[inline(always)]
    fn enter(&mut self, y: T, level: i8) -> bool {
        if level == 0 || level != self.level || !y.is_finite() {
            self.end_episode();
            if level == 0 || !y.is_finite() {
                return false;
            }
            self.level = level;
        }
        true
    }

    /// The accelerations already in (the rows, the episode's blocks and the block being
    /// summed), as if they had been measured `c` times as large: the accelerometer's gain
    /// correction changed (the table accelerometer's gain adopted: every channel rescaled from
    /// the next sample on). ω and ζ are ratios of accelerations and do not move; μ·g and the
    /// offset scale by `c`, as if every row had been taken in the new units.
    pub fn rescale(&mut self, c: f32) {
        if !(c.is_finite() && c > 0.0) {
            return;
        }
        self.normal.rescale(2, c);
        let k = T::from_f64(f64::from(c));
        self.sum = self.sum * k;
        self.prev = [self.prev[0] * k, self.prev[1] * k];
    }

    /// Ends the episode: the next sample starts a new one.
    #[inline(always)]
    pub fn end_episode(&mut self) {
        (self.count, self.sum, self.prev_n, self.level) = (0, T::ZERO, 0, 0);
    }

    /// The row of a block average (the episode's third block on).
    #[inline(never)]
    fn row(&mut self, y: T) {
        if self.prev_n >= 2 {
            let [y1, y2] = self.prev;
            let s = if self.level > 0 { T::ONE } else { -T::ONE };
            self.directions |= if self.level > 0 { 1 } else { 2 };
            let t = y - (y1 + y1) + y2;
            self.normal.add(&[y1, y1 - y2, s, T::ONE], t);
        }
        self.prev = [y, self.prev[0]];
        self.prev_n = (self.prev_n + 1).min(2);
    }

    /// The estimate (`None` before [`MIN_ROWS`] rows, for singular normal equations, or for a
    /// fit that is not an underdamped oscillator with a positive friction acceleration). Until
    /// the base has slid both ways the friction and the offset are one constant: with
    /// `offset_known` the offset is then taken as 0 (the accelerometers were zeroed on a rest),
    /// without it the estimate is that direction's ([`SlidingEstimate::one_way`]).
    pub fn estimate(&self, offset_known: bool) -> Option<SlidingEstimate> {
        if self.normal.rows() < MIN_ROWS {
            return None;
        }
        // Both directions of sliding separate the friction from the offset; until then (one
        // direction: the last two regressors are equal up to sign) the offset is taken as 0.
        let one_way = match self.directions {
            1 if !offset_known => 1,
            2 if !offset_known => -1,
            _ => 0,
        };
        let both = if one_way == 0 {
            self.normal.solve::<4>()
        } else {
            None
        };
        let fit = match both {
            Some(f) => f,
            None if !offset_known && one_way == 0 => return None,
            None => {
                let f = self.normal.solve::<3>()?;
                let mut cov = [[0.0; 4]; 4];
                for (row, r3) in cov.iter_mut().zip(f.cov) {
                    row[..3].copy_from_slice(&r3);
                }
                crate::least_squares::Fit {
                    theta: [f.theta[0], f.theta[1], f.theta[2], 0.0],
                    cov,
                    rows: f.rows,
                }
            }
        };
        let (theta, rows) = (fit.theta, fit.rows);
        let (alpha, beta, gamma, delta) = (-theta[0], -theta[1], theta[2], theta[3]);
        let r2 = 1.0 - beta; // e^(−2ζωh)
        if !(alpha > 0.0 && r2 > 0.0 && r2 < 1.0) {
            return None;
        }
        let a1 = 2.0 - alpha - beta;
        let cos_wd = a1 / (2.0 * libm::sqrt(r2));
        if !(cos_wd > -1.0 && cos_wd < 1.0) {
            return None;
        }
        let h = self.h;
        let zw = -ln(r2)? / (2.0 * h);
        let wd = acos(cos_wd)? / h;
        let omega = libm::sqrt(zw * zw + wd * wd);
        let zeta = zw / omega;
        // (One way: γ·s is the whole constant, μ·g·s + b.)
        let friction_accel = gamma / alpha;
        if !(friction_accel > 0.0 && omega.is_finite()) {
            return None;
        }
        // First-order errors (small ωh: α ≈ (ωh)², β ≈ 2ζωh).
        let var = |i: usize, j: usize| fit.cov[i][j];
        let (va, vb, vg, vag) = (var(0, 0), var(1, 1), var(2, 2), -var(0, 2));
        let (vd, vad) = (var(3, 3), -var(0, 3));
        let off = delta / alpha;
        let var_off = (vd - 2.0 * off * vad + off * off * va) / (alpha * alpha);
        let rel_a = libm::sqrt(va) / alpha;
        let omega_std = 0.5 * omega * rel_a;
        let zeta_std = zeta * libm::sqrt(vb / (beta * beta) + 0.25 * rel_a * rel_a);
        let fa = friction_accel;
        let var_fa = (vg - 2.0 * fa * vag + fa * fa * va) / (alpha * alpha);
        Some(SlidingEstimate {
            omega,
            omega_std,
            damping_ratio: zeta,
            damping_ratio_std: zeta_std,
            friction_accel: fa,
            friction_accel_std: libm::sqrt(libm::fmax(var_fa, 0.0)),
            offset: off,
            offset_std: libm::sqrt(libm::fmax(var_off, 0.0)),
            rows,
            one_way,
        })
    }
}

/// ln x for x in [0.05, 1] by the series of artanh ((x − 1)/(x + 1) within 0.91 of 0: at most
/// 200 terms), `None` outside: the firmware needs no `log` in its flash for it.
pub(crate) fn ln(x: f64) -> Option<f64> {
    if !(0.05..=1.0).contains(&x) {
        return None;
    }
    let z = (x - 1.0) / (x + 1.0);
    let z2 = z * z;
    let (mut sum, mut term, mut k) = (0.0, z, 1.0);
    while k < 400.0 {
        let add = term / k;
        sum += add;
        if add.abs() <= 1e-17 * sum.abs() {
            break;
        }
        term *= z2;
        k += 2.0;
    }
    Some(2.0 * sum)
}

/// acos c for c in [0, 1] (angles up to π/2; the blocks are ~0.25 rad of the oscillation) as
/// 2·asin √((1 − c)/2) by the arcsine's series, `None` outside.
pub(crate) fn acos(c: f64) -> Option<f64> {
    if !(0.0..=1.0).contains(&c) {
        return None;
    }
    let x2 = 0.5 * (1.0 - c);
    let x = libm::sqrt(x2);
    // asin x = Σ a_k x^(2k+1)/(2k + 1), a_(k+1) = a_k·(2k + 1)/(2k + 2); x ≤ 1/√2.
    let (mut sum, mut a, mut p, mut k) = (0.0, 1.0, x, 0.0);
    while k < 200.0 {
        let add = a * p / (2.0 * k + 1.0);
        sum += add;
        if add <= 1e-17 * sum {
            break;
        }
        a *= (2.0 * k + 1.0) / (2.0 * k + 2.0);
        p *= x2;
        k += 1.0;
    }
    Some(2.0 * sum)
}

#[cfg(test)]
mod tests;
