//! Sensor models (`[sensors]`): noise, ranges and ADC resolution of the simulated sensors.

use crate::board::RawChannel;
use crate::error::SceneError;
use crate::parse::ParseContext;
use serde::Deserialize;
use ssvr_core::structure::STANDARD_GRAVITY;
use toml::Spanned;

/// Sensor models (scene table `[sensors]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Sensors {
    /// Seed of the noise generator.
    pub seed: u64,
    /// White-noise RMS of the table, base and top accelerometers (m/s²).
    pub accel_noise_rms_m_s2: f64,
    /// Accelerometer full scale ± (m/s²).
    pub accel_range_m_s2: f64,
    /// Accelerometer ADC resolution (bits).
    pub accel_adc_bits: u32,
    /// White-noise RMS of the base-to-table displacement sensor (m).
    pub disp_noise_rms_m: f64,
    /// Displacement sensor full scale ± (m).
    pub disp_range_m: f64,
    /// Constant offsets of the table, base and top accelerometers (m/s²).
    pub accel_bias_m_s2: [f64; 3],
    /// Gain errors e of the table, base and top accelerometers: measured = (1 + e)·true + bias
    /// + noise.
    pub accel_gain_error: [f64; 3],
    /// Constant offset of the displacement sensor (m).
    pub disp_bias_m: f64,
    /// Probability that a sample's whole frame is missing (flagged), seeded.
    pub dropout_probability: f64,
}

impl Default for Sensors {
    fn default() -> Self {
        Self {
            seed: 1,
            accel_noise_rms_m_s2: 5e-3,
            accel_range_m_s2: 4.0 * STANDARD_GRAVITY,
            accel_adc_bits: 24,
            disp_noise_rms_m: 1e-6,
            disp_range_m: 0.05,
            accel_bias_m_s2: [0.0; 3],
            accel_gain_error: [0.0; 3],
            disp_bias_m: 0.0,
            dropout_probability: 0.0,
        }
    }
}

/// `[sensors]`: the simulated sensors, and the board's `[sensors.<channel>]` tables.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSensors {
    seed: Option<Spanned<u64>>,
    accel_noise_rms_m_s2: Option<Spanned<f64>>,
    accel_range_m_s2: Option<Spanned<f64>>,
    accel_adc_bits: Option<Spanned<u32>>,
    disp_noise_rms_m: Option<Spanned<f64>>,
    disp_range_m: Option<Spanned<f64>>,
    accel_bias_m_s2: Option<Spanned<Vec<f64>>>,
    accel_gain_error: Option<Spanned<Vec<f64>>>,
    disp_bias_m: Option<Spanned<f64>>,
    dropout_probability: Option<Spanned<f64>>,
    // The board's channel scaling (validated in `board`); not spanned, as implicit tables
    // (`displacement.volts_per_unit = 24.0`) have no span.
    table_accel: Option<RawChannel>,
    base_accel: Option<RawChannel>,
    top_accel: Option<RawChannel>,
    displacement: Option<RawChannel>,
}

impl RawSensors {
    /// The `[sensors.<channel>]` table of channel `i` (order `board::CHANNELS`).
    pub(crate) fn channel(&self, i: usize) -> Option<&RawChannel> {
        [
            &self.table_accel,
            &self.base_accel,
            &self.top_accel,
            &self.displacement,
        ][i]
            .as_ref()
    }

    /// The range key of channel `i`'s sensor and its span, when given.
    pub(crate) fn range_span(&self, i: usize) -> Option<(&'static str, std::ops::Range<usize>)> {
        if i < 3 {
            let v = self.accel_range_m_s2.as_ref()?;
            Some(("accel_range_m_s2", v.span()))
        } else {
            let v = self.disp_range_m.as_ref()?;
            Some(("disp_range_m", v.span()))
        }
    }
}

impl ParseContext<'_> {
    /// The `[sensors]` table if there is one, else the defaults.
    pub(crate) fn sensors_or_default(&self, r: Option<&RawSensors>) -> Result<Sensors, SceneError> {
        r.map_or_else(|| Ok(Sensors::default()), |r| self.sensors(r))
    }

    /// The `[sensors]` table.
    pub(crate) fn sensors(&self, r: &RawSensors) -> Result<Sensors, SceneError> {
        const S: Option<&str> = Some("sensors");
        let d = Sensors::default();
        let opt = |v: &Option<Spanned<f64>>,
                   key: &str,
                   default: f64,
                   ok: fn(f64) -> bool,
                   expected: &str|
         -> Result<f64, SceneError> {
            match v {
                Some(v) => self.check(S, key, v, ok(*v.get_ref()), expected),
                None => Ok(default),
            }
        };
        let accel_adc_bits = match &r.accel_adc_bits {
            Some(b) => {
                let bits = *b.get_ref();
                if !(1..=32).contains(&bits) {
                    return Err(self.err(
                        b.span(),
                        format!(
                            "[sensors] accel_adc_bits = {bits} is out of range: expected 1 to 32"
                        ),
                    ));
                }
                bits
            }
            None => d.accel_adc_bits,
        };
        // Three finite numbers (table, base, top), each passing `ok`.
        let three = |v: &Option<Spanned<Vec<f64>>>,
                     key: &str,
                     ok: fn(f64) -> bool,
                     expected: &str|
         -> Result<[f64; 3], SceneError> {
            let Some(v) = v else {
                return Ok([0.0; 3]);
            };
            match v.get_ref().as_slice() {
                &[a, b, c] if [a, b, c].iter().all(|&x| x.is_finite() && ok(x)) => Ok([a, b, c]),
                other => Err(self.err(
                    v.span(),
                    format!(
                        "[sensors] {key} = {other:?} is out of range: expected 3 finite numbers \
                         (table, base, top), {expected}"
                    ),
                )),
            }
        };
        let accel_bias_m_s2 = three(&r.accel_bias_m_s2, "accel_bias_m_s2", |_| true, "in m/s^2")?;
        let accel_gain_error = three(
            &r.accel_gain_error,
            "accel_gain_error",
            |e| e > -1.0,
            "each > -1",
        )?;
        Ok(Sensors {
            accel_bias_m_s2,
            accel_gain_error,
            disp_bias_m: opt(
                &r.disp_bias_m,
                "disp_bias_m",
                d.disp_bias_m,
                |v| v.is_finite(),
                "a finite number of m",
            )?,
            dropout_probability: opt(
                &r.dropout_probability,
                "dropout_probability",
                d.dropout_probability,
                |p| (0.0..1.0).contains(&p),
                "0 <= dropout_probability < 1",
            )?,
            seed: r.seed.as_ref().map_or(d.seed, |s| *s.get_ref()),
            accel_noise_rms_m_s2: opt(
                &r.accel_noise_rms_m_s2,
                "accel_noise_rms_m_s2",
                d.accel_noise_rms_m_s2,
                |v| v >= 0.0,
                ">= 0 m/s^2",
            )?,
            accel_range_m_s2: opt(
                &r.accel_range_m_s2,
                "accel_range_m_s2",
                d.accel_range_m_s2,
                |v| v > 0.0,
                "> 0 m/s^2",
            )?,
            accel_adc_bits,
            disp_noise_rms_m: opt(
                &r.disp_noise_rms_m,
                "disp_noise_rms_m",
                d.disp_noise_rms_m,
                |v| v >= 0.0,
                ">= 0 m",
            )?,
            disp_range_m: opt(
                &r.disp_range_m,
                "disp_range_m",
                d.disp_range_m,
                |v| v > 0.0,
                "> 0 m",
            )?,
        })
    }
}
