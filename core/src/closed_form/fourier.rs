//! The Fourier methods: trapezoid (TFM, eq 14-18) and rectangular (RFM, eq 20-22), corrected as in
//! `docs/equations.md`.
//!
//! The friction is a trapezoid wave of period T whose ramps take a phase α (eq 8, corrected):
//! F(t) = F0 Σ_{n odd} b_n sin(ω_n t), ω_n = 2πn/T, b_n = 4 sin(nα)/(παn²) (α → 0: b_n = 4/(πn),
//! the rectangular wave of eq 19). The top-mass acceleration is
//! ü1 = Σ_{n odd} A_n cos ω_n t + B_n sin ω_n t with D_n = (Mp² − ω_n²)² + 4M²p²ξ²ω_n²,
//! B_n = Mgμ b_n [p²(Mp² − ω_n²) + 4Mp²ξ²ω_n²]/D_n, A_n = −Mgμ b_n 2pξω_n³/D_n.
//!
//! A harmonic count H means the H terms n = 1, 3, …, 2H − 1.

use crate::error::{check, Error, Param};
use crate::structure::Structure;
use core::f64::consts::PI;

/// Largest harmonic count the adaptive peak search will use.
pub const MAX_HARMONICS: u32 = 1 << 21;

/// Relative change of the peak below which the harmonic count is converged (default count).
pub const PEAK_CONVERGENCE: f64 = 1e-6;

/// The steady-state Fourier response to a trapezoid (or rectangular) friction wave.
#[derive(Debug, Clone, Copy)]
pub struct FourierResponse {
    mgmu: f64,
    p: f64,
    xi: f64,
    m: f64,
    omega: f64,
    period: f64,
    alpha: f64,
}

/// Result of the TFM for a harmonic table motion A0·sin(2πt/T).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tfm {
    /// βA0 > gμ: the base slides; the trapezoid friction wave with α of eq (17).
    Sliding {
        /// The response.
        response: FourierResponse,
        /// α (rad), eq (17).
        alpha_rad: f64,
        /// β, eq (18).
        beta: f64,
    },
    /// βA0 ≤ gμ: the base does not slide; the fixed-base steady state applies.
    FixedBase(FixedBase),
}

impl PartialEq for FourierResponse {
    fn eq(&self, o: &Self) -> bool {
        self.mgmu == o.mgmu
            && self.p == o.p
            && self.xi == o.xi
            && self.m == o.m
            && self.period == o.period
            && self.alpha == o.alpha
    }
}

/// Fixed-base steady state under table acceleration A0·sin(ωt).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixedBase {
    /// β, eq (18).
    pub beta: f64,
    /// Peak absolute top acceleration (m/s²).
    pub peak_m_s2: f64,
    /// Phase lead of ü1 over the table acceleration (rad).
    pub phase_rad: f64,
    /// Table circular frequency ω (rad/s).
    pub omega: f64,
}

impl FixedBase {
    /// ü1(t) (m/s²).
    pub fn accel(&self, t: f64) -> f64 {
        self.peak_m_s2 * libm::sin(self.omega * t + self.phase_rad)
    }
}

/// Validate the harmonic input (A0, T).
fn check_input(amplitude: f64, period: f64) -> Result<(), Error> {
    check(Param::Amplitude, amplitude, amplitude >= 0.0, ">= 0 m/s^2")?;
    check(Param::Period, period, period > 0.0, "> 0 s")?;
    Ok(())
}

