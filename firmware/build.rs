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
    println!(
        "cargo::rustc-check-cfg=cfg(ssvr_model, values(\"fixed_base\", \"rectangular\", \"stick_slip\"))"
    );
    let model = match env::var("SSVR_MODEL") {
        Err(env::VarError::NotPresent) => "rectangular".to_string(),
        Ok(m) if m.is_empty() => "rectangular".to_string(),
        Ok(m) if MODELS.contains(&m.as_str()) => m,
        Ok(m) => panic!("SSVR_MODEL = {m:?}: expected one of {MODELS:?} (default rectangular)"),
        Err(e) => panic!("SSVR_MODEL: {e}"),
    };
    println!(
        "cargo::rustc-cfg=ssvr_model=\"{}\"",
        model.replace('-', "_")
    );

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
    let scene = Scene::read(&path, &model);
    let mut consts = scene.common_consts();
    consts.push_str(&scene.model_consts(&model));
    fs::write(out.join("scene.rs"), consts).expect("write OUT_DIR/scene.rs");
    if board {
        fs::write(out.join("scene_board.rs"), scene.board_consts())
            .expect("write OUT_DIR/scene_board.rs");
    }
}

/// The estimator models (`SSVR_MODEL`).
const MODELS: [&str; 3] = ["fixed-base", "rectangular", "stick-slip"];

/// The stick-slip estimator's settings in the firmware (host-sim's `model::STICK_SLIP_CONFIG`,
/// `for_rate` of the scene's rate, which `host-sim qemu` checks against the firmware's `model`
/// message): μ identified and adopted at the start of each sliding episode.
const STICK_SLIP: ssvr_core::stick_slip::StickSlipConfig = ssvr_core::stick_slip::StickSlipConfig {
    use_identified_mu: true,
    ..ssvr_core::stick_slip::StickSlipConfig::DEFAULT
};

/// The fixed-base model's settings (host-sim's `model::FIXED_BASE_CONFIG`): no identification
/// (the estimator never leaves its stuck phase, so identifying μ would change nothing but cost
/// instructions on every sample).
const FIXED_BASE: ssvr_core::stick_slip::StickSlipConfig = ssvr_core::stick_slip::StickSlipConfig {
    identify_mu: false,
    observer_bandwidth: 0.0,
    ..STICK_SLIP
};

const CHANNELS: [&str; 4] = ["table_accel", "base_accel", "top_accel", "displacement"];
/// host-sim's defaults for a scene without a `[sensors]` table.
const DEFAULT_ACCEL_RANGE_M_S2: f64 = 4.0 * 9.80665;
const DEFAULT_DISP_RANGE_M: f64 = 0.05;
const DEFAULT_DISP_NOISE_RMS_M: f64 = 1e-6;
const DEFAULT_ACCEL_NOISE_RMS_M_S2: f64 = 5e-3;

