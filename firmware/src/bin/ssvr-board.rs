//! SSVR estimator firmware, Nucleo-F446RE image (feature `board`).
//!
//! ADS131M04 on SPI1, TIM2 interrupt at the sample rate, defmt over RTT; structure, sample rate
//! and sensor scaling from a scene at build time (`SSVR_SCENE`).
//! Build: `cargo build --release --no-default-features --features board`.
#![no_std]
#![no_main]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "../app/mod.rs"]
mod app;

#[cortex_m_rt::entry]
fn main() -> ! {
    app::board::run()
}
