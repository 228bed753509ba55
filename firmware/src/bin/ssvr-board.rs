//! SSVR estimator firmware, Nucleo-F446RE image (feature `board`): ADS131M04 on SPI1, TIM2
//! sample interrupt, defmt over RTT (`ssvr_firmware::board`).
//! Build: `cargo build --release --no-default-features --features board`.
#![no_std]
#![no_main]

use ssvr_firmware as _;

#[cortex_m_rt::entry]
fn main() -> ! {
    ssvr_firmware::board::run()
}
