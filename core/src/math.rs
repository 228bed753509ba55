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
    /// The largest integer ≤ the value.
    fn floor(self) -> Self;
    /// Truncate to `usize`, saturating (NaN: 0).
    fn to_usize_sat(self) -> usize;
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
    #[inline(always)]
    fn floor(self) -> Self {
        libm::floorf(self)
    }
    #[inline(always)]
    fn to_usize_sat(self) -> usize {
        self as usize
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
    #[inline(always)]
    fn floor(self) -> Self {
        libm::floor(self)
    }
    #[inline(always)]
    fn to_usize_sat(self) -> usize {
        self as usize
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

/// Short pure-f32 polynomial kernels (Cody–Waite range reduction, Taylor polynomials on the reduced
/// interval): as accurate as `libm` in f32 (a few ulp) at a fraction of its cost on a Cortex-M4F,
/// where `libm`'s f32 functions compute in f64 (soft-float) and `micromath` is off by ~1e-3.
/// Measured in docs/PERFORMANCE.md; the firmware default.
#[derive(Debug, Clone, Copy, Default)]
pub struct F32Poly;

const LN2_HI: f32 = f32::from_bits(0x3f31_7000); // 0.693115234375: 12 significant bits, k·LN2_HI exact for |k| < 2^12
const LN2_LO: f32 = 3.194_618_3e-5; // ln 2 − LN2_HI
const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
// π/2 in three parts with trailing zeros: q·P1 and q·P2 are exact for |q| < 2^12.
const PIO2_1: f32 = 1.570_312_5; // 12 significant bits
const PIO2_2: f32 = f32::from_bits(0x39fd_a000); // 4.8375129699707031e-4, 12 significant bits
const PIO2_3: f32 = f32::from_bits(0x33a2_2169); // 7.5497901e-8, // the rest of π/2

/// eˣ for f32 without f64: x = k·ln2 + r, |r| ≤ ln2/2, degree-7 Taylor of eʳ, scale by 2^k.
pub fn exp_f32(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    if x > 88.72 {
        return f32::INFINITY;
    }
    if x < -103.97 {
        return 0.0;
    }
    let k = libm::roundf(x * core::f32::consts::LOG2_E);
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let p = 1.0
        + r * (1.0
            + r * (0.5
                + r * (1.0 / 6.0
                    + r * (1.0 / 24.0
                        + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))));
    let k = k as i32;
    // 2^k in two steps so subnormal results (k down to −150) are formed correctly.
    let (k1, k2) = if k < -126 { (-126, k + 126) } else { (k, 0) };
    let s1 = f32::from_bits(((k1 + 127) as u32) << 23);
    let s2 = f32::from_bits(((k2 + 127) as u32) << 23);
    p * s1 * s2
}

/// eˣ − 1 for f32: degree-9 Taylor for |x| < 0.35, else [`exp_f32`] − 1.
pub fn expm1_f32(x: f32) -> f32 {
    if libm::fabsf(x) < 0.35 {
        let mut term = x;
        let mut sum = x;
        let mut k = 2.0f32;
        while k < 10.0 {
            term *= x / k;
            sum += term;
            k += 1.0;
        }
        sum
    } else {
        exp_f32(x) - 1.0
    }
}

/// (sin x, cos x) for f32 without f64: Cody–Waite reduction by π/2 (accurate for |x| < ~6000),
/// Taylor polynomials of degree 9 and 10 on |r| ≤ π/4. Larger |x| falls back to `libm`.
pub fn sin_cos_f32(x: f32) -> (f32, f32) {
    if x.is_nan() || libm::fabsf(x) >= 6000.0 {
        return libm::sincosf(x);
    }
    let q = libm::roundf(x * FRAC_2_PI);
    let r = ((x - q * PIO2_1) - q * PIO2_2) - q * PIO2_3;
    let r2 = r * r;
    let s = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362_880.0)))));
    let c = 1.0
        + r2 * (-0.5
            + r2 * (1.0 / 24.0
                + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40_320.0 + r2 * (-1.0 / 3_628_800.0)))));
    match (q as i32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

impl Transcendentals<f32> for F32Poly {
    #[inline]
    fn exp(x: f32) -> f32 {
        exp_f32(x)
    }
    #[inline]
    fn expm1(x: f32) -> f32 {
        expm1_f32(x)
    }
    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        sin_cos_f32(x)
    }
    #[inline]
    fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps(got: f32, want: f64) -> f64 {
        let w = want as f32;
        if w == 0.0 {
            return (got as f64 - want).abs() / f32::MIN_POSITIVE as f64;
        }
        let ulp = f32::from_bits(w.abs().to_bits() + 1) - w.abs();
        (got as f64 - want).abs() / ulp as f64
    }

    #[test]
    fn exp_within_2_ulp_of_f64() {
        let mut worst = 0.0f64;
        let mut x = -103.0f32;
        while x < 88.0 {
            let want = libm::exp(x as f64);
            if want > 1.2e-38 {
                worst = worst.max(ulps(exp_f32(x), want));
            }
            x += 0.0137;
        }
        assert!(worst <= 2.0, "exp worst {worst} ulp");
        assert_eq!(exp_f32(-200.0), 0.0);
        // Subnormal results: within two subnormal steps (1.4e-45).
        assert!((exp_f32(-100.0) as f64 - libm::exp(-100.0)).abs() <= 2.0 * 1.401_298_5e-45);
    }

    #[test]
    fn expm1_relative_error() {
        let mut x = -20.0f32;
        while x < 20.0 {
            let want = libm::expm1(x as f64);
            let got = expm1_f32(x) as f64;
            let tol = 4.0 * f32::EPSILON as f64 * want.abs().max(1e-30) + 1e-45;
            assert!(
                (got - want).abs() <= tol.max(2.5e-7 * want.abs()),
                "x={x}: {got} vs {want}"
            );
            x += 0.00731;
        }
        assert_eq!(expm1_f32(0.0), 0.0);
        assert!((expm1_f32(1e-8) - 1e-8).abs() < 1e-15);
    }

    #[test]
    fn sin_cos_absolute_error() {
        let mut worst = 0.0f64;
        let mut x = -5000.0f32;
        while x < 5000.0 {
            let (s, c) = sin_cos_f32(x);
            let (ws, wc) = libm::sincos(x as f64);
            worst = worst.max((s as f64 - ws).abs()).max((c as f64 - wc).abs());
            x += 0.0917;
        }
        assert!(worst < 2.5e-7, "sin/cos worst abs error {worst:e}");
    }
}
