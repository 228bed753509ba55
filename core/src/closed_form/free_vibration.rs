//! The exact free vibration of the relative motion δ'' + 2aδ' + ω0²δ = 0 (eq 25 without forcing).
//!
//! Every method is built from the four functions of τ ≥ 0
//!
//! * `ec  = e^{−aτ} C(τ)`, `es = e^{−aτ} S(τ)`,
//! * `ecm = e^{−aτ}(C − aS)`, `ecp = e^{−aτ}(C + aS)`,
//!
//! with C = cos nτ, S = sin(nτ)/n (underdamped), C = 1, S = τ (critical), C = cosh ντ,
//! S = sinh(ντ)/ν (overdamped). S is written so that it tends to τ continuously as n, ν → 0, and the
//! overdamped forms use the two real rates r1 = ω0²/(a+ν) (slow, no cancellation) and r2 = a + ν, so
//! nothing overflows, underflows to NaN or cancels catastrophically for any a, ν, τ.
//!
//! The state-transition matrix of (δ − δ_eq, δ') over τ is `[[ecp, es], [−ω0²·es, ecm]]`, and the
//! top-mass step response (friction stepping from 0 to +F0) is `gμ (1 − ecm(τ))`.

use crate::math::{Real, Transcendentals};
use crate::structure::{Regime, Structure};

/// The four free-vibration functions at one τ (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FreeVibration<T> {
    /// e^{−aτ} C(τ).
    pub ec: T,
    /// e^{−aτ} S(τ) (seconds).
    pub es: T,
    /// e^{−aτ}(C − aS): the decaying part of the step response, 1 at τ = 0.
    pub ecm: T,
    /// e^{−aτ}(C + aS).
    pub ecp: T,
}

/// Coefficients of the free vibration of one structure, in precision `T`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kernel<T> {
    regime: Regime,
    a: T,
    omega_d: T,
    omega0_sq: T,
    /// Slow rate r1 = ω0²/(a + ν) (overdamped) or a.
    r1: T,
    /// Fast rate r2 = a + ν (overdamped) or a.
    r2: T,
    /// Overdamped and ν > a/2: use the two-exponential form for ecm.
    strongly_overdamped: bool,
}

impl<T: Real> Kernel<T> {
    /// The kernel of a structure, coefficients rounded to `T`.
    pub fn new(s: &Structure) -> Self {
        let (a, wd) = (s.a(), s.omega_d());
        Self {
            regime: s.regime(),
            a: T::from_f64(a),
            omega_d: T::from_f64(wd),
            omega0_sq: T::from_f64(s.omega0_sq()),
            r1: T::from_f64(s.slow_rate()),
            r2: T::from_f64(if s.regime() == Regime::Overdamped {
                a + wd
            } else {
                a
            }),
            strongly_overdamped: s.regime() == Regime::Overdamped && wd > 0.5 * a,
        }
    }

    /// The kernel of the fixed-base oscillator δ'' + 2ξpδ' + p²δ = 0 (the top mass while the base
    /// sticks): a = ξp, ω0 = p, underdamped since 0 ≤ ξ < 1 (or critical when ξ rounds to 1).
    pub fn fixed_base(s: &Structure) -> Self {
        let (p, xi) = (s.p(), s.xi());
        let q = (1.0 - xi) * (1.0 + xi);
        let regime = if q > 0.0 {
            Regime::Underdamped
        } else {
            Regime::Critical
        };
        Self {
            regime,
            a: T::from_f64(xi * p),
            omega_d: T::from_f64(p * libm::sqrt(q.max(0.0))),
            omega0_sq: T::from_f64(p * p),
            r1: T::from_f64(xi * p),
            r2: T::from_f64(xi * p),
            strongly_overdamped: false,
        }
    }

    /// The coefficients: (regime, [a, ω_d (or ν), ω0², r1, r2], strongly overdamped), for
    /// [`Self::from_parts`].
    pub fn to_parts(&self) -> (Regime, [T; 5], bool) {
        (
            self.regime,
            [self.a, self.omega_d, self.omega0_sq, self.r1, self.r2],
            self.strongly_overdamped,
        )
    }

    /// A kernel from the coefficients of [`Self::to_parts`] (e.g. computed by a build script).
    pub const fn from_parts(regime: Regime, c: [T; 5], strongly_overdamped: bool) -> Self {
        let [a, omega_d, omega0_sq, r1, r2] = c;
        Self {
            regime,
            a,
            omega_d,
            omega0_sq,
            r1,
            r2,
            strongly_overdamped,
        }
    }

    /// ω0² = Mp².
    pub fn omega0_sq(&self) -> T {
        self.omega0_sq
    }

    /// Decay rate a.
    pub fn a(&self) -> T {
        self.a
    }

