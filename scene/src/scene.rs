//! A validated scene: structure, table input, duration, sample rate and sensor models.

use crate::error::SceneError;
use crate::input::Input;
use crate::parse::{ParseContext, RawScene};
use crate::sensors::Sensors;
use crate::table_motion::TableMotion;
use ssvr_core::structure::STANDARD_GRAVITY;
use ssvr_core::{ReversalTrain, Structure, StructureParams};
use std::path::{Path, PathBuf};

/// Largest sample count a scene may ask for (2^53: every index is exact in f64).
pub const MAX_SAMPLES: f64 = 9_007_199_254_740_992.0;

/// A validated scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Name (the `name` key, else the file stem).
    pub name: String,
    /// The file the scene came from (None for the built-in default).
    pub source: Option<PathBuf>,
    /// Duration (s).
    pub duration_s: f64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Number of samples, round(duration_s · rate_hz) ≥ 1.
    pub samples: u64,
    /// The structure (its gravity is the scene's `gravity_m_s2`).
    pub structure: Structure,
    /// Static friction coefficient μs ≥ μ.
    pub static_friction_coefficient: f64,
    /// The input.
    pub input: Input,
    /// Sensor models.
    pub sensors: Sensors,
}

impl Scene {
    /// The built-in default: the paper's Table 1 specimen (m1 29.5 kg, m2 1.75 kg, 7 Hz, ξ 0.05,
    /// μ 0.2) on 2 m/s² harmonic table motion of period 0.143 s, 10 s at 10 kHz.
    /// Identical to `host-sim/scenes/table1.toml`.
    pub fn default_scene() -> Scene {
        let params = StructureParams {
            m1_kg: 29.5,
            m2_kg: 1.75,
            natural_frequency_hz: 7.0,
            damping_ratio: 0.05,
            friction_coefficient: 0.2,
            gravity_m_s2: STANDARD_GRAVITY,
        };
        #[allow(clippy::expect_used)]
        let structure = Structure::new(params).expect("the built-in default structure is valid");
        Scene {
            name: "table 1 specimen".into(),
            source: None,
            duration_s: 10.0,
            rate_hz: 10_000.0,
            samples: 100_000,
            structure,
            static_friction_coefficient: 0.2,
            input: Input::Harmonic {
                amplitude_m_s2: 2.0,
                period_s: 0.143,
            },
            sensors: Sensors::default(),
        }
    }

    /// Read and validate a scene file. Record files resolve against the scene file's folder.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: path.to_path_buf(),
            line: None,
            message: format!("cannot read the scene file: {e}"),
        })?;
        Scene::parse(&text, path)
    }

    /// Parse and validate scene text; `origin` names the file in messages and anchors relative
    /// record paths (its parent folder).
    pub fn parse(text: &str, origin: &Path) -> Result<Scene, SceneError> {
        let cx = ParseContext { src: text, origin };
        let raw: RawScene = toml::from_str(text).map_err(|e| cx.toml_error(&e))?;
        cx.build(raw)
    }

    /// Time of sample k (s): k / rate_hz.
    pub fn time(&self, k: u64) -> f64 {
        k as f64 / self.rate_hz
    }

    /// gμ (m/s²), the unit of errors.
    pub fn gmu(&self) -> f64 {
        self.structure.gmu()
    }

    /// The table acceleration (none for a reversals scene).
    pub fn table_motion(&self) -> TableMotion {
        match &self.input {
            Input::Harmonic {
                amplitude_m_s2,
                period_s,
            } => TableMotion::Harmonic {
                amplitude_m_s2: *amplitude_m_s2,
                period_s: *period_s,
            },
            Input::Reversals(_) => TableMotion::None,
            Input::Record(r) => r.motion.clone(),
        }
    }

    /// The friction train of the rectangular Duhamel method: a reversals scene's own train, or for a
    /// harmonic scene the paper's train (reversals at k·T/2, first at 0 with sign +1). None for a
    /// record scene (its reversals come from the stick-slip simulation).
    pub fn rdm_train(&self) -> Option<ReversalTrain<'_>> {
        match &self.input {
            Input::Harmonic { period_s, .. } => Some(ReversalTrain::Periodic {
                first_s: 0.0,
                half_period_s: period_s / 2.0,
                initial_sign: 1.0,
            }),
            Input::Reversals(r) => Some(r.train()),
            Input::Record(_) => None,
        }
    }
}

impl ParseContext<'_> {
    /// The whole scene.
    fn build(&self, raw: RawScene) -> Result<Scene, SceneError> {
        let duration = self.check(
            None,
            "duration_s",
            &raw.duration_s,
            *raw.duration_s.get_ref() > 0.0,
            "duration_s > 0 s",
        )?;
        let gravity = match &raw.gravity_m_s2 {
            Some(g) => self.check(
                None,
                "gravity_m_s2",
                g,
                *g.get_ref() > 0.0,
                "gravity_m_s2 > 0 m/s^2",
            )?,
            None => STANDARD_GRAVITY,
        };
        let (structure, mu_s) = self.structure(&raw.structure, gravity, &raw.gravity_m_s2)?;
        let rate_v = &raw.sampling.get_ref().rate_hz;
        let rate = self.check(
            Some("sampling"),
            "rate_hz",
            rate_v,
            *rate_v.get_ref() > 0.0,
            "rate_hz > 0 Hz",
        )?;
        let n = (duration * rate).round();
        if !(1.0..=MAX_SAMPLES).contains(&n) {
            return Err(self.err(
                raw.duration_s.span(),
                format!(
                    "duration_s = {duration} at [sampling] rate_hz = {rate} gives {n} samples: \
                     expected 1 <= round(duration_s * rate_hz) <= 2^53"
                ),
            ));
        }
        let input = self.input(&raw.input)?;
        let sensors = match &raw.sensors {
            Some(s) => self.sensors(s.get_ref())?,
            None => Sensors::default(),
        };
        let name = raw.name.unwrap_or_else(|| {
            self.origin
                .file_stem()
                .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
        });
        Ok(Scene {
            name,
            source: Some(self.origin.to_path_buf()),
            duration_s: duration,
            rate_hz: rate,
            samples: n as u64,
            structure,
            static_friction_coefficient: mu_s,
            input,
            sensors,
        })
    }
}