/// The model's friction-event detector (host-sim's `model::Detector::for_model`): the stick-slip
/// model times sticks and slip starts from the slip acceleration (base − table accelerometer),
/// the others use the reversal detector on the displacement.
enum DetectorChoice {
    Displacement(ssvr_core::detect::displacement::DetectorConfig),
    Acceleration(ssvr_core::detect::acceleration::PhaseDetectorConfig),
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
    detector: DetectorChoice,
    ring: usize,
    /// The detector's longest back-dating (samples).
    max_age: usize,
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
    fn read(path: &Path, model: &str) -> Self {
        let text = fs::read_to_string(path)
            .unwrap_or_else(|e| panic!("cannot read scene {} (SSVR_SCENE): {e}", path.display()));
        let doc: Value = toml::from_str(&text)
            .unwrap_or_else(|e| panic!("scene {} is not valid TOML: {e}", path.display()));

        let s = "structure";
        let params = ssvr_core::StructureParams {
            m1_kg: need(&doc, s, &["m1_kg", "m1", "top_mass_kg"], path),
            m2_kg: need(&doc, s, &["m2_kg", "m2", "base_mass_kg"], path),
            natural_frequency_hz: need(
                &doc,
                s,
                &["natural_frequency_hz", "frequency_hz", "f_n_hz", "fn_hz"],
                path,
            ),
            damping_ratio: need(&doc, s, &["damping_ratio", "xi", "zeta"], path),
            friction_coefficient: need(&doc, s, &["friction_coefficient", "mu"], path),
            gravity_m_s2: get_f64(&doc, s, &["gravity_m_s2", "g", "gravity"]).unwrap_or(9.80665),
        };
        let structure = ssvr_core::Structure::new(params).unwrap_or_else(|e| {
            panic!(
                "scene {}: invalid structure: {} ({e:?})",
                path.display(),
                e.param().name()
            )
        });
        let mu_static = get_f64(
            &doc,
            s,
            &["static_friction_coefficient", "mu_s", "mu_static"],
        )
        .unwrap_or(params.friction_coefficient);
        assert!(
            mu_static.is_finite() && mu_static >= params.friction_coefficient,
            "scene {}: static_friction_coefficient = {mu_static} must be >= friction_coefficient",
            path.display()
        );
        let rate = need(
            &doc,
            "sampling",
            &["rate_hz", "sample_rate_hz", "sampling_rate_hz", "fs_hz"],
            path,
        );
        if let Err(e) = ssvr_core::recursion::Estimator32::new(&structure, rate) {
            panic!(
                "scene {}: the estimator rejects rate_hz = {rate}: {e:?}",
                path.display()
            );
        }

        let sensors = doc.get("sensors");
        let sensor = |key: &str, default: f64| {
            sensors
                .and_then(|s| s.get(key))
                .and_then(num)
                .unwrap_or(default)
        };
        let accel_range = sensor("accel_range_m_s2", DEFAULT_ACCEL_RANGE_M_S2);
        let disp_range = sensor("disp_range_m", DEFAULT_DISP_RANGE_M);
        let disp_noise = sensor("disp_noise_rms_m", DEFAULT_DISP_NOISE_RMS_M);
        for (name, v) in [
            ("accel_range_m_s2", accel_range),
            ("disp_range_m", disp_range),
        ] {
            assert!(
                v.is_finite() && v > 0.0,
                "scene {}: sensors.{name} = {v} must be finite and > 0",
                path.display()
            );
        }
        let accel_noise = sensor("accel_noise_rms_m_s2", DEFAULT_ACCEL_NOISE_RMS_M_S2);
        // The same settings as host-sim's detector for this scene and model.
        let (detector, ring, max_age) = if model == "stick-slip" {
            let d = ssvr_core::detect::acceleration::PhaseDetectorConfig::for_noise(accel_noise)
                .unwrap_or_else(|e| {
                    panic!(
                        "scene {}: no phase detector for accel_noise_rms_m_s2 = {accel_noise}: {e:?}",
                        path.display()
                    )
                })
                .with_friction(mu_static, params.friction_coefficient);
            (
                DetectorChoice::Acceleration(d),
                d.min_ring(),
                d.max_age_samples(),
            )
        } else {
            let d = ssvr_core::detect::displacement::DetectorConfig::for_noise(disp_noise, rate)
                .unwrap_or_else(|e| {
                    panic!(
                        "scene {}: no reversal detector for disp_noise_rms_m = {disp_noise} at \
                         {rate} Hz: {e:?}",
                        path.display()
                    )
                })
                .with_friction(mu_static, params.friction_coefficient);
            // The detector's ring must hold 2·fit_half + 2 samples; a power of two keeps its
            // index arithmetic (u64 modulo) a mask on the M4F.
            let ring = d.min_ring();
            (
                DetectorChoice::Displacement(d),
                ring,
                d.max_age_samples(ring),
            )
        };
        Self {
            path: path.to_path_buf(),
            doc,
            params,
            mu_static,
            rate,
            disp_noise,
            accel_noise,
            accel_range,
            disp_range,
            detector,
            ring,
            max_age,
        }
    }

    /// Consts of both images.
    fn common_consts(&self) -> String {
        let p = &self.params;
        // The detector settings as a struct literal through their `Debug` form (field names and
        // round-trip exact numbers), so new fields of `DetectorConfig` need no change here; the
        // same text is reported at run time for the host to compare.
        let (debug, module, config, ty, input) = match &self.detector {
            DetectorChoice::Displacement(d) => (
                format!("{d:?}"),
                "detect::displacement",
                "DetectorConfig",
                "ReversalDetector",
                "the base-to-table displacement (m)",
            ),
            DetectorChoice::Acceleration(d) => (
                format!("{d:?}"),
                "detect::acceleration",
                "PhaseDetectorConfig",
                "PhaseDetector",
                "the slip acceleration, base minus table accelerometer (m/s²)",
            ),
        };
        format!(
            "// Generated by build.rs from {scene:?}. Do not edit.\n\
             /// Scene the constants come from (`SSVR_SCENE`).\n\
             pub const SCENE_PATH: &str = {scene:?};\n\
             /// Sample rate (Hz) of the estimator and the detector.\n\
             pub const SAMPLE_RATE_HZ: f64 = {rate:?};\n\
             /// Structure parameters.\n\
             pub const STRUCTURE: ssvr_core::StructureParams = ssvr_core::StructureParams {{\n\
             \x20   m1_kg: {m1:?},\n    m2_kg: {m2:?},\n    natural_frequency_hz: {f:?},\n\
             \x20   damping_ratio: {xi:?},\n    friction_coefficient: {mu:?},\n    gravity_m_s2: {g:?},\n}};\n\
             /// Displacement sensor noise RMS (m) the displacement detector is set for.\n\
             pub const DISP_NOISE_RMS_M: f64 = {noise:?};\n\
             /// Accelerometer noise RMS (m/s²) the slip-acceleration detector is set for.\n\
             pub const ACCEL_NOISE_RMS_M_S2: f64 = {accel_noise:?};\n\
             /// Static friction coefficient (the detector's breakaway shape).\n\
             pub const STATIC_FRICTION_COEFFICIENT: f64 = {mu_s:?};\n\
             /// Displacement full scale ± (m): a sample at or beyond it is saturated.\n\
             pub const DISP_RANGE_M: f32 = f32::from_bits({range:#010x}); // {range_f:?}\n\
             /// The model's detector settings (`{config}::for_noise` of the scene's sensors,\n\
             /// `with_friction(STATIC_FRICTION_COEFFICIENT, mu)`).\n\
             pub const DETECTOR: ssvr_core::{module}::{config} =\n\
             \x20   ssvr_core::{module}::{debug};\n\
             /// `DETECTOR` in its `Debug` form (reported in the `detector` message).\n\
             pub const DETECTOR_DEBUG: &str = {debug:?};\n\
             /// Ring buffer length of the detector (a power of two holding its fit windows).\n\
             pub const DETECTOR_RING: usize = {ring};\n\
             /// Whether the detector reads the slip acceleration (else the displacement).\n\
             pub const DETECTOR_ON_ACCEL: bool = {on_accel};\n\
             /// The detector type of this scene and model: it processes {input}.\n\
             pub type Detector = ssvr_core::{module}::{ty}<DETECTOR_RING>;\n",
            scene = self.path.display().to_string(),
            rate = self.rate,
            m1 = p.m1_kg,
            m2 = p.m2_kg,
            f = p.natural_frequency_hz,
            xi = p.damping_ratio,
            mu = p.friction_coefficient,
            g = p.gravity_m_s2,
            noise = self.disp_noise,
            accel_noise = self.accel_noise,
            on_accel = matches!(self.detector, DetectorChoice::Acceleration(_)),
            mu_s = self.mu_static,
            range = (self.disp_range as f32).to_bits(),
            range_f = self.disp_range as f32,
            ring = self.ring,
        )
    }

