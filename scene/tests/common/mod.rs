//! Helpers shared by the scene tests: a minimal valid scene and error checks.
#![allow(dead_code)]

use ssvr_scene::{Scene, SceneError};
use std::path::{Path, PathBuf};

/// A minimal valid scene (harmonic input, 1 s at 1 kHz).
pub const BASE: &str = r#"name = "t"
duration_s = 1.0
[structure]
m1_kg = 29.5
m2_kg = 1.75
natural_frequency_hz = 7.0
damping_ratio = 0.05
friction_coefficient = 0.2
[input]
kind = "harmonic"
amplitude_m_s2 = 2.0
period_s = 0.143
[sampling]
rate_hz = 1000.0
"#;

pub fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, Path::new("scenes/x.toml"))
}

/// The error of `text`, checked to name the file, `line` and every one of `needles`.
pub fn error_at(text: &str, line: usize, needles: &[&str]) -> SceneError {
    let e = parse(text).expect_err("the scene must be rejected");
    let msg = e.to_string();
    assert_eq!(e.line, Some(line), "{msg}");
    assert!(msg.starts_with(&format!("scenes/x.toml:{line}: ")), "{msg}");
    for n in needles {
        assert!(msg.contains(n), "{msg:?} lacks {n:?}");
    }
    e
}

pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("host-sim")
        .join("scenes")
}
