//! What `host-sim qemu` prints: the report for people ([`print_report`]) or as JSON, and the
//! command itself ([`command`]), which fails unless every goal is met.

use super::check::{
    run_scene_stream, QemuReport, GOAL_MODEL_INSTRUCTIONS_PER_SAMPLE, GOAL_REFERENCE_GMU,
    HOST_TOLERANCE_GMU,
};
use super::image;
use crate::model::Model;
use crate::scene::Scene;
use anyhow::{bail, Context, Result};
use ssvr_proto::Mode;
use std::io::Write;
use std::path::Path;

fn ok(b: bool) -> &'static str {
    if b {
        "ok"
    } else {
        "NOT MET"
    }
}

fn opt(v: Option<f64>, prec: usize) -> String {
    v.map_or_else(|| "-".to_string(), |x| format!("{x:.prec$}"))
}

/// The human-readable report.
pub fn print_report(r: &QemuReport, out: &mut impl Write) -> std::io::Result<()> {
    let g = &r.goals;
    let file = r.scene_file.as_ref().map_or_else(
        || "built-in default".to_string(),
        |p| p.display().to_string(),
    );
    writeln!(
        out,
        "host-sim qemu: scene \"{}\" ({file}), {} samples at {} Hz, gμ = {} m/s²",
        r.scene, r.samples, r.rate_hz, r.gmu_m_s2
    )?;
    let history = r
        .history
        .map_or_else(String::new, |h| format!(", history {h} samples"));
    writeln!(
        out,
        "  model: {} ({}), mode {}{history}",
        r.model, r.model_reason, r.mode
    )?;
    writeln!(
        out,
        "  detector: {} slip starts, {} reversals, {} sticks -> {} level changes pushed (truth: {} friction changes); {} frames flagged, {} events clamped",
        r.slip_starts,
        r.detected_reversals,
        r.sticks,
        r.reversals,
        r.truth_friction_changes,
        r.frames_flagged,
        r.events_clamped
    )?;
    writeln!(
        out,
        "  firmware vs host (same f32 detector + {} estimator): max |diff| = {:.3e} gμ, {} frames differ, mu {} [goal <= {:e} gμ: {}]",
        r.model,
        r.max_err_vs_host_gmu,
        r.frame_mismatches,
        if r.mu_equals_host { "equal" } else { "DIFFERS" },
        HOST_TOLERANCE_GMU,
        ok(g.firmware_equals_host)
    )?;
    writeln!(
        out,
        "  firmware vs {}: max |error| = {:.3e} gμ at t = {:.4} s [goal <= {:e} gμ: {}]",
        r.reference,
        r.max_err_vs_reference_gmu,
        r.max_err_vs_reference_at_s,
        GOAL_REFERENCE_GMU,
        ok(g.reference_error_le_goal)
    )?;
    writeln!(
        out,
        "  firmware vs exact truth: max |error| = {:.3} gμ, rms {:.3} gμ ({})",
        r.max_err_vs_truth_gmu,
        r.rms_err_vs_truth_gmu,
        match r.model {
            "rectangular" => "detection latency, stick phases",
            "fixed-base" => "the fixed-base model ignores any sliding",
            _ => "detection latency",
        }
    )?;
    if let (Some(mu), Some(sd), Some(n)) = (r.mu_estimate, r.mu_std, r.mu_samples) {
        writeln!(
            out,
            "  identified friction coefficient (firmware): mu = {mu:.5} ± {sd:.5} ({n} identification updates, one per block of sliding samples)"
        )?;
    }
    writeln!(
        out,
        "  instructions (QEMU Cortex-M4F, SysTick, -icount shift=0): estimator {:.2}/sample [goal <= {}: {}]{}, +{}/event (age 0.5){}; detector {}/sample, +{}/reversal, +{}/stick and slip start; whole step {}/sample",
        r.instructions_per_steady_sample,
        g.instructions_per_sample_goal,
        ok(g.instructions_per_sample_le_goal),
        match (
            r.block_size,
            r.instructions_per_sample_in_blocks,
            r.instructions_per_sample_stuck_in_blocks,
        ) {
            (Some(n), Some(a), Some(b)) => format!(
                " (blocks of {n}: {a:.2} sliding, {b:.2} stuck; one update() at a time: {:.2} sliding, {} stuck, {} sliding without the mu identification)",
                r.instructions_per_sample,
                opt(r.instructions_per_sample_stuck, 2),
                opt(r.instructions_per_sample_without_identification, 2)
            ),
            (Some(n), None, Some(_)) => format!(
                " (stuck, blocks of {n}; one update() at a time: {:.2})",
                r.instructions_per_sample
            ),
            _ => String::new(),
        },
        opt(r.instructions_per_reversal, 1),
        match (r.instructions_per_event_max_age, r.max_event_age) {
            (Some(i), Some(a)) => format!(", +{i:.0}/event (age {a})"),
            _ => String::new(),
        },
        opt(r.detector_instructions_per_sample, 1),
        opt(r.detector_instructions_per_reversal, 0),
        opt(r.detector_instructions_per_stick, 0),
        opt(r.pipeline_instructions_per_sample, 1)
    )?;
    writeln!(
        out,
        "  model as the pipeline runs it ({}): {}/sample [goal <= {}: {}] (blocks of {}: {} sliding, {} stuck; {} adoptions while timed)",
        match r.model_tuning {
            Some(true) => "all identification on: f and xi identified online",
            Some(false) => "no identification of f and xi",
            None => "-",
        },
        opt(r.instructions_per_steady_sample_model, 2),
        GOAL_MODEL_INSTRUCTIONS_PER_SAMPLE,
        ok(g.model_instructions_per_sample_le_50),
        r.block_size.unwrap_or(ssvr_proto::BATCH as u32),
        opt(r.instructions_per_sample_model_sliding, 2),
        opt(r.instructions_per_sample_model_stuck, 2),
        r.model_adoptions
            .map_or_else(|| "-".to_string(), |n| n.to_string())
    )?;
    let board = match (r.board_flash_bytes, r.board_ram_bytes) {
        (Some(f), Some(m)) => format!(
            "ssvr-board flash {f} B [<= {} KiB: {}], static RAM {m} B [<= 8 KiB: {}]",
            g.board_flash_budget_bytes / 1024,
            ok(g.board_flash_le_budget),
            ok(g.board_ram_le_8k)
        ),
        _ => format!(
            "ssvr-board not built: {}",
            r.board_error.as_deref().unwrap_or("?")
        ),
    };
    writeln!(
        out,
        "  sizes ({} model): ssvr-qemu flash {} B, static RAM {} B, stack {} B; {board}",
        r.model,
        r.flash_bytes,
        r.ram_bytes,
        r.stack_bytes.map_or_else(|| "-".into(), |s| s.to_string())
    )?;
    writeln!(out, "  image: {}", r.elf.display())?;
    writeln!(
        out,
        "  time: simulate {:.1} s, build {:.1} s, qemu {:.1} s, compare {:.1} s",
        r.timing.simulate_s, r.timing.build_s, r.timing.qemu_s, r.timing.compare_s
    )?;
    writeln!(
        out,
        "  result: {}",
        if r.passed {
            "every goal met (firmware = host on every sample)"
        } else if !g.firmware_equals_host {
            "FIRMWARE DIFFERS FROM THE HOST"
        } else {
            "A GOAL IS NOT MET"
        }
    )
}

