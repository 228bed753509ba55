//! The four measured channels of a sample, in the order of the sensor log and the frames.

/// Number of measured channels.
pub const CHANNELS: usize = 4;

/// A measured channel (its index in a sample's `channels`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Channel {
    /// Table (ground) acceleration (m/s²).
    TableAccel = 0,
    /// Sliding-base acceleration (m/s²).
    BaseAccel = 1,
    /// Top-mass acceleration (m/s²).
    TopAccel = 2,
    /// Base-to-table displacement, the slip (m).
    Displacement = 3,
}

impl Channel {
    /// Every channel, in order.
    pub const ALL: [Channel; CHANNELS] = [
        Channel::TableAccel,
        Channel::BaseAccel,
        Channel::TopAccel,
        Channel::Displacement,
    ];

    /// Its index in a sample's channels.
    #[inline(always)]
    pub const fn index(self) -> usize {
        self as usize
    }

    /// Its name in scenes and CSV files (`table_accel`, `base_accel`, `top_accel`,
    /// `displacement`).
    pub const fn name(self) -> &'static str {
        match self {
            Channel::TableAccel => "table_accel",
            Channel::BaseAccel => "base_accel",
            Channel::TopAccel => "top_accel",
            Channel::Displacement => "displacement",
        }
    }
}
