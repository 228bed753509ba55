//! The structure: a top mass on a spring and dashpot over a sliding base (paper Fig. 1), validated on
//! construction, with the derived quantities of the paper (eq 11-13, 26-27, 30-31, 34-38) and of
//! `docs/equations.md`.

use crate::error::{check, Error, Param};

/// Standard gravity (m/s²), the default of scene files.
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// Raw parameters of a structure, in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StructureParams {
    /// Top mass m1 (kg), > 0.
    pub m1_kg: f64,
    /// Sliding-base mass m2 (kg), > 0.
    pub m2_kg: f64,
    /// Fixed-base natural frequency p/(2π) (Hz), > 0.
    pub natural_frequency_hz: f64,
    /// Fixed-base damping ratio ξ, 0 ≤ ξ < 1.
    pub damping_ratio: f64,
    /// Kinetic friction coefficient μ, > 0.
    pub friction_coefficient: f64,
    /// Gravitational acceleration g (m/s²), > 0.
    pub gravity_m_s2: f64,
}

/// Damping regime of the relative motion δ = u1 − u2 (damping ratio ζ = √M·ξ).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Regime {
    /// Mξ² < 1: pseudo-harmonic free vibration at n (eq 30).
    Underdamped,
    /// Mξ² = 1: critically damped.
    Critical,
    /// Mξ² > 1: two real decay rates, no pseudo-harmonic motion.
    Overdamped,
}

/// A validated structure with its derived quantities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Structure {
    params: StructureParams,
    p: f64,
    mass_ratio: f64,
    a: f64,
    zeta: f64,
    omega0_sq: f64,
    /// 1 − ζ², computed as (1 − ζ)(1 + ζ) (signed).
    one_minus_zeta_sq: f64,
    /// n (underdamped), ν (overdamped) or 0 (critical).
    omega_d: f64,
    regime: Regime,
}

impl Structure {
    /// Validate the parameters: all finite, m1 > 0, m2 > 0, frequency > 0, 0 ≤ ξ < 1, μ > 0, g > 0.
    pub fn new(params: StructureParams) -> Result<Self, Error> {
        let m1 = check(Param::M1, params.m1_kg, params.m1_kg > 0.0, "m1 > 0 kg")?;
        let m2 = check(Param::M2, params.m2_kg, params.m2_kg > 0.0, "m2 > 0 kg")?;
        let f = check(
            Param::NaturalFrequency,
            params.natural_frequency_hz,
            params.natural_frequency_hz > 0.0,
            "natural frequency > 0 Hz",
        )?;
        let xi = check(
            Param::DampingRatio,
            params.damping_ratio,
            (0.0..1.0).contains(&params.damping_ratio),
            "0 <= damping ratio < 1",
        )?;
        check(
            Param::FrictionCoefficient,
            params.friction_coefficient,
            params.friction_coefficient > 0.0,
            "friction coefficient > 0",
        )?;
        check(
            Param::Gravity,
            params.gravity_m_s2,
            params.gravity_m_s2 > 0.0,
            "gravity > 0 m/s^2",
        )?;
        let p = 2.0 * core::f64::consts::PI * f;
        // M = (m1 + m2)/m2 = 1 + m1/m2 (eq 13), exact for any ratio.
        let mass_ratio = 1.0 + m1 / m2;
        let (omega0_sq, a) = (mass_ratio * p * p, mass_ratio * p * xi);
        let gmu = params.gravity_m_s2 * params.friction_coefficient;
        if !(mass_ratio.is_finite() && omega0_sq.is_finite() && gmu.is_finite()) {
            return Err(Error::OutOfRange {
                param: Param::M2,
                value: m2,
                expected: "m1/m2 and (m1/m2)·p² representable as finite numbers",
            });
        }
        let zeta = libm::sqrt(mass_ratio) * xi;
        let one_minus_zeta_sq = (1.0 - zeta) * (1.0 + zeta);
        let omega0 = libm::sqrt(omega0_sq);
        let (omega_d, regime) = if one_minus_zeta_sq > 0.0 {
            (omega0 * libm::sqrt(one_minus_zeta_sq), Regime::Underdamped)
        } else if one_minus_zeta_sq < 0.0 {
            (omega0 * libm::sqrt(-one_minus_zeta_sq), Regime::Overdamped)
        } else {
            (0.0, Regime::Critical)
        };
        Ok(Self {
            params,
            p,
            mass_ratio,
            a,
            zeta,
            omega0_sq,
            one_minus_zeta_sq,
            omega_d,
            regime,
        })
    }

