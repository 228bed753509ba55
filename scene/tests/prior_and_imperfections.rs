//! The keys of the controller's prior (`[estimator]`), the sensor imperfections (`[sensors]`
//! offsets, gains, dropouts) and the rest before the input (`[input] start_s`): defaults,
//! values, the prior's defaulting rule, and bad values named with file, line and key.

mod common;
use common::{error_at, parse, BASE};
use ssvr_scene::{Specimen, TableMotion};
use std::path::Path;

#[test]
fn without_the_new_keys_everything_is_as_before() {
    let s = parse(BASE).unwrap();
    assert_eq!(s.estimator.params, *s.structure.params());
    assert_eq!(
        s.estimator.static_friction_coefficient,
        s.static_friction_coefficient
    );
    assert_eq!(s.start_s, 0.0);
    assert_eq!(s.sensors.accel_bias_m_s2, [0.0; 3]);
    assert_eq!(s.sensors.accel_gain_error, [0.0; 3]);
    assert_eq!(s.sensors.disp_bias_m, 0.0);
    assert_eq!(s.sensors.dropout_probability, 0.0);
    assert!(matches!(s.table_motion(), TableMotion::Harmonic { .. }));
}

#[test]
fn the_prior_defaults_key_by_key_to_the_structure() {
    let text = BASE.replace(
        "[input]",
        "[estimator]\nnatural_frequency_hz = 7.3\ndamping_ratio = 0.08\n[input]",
    );
    let s = parse(&text).unwrap();
    let (p, t) = (s.estimator.params, *s.structure.params());
    assert_eq!(p.natural_frequency_hz, 7.3);
    assert_eq!(p.damping_ratio, 0.08);
    assert_eq!(
        (p.m1_kg, p.m2_kg, p.friction_coefficient),
        (t.m1_kg, t.m2_kg, 0.2)
    );
    assert_eq!(t.natural_frequency_hz, 7.0, "the truth keeps [structure]");
    // The prior's static coefficient: the structure's when it is at least the prior's μ ...
    let text = BASE
        .replace(
            "friction_coefficient = 0.2",
            "friction_coefficient = 0.2\nstatic_friction_coefficient = 0.25",
        )
        .replace(
            "[input]",
            "[estimator]\nfriction_coefficient = 0.22\n[input]",
        );
    let s = parse(&text).unwrap();
    assert_eq!(s.estimator.static_friction_coefficient, 0.25);
    // ... else the prior's μ; an explicit one is checked against the prior's μ.
    let text = BASE.replace(
        "[input]",
        "[estimator]\nfriction_coefficient = 0.3\nnatural_period_s = 0.125\n[input]",
    );
    let s = parse(&text).unwrap();
    assert_eq!(s.estimator.static_friction_coefficient, 0.3);
    assert_eq!(s.estimator.params.natural_frequency_hz, 8.0);
    let spec = Specimen::from(&s).prior();
    assert_eq!(spec.structure, s.estimator.params);
    assert_eq!(spec.static_friction_coefficient, 0.3);
}

#[test]
fn sensor_imperfections_and_the_rest_are_read() {
    let text = BASE.replace("[input]", "[input]\nstart_s = 0.5").to_string()
        + "[sensors]\naccel_bias_m_s2 = [0.3, -0.2, 0.1]\naccel_gain_error = [0.0, 0.01, -0.01]\ndisp_bias_m = 1e-3\ndropout_probability = 0.01\n";
    let s = parse(&text).unwrap();
    assert_eq!(s.sensors.accel_bias_m_s2, [0.3, -0.2, 0.1]);
    assert_eq!(s.sensors.accel_gain_error, [0.0, 0.01, -0.01]);
    assert_eq!(s.sensors.disp_bias_m, 1e-3);
    assert_eq!(s.sensors.dropout_probability, 0.01);
    assert_eq!(s.start_s, 0.5);
    let m = s.table_motion();
    assert_eq!(m.accel(0.49), 0.0, "at rest before start_s");
    let plain = parse(BASE).unwrap().table_motion();
    for t in [0.5, 0.51, 0.7, 1.2] {
        assert_eq!(m.accel(t), plain.accel(t - 0.5));
    }
    let spec = Specimen::parse(&text, Path::new("scenes/x.toml")).unwrap();
    assert_eq!(spec.start_s, 0.5);
}

