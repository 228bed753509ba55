//! Typed errors. Every error names the parameter or input that caused it.

use core::fmt;

/// A parameter of a structure, an input or an estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Param {
    /// Top mass `m1` (kg).
    M1,
    /// Sliding-base mass `m2` (kg).
    M2,
    /// Natural (fixed-base) frequency (Hz) or period (s).
    NaturalFrequency,
    /// Fixed-base damping ratio ξ.
    DampingRatio,
    /// Kinetic friction coefficient μ.
    FrictionCoefficient,
    /// Gravitational acceleration g (m/s²).
    Gravity,
    /// Table acceleration amplitude A0 (m/s²).
    Amplitude,
    /// Period of the table motion or of the friction wave (s).
    Period,
    /// Number of harmonics of a Fourier series.
    Harmonics,
    /// Trapezoid ramp phase α (rad).
    Alpha,
    /// A time (s).
    Time,
    /// The times of a reversal train (must be finite and strictly increasing).
    ReversalTimes,
    /// The sign of a reversal (must be +1 or -1).
    ReversalSign,
    /// Sample rate (Hz).
    SampleRate,
    /// Sub-sample offset or back-dating delay of an event.
    EventTime,
    /// The length of a block of samples (its slices must be equally long).
    BlockLength,
}

impl Param {
    /// The parameter's name as used in messages.
    pub const fn name(self) -> &'static str {
        match self {
            Param::M1 => "m1",
            Param::M2 => "m2",
            Param::NaturalFrequency => "natural frequency",
            Param::DampingRatio => "damping ratio",
            Param::FrictionCoefficient => "friction coefficient",
            Param::Gravity => "gravity",
            Param::Amplitude => "amplitude",
            Param::Period => "period",
            Param::Harmonics => "harmonics",
            Param::Alpha => "alpha",
            Param::Time => "time",
            Param::ReversalTimes => "reversal times",
            Param::ReversalSign => "reversal sign",
            Param::SampleRate => "sample rate",
            Param::EventTime => "event time",
            Param::BlockLength => "block length",
        }
    }
}

/// Errors of `ssvr-core`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Error {
    /// A value is NaN or infinite.
    NotFinite(Param),
    /// A value is outside its physical range; `expected` says which range.
    OutOfRange {
        /// The offending parameter.
        param: Param,
        /// The offending value.
        value: f64,
        /// The allowed range, in words.
        expected: &'static str,
    },
    /// Reversal times are not strictly increasing (index of the first offending time).
    NotIncreasing {
        /// Index of the first time that is not greater than its predecessor.
        index: usize,
    },
    /// A fixed-capacity buffer is full.
    CapacityExceeded(Param),
}

impl Error {
    /// The parameter the error is about.
    pub fn param(&self) -> Param {
        match *self {
            Error::NotFinite(p) | Error::CapacityExceeded(p) => p,
            Error::OutOfRange { param, .. } => param,
            Error::NotIncreasing { .. } => Param::ReversalTimes,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::NotFinite(p) => write!(f, "{} must be a finite number", p.name()),
            Error::OutOfRange {
                param,
                value,
                expected,
            } => write!(
                f,
                "{} = {} is out of range: expected {}",
                param.name(),
                value,
                expected
            ),
            Error::NotIncreasing { index } => write!(
                f,
                "reversal times must be strictly increasing (time #{index} is not)"
            ),
            Error::CapacityExceeded(p) => write!(f, "too many {} for the fixed capacity", p.name()),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for Error {}

/// Check that `value` is finite and satisfies `ok`, else name `param`.
pub(crate) fn check(
    param: Param,
    value: f64,
    ok: bool,
    expected: &'static str,
) -> Result<f64, Error> {
    if !value.is_finite() {
        Err(Error::NotFinite(param))
    } else if !ok {
        Err(Error::OutOfRange {
            param,
            value,
            expected,
        })
    } else {
        Ok(value)
    }
}
