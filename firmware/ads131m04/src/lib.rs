//! # ads131m04
//!
//! A `no_std` [`embedded-hal` 1.0](embedded_hal) driver for the TI **ADS131M04**, a 4-channel,
//! simultaneously sampling, 24-bit delta-sigma ADC (datasheet SBAS788).
//!
//! The driver owns an [`SpiDevice`] (chip select is the device's business, e.g.
//! `embedded_hal_bus::spi::ExclusiveDevice`). The bus must run in **SPI mode 1** (CPOL = 0,
//! CPHA = 1), MSB first, at most 25 MHz.
//!
//! ## Frames (SBAS788 §8.5.1)
//!
//! Every SPI transaction is one *frame* of words; a word is 16, 24 (default), or 32 bits. A frame
//! has at least N + 2 = 6 words:
//!
//! * **in** (DIN): command word, the data words of a `WREG`, an optional input CRC word
//!   (`MODE.RX_CRC_EN`), then zero padding;
//! * **out** (DOUT): the *response* to the command of the **previous** frame, the four channel
//!   conversions (two's complement, MSB first), then the output CRC word.
//!
//! 16-bit commands, responses, register values and CRCs are MSB-aligned in a word and padded with
//! zeros. The CRC is CRC-16-CCITT (polynomial 0x1021, seed 0xFFFF, no reflection) over every byte
//! of the frame that precedes the CRC word, padding included; the device always sends the output
//! CRC, and [`Ads131m04::read_frame`] checks it.
//!
//! Responses arrive one frame late, so each command method sends its command and then a `NULL`
//! frame to fetch and check the response (`NULL`'s own response is the `STATUS` register).
#![no_std]
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::SpiDevice;

/// Number of channels of the ADS131M04.
pub const NUM_CHANNELS: usize = 4;
/// Words in a standard frame: response/command, 4 channels, CRC.
pub const FRAME_WORDS: usize = NUM_CHANNELS + 2;
/// Largest frame the driver builds (a `WREG` of [`MAX_WRITE_REGISTERS`] registers plus CRC).
const MAX_FRAME_WORDS: usize = 16;
/// Most registers one [`Ads131m04::write_registers`] call may write.
pub const MAX_WRITE_REGISTERS: usize = MAX_FRAME_WORDS - 2;
/// Internal reference voltage (V): full scale is ±1.2 V / gain.
pub const VREF_INTERNAL: f32 = 1.2;
/// Largest 24-bit code (positive full scale, also the saturation code).
pub const CODE_MAX: i32 = 0x7F_FFFF;
/// Smallest 24-bit code (negative full scale, also the saturation code).
pub const CODE_MIN: i32 = -0x80_0000;

mod config;
mod protocol;

pub use config::{Config, Gain, Osr, PowerMode, Status, WordLength};
pub use protocol::{command, reg, response};

/// Driver errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The SPI device failed.
    Spi(E),
    /// The output CRC of a frame does not match its contents.
    Crc {
        /// CRC computed over the received frame.
        computed: u16,
        /// CRC word the device sent.
        received: u16,
    },
    /// A command got an unexpected response.
    BadResponse {
        /// The command sent.
        command: u16,
        /// The response expected.
        expected: u16,
        /// The response received.
        received: u16,
    },
    /// The device reported an input CRC error (`STATUS.CRC_ERR`) for the previous command.
    InputCrc {
        /// The `STATUS` word.
        status: u16,
    },
    /// The `ID` register does not name a 4-channel device.
    BadId {
        /// The `ID` register value.
        id: u16,
    },
    /// An argument is out of range (register address, register count).
    InvalidArgument,
}

impl<E> Error<E> {
    /// Map the SPI error (e.g. to `()` to log an error whose SPI type has no `defmt::Format`).
    pub fn map_spi<F>(self, f: impl FnOnce(E) -> F) -> Error<F> {
        match self {
            Error::Spi(e) => Error::Spi(f(e)),
            Error::Crc { computed, received } => Error::Crc { computed, received },
            Error::BadResponse {
                command,
                expected,
                received,
            } => Error::BadResponse {
                command,
                expected,
                received,
            },
            Error::InputCrc { status } => Error::InputCrc { status },
            Error::BadId { id } => Error::BadId { id },
            Error::InvalidArgument => Error::InvalidArgument,
        }
    }
}

impl<E> From<E> for Error<E> {
    fn from(e: E) -> Self {
        Error::Spi(e)
    }
}

