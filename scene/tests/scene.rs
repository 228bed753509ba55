//! Scene files: values, defaults and the errors (file, line, key) of bad scenes.

mod common;

use common::{error_at, parse, scenes_dir, BASE};
use ssvr_core::structure::STANDARD_GRAVITY;
use ssvr_core::ReversalTrain;
use ssvr_scene::{Input, Reversals, Scene, Sensors, TableMotion};
use std::fs;
use std::path::Path;

#[test]
fn base_scene_parses() {
    let s = parse(BASE).unwrap();
    assert_eq!(s.name, "t");
    assert_eq!(s.samples, 1000);
    assert_eq!(s.rate_hz, 1000.0);
    assert_eq!(s.structure.g(), STANDARD_GRAVITY);
    assert_eq!(s.static_friction_coefficient, 0.2);
    assert_eq!(s.sensors, Sensors::default());
    assert_eq!(s.time(500), 0.5);
    assert_eq!(
        s.input,
        Input::Harmonic {
            amplitude_m_s2: 2.0,
            period_s: 0.143
        }
    );
    assert_eq!(
        s.rdm_train(),
        Some(ReversalTrain::Periodic {
            first_s: 0.0,
            half_period_s: 0.0715,
            initial_sign: 1.0
        })
    );
    assert_eq!(s.table_motion().accel(0.143 / 4.0), 2.0);
}

#[test]
fn integers_period_gravity_and_name_default() {
    let text = BASE
        .replace("name = \"t\"\n", "")
        .replace("duration_s = 1.0", "duration_s = 2\ngravity_m_s2 = 9.81")
        .replace("natural_frequency_hz = 7.0", "natural_period_s = 0.25")
        .replace("rate_hz = 1000.0", "rate_hz = 999.6");
    let s = parse(&text).unwrap();
    assert_eq!(s.name, "x");
    assert_eq!(s.samples, 1999); // round(1999.2)
    assert_eq!(s.structure.g(), 9.81);
    assert!((s.structure.p() - 2.0 * std::f64::consts::PI * 4.0).abs() < 1e-12);
}

#[test]
fn table1_file_is_the_default_scene() {
    let mut s = Scene::load(scenes_dir().join("table1.toml")).unwrap();
    assert!(s.source.is_some());
    s.source = None;
    assert_eq!(s, Scene::default_scene());
}

