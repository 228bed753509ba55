//! Build script of the firmware.
//!
//! * Selects the linker memory map: `qemu/memory.x` (feature `qemu`, QEMU mps2-an386) or the
//!   top-level `../memory.x` (feature `board`, STM32F446RE), copied to `OUT_DIR` as `memory.x`.
//! * Adds the cortex-m-rt and defmt linker scripts (`-Tlink.x`, `-Tdefmt.x`) for the binaries
//!   only, so host builds of other workspace members (the ADC driver's tests) are unaffected.
//! * Reads the scene named by `SSVR_SCENE` (relative to `firmware/`; default
//!   `../host-sim/scenes/table1.toml` for the QEMU image, `scenes/board.toml` for the board) with
//!   the host's own parser (`ssvr_scene::Specimen`: a scene the host rejects fails the build with
//!   the same message) and makes the plan of its specimen and the model `SSVR_MODEL` =
//!   `fixed-base` | `rectangular` (default) | `stick-slip`, in the mode `SSVR_MODE` = `fuse`
//!   (default) | `predict`, with the host's own code
//!   (`ssvr_proto::Plan::new`), and the planned input's start `SSVR_PLANNED_START`
//!   (`accel,rise`, two f32s' bits in hex, or `none`, as `host-sim qemu` passes it; unset or
//!   empty: the scene file's own input, if it is a whole scene; kept for a plan without a rest
//!   only, `Plan::with_planned_start`). Writes `OUT_DIR/plan.rs`: the plan's words and digest, the
//!   detector's ring, the stick-slip storage, and the model's and detector's types (only that
//!   model's code is compiled in).
//! * Board image: also `OUT_DIR/scene_board.rs`: the integer TIM2 rate, the ADC configuration and
//!   the sensor scaling of the scene's board settings.
//!
//! Rebuilds track the scene and the model: `rerun-if-env-changed=SSVR_SCENE`, `SSVR_MODEL`,
//! `SSVR_MODE`, `SSVR_PLANNED_START` and `rerun-if-changed=<scene>`.