#[test]
fn bad_values_are_named_with_file_line_and_key() {
    let est = |kv: &str| BASE.replace("[input]", &format!("[estimator]\n{kv}\n[input]"));
    // The [estimator] table starts at line 9 in these texts; its key is on line 10.
    error_at(
        &est("damping_ratio = 1.5"),
        10,
        &["[estimator] damping_ratio"],
    );
    error_at(&est("m1_kg = -1.0"), 10, &["[estimator] m1_kg"]);
    error_at(
        &est("static_friction_coefficient = 0.1"),
        10,
        &["[estimator] static_friction_coefficient"],
    );
    error_at(
        &est("natural_frequency_hz = 7.0\nnatural_period_s = 0.1"),
        11,
        &["[estimator] natural_period_s", "not both"],
    );
    error_at(&est("mass = 3.0"), 10, &["unknown", "mass"]);
    let sens = |kv: &str| format!("{BASE}[sensors]\n{kv}\n");
    let line = BASE.lines().count() + 2;
    error_at(
        &sens("accel_bias_m_s2 = [0.1, 0.2]"),
        line,
        &["[sensors] accel_bias_m_s2", "3 finite numbers"],
    );
    error_at(
        &sens("accel_gain_error = [0.0, -1.0, 0.0]"),
        line,
        &["[sensors] accel_gain_error", "> -1"],
    );
    error_at(
        &sens("dropout_probability = 1.0"),
        line,
        &["[sensors] dropout_probability"],
    );
    error_at(&sens("disp_bias_m = nan"), line, &["[sensors] disp_bias_m"]);
    let rest = |v: &str| BASE.replace("[input]", &format!("[input]\nstart_s = {v}"));
    error_at(&rest("-0.1"), 10, &["[input] start_s"]);
    let lag = |v: &str| BASE.replace("[input]", &format!("[input]\ntable_lag_s = {v}"));
    error_at(&lag("-0.001"), 10, &["[input] table_lag_s", ">= 0"]);
    error_at(&lag("inf"), 10, &["[input] table_lag_s"]);
}

/// `[input] table_lag_s`: the truth's table follows the input that late after `start_s`, the
/// plan the controller is told does not; 0 when absent; not for a friction train.
#[test]
fn the_tables_lag_delays_the_truth_not_the_plan() {
    let plain = parse(BASE).unwrap();
    assert_eq!(plain.table_lag_s, 0.0);
    let text = BASE.replace("[input]", "[input]\nstart_s = 0.5\ntable_lag_s = 0.002");
    let s = parse(&text).unwrap();
    assert_eq!((s.start_s, s.table_lag_s), (0.5, 0.002));
    let (truth, plan, input) = (s.table_motion(), s.planned_motion(), s.input_motion());
    for t in [0.3, 0.5, 0.501, 0.5019] {
        assert_eq!(truth.accel(t), 0.0, "the table at rest at t = {t}");
    }
    for t in [0.502, 0.51, 0.7, 1.2] {
        assert_eq!(truth.accel(t), input.accel(t - 0.502), "t = {t}");
    }
    for t in [0.5, 0.501, 0.51, 1.2] {
        assert_eq!(plan.accel(t), input.accel(t - 0.5), "t = {t}");
    }
    let reversals = "duration_s = 1.0\n[structure]\nm1_kg = 2.0\nm2_kg = 1.0\nnatural_period_s = 0.2\n\
                     damping_ratio = 0.02\nfriction_coefficient = 0.2\n[input]\nkind = \"reversals\"\n\
                     half_period_s = 0.1\ntable_lag_s = 0.001\n[sampling]\nrate_hz = 1000.0\n";
    let e = parse(reversals).unwrap_err().to_string();
    assert!(e.contains("table_lag_s") && e.contains("reversals"), "{e}");
}

