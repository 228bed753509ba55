//! One sample interval's phases packed in a byte: bits 0–1 the phase at the start, bits 2–3 the
//! number of switches (≤ [`MAX_SWITCHES`]), bits 4–5 and 6–7 the phase after the first and the
//! second switch; a phase is coded in two bits as its two's complement (0 → 0b00, +1 → 0b01,
//! −1 → 0b11).

use super::phase::Level;

/// Phase changes kept per sample interval.
pub const MAX_SWITCHES: usize = 2;

/// The code of a phase (−1, 0, 1).
#[inline(always)]
pub fn code(p: Level) -> u8 {
    (p as u8) & 3
}

/// The phase of a code.
#[inline(always)]
pub fn phase(c: u8) -> Level {
    ((c << 6) as i8) >> 6
}

/// A new interval: `start` throughout, no switch.
#[inline(always)]
pub fn new(start: Level) -> u8 {
    code(start)
}

/// Number of switches.
#[inline(always)]
pub fn switches(b: u8) -> usize {
    ((b >> 2) & 3) as usize
}

/// Phase at the start.
#[inline(always)]
pub fn start(b: u8) -> Level {
    phase(b & 3)
}

/// Phase after switch `j` (< `MAX_SWITCHES`).
#[inline(always)]
pub fn after(b: u8, j: usize) -> Level {
    phase((b >> (4 + 2 * j)) & 3)
}

/// Phase at the end.
pub fn end(b: u8) -> Level {
    match switches(b) {
        0 => start(b),
        n => after(b, n.min(MAX_SWITCHES) - 1),
    }
}

/// Add a switch to `phase` at fraction `f` (after the others); more than `MAX_SWITCHES`
/// inside one sample: the last one wins.
pub fn add<T: Copy>(b: &mut u8, fr: &mut [T; MAX_SWITCHES], f: T, phase: Level) {
    let n = switches(*b);
    let j = if n < MAX_SWITCHES {
        n
    } else {
        MAX_SWITCHES - 1
    };
    fr[j] = f;
    let shift = 4 + 2 * j;
    let count = (j + 1) as u8;
    *b = (*b & !(0x0C | (3 << shift))) | (count << 2) | (code(phase) << shift);
}
