//! Parser of the binary sensor log (format version 1, see `LOG_FORMAT.md`). Pure functions over
//! byte slices; the QEMU image feeds them from a semihosting file.

use super::pipeline::{flags, Reversal, Sample, CHANNELS};
use ssvr_core::StructureParams;

/// File magic.
pub const MAGIC: [u8; 8] = *b"SSVRLOG1";
/// Format version this firmware reads.
pub const VERSION: u16 = 1;
/// Length of the version-1 header (a larger `header_len` is accepted; the rest is skipped).
pub const HEADER_LEN: usize = 80;
/// Fixed part of a record: 4 × f32 channels + u8 flags.
pub const RECORD_LEN: usize = 4 * CHANNELS + 1;
/// Optional reversal event after the fixed part: i8 level + f32 age (samples).
pub const REVERSAL_LEN: usize = 5;
/// `sample_count` meaning "read until end of file".
pub const COUNT_UNTIL_EOF: u32 = u32::MAX;

/// Bits of a record's flags byte.
pub mod record_flags {
    /// A channel was at the ADC full scale.
    pub const SATURATED: u8 = 1 << 0;
    /// The sample was not acquired (its channels are meaningless).
    pub const MISSING: u8 = 1 << 1;
    /// The displacement channel was at its full scale (the detector skips the sample).
    pub const DISP_SATURATED: u8 = 1 << 2;
    /// A reversal event (i8 level, f32 age in samples) follows the flags byte.
    pub const HAS_REVERSAL: u8 = 1 << 7;
}

/// Bits of the header's `options` field (offset 14).
pub mod options {
    /// Test hook: the estimator takes its friction events from the records' reversal events
    /// instead of the reversal detector (which still runs).
    pub const LOG_REVERSALS: u16 = 1 << 0;
}

/// The log header.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Header {
    /// Format version.
    pub version: u16,
    /// Header length in bytes (≥ [`HEADER_LEN`]).
    pub header_len: u16,
    /// Channels per record (must be 4).
    pub channel_count: u16,
    /// Bits of [`options`].
    pub options: u16,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Structure parameters.
    pub params: StructureParams,
    /// Number of records, or [`COUNT_UNTIL_EOF`].
    pub sample_count: u32,
}

/// Log errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, defmt::Format)]
pub enum LogError {
    /// The file could not be opened.
    Open,
    /// A host read failed.
    Io,
    /// Wrong magic.
    BadMagic,
    /// Unsupported version.
    BadVersion(u16),
    /// Header shorter than version 1's.
    BadHeaderLen(u16),
    /// The firmware needs 4 channels.
    BadChannelCount(u16),
    /// The sample rate is not finite and positive.
    BadSampleRate,
    /// The file ends inside a record, or before `sample_count` records.
    Truncated,
}

fn u16_at(b: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([b[i], b[i + 1]])
}
fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}
fn f32_at(b: &[u8], i: usize) -> f32 {
    f32::from_bits(u32_at(b, i))
}
fn f64_at(b: &[u8], i: usize) -> f64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[i..i + 8]);
    f64::from_le_bytes(a)
}

/// Parse the first [`HEADER_LEN`] bytes of a log.
pub fn parse_header(b: &[u8; HEADER_LEN]) -> Result<Header, LogError> {
    if b[0..8] != MAGIC {
        return Err(LogError::BadMagic);
    }
    let version = u16_at(b, 8);
    if version != VERSION {
        return Err(LogError::BadVersion(version));
    }
    let header_len = u16_at(b, 10);
    if usize::from(header_len) < HEADER_LEN {
        return Err(LogError::BadHeaderLen(header_len));
    }
    let channel_count = u16_at(b, 12);
    if usize::from(channel_count) != CHANNELS {
        return Err(LogError::BadChannelCount(channel_count));
    }
    let sample_rate_hz = f64_at(b, 16);
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(LogError::BadSampleRate);
    }
    Ok(Header {
        version,
        header_len,
        channel_count,
        options: u16_at(b, 14),
        sample_rate_hz,
        params: StructureParams {
            m1_kg: f64_at(b, 24),
            m2_kg: f64_at(b, 32),
            natural_frequency_hz: f64_at(b, 40),
            damping_ratio: f64_at(b, 48),
            friction_coefficient: f64_at(b, 56),
            gravity_m_s2: f64_at(b, 64),
        },
        sample_count: u32_at(b, 72),
    })
}

/// Parse the fixed part of a record; returns the sample and whether a reversal event follows.
pub fn parse_record(b: &[u8; RECORD_LEN]) -> (Sample, bool) {
    let mut channels = [0.0f32; CHANNELS];
    for (i, c) in channels.iter_mut().enumerate() {
        *c = f32_at(b, 4 * i);
    }
    let rf = b[4 * CHANNELS];
    let mut fl = 0;
    if rf & record_flags::SATURATED != 0 {
        fl |= flags::SATURATED;
    }
    if rf & record_flags::MISSING != 0 {
        fl |= flags::MISSING;
    }
    if rf & record_flags::DISP_SATURATED != 0 {
        fl |= flags::SATURATED | flags::DISP_INVALID;
    }
    (
        Sample {
            channels,
            flags: fl,
            reversal: None,
        },
        rf & record_flags::HAS_REVERSAL != 0,
    )
}

/// Parse a reversal event.
pub fn parse_reversal(b: &[u8; REVERSAL_LEN]) -> Reversal {
    Reversal {
        level: f32::from(b[0] as i8),
        age_samples: f32_at(b, 1),
    }
}