use ssvr_proto::{DetectorPlan, Mode, ModelKind, Plan};
use ssvr_scene::Specimen;
use std::env;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let qemu = env::var_os("CARGO_FEATURE_QEMU").is_some();
    let board = env::var_os("CARGO_FEATURE_BOARD").is_some();

    let memory = match (qemu, board) {
        (true, false) => manifest.join("qemu").join("memory.x"),
        (false, true) => manifest.join("..").join("memory.x"),
        // lib.rs reports the feature error with a clear message.
        _ => manifest.join("qemu").join("memory.x"),
    };
    let text = fs::read(&memory)
        .unwrap_or_else(|e| panic!("cannot read the memory map {}: {e}", memory.display()));
    fs::write(out.join("memory.x"), text).expect("write OUT_DIR/memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory.display());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=SSVR_QEMU_LOG");

    let target = env::var("TARGET").unwrap_or_default();
    if target.starts_with("thumb") {
        println!("cargo:rustc-link-arg-bins=--nmagic");
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }

    println!("cargo:rerun-if-env-changed=SSVR_MODEL");
    let model = match env::var("SSVR_MODEL") {
        Err(env::VarError::NotPresent) => ModelKind::Rectangular,
        Ok(m) if m.is_empty() => ModelKind::Rectangular,
        Ok(m) => ModelKind::from_name(&m).unwrap_or_else(|| {
            panic!(
                "SSVR_MODEL = {m:?}: expected fixed-base, rectangular or stick-slip (default \
                 rectangular)"
            )
        }),
        Err(e) => panic!("SSVR_MODEL: {e}"),
    };

    println!("cargo:rerun-if-env-changed=SSVR_MODE");
    let mode = match env::var("SSVR_MODE") {
        Err(env::VarError::NotPresent) => Mode::Fuse,
        Ok(m) if m.is_empty() => Mode::Fuse,
        Ok(m) => Mode::from_name(&m).unwrap_or_else(|| {
            panic!("SSVR_MODE = {m:?}: expected fuse or predict (default fuse)")
        }),
        Err(e) => panic!("SSVR_MODE: {e}"),
    };

    println!("cargo:rerun-if-env-changed=SSVR_SCENE");
    let path = match env::var_os("SSVR_SCENE") {
        Some(p) => {
            let p = PathBuf::from(p);
            if p.is_absolute() {
                p
            } else {
                manifest.join(p)
            }
        }
        None if board && !qemu => manifest.join("scenes").join("board.toml"),
        None => manifest
            .join("..")
            .join("host-sim")
            .join("scenes")
            .join("table1.toml"),
    };
    println!("cargo:rerun-if-changed={}", path.display());
    // The host's parser: the same checks and the same messages (file, line, key).
    let specimen = Specimen::load(&path).unwrap_or_else(|e| panic!("SSVR_SCENE: {e}"));
    let mut plan = Plan::new(specimen.prior(), model)
        .unwrap_or_else(|e| panic!("scene {}: {e} (model {})", path.display(), model.name()))
        .with_mode(mode)
        .with_rest(specimen.start_s);
    // The planned input's start, as the host plans it (`host_sim::pipeline::plan_for_mode`:
    // without a rest only): `SSVR_PLANNED_START` (host-sim's builds: the two f32s'
    // bits in hex, `accel,rise`, or `none`), else the scene file's own input (a whole scene: the
    // default table1.toml; a specimen file, as host-sim writes, has none), else none.
    println!("cargo:rerun-if-env-changed=SSVR_PLANNED_START");
    plan = match env::var("SSVR_PLANNED_START") {
        Ok(v) if v == "none" => plan.with_planned_start(None),
        Ok(v) if !v.is_empty() => {
            let p: ssvr_proto::PlannedStart = v.parse().unwrap_or_else(|_| {
                panic!(
                    "SSVR_PLANNED_START: {v:?} is not `accel,rise`, two finite f32s' bits in hex"
                )
            });
            plan.with_planned_start(Some(p))
        }
        _ => planned_from_scene(plan, &path),
    };
    fs::write(out.join("plan.rs"), plan_consts(&path, &plan)).expect("write OUT_DIR/plan.rs");
    if board {
        fs::write(out.join("scene_board.rs"), board_consts(&path, &specimen))
            .expect("write OUT_DIR/scene_board.rs");
    }
}

/// `plan` with the planned input of the scene file at `path`, if it is a whole scene (a specimen
/// file has no input: none).
fn planned_from_scene(plan: Plan, path: &Path) -> Plan {
    match ssvr_scene::Scene::load(path) {
        Ok(s) => {
            let input = s.input_motion();
            plan.with_planned_input(|t| input.accel(t))
        }
        Err(_) => plan,
    }
}

