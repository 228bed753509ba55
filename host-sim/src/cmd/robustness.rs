//! `host-sim robustness [--quick] [--json] [--out DIR] [--rate-hz HZ]`: the robustness
//! scorecard (the runs: [`crate::report::robustness`]).

use crate::plot::robustness::figure;
use crate::report::robustness::{
    markdown, perturbations, quick_perturbations, scenes, scorecard, tally,
};
use anyhow::{anyhow, Context, Result};
use ssvr_proto::Mode;
use std::io::IsTerminal;
use std::path::PathBuf;

/// Arguments of `robustness`.
#[derive(clap::Args, Debug)]
pub struct RobustnessArgs {
    /// 2 s of each scene, the fuse mode and five perturbations (for tests).
    #[arg(long)]
    pub quick: bool,
    /// Print `{"rows": [...]}` instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Output folder of robustness.json, robustness.md and robustness.png.
    #[arg(long, default_value = "robustness-out")]
    pub out: PathBuf,
    /// Only the perturbations whose id contains one of these (comma-separated, e.g.
    /// `mu,f+8%`).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Only this mode (`fuse` or `predict`).
    #[arg(long, value_parser = crate::model::parse_mode)]
    pub mode: Option<Mode>,
    /// Every scene sampled at this rate (Hz) instead of its own (10 kHz): e.g. 1000, the
    /// board's rate (`firmware/scenes/board.toml`).
    #[arg(long)]
    pub rate_hz: Option<f64>,
}

/// `host-sim robustness`.
pub fn command(args: RobustnessArgs) -> Result<()> {
    let mut scenes = scenes(args.quick)?;
    if let Some(rate) = args.rate_hz {
        scenes = scenes
            .iter()
            .map(|s| {
                s.at_rate(rate).ok_or_else(|| {
                    anyhow!(
                        "--rate-hz {rate}: expected a rate > 0 Hz giving {} at least one sample",
                        s.name
                    )
                })
            })
            .collect::<Result<_>>()?;
    }
    let (mut modes, mut perts) = if args.quick {
        (vec![Mode::Fuse], quick_perturbations())
    } else {
        (vec![Mode::Fuse, Mode::Predict], perturbations())
    };
    if let Some(m) = args.mode {
        modes = vec![m];
    }
    if !args.only.is_empty() {
        // The unperturbed row stays: the event goal of the offset rows compares with it.
        perts.retain(|p| p.id == "none" || args.only.iter().any(|o| p.id.contains(o.as_str())));
    }
    let progress = std::io::stderr().is_terminal();
    let rows = scorecard(&scenes, &modes, &perts, progress)?;
    let dir = &args.out;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let json = serde_json::to_string_pretty(&serde_json::json!({ "rows": rows }))
        .context("serialising the scorecard")?;
    let p = dir.join("robustness.json");
    std::fs::write(&p, &json).with_context(|| format!("cannot write {}", p.display()))?;
    let md = markdown(&rows);
    let p = dir.join("robustness.md");
    std::fs::write(&p, &md).with_context(|| format!("cannot write {}", p.display()))?;
    figure(&rows, &dir.join("robustness.png"))?;
    if args.json {
        println!("{json}");
        let (met, counted) = tally(&rows);
        eprintln!(
            "{met} of {counted} rows meet their goal ({} beyond the goals' range not counted)",
            rows.len() - counted
        );
    } else {
        print!("{md}");
    }
    Ok(())
}
