//! Table (ground) acceleration ü_g(t) of a scene.

/// Table acceleration as a function of time (m/s²).
#[derive(Debug, Clone, PartialEq)]
pub enum TableMotion {
    /// No table motion (reversal-train scenes prescribe the friction instead).
    None,
    /// `amplitude_m_s2 · sin(2πt/period_s)` for t ≥ 0.
    Harmonic {
        /// Amplitude A0 (m/s²).
        amplitude_m_s2: f64,
        /// Period T (s).
        period_s: f64,
    },
    /// An earthquake record: piecewise linear between samples (`times_s` strictly increasing),
    /// zero before the first and after the last sample.
    Record {
        /// Sample times (s).
        times_s: Vec<f64>,
        /// Accelerations (m/s², already scaled).
        accel_m_s2: Vec<f64>,
    },
    /// The table at rest until `start_s`, then `motion` (its own t = 0 at `start_s`).
    Delayed {
        /// When the motion starts (s, ≥ 0).
        start_s: f64,
        /// The motion.
        motion: Box<TableMotion>,
    },
}

impl TableMotion {
    /// ü_g(t) (m/s²).
    pub fn accel(&self, t: f64) -> f64 {
        match self {
            TableMotion::None => 0.0,
            TableMotion::Harmonic {
                amplitude_m_s2,
                period_s,
            } => {
                if t < 0.0 {
                    0.0
                } else {
                    amplitude_m_s2 * (2.0 * std::f64::consts::PI * t / period_s).sin()
                }
            }
            TableMotion::Record {
                times_s,
                accel_m_s2,
            } => {
                let n = times_s.partition_point(|&x| x <= t);
                if n == 0 || n >= times_s.len() {
                    if n >= 1 && n == times_s.len() && t == times_s[n - 1] {
                        return accel_m_s2[n - 1];
                    }
                    return 0.0;
                }
                let (t0, t1) = (times_s[n - 1], times_s[n]);
                let (a0, a1) = (accel_m_s2[n - 1], accel_m_s2[n]);
                a0 + (a1 - a0) * (t - t0) / (t1 - t0)
            }
            TableMotion::Delayed { start_s, motion } => {
                if t < *start_s {
                    0.0
                } else {
                    motion.accel(t - start_s)
                }
            }
        }
    }
}
