//! `host-sim replay`: the command-line glue of [`crate::replay`]: arguments, Ctrl-C, the progress
//! bar and the summary or JSON report.

use super::print_json;
use crate::replay::{self, ReplayOptions};
use crate::scene::ReplayScene;
use anyhow::{Context, Result};
use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Arguments of `replay`.
#[derive(clap::Args, Debug)]
#[allow(rustdoc::invalid_html_tags)] // `<scene-stem>` is help text, not HTML
pub struct ReplayArgs {
    /// Scene file (TOML) with a [recording].
    pub scene: PathBuf,
    /// CSV output (default: <scene-stem>.replay.csv next to the scene file).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// The estimator model (default: stick-slip with a base accelerometer column, else
    /// rectangular with a slip column, else fixed-base).
    #[arg(long, value_parser = crate::model::parse)]
    pub model: Option<crate::model::Model>,
    /// What the model may read: `fuse` (every channel) or `predict` (never the top
    /// accelerometer). Default: fuse with a top accelerometer column, else predict.
    #[arg(long, value_parser = crate::model::parse_mode)]
    pub mode: Option<ssvr_proto::Mode>,
}

/// Set by Ctrl-C: `replay` stops at the next flush and keeps the rows written so far.
static STOP: AtomicBool = AtomicBool::new(false);

/// `host-sim replay`.
pub fn command(args: ReplayArgs) -> Result<()> {
    let start = Instant::now();
    let scene = ReplayScene::load(&args.scene)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| replay::default_out_path(&scene));
    let mut opts = ReplayOptions::new(out.display().to_string());
    opts.model = args.model;
    opts.mode = args.mode;
    // Ctrl-C: stop cleanly at the next flush (as `run`). Failing to install the handler only
    // loses that.
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::Relaxed));
    let progress = |_: u64, _: u64| {};
    let outcome = replay::replay_to_file(&scene, &out, &opts, &STOP, &progress)?;
    let mut report = outcome.report;
    report.runtime_s = start.elapsed().as_secs_f64();
    if args.json {
        print_json(&report)
    } else {
        let text = replay::summary_text(&report);
        let mut o = std::io::stdout().lock();
        o.write_all(text.as_bytes())
            .and_then(|()| o.flush())
            .context("writing the summary")
    }
}
