//! The inputs of a truth simulation ([`TruthInput`]) and why a simulation can be refused or stop
//! ([`TruthError`]).

use crate::table_motion::TableMotion;
use core::fmt;
use ssvr_core::{FrictionLaw, Structure};

/// Inputs of [`simulate`](super::simulate).
#[derive(Debug, Clone, Copy)]
pub struct TruthInput<'a> {
    /// The structure (m1, m2, p, ξ, kinetic μ, g).
    pub structure: &'a Structure,
    /// Static friction coefficient μs ≥ μ (breakaway threshold μs (m1+m2) g); `None` means μs = μ.
    pub mu_static: Option<f64>,
    /// The table acceleration.
    pub table: &'a TableMotion,
    /// Simulated duration (s), finite and > 0. Past the end of a record the table is at rest.
    pub duration_s: f64,
    /// The friction law (its μ_fast is the structure's μ); Coulomb by default.
    pub friction: FrictionLaw,
    /// Integrate sliding phases even under Coulomb friction (to check the integration against
    /// the closed forms); a velocity-dependent law is always integrated.
    pub integrate_sliding: bool,
}

impl<'a> TruthInput<'a> {
    /// Inputs with μs = μ.
    pub fn new(structure: &'a Structure, table: &'a TableMotion, duration_s: f64) -> Self {
        Self {
            structure,
            mu_static: None,
            table,
            duration_s,
            friction: FrictionLaw::Coulomb,
            integrate_sliding: false,
        }
    }

    /// The same inputs with a friction law.
    pub fn with_friction(mut self, friction: FrictionLaw) -> Self {
        self.friction = friction;
        self
    }

    /// The same inputs with a static friction coefficient μs (must be ≥ μ).
    pub fn with_static_friction(mut self, mu_static: f64) -> Self {
        self.mu_static = Some(mu_static);
        self
    }
}

/// Why a simulation could not be run.
#[derive(Debug, Clone, PartialEq)]
pub enum TruthError {
    /// The duration is not finite or not > 0.
    Duration(f64),
    /// μs is not finite or below the kinetic μ (at rest).
    StaticFriction {
        /// The offending μs.
        mu_static: f64,
        /// The kinetic μ of the structure (at rest).
        mu: f64,
    },
    /// The friction law is invalid for the structure's μ.
    Friction(ssvr_core::Error),
    /// The harmonic table motion has a non-finite amplitude or a period that is not finite and > 0.
    Harmonic {
        /// Amplitude (m/s²).
        amplitude_m_s2: f64,
        /// Period (s).
        period_s: f64,
    },
    /// The start of a delayed table motion is not finite or negative.
    Start {
        /// The start (s).
        start_s: f64,
    },
    /// The record's time and acceleration arrays have different lengths.
    RecordLengths {
        /// Number of times.
        times: usize,
        /// Number of accelerations.
        accels: usize,
    },
    /// A record time or acceleration is NaN or infinite.
    RecordNotFinite {
        /// Index of the sample.
        index: usize,
    },
    /// Record times are not strictly increasing.
    RecordNotIncreasing {
        /// Index of the first time not greater than its predecessor.
        index: usize,
    },
    /// More than [`MAX_EVENTS`](super::MAX_EVENTS) events, or events that make no progress in time.
    TooManyEvents {
        /// Time reached (s).
        time_s: f64,
    },
    /// The response overflowed (inputs far outside any physical range).
    NotFinite {
        /// Time reached (s).
        time_s: f64,
    },
}

impl fmt::Display for TruthError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TruthError::Duration(d) => write!(f, "duration {d} s: expected a finite value > 0"),
            TruthError::StaticFriction { mu_static, mu } => write!(
                f,
                "static friction coefficient {mu_static}: expected a finite value >= the kinetic {mu}"
            ),
            TruthError::Friction(e) => write!(f, "friction law: {e}"),
            TruthError::Harmonic {
                amplitude_m_s2,
                period_s,
            } => write!(
                f,
                "harmonic table motion (amplitude {amplitude_m_s2} m/s^2, period {period_s} s): \
                 expected a finite amplitude and a finite period > 0"
            ),
            TruthError::Start { start_s } => {
                write!(f, "table motion start {start_s} s: expected a finite value >= 0")
            }
            TruthError::RecordLengths { times, accels } => write!(
                f,
                "record has {times} times but {accels} accelerations"
            ),
            TruthError::RecordNotFinite { index } => {
                write!(f, "record sample {index} is not finite")
            }
            TruthError::RecordNotIncreasing { index } => {
                write!(f, "record time {index} is not greater than the previous one")
            }
            TruthError::TooManyEvents { time_s } => write!(
                f,
                "stick-slip events do not progress in time (stopped at t = {time_s} s)"
            ),
            TruthError::NotFinite { time_s } => {
                write!(f, "the response overflowed at t = {time_s} s")
            }
        }
    }
}

impl std::error::Error for TruthError {}
