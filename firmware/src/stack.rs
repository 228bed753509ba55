//! Stack high-water mark by painting: fill the free stack below the current stack pointer with
//! a pattern at start-up, later find the lowest word that no longer holds it. `elf_sizes` on the
//! host counts only static RAM (`.data` + `.bss`); this gives the stack on top of it.

use core::ptr::{addr_of, read_volatile, write_volatile};

const PATTERN: u32 = 0x5AA5_C33C;
/// Most bytes painted (keeps start-up short on the 4 MiB QEMU RAM).
const MAX_PAINT: usize = 64 * 1024;

extern "C" {
    static _stack_start: u32;
    static _stack_end: u32;
}

/// The painted region `[lo, hi)`.
#[derive(Debug, Clone, Copy)]
pub struct Painted {
    lo: usize,
    hi: usize,
}

/// Paint the free stack (up to [`MAX_PAINT`] bytes below the current stack pointer).
#[inline(never)]
pub fn paint() -> Painted {
    let sp = cortex_m::register::msp::read() as usize;
    // Linker symbol of cortex-m-rt; only its address is used.
    let end = addr_of!(_stack_end) as usize;
    let hi = (sp - 64) & !3;
    let lo = hi.saturating_sub(MAX_PAINT).max((end + 3) & !3);
    let mut a = lo;
    while a < hi {
        // SAFETY: [lo, hi) is free stack below this function's frame, above .bss/.uninit.
        unsafe { write_volatile(a as *mut u32, PATTERN) };
        a += 4;
    }
    Painted { lo, hi }
}

/// Bytes of stack used so far (from `_stack_start` down to the lowest overwritten word), and
/// whether the whole painted region was overwritten (then the figure is a lower bound).
pub fn used(p: &Painted) -> (u32, bool) {
    // Linker symbol, address only.
    let start = addr_of!(_stack_start) as usize;
    let mut a = p.lo;
    // SAFETY: reads of the painted region.
    while a < p.hi && unsafe { read_volatile(a as *const u32) } == PATTERN {
        a += 4;
    }
    ((start - a) as u32, a == p.lo)
}

/// Emit `stack used_bytes=.. painted_bytes=.. overflowed_paint=..`.
pub fn report(p: &Painted) {
    let (used, all) = used(p);
    defmt::info!(
        "stack used_bytes={=u32} painted_bytes={=u32} overflowed_paint={=bool}",
        used,
        (p.hi - p.lo) as u32,
        all
    );
}