#[test]
fn a_rest_before_a_record_shifts_its_times_and_keeps_the_duration() {
    let dir = common::scenes_dir();
    let plain = ssvr_scene::Scene::load(dir.join("elcentro.toml")).unwrap();
    let text = std::fs::read_to_string(dir.join("elcentro.toml"))
        .unwrap()
        .replace("[input]", "[input]\nstart_s = 0.75");
    let late = ssvr_scene::Scene::parse(&text, &dir.join("late.toml")).unwrap();
    assert_eq!(late.start_s, 0.75);
    // The run still covers [0, duration_s): the rest is part of it.
    assert_eq!(
        (late.samples, late.duration_s),
        (plain.samples, plain.duration_s)
    );
    let (m, p) = (late.table_motion(), plain.table_motion());
    for t in [0.0, 0.3, 0.7499] {
        assert_eq!(m.accel(t), 0.0, "at rest at t = {t}");
    }
    for t in [0.75, 0.8, 1.0123, 3.3, 10.0] {
        assert_eq!(m.accel(t), p.accel(t - 0.75), "t = {t}");
    }
}

#[test]
fn more_keys_and_their_errors() {
    // Integers are numbers too; a period instead of a frequency; static friction given alone.
    let text = BASE.replace(
        "[input]",
        "[estimator]\nnatural_period_s = 0.25\nstatic_friction_coefficient = 0.3\n[input]",
    ) + "[sensors]\naccel_bias_m_s2 = [0, 1, -1]\naccel_gain_error = [0, 0, 0.02]\n";
    let s = parse(&text).unwrap();
    assert_eq!(s.estimator.params.natural_frequency_hz, 4.0);
    assert_eq!(s.estimator.static_friction_coefficient, 0.3);
    assert_eq!(s.estimator.params.friction_coefficient, 0.2);
    assert_eq!(s.sensors.accel_bias_m_s2, [0.0, 1.0, -1.0]);
    assert_eq!(s.sensors.accel_gain_error, [0.0, 0.0, 0.02]);
    // The board's view of a scene (no input needed) reads the same prior.
    let spec = Specimen::parse(&text, Path::new("scenes/x.toml")).unwrap();
    assert_eq!(spec.estimator, s.estimator);
    assert_eq!(spec.prior().structure.natural_frequency_hz, 4.0);
    assert_eq!(spec.prior().static_friction_coefficient, 0.3);
    assert_eq!(spec.sensors, s.sensors);

    let est = |kv: &str| BASE.replace("[input]", &format!("[estimator]\n{kv}\n[input]"));
    error_at(
        &est("natural_period_s = -0.1"),
        10,
        &["[estimator] natural_period_s = -0.1", "expected"],
    );
    error_at(
        &est("natural_frequency_hz = 0.0"),
        10,
        &["[estimator] natural_frequency_hz = 0", "expected"],
    );
    error_at(&est("m2_kg = inf"), 10, &["[estimator] m2_kg", "finite"]);
    error_at(
        &est("friction_coefficient = -0.2"),
        10,
        &["[estimator] friction_coefficient = -0.2"],
    );
    // The estimator's own static coefficient is checked against its own kinetic one.
    error_at(
        &est("friction_coefficient = 0.3\nstatic_friction_coefficient = 0.25"),
        11,
        &["[estimator] static_friction_coefficient = 0.25", ">="],
    );
    let sens = |kv: &str| format!("{BASE}[sensors]\n{kv}\n");
    let line = BASE.lines().count() + 2;
    error_at(
        &sens("accel_bias_m_s2 = [0.1, nan, 0.2]"),
        line,
        &["[sensors] accel_bias_m_s2", "3 finite numbers"],
    );
    error_at(
        &sens("accel_gain_error = [0.0, 0.0, 0.0, 0.0]"),
        line,
        &["[sensors] accel_gain_error", "3 finite numbers"],
    );
    error_at(
        &sens("dropout_probability = -0.01"),
        line,
        &["[sensors] dropout_probability = -0.01", "expected"],
    );
    let rest = |v: &str| BASE.replace("[input]", &format!("[input]\nstart_s = {v}"));
    error_at(&rest("inf"), 10, &["[input] start_s", "finite"]);
    let reversals = BASE.replace(
        "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
        "kind = \"reversals\"\nhalf_period_s = 0.0715\nstart_s = 0.5",
    );
    error_at(
        &reversals,
        12,
        &["[input] start_s = 0.5", "kind = \"reversals\""],
    );
}
