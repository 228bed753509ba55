//! SSVR estimator firmware, QEMU `mps2-an386` image (feature `qemu`, the default): replays a
//! sensor log over semihosting (`ssvr_firmware::qemu`). Build: `cargo build --release`.
#![no_std]
#![no_main]

use ssvr_firmware as _;

#[cortex_m_rt::entry]
fn main() -> ! {
    ssvr_firmware::qemu::run()
}