#[test]
fn every_example_scene_loads() {
    let mut n = 0;
    for entry in fs::read_dir(scenes_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(n >= 6);
    let crit = Scene::load(scenes_dir().join("critical.toml")).unwrap();
    assert_eq!(crit.structure.regime(), ssvr_core::Regime::Critical);
    let over = Scene::load(scenes_dir().join("overdamped.toml")).unwrap();
    assert_eq!(over.structure.regime(), ssvr_core::Regime::Overdamped);
}

#[test]
fn reversal_trains() {
    let periodic = BASE.replace(
        "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
        "kind = \"reversals\"\nhalf_period_s = 0.0715\ninitial_sign = -1",
    );
    let s = parse(&periodic).unwrap();
    assert_eq!(
        s.input,
        Input::Reversals(Reversals::Periodic {
            half_period_s: 0.0715,
            initial_sign: -1.0
        })
    );
    assert_eq!(s.table_motion(), TableMotion::None);
    let times = BASE.replace(
        "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
        "kind = \"reversals\"\ntimes_s = [-0.01, 0, 0.03125,\n 0.5]",
    );
    let s = parse(&times).unwrap();
    let train = s.rdm_train().unwrap();
    assert_eq!(train.len(), Some(4));
    assert_eq!(train.get(0).unwrap().level, 1.0);
    assert_eq!(train.get(1).unwrap().level, -1.0);
    assert_eq!(train.get(2).unwrap().time_s, 0.03125);
}

#[test]
fn sensors_table() {
    let text = format!("{BASE}[sensors]\nseed = 7\naccel_adc_bits = 16\ndisp_range_m = 0.1\n");
    let s = parse(&text).unwrap();
    assert_eq!(s.sensors.seed, 7);
    assert_eq!(s.sensors.accel_adc_bits, 16);
    assert_eq!(s.sensors.disp_range_m, 0.1);
    assert_eq!(s.sensors.accel_noise_rms_m_s2, 5e-3);
    assert_eq!(s.sensors.accel_range_m_s2, 39.2266);
    let empty = format!("{BASE}[sensors]\n");
    assert_eq!(parse(&empty).unwrap().sensors, Sensors::default());
}

#[test]
fn unknown_keys_are_named_with_their_line() {
    error_at(
        &BASE.replace("damping_ratio = 0.05", "damping_ratio = 0.05\ndamping = 1"),
        8,
        &["[structure]", "unknown key `damping`"],
    );
    error_at(
        &BASE.replace("duration_s = 1.0", "duration_s = 1.0\nduraton = 2"),
        3,
        &["unknown key `duraton`"],
    );
    error_at(
        &format!("{BASE}[sensors]\nnoise = 1\n"),
        16,
        &["[sensors]", "unknown key `noise`"],
    );
    // An unknown table is named as a table at its header, not as a key of the table before it.
    let e = error_at(
        &format!("{BASE}[extra]\nx = 1\n"),
        15,
        &["unknown table `[extra]`"],
    );
    assert!(!e.message.contains("[sampling]"), "{e}");
    // A key of another input kind.
    error_at(
        &BASE.replace("period_s = 0.143", "period_s = 0.143\nhalf_period_s = 0.07"),
        13,
        &["[input] half_period_s", "kind = \"harmonic\""],
    );
}

#[test]
fn unknown_tables_are_named_at_their_header() {
    // A top-level table: no `[structure] unknown key` (the table before it).
    let text = BASE.replace("[input]", "[damper]\nmu = 0.2\n[input]");
    let e = error_at(&text, 9, &["unknown table `[damper]`"]);
    assert!(e.message.starts_with("unknown table `[damper]`"), "{e}");
    assert!(!e.message.contains("[structure]"), "{e}");
    // An array of tables.
    error_at(
        &format!("{BASE}[[runs]]\nx = 1\n"),
        15,
        &["unknown table `[[runs]]`"],
    );
    // A sub-table: named under its parent.
    let e = error_at(
        &BASE.replace("[input]", "[structure.extra]\nx = 1\n[input]"),
        9,
        &["[structure] unknown table `[structure.extra]`"],
    );
    assert!(e.message.starts_with("[structure] unknown table"), "{e}");
    // A key is still a key of the table it is in.
    error_at(
        &BASE.replace("[input]", "friction = 1\n[input]"),
        9,
        &["[structure] unknown key `friction`"],
    );
}

#[test]
fn missing_keys_are_named() {
    error_at(
        &BASE.replace("m2_kg = 1.75\n", ""),
        3,
        &["[structure]", "missing key `m2_kg`"],
    );
    error_at(
        &BASE.replace("duration_s = 1.0\n", ""),
        1,
        &["missing key `duration_s`"],
    );
    error_at(
        &BASE.replace("[sampling]\nrate_hz = 1000.0\n", ""),
        1,
        &["missing table [sampling]"],
    );
    error_at(
        &BASE.replace("natural_frequency_hz = 7.0\n", ""),
        3,
        &["[structure]", "natural_frequency_hz", "natural_period_s"],
    );
    error_at(
        &BASE.replace("period_s = 0.143\n", ""),
        9,
        &["[input]", "missing key `period_s`"],
    );
    error_at(
        &BASE.replace(
            "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
            "kind = \"reversals\"",
        ),
        9,
        &["[input]", "half_period_s", "times_s"],
    );
    error_at(
        &BASE.replace(
            "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
            "kind = \"record\"\nfile = \"a.txt\"",
        ),
        9,
        &["[input]", "missing key `units`"],
    );
}

#[test]
fn bad_values_are_named_with_their_line() {
    let e = error_at(
        &BASE.replace("damping_ratio = 0.05", "damping_ratio = 1.2"),
        7,
        &["[structure] damping_ratio = 1.2 is out of range: expected 0 <= damping ratio < 1"],
    );
    assert_eq!(e.file, Path::new("scenes/x.toml"));
    let cases: &[(&str, &str, usize, &str)] = &[
        ("m1_kg = 29.5", "m1_kg = 0", 4, "[structure] m1_kg = 0"),
        ("m2_kg = 1.75", "m2_kg = -1", 5, "[structure] m2_kg = -1"),
        (
            "m2_kg = 1.75",
            "m2_kg = nan",
            5,
            "[structure] m2_kg must be a finite",
        ),
        (
            "natural_frequency_hz = 7.0",
            "natural_frequency_hz = 0.0",
            6,
            "[structure] natural_frequency_hz = 0",
        ),
        (
            "natural_frequency_hz = 7.0",
            "natural_period_s = -0.1",
            6,
            "[structure] natural_period_s = -0.1",
        ),
        (
            "friction_coefficient = 0.2",
            "friction_coefficient = 0.0",
            8,
            "[structure] friction_coefficient = 0",
        ),
        (
            "friction_coefficient = 0.2",
            "friction_coefficient = 0.2\nstatic_friction_coefficient = 0.1",
            9,
            "[structure] static_friction_coefficient = 0.1",
        ),
        (
            "duration_s = 1.0",
            "duration_s = -1.0",
            2,
            "duration_s = -1",
        ),
        (
            "duration_s = 1.0",
            "duration_s = 1e-9",
            2,
            "duration_s = 0.000000001",
        ),
        (
            "duration_s = 1.0",
            "duration_s = 1.0\ngravity_m_s2 = 0",
            3,
            "gravity_m_s2 = 0",
        ),
        (
            "rate_hz = 1000.0",
            "rate_hz = 0",
            14,
            "[sampling] rate_hz = 0",
        ),
        (
            "rate_hz = 1000.0",
            "rate_hz = inf",
            14,
            "[sampling] rate_hz must be a finite",
        ),
        (
            "amplitude_m_s2 = 2.0",
            "amplitude_m_s2 = -2.0",
            11,
            "[input] amplitude_m_s2 = -2",
        ),
        (
            "period_s = 0.143",
            "period_s = 0",
            12,
            "[input] period_s = 0",
        ),
        (
            "kind = \"harmonic\"",
            "kind = \"sine\"",
            10,
            "[input] kind: unknown variant `sine`",
        ),
        (
            "m1_kg = 29.5",
            "m1_kg = \"heavy\"",
            4,
            "[structure] m1_kg: invalid type",
        ),
    ];
    for (from, to, line, needle) in cases {
        error_at(&BASE.replace(from, to), *line, &[needle]);
    }
    let rev = |body: &str| {
        BASE.replace(
            "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
            &format!("kind = \"reversals\"\n{body}"),
        )
    };
    error_at(
        &rev("times_s = [0.0, 0.1,\n  0.1]"),
        12,
        &["[input] times_s[2] = 0.1", "strictly increasing"],
    );
    error_at(&rev("times_s = []"), 11, &["[input] times_s is empty"]);
    error_at(
        &rev("half_period_s = 0.1\ninitial_sign = 0.5"),
        12,
        &["[input] initial_sign = 0.5", "1 or -1"],
    );
    error_at(
        &rev("half_period_s = 0"),
        11,
        &["[input] half_period_s = 0"],
    );
    error_at(
        &format!("{BASE}[sensors]\naccel_adc_bits = 0\n"),
        16,
        &["[sensors] accel_adc_bits = 0"],
    );
    error_at(
        &format!("{BASE}[sensors]\nseed = -1\n"),
        16,
        &["[sensors] seed: invalid value"],
    );
    error_at(
        &format!("{BASE}[sensors]\ndisp_noise_rms_m = -1e-6\n"),
        16,
        &["[sensors] disp_noise_rms_m = -0.000001"],
    );
    error_at(
        &BASE.replace("damping_ratio = 0.05", "damping_ratio = "),
        7,
        &["[structure]"],
    );
}

#[test]
fn missing_scene_file() {
    let e = Scene::load("/nonexistent/scene.toml").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("/nonexistent/scene.toml: cannot read"),
        "{e}"
    );
}
