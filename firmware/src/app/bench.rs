//! Cost of the estimator measured with SysTick on the core clock.
//!
//! Under QEMU with `-icount shift=0` every executed instruction advances virtual time by exactly
//! 1 ns and the mps2-an386 core clock is 25 MHz, so SysTick counts one tick per 40 executed
//! instructions, deterministically. [`calibrate`] measures that ratio instead of assuming it: it
//! times two runs of a hand-written loop of known length (10 instructions per iteration) and
//! takes the difference, which cancels the fixed overhead. On the board the same code counts
//! core clock cycles (the calibration then reports cycles per instruction of that loop).
//!
//! Messages (parsed by host-sim's `qemu_runner`):
//! * `icount calibration instructions=.. ticks=..`
//! * `icount raw updates=.. update_ticks=.. loop_ticks=.. reversals=.. reversal_ticks=.. reversal_errors=..`
//! * `icount result instructions_per_tick=.. instructions_per_sample=.. instructions_per_reversal=..`

use core::hint::black_box;
use core::sync::atomic::{compiler_fence, Ordering};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use ssvr_core::duhamel_recursion::Estimator32;

/// Steady-state updates timed in one block.
pub const UPDATES: u32 = 10_000;
/// Samples with a reversal timed in one block.
pub const REVERSALS: u32 = 1_000;
/// Instructions per iteration of [`spin`].
const SPIN_INSTRUCTIONS: u32 = 10;
/// Iterations of the short calibration run (the long one is twice as long).
const SPIN_ITERS: u32 = 100_000;

/// A free-running 24-bit SysTick on the core clock.
pub struct Ticks {
    _syst: SYST,
}

impl Ticks {
    /// Start SysTick counting down from 2^24 − 1 on the core clock, no interrupt.
    pub fn new(mut syst: SYST) -> Self {
        syst.disable_interrupt();
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        syst.enable_counter();
        Self { _syst: syst }
    }

    /// Ticks elapsed while running `f` (valid below 2^24 ticks).
    #[inline(never)]
    pub fn time<F: FnOnce()>(&mut self, f: F) -> u32 {
        let start = SYST::get_current();
        compiler_fence(Ordering::SeqCst);
        f();
        compiler_fence(Ordering::SeqCst);
        let end = SYST::get_current();
        start.wrapping_sub(end) & 0x00FF_FFFF
    }
}

/// Exactly `SPIN_INSTRUCTIONS * iters` instructions (8 nops, subs, bne per iteration).
#[inline(never)]
fn spin(iters: u32) {
    if iters == 0 {
        return;
    }
    // SAFETY: a register-only countdown loop, no memory or stack access.
    unsafe {
        core::arch::asm!(
            "2:",
            ".rept 8",
            "nop",
            ".endr",
            "subs {n}, {n}, #1",
            "bne 2b",
            n = inout(reg) iters => _,
            options(nomem, nostack),
        );
    }
}

/// Ticks per `SPIN_INSTRUCTIONS * SPIN_ITERS` instructions; emits the calibration message.
pub fn calibrate(t: &mut Ticks) -> (u32, u32) {
    let short = t.time(|| spin(SPIN_ITERS));
    let long = t.time(|| spin(2 * SPIN_ITERS));
    let instructions = SPIN_INSTRUCTIONS * SPIN_ITERS;
    let ticks = long.wrapping_sub(short);
    defmt::info!(
        "icount calibration instructions={=u32} ticks={=u32} short_ticks={=u32} long_ticks={=u32}",
        instructions,
        ticks,
        short,
        long
    );
    (instructions, ticks)
}

/// Time [`UPDATES`] steady-state `update()` calls and [`REVERSALS`] samples that each push a
/// reversal (alternating ±1, age 0.5 samples) before their update; emit raw ticks and the
/// derived instruction counts. `est` should be freshly built (it is run in the sliding state).
pub fn run(t: &mut Ticks, mut est: Estimator32) {
    let (cal_instr, cal_ticks) = calibrate(t);
    let ipt = if cal_ticks == 0 {
        0.0
    } else {
        cal_instr as f32 / cal_ticks as f32
    };

    // Enter the sliding state and let the response settle into its steady recursion.
    let mut errors: u32 = 0;
    if est.push_reversal(1.0, 0.0).is_err() {
        errors += 1;
    }
    for _ in 0..1000 {
        black_box(est.update());
    }

    let loop_ticks = t.time(|| {
        for i in 0..UPDATES {
            black_box(i);
        }
    });
    let update_ticks = t.time(|| {
        for _ in 0..UPDATES {
            black_box(black_box(&mut est).update());
        }
    });
    let mut level = -1.0f32;
    let reversal_ticks = t.time(|| {
        for _ in 0..REVERSALS {
            let e = black_box(&mut est);
            if e.push_reversal(level, 0.5).is_err() {
                errors += 1;
            }
            black_box(e.update());
            level = -level;
        }
    });
    defmt::info!(
        "icount raw updates={=u32} update_ticks={=u32} loop_ticks={=u32} reversals={=u32} reversal_ticks={=u32} reversal_errors={=u32}",
        UPDATES,
        update_ticks,
        loop_ticks,
        REVERSALS,
        reversal_ticks,
        errors
    );
    // Loop overhead per iteration (empty loop with the same black_box), subtracted from both.
    let overhead = loop_ticks as f32 * ipt / UPDATES as f32;
    let per_sample = update_ticks as f32 * ipt / UPDATES as f32 - overhead;
    let per_reversal_sample = reversal_ticks as f32 * ipt / REVERSALS as f32 - overhead;
    defmt::info!(
        "icount result instructions_per_tick={=f32} instructions_per_sample={=f32} instructions_per_reversal={=f32} instructions_per_reversal_sample={=f32}",
        ipt,
        per_sample,
        per_reversal_sample - per_sample,
        per_reversal_sample
    );
}
