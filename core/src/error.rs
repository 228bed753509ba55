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
    /// The friction level a reversal sets (units of F0, in [−1, 1]).
    ReversalLevel,
    /// The contact phase of an event (−1, 0 stuck or +1).
    Phase,
    /// The length of a precomputed table (its const capacity).
    TableLength,
    /// A sensor's noise RMS a detector is set for.
    NoiseRms,
    /// The displacement detector's hysteresis (m).
    Hysteresis,
    /// The displacement detector's fit half-width (samples; its fits must fit in the ring).
    FitHalf,
    /// The displacement detector's samples within the hysteresis before a stick.
    StickSamples,
    /// The acceleration detector's threshold (m/s²).
    Threshold,
    /// The acceleration detector's samples confirming a slip start.
    ConfirmSamples,
    /// The acceleration detector's samples below the threshold before a stall stick.
    StallSamples,
    /// The length of a detector's ring (its const capacity).
    RingLength,
    /// The RLS forgetting factor λ of the friction identification.
    Forgetting,
    /// The length of the friction identification's blocks (samples).
    IdentifyEvery,
    /// The history of an estimator (samples).
    History,
    /// The stuck-phase observer's bandwidth (units of p).
    ObserverBandwidth,
    /// The friction coefficient of a velocity-dependent law as the slip speed goes to 0.
    MuSlow,
    /// The rate `a` (s/m) of a velocity-dependent friction law.
    FrictionRate,
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
            Param::ReversalLevel => "reversal level",
            Param::Phase => "phase",
            Param::TableLength => "table length",
            Param::NoiseRms => "noise rms",
            Param::Hysteresis => "hysteresis",
            Param::FitHalf => "fit half-width",
            Param::StickSamples => "stick samples",
            Param::Threshold => "threshold",
            Param::ConfirmSamples => "confirm samples",
            Param::StallSamples => "stall samples",
            Param::RingLength => "ring length",
            Param::Forgetting => "forgetting factor",
            Param::IdentifyEvery => "identification block length",
            Param::History => "history",
            Param::ObserverBandwidth => "observer bandwidth",
            Param::MuSlow => "slow friction coefficient",
            Param::FrictionRate => "friction rate",
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

/// A sample rate (Hz): finite and > 0.
pub(crate) fn check_sample_rate(sample_rate_hz: f64) -> Result<f64, Error> {
    check(
        Param::SampleRate,
        sample_rate_hz,
        sample_rate_hz > 0.0,
        "sample rate > 0 Hz",
    )
}

/// A forgetting factor: in (0, 1].
pub(crate) fn check_forgetting(forgetting: f64) -> Result<f64, Error> {
    check(
        Param::Forgetting,
        forgetting,
        forgetting > 0.0 && forgetting <= 1.0,
        "forgetting factor in (0, 1]",
    )
}
