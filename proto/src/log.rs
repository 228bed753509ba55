//! The binary sensor log (format version 1, little-endian; `proto/LOG_FORMAT.md`): what the
//! QEMU image replays through the pipeline. The host writes it ([`encode_header`],
//! [`encode_record`]), the firmware reads it ([`parse_header`], [`parse_record`],
//! [`parse_reversal`]). Pure functions over byte arrays.

use crate::channel::CHANNELS;
use crate::flags;
use crate::frame::Sample;
use ssvr_core::StructureParams;

/// File magic.
pub const MAGIC: [u8; 8] = *b"SSVRLOG1";
/// Format version written and read.
pub const VERSION: u16 = 1;
/// Length of the version-1 header (a larger `header_len` is accepted; the rest is skipped).
pub const HEADER_LEN: usize = 80;
/// Fixed part of a record: 4 × f32 channels + u8 flags.
pub const RECORD_LEN: usize = 4 * CHANNELS + 1;
/// Optional reversal event after the fixed part: i8 level + f32 age (samples).
pub const REVERSAL_LEN: usize = 5;
/// Longest record.
pub const MAX_RECORD_LEN: usize = RECORD_LEN + REVERSAL_LEN;
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
    /// instead of the detector (which still runs).
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

impl Header {
    /// A version-1 header.
    pub fn new(
        sample_rate_hz: f64,
        params: StructureParams,
        options: u16,
        sample_count: u32,
    ) -> Self {
        Self {
            version: VERSION,
            header_len: HEADER_LEN as u16,
            channel_count: CHANNELS as u16,
            options,
            sample_rate_hz,
            params,
            sample_count,
        }
    }
}

/// A friction reversal carried by a record (the test hook [`options::LOG_REVERSALS`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogReversal {
    /// New friction level: +1 or −1 (0 allowed).
    pub level: i8,
    /// Sample intervals between the reversal and this record's sample (≥ 0).
    pub age_samples: f32,
}

/// Log errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
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
    /// The pipeline needs 4 channels.
    BadChannelCount(u16),
    /// The sample rate is not finite and positive.
    BadSampleRate,
    /// The file ends inside a record, or before `sample_count` records.
    Truncated,
}

