//! The planned input's start ([`PlannedStart`]): the least-squares line through the planned
//! table acceleration over the input's first samples, which a plan without a rest carries ([`Plan::planned_start`](crate::Plan::planned_start)) and against which the table
//! accelerometer's offset is found
//! ([`BaseTuning::note_table_start`](crate::model::BaseTuning::note_table_start)); its text
//! form for the firmware's build (`SSVR_PLANNED_START`).

use crate::model::open_start_samples;
use crate::plan::PlanError;
use crate::table_start::LineFit;
use ssvr_core::StructureParams;

/// The least-squares line through the planned table acceleration over the open-loop start's
/// samples ([`open_start_samples`]), from the input's first sample ([`planned_start`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannedStart {
    /// Its value at the input's first sample (m/s²).
    pub accel_m_s2: f32,
    /// Its rise per sample (m/s²): what a lag of one sample between the plan and the table
    /// moves the measured intercept by.
    pub rise_per_sample_m_s2: f32,
}

/// `accel,rise`: the two f32s' bits in hex (`SSVR_PLANNED_START`, how `host-sim qemu` hands a
/// plan's planned start to the firmware's build; its `FromStr` reads it back).
impl core::fmt::Display for PlannedStart {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{:08x},{:08x}",
            self.accel_m_s2.to_bits(),
            self.rise_per_sample_m_s2.to_bits()
        )
    }
}

impl core::str::FromStr for PlannedStart {
    type Err = PlanError;

    /// The [`Display`](core::fmt::Display) form: two f32s' bits in hex, both finite, nothing
    /// else (`PlanError::Words` otherwise).
    fn from_str(s: &str) -> Result<Self, PlanError> {
        let mut parts = s.split(',');
        let mut next = || {
            parts
                .next()
                .and_then(|p| u32::from_str_radix(p, 16).ok())
                .map(f32::from_bits)
                .filter(|x| x.is_finite())
        };
        match (next(), next(), parts.next()) {
            (Some(accel_m_s2), Some(rise_per_sample_m_s2), None) => Ok(Self {
                accel_m_s2,
                rise_per_sample_m_s2,
            }),
            _ => Err(PlanError::Words),
        }
    }
}

/// The planned table acceleration's line at the input's start for the prior `params` at
/// `rate` ([`PlannedStart`]): the least-squares line through `accel(k/rate)` over the first
/// [`open_start_samples`] samples, at most the `LAGS − 1` whose statistics the table's start
/// keeps ([`crate::table_start`]) (`None` if there are none or it is not finite in f32).
pub fn planned_start(
    params: &StructureParams,
    rate: f64,
    accel: impl Fn(f64) -> f64,
) -> Option<PlannedStart> {
    let n = open_start_samples(params, rate).min(crate::table_start::LAGS as u32 - 1);
    let (mut s, mut sk, mut skk, mut sy, mut sky) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 0..n {
        let (k, y) = (k as f64, accel(k as f64 / rate));
        (s, sk, skk, sy, sky) = (s + 1.0, sk + k, skk + k * k, sy + y, sky + k * y);
    }
    let line = LineFit::new([s, sk, skk, sy, sky])?;
    let p = PlannedStart {
        accel_m_s2: line.intercept as f32,
        rise_per_sample_m_s2: line.slope as f32,
    };
    (p.accel_m_s2.is_finite() && p.rise_per_sample_m_s2.is_finite()).then_some(p)
}
