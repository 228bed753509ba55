//! host-sim: the host-side simulator and harness.
//!
//! `host-sim` with no command runs `run` on the built-in default scene; see `host-sim --help`.

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use host_sim::methods::{self, PeakMethod, Precision, TraceMethod, TraceOptions};
use host_sim::plot;
use host_sim::run::{self, Interrupted, RunOptions, StickPolicy};
use host_sim::scene::{Input, Scene};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Controller-side estimator of base-sliding isolation shake-table tests: host simulator and harness.
#[derive(Parser, Debug)]
#[command(name = "host-sim", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// The main job (the default command): simulate the exact stick-slip truth, measure it, detect
    /// the friction reversals in the measured slip and predict ü1 with the firmware's f32
    /// estimator, sample by sample; stream a CSV row per sample and print a summary.
    Run(RunArgs),
    /// The old no-command summary: TFM/RFM peaks and the recursion against the closed form on the
    /// built-in default scene.
    Summary,
    /// Steady-state peak of |ü1| of a harmonic scene by the trapezoid or rectangular Fourier method.
    Peak {
        /// Scene file (TOML), or `default` for the built-in default scene.
        scene: PathBuf,
        /// tfm (trapezoid, eq 14-18) or rfm (rectangular, eq 20-22).
        #[arg(long, value_enum)]
        method: PeakMethod,
        /// Number of odd harmonics (default: doubled from 16 until the peak converges to 1e-6).
        #[arg(long)]
        harmonics: Option<u32>,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// CSV trace `t_s,top_accel_m_s2` of the top-mass acceleration ü1 at the scene's samples.
    Trace {
        /// Scene file (TOML), or `default` for the built-in default scene.
        scene: PathBuf,
        /// The method.
        #[arg(long, value_enum)]
        method: TraceMethod,
        /// Precision of rdm-recursion (the other methods run in f64).
        #[arg(long, value_enum, default_value = "f64")]
        precision: Precision,
        /// Harmonics of tfm/rfm (default: the converged count of the peak).
        #[arg(long)]
        harmonics: Option<u32>,
        /// Output every K-th sample (k = 0, K, 2K, …); the recursion still runs over every sample.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
        stride: u64,
        /// Output file (default: standard output).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Run the estimator (the recursion) over every sample and compare it with the closed form.
    Check {
        /// Scene file (TOML), or `default` for the built-in default scene.
        scene: PathBuf,
        /// Precision of the recursion.
        #[arg(long, value_enum, default_value = "f64")]
        precision: Precision,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Run the firmware's QEMU image (built for the scene and the estimator model) on the
    /// scene's simulated sensor log and compare every prediction with the host (same f32 code)
    /// and a full-precision reference; instruction counts and image sizes. Fails if the firmware
    /// differs from the host.
    Qemu {
        /// Scene file (TOML); default: the built-in default scene.
        scene: Option<PathBuf>,
        /// The estimator model built into the firmware (default: the smallest that serves the
        /// scene, chosen from the simulated run like `run`: fixed-base, rectangular or
        /// stick-slip).
        #[arg(long)]
        model: Option<host_sim::model::Model>,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Speed against error of every method (recursion, closed form, truncated closed form, RFM,
    /// TFM, truth) on three fixed scenes: a markdown table, bench.json/bench.md and Pareto plots.
    Bench {
        /// Shorter scenes and fewer repetitions (under a minute).
        #[arg(long)]
        quick: bool,
        /// Print the rows as JSON (`{"rows": [...]}`) instead of the markdown table.
        #[arg(long)]
        json: bool,
        /// Output folder of the figures, bench.json and bench.md.
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
    },
    /// Regenerate the paper's results (Table 2, Figs 6, 9, 10, sliding response spectra) as
    /// figures and a report.md, sweeps in parallel.
    Reproduce {
        /// Output folder.
        #[arg(long, default_value = "reproduce-out")]
        out: PathBuf,
        /// Fewer sweep points and shorter runs (for tests).
        #[arg(long)]
        quick: bool,
    },
}

/// Arguments of `run`.
#[derive(clap::Args, Debug)]
struct RunArgs {
    /// Scene file (TOML), or `default` (also when omitted) for the built-in default scene.
    scene: Option<PathBuf>,
    /// CSV output (default: <scene-stem>.run.csv next to the scene file, or default.run.csv in the
    /// working directory for the built-in scene).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
    /// Draw the figure to FILE.svg or FILE.png.
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Length of the plotted window from --plot-from (s); e.g. 1e9 for the whole run.
    #[arg(long, value_name = "S", default_value_t = host_sim::run::DEFAULT_PLOT_WINDOW_S)]
    plot_window: f64,
    /// Start of the plot window (s).
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    plot_from: f64,
    /// What a detected stick does to the rectangular model: keep the last friction level, or push 0.
    #[arg(long, value_enum, default_value = "keep")]
    on_stick: StickPolicy,
    /// The estimator model (default: the smallest that serves the scene, chosen from the
    /// simulated run: fixed-base, rectangular or stick-slip).
    #[arg(long)]
    model: Option<host_sim::model::Model>,
    /// Half-width of the window matching detected to true events (ms).
    #[arg(long, value_name = "MS", default_value_t = 1e3 * host_sim::run::DEFAULT_MATCH_TOLERANCE_S)]
    match_tolerance_ms: f64,
}

impl Default for RunArgs {
    /// `host-sim run` with no arguments (the clap defaults).
    fn default() -> Self {
        Self {
            scene: None,
            out: None,
            json: false,
            plot: None,
            plot_window: host_sim::run::DEFAULT_PLOT_WINDOW_S,
            plot_from: 0.0,
            on_stick: StickPolicy::Keep,
            model: None,
            match_tolerance_ms: 1e3 * host_sim::run::DEFAULT_MATCH_TOLERANCE_S,
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

fn print_json<T: serde::Serialize>(value: &T) -> Result<()> {
    let s = serde_json::to_string_pretty(value).context("serialising the report")?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{s}")
        .and_then(|()| out.flush())
        .context("writing the report")
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        None => run_command(RunArgs::default()),
        Some(Command::Run(args)) => run_command(args),
        Some(Command::Summary) => summary(),
        Some(Command::Peak {
            scene,
            method,
            harmonics,
            json,
        }) => {
            let scene = load(&scene)?;
            let r = methods::peak(&scene, method, harmonics)?;
            if json {
                print_json(&r)
            } else {
                print_peak(&r);
                Ok(())
            }
        }
        Some(Command::Trace {
            scene,
            method,
            precision,
            harmonics,
            stride,
            out,
        }) => {
            let scene = load(&scene)?;
            let opts = TraceOptions {
                method,
                precision,
                harmonics,
                stride,
            };
            match out {
                Some(path) => {
                    let file = std::fs::File::create(&path)
                        .with_context(|| format!("cannot create {}", path.display()))?;
                    write_trace(&scene, opts, BufWriter::new(file))
                        .with_context(|| format!("trace to {}", path.display()))
                }
                None => write_trace(&scene, opts, BufWriter::new(std::io::stdout().lock())),
            }
        }
        Some(Command::Check {
            scene,
            precision,
            json,
        }) => {
            let scene = load(&scene)?;
            let r = methods::check(&scene, precision)?;
            if json {
                print_json(&r)
            } else {
                print_check(&r);
                Ok(())
            }
        }
        Some(Command::Qemu { scene, model, json }) => {
            host_sim::qemu::command(scene.as_deref(), json, model)
        }
        Some(Command::Bench { quick, json, out }) => {
            let report = host_sim::bench::run(&host_sim::bench::BenchOptions {
                quick,
                out_dir: out.clone(),
                progress: true,
            })?;
            if json {
                print_json(&report)
            } else {
                print!("{}", host_sim::bench::markdown(&report));
                println!(
                    "wrote {}/bench.md, bench.json and pareto-*.png",
                    out.display()
                );
                Ok(())
            }
        }
        Some(Command::Reproduce { out, quick }) => {
            let report = host_sim::reproduce::run(&host_sim::reproduce::ReproduceOptions {
                quick,
                out_dir: out,
                progress: true,
            })?;
            println!("wrote {}", report.display());
            Ok(())
        }
    }
}

/// Set by Ctrl-C: `run` stops at the next flush and keeps the rows written so far.
static STOP: AtomicBool = AtomicBool::new(false);

fn run_command(args: RunArgs) -> Result<()> {
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
    if args.json {
        print_json(&report)
    } else {
        let mut text = run::summary_text(&report);
        if let Some(p) = &args.plot {
            text += &format!("  plot: {}\n", p.display());
        }
        let mut o = std::io::stdout().lock();
        o.write_all(text.as_bytes())
            .and_then(|()| o.flush())
            .context("writing the summary")
    }
}

/// Stream the trace through `w`; flush at the end and on error.
fn write_trace<W: Write>(scene: &Scene, opts: TraceOptions, mut w: BufWriter<W>) -> Result<()> {
    let result = methods::trace(scene, opts, &mut w);
    let flushed = w.flush().context("writing the trace");
    result?;
    flushed
}

fn print_peak(r: &methods::PeakReport) {
    let method = match r.method {
        PeakMethod::Tfm => "TFM",
        PeakMethod::Rfm => "RFM",
    };
    if r.sliding {
        println!(
            "{method} peak |ü1| = {:.6} m/s² ({:.6} gμ); alpha = {:.6} rad, beta = {:.6}, {} harmonics{}",
            r.peak_m_s2,
            r.peak_gmu,
            r.alpha_rad.unwrap_or(0.0),
            r.beta,
            r.harmonics.unwrap_or(0),
            if r.converged { " (converged)" } else { "" }
        );
    } else {
        println!(
            "the base does not slide (beta·A0 = {:.6} <= gμ = {:.6} m/s²): fixed-base peak |ü1| = {:.6} m/s² ({:.6} gμ), beta = {:.6}",
            r.beta * r.amplitude_m_s2,
            r.gmu_m_s2,
            r.peak_m_s2,
            r.peak_gmu,
            r.beta
        );
    }
}

fn print_check(r: &methods::CheckReport) {
    println!(
        "recursion ({}) vs closed form on \"{}\": {} samples ({} compared), {} reversals",
        r.precision.name(),
        r.scene,
        r.samples,
        r.compared_samples,
        r.reversals
    );
    println!(
        "  max |error| = {:.3e} gμ ({:.3e} m/s²) at t = {} s; rms = {:.3e} gμ",
        r.max_err_gmu, r.max_err_m_s2, r.max_err_at_s, r.rms_err_gmu
    );
}

/// `host-sim summary`: peaks and the recursion check on the built-in default scene.
fn summary() -> Result<()> {
    let scene = Scene::default_scene();
    let s = &scene.structure;
    println!(
        "host-sim: built-in default scene \"{}\" (= host-sim/scenes/table1.toml)",
        scene.name
    );
    println!(
        "  structure: m1 = {} kg, m2 = {} kg, {} Hz, xi = {}, mu = {} (M = {:.4}, zeta = {:.4}, {:?})",
        s.m1(),
        s.m2(),
        s.p() / (2.0 * std::f64::consts::PI),
        s.xi(),
        s.mu(),
        s.mass_ratio(),
        s.zeta(),
        s.regime()
    );
    if let Input::Harmonic {
        amplitude_m_s2,
        period_s,
    } = scene.input
    {
        println!("  input: table acceleration {amplitude_m_s2} m/s² · sin(2πt/{period_s} s)");
    }
    println!(
        "  run: {} s at {} Hz ({} samples); gμ = {} m/s²",
        scene.duration_s,
        scene.rate_hz,
        scene.samples,
        scene.gmu()
    );
    for m in [PeakMethod::Tfm, PeakMethod::Rfm] {
        print!("  ");
        print_peak(&methods::peak(&scene, m, None)?);
    }
    for p in [Precision::F64, Precision::F32] {
        let r = methods::check(&scene, p)?;
        println!(
            "  check: recursion ({}) vs closed form over {} samples, {} reversals: max |error| = {:.3e} gμ at t = {} s, rms = {:.3e} gμ",
            p.name(),
            r.samples,
            r.reversals,
            r.max_err_gmu,
            r.max_err_at_s,
            r.rms_err_gmu
        );
    }
    println!("Commands: host-sim run | summary | peak | trace | check (host-sim --help).");
    Ok(())
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        // A closed pipe (e.g. `| head`) is not an error of ours.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<Interrupted>().is_some() => {
            eprintln!("host-sim: {e:#}");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("host-sim: error: {e:#}");
            ExitCode::FAILURE
        }
    }
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
        assert_eq!(format!("{args:?}"), format!("{:?}", RunArgs::default()));
    }
}
