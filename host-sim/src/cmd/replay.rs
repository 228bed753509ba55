//! `host-sim replay`: the command-line glue of [`crate::replay`]: arguments, Ctrl-C, the progress
//! bar and the summary or JSON report.

use super::print_report;
use crate::plot;
use crate::replay::{self, ReplayOptions};
use crate::scene::ReplayScene;
use anyhow::{bail, Result};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Arguments of `replay`.
#[derive(clap::Args, Debug)]
#[allow(rustdoc::invalid_html_tags)] // `<scene-stem>` is help text, not HTML
pub struct ReplayArgs {
    /// Scene file (TOML) with a `[recording]` table.
    pub scene: PathBuf,
    /// CSV output (default: <scene-stem>.replay.csv next to the scene file).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Draw the figure to FILE.svg or FILE.png: measured and predicted top acceleration, the
    /// slip and the detected events.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Start of the plot window (s, the recording's time; default: its start).
    #[arg(long, value_name = "S")]
    pub plot_from: Option<f64>,
    /// Length of the plot window (s; default: the whole recording).
    #[arg(long, value_name = "S")]
    pub plot_window: Option<f64>,
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
    if let Some(p) = &args.plot {
        plot::format_of(p)?;
    }
    let len = args.plot_window.unwrap_or(f64::INFINITY);
    if args.plot_from.is_some_and(|f| !f.is_finite()) || len.is_nan() || len <= 0.0 {
        bail!("--plot-from / --plot-window is out of range");
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| replay::default_out_path(&scene));
    let mut opts = ReplayOptions::new(out.display().to_string());
    opts.model = args.model;
    opts.mode = args.mode;
    if args.plot.is_some() {
        opts.plot_window = Some((args.plot_from, len));
    }
    // Ctrl-C: stop cleanly at the next flush (as `run`). Failing to install the handler only
    // loses that.
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::Relaxed));
    // A progress bar over the file's bytes on a terminal (hidden otherwise).
    let bar = if std::io::stderr().is_terminal() {
        let pb = ProgressBar::new(0);
        if let Ok(style) = ProgressStyle::with_template(
            "{msg} [{bar:40}] {bytes}/{total_bytes} ({bytes_per_sec}, {eta})",
        ) {
            pb.set_style(style.progress_chars("=> "));
        }
        pb.set_message("replay");
        pb
    } else {
        ProgressBar::hidden()
    };
    let progress = |pos: u64, size: u64| {
        bar.set_length(size);
        bar.set_position(pos);
    };
    let outcome = replay::replay_to_file(&scene, &out, &opts, &STOP, &progress);
    bar.finish_and_clear();
    let outcome = outcome?;
    let mut report = outcome.report;
    if let (Some(path), Some(data)) = (&args.plot, &outcome.plot) {
        plot::render(data, path)?;
    }
    report.runtime_s = start.elapsed().as_secs_f64();
    print_report(
        &report,
        args.json,
        replay::summary_text,
        args.plot.as_deref(),
    )
}
