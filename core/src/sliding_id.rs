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
//! **Estimation.** Least squares on every row whose three blocks lie in one sliding episode:
//! the rows' products are summed in f32 over pages of [`PAGE`] rows and the pages in f64, with a
//! forgetting factor per page. The estimate solves the 4×4 normal equations in f64; the
//! standard deviations are the formal ones, σ²·S⁻¹, carried to ω, ζ and μ·g to first order.

use crate::error::{check, Error, Param};
use crate::math::Real;

/// Rows summed in f32 before they are added to the f64 sums.
pub const PAGE: u32 = 32;
/// The block duration the identifier aims at, in radians of the prior's sliding oscillator
/// (ω·h). The error of μ·g = γ/α falls as h^(−3/2) (α grows as h², the noise of a block average
/// falls as h^(−1/2), the rows as 1/h): 0.25 rad leaves ~25 blocks per period, and episodes of
/// a few tens of samples still hold three blocks at 10 kHz.
pub const OMEGA_H: f64 = 0.25;
/// Largest decimation (samples per block).
pub const MAX_DECIMATION: u32 = 64;
/// Rows needed before an estimate.
pub const MIN_ROWS: f64 = 8.0;
/// Products kept per row: the 10 of the symmetric 4×4 normal matrix, the 4 of the right-hand
/// side, and the target's square.
const K: usize = 15;

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
    /// The page of rows (f32 on the firmware) and its row count.
    page: [T; K],
    page_rows: u32,
    /// The pages' sums (f64), with forgetting per page.
    sums: [f64; K],
    rows: f64,
    /// Rows ever added (wrapping).
    added: u32,
    rho_page: f64,
    /// Block duration (s).
    h: f64,
}

impl<T: Real> SlidingIdentifier<T> {
    /// An identifier for samples at `sample_rate_hz`, its blocks sized for the prior's sliding
    /// oscillator `prior_omega` (rad/s), forgetting `forgetting` per row in (0, 1].
    pub fn new(sample_rate_hz: f64, prior_omega: f64, forgetting: f64) -> Result<Self, Error> {
        check(
            Param::SampleRate,
            sample_rate_hz,
            sample_rate_hz > 0.0 && sample_rate_hz.is_finite(),
            "sample rate > 0 Hz",
        )?;
        check(
            Param::NaturalFrequency,
            prior_omega,
            prior_omega > 0.0 && prior_omega.is_finite(),
            "sliding circular frequency > 0",
        )?;
        check(
            Param::Forgetting,
            forgetting,
            forgetting > 0.0 && forgetting <= 1.0,
            "forgetting factor in (0, 1]",
        )?;
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
            page: [T::ZERO; K],
            page_rows: 0,
            sums: [0.0; K],
            rows: 0.0,
            added: 0,
            rho_page: (0..PAGE).fold(1.0, |a, _| a * forgetting),
            h: d / sample_rate_hz,
        })
    }

    /// Samples per block.
    pub fn decimation(&self) -> u32 {
        self.decimation
    }

    /// Rows ever added (wrapping): an estimate changes only when it does.
    pub fn rows_added(&self) -> u32 {
        self.added
    }

    /// One sample of the base acceleration `y` with its phase `level`: ±1 for a sample inside
    /// a sliding episode (the direction of the friction force), 0 for anything else (stuck, a
    /// phase change within the sample's interval, or a sample not to use). A level 0, a change
    /// of level or a non-finite sample ends the episode.
    #[inline(always)]
    pub fn push(&mut self, y: T, level: i8) {
        if level == 0 || level != self.level || !y.is_finite() {
            self.end_episode();
            if level == 0 || !y.is_finite() {
                return;
            }
            self.level = level;
        }
        self.sum += y;
        self.count += 1;
        if self.count >= self.decimation {
            self.block();
        }
    }

    /// Ends the episode: the next sample starts a new one.
    #[inline(always)]
    pub fn end_episode(&mut self) {
        (self.count, self.sum, self.prev_n, self.level) = (0, T::ZERO, 0, 0);
    }

    #[inline(never)]
    fn block(&mut self) {
        let y = self.sum * self.inv_n;
        (self.count, self.sum) = (0, T::ZERO);
        if self.prev_n >= 2 {
            let [y1, y2] = self.prev;
            let s = if self.level > 0 { T::ONE } else { -T::ONE };
            let t = y - (y1 + y1) + y2;
            let phi = [y1, y1 - y2, s, T::ONE];
            let mut k = 0;
            for i in 0..4 {
                for j in i..4 {
                    self.page[k] += phi[i] * phi[j];
                    k += 1;
                }
            }
            for p in phi {
                self.page[k] += p * t;
                k += 1;
            }
            self.page[k] += t * t;
            self.page_rows += 1;
            self.added = self.added.wrapping_add(1);
            if self.page_rows >= PAGE {
                self.fold();
            }
        }
        self.prev = [y, self.prev[0]];
        self.prev_n = (self.prev_n + 1).min(2);
    }

    /// Adds the page to the f64 sums (forgetting the older ones).
    #[inline(never)]
    fn fold(&mut self) {
        for (s, p) in self.sums.iter_mut().zip(self.page.iter_mut()) {
            *s = *s * self.rho_page + p.to_f64();
            *p = T::ZERO;
        }
        self.rows = self.rows * self.rho_page + self.page_rows as f64;
        self.page_rows = 0;
    }

    /// The estimate (`None` before [`MIN_ROWS`] rows, for singular normal equations, or for a
    /// fit that is not an underdamped oscillator with a positive friction acceleration). Until
    /// the base has slid both ways the friction and the offset are one constant: with
    /// `offset_known` the offset is then taken as 0 (the accelerometers were zeroed on a rest),
    /// without it there is no estimate.
    pub fn estimate(&self, offset_known: bool) -> Option<SlidingEstimate> {
        let mut v = self.sums;
        for (s, p) in v.iter_mut().zip(self.page.iter()) {
            *s += p.to_f64();
        }
        let rows = self.rows + self.page_rows as f64;
        if rows < MIN_ROWS {
            return None;
        }
        // S (upper triangle, row-major), c, tt.
        let s = [
            [v[0], v[1], v[2], v[3]],
            [v[1], v[4], v[5], v[6]],
            [v[2], v[5], v[7], v[8]],
            [v[3], v[6], v[8], v[9]],
        ];
        let c = [v[10], v[11], v[12], v[13]];
        // Both directions of sliding separate the friction from the offset; until then (one
        // direction: the last two regressors are equal up to sign) the offset is taken as 0.
        let (theta, inv, fit) = match solve(&s, &c) {
            Some(r) => r,
            None if !offset_known => return None,
            None => {
                let s3 = [
                    [s[0][0], s[0][1], s[0][2]],
                    [s[1][0], s[1][1], s[1][2]],
                    [s[2][0], s[2][1], s[2][2]],
                ];
                let (t, i3, fit) = solve(&s3, &[c[0], c[1], c[2]])?;
                let mut inv = [[0.0; 4]; 4];
                for (row, r3) in inv.iter_mut().zip(i3) {
                    row[..3].copy_from_slice(&r3);
                }
                ([t[0], t[1], t[2], 0.0], inv, fit)
            }
        };
        let sigma2 = libm::fmax(v[14] - fit, 0.0) / libm::fmax(rows - 4.0, 1.0);
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
        let zw = -libm::log(r2) / (2.0 * h);
        let wd = libm::acos(cos_wd) / h;
        let omega = libm::sqrt(zw * zw + wd * wd);
        let zeta = zw / omega;
        let friction_accel = gamma / alpha;
        if !(friction_accel > 0.0 && omega.is_finite()) {
            return None;
        }
        // First-order errors (small ωh: α ≈ (ωh)², β ≈ 2ζωh).
        let var = |i: usize, j: usize| sigma2 * inv[i][j];
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
        })
    }
}

