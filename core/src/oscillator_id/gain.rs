//! The top accelerometer's gain relative to the base's, from the oscillator identifier's
//! relation with the gain in it (the parent module's documentation, **The top accelerometer's
//! gain**): [`TopGainFit`], kept in an [`OscillatorIdentifier`](super::OscillatorIdentifier) through [`GainRows`] (`()`:
//! none).

use crate::least_squares::PagedNormal;
use crate::math::Real;

/// The top accelerometer's gain relative to the base's ([`OscillatorIdentifier::gain_estimate`](super::OscillatorIdentifier::gain_estimate)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GainEstimate {
    /// G: the top accelerometer reads G times the top acceleration (in the base's units).
    pub gain: f64,
    /// Its standard deviation.
    pub gain_std: f64,
}

/// Where an [`OscillatorIdentifier`](super::OscillatorIdentifier) keeps the top accelerometer's gain fit: [`TopGainFit`], or
/// `()` (no fit, no storage: the fixed-base model's image has no RAM for it).
pub trait GainRows<T>: Clone + core::fmt::Debug {
    /// The fit for a forgetting `rho` per block.
    fn new(rho: f64) -> Self;
    /// One block's regressors `x` (Φ1, Φ2, Φ1(B), Φ2(B)), left-hand side `t`, the oscillator
    /// fit's a-priori residual `e`, and the residual's smoothing `alpha`.
    fn row(&mut self, x: [T; 4], t: T, e: T, alpha: T);
    /// The gain, its variance inflated by `inflation` ([`OscillatorIdentifier::gain_estimate`](super::OscillatorIdentifier::gain_estimate)).
    fn estimate(&mut self, inflation: f64) -> Option<GainEstimate>;
    /// The top's scale for the oscillator's rows
    /// ([`OscillatorIdentifier::set_top_scale`](super::OscillatorIdentifier::set_top_scale)).
    fn scale(&self) -> T;
    /// Set it.
    fn set_scale(&mut self, scale: T);
}

impl<T: Real> GainRows<T> for () {
    fn new(_: f64) -> Self {}
    #[inline(always)]
    fn row(&mut self, _: [T; 4], _: T, _: T, _: T) {}
    fn estimate(&mut self, _: f64) -> Option<GainEstimate> {
        None
    }
    #[inline(always)]
    fn scale(&self) -> T {
        T::ONE
    }
    fn set_scale(&mut self, _: T) {}
}

/// The top accelerometer's gain fit (module documentation): the least squares on
/// (Φ1, Φ2, Φ1(B), Φ2(B)) with forgetting, the fit of its last estimate (until then, the
/// oscillator's with no gain term) and the mean square of its residual, tracked as the
/// identifier's.
#[derive(Debug, Clone)]
pub struct TopGainFit<T> {
    normal: PagedNormal<T, 4, 15>,
    theta: Option<[T; 4]>,
    e2: T,
    scale: T,
}

impl<T: Real> GainRows<T> for TopGainFit<T> {
    fn new(rho: f64) -> Self {
        Self {
            normal: PagedNormal::new(rho),
            theta: None,
            e2: T::ZERO,
            scale: T::ONE,
        }
    }

    #[inline(always)]
    fn row(&mut self, x: [T; 4], t: T, e: T, alpha: T) {
        let eg = match self.theta {
            Some(g) => t - (g[0] * x[0] + g[1] * x[1] + g[2] * x[2] + g[3] * x[3]),
            None => e,
        };
        let e2 = self.e2 + (eg * eg - self.e2) * alpha;
        if e2.is_finite() {
            self.e2 = e2;
        }
        self.normal.add(&x, t);
    }

    #[inline(always)]
    fn scale(&self) -> T {
        self.scale
    }

    fn set_scale(&mut self, scale: T) {
        self.scale = scale;
    }

    fn estimate(&mut self, inflation: f64) -> Option<GainEstimate> {
        let var = self.e2.to_f64() * inflation;
        let f = self.normal.solve_given::<4>(var)?;
        let (a1, a3) = (f.theta[0], f.theta[2]);
        if a1.is_nan() || a1 <= 0.0 {
            return None;
        }
        self.theta = Some(f.theta.map(T::from_f64));
        // G = 1 − a3/a1: ∂G/∂a1 = a3/a1², ∂G/∂a3 = −1/a1.
        let (d1, d3) = (a3 / (a1 * a1), -1.0 / a1);
        let v = d1 * d1 * f.cov[0][0] + 2.0 * d1 * d3 * f.cov[0][2] + d3 * d3 * f.cov[2][2];
        let e = GainEstimate {
            gain: 1.0 - a3 / a1,
            gain_std: libm::sqrt(libm::fmax(v, 0.0)),
        };
        (e.gain.is_finite() && e.gain_std.is_finite() && e.gain_std < 0.1).then_some(e)
    }
}
