//! `host-sim qemu`: the firmware under QEMU, checked against the host's run of the same
//! pipeline, a full-precision reference and the truth.
//!
//! * [`image`]: build the firmware's images for a scene and a model, run QEMU, size an ELF;
//! * [`log`]: a scene's sensor log (`ssvr_proto::log`);
//! * [`decode`]: the defmt stream decoded by type into messages and `ssvr_proto::Frame`s;
//! * [`icount`]: the instruction counts the image measures;
//! * [`check`]: the comparisons and the goals ([`check::QemuReport`]);
//! * [`reference`](mod@reference): the full-precision references of each model;
//! * [`report`]: printing and the command.

pub mod check;
pub mod decode;
pub mod goals;
pub mod icount;
pub mod image;
pub mod log;
pub mod reference;
pub mod report;

pub use check::{
    measure_instruction_counts, run_scene, run_scene_mode, run_scene_model, run_scene_stream,
    QemuReport,
};
pub use report::{command, print_report};
