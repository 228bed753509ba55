//! `host-sim peak`: the steady-state peak of |ü1| of a harmonic scene by TFM or RFM
//! ([`crate::methods::peak`]), printed as a line or as JSON.

use super::{load, print_json};
use crate::methods::{self, PeakMethod};
use anyhow::Result;
use std::path::PathBuf;

/// Arguments of `peak`.
#[derive(clap::Args, Debug)]
pub struct PeakArgs {
    /// Scene file (TOML), or `default` for the built-in default scene.
    pub scene: PathBuf,
    /// tfm (trapezoid, eq 14-18) or rfm (rectangular, eq 20-22).
    #[arg(long, value_enum)]
    pub method: PeakMethod,
    /// Number of odd harmonics (default: doubled from 16 until the peak converges to 1e-6).
    #[arg(long)]
    pub harmonics: Option<u32>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// `host-sim peak`.
pub fn command(args: PeakArgs) -> Result<()> {
    let scene = load(&args.scene)?;
    let r = methods::peak(&scene, args.method, args.harmonics)?;
    if args.json {
        print_json(&r)
    } else {
        print_peak(&r);
        Ok(())
    }
}

/// The peak as one line of text.
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
