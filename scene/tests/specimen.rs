//! The specimen entry point (the firmware's scenes) and the board settings (`[adc]`,
//! `[sensors.<channel>]`): values, defaults and the errors of bad settings.

mod common;

use common::{error_at, parse, scenes_dir, BASE};
use ssvr_scene::{BoardSettings, ChannelScale, Scene, SceneError, Sensors, Specimen, CHANNELS};
use std::fs;
use std::path::{Path, PathBuf};

fn board_toml() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware/scenes/board.toml")
}

/// BASE without its table motion (`duration_s` and `[input]`).
fn specimen_text() -> String {
    BASE.replace("duration_s = 1.0\n", "").replace(
        "[input]\nkind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143\n",
        "",
    )
}

fn parse_specimen(text: &str) -> Result<Specimen, SceneError> {
    Specimen::parse(text, Path::new("scenes/x.toml"))
}

/// The specimen error of `text`, checked to name the file, `line` and every one of `needles`.
fn specimen_error_at(text: &str, line: usize, needles: &[&str]) -> SceneError {
    let e = parse_specimen(text).expect_err("the specimen must be rejected");
    let msg = e.to_string();
    assert_eq!(e.line, Some(line), "{msg}");
    assert!(msg.starts_with(&format!("scenes/x.toml:{line}: ")), "{msg}");
    for n in needles {
        assert!(msg.contains(n), "{msg:?} lacks {n:?}");
    }
    e
}

#[test]
fn board_scene_values_are_those_of_the_firmware_build() {
    let s = Specimen::load(board_toml()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.name, "board default: table 1 specimen");
    assert_eq!(s.rate_hz, 1000.0);
    assert_eq!(s.gravity_m_s2, 9.80665);
    let p = s.structure.params();
    assert_eq!(
        (p.m1_kg, p.m2_kg, p.natural_frequency_hz),
        (29.5, 1.75, 7.0)
    );
    assert_eq!((p.damping_ratio, p.friction_coefficient), (0.05, 0.2));
    assert_eq!(s.static_friction_coefficient, 0.2);
    assert_eq!(s.sensors.accel_range_m_s2, 39.2266);
    assert_eq!(s.sensors.disp_range_m, 0.05);
    assert_eq!(s.board.adc_gains, [1, 1, 1, 1]);
    assert_eq!(s.board.osr, 4096);
    assert_eq!(s.board.odr_hz(), 1000.0);
    // Explicit displacement scaling; the accelerometers' from their range (build.rs's defaults).
    assert_eq!(
        s.board.channels[3],
        ChannelScale {
            volts_per_unit: 24.0,
            offset_volts: 0.0
        }
    );
    for ch in &s.board.channels[..3] {
        assert_eq!(ch.volts_per_unit, 1.2 / 39.2266);
        assert_eq!(ch.offset_volts, 0.0);
    }
    // A board scene has no table motion: not a full scene.
    let e = Scene::load(board_toml()).unwrap_err();
    assert!(e.to_string().contains("missing key `duration_s`"), "{e}");
}

#[test]
fn every_host_scene_is_a_specimen() {
    let mut n = 0;
    for entry in fs::read_dir(scenes_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            let specimen = Specimen::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(specimen, Specimen::from(&scene), "{}", path.display());
            n += 1;
        }
    }
    assert!(n >= 6);
}

#[test]
fn specimen_without_table_motion_and_defaults() {
    let s = parse_specimen(&specimen_text()).unwrap();
    assert_eq!(s.name, "t");
    assert_eq!(s.rate_hz, 1000.0);
    assert_eq!(s.sensors, Sensors::default());
    assert_eq!(
        s.board,
        BoardSettings::defaults(1000.0, &Sensors::default())
    );
    assert_eq!(s.board.osr, 4096);
    assert_eq!(s.board.adc_gains, [1; 4]);
    let d = Sensors::default();
    assert_eq!(s.board.channels[0].volts_per_unit, 1.2 / d.accel_range_m_s2);
    assert_eq!(s.board.channels[3].volts_per_unit, 1.2 / d.disp_range_m);
    // The full scene of the same structure has the same specimen.
    assert_eq!(Specimen::from(&parse(BASE).unwrap()).board, s.board);
    // A full scene still needs its table motion.
    let e = Scene::parse(&specimen_text(), Path::new("scenes/x.toml")).unwrap_err();
    assert_eq!(e.line, Some(1));
    assert!(e.message.contains("missing key `duration_s`"), "{e}");
    let e = Scene::parse(
        &format!("duration_s = 1.0\n{}", specimen_text()),
        Path::new("scenes/x.toml"),
    )
    .unwrap_err();
    assert!(e.message.contains("missing table [input]"), "{e}");
}