/// `host-sim qemu [SCENE] [--model MODEL] [--json] [--stream-out FILE]`: load the scene (None
/// or `default`: the built-in default), run [`run_scene_stream`] with `firmware/` next to
/// host-sim (saving the raw stream to `stream_out`), print the report, and fail when the
/// firmware differs from the host.
pub fn command(
    scene: Option<&Path>,
    json: bool,
    model: Option<Model>,
    mode: Mode,
    stream_out: Option<&Path>,
) -> Result<()> {
    let scene = match scene {
        None => Scene::default_scene(),
        Some(p) if p == Path::new("default") && !p.exists() => Scene::default_scene(),
        Some(p) => Scene::load(p)?,
    };
    let report = run_scene_stream(
        &scene,
        &image::default_firmware_dir(),
        model,
        mode,
        stream_out,
    )?;
    let mut out = std::io::stdout().lock();
    if json {
        let s = serde_json::to_string_pretty(&report).context("serialising the report")?;
        writeln!(out, "{s}").context("writing the report")?;
    } else {
        print_report(&report, &mut out).context("writing the report")?;
    }
    out.flush().context("writing the report")?;
    let g = &report.goals;
    if !g.firmware_equals_host {
        bail!(
            "the firmware differs from the host: max |diff| = {:e} gμ (tolerance {:e}), {} frames with other flags/events, mu {}",
            report.max_err_vs_host_gmu,
            HOST_TOLERANCE_GMU,
            report.frame_mismatches,
            if report.mu_equals_host { "equal" } else { "differs" }
        );
    }
    if !report.passed {
        let mut unmet = Vec::new();
        if !g.instructions_per_sample_le_goal {
            unmet.push(format!(
                "{:.2} instructions per steady sample > {}",
                report.instructions_per_steady_sample, g.instructions_per_sample_goal
            ));
        }
        if !g.board_flash_le_budget || !g.board_ram_le_8k {
            unmet.push(format!(
                "board image flash {:?} B / RAM {:?} B over {} KiB / 8 KiB ({})",
                report.board_flash_bytes,
                report.board_ram_bytes,
                g.board_flash_budget_bytes / 1024,
                report.board_error.as_deref().unwrap_or("built")
            ));
        }
        if !g.reference_error_le_goal {
            unmet.push(format!(
                "error vs the reference {:e} gμ > {GOAL_REFERENCE_GMU:e}",
                report.max_err_vs_reference_gmu
            ));
        }
        bail!("goals not met: {}", unmet.join("; "));
    }
    Ok(())
}
