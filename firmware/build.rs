//! Build script of the firmware.
//!
//! * Selects the linker memory map: `qemu/memory.x` (feature `qemu`, QEMU mps2-an386) or the
//!   top-level `../memory.x` (feature `board`, STM32F446RE), copied to `OUT_DIR` as `memory.x`.
//! * Adds the cortex-m-rt and defmt linker scripts (`-Tlink.x`, `-Tdefmt.x`) for the binary only,
//!   so host builds of other workspace members (the ADC driver's tests) are unaffected.
//! * Both images: reads the scene TOML named by `SSVR_SCENE` (relative to `firmware/`; default
//!   `../host-sim/scenes/table1.toml` for the QEMU image, `scenes/board.toml` for the board) and
//!   generates `OUT_DIR/scene.rs`: structure parameters, sample rate, displacement range and the
//!   model's friction-event detector (host-sim's `model::Detector::for_model`): for the
//!   stick-slip model ssvr-core's `PhaseDetector` on the slip acceleration
//!   (`PhaseDetectorConfig::for_noise` of the scene's accelerometer noise), otherwise the
//!   `ReversalDetector` on the displacement (`DetectorConfig::for_noise` of its displacement
//!   noise and rate); `with_friction` of the static and kinetic friction, a ring buffer sized for
//!   it, all as consts.
//! * Board image: also `OUT_DIR/scene_board.rs` with the ADC configuration and sensor scaling.
//!
//! * The estimator model, `SSVR_MODEL` = `fixed-base` | `rectangular` (default) | `stick-slip`:
//!   the cfg `ssvr_model = "fixed_base" | "rectangular" | "stick_slip"` selects the model's code
//!   (only that model is compiled in), and `OUT_DIR/scene.rs` gets `MODEL`, the stick-slip
//!   estimator's settings (`STICK_SLIP`) and its history (`HISTORY`: the detector's longest
//!   back-dating + 2).
//!
//! Rebuilds track the scene and the model: `rerun-if-env-changed=SSVR_SCENE`, `SSVR_MODEL` and
//! `rerun-if-changed=<scene>`.

use ssvr_proto::{DetectorPlan, ModelKind, Plan, Specimen};
use std::env;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use toml::Value;

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let qemu = env::var_os("CARGO_FEATURE_QEMU").is_some();
    let board = env::var_os("CARGO_FEATURE_BOARD").is_some();

    let memory = match (qemu, board) {
        (true, false) => manifest.join("qemu").join("memory.x"),
        (false, true) => manifest.join("..").join("memory.x"),
        // app/mod.rs reports the feature error with a clear message.
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
    let scene = Scene::read(&path);
    let plan = Plan::new(scene.specimen(), model)
        .unwrap_or_else(|e| panic!("scene {}: {e} (model {})", path.display(), model.name()));
    fs::write(out.join("plan.rs"), plan_consts(&path, &plan)).expect("write OUT_DIR/plan.rs");
    if board {
        fs::write(out.join("scene_board.rs"), scene.board_consts())
            .expect("write OUT_DIR/scene_board.rs");
    }
}

const CHANNELS: [&str; 4] = ["table_accel", "base_accel", "top_accel", "displacement"];
/// host-sim's defaults for a scene without a `[sensors]` table.
const DEFAULT_ACCEL_RANGE_M_S2: f64 = 4.0 * 9.80665;
const DEFAULT_DISP_RANGE_M: f64 = 0.05;
const DEFAULT_DISP_NOISE_RMS_M: f64 = 1e-6;
const DEFAULT_ACCEL_NOISE_RMS_M_S2: f64 = 5e-3;

/// `OUT_DIR/plan.rs`: the plan's words and digest, the detector's ring, the stick-slip storage,
/// and the model's and detector's types (only that model's code is compiled in).
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
        ModelKind::StickSlip => "ssvr_proto::StickSlipModel<STORAGE>",
        ModelKind::FixedBase => "ssvr_proto::FixedBaseModel<STORAGE>",
    };
    let detector = match plan.detector {
        DetectorPlan::Displacement(_) => "ssvr_proto::DisplacementDetector<RING>",
        DetectorPlan::SlipAcceleration(_) => "ssvr_proto::AccelerationDetector<RING>",
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
         pub type Detector = {detector};\n",
        scene = path.display().to_string(),
        name = plan.model.name(),
        digest = plan.digest(),
        ring = plan.ring,
        storage = plan.storage,
    )
}

