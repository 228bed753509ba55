//! `host-sim bench`: speed against error of every method on three fixed scenes. The command runs
//! the measurements of [`crate::report::bench`], writes `bench.json`, `bench.md` and the Pareto
//! figures ([`crate::plot::bench`]) and prints the markdown table (or the JSON report).

use super::print_json;
use crate::plot::bench::pareto_figure;
use crate::plot::figure;
use crate::report::bench::{markdown, measure_scene, scenes, Report, SceneInfo};
use anyhow::{Context, Result};
use std::path::PathBuf;
use std::time::Instant;

/// Options of [`run`].
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// Shorter scenes and fewer repetitions (under a minute).
    pub quick: bool,
    /// Output folder of the figures, `bench.json` and `bench.md`.
    pub out_dir: PathBuf,
    /// Print progress on standard error.
    pub progress: bool,
}

/// Run the bench: measure, write `bench.json`, `bench.md` and the Pareto figures into the output
/// folder, and return the report.
pub fn run(opts: &BenchOptions) -> Result<Report> {
    std::fs::create_dir_all(&opts.out_dir)
        .with_context(|| format!("cannot create {}", opts.out_dir.display()))?;
    let reps = if opts.quick { 3 } else { 9 };
    let t0 = Instant::now();
    let scenes = scenes(opts.quick)?;
    let mut rows = Vec::new();
    let mut notes = Vec::new();
    let mut infos = Vec::new();
    for sc in &scenes {
        rows.extend(measure_scene(sc, reps, opts.progress, &mut notes)?);
        infos.push(SceneInfo {
            id: sc.id.into(),
            description: sc.description.clone(),
            samples: sc.samples,
            rate_hz: sc.rate_hz,
            reversals: sc.train.len(),
            compared_samples: sc.eval.len() as u64,
            gmu_m_s2: sc.structure.gmu(),
        });
    }
    let find = |scene: &str, method: &str, setting: &str| {
        rows.iter()
            .find(|r| r.scene == scene && r.method == method && r.setting.starts_with(setting))
    };
    let long_train_speedup = match (
        find("long-train", "rdm-closed", "full"),
        find("long-train", "rdm-recursion", "F32Poly"),
    ) {
        (Some(c), Some(r)) => Some(c.ns_per_sample / r.ns_per_sample),
        _ => None,
    };
    notes.push(format!(
        "measured in {:.1} s{}",
        t0.elapsed().as_secs_f64(),
        if opts.quick { " (--quick)" } else { "" }
    ));
    let report = Report {
        rows,
        scenes: infos,
        notes,
        quick: opts.quick,
        long_train_speedup,
    };
    let json = serde_json::to_string_pretty(&report).context("serialising the bench report")?;
    let md = markdown(&report);
    let write = |name: &str, text: &str| {
        let p = opts.out_dir.join(name);
        std::fs::write(&p, text).with_context(|| format!("cannot write {}", p.display()))
    };
    write("bench.json", &json)?;
    write("bench.md", &md)?;
    for sc in &scenes {
        let path = opts.out_dir.join(format!("pareto-{}.png", sc.id));
        figure::render_png(&pareto_figure(&report, sc), &path)?;
    }
    Ok(report)
}

/// Arguments of `bench`.
#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Shorter scenes and fewer repetitions (under a minute).
    #[arg(long)]
    pub quick: bool,
    /// Print the rows as JSON (`{"rows": [...]}`) instead of the markdown table.
    #[arg(long)]
    pub json: bool,
    /// Output folder of the figures, bench.json and bench.md.
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
}

/// `host-sim bench`: run the bench, then print the report as JSON or the markdown table.
pub fn command(args: BenchArgs) -> Result<()> {
    let BenchArgs { quick, json, out } = args;
    let report = run(&BenchOptions {
        quick,
        out_dir: out.clone(),
        progress: true,
    })?;
    if json {
        print_json(&report)
    } else {
        print!("{}", markdown(&report));
        println!(
            "wrote {}/bench.md, bench.json and pareto-*.png",
            out.display()
        );
        Ok(())
    }
}
