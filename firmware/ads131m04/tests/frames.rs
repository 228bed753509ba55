//! Host tests of the ADS131M04 driver against the frame format of SBAS788 §8.5, with
//! `embedded-hal-mock`. Run from `firmware/`:
//!
//! ```text
//! cargo test -p ads131m04 --target x86_64-unknown-linux-gnu    # or: cargo test-host
//! ```
//!
//! Frames are built here byte by byte (24-bit words: 16-bit commands/responses/CRCs MSB-aligned
//! and zero-padded, channel codes as 3 big-endian bytes), with an independent bit-serial CRC.

use ads131m04::{
    command, crc16_ccitt, reg, response, Ads131m04, ChannelScale, Config, Error, Gain, Osr,
    PowerMode, WordLength,
};
use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};
use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::spi::{Mock, Transaction};

/// CRC-16-CCITT (0x1021, seed 0xFFFF) computed bit by bit over the message bits, as an LFSR
/// (independent of the driver's byte-wise loop).
fn crc_reference(bytes: &[u8]) -> u16 {
    let mut reg: u32 = 0xFFFF;
    for &b in bytes {
        for i in (0..8).rev() {
            let bit = ((b >> i) & 1) as u32;
            let msb = (reg >> 15) & 1;
            reg = (reg << 1) & 0xFFFF;
            if msb ^ bit == 1 {
                reg ^= 0x1021;
            }
        }
    }
    reg as u16
}

/// A 24-bit word holding a 16-bit value, MSB-aligned.
fn w16(v: u16) -> [u8; 3] {
    [(v >> 8) as u8, v as u8, 0]
}

/// A 24-bit word holding a conversion code.
fn code(v: i32) -> [u8; 3] {
    let u = (v as u32) & 0xFF_FFFF;
    [(u >> 16) as u8, (u >> 8) as u8, u as u8]
}

/// Input frame: command, data words, optional CRC, zero padding to at least 6 words.
fn tx(cmd: u16, data: &[u16], with_crc: bool) -> Vec<u8> {
    let mut f = Vec::new();
    f.extend_from_slice(&w16(cmd));
    for &d in data {
        f.extend_from_slice(&w16(d));
    }
    if with_crc {
        let c = crc_reference(&f);
        f.extend_from_slice(&w16(c));
    }
    while f.len() < 6 * 3 {
        f.extend_from_slice(&[0, 0, 0]);
    }
    f
}

/// Output frame: response, 4 codes, CRC over the 15 preceding bytes, padded to `len` bytes.
fn rx_len(resp: u16, codes: [i32; 4], len: usize) -> Vec<u8> {
    let mut f = Vec::new();
    f.extend_from_slice(&w16(resp));
    for c in codes {
        f.extend_from_slice(&code(c));
    }
    let c = crc_reference(&f);
    f.extend_from_slice(&w16(c));
    f.resize(len.max(f.len()), 0);
    f
}

fn rx(resp: u16, codes: [i32; 4]) -> Vec<u8> {
    rx_len(resp, codes, 18)
}

/// One SPI-device transaction: CS low, full-duplex transfer, CS high.
fn frame(tx: Vec<u8>, rx: Vec<u8>) -> [Transaction<u8>; 3] {
    [
        Transaction::transaction_start(),
        Transaction::transfer_in_place(tx, rx),
        Transaction::transaction_end(),
    ]
}

fn script(frames: Vec<[Transaction<u8>; 3]>) -> Vec<Transaction<u8>> {
    frames.into_iter().flatten().collect()
}

const STATUS_IDLE: u16 = 0x0500; // WLENGTH = 24 bit, RESET flag
const STATUS_DRDY: u16 = 0x050F; // + DRDY0..3

#[test]
fn crc_matches_ccitt_false_check_value() {
    assert_eq!(crc16_ccitt(b"123456789"), 0x29B1);
    assert_eq!(crc_reference(b"123456789"), 0x29B1);
    let frame = [0xFFu8, 0x24, 0x00, 0x12, 0x34, 0x56, 0x80, 0x00, 0x00];
    assert_eq!(crc16_ccitt(&frame), crc_reference(&frame));
}

#[test]
fn command_words_follow_the_datasheet_opcodes() {
    assert_eq!(command::rreg(reg::ID, 1), 0xA000);
    assert_eq!(command::rreg(reg::CLOCK, 1), 0b1010_0001_1000_0000);
    assert_eq!(command::rreg(reg::REGMAP_CRC, 1), 0xBF00);
    assert_eq!(command::wreg(reg::MODE, 3), 0b0110_0001_0000_0010);
    assert_eq!(response::wreg_ack(reg::MODE, 3), 0b0100_0001_0000_0010);
    assert_eq!(reg::ch_cfg(3), 0x18);
    let c = Config {
        osr: Osr::Osr4096,
        power: PowerMode::HighResolution,
        gains: [Gain::X1, Gain::X2, Gain::X4, Gain::X128],
        input_crc: false,
    };
    assert_eq!(c.clock_register(), 0x0F16);
    assert_eq!(c.gain_register(), 0x7210);
    assert_eq!(c.mode_register(), 0x0110);
    assert_eq!(Config::default().clock_register(), reg::CLOCK_RESET_VALUE);
}

