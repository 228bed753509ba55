//! Earthquake records: two-column text and PEER AT2 files, units, and the errors of bad records.

mod common;

use common::{scenes_dir, BASE};
use ssvr_core::structure::STANDARD_GRAVITY;
use ssvr_scene::{Input, Scene, TableMotion, Units};
use std::fs;
use std::path::{Path, PathBuf};

#[test]
fn elcentro_record_in_g() {
    let s = Scene::load(scenes_dir().join("elcentro.toml")).unwrap();
    assert_eq!(s.static_friction_coefficient, 0.25);
    let Input::Record(r) = &s.input else {
        panic!("not a record")
    };
    assert_eq!(r.units, Units::G);
    let TableMotion::Record {
        times_s,
        accel_m_s2,
    } = &r.motion
    else {
        panic!("not a record motion")
    };
    assert_eq!(times_s.len(), 1560);
    assert_eq!(times_s[1559], 31.18);
    assert_eq!(accel_m_s2[0], 0.0063 * STANDARD_GRAVITY);
    let peak = accel_m_s2.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    assert!((peak / STANDARD_GRAVITY - 0.319).abs() < 1e-3, "{peak}");
    // Piecewise linear between samples, zero after the end.
    let mid = s.table_motion().accel(0.01);
    assert!((mid - 0.5 * (0.0063 + 0.00364) * STANDARD_GRAVITY).abs() < 1e-12);
    assert_eq!(s.table_motion().accel(31.2), 0.0);
    assert!(s.rdm_train().is_none());
}

fn record_scene(dir: &Path, file: &str, units: &str, scale: Option<f64>) -> PathBuf {
    let scale = scale.map_or(String::new(), |s| format!("scale = {s}\n"));
    let text = BASE.replace(
        "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143\n",
        &format!("kind = \"record\"\nfile = \"{file}\"\nunits = \"{units}\"\n{scale}"),
    );
    let path = dir.join("scene.toml");
    fs::write(&path, text).unwrap();
    path
}

fn motion(s: &Scene) -> (Vec<f64>, Vec<f64>) {
    match s.table_motion() {
        TableMotion::Record {
            times_s,
            accel_m_s2,
        } => (times_s, accel_m_s2),
        other => panic!("{other:?}"),
    }
}

#[test]
fn two_column_record_and_units() {
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir(dir.path().join("data")).unwrap();
    fs::write(
        dir.path().join("data/rec.txt"),
        "# time accel\n\n0.0  1.0\n0.01, -2.0   # comma-separated\n\t0.02\t0.5\n",
    )
    .unwrap();
    for (units, scale, factor) in [
        ("g", None, STANDARD_GRAVITY),
        ("m/s2", None, 1.0),
        ("gal", Some(2.0), 0.02),
        ("m/s2", Some(-0.5), -0.5),
    ] {
        let s = Scene::load(record_scene(dir.path(), "data/rec.txt", units, scale)).unwrap();
        let (t, a) = motion(&s);
        assert_eq!(t, [0.0, 0.01, 0.02]);
        assert_eq!(a, [factor, -2.0 * factor, 0.5 * factor], "{units}");
        let Input::Record(r) = &s.input else { panic!() };
        assert_eq!(r.path, dir.path().join("data/rec.txt"));
        assert_eq!(r.units.name(), units);
    }
}

#[test]
fn at2_record() {
    let dir = tempfile::tempdir().unwrap();
    let at2 = "PEER NGA STRONG MOTION DATABASE RECORD\n\
               IMPERIAL VALLEY 5/19/40, EL CENTRO ARRAY #9, 180\n\
               ACCELERATION TIME SERIES IN UNITS OF G\n\
               NPTS=    7, DT=   .0100 SEC,\n  \
               .1000000E-01  .2000000E-01 -.3000000E-01  .4000000E-01  .5000000E-01\n  \
               -.6000000E-01  .7000000E-01\n";
    fs::write(dir.path().join("rec.AT2"), at2).unwrap();
    let s = Scene::load(record_scene(dir.path(), "rec.AT2", "g", None)).unwrap();
    let (t, a) = motion(&s);
    assert_eq!(t.len(), 7);
    assert_eq!(t[6], 0.06);
    assert_eq!(a[2], -0.03 * STANDARD_GRAVITY);
    assert_eq!(a[6], 0.07 * STANDARD_GRAVITY);
    // The old header layout "NPTS, DT" after the numbers.
    let old = at2.replace("NPTS=    7, DT=   .0100 SEC,", "    7    .0100    NPTS, DT");
    fs::write(dir.path().join("old.at2"), old).unwrap();
    let s = Scene::load(record_scene(dir.path(), "old.at2", "g", None)).unwrap();
    assert_eq!(motion(&s).0.len(), 7);
    // Too few values: the record file and NPTS are named.
    fs::write(
        dir.path().join("short.at2"),
        at2.replace("  .7000000E-01", ""),
    )
    .unwrap();
    let e = Scene::load(record_scene(dir.path(), "short.at2", "g", None)).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("short.at2:6:") && msg.contains("NPTS = 7"),
        "{msg}"
    );
    // A bad value: its line.
    fs::write(
        dir.path().join("bad.at2"),
        at2.replace("-.6000000E-01", "-.6E-0x"),
    )
    .unwrap();
    let e = Scene::load(record_scene(dir.path(), "bad.at2", "g", None)).unwrap_err();
    assert!(
        e.to_string().contains("bad.at2:6: value \"-.6E-0x\""),
        "{e}"
    );
}

#[test]
fn record_errors_name_the_record_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("0 1\n0.01 2 3\n", 2, "two columns"),
        ("0 1\n# c\n0.01 abc\n", 3, "acceleration \"abc\""),
        ("0 1\n0.01 2\n0.01 3\n", 3, "not after the previous time"),
        ("0 1\n", 0, "at least 2"),
    ];
    for (i, (text, line, needle)) in cases.iter().enumerate() {
        let name = format!("r{i}.txt");
        fs::write(dir.path().join(&name), text).unwrap();
        let scene = record_scene(dir.path(), &name, "g", None);
        let e = Scene::load(&scene).unwrap_err();
        let msg = e.to_string();
        assert_eq!(e.file, dir.path().join(&name), "{msg}");
        if *line > 0 {
            assert_eq!(e.line, Some(*line), "{msg}");
        }
        assert!(msg.contains(needle), "{msg}");
        assert!(msg.contains("scene.toml:11"), "{msg}"); // the referencing key
    }
    // A missing record file: the scene's `file` key.
    let scene = record_scene(dir.path(), "nope.txt", "g", None);
    let e = Scene::load(&scene).unwrap_err();
    assert_eq!(e.file, scene);
    assert_eq!(e.line, Some(11));
    assert!(e.to_string().contains("[input] file = \"nope.txt\""), "{e}");
    // Bad units.
    let scene = record_scene(dir.path(), "r0.txt", "furlongs", None);
    let e = Scene::load(&scene).unwrap_err();
    assert_eq!(e.line, Some(12));
    assert!(
        e.to_string().contains("[input] units: unknown variant"),
        "{e}"
    );
}