/// The parsed scene. The lookup is lenient about layout: every key is searched for anywhere in
/// the document (depth first, `[structure]`, `[sensors.<channel>]` and `[adc]` tables first),
/// under the names listed below; host-sim scenes work as they are.
struct Scene {
    path: PathBuf,
    doc: Value,
    params: ssvr_core::StructureParams,
    mu_static: f64,
    rate: f64,
    disp_noise: f64,
    accel_noise: f64,
    accel_range: f64,
    disp_range: f64,
}

fn find<'a>(v: &'a Value, keys: &[&str]) -> Option<&'a Value> {
    let t = v.as_table()?;
    for k in keys {
        if let Some(x) = t.get(*k) {
            if !x.is_table() {
                return Some(x);
            }
        }
    }
    t.values().find_map(|x| find(x, keys))
}

fn num(v: &Value) -> Option<f64> {
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}

fn get_f64(doc: &Value, section: &str, keys: &[&str]) -> Option<f64> {
    doc.get(section)
        .and_then(|s| find(s, keys))
        .or_else(|| find(doc, keys))
        .and_then(num)
}

fn need(doc: &Value, section: &str, keys: &[&str], path: &Path) -> f64 {
    get_f64(doc, section, keys).unwrap_or_else(|| {
        panic!(
            "scene {}: missing number `{}` (also accepted: {:?})",
            path.display(),
            keys[0],
            &keys[1..]
        )
    })
}

impl Scene {
    fn read(path: &Path) -> Self {
        let text = fs::read_to_string(path)
            .unwrap_or_else(|e| panic!("cannot read scene {} (SSVR_SCENE): {e}", path.display()));
        let doc: Value = toml::from_str(&text)
            .unwrap_or_else(|e| panic!("scene {} is not valid TOML: {e}", path.display()));
        let s = "structure";
        let params = ssvr_core::StructureParams {
            m1_kg: need(&doc, s, &["m1_kg"], path),
            m2_kg: need(&doc, s, &["m2_kg"], path),
            natural_frequency_hz: need(&doc, s, &["natural_frequency_hz"], path),
            damping_ratio: need(&doc, s, &["damping_ratio"], path),
            friction_coefficient: need(&doc, s, &["friction_coefficient"], path),
            gravity_m_s2: get_f64(&doc, s, &["gravity_m_s2"]).unwrap_or(9.80665),
        };
        let mu_static = get_f64(&doc, s, &["static_friction_coefficient"])
            .unwrap_or(params.friction_coefficient);
        let rate = need(&doc, "sampling", &["rate_hz"], path);
        let sensors = doc.get("sensors");
        let sensor = |key: &str, default: f64| {
            sensors
                .and_then(|s| s.get(key))
                .and_then(num)
                .unwrap_or(default)
        };
        Self {
            path: path.to_path_buf(),
            params,
            mu_static,
            rate,
            disp_noise: sensor("disp_noise_rms_m", DEFAULT_DISP_NOISE_RMS_M),
            accel_noise: sensor("accel_noise_rms_m_s2", DEFAULT_ACCEL_NOISE_RMS_M_S2),
            accel_range: sensor("accel_range_m_s2", DEFAULT_ACCEL_RANGE_M_S2),
            disp_range: sensor("disp_range_m", DEFAULT_DISP_RANGE_M),
            doc,
        }
    }

    fn specimen(&self) -> Specimen {
        Specimen {
            structure: self.params,
            static_friction_coefficient: self.mu_static,
            sample_rate_hz: self.rate,
            disp_noise_rms_m: self.disp_noise,
            accel_noise_rms_m_s2: self.accel_noise,
            disp_range_m: self.disp_range,
        }
    }

