//! The device's settings: the `STATUS` register, word length, gains, oversampling, power mode,
//! and the driver's [`Config`].

use crate::{reg, NUM_CHANNELS};

/// The device's `STATUS` register (the response to `NULL`), SBAS788 §8.6.1.2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status(pub u16);

impl Status {
    /// `LOCK`: the interface is locked.
    pub fn locked(self) -> bool {
        self.0 & (1 << 15) != 0
    }
    /// `F_RESYNC`: the ADC resynchronised (SYNC/RESET pulse).
    pub fn resync(self) -> bool {
        self.0 & (1 << 14) != 0
    }
    /// `REG_MAP`: the register-map CRC changed.
    pub fn reg_map_changed(self) -> bool {
        self.0 & (1 << 13) != 0
    }
    /// `CRC_ERR`: the input CRC of the previous frame was wrong.
    pub fn crc_error(self) -> bool {
        self.0 & (1 << 12) != 0
    }
    /// `CRC_TYPE`: true for ANSI, false for CCITT.
    pub fn crc_type_ansi(self) -> bool {
        self.0 & (1 << 11) != 0
    }
    /// `RESET`: the device was reset since `MODE.RESET` was last cleared.
    pub fn reset(self) -> bool {
        self.0 & (1 << 10) != 0
    }
    /// `WLENGTH`: the current word length.
    pub fn word_length(self) -> WordLength {
        WordLength::from_bits(self.0 >> 8)
    }
    /// `DRDYn`: channel `ch` has new data.
    pub fn data_ready(self, ch: usize) -> bool {
        ch < NUM_CHANNELS && self.0 & (1 << ch) != 0
    }
}

/// SPI word length (`MODE.WLENGTH`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WordLength {
    /// 16 bits, conversions truncated to 16 bits.
    Bits16,
    /// 24 bits (reset default).
    Bits24,
    /// 32 bits, conversions zero-padded in the LSBs.
    Bits32ZeroPad,
    /// 32 bits, conversions sign-extended in the MSBs.
    Bits32SignExtend,
}

impl WordLength {
    /// Bytes per word.
    pub const fn bytes(self) -> usize {
        match self {
            WordLength::Bits16 => 2,
            WordLength::Bits24 => 3,
            WordLength::Bits32ZeroPad | WordLength::Bits32SignExtend => 4,
        }
    }
    /// `WLENGTH` field value.
    pub const fn bits(self) -> u16 {
        match self {
            WordLength::Bits16 => 0,
            WordLength::Bits24 => 1,
            WordLength::Bits32ZeroPad => 2,
            WordLength::Bits32SignExtend => 3,
        }
    }
    pub(crate) fn from_bits(bits: u16) -> Self {
        match bits & 0b11 {
            0 => WordLength::Bits16,
            1 => WordLength::Bits24,
            2 => WordLength::Bits32ZeroPad,
            _ => WordLength::Bits32SignExtend,
        }
    }
    /// Codes per volt-of-reference: 2^23 for 24-bit data, 2^15 for 16-bit words.
    pub(crate) fn full_scale_codes(self) -> f32 {
        match self {
            WordLength::Bits16 => 32_768.0,
            _ => 8_388_608.0,
        }
    }
}

/// PGA gain (`GAIN1.PGAGAINn`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Gain {
    /// ×1 (±1.2 V).
    X1 = 0,
    /// ×2.
    X2 = 1,
    /// ×4.
    X4 = 2,
    /// ×8.
    X8 = 3,
    /// ×16.
    X16 = 4,
    /// ×32.
    X32 = 5,
    /// ×64.
    X64 = 6,
    /// ×128.
    X128 = 7,
}

impl Gain {
    /// The gain factor.
    pub const fn factor(self) -> f32 {
        (1u32 << (self as u32)) as f32
    }
}

/// Oversampling ratio (`CLOCK.OSR`); output data rate = f_CLKIN / 2 / OSR.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Osr {
    /// 128 (32 kSPS at 8.192 MHz).
    Osr128 = 0,
    /// 256 (16 kSPS).
    Osr256 = 1,
    /// 512 (8 kSPS).
    Osr512 = 2,
    /// 1024 (4 kSPS, reset default).
    Osr1024 = 3,
    /// 2048 (2 kSPS).
    Osr2048 = 4,
    /// 4096 (1 kSPS).
    Osr4096 = 5,
    /// 8192 (500 SPS).
    Osr8192 = 6,
    /// 16256 (≈252 SPS).
    Osr16256 = 7,
}

/// Power mode (`CLOCK.PWR`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PowerMode {
    /// Very low power.
    VeryLowPower = 0,
    /// Low power.
    LowPower = 1,
    /// High resolution (reset default).
    HighResolution = 2,
}

/// Configuration written by [`Ads131m04::configure`](crate::Ads131m04::configure).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Oversampling ratio.
    pub osr: Osr,
    /// Power mode.
    pub power: PowerMode,
    /// PGA gain per channel.
    pub gains: [Gain; NUM_CHANNELS],
    /// Enable the input CRC (`MODE.RX_CRC_EN`): the driver appends a CRC to every command.
    pub input_crc: bool,
}

impl Default for Config {
    /// The reset configuration: OSR 1024, high resolution, gain 1, no input CRC.
    fn default() -> Self {
        Self {
            osr: Osr::Osr1024,
            power: PowerMode::HighResolution,
            gains: [Gain::X1; NUM_CHANNELS],
            input_crc: false,
        }
    }
}

impl Config {
    /// The `CLOCK` register value (all channels enabled).
    pub const fn clock_register(&self) -> u16 {
        0x0F00 | ((self.osr as u16) << 2) | (self.power as u16)
    }
    /// The `GAIN1` register value.
    pub const fn gain_register(&self) -> u16 {
        (self.gains[0] as u16)
            | ((self.gains[1] as u16) << 4)
            | ((self.gains[2] as u16) << 8)
            | ((self.gains[3] as u16) << 12)
    }
    /// The `MODE` register value: 24-bit words, CCITT CRC, SPI timeout on, `RESET` flag cleared.
    pub const fn mode_register(&self) -> u16 {
        let crc = if self.input_crc {
            reg::MODE_RX_CRC_EN
        } else {
            0
        };
        crc | (WordLength::Bits24.bits() << reg::MODE_WLENGTH_SHIFT) | reg::MODE_TIMEOUT
    }
}
