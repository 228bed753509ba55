//! `host-sim trace`: the CSV trace `t_s,top_accel_m_s2` of ü1 at a scene's samples by one method
//! ([`crate::methods::trace`]), to a file or standard output.

use super::load;
use crate::methods::{self, Precision, TraceMethod, TraceOptions};
use crate::scene::Scene;
use anyhow::{Context, Result};
use std::io::{BufWriter, Write};
use std::path::PathBuf;

/// Arguments of `trace`.
#[derive(clap::Args, Debug)]
pub struct TraceArgs {
    /// Scene file (TOML), or `default` for the built-in default scene.
    pub scene: PathBuf,
    /// The method.
    #[arg(long, value_enum)]
    pub method: TraceMethod,
    /// Precision of rdm-recursion (the other methods run in f64).
    #[arg(long, value_enum, default_value = "f64")]
    pub precision: Precision,
    /// Harmonics of tfm/rfm (default: the converged count of the peak).
    #[arg(long)]
    pub harmonics: Option<u32>,
    /// Output every K-th sample (k = 0, K, 2K, …); the recursion still runs over every sample.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub stride: u64,
    /// Output file (default: standard output).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// `host-sim trace`.
pub fn command(args: TraceArgs) -> Result<()> {
    let scene = load(&args.scene)?;
    let opts = TraceOptions {
        method: args.method,
        precision: args.precision,
        harmonics: args.harmonics,
        stride: args.stride,
    };
    match args.out {
        Some(path) => {
            let file = std::fs::File::create(&path)
                .with_context(|| format!("cannot create {}", path.display()))?;
            write_trace(&scene, opts, BufWriter::new(file))
                .with_context(|| format!("trace to {}", path.display()))
        }
        None => write_trace(&scene, opts, BufWriter::new(std::io::stdout().lock())),
    }
}

/// Stream the trace through `w`; flush at the end and on error.
fn write_trace<W: Write>(scene: &Scene, opts: TraceOptions, mut w: BufWriter<W>) -> Result<()> {
    let result = methods::trace(scene, opts, &mut w);
    let flushed = w.flush().context("writing the trace");
    result?;
    flushed
}
