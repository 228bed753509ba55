//! `host-sim qemu`: the command-line glue of [`crate::qemu::command`] (the firmware's QEMU
//! image on the scene's simulated sensor log, against the host and the closed form).

use anyhow::Result;
use std::path::PathBuf;

/// Arguments of `qemu`.
#[derive(clap::Args, Debug)]
pub struct QemuArgs {
    /// Scene file (TOML); default: the built-in default scene.
    pub scene: Option<PathBuf>,
    /// The estimator model built into the firmware (default: the smallest that serves the
    /// scene, chosen from the simulated run like `run`: fixed-base, rectangular or
    /// stick-slip).
    #[arg(long, value_parser = crate::model::parse)]
    pub model: Option<crate::model::Model>,
    /// What the model may read: `fuse` (every channel, default) or `predict` (never the top
    /// accelerometer); the firmware is built for it (`SSVR_MODE`).
    #[arg(long, value_parser = crate::model::parse_mode, default_value = "fuse")]
    pub mode: ssvr_proto::Mode,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Also write the raw defmt stream QEMU produced (its stdout, before decoding) to FILE, for
    /// `host-sim monitor --elf <the report's elf> --input FILE`.
    #[arg(long, value_name = "FILE")]
    pub stream_out: Option<PathBuf>,
}

/// `host-sim qemu`.
pub fn command(args: QemuArgs) -> Result<()> {
    crate::qemu::command(
        args.scene.as_deref(),
        args.json,
        args.model,
        args.mode,
        args.stream_out.as_deref(),
    )
}
