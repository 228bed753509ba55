//! The contact phase of the sliding base ([`SlidingPhase`]: stuck, or sliding with the friction
//! level ±1) and its integer friction level, the form the estimator works on internally.

use crate::error::{Error, Param};

/// A contact phase as its friction level F/F0 (−1, 0 stuck, +1): the form the estimator keeps
/// (packed in two bits per phase, compared and scaled on the general path).
pub(super) type Level = i8;

/// The contact phase of the sliding base: stuck, or sliding with the friction level F/F0 = ±1
/// (friction opposes slip).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i8)]
pub enum SlidingPhase {
    /// Sliding with the friction level −1.
    Negative = -1,
    /// Stuck: the base moves with the table.
    Stuck = 0,
    /// Sliding with the friction level +1.
    Positive = 1,
}

impl SlidingPhase {
    /// The friction level F/F0: −1, 0 (stuck) or +1.
    #[inline(always)]
    pub const fn level(self) -> i8 {
        self as i8
    }

    /// The phase of a friction level −1, 0 (stuck) or +1; any other level is an error.
    #[inline]
    pub fn from_level(level: i8) -> Result<Self, Error> {
        match level {
            -1 => Ok(Self::Negative),
            0 => Ok(Self::Stuck),
            1 => Ok(Self::Positive),
            _ => Err(Error::OutOfRange {
                param: Param::Phase,
                value: level as f64,
                expected: "a phase of -1, 0 or 1",
            }),
        }
    }
}