    /// The parameters this structure was built from.
    pub fn params(&self) -> &StructureParams {
        &self.params
    }
    /// Top mass m1 (kg).
    pub fn m1(&self) -> f64 {
        self.params.m1_kg
    }
    /// Base mass m2 (kg).
    pub fn m2(&self) -> f64 {
        self.params.m2_kg
    }
    /// Fixed-base damping ratio ξ.
    pub fn xi(&self) -> f64 {
        self.params.damping_ratio
    }
    /// Friction coefficient μ.
    pub fn mu(&self) -> f64 {
        self.params.friction_coefficient
    }
    /// Gravity g (m/s²).
    pub fn g(&self) -> f64 {
        self.params.gravity_m_s2
    }
    /// gμ (m/s²): the top-mass acceleration of a rigid sliding body (eq 6), the unit of errors.
    pub fn gmu(&self) -> f64 {
        self.params.gravity_m_s2 * self.params.friction_coefficient
    }
    /// Fixed-base circular frequency p = √(K/m1) (rad/s, eq 12).
    pub fn p(&self) -> f64 {
        self.p
    }
    /// Mass ratio M = (m1 + m2)/m2 (eq 13).
    pub fn mass_ratio(&self) -> f64 {
        self.mass_ratio
    }
    /// Decay rate a = Mpξ (1/s, eq 31).
    pub fn a(&self) -> f64 {
        self.a
    }
    /// Damping ratio of the relative motion ζ = √M·ξ (sin ε, eq 35 corrected).
    pub fn zeta(&self) -> f64 {
        self.zeta
    }
    /// Squared natural frequency of the relative motion ω0² = Mp² (rad²/s²).
    pub fn omega0_sq(&self) -> f64 {
        self.omega0_sq
    }
    /// 1 − ζ² = 1 − Mξ² (signed; its sign is the regime).
    pub fn one_minus_zeta_sq(&self) -> f64 {
        self.one_minus_zeta_sq
    }
    /// Sliding frequency n = p√M·√(1 − Mξ²) (eq 30), for the underdamped regime.
    pub fn n(&self) -> Option<f64> {
        (self.regime == Regime::Underdamped).then_some(self.omega_d)
    }
    /// ν = p√M·√(Mξ² − 1), for the overdamped regime.
    pub fn nu(&self) -> Option<f64> {
        (self.regime == Regime::Overdamped).then_some(self.omega_d)
    }
    /// |n| or ν (0 at critical damping): the imaginary or real part split of the eigenvalues −a ± i n.
    pub fn omega_d(&self) -> f64 {
        self.omega_d
    }
    /// The damping regime of the relative motion.
    pub fn regime(&self) -> Regime {
        self.regime
    }
    /// ε of eq (34)-(35): sin ε = √M·ξ, cos ε = √(1 − Mξ²) (underdamped only).
    pub fn epsilon(&self) -> Option<f64> {
        self.n()
            .map(|_| libm::atan2(self.zeta, libm::sqrt(self.one_minus_zeta_sq)))
    }
    /// ε' of eq (37)-(38): cos ε' = 2Mξ² − 1, sin ε' = 2nξ/p (underdamped only; ε' = π − 2ε).
    pub fn epsilon_prime(&self) -> Option<f64> {
        self.n().map(|n| {
            let c = 2.0 * self.zeta * self.zeta - 1.0;
            let s = 2.0 * n * self.params.damping_ratio / self.p;
            libm::atan2(s, c)
        })
    }
    /// Slow decay rate of the relative motion: a for under/critical damping, Mp²/(a + ν) otherwise
    /// (computed without cancellation).
    pub fn slow_rate(&self) -> f64 {
        match self.regime {
            Regime::Overdamped => self.omega0_sq / (self.a + self.omega_d),
            _ => self.a,
        }
    }
    /// Fixed-base displacement amplification β at circular frequency ω (eq 18).
    pub fn beta(&self, omega: f64) -> f64 {
        let r = omega / self.p;
        let xi = self.params.damping_ratio;
        1.0 / libm::sqrt((1.0 - r * r) * (1.0 - r * r) + (2.0 * xi * r) * (2.0 * xi * r))
    }
    /// Fixed-base steady-state peak absolute top acceleration per unit table acceleration amplitude
    /// at circular frequency ω (transmissibility √(1 + (2ξr)²)·β).
    pub fn fixed_base_transmissibility(&self, omega: f64) -> f64 {
        let r = omega / self.p;
        let xi = self.params.damping_ratio;
        libm::sqrt(1.0 + (2.0 * xi * r) * (2.0 * xi * r)) * self.beta(omega)
    }
}

