//! Board settings of the firmware's board image: the ADS131M04 ADC (`[adc]`: PGA gains and
//! oversampling ratio) and the scaling of its four channels from volts to SI units
//! (`[sensors.<channel>]`: `volts_per_unit`, `offset_volts`).
//!
//! ```toml
//! [adc]                     # optional
//! gains = [1, 1, 1, 1]      # PGA gain per channel: a power of two in 1..=128 (default 1)
//! osr = 4096                # default: the largest OSR with 4 096 000 / osr >= rate_hz, else 128
//! [sensors.displacement]    # optional, also table_accel, base_accel, top_accel
//! volts_per_unit = 24.0     # SI = (volts - offset_volts) / volts_per_unit; finite, non-zero
//! offset_volts = 0.0        # finite (default 0)
//! ```
//!
//! Without `volts_per_unit` a channel maps its sensor's range onto the ADC full scale:
//! (1.2 V / gain) / `[sensors] accel_range_m_s2` for the accelerometers, / `disp_range_m` for the
//! displacement sensor. Every scene has board settings (all defaults when it sets none).

use crate::error::SceneError;
use crate::parse::ParseContext;
use crate::sensors::{RawSensors, Sensors};
use serde::Deserialize;
use toml::Spanned;

/// The ADC's channels in order (index of [`BoardSettings::adc_gains`] and
/// [`BoardSettings::channels`]), named as their `[sensors.<channel>]` tables.
pub const CHANNELS: [&str; 4] = ["table_accel", "base_accel", "top_accel", "displacement"];

/// The ADS131M04's oversampling ratios, smallest first.
pub const ADC_OSRS: [u32; 8] = [128, 256, 512, 1024, 2048, 4096, 8192, 16256];

/// The ADC's modulator clock over 2 (Hz): the output data rate is `ADC_ODR_CLOCK_HZ / osr`
/// (8.192 MHz CLKIN).
pub const ADC_ODR_CLOCK_HZ: f64 = 4_096_000.0;

/// The ADC's full scale at gain 1 (V); at gain g it is `ADC_FULL_SCALE_V / g`.
pub const ADC_FULL_SCALE_V: f64 = 1.2;

/// The scaling of one ADC channel: SI = (volts − `offset_volts`) / `volts_per_unit`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelScale {
    /// Volts per SI unit (V per m/s², or V per m); finite and non-zero.
    pub volts_per_unit: f64,
    /// Volts at zero (V); finite.
    pub offset_volts: f64,
}

/// The board image's ADC configuration and channel scaling, defaults resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoardSettings {
    /// PGA gain per channel (order [`CHANNELS`]), each a power of two in 1..=128.
    pub adc_gains: [u8; 4],
    /// Oversampling ratio, one of [`ADC_OSRS`].
    pub osr: u32,
    /// Scaling per channel (order [`CHANNELS`]).
    pub channels: [ChannelScale; 4],
}

impl BoardSettings {
    /// The defaults of a scene without `[adc]` and `[sensors.<channel>]` tables: gains 1,
    /// [`default_osr`](Self::default_osr) of the rate, the sensors' ranges on the ADC full scale.
    pub fn defaults(rate_hz: f64, sensors: &Sensors) -> BoardSettings {
        let adc_gains = [1; 4];
        BoardSettings {
            adc_gains,
            osr: Self::default_osr(rate_hz),
            channels: std::array::from_fn(|i| ChannelScale {
                volts_per_unit: Self::derived_volts_per_unit(i, adc_gains[i], sensors),
                offset_volts: 0.0,
            }),
        }
    }

    /// The largest OSR whose output data rate (`ADC_ODR_CLOCK_HZ / osr`) is at least `rate_hz`,
    /// else the smallest (128).
    pub fn default_osr(rate_hz: f64) -> u32 {
        ADC_OSRS
            .iter()
            .rev()
            .copied()
            .find(|&osr| ADC_ODR_CLOCK_HZ / osr as f64 >= rate_hz)
            .unwrap_or(ADC_OSRS[0])
    }

    /// The output data rate of the ADC (Hz).
    pub fn odr_hz(&self) -> f64 {
        ADC_ODR_CLOCK_HZ / self.osr as f64
    }

