//! Contact states of the base: the sliding [`Direction`], the [`Phase`] (stuck or sliding) and the
//! [`Event`]s between phases (breakaway, stick, reversal).

/// Direction of sliding of the base relative to the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// ẋ2 > 0.
    Positive,
    /// ẋ2 < 0.
    Negative,
}

impl Direction {
    /// +1 or −1.
    pub fn sign(self) -> f64 {
        match self {
            Direction::Positive => 1.0,
            Direction::Negative => -1.0,
        }
    }

    pub(super) fn opposite(self) -> Self {
        match self {
            Direction::Positive => Direction::Negative,
            Direction::Negative => Direction::Positive,
        }
    }

    /// The direction a net friction demand F_req pushes the base: −sign(F_req).
    pub(super) fn pushed_by(f_req: f64) -> Self {
        if f_req > 0.0 {
            Direction::Negative
        } else {
            Direction::Positive
        }
    }
}

/// Contact state of the base.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// The base moves with the table.
    Stuck,
    /// The base slides in the +x direction relative to the table (friction level −1).
    SlidingPos,
    /// The base slides in the −x direction relative to the table (friction level +1).
    SlidingNeg,
}

impl Phase {
    pub(super) fn sliding(d: Direction) -> Self {
        match d {
            Direction::Positive => Phase::SlidingPos,
            Direction::Negative => Phase::SlidingNeg,
        }
    }

    /// The sliding direction, `None` when stuck.
    pub fn direction(self) -> Option<Direction> {
        match self {
            Phase::Stuck => None,
            Phase::SlidingPos => Some(Direction::Positive),
            Phase::SlidingNeg => Some(Direction::Negative),
        }
    }
}

/// What happened at an event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    /// A stuck base breaks away.
    SlipStart {
        /// Direction of the slide that starts.
        direction: Direction,
    },
    /// A sliding base stops and sticks.
    Stick,
    /// A sliding base stops and immediately slides back.
    Reversal {
        /// Direction of the new slide.
        new_direction: Direction,
    },
}

/// A located event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// Time (s).
    pub time_s: f64,
    /// What happened.
    pub kind: EventKind,
}
