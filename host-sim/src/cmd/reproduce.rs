//! `host-sim reproduce`: the seed paper's results regenerated as figures, `results.json` and a
//! `report.md` (the computations: [`crate::report::reproduce`]).

use crate::report::reproduce::{
    fig10::fig10, fig6::fig6, fig9::fig9, friction::friction, markdown::report_md,
    spectra::spectra, table2::table2, Results, Sweep,
};
use anyhow::{Context, Result};
use std::path::PathBuf;
use std::time::Instant;

/// Options of [`run`].
#[derive(Debug, Clone)]
pub struct ReproduceOptions {
    /// Fewer sweep points and shorter runs.
    pub quick: bool,
    /// Output folder.
    pub out_dir: PathBuf,
    /// Show progress bars.
    pub progress: bool,
}

/// Regenerate the results into the output folder; returns the path of `report.md`.
pub fn run(opts: &ReproduceOptions) -> Result<PathBuf> {
    let dir = &opts.out_dir;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut seconds = Vec::new();
    let mut clock = Instant::now();
    let mut lap = |name: &str| {
        seconds.push((name.to_string(), clock.elapsed().as_secs_f64()));
        clock = Instant::now();
    };
    let sweep = Sweep {
        quick: opts.quick,
        progress: opts.progress,
    };
    let t2 = table2(sweep)?;
    lap("table 2");
    let f6 = fig6(&dir.join("fig6-table1-tfm-rfm-rdm.png"))?;
    lap("fig 6");
    let f9 = fig9(&dir.join("fig9-m1-much-larger-than-m2.png"))?;
    lap("fig 9");
    let f10 = fig10(sweep, &dir.join("fig10-peak-vs-mass-ratio.png"))?;
    lap("fig 10");
    let sp = spectra(sweep, &dir.join("fig11-sliding-response-spectra.png"))?;
    lap("fig 11");
    let fr = friction(sweep, &dir.join("friction.png"))?;
    lap("friction");
    let results = Results {
        table2: t2,
        fig6: f6,
        fig9: f9,
        fig10: f10,
        spectra: sp,
        friction: fr,
        seconds,
        quick: opts.quick,
    };
    let json = serde_json::to_string_pretty(&results).context("serialising the results")?;
    let p = dir.join("results.json");
    std::fs::write(&p, json).with_context(|| format!("cannot write {}", p.display()))?;
    let report = dir.join("report.md");
    std::fs::write(&report, report_md(&results))
        .with_context(|| format!("cannot write {}", report.display()))?;
    Ok(report)
}

/// Arguments of `reproduce`.
#[derive(clap::Args, Debug)]
pub struct ReproduceArgs {
    /// Output folder.
    #[arg(long, default_value = "reproduce-out")]
    pub out: PathBuf,
    /// Fewer sweep points and shorter runs (for tests).
    #[arg(long)]
    pub quick: bool,
}

/// `host-sim reproduce`: regenerate everything and print the path of `report.md`.
pub fn command(args: ReproduceArgs) -> Result<()> {
    let report = run(&ReproduceOptions {
        quick: args.quick,
        out_dir: args.out,
        progress: true,
    })?;
    println!("wrote {}", report.display());
    Ok(())
}