/// The paper's Table 1 specimen (m1 29.5 kg, m2 1.75 kg, 7 Hz, ξ 0.05, μ 0.2): the structure of
/// the crate's unit tests.
#[cfg(test)]
#[allow(clippy::unwrap_used)]
pub(crate) fn table1() -> Structure {
    Structure::new(tests::table1()).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn table1() -> StructureParams {
        StructureParams {
            m1_kg: 29.5,
            m2_kg: 1.75,
            natural_frequency_hz: 7.0,
            damping_ratio: 0.05,
            friction_coefficient: 0.2,
            gravity_m_s2: STANDARD_GRAVITY,
        }
    }

    #[test]
    fn derived_quantities_of_table1() {
        let s = Structure::new(table1()).unwrap();
        let m = (29.5 + 1.75) / 1.75;
        assert!((s.mass_ratio() - m).abs() < 1e-14 * m);
        let p = 2.0 * core::f64::consts::PI * 7.0;
        assert!((s.p() - p).abs() < 1e-12);
        assert!((s.a() - m * p * 0.05).abs() < 1e-12);
        assert_eq!(s.regime(), Regime::Underdamped);
        let n = p * m.sqrt() * (1.0 - m * 0.0025).sqrt();
        assert!((s.n().unwrap() - n).abs() < 1e-10 * n);
        // ε' = π − 2ε (cos ε' = 2Mξ² − 1, sin ε' = 2nξ/p).
        let (e, ep) = (s.epsilon().unwrap(), s.epsilon_prime().unwrap());
        assert!((ep - (core::f64::consts::PI - 2.0 * e)).abs() < 1e-12);
        assert!((libm::sin(e) - m.sqrt() * 0.05).abs() < 1e-14);
    }

    #[test]
    fn regimes() {
        let mut p = table1();
        // M = 4, ξ = 0.5: Mξ² = 1 exactly.
        p.m1_kg = 3.0;
        p.m2_kg = 1.0;
        p.damping_ratio = 0.5;
        assert_eq!(Structure::new(p).unwrap().regime(), Regime::Critical);
        p.damping_ratio = 0.6;
        let s = Structure::new(p).unwrap();
        assert_eq!(s.regime(), Regime::Overdamped);
        // slow root times fast root = ω0².
        let fast = s.a() + s.nu().unwrap();
        assert!((s.slow_rate() * fast / s.omega0_sq() - 1.0).abs() < 1e-14);
    }

    #[test]
    fn each_bad_parameter_is_named() {
        type Case = (fn(&mut StructureParams), Param);
        let cases: [Case; 9] = [
            (|p| p.m1_kg = 0.0, Param::M1),
            (|p| p.m1_kg = f64::NAN, Param::M1),
            (|p| p.m2_kg = -1.0, Param::M2),
            (|p| p.natural_frequency_hz = 0.0, Param::NaturalFrequency),
            (
                |p| p.natural_frequency_hz = f64::INFINITY,
                Param::NaturalFrequency,
            ),
            (|p| p.damping_ratio = 1.0, Param::DampingRatio),
            (|p| p.damping_ratio = -0.01, Param::DampingRatio),
            (|p| p.friction_coefficient = 0.0, Param::FrictionCoefficient),
            (|p| p.gravity_m_s2 = 0.0, Param::Gravity),
        ];
        for (mutate, param) in cases {
            let mut p = table1();
            mutate(&mut p);
            let err = Structure::new(p).unwrap_err();
            assert_eq!(err.param(), param, "{err}");
        }
    }
}
