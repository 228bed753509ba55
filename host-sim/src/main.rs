//! host-sim: the host-side simulator and harness.
//!
//! `host-sim` with no command prints a summary of the built-in default scene; see `host-sim --help`.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use host_sim::methods::{self, PeakMethod, Precision, TraceMethod, TraceOptions};
use host_sim::scene::{Input, Scene};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Controller-side estimator of base-sliding isolation shake-table tests: host simulator and harness.
#[derive(Parser, Debug)]
#[command(name = "host-sim", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    // Slot for `Run` (the main job on a scene: truth, sensors, estimator); it will become the
    // default when no command is given.
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
        None => summary(),
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

/// The no-command default: a summary of the built-in default scene.
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
    println!("Commands: host-sim peak | trace | check (host-sim --help).");
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
        Err(e) => {
            eprintln!("host-sim: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