#[test]
fn reset_expects_ff24_in_the_next_frame() {
    let exp = script(vec![
        frame(tx(command::RESET, &[], false), rx(STATUS_IDLE, [0; 4])),
        frame(tx(command::NULL, &[], false), rx(0xFF24, [0; 4])),
    ]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    adc.reset(&mut NoopDelay::new()).unwrap();
    spi.done();
}

#[test]
fn reset_with_wrong_response_is_bad_response() {
    let exp = script(vec![
        frame(tx(command::RESET, &[], false), rx(STATUS_IDLE, [0; 4])),
        frame(tx(command::NULL, &[], false), rx(STATUS_IDLE, [0; 4])),
    ]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    assert_eq!(
        adc.reset(&mut NoopDelay::new()),
        Err(Error::BadResponse {
            command: 0x0011,
            expected: 0xFF24,
            received: STATUS_IDLE
        })
    );
    spi.done();
}

#[test]
fn data_frame_is_status_plus_four_twos_complement_codes() {
    let codes = [0x40_0000, -1, 0x7F_FFFF, -0x80_0000];
    let exp = script(vec![frame(
        tx(command::NULL, &[], false),
        rx(STATUS_DRDY, codes),
    )]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    let f = adc.read_frame().unwrap();
    assert_eq!(f.raw, codes);
    assert_eq!(f.status().word_length(), WordLength::Bits24);
    assert!(f.status().reset());
    assert!((0..4).all(|ch| f.status().data_ready(ch)));
    assert!(!f.status().crc_error());
    assert_eq!(f.saturation_mask(), 0b1100);
    let v = adc.to_volts(&f);
    assert!((v[0] - 0.6).abs() < 1e-7);
    assert!((v[1] + 1.2 / 8_388_608.0).abs() < 1e-12);
    assert!((v[3] + 1.2).abs() < 1e-7);
    spi.done();
}

#[test]
fn corrupted_frame_is_a_crc_error() {
    let mut bad = rx(STATUS_DRDY, [1, 2, 3, 4]);
    bad[5] ^= 0x01; // flip a bit of channel 0
    let good_crc = u16::from_be_bytes([bad[15], bad[16]]);
    let exp = script(vec![frame(tx(command::NULL, &[], false), bad.clone())]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    match adc.read_frame() {
        Err(Error::Crc { computed, received }) => {
            assert_eq!(received, good_crc);
            assert_eq!(computed, crc_reference(&bad[..15]));
        }
        other => panic!("expected a CRC error, got {other:?}"),
    }
    spi.done();
}

#[test]
fn read_register_sends_rreg_and_reads_the_value_a_frame_later() {
    let exp = script(vec![
        frame(tx(0xA180, &[], false), rx(STATUS_IDLE, [0; 4])),
        frame(tx(command::NULL, &[], false), rx(0x0F0E, [0; 4])),
    ]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    assert_eq!(adc.read_register(reg::CLOCK).unwrap(), 0x0F0E);
    spi.done();
}

#[test]
fn unlock_and_lock_check_their_acknowledgements() {
    let exp = script(vec![
        frame(tx(command::UNLOCK, &[], false), rx(STATUS_IDLE, [0; 4])),
        frame(tx(command::NULL, &[], false), rx(0x0655, [0; 4])),
        frame(tx(command::LOCK, &[], false), rx(STATUS_IDLE, [0; 4])),
        frame(tx(command::NULL, &[], false), rx(0x0000, [0; 4])),
    ]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    adc.unlock().unwrap();
    assert_eq!(
        adc.lock(),
        Err(Error::BadResponse {
            command: 0x0555,
            expected: 0x0555,
            received: 0
        })
    );
    spi.done();
}

#[test]
fn configure_checks_id_then_writes_mode_clock_gain_in_one_wreg() {
    let config = Config {
        osr: Osr::Osr4096,
        power: PowerMode::HighResolution,
        gains: [Gain::X2, Gain::X2, Gain::X1, Gain::X1],
        input_crc: false,
    };
    let exp = script(vec![
        frame(tx(0xA000, &[], false), rx(STATUS_IDLE, [0; 4])),
        frame(tx(command::NULL, &[], false), rx(0x2410, [0; 4])),
        frame(
            tx(0x6102, &[0x0110, 0x0F16, 0x0011], false),
            rx(STATUS_IDLE, [0; 4]),
        ),
        frame(tx(command::NULL, &[], false), rx(0x4102, [0; 4])),
        frame(
            tx(command::NULL, &[], false),
            rx(0x010F, [0x40_0000, 0x40_0000, 0x40_0000, 0]),
        ),
    ]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    adc.configure(&config).unwrap();
    assert_eq!(adc.gains(), config.gains);
    // Scaling follows the gain: half of full scale is 0.3 V at gain 2.
    let scales = [ChannelScale {
        volts_per_unit: 0.1,
        offset_volts: 0.0,
    }; 4];
    let (_, si) = adc.read_si(&scales).unwrap();
    assert!((si[0] - 3.0).abs() < 1e-5, "{si:?}");
    assert!((si[2] - 6.0).abs() < 1e-5, "{si:?}");
    spi.done();
}

#[test]
fn configure_rejects_a_device_that_is_not_4_channel() {
    let exp = script(vec![
        frame(tx(0xA000, &[], false), rx(STATUS_IDLE, [0; 4])),
        frame(tx(command::NULL, &[], false), rx(0x2810, [0; 4])),
    ]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    assert_eq!(
        adc.configure(&Config::default()),
        Err(Error::BadId { id: 0x2810 })
    );
    spi.done();
}

#[test]
fn input_crc_is_appended_after_enabling_it() {
    let config = Config {
        input_crc: true,
        ..Config::default()
    };
    let mode = config.mode_register();
    assert_eq!(mode, 0x1110);
    let exp = script(vec![
        frame(tx(0xA000, &[], false), rx(STATUS_IDLE, [0; 4])),
        frame(tx(command::NULL, &[], false), rx(0x2410, [0; 4])),
        // The WREG that enables RX_CRC_EN is itself sent without CRC.
        frame(
            tx(0x6102, &[mode, 0x0F0E, 0x0000], false),
            rx(STATUS_IDLE, [0; 4]),
        ),
        // From now on every command carries its CRC word.
        frame(tx(command::NULL, &[], true), rx(0x4102, [0; 4])),
        frame(tx(command::NULL, &[], true), rx(0x1100, [0; 4])),
    ]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    adc.configure(&config).unwrap();
    assert_eq!(adc.read_frame(), Err(Error::InputCrc { status: 0x1100 }));
    spi.done();
}

#[test]
fn switching_to_32_bit_words_lengthens_the_frame() {
    // MODE with WLENGTH = 10b (32-bit, zero-padded codes).
    let mode = 0x0210;
    let mut ack = Vec::new();
    ack.extend_from_slice(&[0x41, 0x00, 0, 0]);
    ack.extend_from_slice(&[0x12, 0x34, 0x56, 0]);
    ack.extend_from_slice(&[0xFF, 0xFF, 0xFE, 0]);
    ack.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 0]);
    let c = crc_reference(&ack);
    ack.extend_from_slice(&[(c >> 8) as u8, c as u8, 0, 0]);
    let mut null32 = vec![0u8; 24];
    null32[0] = 0;
    let exp = script(vec![
        frame(tx(0x6100, &[mode], false), rx(STATUS_IDLE, [0; 4])),
        frame(null32, ack),
    ]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    adc.write_register(reg::MODE, mode).unwrap();
    assert_eq!(adc.word_length(), WordLength::Bits32ZeroPad);
    spi.done();
}

#[test]
fn long_wreg_grows_the_frame() {
    let values = [1u16, 2, 3, 4, 5, 6];
    let exp = script(vec![
        frame(tx(0x6485, &values, false), rx_len(STATUS_IDLE, [0; 4], 21)),
        frame(tx(command::NULL, &[], false), rx(0x4485, [0; 4])),
    ]);
    let mut spi = Mock::new(&exp);
    let mut adc = Ads131m04::new(spi.clone());
    adc.write_registers(reg::ch_cfg(0), &values).unwrap();
    assert_eq!(
        adc.write_registers(0x3F, &[1, 2]),
        Err(Error::InvalidArgument)
    );
    assert_eq!(adc.write_registers(0x10, &[]), Err(Error::InvalidArgument));
    spi.done();
}

/// An SPI device that always fails.
struct Broken;
impl ErrorType for Broken {
    type Error = ErrorKind;
}
impl SpiDevice for Broken {
    fn transaction(&mut self, _: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        Err(ErrorKind::ModeFault)
    }
}

#[test]
fn spi_errors_are_passed_through() {
    let mut adc = Ads131m04::new(Broken);
    assert_eq!(adc.read_frame(), Err(Error::Spi(ErrorKind::ModeFault)));
    assert_eq!(
        adc.reset(&mut NoopDelay::new()),
        Err(Error::Spi(ErrorKind::ModeFault))
    );
}
