//! `host-sim robustness [--quick] [--json] [--out DIR]`: the robustness scorecard (the runs:
//! [`crate::report::robustness`]).

use crate::plot::robustness::figure;
use crate::report::robustness::{markdown, perturbations, quick_perturbations, scenes, scorecard};
use anyhow::{Context, Result};
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
}

/// `host-sim robustness`.
pub fn command(args: RobustnessArgs) -> Result<()> {
    let scenes = scenes(args.quick)?;
    let (modes, perts) = if args.quick {
        (vec![Mode::Fuse], quick_perturbations())
    } else {
        (vec![Mode::Fuse, Mode::Predict], perturbations())
    };
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
        let met = rows.iter().filter(|r| r.goal_met).count();
        eprintln!("{met} of {} rows meet their goal", rows.len());
    } else {
        print!("{md}");
    }
    Ok(())
}