/// One output frame: the response word, the four raw conversions and the CRC (already checked).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    /// Response to the previous frame's command (`STATUS` after a `NULL`).
    pub response: u16,
    /// Raw conversions, sign-extended to i32 (24-bit codes, or 16-bit codes with 16-bit words).
    pub raw: [i32; NUM_CHANNELS],
    /// The output CRC word.
    pub crc: u16,
}

impl Frame {
    /// The response interpreted as `STATUS` (valid when the previous command was `NULL`).
    pub fn status(&self) -> Status {
        Status(self.response)
    }
    /// Channel `ch` is at a full-scale code (the modulator clips there).
    pub fn saturated(&self, ch: usize) -> bool {
        match self.raw.get(ch) {
            Some(&r) => r >= CODE_MAX || r <= CODE_MIN,
            None => false,
        }
    }
    /// Bit `n` set when channel `n` is saturated.
    pub fn saturation_mask(&self) -> u8 {
        (0..NUM_CHANNELS).fold(0, |m, ch| m | ((self.saturated(ch) as u8) << ch))
    }
}

/// CRC-16-CCITT as the device computes it: polynomial 0x1021, seed 0xFFFF, MSB first, no final XOR.
pub fn crc16_ccitt(bytes: &[u8]) -> u16 {
    let mut crc: u16 = 0xFFFF;
    for &b in bytes {
        crc ^= (b as u16) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// Linear scaling of one channel from ADC input volts to SI units: `si = (volts − offset) / sensitivity`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelScale {
    /// Sensor sensitivity at the ADC input (V per SI unit, e.g. V/(m/s²) or V/m), non-zero.
    pub volts_per_unit: f32,
    /// ADC input voltage at zero physical quantity (V).
    pub offset_volts: f32,
}

impl ChannelScale {
    /// Convert volts to SI units.
    pub fn to_si(&self, volts: f32) -> f32 {
        (volts - self.offset_volts) / self.volts_per_unit
    }
}

/// The ADS131M04 on an SPI device.
#[derive(Debug)]
pub struct Ads131m04<SPI> {
    spi: SPI,
    word: WordLength,
    input_crc: bool,
    gains: [Gain; NUM_CHANNELS],
}

impl<SPI: SpiDevice> Ads131m04<SPI> {
    /// Take the SPI device. Assumes the reset state (24-bit words, no input CRC, gain 1) until
    /// [`Self::reset`] or [`Self::configure`] is called.
    pub fn new(spi: SPI) -> Self {
        Self {
            spi,
            word: WordLength::Bits24,
            input_crc: false,
            gains: [Gain::X1; NUM_CHANNELS],
        }
    }

    /// Give the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// The word length the driver uses.
    pub fn word_length(&self) -> WordLength {
        self.word
    }

    /// The PGA gains the driver assumes when converting to volts.
    pub fn gains(&self) -> [Gain; NUM_CHANNELS] {
        self.gains
    }

    /// Send one frame with `command` and `data` words; return the output frame (CRC checked).
    pub fn transfer_frame(
        &mut self,
        command: u16,
        data: &[u16],
    ) -> Result<Frame, Error<SPI::Error>> {
        let wb = self.word.bytes();
        let in_words = 1 + data.len() + usize::from(self.input_crc);
        if in_words > MAX_FRAME_WORDS {
            return Err(Error::InvalidArgument);
        }
        let words = if in_words > FRAME_WORDS {
            in_words
        } else {
            FRAME_WORDS
        };
        let mut buf = [0u8; MAX_FRAME_WORDS * 4];
        let frame = &mut buf[..words * wb];
        put_word16(frame, 0, wb, command);
        for (i, &d) in data.iter().enumerate() {
            put_word16(frame, 1 + i, wb, d);
        }
        if self.input_crc {
            let n = (1 + data.len()) * wb;
            let crc = crc16_ccitt(&frame[..n]);
            put_word16(frame, 1 + data.len(), wb, crc);
        }
        self.spi.transfer_in_place(frame)?;
        self.parse(frame)
    }

    fn parse(&self, frame: &[u8]) -> Result<Frame, Error<SPI::Error>> {
        let wb = self.word.bytes();
        let crc_at = (FRAME_WORDS - 1) * wb;
        let computed = crc16_ccitt(&frame[..crc_at]);
        let received = get_word16(frame, FRAME_WORDS - 1, wb);
        if computed != received {
            return Err(Error::Crc { computed, received });
        }
        let mut raw = [0i32; NUM_CHANNELS];
        for (ch, r) in raw.iter_mut().enumerate() {
            *r = get_code(frame, 1 + ch, self.word);
        }
        Ok(Frame {
            response: get_word16(frame, 0, wb),
            raw,
            crc: received,
        })
    }

    /// Send `command`, then a `NULL` frame whose response must be `expected`.
    /// Returns the `NULL` frame.
    fn command_checked(
        &mut self,
        command: u16,
        data: &[u16],
        expected: u16,
    ) -> Result<Frame, Error<SPI::Error>> {
        self.transfer_frame(command, data)?;
        let f = self.transfer_frame(command::NULL, &[])?;
        if f.response != expected {
            return Err(Error::BadResponse {
                command,
                expected,
                received: f.response,
            });
        }
        Ok(f)
    }

    /// Software reset: `RESET`, wait 1 ms, then `NULL`, whose response must be `0xFF24`.
    /// Afterwards the driver assumes the reset state (24-bit words, no input CRC, gain 1).
    pub fn reset(&mut self, delay: &mut impl DelayNs) -> Result<(), Error<SPI::Error>> {
        self.transfer_frame(command::RESET, &[])?;
        self.word = WordLength::Bits24;
        self.input_crc = false;
        self.gains = [Gain::X1; NUM_CHANNELS];
        delay.delay_ms(1);
        let f = self.transfer_frame(command::NULL, &[])?;
        if f.response != response::RESET_OK {
            return Err(Error::BadResponse {
                command: command::RESET,
                expected: response::RESET_OK,
                received: f.response,
            });
        }
        Ok(())
    }

    /// `UNLOCK` the register map (response `0x0655`).
    pub fn unlock(&mut self) -> Result<(), Error<SPI::Error>> {
        self.command_checked(command::UNLOCK, &[], response::UNLOCK_OK)
            .map(|_| ())
    }

    /// `LOCK` the interface (response `0x0555`).
    pub fn lock(&mut self) -> Result<(), Error<SPI::Error>> {
        self.command_checked(command::LOCK, &[], response::LOCK_OK)
            .map(|_| ())
    }

    /// `STANDBY` (response `0x0022`).
    pub fn standby(&mut self) -> Result<(), Error<SPI::Error>> {
        self.command_checked(command::STANDBY, &[], response::STANDBY_OK)
            .map(|_| ())
    }

    /// `WAKEUP` (response `0x0033`).
    pub fn wakeup(&mut self) -> Result<(), Error<SPI::Error>> {
        self.command_checked(command::WAKEUP, &[], response::WAKEUP_OK)
            .map(|_| ())
    }

    /// Read one register (`RREG` with n = 0; the response is the register value).
    pub fn read_register(&mut self, addr: u8) -> Result<u16, Error<SPI::Error>> {
        if addr > 0x3F {
            return Err(Error::InvalidArgument);
        }
        self.transfer_frame(command::rreg(addr, 1), &[])?;
        Ok(self.transfer_frame(command::NULL, &[])?.response)
    }

    /// Write consecutive registers from `addr` (`WREG`), then check the acknowledgement
    /// `010a aaaa ammm mmmm`. A write to `MODE` switches the driver's word length / input CRC.
    pub fn write_registers(&mut self, addr: u8, values: &[u16]) -> Result<(), Error<SPI::Error>> {
        let n = values.len();
        if n == 0 || n > MAX_WRITE_REGISTERS || usize::from(addr) + n > 0x40 {
            return Err(Error::InvalidArgument);
        }
        let count = n as u8;
        let cmd = command::wreg(addr, count);
        self.transfer_frame(cmd, values)?;
        if let Some(&mode) = values.get(usize::from(reg::MODE).wrapping_sub(usize::from(addr))) {
            if addr <= reg::MODE {
                self.word = WordLength::from_bits(mode >> reg::MODE_WLENGTH_SHIFT);
                self.input_crc = mode & reg::MODE_RX_CRC_EN != 0;
            }
        }
        if let Some(&gain) = values.get(usize::from(reg::GAIN1).wrapping_sub(usize::from(addr))) {
            if addr <= reg::GAIN1 {
                self.gains = gains_from_register(gain);
            }
        }
        let expected = response::wreg_ack(addr, count);
        let f = self.transfer_frame(command::NULL, &[])?;
        if f.response != expected {
            return Err(Error::BadResponse {
                command: cmd,
                expected,
                received: f.response,
            });
        }
        Ok(())
    }

    /// Write one register.
    pub fn write_register(&mut self, addr: u8, value: u16) -> Result<(), Error<SPI::Error>> {
        self.write_registers(addr, &[value])
    }

    /// Check `ID` (4 channels), then write `MODE`, `CLOCK` and `GAIN1` (one `WREG` of 3 registers).
    pub fn configure(&mut self, config: &Config) -> Result<(), Error<SPI::Error>> {
        let id = self.read_register(reg::ID)?;
        if (id >> 8) & 0x0F != NUM_CHANNELS as u16 {
            return Err(Error::BadId { id });
        }
        self.write_registers(
            reg::MODE,
            &[
                config.mode_register(),
                config.clock_register(),
                config.gain_register(),
            ],
        )
    }

    /// Read the latest conversions with a `NULL` frame. The response is `STATUS`; an input CRC
    /// error it reports is returned as [`Error::InputCrc`].
    pub fn read_frame(&mut self) -> Result<Frame, Error<SPI::Error>> {
        let f = self.transfer_frame(command::NULL, &[])?;
        if self.input_crc && f.status().crc_error() {
            return Err(Error::InputCrc { status: f.response });
        }
        Ok(f)
    }

    /// Volts at the ADC inputs of a frame: code × 1.2 V / (gain · 2^23).
    pub fn to_volts(&self, frame: &Frame) -> [f32; NUM_CHANNELS] {
        let fs = self.word.full_scale_codes();
        let mut v = [0.0f32; NUM_CHANNELS];
        for ((v, &raw), gain) in v.iter_mut().zip(frame.raw.iter()).zip(self.gains.iter()) {
            *v = raw as f32 * (VREF_INTERNAL / (gain.factor() * fs));
        }
        v
    }

    /// Read a frame and convert it to SI units with per-channel scales.
    pub fn read_si(
        &mut self,
        scales: &[ChannelScale; NUM_CHANNELS],
    ) -> Result<(Frame, [f32; NUM_CHANNELS]), Error<SPI::Error>> {
        let f = self.read_frame()?;
        let v = self.to_volts(&f);
        let mut si = [0.0f32; NUM_CHANNELS];
        for ((s, v), scale) in si.iter_mut().zip(v.iter()).zip(scales.iter()) {
            *s = scale.to_si(*v);
        }
        Ok((f, si))
    }
}

fn gains_from_register(value: u16) -> [Gain; NUM_CHANNELS] {
    let mut g = [Gain::X1; NUM_CHANNELS];
    for (ch, g) in g.iter_mut().enumerate() {
        *g = match (value >> (4 * ch)) & 0b111 {
            0 => Gain::X1,
            1 => Gain::X2,
            2 => Gain::X4,
            3 => Gain::X8,
            4 => Gain::X16,
            5 => Gain::X32,
            6 => Gain::X64,
            _ => Gain::X128,
        };
    }
    g
}

/// Put a 16-bit value MSB-aligned into word `i` (the rest of the word stays zero).
fn put_word16(frame: &mut [u8], i: usize, wb: usize, value: u16) {
    let [hi, lo] = value.to_be_bytes();
    if let Some(w) = frame.get_mut(i * wb..i * wb + 2) {
        w[0] = hi;
        w[1] = lo;
    }
}

/// The MSB-aligned 16 bits of word `i`.
fn get_word16(frame: &[u8], i: usize, wb: usize) -> u16 {
    match frame.get(i * wb..i * wb + 2) {
        Some(w) => u16::from_be_bytes([w[0], w[1]]),
        None => 0,
    }
}

/// The conversion code in word `i`, sign-extended.
fn get_code(frame: &[u8], i: usize, word: WordLength) -> i32 {
    let wb = word.bytes();
    let Some(w) = frame.get(i * wb..(i + 1) * wb) else {
        return 0;
    };
    match word {
        WordLength::Bits16 => i16::from_be_bytes([w[0], w[1]]) as i32,
        WordLength::Bits24 | WordLength::Bits32ZeroPad => {
            // The code is in the top 24 bits: shift into the top of an i32 and back.
            i32::from_be_bytes([w[0], w[1], w[2], 0]) >> 8
        }
        WordLength::Bits32SignExtend => i32::from_be_bytes([0, w[1], w[2], w[3]]) << 8 >> 8,
    }
}