/// `OUT_DIR/plan.rs`: the plan's words and digest, the detector's ring, the stick-slip storage,
/// and the model's, detector's and gain slot's types (only that model's code is compiled in).
fn plan_consts(path: &Path, plan: &Plan) -> String {
    let mut words = String::new();
    for (i, w) in plan.to_words().iter().enumerate() {
        if i % 8 == 0 {
            words.push_str("\n   ");
        }
        let _ = write!(words, " {w:#010x},");
    }
    let model = match plan.model {
        ModelKind::Rectangular => "ssvr_proto::RectangularModel",
        // A velocity-dependent law: the model that follows it (only then is its code compiled in).
        ModelKind::StickSlip if plan.follows_law() => "ssvr_proto::StickSlipLawModel<STORAGE>",
        ModelKind::StickSlip => "ssvr_proto::StickSlipModel<STORAGE>",
        ModelKind::FixedBase => "ssvr_proto::FixedBaseModel<STORAGE>",
    };
    let detector = match plan.detector {
        DetectorPlan::Displacement(_) => "ssvr_proto::DisplacementDetector<RING>",
        DetectorPlan::SlipAcceleration(_) => "ssvr_proto::AccelerationDetector<RING>",
    };
    let gain = if plan.identifies_table_gain() {
        "Option<ssvr_proto::table_gain::TableGain>"
    } else {
        "()"
    };
    format!(
        "// Generated by build.rs from {scene:?}. Do not edit.\n\
         /// The scene the plan was made from (`SSVR_SCENE`).\n\
         pub const SCENE_PATH: &str = {scene:?};\n\
         /// The plan's words (`ssvr_proto::Plan::to_words`; model {name}).\n\
         pub const PLAN_WORDS: [u32; ssvr_proto::plan::WORDS] = [{words}\n];\n\
         /// The plan's digest (`ssvr_proto::Plan::digest`).\n\
         pub const PLAN_DIGEST: u32 = {digest:#010x};\n\
         /// The detector's ring (samples).\n\
         pub const RING: usize = {ring};\n\
         /// The stick-slip estimator's storage (samples; `storage_for` the plan's history).\n\
         pub const STORAGE: usize = {storage};\n\
         /// The model of the plan.\n\
         pub type Model = {model};\n\
         /// The friction-event detector of the plan.\n\
         pub type Detector = {detector};\n\
         /// Where the pipeline keeps the table accelerometer's gain identification.\n\
         pub type Gain = {gain};\n",
        scene = path.display().to_string(),
        name = plan.model.name(),
        digest = plan.digest(),
        ring = plan.ring,
        storage = plan.storage,
    )
}

/// Board-only consts: the integer TIM2 rate, the ADC configuration and the sensor scaling (ADC
/// volts → SI) of the scene's board settings (`[adc]`, `[sensors.<channel>]`, defaults resolved
/// by `ssvr_scene`). Floats are written by their bits.
fn board_consts(path: &Path, s: &Specimen) -> String {
    let rate = s.rate_hz;
    assert!(
        (1.0..=32_000.0).contains(&rate) && rate.fract() == 0.0,
        "scene {}: the board needs an integer sample rate in 1..=32000 Hz (got {rate})",
        path.display()
    );
    let b = &s.board;
    let gain = |g: u8| format!("X{g}");
    let mut scales = String::new();
    for (c, name) in b.channels.iter().zip(ssvr_scene::CHANNELS) {
        let _ = writeln!(
            scales,
            "    ads131m04::ChannelScale {{ volts_per_unit: f32::from_bits({:#010x}), \
             offset_volts: f32::from_bits({:#010x}) }}, // {name}: {} V/unit, {} V",
            (c.volts_per_unit as f32).to_bits(),
            (c.offset_volts as f32).to_bits(),
            c.volts_per_unit as f32,
            c.offset_volts as f32,
        );
    }
    format!(
        "// Generated by build.rs from {scene:?}. Do not edit.\n\
         /// Sample rate (Hz) of the TIM2 interrupt.\n\
         pub const TIMER_RATE_HZ: u32 = {rate};\n\
         /// Sensor scaling (ADC volts -> SI) of table accel, base accel, top accel, displacement.\n\
         pub const CHANNEL_SCALES: [ads131m04::ChannelScale; 4] = [\n{scales}];\n\
         /// ADC configuration.\n\
         pub const ADC_CONFIG: ads131m04::Config = ads131m04::Config {{\n\
         \x20   osr: ads131m04::Osr::Osr{osr},\n\
         \x20   power: ads131m04::PowerMode::HighResolution,\n\
         \x20   gains: [ads131m04::Gain::{g0}, ads131m04::Gain::{g1}, ads131m04::Gain::{g2}, ads131m04::Gain::{g3}],\n\
         \x20   input_crc: true,\n}};\n",
        scene = path.display().to_string(),
        rate = rate as u32,
        osr = b.osr,
        g0 = gain(b.adc_gains[0]),
        g1 = gain(b.adc_gains[1]),
        g2 = gain(b.adc_gains[2]),
        g3 = gain(b.adc_gains[3]),
    )
}
