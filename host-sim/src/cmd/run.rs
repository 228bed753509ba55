//! `host-sim run` (also `host-sim` with no command): the command-line glue of [`crate::run`]:
//! arguments, Ctrl-C, the optional figure ([`crate::plot::run`]) and the summary or JSON report.

use super::{load, print_report};
use crate::plot;
use crate::run::{self, RunOptions, StickPolicy};
use crate::scene::Scene;
use anyhow::{bail, Result};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Arguments of `run`.
#[derive(clap::Args, Debug)]
#[allow(rustdoc::invalid_html_tags)] // `<scene-stem>` is help text, not HTML
pub struct RunArgs {
    /// Scene file (TOML), or `default` (also when omitted) for the built-in default scene.
    pub scene: Option<PathBuf>,
    /// CSV output (default: <scene-stem>.run.csv next to the scene file, or default.run.csv in the
    /// working directory for the built-in scene).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Draw the figure to FILE.svg or FILE.png.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Length of the plotted window from --plot-from (s); e.g. 1e9 for the whole run.
    #[arg(long, value_name = "S", default_value_t = run::DEFAULT_PLOT_WINDOW_S)]
    pub plot_window: f64,
    /// Start of the plot window (s).
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    pub plot_from: f64,
    /// What a detected stick does to the rectangular model: keep the last friction level, or push 0.
    #[arg(long, value_enum, default_value = "keep")]
    pub on_stick: StickPolicy,
    /// The estimator model (default: the smallest that serves the scene, chosen from the
    /// simulated run: fixed-base, rectangular or stick-slip).
    #[arg(long, value_parser = crate::model::parse)]
    pub model: Option<crate::model::Model>,
    /// What the model may read: `fuse` (every channel: the best estimate) or `predict` (never the
    /// top accelerometer: the model's own prediction, to show beside the measured one).
    #[arg(long, value_parser = crate::model::parse_mode, default_value = "fuse")]
    pub mode: ssvr_proto::Mode,
    /// Half-width of the window matching detected to true events (ms).
    #[arg(long, value_name = "MS", default_value_t = 1e3 * run::DEFAULT_MATCH_TOLERANCE_S)]
    pub match_tolerance_ms: f64,
}

impl Default for RunArgs {
    /// `host-sim run` with no arguments (the clap defaults).
    fn default() -> Self {
        Self {
            scene: None,
            out: None,
            json: false,
            plot: None,
            plot_window: run::DEFAULT_PLOT_WINDOW_S,
            plot_from: 0.0,
            on_stick: StickPolicy::Keep,
            model: None,
            mode: ssvr_proto::Mode::Fuse,
            match_tolerance_ms: 1e3 * run::DEFAULT_MATCH_TOLERANCE_S,
        }
    }
}

/// Set by Ctrl-C: `run` stops at the next flush and keeps the rows written so far.
static STOP: AtomicBool = AtomicBool::new(false);

/// `host-sim run`.
pub fn command(args: RunArgs) -> Result<()> {
    let start = Instant::now();
    let scene = match &args.scene {
        Some(p) => load(p)?,
        None => Scene::default_scene(),
    };
    run::check_runnable(&scene)?;
    if let Some(p) = &args.plot {
        plot::format_of(p)?;
    }
    let finite = |name: &str, v: f64, ok: bool| -> Result<()> {
        if v.is_finite() && ok {
            Ok(())
        } else {
            bail!("{name} {v} is out of range")
        }
    };
    finite(
        "--match-tolerance-ms",
        args.match_tolerance_ms,
        args.match_tolerance_ms > 0.0,
    )?;
    finite("--plot-from", args.plot_from, args.plot_from >= 0.0)?;
    finite("--plot-window", args.plot_window, args.plot_window > 0.0)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| run::default_out_path(&scene));
    let mut opts = RunOptions::new(out.display().to_string());
    opts.match_tolerance_s = args.match_tolerance_ms / 1e3;
    opts.on_stick = args.on_stick;
    opts.model = args.model;
    opts.mode = args.mode;
    if args.plot.is_some() {
        opts.plot_window = Some((args.plot_from, args.plot_from + args.plot_window));
    }
    // Ctrl-C: stop cleanly (a second Ctrl-C while stopping is ignored; the run stops within a
    // few thousand samples). Failing to install the handler only loses that.
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::Relaxed));
    let outcome = run::run_to_file(&scene, &out, &opts, &STOP)?;
    let mut report = outcome.report;
    if let (Some(path), Some(data)) = (&args.plot, &outcome.plot) {
        plot::render(data, path)?;
    }
    report.runtime_s = start.elapsed().as_secs_f64();
    print_report(&report, args.json, run::summary_text, args.plot.as_deref())
}