fn u16_at(b: &[u8], i: usize) -> u16 {
    match b.get(i..i + 2) {
        Some(&[a, c]) => u16::from_le_bytes([a, c]),
        _ => 0,
    }
}
fn u32_at(b: &[u8], i: usize) -> u32 {
    match b.get(i..i + 4) {
        Some(&[a, c, d, e]) => u32::from_le_bytes([a, c, d, e]),
        _ => 0,
    }
}
fn f32_at(b: &[u8], i: usize) -> f32 {
    f32::from_bits(u32_at(b, i))
}
fn f64_at(b: &[u8], i: usize) -> f64 {
    f64::from_bits(u64::from(u32_at(b, i)) | (u64::from(u32_at(b, i + 4)) << 32))
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

/// Encode a version-1 header.
pub fn encode_header(h: &Header) -> [u8; HEADER_LEN] {
    let mut b = [0u8; HEADER_LEN];
    b[0..8].copy_from_slice(&MAGIC);
    b[8..10].copy_from_slice(&VERSION.to_le_bytes());
    b[10..12].copy_from_slice(&(HEADER_LEN as u16).to_le_bytes());
    b[12..14].copy_from_slice(&(CHANNELS as u16).to_le_bytes());
    b[14..16].copy_from_slice(&h.options.to_le_bytes());
    let p = &h.params;
    for (i, v) in [
        h.sample_rate_hz,
        p.m1_kg,
        p.m2_kg,
        p.natural_frequency_hz,
        p.damping_ratio,
        p.friction_coefficient,
        p.gravity_m_s2,
    ]
    .into_iter()
    .enumerate()
    {
        b[16 + 8 * i..24 + 8 * i].copy_from_slice(&v.to_le_bytes());
    }
    b[72..76].copy_from_slice(&h.sample_count.to_le_bytes());
    b
}

/// Parse the fixed part of a record: the sample (acquisition flags mapped to frame flags: a
/// saturated displacement is `SATURATED | DISP_INVALID`) and whether a reversal event follows.
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
pub fn parse_reversal(b: &[u8; REVERSAL_LEN]) -> LogReversal {
    LogReversal {
        level: b[0] as i8,
        age_samples: f32_at(b, 1),
    }
}

/// Encode a sample as a record (the inverse of [`parse_record`] and [`parse_reversal`]: flag
/// `DISP_INVALID` is written as a saturated displacement, `SATURATED` and `MISSING` as such; the
/// others are the pipeline's and are not logged). Returns the record's length.
pub fn encode_record(s: &Sample, b: &mut [u8; MAX_RECORD_LEN]) -> usize {
    for (i, v) in s.channels.iter().enumerate() {
        b[4 * i..4 * i + 4].copy_from_slice(&v.to_le_bytes());
    }
    let mut rf = 0u8;
    if s.flags & (flags::SATURATED | flags::DISP_INVALID) != 0 {
        rf |= record_flags::SATURATED;
    }
    if s.flags & flags::DISP_INVALID != 0 {
        rf |= record_flags::DISP_SATURATED;
    }
    if s.flags & flags::MISSING != 0 {
        rf |= record_flags::MISSING;
    }
    if s.reversal.is_some() {
        rf |= record_flags::HAS_REVERSAL;
    }
    b[4 * CHANNELS] = rf;
    match s.reversal {
        Some(r) => {
            b[RECORD_LEN] = r.level as u8;
            b[RECORD_LEN + 1..MAX_RECORD_LEN].copy_from_slice(&r.age_samples.to_le_bytes());
            MAX_RECORD_LEN
        }
        None => RECORD_LEN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_and_records_round_trip() {
        let p = crate::test_params();
        let h = Header::new(10_000.0, p, options::LOG_REVERSALS, 3);
        assert_eq!(parse_header(&encode_header(&h)), Ok(h));
        for s in [
            Sample {
                channels: [1.0, -2.5, 3.25, 1e-3],
                flags: 0,
                reversal: None,
            },
            Sample {
                channels: [1.0, f32::INFINITY, 0.0, 0.05],
                flags: flags::SATURATED | flags::DISP_INVALID,
                reversal: Some(LogReversal {
                    level: -1,
                    age_samples: 0.75,
                }),
            },
            Sample::missing(0),
        ] {
            let mut b = [0u8; MAX_RECORD_LEN];
            let n = encode_record(&s, &mut b);
            let mut fixed = [0u8; RECORD_LEN];
            fixed.copy_from_slice(&b[..RECORD_LEN]);
            let (mut back, more) = parse_record(&fixed);
            assert_eq!(more, s.reversal.is_some());
            if more {
                let mut r = [0u8; REVERSAL_LEN];
                r.copy_from_slice(&b[RECORD_LEN..n]);
                back.reversal = Some(parse_reversal(&r));
            }
            assert_eq!(back.flags, s.flags);
            assert_eq!(back.reversal, s.reversal);
            for (a, c) in back.channels.iter().zip(s.channels.iter()) {
                assert_eq!(a.to_bits(), c.to_bits());
            }
        }
    }

    #[test]
    fn bad_headers_are_typed_errors() {
        let h = Header::new(1000.0, crate::test_params(), 0, 0);
        let mut b = encode_header(&h);
        b[0] = b'X';
        assert_eq!(parse_header(&b), Err(LogError::BadMagic));
        let mut b = encode_header(&h);
        b[8] = 2;
        assert_eq!(parse_header(&b), Err(LogError::BadVersion(2)));
        let mut b = encode_header(&Header::new(f64::NAN, crate::test_params(), 0, 0));
        assert_eq!(parse_header(&b), Err(LogError::BadSampleRate));
        b[12] = 3;
        assert_eq!(parse_header(&b), Err(LogError::BadChannelCount(3)));
    }
}
