//! `host-sim check`: the recursion against the closed form over every sample of a scene
//! ([`crate::methods::check`]), printed as text or as JSON.

use super::{load, print_json};
use crate::methods::{self, Precision};
use anyhow::Result;
use std::path::PathBuf;

/// Arguments of `check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Scene file (TOML), or `default` for the built-in default scene.
    pub scene: PathBuf,
    /// Precision of the recursion.
    #[arg(long, value_enum, default_value = "f64")]
    pub precision: Precision,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// `host-sim check`.
pub fn command(args: CheckArgs) -> Result<()> {
    let scene = load(&args.scene)?;
    let r = methods::check(&scene, args.precision)?;
    if args.json {
        print_json(&r)
    } else {
        print_check(&r);
        Ok(())
    }
}

/// The check as two lines of text.
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
