//! The per-interval maps of the hot paths (the stuck map with or without the observer's
//! correction, the sliding map) and the f64 composition of a per-sample map into an n-step one.

use super::coefficients::StickSlipCoefficients;
use crate::math::Real;

/// The fixed-base (stuck) map over one whole interval from the state `z` of its first sample
/// (measured top acceleration `y0`), table accelerations `u0` → `u1`: with [`StuckMap::closed`]
/// the observer's correction from `y0` included, with [`StuckMap::open`] (`y0` = 0) without.
#[inline(always)]
pub(super) fn stuck_map<T: Real>(m: &StuckMap<T>, z: [T; 2], y0: T, u0: T, u1: T) -> [T; 2] {
    [
        z[0] + (m.a[0] * z[0] + m.a[1] * z[1] + m.h[0] * y0 + m.b0[0] * u0 + m.b1[0] * u1),
        z[1] + (m.a[2] * z[0] + m.a[3] * z[1] + m.h[1] * y0 + m.b0[1] * u0 + m.b1[1] * u1),
    ]
}

/// [`stuck_map`] with the observer's correction if `y0` is finite (`closed`), else without
/// (`open`).
#[inline(always)]
pub(super) fn stuck_step<T: Real>(
    closed: &StuckMap<T>,
    open: &StuckMap<T>,
    z: [T; 2],
    y0: T,
    u0: T,
    u1: T,
) -> [T; 2] {
    let (m, y0) = if y0.is_finite() {
        (closed, y0)
    } else {
        (open, T::ZERO)
    };
    stuck_map(m, z, y0, u0, u1)
}

/// A stuck interval as one affine map in increment form: z ↦ z + A·z + h·y0 + b0·u0 + b1·u1
/// (ten coefficients, few enough to stay in registers over a block of samples).
#[derive(Debug, Clone, Copy)]
pub(super) struct StuckMap<T> {
    pub(super) a: [T; 4],
    pub(super) h: [T; 2],
    pub(super) b0: [T; 2],
    pub(super) b1: [T; 2],
}

impl<T: Real> StuckMap<T> {
    /// Without the observer: Φf − I, and the piecewise-linear input b0·u0 + b1·(u1 − u0) as
    /// (b0 − b1)·u0 + b1·u1.
    pub(super) fn open(c: &StickSlipCoefficients<T>) -> Self {
        let (b0, b1) = (c.b0.map(T::to_f64), c.b1.map(T::to_f64));
        Self {
            a: c.phi_f,
            h: [T::ZERO; 2],
            b0: [T::from_f64(b0[0] - b1[0]), T::from_f64(b0[1] - b1[1])],
            b1: c.b1,
        }
    }

    /// With the observer's correction z += G·(z0 − y0) at the interval's start (gain `g`):
    /// z + A(z + G(z0 − y0)) + G(z0 − y0) + … = z + (A + ΦG·e0ᵀ)z − ΦG·y0 + …, Φ = I + A
    /// (composed in f64).
    pub(super) fn closed(c: &StickSlipCoefficients<T>, g: [T; 2]) -> Self {
        let (a, h) = close(&c.phi_f, g);
        Self {
            a,
            h,
            ..Self::open(c)
        }
    }
}

/// An increment map `a` (Φ − I) closed by the correction z += G·(z0 − y0) at the interval's
/// start: (A + ΦG·e0ᵀ, −ΦG), composed in f64.
fn close<T: Real>(a: &[T; 4], g: [T; 2]) -> ([T; 4], [T; 2]) {
    let a64 = a.map(T::to_f64);
    let g = g.map(T::to_f64);
    // ΦG = G + A·G.
    let pg = [
        g[0] + (a64[0] * g[0] + a64[1] * g[1]),
        g[1] + (a64[2] * g[0] + a64[3] * g[1]),
    ];
    (
        [
            T::from_f64(a64[0] + pg[0]),
            a[1],
            T::from_f64(a64[2] + pg[1]),
            a[3],
        ],
        [T::from_f64(-pg[0]), T::from_f64(-pg[1])],
    )
}