#[test]
fn specimen_validates_table_motion_when_present() {
    let s = parse_specimen(BASE).unwrap();
    assert_eq!(s.rate_hz, 1000.0);
    specimen_error_at(
        &BASE.replace("duration_s = 1.0", "duration_s = -1.0"),
        2,
        &["duration_s = -1 is out of range"],
    );
    specimen_error_at(
        &BASE.replace("period_s = 0.143", "period_s = 0"),
        12,
        &["[input] period_s = 0"],
    );
    specimen_error_at(
        &BASE.replace("kind = \"harmonic\"\n", ""),
        9,
        &["[input] missing key `kind`"],
    );
    // Unknown keys and tables are errors as in a full scene.
    specimen_error_at(
        &format!("{}[extra]\nx = 1\n", specimen_text()),
        10,
        &["unknown table `[extra]`"],
    );
    specimen_error_at(
        &specimen_text().replace("damping_ratio = 0.05", "damping_ratio = 0.05\ndamping = 1"),
        7,
        &["[structure] unknown key `damping`"],
    );
    specimen_error_at(
        &specimen_text().replace("[sampling]\nrate_hz = 1000.0\n", ""),
        1,
        &["missing table [sampling]"],
    );
}

#[test]
fn board_settings_are_read() {
    let text = format!(
        "{BASE}[sensors]\naccel_range_m_s2 = 20.0\n\
         [sensors.table_accel]\noffset_volts = -0.5\n\
         [sensors.top_accel]\nvolts_per_unit = -0.25\n\
         [adc]\ngains = [2, 1, 128, 4]\nosr = 16256\n"
    );
    let s = parse(&text).unwrap();
    let b = s.board;
    assert_eq!(b.adc_gains, [2, 1, 128, 4]);
    assert_eq!(b.osr, 16256);
    assert_eq!(b.channels[0].volts_per_unit, 1.2 / 2.0 / 20.0);
    assert_eq!(b.channels[0].offset_volts, -0.5);
    assert_eq!(b.channels[1].volts_per_unit, 1.2 / 20.0);
    assert_eq!(b.channels[2].volts_per_unit, -0.25);
    assert_eq!(b.channels[3].volts_per_unit, 1.2 / 4.0 / 0.05);
    assert_eq!(b.channels[3].offset_volts, 0.0);
    assert_eq!(CHANNELS[2], "top_accel");
    // The simulated sensors are unchanged by the board tables.
    assert_eq!(s.sensors.accel_range_m_s2, 20.0);
    assert_eq!(s.sensors.seed, Sensors::default().seed);
}

#[test]
fn default_osr_follows_the_rate() {
    for (rate, osr) in [
        (1000.0, 4096),
        (1000.5, 2048),
        (250.0, 16256),
        (100.0, 16256),
        (10_000.0, 256),
        (32_000.0, 128),
        (64_000.0, 128),
    ] {
        assert_eq!(BoardSettings::default_osr(rate), osr, "{rate} Hz");
    }
    let s = parse(&BASE.replace("rate_hz = 1000.0", "rate_hz = 8000")).unwrap();
    assert_eq!(s.board.osr, 512);
}

