//! The friction law of the sliding interface: the kinetic coefficient as a function of the slip
//! speed.
//!
//! * **Coulomb** (the paper's): μ(v) = μ, constant.
//! * **Velocity-dependent** (PTFE on stainless steel; Constantinou, Mokha and Reinhorn 1990):
//!   μ(v) = μ_fast − (μ_fast − μ_slow)·e^{−a|v|}, from μ_slow at rest to μ_fast above a few 1/a.
//!   μ_fast is the structure's friction coefficient; μ_slow ≤ μ_fast and a > 0 are the law's.
//!
//! The Coulomb law is the limit a → ∞ (for v ≠ 0) and the case μ_slow = μ_fast.

use crate::error::{Error, Param};
use crate::math::{Libm, Transcendentals};

/// The friction law of the sliding interface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionLaw {
    /// Constant kinetic coefficient (the structure's μ).
    Coulomb,
    /// μ(v) = μ_fast − (μ_fast − μ_slow)·e^{−a|v|}, μ_fast the structure's μ.
    VelocityDependent {
        /// μ as |v| → 0.
        mu_slow: f64,
        /// a (s/m).
        rate_s_m: f64,
    },
}

impl FrictionLaw {
    /// A velocity-dependent law over the kinetic coefficient `mu_fast`, validated: μ_slow finite,
    /// in (0, μ_fast]; a finite and > 0.
    pub fn velocity_dependent(mu_slow: f64, rate_s_m: f64, mu_fast: f64) -> Result<Self, Error> {
        if !mu_slow.is_finite() {
            return Err(Error::NotFinite(Param::MuSlow));
        }
        if !(mu_slow > 0.0 && mu_slow <= mu_fast) {
            return Err(Error::OutOfRange {
                param: Param::MuSlow,
                value: mu_slow,
                expected: "0 < mu_slow <= the kinetic friction coefficient",
            });
        }
        if !rate_s_m.is_finite() {
            return Err(Error::NotFinite(Param::FrictionRate));
        }
        if rate_s_m <= 0.0 {
            return Err(Error::OutOfRange {
                param: Param::FrictionRate,
                value: rate_s_m,
                expected: "rate > 0 s/m",
            });
        }
        Ok(FrictionLaw::VelocityDependent { mu_slow, rate_s_m })
    }

    /// The kinetic coefficient at slip speed `speed` (m/s, its magnitude is used) for the
    /// structure's coefficient `mu_fast`.
    pub fn coefficient(&self, mu_fast: f64, speed: f64) -> f64 {
        match *self {
            FrictionLaw::Coulomb => mu_fast,
            FrictionLaw::VelocityDependent { mu_slow, rate_s_m } => {
                mu_fast - (mu_fast - mu_slow) * Libm::exp(-rate_s_m * speed.abs())
            }
        }
    }

    /// d μ / d|v| at slip speed `speed` (1/(m/s)).
    pub fn slope(&self, mu_fast: f64, speed: f64) -> f64 {
        match *self {
            FrictionLaw::Coulomb => 0.0,
            FrictionLaw::VelocityDependent { mu_slow, rate_s_m } => {
                rate_s_m * (mu_fast - mu_slow) * Libm::exp(-rate_s_m * speed.abs())
            }
        }
    }

    /// The coefficient at rest (μ_slow; μ for Coulomb): the friction a slide starts with.
    pub fn at_rest(&self, mu_fast: f64) -> f64 {
        match *self {
            FrictionLaw::Coulomb => mu_fast,
            FrictionLaw::VelocityDependent { mu_slow, .. } => mu_slow,
        }
    }

    /// Whether the law is Coulomb's (constant μ), including μ_slow = μ_fast.
    pub fn is_coulomb(&self, mu_fast: f64) -> bool {
        match *self {
            FrictionLaw::Coulomb => true,
            FrictionLaw::VelocityDependent { mu_slow, .. } => mu_slow == mu_fast,
        }
    }

    /// The law's name as in a scene's `[friction] law`.
    pub const fn name(&self) -> &'static str {
        match self {
            FrictionLaw::Coulomb => "coulomb",
            FrictionLaw::VelocityDependent { .. } => "velocity-dependent",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_and_validation() {
        let law = FrictionLaw::velocity_dependent(0.12, 30.0, 0.2).unwrap();
        assert_eq!(law.coefficient(0.2, 0.0), 0.12);
        // Symmetric in v; e^{-30·0.1} = 0.049787068367863944.
        let at = 0.2 - 0.08 * 0.049_787_068_367_863_944;
        assert!((law.coefficient(0.2, -0.1) - at).abs() < 1e-15);
        assert!((law.coefficient(0.2, 10.0) - 0.2).abs() < 1e-15);
        // The slope is the derivative (central difference).
        let h = 1e-6;
        let fd = (law.coefficient(0.2, 0.05 + h) - law.coefficient(0.2, 0.05 - h)) / (2.0 * h);
        assert!((fd - law.slope(0.2, 0.05)).abs() < 1e-8);
        assert_eq!(FrictionLaw::Coulomb.coefficient(0.2, 3.0), 0.2);
        let e = FrictionLaw::velocity_dependent(0.25, 30.0, 0.2).unwrap_err();
        assert_eq!(e.param(), Param::MuSlow);
        let e = FrictionLaw::velocity_dependent(0.1, 0.0, 0.2).unwrap_err();
        assert_eq!(e.param(), Param::FrictionRate);
        let e = FrictionLaw::velocity_dependent(f64::NAN, 1.0, 0.2).unwrap_err();
        assert_eq!(e, Error::NotFinite(Param::MuSlow));
        assert!(FrictionLaw::velocity_dependent(0.2, 5.0, 0.2)
            .unwrap()
            .is_coulomb(0.2));
    }
}