/// The solution θ of S·θ = c, S⁻¹ and θ·c (`None` if S is not positive definite).
#[allow(clippy::type_complexity)]
fn solve<const N: usize>(
    s: &[[f64; N]; N],
    c: &[f64; N],
) -> Option<([f64; N], [[f64; N]; N], f64)> {
    let inv = invert_spd(s)?;
    let theta: [f64; N] = core::array::from_fn(|i| (0..N).map(|j| inv[i][j] * c[j]).sum());
    let fit = (0..N).map(|i| theta[i] * c[i]).sum();
    Some((theta, inv, fit))
}

/// The inverse of a symmetric positive definite matrix by Cholesky (`None` if it is not
/// positive definite to working precision).
#[allow(clippy::needless_range_loop)]
fn invert_spd<const N: usize>(a: &[[f64; N]; N]) -> Option<[[f64; N]; N]> {
    let mut l = [[0.0f64; N]; N];
    for i in 0..N {
        for j in 0..=i {
            let mut sum = a[i][j];
            for k in 0..j {
                sum -= l[i][k] * l[j][k];
            }
            if i == j {
                if sum <= 1e-9 * a[i][i].abs() || !sum.is_finite() {
                    return None;
                }
                l[i][i] = libm::sqrt(sum);
            } else {
                l[i][j] = sum / l[j][j];
            }
        }
    }
    // L⁻¹ (lower), then S⁻¹ = L⁻ᵀ·L⁻¹.
    let mut li = [[0.0f64; N]; N];
    for i in 0..N {
        li[i][i] = 1.0 / l[i][i];
        for j in 0..i {
            let mut sum = 0.0;
            for k in j..i {
                sum -= l[i][k] * li[k][j];
            }
            li[i][j] = sum / l[i][i];
        }
    }
    let mut inv = [[0.0f64; N]; N];
    for i in 0..N {
        for j in 0..N {
            inv[i][j] = (i.max(j)..N).map(|k| li[k][i] * li[k][j]).sum();
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests;