/// `Scene::at_rate`: the same run at another rate, the default OSR following it, a scene's own
/// OSR kept; no scene for a rate that is not finite and positive or gives no sample.
#[test]
fn a_scene_at_another_rate() {
    let s = parse(&BASE.replace("rate_hz = 1000.0", "rate_hz = 10000")).unwrap();
    assert_eq!((s.samples, s.board.osr), (10_000, 256));
    let r = s.at_rate(1000.0).unwrap();
    assert_eq!((r.rate_hz, r.samples, r.board.osr), (1000.0, 1000, 4096));
    assert_eq!(
        (r.duration_s, &r.input, &r.sensors),
        (s.duration_s, &s.input, &s.sensors)
    );
    let own = parse(&format!("{BASE}[adc]\nosr = 128\n")).unwrap();
    assert_eq!(own.at_rate(2000.0).unwrap().board.osr, 128);
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e-6] {
        assert!(s.at_rate(bad).is_none(), "{bad}");
    }
}

#[test]
fn bad_board_settings_are_named_with_their_line() {
    // BASE has 14 lines: `[adc]` is line 15, its first key line 16.
    let adc = |body: &str| format!("{BASE}[adc]\n{body}\n");
    // A misspelled key.
    let e = error_at(&adc("osrr = 4096"), 16, &["[adc] unknown key `osrr`"]);
    assert!(e.message.contains("`osr`"), "{e}");
    specimen_error_at(
        &format!("{}[adc]\ngain = [1, 1, 1, 1]\n", specimen_text()),
        11,
        &["[adc] unknown key `gain`"],
    );
    error_at(
        &adc("gains = [1, 3, 1, 1]"),
        16,
        &[
            "[adc] gains[1] = 3 is out of range",
            "power of two in 1..=128",
        ],
    );
    error_at(
        &adc("gains = [1, 1, 1, 256]"),
        16,
        &["[adc] gains[3] = 256 is out of range"],
    );
    error_at(&adc("gains = [0, 1, 1, 1]"), 16, &["[adc] gains[0] = 0"]);
    error_at(&adc("gains = [-2, 1, 1, 1]"), 16, &["[adc] gains[0] = -2"]);
    error_at(
        &adc("gains = [1, 1,\n 1]"),
        16,
        &["[adc] gains has 3 value(s): expected 4"],
    );
    error_at(
        &adc("gains = [1, 1,\n 1.5, 1]"),
        17,
        &["[adc] gains: invalid type"],
    );
    error_at(
        &adc("osr = 1000"),
        16,
        &["[adc] osr = 1000 is out of range", "16256"],
    );
    error_at(&adc("osr = \"4096\""), 16, &["[adc] osr: invalid type"]);
    // Channel tables.
    let ch = |name: &str, body: &str| format!("{BASE}[sensors.{name}]\n{body}\n");
    error_at(
        &ch("displacement", "volts_per_unit = 0"),
        16,
        &["[sensors.displacement] volts_per_unit = 0 is out of range"],
    );
    error_at(
        &ch("base_accel", "volts_per_unit = inf"),
        16,
        &["[sensors.base_accel] volts_per_unit must be a finite number"],
    );
    error_at(
        &ch("table_accel", "offset_volts = nan"),
        16,
        &["[sensors.table_accel] offset_volts must be a finite number"],
    );
    error_at(
        &ch("top_accel", "volt_per_unit = 1"),
        16,
        &["[sensors.top_accel] unknown key `volt_per_unit`"],
    );
    error_at(
        &ch("pressure", "volts_per_unit = 1"),
        15,
        &["[sensors] unknown table `[sensors.pressure]`"],
    );
    // Channel tables and ADC keys defined implicitly (dotted headers and keys).
    let s = parse(&format!(
        "{BASE}[sensors.displacement]\nvolts_per_unit = 2.0\n[adc]\ngains = [1, 1, 1, 2]\n"
    ))
    .unwrap();
    assert_eq!(s.board.channels[3].volts_per_unit, 2.0);
    let s = parse(&BASE.replace(
        "duration_s = 1.0",
        "duration_s = 1.0\nadc.osr = 128\nsensors.top_accel.offset_volts = 0.1",
    ))
    .unwrap();
    assert_eq!((s.board.osr, s.board.channels[2].offset_volts), (128, 0.1));
    // A range so small that the derived scaling overflows.
    error_at(
        &format!("{BASE}[sensors]\ndisp_range_m = 1e-310\n"),
        16,
        &["[sensors] disp_range_m gives [sensors.displacement] volts_per_unit = inf"],
    );
}