/// The sliding map with the observer's correction z += G·(z0 − y0) at the interval's start:
/// z ↦ z + A'·z + h·y0 + d with A' = A + ΦsG·e0ᵀ, h = −ΦsG (composed in f64, as
/// [`StuckMap::closed`]); the forcing d is the open map's.
#[derive(Debug, Clone, Copy)]
pub(super) struct SlideMap<T> {
    pub(super) a: [T; 4],
    pub(super) h: [T; 2],
}

impl<T: Real> SlideMap<T> {
    /// The closed sliding map of `c` for the sliding observer's gain `g`.
    pub(super) fn closed(c: &StickSlipCoefficients<T>, g: [T; 2]) -> Self {
        let (a, h) = close(&c.phi_s, g);
        Self { a, h }
    }
}

/// The closed sliding map ([`SlideMap`]) from the state `z` of the interval's first sample and
/// its measured top acceleration `y0`, forcing `d`.
#[inline(always)]
pub(super) fn slide_map<T: Real>(m: &SlideMap<T>, d: [T; 2], z: [T; 2], y0: T) -> [T; 2] {
    [
        z[0] + (d[0] + m.a[0] * z[0] + m.a[1] * z[1] + m.h[0] * y0),
        z[1] + (d[1] + m.a[2] * z[0] + m.a[3] * z[1] + m.h[1] * y0),
    ]
}

/// [`slide_map`] if `y0` is finite, else the open sliding map (`a` = Φs − I).
#[inline(always)]
pub(super) fn slide_step<T: Real>(
    closed: &SlideMap<T>,
    a: &[T; 4],
    d: [T; 2],
    z: [T; 2],
    y0: T,
) -> [T; 2] {
    if y0.is_finite() {
        slide_map(closed, d, z, y0)
    } else {
        sliding_map(a, d, z)
    }
}

/// The sliding map over one whole interval: increment map `a` (Φs − I), forcing `d`.
#[inline(always)]
pub(super) fn sliding_map<T: Real>(a: &[T; 4], d: [T; 2], z: [T; 2]) -> [T; 2] {
    [
        z[0] + (d[0] + a[0] * z[0] + a[1] * z[1]),
        z[1] + (d[1] + a[2] * z[0] + a[3] * z[1]),
    ]
}

#[inline(always)]
pub(super) fn mat<T: Real>(m: &[T; 4], z: [T; 2]) -> [T; 2] {
    [m[0] * z[0] + m[1] * z[1], m[2] * z[0] + m[3] * z[1]]
}

/// An affine per-sample map z ↦ z + A·z + F in increment form (A = Φ − I), in f64.
pub(super) type Affine = ([f64; 4], [f64; 2]);

/// `y` after `x`: (I + Ay)((I + Ax)z + Fx) + Fy.
pub(super) fn compose(x: &Affine, y: &Affine) -> Affine {
    let (ax, fx) = x;
    let (ay, fy) = y;
    let yx = [
        ay[0] * ax[0] + ay[1] * ax[2],
        ay[0] * ax[1] + ay[1] * ax[3],
        ay[2] * ax[0] + ay[3] * ax[2],
        ay[2] * ax[1] + ay[3] * ax[3],
    ];
    let yf = [ay[0] * fx[0] + ay[1] * fx[1], ay[2] * fx[0] + ay[3] * fx[1]];
    (
        [
            ax[0] + ay[0] + yx[0],
            ax[1] + ay[1] + yx[1],
            ax[2] + ay[2] + yx[2],
            ax[3] + ay[3] + yx[3],
        ],
        [fx[0] + fy[0] + yf[0], fx[1] + fy[1] + yf[1]],
    )
}

/// `m` applied `n` times (binary powering; powers of one map commute).
pub(super) fn power(m: &Affine, n: u32) -> Affine {
    let (mut r, mut b, mut e) = (([0.0; 4], [0.0; 2]), *m, n);
    while e > 0 {
        if e & 1 == 1 {
            r = compose(&r, &b);
        }
        e >>= 1;
        if e > 0 {
            b = compose(&b, &b);
        }
    }
    r
}

/// `x^n` in f64 (binary powering).
pub(super) fn powi(x: f64, n: u32) -> f64 {
    let (mut r, mut b, mut e) = (1.0, x, n);
    while e > 0 {
        if e & 1 == 1 {
            r *= b;
        }
        e >>= 1;
        b *= b;
    }
    r
}
