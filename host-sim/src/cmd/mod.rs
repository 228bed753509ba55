//! The `host-sim` command line: the commands ([`Cli`], parsed by clap) and one module per command
//! with its arguments and handler.
//!
//! * [`replay`]: a recorded test through the same pipeline; [`monitor`]: the firmware's live
//!   defmt stream decoded into the same CSV.
//! * [`run`]: the main job (also `host-sim` with no command); [`qemu`]: the firmware under QEMU.
//! * [`peak`], [`trace`], [`check`]: the methods on one scene ([`crate::methods`]).
//! * [`bench`](mod@bench): speed against error of every method; [`reproduce`]: the paper's
//!   results.

pub mod bench;
pub mod check;
pub mod monitor;
pub mod peak;
pub mod qemu;
pub mod replay;
pub mod reproduce;
pub mod robustness;
pub mod run;
pub mod trace;

use crate::scene::Scene;
use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use std::io::Write;
use std::path::Path;

/// Controller-side estimator of base-sliding isolation shake-table tests: host simulator and harness.
#[derive(Parser, Debug)]
#[command(name = "host-sim", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// The main job (the default command): simulate the exact stick-slip truth, measure it, detect
    /// the friction reversals in the measured slip and predict ü1 with the firmware's f32
    /// estimator, sample by sample; stream a CSV row per sample and print a summary.
    Run(run::RunArgs),
    /// Replay a recorded test (a scene with a [recording]: a CSV of the measured channels)
    /// through the controller's pipeline, sample by sample; stream a CSV row per sample with the
    /// predicted ü1 and the detected events, and print a summary.
    Replay(replay::ReplayArgs),
    /// Decode the firmware's raw defmt stream (probe-rs RTT, a serial dump, QEMU's stdout;
    /// stdin by default) with the ELF's table and write replay's CSV as the frames arrive, with
    /// a live summary on a terminal; damaged or lost frames are reported and skipped.
    Monitor(monitor::MonitorArgs),
    /// Steady-state peak of |ü1| of a harmonic scene by the trapezoid or rectangular Fourier method.
    Peak(peak::PeakArgs),
    /// CSV trace `t_s,top_accel_m_s2` of the top-mass acceleration ü1 at the scene's samples.
    Trace(trace::TraceArgs),
    /// Run the estimator (the recursion) over every sample and compare it with the closed form.
    Check(check::CheckArgs),
    /// Run the firmware's QEMU image (built for the scene and the estimator model) on the
    /// scene's simulated sensor log and compare every prediction with the host (same f32 code)
    /// and a full-precision reference; instruction counts and image sizes. Fails if the firmware
    /// differs from the host.
    Qemu(qemu::QemuArgs),
    /// Speed against error of every method (recursion, closed form, truncated closed form, RFM,
    /// TFM, truth) on three fixed scenes: a markdown table, bench.json/bench.md and Pareto plots.
    Bench(bench::BenchArgs),
    /// Regenerate the paper's results (Table 2, Figs 6, 9, 10, sliding response spectra) as
    /// figures and a report.md, sweeps in parallel.
    Reproduce(reproduce::ReproduceArgs),
    /// The robustness scorecard: `run` on perturbed copies of three scenes (the prior told off,
    /// accelerometer offsets and gains, dropped frames, a rest before the input), in both modes:
    /// error against perturbation, robustness.json/.md/.png.
    Robustness(robustness::RobustnessArgs),
}

impl Cli {
    /// Run the command (`run` with its defaults when none was given).
    pub fn run(self) -> Result<()> {
        match self.command {
            None => run::command(run::RunArgs::default()),
            Some(Command::Run(args)) => run::command(args),
            Some(Command::Replay(args)) => replay::command(args),
            Some(Command::Monitor(args)) => monitor::command(args),
            Some(Command::Peak(args)) => peak::command(args),
            Some(Command::Trace(args)) => trace::command(args),
            Some(Command::Check(args)) => check::command(args),
            Some(Command::Qemu(args)) => qemu::command(args),
            Some(Command::Bench(args)) => bench::command(args),
            Some(Command::Reproduce(args)) => reproduce::command(args),
            Some(Command::Robustness(args)) => robustness::command(args),
        }
    }
}

/// Load a scene; `default` (when no such file exists) is the built-in default.
fn load(path: &Path) -> Result<Scene> {
    if path == Path::new("default") && !path.exists() {
        return Ok(Scene::default_scene());
    }
    Ok(Scene::load(path)?)
}

/// Print `value` as pretty JSON on standard output.
fn print_json<T: serde::Serialize>(value: &T) -> Result<()> {
    let s = serde_json::to_string_pretty(value).context("serialising the report")?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{s}")
        .and_then(|()| out.flush())
        .context("writing the report")
}

/// The end of a command that writes a report: `--json` prints it, else its summary text (with
/// the plot's path, when one was drawn) goes to standard output.
fn print_report<T: serde::Serialize>(
    report: &T,
    json: bool,
    summary: impl FnOnce(&T) -> String,
    plot: Option<&std::path::Path>,
) -> Result<()> {
    if json {
        return print_json(report);
    }
    let mut text = summary(report);
    if let Some(p) = plot {
        text += &format!("  plot: {}\n", p.display());
    }
    let mut o = std::io::stdout().lock();
    o.write_all(text.as_bytes())
        .and_then(|()| o.flush())
        .context("writing the summary")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `host-sim` with no command runs `run` with exactly the defaults of `host-sim run`.
    #[test]
    fn run_args_default_matches_the_cli_defaults() {
        let cli = Cli::try_parse_from(["host-sim", "run"]).unwrap();
        let Some(Command::Run(args)) = cli.command else {
            panic!("not a run command");
        };
        assert_eq!(
            format!("{args:?}"),
            format!("{:?}", run::RunArgs::default())
        );
    }
}
