//! Build script of the firmware.
//!
//! * Selects the linker memory map: `qemu/memory.x` (feature `qemu`, QEMU mps2-an386) or the
//!   top-level `../memory.x` (feature `board`, STM32F446RE), copied to `OUT_DIR` as `memory.x`.
//! * Adds the cortex-m-rt and defmt linker scripts (`-Tlink.x`, `-Tdefmt.x`) for the binary only,
//!   so host builds of other workspace members (the ADC driver's tests) are unaffected.
//! * Board image: reads the scene TOML named by `SSVR_SCENE` (default `scenes/board.toml`) and
//!   generates `scene.rs` in `OUT_DIR` with the structure parameters, the sample rate, the ADC
//!   configuration and the sensor scaling, all as consts.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let qemu = env::var_os("CARGO_FEATURE_QEMU").is_some();
    let board = env::var_os("CARGO_FEATURE_BOARD").is_some();

    let memory = match (qemu, board) {
        (true, false) => manifest.join("qemu").join("memory.x"),
        (false, true) => manifest.join("..").join("memory.x"),
        // main.rs reports the feature error with a clear message.
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

    #[cfg(feature = "board")]
    scene::generate(&manifest, &out);
}

#[cfg(feature = "board")]
mod scene {
    //! Scene TOML -> consts. The lookup is lenient about layout: every key is searched for
    //! anywhere in the document (depth first, `[structure]`, `[sensors.<channel>]` and `[adc]`
    //! tables first), under the names listed below.
    use std::env;
    use std::fmt::Write as _;
    use std::fs;
    use std::path::{Path, PathBuf};
    use toml::Value;

    const CHANNELS: [&str; 4] = ["table_accel", "base_accel", "top_accel", "displacement"];

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

    pub fn generate(manifest: &Path, out: &Path) {
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
            None => manifest.join("scenes").join("board.toml"),
        };
        println!("cargo:rerun-if-changed={}", path.display());
        let text = fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("cannot read scene {}: {e}", path.display()));
        let doc: Value = toml::from_str(&text)
            .unwrap_or_else(|e| panic!("scene {} is not valid TOML: {e}", path.display()));

        let s = "structure";
        let m1 = need(&doc, s, &["m1_kg", "m1", "top_mass_kg"], &path);
        let m2 = need(&doc, s, &["m2_kg", "m2", "base_mass_kg"], &path);
        let f = need(
            &doc,
            s,
            &["natural_frequency_hz", "frequency_hz", "f_n_hz", "fn_hz"],
            &path,
        );
        let xi = need(&doc, s, &["damping_ratio", "xi", "zeta"], &path);
        let mu = need(&doc, s, &["friction_coefficient", "mu"], &path);
        let g = get_f64(&doc, s, &["gravity_m_s2", "g", "gravity"]).unwrap_or(9.80665);
        let rate = need(
            &doc,
            "sampling",
            &["rate_hz", "sample_rate_hz", "sampling_rate_hz", "fs_hz"],
            &path,
        );
        for (name, v, ok) in [
            ("m1", m1, m1 > 0.0),
            ("m2", m2, m2 > 0.0),
            ("natural frequency", f, f > 0.0),
            ("damping ratio", xi, (0.0..1.0).contains(&xi)),
            ("friction coefficient", mu, mu > 0.0),
            ("gravity", g, g > 0.0),
        ] {
            assert!(
                v.is_finite() && ok,
                "scene {}: {name} = {v} out of range",
                path.display()
            );
        }
        assert!(
            (1.0..=32_000.0).contains(&rate) && rate.fract() == 0.0,
            "scene {}: the board needs an integer sample rate in 1..=32000 Hz (got {rate})",
            path.display()
        );

        let adc = doc.get("adc");
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
        // host-sim scene's sensor ranges mapped onto the ADC full scale (1.2 V / gain).
        let sensors = doc.get("sensors");
        let range = |key: &str, default: f64| {
            sensors
                .and_then(|s| s.get(key))
                .and_then(num)
                .unwrap_or(default)
        };
        let accel_range = range("accel_range_m_s2", 4.0 * 9.80665);
        let disp_range = range("disp_range_m", 0.05);
        let mut scales = String::new();
        for (i, ch) in CHANNELS.iter().enumerate() {
            let sec = sensors.and_then(|s| s.get(*ch)).filter(|t| t.is_table());
            let full_scale_v = 1.2 / gains[i] as f64;
            let derived = full_scale_v / if i < 3 { accel_range } else { disp_range };
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

        let code = format!(
            "// Generated by build.rs from {scene:?}. Do not edit.\n\
             /// Scene the constants come from.\n\
             pub const SCENE_PATH: &str = {scene:?};\n\
             /// Sample rate (Hz) of the TIM2 interrupt and of the estimator.\n\
             pub const SAMPLE_RATE_HZ: u32 = {rate};\n\
             /// Structure parameters.\n\
             pub const STRUCTURE: ssvr_core::StructureParams = ssvr_core::StructureParams {{\n\
             \x20   m1_kg: {m1:?},\n    m2_kg: {m2:?},\n    natural_frequency_hz: {f:?},\n\
             \x20   damping_ratio: {xi:?},\n    friction_coefficient: {mu:?},\n    gravity_m_s2: {g:?},\n}};\n\
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
        );
        fs::write(out.join("scene.rs"), code).expect("write OUT_DIR/scene.rs");
    }
}