    /// Evaluate the four functions at τ ≥ 0 with the transcendentals of `M`.
    #[inline]
    pub fn eval<M: Transcendentals<T>>(&self, tau: T) -> FreeVibration<T> {
        let two = T::ONE + T::ONE;
        match self.regime {
            Regime::Underdamped => {
                let e = M::exp(-(self.a * tau));
                let (sn, cs) = M::sin_cos(self.omega_d * tau);
                let ec = e * cs;
                let es = e * (sn / self.omega_d);
                let aes = self.a * es;
                FreeVibration {
                    ec,
                    es,
                    ecm: ec - aes,
                    ecp: ec + aes,
                }
            }
            Regime::Critical => {
                let e = M::exp(-(self.a * tau));
                let es = e * tau;
                let aes = self.a * es;
                FreeVibration {
                    ec: e,
                    es,
                    ecm: e - aes,
                    ecp: e + aes,
                }
            }
            Regime::Overdamped => {
                let e1 = M::exp(-(self.r1 * tau));
                let e2 = M::exp(-(self.r2 * tau));
                let ec = (e1 + e2) / two;
                // e^{−aτ} sinh(ντ)/ν = e1 (1 − e^{−2ντ}) / (2ν), via expm1: exact as ν → 0.
                let x = two * self.omega_d * tau;
                let es = if x > T::ZERO {
                    e1 * (-M::expm1(-x) / (two * self.omega_d))
                } else {
                    e1 * tau
                };
                let aes = self.a * es;
                let ecm = if self.strongly_overdamped {
                    (self.r2 * e2 - self.r1 * e1) / (two * self.omega_d)
                } else {
                    ec - aes
                };
                FreeVibration {
                    ec,
                    es,
                    ecm,
                    ecp: ec + aes,
                }
            }
        }
    }

    /// An upper bound of |ecm(τ)| and |ecp(τ)|: e^{−r1 τ}(1 + aτ).
    pub fn envelope<M: Transcendentals<T>>(&self, tau: T) -> T {
        M::exp(-(self.r1 * tau)) * (T::ONE + self.a * tau)
    }

    /// τ beyond which [`Kernel::envelope`] decreases monotonically (1/r1 − 1/a, or 0).
    pub fn envelope_peak(&self) -> T {
        if self.regime == Regime::Overdamped && self.r1 > T::ZERO && self.a > T::ZERO {
            T::ONE / self.r1 - T::ONE / self.a
        } else {
            T::ZERO
        }
    }

    /// The slow decay rate r1 (0 for an undamped structure).
    pub fn slow_rate(&self) -> T {
        self.r1
    }
}

/// The top-mass step response per unit gμ: 1 − ecm(τ) for τ ≥ 0, 0 before.
pub fn unit_step_response(kernel: &Kernel<f64>, tau: f64) -> f64 {
    if tau < 0.0 {
        0.0
    } else {
        1.0 - kernel.eval::<crate::math::Libm>(tau).ecm
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;
    use crate::structure::StructureParams;

    fn structure(m1: f64, m2: f64, xi: f64) -> Structure {
        Structure::new(StructureParams {
            m1_kg: m1,
            m2_kg: m2,
            natural_frequency_hz: 7.0,
            damping_ratio: xi,
            friction_coefficient: 0.2,
            gravity_m_s2: 9.80665,
        })
        .unwrap()
    }

    /// The textbook forms of docs/equations.md ("Free vibration"), written independently.
    fn textbook_ecm(s: &Structure, t: f64) -> f64 {
        let a = s.a();
        match s.regime() {
            Regime::Underdamped => {
                let n = s.n().unwrap();
                let eps = s.epsilon().unwrap();
                (-a * t).exp() * (n * t + eps).cos() / eps.cos()
            }
            Regime::Critical => (-a * t).exp() * (1.0 - a * t),
            Regime::Overdamped => {
                let nu = s.nu().unwrap();
                (-a * t).exp() * ((nu * t).cosh() - a / nu * (nu * t).sinh())
            }
        }
    }

    #[test]
    fn matches_textbook_forms_in_each_regime() {
        for (m1, m2, xi) in [
            (29.5, 1.75, 0.05),
            (3.0, 1.0, 0.5),
            (3.0, 1.0, 0.7),
            (1.0, 1.0, 0.0),
        ] {
            let s = structure(m1, m2, xi);
            let k = Kernel::<f64>::new(&s);
            for i in 0..200 {
                let t = i as f64 * 1e-3;
                let got = k.eval::<Libm>(t).ecm;
                let want = textbook_ecm(&s, t);
                assert!(
                    (got - want).abs() < 1e-12,
                    "{m1} {m2} {xi} t={t}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn continuous_across_critical_damping() {
        // M = 4; ξ = 0.5 ± δ puts Mξ² = 1 ± 4δ.
        let (below, at, above) = (
            Kernel::<f64>::new(&structure(3.0, 1.0, 0.5 - 2.5e-10)),
            Kernel::<f64>::new(&structure(3.0, 1.0, 0.5)),
            Kernel::<f64>::new(&structure(3.0, 1.0, 0.5 + 2.5e-10)),
        );
        for i in 0..1000 {
            let t = i as f64 * 1e-3;
            let (b, c, a) = (
                below.eval::<Libm>(t),
                at.eval::<Libm>(t),
                above.eval::<Libm>(t),
            );
            for (x, y) in [(b.ecm, c.ecm), (a.ecm, c.ecm), (b.es, c.es), (a.es, c.es)] {
                assert!((x - y).abs() < 1e-9, "t={t}: {x} vs {y}");
            }
        }
    }

    #[test]
    fn vanishing_base_mass_is_finite_and_tends_to_eq39() {
        let s = structure(1.0, 1e-9, 0.05);
        let k = Kernel::<f64>::new(&s);
        for i in 0..100 {
            let t = i as f64 * 1e-4;
            let f = k.eval::<Libm>(t);
            assert!(f.ecm.is_finite() && f.es.is_finite() && f.ecp.is_finite());
            if t > 0.0 {
                // Step response → gμ: the decaying part is at most r1/(2ν) ≈ 1e-9.
                assert!(f.ecm.abs() < 1e-7, "t={t}: {}", f.ecm);
            }
        }
        assert_eq!(k.eval::<Libm>(0.0).ecm, 1.0);
        assert!(k.eval::<Libm>(1e300).ecm.abs() < 1e-300);
    }
}
