//! Replay scenes (`[recording]`): values, defaults and the errors (file, line, key) of bad ones.

use ssvr_scene::{ReplayScene, Scene, SceneError, SlipUnits, Specimen, Timebase, Units};
use std::path::{Path, PathBuf};

/// A minimal valid replay scene.
const REPLAY: &str = r#"name = "r"
[structure]
m1_kg = 29.5
m2_kg = 1.75
natural_frequency_hz = 7.0
damping_ratio = 0.05
friction_coefficient = 0.2
[recording]
file = "test-07.csv"
time_column = "Time (s)"
table_accel_column = "A table"
base_accel_column = "A base"
top_accel_column = "A top"
slip_column = "LVDT"
accel_units = "g"
slip_units = "mm"
"#;

fn parse(text: &str) -> Result<ReplayScene, SceneError> {
    ReplayScene::parse(text, Path::new("scenes/x.toml"))
}

/// The error of `text`, checked to name the file, `line` and every one of `needles`.
fn error_at(text: &str, line: usize, needles: &[&str]) {
    let e = parse(text).expect_err("the scene must be rejected");
    let msg = e.to_string();
    assert_eq!(e.line, Some(line), "{msg}");
    assert!(msg.starts_with(&format!("scenes/x.toml:{line}: ")), "{msg}");
    for n in needles {
        assert!(msg.contains(n), "{msg:?} lacks {n:?}");
    }
}

#[test]
fn good_recording_parses() {
    let s = parse(REPLAY).unwrap();
    assert_eq!(s.name, "r");
    let r = &s.recording;
    assert_eq!(r.file, PathBuf::from("scenes/test-07.csv"));
    assert_eq!(r.file_as_given, "test-07.csv");
    assert_eq!(r.time, Timebase::Column("Time (s)".into()));
    assert_eq!(r.table_accel_column, "A table");
    assert_eq!(r.base_accel_column.as_deref(), Some("A base"));
    assert_eq!(r.top_accel_column.as_deref(), Some("A top"));
    assert_eq!(r.slip_column.as_deref(), Some("LVDT"));
    assert_eq!(r.accel_units, Units::G);
    assert_eq!(r.slip_units, SlipUnits::Mm);
    assert_eq!(r.slip_units.factor(), 1e-3);
    assert_eq!(r.start_s, 0.0);
    let sp = s.specimen(1000.0);
    assert_eq!(sp.rate_hz, 1000.0);
    assert_eq!(sp.prior().sample_rate_hz, 1000.0);
    assert_eq!(sp.structure, s.structure);
}

#[test]
fn rate_units_optional_columns_and_start() {
    let text = REPLAY
        .replace("time_column = \"Time (s)\"", "rate_hz = 1000")
        .replace("base_accel_column = \"A base\"\n", "")
        .replace("top_accel_column = \"A top\"\n", "")
        .replace("slip_column = \"LVDT\"\n", "")
        .replace("slip_units = \"mm\"\n", "start_s = 0.5\n")
        .replace("accel_units = \"g\"", "accel_units = \"gal\"")
        .replace("file = \"test-07.csv\"", "file = \"/abs/t.csv\"");
    let s = parse(&text).unwrap();
    let r = &s.recording;
    assert_eq!(r.time, Timebase::Rate(1000.0));
    assert_eq!(r.file, PathBuf::from("/abs/t.csv"));
    assert_eq!(r.base_accel_column, None);
    assert_eq!(r.top_accel_column, None);
    assert_eq!(r.slip_column, None);
    assert_eq!(r.slip_units, SlipUnits::M);
    assert_eq!(r.accel_units, Units::Gal);
    assert_eq!(r.start_s, 0.5);
    assert_eq!(s.specimen(1000.0).start_s, 0.5);
    let ms2 = parse(&REPLAY.replace("\"g\"", "\"m/s2\"")).unwrap();
    assert_eq!(ms2.recording.accel_units, Units::MPerS2);
}

