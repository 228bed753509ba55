//! The constants of one truth simulation ([`Model`]): masses, frequencies, friction thresholds, the
//! sliding free-vibration kernel, the event-bracketing grid steps and the rounding tolerances.

use super::phase::Phase;
use crate::table_motion::TableMotion;
use ssvr_core::closed_form::free_vibration::Kernel;
use ssvr_core::{FrictionLaw, Regime, Structure};
use std::f64::consts::PI;

/// Relaxation rate of the slip speed (1/s) above which the integrated sliding phases are stiff.
pub(super) const STIFF_RATE: f64 = 1e4;

/// Grid points per shortest time scale (2π/ω of the fastest frequency or rate) for event bracketing.
const GRID_PER_PERIOD: f64 = 64.0;

/// Constants of one simulation.
#[derive(Debug, Clone, Copy)]
pub(super) struct Model {
    pub(super) m1: f64,
    pub(super) m2: f64,
    pub(super) m_total: f64,
    /// m1/(m1+m2).
    pub(super) r: f64,
    /// M = (m1+m2)/m2.
    pub(super) mass_ratio: f64,
    pub(super) p2: f64,
    pub(super) two_xi_p: f64,
    /// Kinetic friction F0 = μ(m1+m2)g (N).
    pub(super) f0: f64,
    /// Breakaway threshold μs(m1+m2)g (N).
    pub(super) fs: f64,
    /// gμ/p² (m): the sliding equilibrium drift per unit direction.
    pub(super) delta_eq: f64,
    /// Fixed-base decay rate ξp and damped frequency p√(1−ξ²).
    pub(super) fb_alpha: f64,
    pub(super) fb_n: f64,
    /// Sliding free vibration (eq 25).
    pub(super) kernel: Kernel<f64>,
    pub(super) omega0_sq: f64,
    /// Bracketing grid steps (s): stuck, sliding, and the finest sliding step right after a
    /// transition when the sliding drift is overdamped (its fast mode e^{−(a+ν)τ}).
    pub(super) h_stuck: f64,
    pub(super) h_slide: f64,
    pub(super) h_fast: f64,
    /// Tolerances of "near the threshold": force (N) and slip velocity (m/s).
    pub(super) tol_f: f64,
    pub(super) tol_v: f64,
    /// Sliding phases integrated ([`super::integrate`]) rather than in closed form: a
    /// velocity-dependent law (or a Coulomb one, forced, to check the integration).
    pub(super) integrated: bool,
    /// Integrated sliding phases are stiff: the friction's relaxation a·(μ_fast − μ_slow)·N/m2
    /// exceeds [`STIFF_RATE`]; they are integrated by Rodas5 ([`super::stiff`]).
    pub(super) stiff: bool,
    /// The law μ(v) = mu_fast − mu_drop·e^{−rate·v} (mu_drop = 0, rate = 0 for Coulomb) and the
    /// normal force (m1+m2)g (N).
    pub(super) mu_fast: f64,
    pub(super) mu_drop: f64,
    pub(super) rate: f64,
    pub(super) normal: f64,
    /// Units of the integration's error scale: gμ/p² (m) and gμ/p (m/s).
    pub(super) disp_unit: f64,
    pub(super) vel_unit: f64,
}

impl Model {
    pub(super) fn new(
        s: &Structure,
        mu_static: f64,
        table: &TableMotion,
        law: FrictionLaw,
        integrate: bool,
    ) -> Self {
        let (m1, m2, p, xi) = (s.m1(), s.m2(), s.p(), s.xi());
        let m_total = m1 + m2;
        let f0 = s.mu() * m_total * s.g();
        let fb_n = p * ((1.0 - xi) * (1.0 + xi)).sqrt();
        // Time scales: the fixed-base frequency, the input frequency and, while sliding, the drift's
        // frequency ω0 (under/critically damped) or its slow rate (overdamped); the overdamped fast
        // mode only matters for a few 1/(a+ν) after a transition and gets a geometric grid there.
        let omega_in = match table {
            TableMotion::Harmonic { period_s, .. } => 2.0 * PI / period_s,
            TableMotion::Delayed { motion, .. } => match motion.as_ref() {
                TableMotion::Harmonic { period_s, .. } => 2.0 * PI / period_s,
                _ => 0.0,
            },
            _ => 0.0,
        };
        let omega_stuck = p.max(omega_in);
        let (omega_slide, omega_fast) = match s.regime() {
            Regime::Overdamped => (
                omega_stuck.max(s.slow_rate()),
                omega_stuck.max(s.slow_rate()).max(s.a() + s.omega_d()),
            ),
            _ => {
                let w = omega_stuck.max(s.omega0_sq().sqrt());
                (w, w)
            }
        };
        let step = |w: f64| 2.0 * PI / (GRID_PER_PERIOD * w);
        Self {
            m1,
            m2,
            m_total,
            r: m1 / m_total,
            mass_ratio: s.mass_ratio(),
            p2: p * p,
            two_xi_p: 2.0 * xi * p,
            f0,
            fs: mu_static * m_total * s.g(),
            delta_eq: s.gmu() / (p * p),
            fb_alpha: xi * p,
            fb_n,
            kernel: Kernel::new(s),
            omega0_sq: s.omega0_sq(),
            h_stuck: step(omega_stuck),
            h_slide: step(omega_slide),
            h_fast: step(omega_fast),
            tol_f: 1e-11 * mu_static * m_total * s.g(),
            tol_v: 1e-13 * s.gmu() / p,
            integrated: integrate || !law.is_coulomb(s.mu()),
            stiff: match law {
                FrictionLaw::Coulomb => false,
                FrictionLaw::VelocityDependent { mu_slow, rate_s_m } => {
                    rate_s_m * (s.mu() - mu_slow) * m_total * s.g() / m2 > STIFF_RATE
                }
            },
            mu_fast: s.mu(),
            mu_drop: s.mu() - law.at_rest(s.mu()),
            rate: match law {
                FrictionLaw::Coulomb => 0.0,
                FrictionLaw::VelocityDependent { rate_s_m, .. } => rate_s_m,
            },
            normal: m_total * s.g(),
            disp_unit: s.gmu() / (p * p),
            vel_unit: s.gmu() / p,
        }
    }

    /// Grid step at a point of a piece of `phase`, `age` seconds after the last transition: uniform,
    /// except a geometric refinement (steps of age/8, at least `h_fast`) just after an overdamped
    /// slide starts.
    pub(super) fn grid_step(&self, phase: Phase, age: f64) -> f64 {
        match phase {
            Phase::Stuck => self.h_stuck,
            _ => self.h_slide.min(self.h_fast.max(0.125 * age)),
        }
    }
}
