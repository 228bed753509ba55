//! The SSVR estimator firmware as a library; the two binaries (`src/bin/`) only call
//! [`qemu::run`] or [`board::run`].
//!
//! Per sample the image runs the shared pipeline step of `ssvr-proto` (flags → the model's
//! friction-event detector → events → the model's f32 prediction) and streams one frame per
//! sample with defmt. What the image runs is a [`plan`] made at build time from the scene in
//! `SSVR_SCENE` and the model in `SSVR_MODEL` by the same code the host uses (`ssvr-scene`,
//! `ssvr_proto::Plan`): the plan's words, its digest, and the model and detector types.
//!
//! * [`plan`]: the compiled-in plan and the pipeline built from it;
//! * [`stream`]: the queue between the sample side and the streaming loop;
//! * [`qemu`] (feature `qemu`): replay a sensor log over semihosting, then the benchmark;
//! * [`board`] (feature `board`): ADS131M04 on SPI1, TIM2 sample interrupt, RTT;
//! * [`bench`] (feature `bench`): instruction counts with SysTick;
//! * [`stack`]: the stack's high-water mark.
#![no_std]
#![deny(missing_docs)]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(all(feature = "qemu", feature = "board"))]
compile_error!(
    "features `qemu` and `board` are exclusive: use `--no-default-features --features board`"
);
#[cfg(not(any(feature = "qemu", feature = "board")))]
compile_error!("select an image: feature `qemu` (default) or `board`");

#[cfg(feature = "bench")]
pub mod bench;
#[cfg(all(feature = "board", not(feature = "qemu")))]
pub mod board;
pub mod plan;
#[cfg(feature = "qemu")]
pub mod qemu;
pub mod stack;
pub mod stream;
