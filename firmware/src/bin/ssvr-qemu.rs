//! SSVR estimator firmware, QEMU `mps2-an386` image (feature `qemu`, the default).
//!
//! Replays a binary sensor log (`LOG_FORMAT.md`) read over semihosting, streams defmt over
//! semihosting, measures the estimator's instruction counts with SysTick under
//! `-icount shift=0`, and exits with a semihosting status. Build: `cargo build --release`.
#![no_std]
#![no_main]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "../app/mod.rs"]
mod app;

#[cortex_m_rt::entry]
fn main() -> ! {
    app::qemu::run()
}
