//! The firmware application, shared by both images (each binary includes this module with
//! `#[path]`; the cargo feature decides which image module is compiled).
//!
//! Per sample: read the four channels, run the f32 estimator, queue a frame (heapless SPSC) for
//! the streaming loop, which emits one defmt `sample` message per frame. Invalid or missing
//! samples are flagged and the estimator still updates, to keep time.

#[cfg(all(feature = "qemu", feature = "board"))]
compile_error!(
    "features `qemu` and `board` are exclusive: use `--no-default-features --features board`"
);
#[cfg(not(any(feature = "qemu", feature = "board")))]
compile_error!("select an image: feature `qemu` (default) or `board`");

pub mod bench;
pub mod pipeline;
pub mod stack;

#[cfg(feature = "qemu")]
pub mod qemu;
#[cfg(feature = "qemu")]
pub mod sensor_log;

#[cfg(all(feature = "board", not(feature = "qemu")))]
pub mod board;
