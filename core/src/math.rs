//! Precision and the one switch for transcendental functions.
//!
//! [`Real`] abstracts over `f32` (the firmware default) and `f64`. [`Transcendentals`] is the single
//! place where `exp`, `expm1`, `sin`, `cos` and `sqrt` are evaluated at run time (at friction
//! reversals); [`Libm`] and [`Micromath`] are the two implementations. Coefficients computed once at
//! construction always use `libm` in `f64`.

use core::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// A floating-point type the estimator can run in.
pub trait Real:
    Copy
    + PartialOrd
    + Default
    + core::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// Round an `f64` to this type.
    fn from_f64(x: f64) -> Self;
    /// Widen to `f64` (exact).
    fn to_f64(self) -> f64;
    /// Absolute value.
    fn abs(self) -> Self;
    /// Whether the value is finite.
    fn is_finite(self) -> bool;
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn abs(self) -> Self {
        libm::fabsf(self)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline(always)]
    fn abs(self) -> Self {
        libm::fabs(self)
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
}

/// The transcendental functions evaluated at run time, in precision `T`.
pub trait Transcendentals<T: Real> {
    /// eˣ.
    fn exp(x: T) -> T;
    /// eˣ − 1, accurate for small |x|.
    fn expm1(x: T) -> T;
    /// (sin x, cos x).
    fn sin_cos(x: T) -> (T, T);
    /// √x.
    fn sqrt(x: T) -> T;
}

/// `libm`: correctly rounded to within about one ulp.
#[derive(Debug, Clone, Copy, Default)]
pub struct Libm;

/// `micromath`: fast approximations (measured error in docs/PERFORMANCE.md).
#[derive(Debug, Clone, Copy, Default)]
pub struct Micromath;

impl Transcendentals<f64> for Libm {
    #[inline]
    fn exp(x: f64) -> f64 {
        libm::exp(x)
    }
    #[inline]
    fn expm1(x: f64) -> f64 {
        libm::expm1(x)
    }
    #[inline]
    fn sin_cos(x: f64) -> (f64, f64) {
        libm::sincos(x)
    }
    #[inline]
    fn sqrt(x: f64) -> f64 {
        libm::sqrt(x)
    }
}

impl Transcendentals<f32> for Libm {
    #[inline]
    fn exp(x: f32) -> f32 {
        libm::expf(x)
    }
    #[inline]
    fn expm1(x: f32) -> f32 {
        libm::expm1f(x)
    }
    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        libm::sincosf(x)
    }
    #[inline]
    fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
}

impl Transcendentals<f32> for Micromath {
    #[inline]
    fn exp(x: f32) -> f32 {
        micromath::F32Ext::exp(x)
    }
    #[inline]
    fn expm1(x: f32) -> f32 {
        // micromath has no expm1: a short Taylor series where exp(x) − 1 would cancel.
        if libm::fabsf(x) < 0.35 {
            let mut term = x;
            let mut sum = x;
            let mut k = 2.0f32;
            while k < 9.0 {
                term *= x / k;
                sum += term;
                k += 1.0;
            }
            sum
        } else {
            micromath::F32Ext::exp(x) - 1.0
        }
    }
    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        (micromath::F32Ext::sin(x), micromath::F32Ext::cos(x))
    }
    #[inline]
    fn sqrt(x: f32) -> f32 {
        micromath::F32Ext::sqrt(x)
    }
}