impl Tfm {
    /// The TFM for table acceleration `amplitude`·sin(2πt/`period`).
    pub fn new(s: &Structure, amplitude: f64, period: f64) -> Result<Self, Error> {
        check_input(amplitude, period)?;
        let omega = 2.0 * PI / period;
        let beta = s.beta(omega);
        if beta.is_nan() || beta * amplitude <= s.gmu() {
            let r = omega / s.p();
            let xi = s.xi();
            // Fixed-base absolute acceleration transfer (p² + 2iξpω)/(p² − ω² + 2iξpω).
            let num_phase = libm::atan2(2.0 * xi * r, 1.0);
            let den_phase = libm::atan2(2.0 * xi * r, 1.0 - r * r);
            return Ok(Tfm::FixedBase(FixedBase {
                beta,
                peak_m_s2: amplitude * s.fixed_base_transmissibility(omega),
                phase_rad: num_phase - den_phase,
                omega,
            }));
        }
        let alpha_rad = libm::asin(s.gmu() / (beta * amplitude));
        Ok(Tfm::Sliding {
            response: FourierResponse::trapezoid(s, period, alpha_rad)?,
            alpha_rad,
            beta,
        })
    }

    /// Whether the base slides.
    pub fn sliding(&self) -> bool {
        matches!(self, Tfm::Sliding { .. })
    }

    /// ü1(t) (m/s²) with `harmonics` terms (ignored when the base does not slide).
    pub fn accel(&self, t: f64, harmonics: u32) -> f64 {
        match self {
            Tfm::Sliding { response, .. } => response.accel(t, harmonics),
            Tfm::FixedBase(f) => f.accel(t),
        }
    }
}

impl FourierResponse {
    /// Trapezoid friction wave of period `period` with ramp phase `alpha_rad` in [0, π/2].
    pub fn trapezoid(s: &Structure, period: f64, alpha_rad: f64) -> Result<Self, Error> {
        check(Param::Period, period, period > 0.0, "> 0 s")?;
        check(
            Param::Alpha,
            alpha_rad,
            (0.0..=PI / 2.0).contains(&alpha_rad),
            "0 <= alpha <= pi/2",
        )?;
        Ok(Self {
            mgmu: s.mass_ratio() * s.gmu(),
            p: s.p(),
            xi: s.xi(),
            m: s.mass_ratio(),
            omega: 2.0 * PI / period,
            period,
            alpha: alpha_rad,
        })
    }

    /// Rectangular friction wave of period `period` (RFM, eq 19-22).
    pub fn rectangular(s: &Structure, period: f64) -> Result<Self, Error> {
        Self::trapezoid(s, period, 0.0)
    }

    /// Period T (s).
    pub fn period(&self) -> f64 {
        self.period
    }

    /// Ramp phase α (rad); 0 for the rectangular wave.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// (A_n, B_n) of odd harmonic n (eq 15-16 / 21-22, corrected).
    pub fn coefficients(&self, n: u32) -> (f64, f64) {
        let nf = n as f64;
        let b = if self.alpha > 0.0 {
            4.0 * libm::sin(nf * self.alpha) / (PI * self.alpha * nf * nf)
        } else {
            4.0 / (PI * nf)
        };
        let w = nf * self.omega;
        let (p, xi, m) = (self.p, self.xi, self.m);
        let k = m * p * p - w * w;
        let c = 2.0 * m * p * xi * w;
        let d = k * k + c * c;
        let bn = self.mgmu * b * (p * p * k + 4.0 * m * p * p * xi * xi * w * w) / d;
        let an = -self.mgmu * b * 2.0 * p * xi * w * w * w / d;
        (an, bn)
    }

    /// ü1(t) (m/s²) summed over `harmonics` odd harmonics.
    pub fn accel(&self, t: f64, harmonics: u32) -> f64 {
        // cos/sin(nθ) by an exact-angle restart every 64 terms and a rotation in between.
        let theta = libm::remainder(self.omega * t, 2.0 * PI);
        let (s2, c2) = libm::sincos(2.0 * theta);
        let (mut sn, mut cn) = (0.0, 0.0);
        let mut sum = 0.0;
        for k in 0..harmonics {
            let n = 2 * k + 1;
            if k % 64 == 0 {
                let (s, c) = libm::sincos(libm::remainder(n as f64 * theta, 2.0 * PI));
                sn = s;
                cn = c;
            } else {
                let (s, c) = (sn * c2 + cn * s2, cn * c2 - sn * s2);
                sn = s;
                cn = c;
            }
            let (a, b) = self.coefficients(n);
            sum += a * cn + b * sn;
        }
        sum
    }

