//! `host-sim monitor`: the command-line glue of [`crate::monitor`]: arguments, the input and
//! output files, the live line on a terminal, the final summary (stderr) and the plot.

use crate::monitor::{self, MonitorOptions, Note};
use crate::plot;
use crate::qemu::decode;
use anyhow::{bail, Context, Result};
use std::io::{IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// Arguments of `monitor`.
#[derive(clap::Args, Debug)]
pub struct MonitorArgs {
    /// The firmware image whose defmt stream is read (its interning table decodes it).
    #[arg(long, value_name = "ELF")]
    pub elf: PathBuf,
    /// The raw defmt stream: a file, or `-` for standard input (the default).
    #[arg(long, value_name = "FILE", default_value = "-")]
    pub input: PathBuf,
    /// CSV output (replay's columns); `-` or absent: standard output.
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,
    /// Draw measured and predicted top acceleration and the detected events to FILE.svg or
    /// FILE.png at the end (keeps 16 bytes per sample in memory).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// The sample rate (Hz) for `t_s`, instead of the firmware's `plan` message (needed when
    /// the stream starts after it).
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
}

/// Set by Ctrl-C: `monitor` stops after the next chunk read and keeps every row (flushed).
static STOP: AtomicBool = AtomicBool::new(false);

fn is_stdio(p: &Path) -> bool {
    p == Path::new("-")
}

/// `host-sim monitor`. Exit status 0 when the stream was read to its end, damage included (it
/// is reported on stderr); an error for unreadable files or an unknown rate.
pub fn command(args: MonitorArgs) -> Result<()> {
    if let Some(p) = &args.plot {
        plot::format_of(p)?;
    }
    if args.rate.is_some_and(|r| !r.is_finite() || r <= 0.0) {
        bail!("--rate must be a positive number of Hz");
    }
    let table = decode::table(&args.elf)?;
    let input: Box<dyn Read> = if is_stdio(&args.input) {
        Box::new(std::io::stdin().lock())
    } else {
        Box::new(
            std::fs::File::open(&args.input)
                .with_context(|| format!("cannot open the input {}", args.input.display()))?,
        )
    };
    let out_path = args.out.clone().filter(|p| !is_stdio(p));
    let output: Box<dyn Write> = match &out_path {
        None => Box::new(std::io::stdout().lock()),
        Some(p) => Box::new(
            std::fs::File::create(p)
                .with_context(|| format!("cannot create the output file {}", p.display()))?,
        ),
    };
    let opts = MonitorOptions {
        input_name: if is_stdio(&args.input) {
            "standard input".into()
        } else {
            args.input.display().to_string()
        },
        out_name: out_path.as_ref().map_or_else(
            || "standard output".to_string(),
            |p| p.display().to_string(),
        ),
        rate_hz: args.rate,
        plot: args.plot.is_some(),
    };
    // Ctrl-C: stop after the next chunk and flush (failing to install the handler only loses
    // that; a pipe's writer ending also ends the input).
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::Relaxed));
    let terminal = std::io::stderr().is_terminal();
    let mut live_shown = false;
    let mut note = |n: Note<'_>| {
        let mut err = std::io::stderr().lock();
        // Errors writing to stderr are not the monitor's to fail on.
        let _ = match n {
            Note::Live(r) if terminal => {
                live_shown = true;
                write!(err, "\r\x1b[2K{}", monitor::live_line(r))
            }
            Note::Live(_) => Ok(()),
            Note::Problem(text) => {
                let clear = if live_shown { "\r\x1b[2K" } else { "" };
                live_shown = false;
                writeln!(err, "{clear}host-sim monitor: {text}")
            }
        };
        let _ = err.flush();
    };
    let outcome = monitor::monitor(&table, input, output, &opts, &STOP, &mut note)?;
    let r = &outcome.report;
    let mut text = monitor::summary_text(r);
    if let (Some(path), Some(series), Some(rate)) = (&args.plot, &outcome.plot, r.rate_hz) {
        let name = args
            .elf
            .file_stem()
            .map_or_else(|| "firmware".into(), |s| s.to_string_lossy().into_owned());
        plot::render(&series.plot_data(rate, &name), path)?;
        text += &format!("  plot: {}\n", path.display());
    }
    let mut err = std::io::stderr().lock();
    let clear = if terminal { "\r\x1b[2K" } else { "" };
    let _ = write!(err, "{clear}{text}");
    Ok(())
}