    /// Consts of the estimator model: its name, the stick-slip settings and history.
    fn model_consts(&self, model: &str) -> String {
        use ssvr_core::stick_slip::{history_for_age, StickSlipCoefficients, StickSlipEstimator};
        let max_age = self.max_age;
        let history = history_for_age(max_age);
        let structure = ssvr_core::Structure::new(self.params)
            .unwrap_or_else(|e| panic!("scene {}: {e:?}", self.path.display()));
        // The stick-slip estimator's coefficients, computed here with ssvr-core in f64 and rounded
        // to f32 exactly as `StickSlipEstimator::new` does on the host: the image restores them
        // from their bits and needs no f64 start-up code.
        let coefficients =
            StickSlipCoefficients::<f32>::new(&structure, self.rate).unwrap_or_else(|e| {
                panic!(
                    "scene {}: the stick-slip estimator rejects rate_hz = {}: {e:?}",
                    self.path.display(),
                    self.rate
                )
            });
        if model != "rectangular" {
            // host-sim's mirror (`qemu_cmd::HOST_HISTORY_CAPACITY`) holds up to 2048 samples.
            type Check = StickSlipEstimator<f32, ssvr_core::math::F32Poly, 2048>;
            assert!(
                history <= 2048,
                "scene {}: the stick-slip history of {history} samples (the detector's longest \
                 back-dating at {} Hz) is too long for the firmware",
                self.path.display(),
                self.rate
            );
            if let Err(e) =
                Check::from_coefficients(coefficients, STICK_SLIP.for_rate(self.rate), history)
            {
                panic!(
                    "scene {}: the stick-slip estimator rejects the scene: {e:?}",
                    self.path.display()
                );
            }
        }
        let mut words = String::new();
        for w in coefficients.to_bits() {
            let _ = write!(words, "{w:#010x}, ");
        }
        let n = StickSlipCoefficients::<f32>::BITS;
        let cfg = if model == "fixed-base" {
            FIXED_BASE
        } else {
            STICK_SLIP
        }
        .for_rate(self.rate);
        let debug = format!("{cfg:?}");
        format!(
            "/// The estimator model (`SSVR_MODEL`).\n\
             pub const MODEL: &str = {model:?};\n\
             /// The stick-slip estimator's settings (stick-slip model; fixed-base: no identification).\n\
             pub const STICK_SLIP: ssvr_core::stick_slip::StickSlipConfig =\n\
             \x20   ssvr_core::stick_slip::{debug};\n\
             /// `STICK_SLIP` in its `Debug` form (reported in the `model` message).\n\
             pub const STICK_SLIP_DEBUG: &str = {debug:?};\n\
             /// The detector's longest back-dating (samples).\n\
             pub const MAX_EVENT_AGE_SAMPLES: usize = {max_age};\n\
             /// History of the stick-slip estimator (samples): `MAX_EVENT_AGE_SAMPLES + 2`.\n\
             pub const HISTORY: usize = {history};\n\
             /// The stick-slip estimator's coefficients (`StickSlipCoefficients::<f32>::to_bits`).\n\
             pub const STICK_SLIP_COEFFICIENTS: [u32; {n}] = [{words}];\n"
        )
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