    /// Channel `i`'s default volts per unit: its sensor's range on the full scale at `gain`.
    fn derived_volts_per_unit(i: usize, gain: u8, sensors: &Sensors) -> f64 {
        let range = if i < 3 {
            sensors.accel_range_m_s2
        } else {
            sensors.disp_range_m
        };
        ADC_FULL_SCALE_V / f64::from(gain) / range
    }
}

/// `[adc]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawAdc {
    gains: Option<Spanned<Vec<Spanned<i64>>>>,
    osr: Option<Spanned<i64>>,
}

/// `[sensors.<channel>]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawChannel {
    volts_per_unit: Option<Spanned<f64>>,
    offset_volts: Option<Spanned<f64>>,
}

impl ParseContext<'_> {
    /// The board settings: `[adc]` and the `[sensors.<channel>]` tables of `sensors` (validated
    /// into `resolved`), at sample rate `rate_hz`.
    pub(crate) fn board(
        &self,
        adc: Option<&RawAdc>,
        sensors: Option<&RawSensors>,
        resolved: &Sensors,
        rate_hz: f64,
    ) -> Result<BoardSettings, SceneError> {
        let mut board = BoardSettings::defaults(rate_hz, resolved);
        if let Some(r) = adc {
            if let Some(gains) = &r.gains {
                let list = gains.get_ref();
                if list.len() != CHANNELS.len() {
                    return Err(self.err(
                        gains.span(),
                        format!(
                            "[adc] gains has {} value(s): expected 4, one per channel ({})",
                            list.len(),
                            CHANNELS.join(", ")
                        ),
                    ));
                }
                for (i, g) in list.iter().enumerate() {
                    let value = *g.get_ref();
                    board.adc_gains[i] = match u8::try_from(value) {
                        Ok(v) if v.is_power_of_two() => v,
                        _ => {
                            return Err(self.err(
                                g.span(),
                                format!(
                                    "[adc] gains[{i}] = {value} is out of range: expected a \
                                     power of two in 1..=128 (1, 2, 4, 8, 16, 32, 64 or 128)"
                                ),
                            ))
                        }
                    };
                }
            }
            if let Some(osr) = &r.osr {
                let value = *osr.get_ref();
                board.osr = match u32::try_from(value) {
                    Ok(v) if ADC_OSRS.contains(&v) => v,
                    _ => {
                        let list: Vec<String> = ADC_OSRS.iter().map(u32::to_string).collect();
                        return Err(self.err(
                            osr.span(),
                            format!(
                                "[adc] osr = {value} is out of range: expected an ADS131M04 \
                                 oversampling ratio ({})",
                                list.join(", ")
                            ),
                        ));
                    }
                };
            }
        }
        for (i, name) in CHANNELS.iter().enumerate() {
            let section = format!("sensors.{name}");
            let table = sensors.and_then(|s| s.channel(i));
            let explicit = table.and_then(|t| t.volts_per_unit.as_ref());
            board.channels[i].volts_per_unit = match explicit {
                Some(v) => self.check(
                    Some(&section),
                    "volts_per_unit",
                    v,
                    *v.get_ref() != 0.0,
                    "a finite, non-zero number (V per SI unit)",
                )?,
                None => {
                    let v = BoardSettings::derived_volts_per_unit(i, board.adc_gains[i], resolved);
                    if !(v.is_finite() && v != 0.0) {
                        // Only a range key at the edge of f64 gets here, so it is given.
                        let (key, span) = sensors
                            .and_then(|s| s.range_span(i))
                            .unwrap_or(("range", 0..0));
                        return Err(self.err(
                            span,
                            format!(
                                "[sensors] {key} gives [{section}] volts_per_unit = {v} \
                                 (1.2 V / gain / range): expected a finite, non-zero number; \
                                 set volts_per_unit"
                            ),
                        ));
                    }
                    v
                }
            };
            if let Some(off) = table.and_then(|t| t.offset_volts.as_ref()) {
                board.channels[i].offset_volts = self.check(
                    Some(&section),
                    "offset_volts",
                    off,
                    true,
                    "a finite number (V)",
                )?;
            }
        }
        Ok(board)
    }
}
