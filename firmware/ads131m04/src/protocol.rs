//! The device's SPI protocol constants: commands, responses and register addresses and fields
//! (SBAS788 §8.5, §8.6).

/// SPI commands (16-bit, SBAS788 table 8-11).
pub mod command {
    /// No operation; the response is the `STATUS` register.
    pub const NULL: u16 = 0x0000;
    /// Software reset.
    pub const RESET: u16 = 0x0011;
    /// Enter standby.
    pub const STANDBY: u16 = 0x0022;
    /// Leave standby.
    pub const WAKEUP: u16 = 0x0033;
    /// Lock the interface (only `NULL`, `RREG`, `UNLOCK` accepted).
    pub const LOCK: u16 = 0x0555;
    /// Unlock the interface.
    pub const UNLOCK: u16 = 0x0655;

    /// `RREG`: `101a aaaa annn nnnn`, read `count` (1..=128) registers from `addr` (6 bits).
    pub const fn rreg(addr: u8, count: u8) -> u16 {
        0xA000 | (((addr as u16) & 0x3F) << 7) | ((count.wrapping_sub(1) as u16) & 0x7F)
    }

    /// `WREG`: `011a aaaa annn nnnn`, write `count` (1..=128) registers from `addr` (6 bits).
    pub const fn wreg(addr: u8, count: u8) -> u16 {
        0x6000 | (((addr as u16) & 0x3F) << 7) | ((count.wrapping_sub(1) as u16) & 0x7F)
    }
}

/// Command responses (SBAS788 table 8-11).
pub mod response {
    /// Response to `RESET` on a 4-channel device (`1111 1111 0010 0100`, "FF" + channel count).
    pub const RESET_OK: u16 = 0xFF24;
    /// Response to `STANDBY`.
    pub const STANDBY_OK: u16 = 0x0022;
    /// Response to `WAKEUP`.
    pub const WAKEUP_OK: u16 = 0x0033;
    /// Response to `LOCK`.
    pub const LOCK_OK: u16 = 0x0555;
    /// Response to `UNLOCK`.
    pub const UNLOCK_OK: u16 = 0x0655;

    /// Response to `WREG`: `010a aaaa ammm mmmm` (m = registers written − 1).
    pub const fn wreg_ack(addr: u8, count: u8) -> u16 {
        0x4000 | (((addr as u16) & 0x3F) << 7) | ((count.wrapping_sub(1) as u16) & 0x7F)
    }
}

/// Register addresses (SBAS788 §8.6).
pub mod reg {
    /// `ID` (read-only): bits 11:8 = channel count.
    pub const ID: u8 = 0x00;
    /// `STATUS` (read-only), see [`crate::Status`].
    pub const STATUS: u8 = 0x01;
    /// `MODE`: CRC, word length, timeout, DRDY behaviour. Reset 0x0510.
    pub const MODE: u8 = 0x02;
    /// `CLOCK`: channel enables, OSR, power mode. Reset 0x0F0E.
    pub const CLOCK: u8 = 0x03;
    /// `GAIN1`: PGA gains of channels 0..3. Reset 0x0000.
    pub const GAIN1: u8 = 0x04;
    /// `CFG`: global chop, current detect. Reset 0x0600.
    pub const CFG: u8 = 0x06;
    /// `THRSHLD_MSB`.
    pub const THRSHLD_MSB: u8 = 0x07;
    /// `THRSHLD_LSB`.
    pub const THRSHLD_LSB: u8 = 0x08;
    /// `CHn_CFG` of channel `ch` (0..3); `CHn_OCAL_MSB/LSB`, `CHn_GCAL_MSB/LSB` follow it.
    pub const fn ch_cfg(ch: u8) -> u8 {
        0x09 + 5 * ch
    }
    /// `REGMAP_CRC` (read-only).
    pub const REGMAP_CRC: u8 = 0x3E;

    /// `MODE` reset value.
    pub const MODE_RESET_VALUE: u16 = 0x0510;
    /// `MODE.REG_CRC_EN`.
    pub const MODE_REG_CRC_EN: u16 = 1 << 13;
    /// `MODE.RX_CRC_EN`: the device checks a CRC word after the input command/data.
    pub const MODE_RX_CRC_EN: u16 = 1 << 12;
    /// `MODE.CRC_TYPE`: 0 = CCITT, 1 = ANSI.
    pub const MODE_CRC_TYPE_ANSI: u16 = 1 << 11;
    /// `MODE.RESET`: set by a reset, write 0 to clear.
    pub const MODE_RESET: u16 = 1 << 10;
    /// `MODE.WLENGTH` field (bits 9:8).
    pub const MODE_WLENGTH_SHIFT: u16 = 8;
    /// `MODE.TIMEOUT`: SPI timeout enabled.
    pub const MODE_TIMEOUT: u16 = 1 << 4;
    /// `CLOCK` reset value.
    pub const CLOCK_RESET_VALUE: u16 = 0x0F0E;
}
