//! Units of an earthquake record's acceleration column.

use serde::Deserialize;
use ssvr_core::structure::STANDARD_GRAVITY;

/// Units of an earthquake record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum Units {
    /// Standard gravity (9.80665 m/s²), whatever the scene's `gravity_m_s2`.
    #[serde(rename = "g")]
    G,
    /// m/s².
    #[serde(rename = "m/s2", alias = "m/s^2")]
    MPerS2,
    /// 1 gal = 0.01 m/s².
    #[serde(rename = "gal")]
    Gal,
}

impl Units {
    /// m/s² per unit.
    pub fn factor(self) -> f64 {
        match self {
            Units::G => STANDARD_GRAVITY,
            Units::MPerS2 => 1.0,
            Units::Gal => 0.01,
        }
    }

    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Units::G => "g",
            Units::MPerS2 => "m/s2",
            Units::Gal => "gal",
        }
    }
}
