//! The estimator's coefficients for one structure and sample rate: the per-sample maps, computed
//! in f64 and rounded, and their bits (restored by a firmware image without f64 start-up code).

use crate::closed_form::free_vibration::Kernel;
use crate::error::Error;
use crate::math::Real;
use crate::structure::{Regime, Structure};

/// The estimator's coefficients for one structure and sample rate, in precision `T`: computed
/// in f64 and rounded ([`Self::new`]), or, in f32, restored from their bits
/// ([`StickSlipCoefficients::from_bits`]) — e.g. computed by a build script, so that a firmware
/// image needs no f64 start-up code.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StickSlipCoefficients<T> {
    // The per-sample maps act on the state w = (o, z1), o = −(z0 + 2ξ·z1) = ü1 (the prediction
    // itself): w = T·z with T = [[−1, −2ξ], [0, 1]] (T² = I), each map T·M·T. `phi_s` and
    // `phi_f` hold Φ − I.
    pub(super) phi_s: [T; 4],
    /// The sliding map's response to the friction force f = ±g·μ, per unit f.
    pub(super) force_s: [T; 2],
    pub(super) phi_f: [T; 4],
    /// B0 + B1 (applies to u0).
    pub(super) b0: [T; 2],
    /// B1 (applies to u1 − u0).
    pub(super) b1: [T; 2],
    pub(super) ks: Kernel<T>,
    pub(super) kf: Kernel<T>,
    pub(super) p: T,
    pub(super) two_xi: T,
    pub(super) mp: T,
    pub(super) g: T,
    pub(super) dt: T,
    pub(super) rate: T,
    /// The structure's μ (the model's μ until μ̂ is adopted).
    pub(super) mu: T,
}

impl<T: Real> StickSlipCoefficients<T> {
    /// The coefficients of `structure` sampled at `sample_rate_hz` (computed in f64).
    pub fn new(structure: &Structure, sample_rate_hz: f64) -> Result<Self, Error> {
        crate::error::check_sample_rate(sample_rate_hz)?;
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
        // In the coordinates w = T·z (T = [[−1, −2ξ], [0, 1]]): vectors T·v, matrices T·A·T.
        let x2 = 2.0 * xi;
        let tv = |v: [f64; 2]| [t(-v[0] - x2 * v[1]), t(v[1])];
        let tm = |a: [f64; 4]| {
            [
                t(a[0] + x2 * a[2]),
                t(x2 * a[0] + x2 * x2 * a[2] - a[1] - x2 * a[3]),
                t(-a[2]),
                t(a[3] - x2 * a[2]),
            ]
        };
        // Per-sample maps in increment form, Φ − I (the diagonal as −(1 − e^{-aτ}C ∓ …)
        // computed in f64): fine sampling keeps its relative accuracy in f32.
        let inc = |a: [f64; 4]| [a[0] - 1.0, a[1], a[2], a[3] - 1.0];
        Ok(Self {
            phi_s: tm(inc(phi_s)),
            force_s: tv([-(1.0 - fs.ecp), -m * p * fs.es]),
            phi_f: tm(inc(phi_f)),
            // Input map as Bsum·u0 + B1·(u1 − u0): B0 ≈ −B1 are large at fine sampling and
            // would cancel; their sum (the per-sample gain) is small and computed in f64.
            b0: tv([b0[0] + b1[0], b0[1] + b1[1]]),
            b1: tv(b1),
            ks: Kernel::new(structure),
            kf: Kernel::fixed_base(structure),
            p: t(p),
            two_xi: t(2.0 * xi),
            mp: t(m * p),
            g: t(structure.g()),
            dt: t(dt),
            rate: t(sample_rate_hz),
            mu: t(structure.mu()),
        })
    }
}

fn regime_code(r: Regime) -> u32 {
    match r {
        Regime::Underdamped => 0,
        Regime::Critical => 1,
        Regime::Overdamped => 2,
    }
}

impl StickSlipCoefficients<f32> {
    /// Length of [`Self::to_bits`].
    pub const BITS: usize = 35;

    /// The coefficients as words: the f32 values' bits (21 scalars, then each kernel's 5
    /// values), the kernels' regimes (0 underdamped, 1 critical, 2 overdamped) and flags.
    pub fn to_bits(&self) -> [u32; Self::BITS] {
        let mut v = [0u32; Self::BITS];
        let scalars = [
            self.phi_s[0],
            self.phi_s[1],
            self.phi_s[2],
            self.phi_s[3],
            self.force_s[0],
            self.force_s[1],
            self.phi_f[0],
            self.phi_f[1],
            self.phi_f[2],
            self.phi_f[3],
            self.b0[0],
            self.b0[1],
            self.b1[0],
            self.b1[1],
            self.p,
            self.two_xi,
            self.mp,
            self.g,
            self.dt,
            self.rate,
            self.mu,
        ];
        let (rs, cs, os) = self.ks.to_parts();
        let (rf, cf, of) = self.kf.to_parts();
        for (d, x) in v.iter_mut().zip(scalars.iter().chain(&cs).chain(&cf)) {
            *d = x.to_bits();
        }
        v[31] = regime_code(rs);
        v[32] = regime_code(rf);
        v[33] = u32::from(os);
        v[34] = u32::from(of);
        v
    }

    /// The coefficients from [`Self::to_bits`]; `None` for an invalid regime or flag word.
    pub fn from_bits(v: &[u32; Self::BITS]) -> Option<Self> {
        let f = |i: usize| f32::from_bits(v[i]);
        let regime = |w: u32| match w {
            0 => Some(Regime::Underdamped),
            1 => Some(Regime::Critical),
            2 => Some(Regime::Overdamped),
            _ => None,
        };
        let flag = |w: u32| match w {
            0 => Some(false),
            1 => Some(true),
            _ => None,
        };
        let kernel = |at: usize, r: u32, o: u32| {
            Some(Kernel::from_parts(
                regime(r)?,
                [f(at), f(at + 1), f(at + 2), f(at + 3), f(at + 4)],
                flag(o)?,
            ))
        };
        Some(Self {
            phi_s: [f(0), f(1), f(2), f(3)],
            force_s: [f(4), f(5)],
            phi_f: [f(6), f(7), f(8), f(9)],
            b0: [f(10), f(11)],
            b1: [f(12), f(13)],
            p: f(14),
            two_xi: f(15),
            mp: f(16),
            g: f(17),
            dt: f(18),
            rate: f(19),
            mu: f(20),
            ks: kernel(21, v[31], v[33])?,
            kf: kernel(26, v[32], v[34])?,
        })
    }
}