    /// Steady-state peak of |ü1| (m/s²) over one period with `harmonics` terms.
    pub fn peak(&self, harmonics: u32) -> f64 {
        const GRID: u32 = 1024;
        let f = |t: f64| libm::fabs(self.accel(t, harmonics));
        let h = self.period / GRID as f64;
        // Candidates: the three largest grid values, each refined by golden-section search.
        let mut best = [(0.0f64, 0.0f64); 3];
        for i in 0..GRID {
            let t = i as f64 * h;
            let v = f(t);
            if v > best[2].1 {
                best[2] = (t, v);
                best.sort_unstable_by(|x, y| y.1.total_cmp(&x.1));
            }
        }
        let mut peak = best[0].1;
        for &(t0, _) in &best {
            let (mut lo, mut hi) = (t0 - h, t0 + h);
            let g = 0.618_033_988_749_894_9;
            let mut x1 = hi - g * (hi - lo);
            let mut x2 = lo + g * (hi - lo);
            let (mut f1, mut f2) = (f(x1), f(x2));
            for _ in 0..60 {
                if f1 > f2 {
                    hi = x2;
                    x2 = x1;
                    f2 = f1;
                    x1 = hi - g * (hi - lo);
                    f1 = f(x1);
                } else {
                    lo = x1;
                    x1 = x2;
                    f1 = f2;
                    x2 = lo + g * (hi - lo);
                    f2 = f(x2);
                }
                if hi - lo < 1e-13 * self.period {
                    break;
                }
            }
            peak = peak.max(f1).max(f2);
        }
        peak
    }

    /// The peak with a harmonic count doubled from 16 until it changes by less than
    /// [`PEAK_CONVERGENCE`] (relative), at most [`MAX_HARMONICS`]: (peak, harmonics).
    pub fn converged_peak(&self) -> (f64, u32) {
        let mut h = 16u32;
        let mut prev = self.peak(h);
        while h < MAX_HARMONICS {
            h *= 2;
            let next = self.peak(h);
            if libm::fabs(next - prev) <= PEAK_CONVERGENCE * libm::fabs(next) {
                return (next, h);
            }
            prev = next;
        }
        (prev, h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::table1;

    #[test]
    fn rotation_matches_direct_sum() {
        let r = FourierResponse::trapezoid(&table1(), 0.143, 0.3).unwrap();
        for i in 0..50 {
            let t = i as f64 * 0.0123;
            let mut direct = 0.0;
            for k in 0..500u32 {
                let n = 2 * k + 1;
                let (a, b) = r.coefficients(n);
                let w = n as f64 * 2.0 * PI / 0.143;
                direct += a * (w * t).cos() + b * (w * t).sin();
            }
            assert!((r.accel(t, 500) - direct).abs() < 1e-11);
        }
    }

    #[test]
    fn rfm_is_the_alpha_limit_of_tfm() {
        let s = table1();
        let rect = FourierResponse::rectangular(&s, 0.143).unwrap();
        let trap = FourierResponse::trapezoid(&s, 0.143, 1e-7).unwrap();
        for i in 0..100 {
            let t = i as f64 * 0.00143;
            let (x, y) = (rect.accel(t, 200), trap.accel(t, 200));
            assert!((x - y).abs() < 1e-9 * s.gmu(), "{x} {y}");
        }
    }

    #[test]
    fn no_sliding_gives_fixed_base_peak() {
        let s = table1();
        // Far below resonance with a small amplitude: βA0 < gμ.
        let tfm = Tfm::new(&s, 0.1, 1.0).unwrap();
        assert!(!tfm.sliding());
        let omega = 2.0 * PI;
        let r = omega / s.p();
        let want = 0.1 * (1.0 + (0.1 * r).powi(2)).sqrt()
            / ((1.0 - r * r).powi(2) + (0.1 * r).powi(2)).sqrt();
        match tfm {
            Tfm::FixedBase(f) => assert!((f.peak_m_s2 - want).abs() < 1e-15),
            _ => unreachable!(),
        }
    }
}