#[test]
fn missing_column_key() {
    // A missing required key: the TOML layer names the table.
    let text = REPLAY.replace("table_accel_column = \"A table\"\n", "");
    let e = parse(&text).unwrap_err().to_string();
    assert!(e.starts_with("scenes/x.toml:"), "{e}");
    assert!(
        e.contains("[recording]") && e.contains("table_accel_column"),
        "{e}"
    );
    let text = REPLAY.replace("file = \"test-07.csv\"\n", "");
    let e = parse(&text).unwrap_err().to_string();
    assert!(e.contains("missing key `file`"), "{e}");
    // A slip column needs its units.
    error_at(
        &REPLAY.replace("slip_units = \"mm\"\n", ""),
        8,
        &["[recording]", "missing key `slip_units`"],
    );
    // An empty column name.
    error_at(
        &REPLAY.replace("\"A top\"", "\"\""),
        13,
        &["[recording] top_accel_column", "must name a column"],
    );
}

#[test]
fn bad_units() {
    error_at(
        &REPLAY.replace("accel_units = \"g\"", "accel_units = \"ft/s2\""),
        15,
        &["[recording]", "accel_units", "ft/s2"],
    );
    error_at(
        &REPLAY.replace("slip_units = \"mm\"", "slip_units = \"in\""),
        16,
        &["[recording]", "slip_units", "in"],
    );
}

#[test]
fn time_column_and_rate_exactly_one() {
    error_at(
        &REPLAY.replace(
            "time_column = \"Time (s)\"",
            "time_column = \"Time (s)\"\nrate_hz = 1000.0",
        ),
        11,
        &["[recording] rate_hz", "either `time_column` or `rate_hz`"],
    );
    error_at(
        &REPLAY.replace("time_column = \"Time (s)\"\n", ""),
        8,
        &["[recording]", "missing key `time_column` or `rate_hz`"],
    );
    error_at(
        &REPLAY.replace("time_column = \"Time (s)\"", "rate_hz = -5.0"),
        10,
        &["[recording] rate_hz = -5", "out of range"],
    );
    error_at(
        &REPLAY.replace("slip_units = \"mm\"", "slip_units = \"mm\"\nstart_s = -1.0"),
        17,
        &["[recording] start_s = -1", "out of range"],
    );
}

#[test]
fn unknown_keys_and_what_the_recording_sets() {
    error_at(
        &REPLAY.replace("slip_units = \"mm\"", "slip_units = \"mm\"\ngain = 2.0"),
        17,
        &["[recording]", "unknown key `gain`"],
    );
    error_at(
        &REPLAY.replace("name = \"r\"\n", "name = \"r\"\nduration_s = 1.0\n"),
        2,
        &["duration_s does not apply", "[recording]"],
    );
    error_at(
        &format!("{REPLAY}[sampling]\nrate_hz = 1000.0\n"),
        17,
        &["[sampling] does not apply", "[recording]"],
    );
    error_at(
        &format!("{REPLAY}[input]\nkind = \"harmonic\"\namplitude_m_s2 = 1.0\nperiod_s = 0.2\n"),
        17,
        &["[input] does not apply"],
    );
    // Structure errors are the scene's own.
    error_at(
        &REPLAY.replace("damping_ratio = 0.05", "damping_ratio = 1.5"),
        6,
        &["[structure] damping_ratio = 1.5"],
    );
    // A replay scene needs a recording.
    let no_rec = &REPLAY[..REPLAY.find("[recording]").unwrap()];
    let e = parse(no_rec).unwrap_err().to_string();
    assert!(e.contains("missing table [recording]"), "{e}");
}

#[test]
fn simulated_scenes_reject_a_recording() {
    let text = format!(
        "duration_s = 1.0\n[input]\nkind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143\n\
         [sampling]\nrate_hz = 1000.0\n{}",
        &REPLAY[REPLAY.find("[structure]").unwrap()..]
    );
    let e = Scene::parse(&text, Path::new("scenes/x.toml")).unwrap_err();
    assert_eq!(e.line, Some(14), "{e}");
    assert!(e.to_string().contains("host-sim replay"), "{e}");
    let e = Specimen::parse(&text, Path::new("scenes/x.toml")).unwrap_err();
    assert!(e.to_string().contains("host-sim replay"), "{e}");
}