    /// Board-only consts: integer sample rate, ADC configuration, sensor scaling.
    fn board_consts(&self) -> String {
        let path = &self.path;
        let rate = self.rate;
        assert!(
            (1.0..=32_000.0).contains(&rate) && rate.fract() == 0.0,
            "scene {}: the board needs an integer sample rate in 1..=32000 Hz (got {rate})",
            path.display()
        );
        let adc = self.doc.get("adc");
        let gains: Vec<i64> = match adc.and_then(|a| a.get("gains")).and_then(|g| g.as_array()) {
            Some(a) => a.iter().filter_map(|x| x.as_integer()).collect(),
            None => vec![1; 4],
        };
        assert!(
            gains.len() == 4,
            "scene {}: adc.gains must list 4 integers",
            path.display()
        );
        let gain_name = |g: i64| match g {
            1 => "X1",
            2 => "X2",
            4 => "X4",
            8 => "X8",
            16 => "X16",
            32 => "X32",
            64 => "X64",
            128 => "X128",
            _ => panic!(
                "scene {}: ADC gain {g} is not a power of 2 in 1..=128",
                path.display()
            ),
        };
        // Output data rate = 8.192 MHz / 2 / OSR; default: the largest OSR still >= the rate.
        let osrs = [
            (16256, "Osr16256"),
            (8192, "Osr8192"),
            (4096, "Osr4096"),
            (2048, "Osr2048"),
            (1024, "Osr1024"),
            (512, "Osr512"),
            (256, "Osr256"),
            (128, "Osr128"),
        ];
        let osr = match adc.and_then(|a| a.get("osr")).and_then(|o| o.as_integer()) {
            Some(o) => o,
            None => osrs
                .iter()
                .map(|&(o, _)| o)
                .find(|&o| 4_096_000.0 / o as f64 >= rate)
                .unwrap_or(128),
        };
        let osr_name = osrs
            .iter()
            .find(|&&(o, _)| o == osr)
            .map(|&(_, n)| n)
            .unwrap_or_else(|| {
                panic!(
                    "scene {}: adc.osr = {osr} is not an ADS131M04 OSR",
                    path.display()
                )
            });

        // Sensor scaling: explicit [sensors.<channel>] volts_per_unit / offset_volts, else the
        // scene's sensor ranges mapped onto the ADC full scale (1.2 V / gain).
        let sensors = self.doc.get("sensors");
        let mut scales = String::new();
        for (i, ch) in CHANNELS.iter().enumerate() {
            let sec = sensors.and_then(|s| s.get(*ch)).filter(|t| t.is_table());
            let full_scale_v = 1.2 / gains[i] as f64;
            let derived = full_scale_v
                / if i < 3 {
                    self.accel_range
                } else {
                    self.disp_range
                };
            let vpu = sec
                .and_then(|t| t.get("volts_per_unit"))
                .and_then(num)
                .unwrap_or(derived);
            let off = sec
                .and_then(|t| t.get("offset_volts"))
                .and_then(num)
                .unwrap_or(0.0);
            assert!(
                vpu.is_finite() && vpu != 0.0 && off.is_finite(),
                "scene {}: sensors.{ch}: volts_per_unit must be finite and non-zero",
                path.display()
            );
            let _ = writeln!(
                scales,
                "    ads131m04::ChannelScale {{ volts_per_unit: {:?}_f32, offset_volts: {:?}_f32 }}, // {ch}",
                vpu as f32, off as f32
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
             \x20   osr: ads131m04::Osr::{osr_name},\n\
             \x20   power: ads131m04::PowerMode::HighResolution,\n\
             \x20   gains: [ads131m04::Gain::{g0}, ads131m04::Gain::{g1}, ads131m04::Gain::{g2}, ads131m04::Gain::{g3}],\n\
             \x20   input_crc: true,\n}};\n",
            scene = path.display().to_string(),
            rate = rate as u32,
            g0 = gain_name(gains[0]),
            g1 = gain_name(gains[1]),
            g2 = gain_name(gains[2]),
            g3 = gain_name(gains[3]),
        )
    }
}
