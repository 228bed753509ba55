//! The specimen part of a scene: structure, friction, gravity, sample rate, sensors and board
//! settings, without the table motion. The firmware's build script reads its scene this way: a
//! board scene (`firmware/scenes/board.toml`) has no `[input]` and no `duration_s`.
//!
//! The document goes through the same walk as a full [`Scene`](crate::Scene): unknown keys and
//! bad values are the same errors; `duration_s` and `[input]` may be absent and are validated
//! (record file included) when present.

use crate::board::BoardSettings;
use crate::document::{read_scene_file, Motion};
use crate::error::SceneError;
use crate::estimator::Prior;
use crate::parse::ParseContext;
use crate::scene::Scene;
use crate::sensors::Sensors;
use ssvr_core::{FrictionLaw, Structure};
use std::path::{Path, PathBuf};

/// A validated specimen: everything of a scene but its table motion.
#[derive(Debug, Clone, PartialEq)]
pub struct Specimen {
    /// Name (the `name` key, else the file stem).
    pub name: String,
    /// The file the specimen came from (None when taken from a scene without one).
    pub source: Option<PathBuf>,
    /// The structure (its gravity is the scene's `gravity_m_s2`; its parameters are
    /// [`Structure::params`]).
    pub structure: Structure,
    /// Static friction coefficient μs ≥ μ (≥ μ_slow for a velocity-dependent law).
    pub static_friction_coefficient: f64,
    /// The friction law of the interface (`[friction]`; Coulomb without it).
    pub friction: FrictionLaw,
    /// Gravity (m/s²): `gravity_m_s2`, default standard gravity.
    pub gravity_m_s2: f64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Sensor models.
    pub sensors: Sensors,
    /// The board image's ADC configuration and channel scaling, defaults resolved.
    pub board: BoardSettings,
    /// The estimator's prior (`[estimator]`; the specimen itself without it).
    pub estimator: Prior,
    /// The table at rest until then (s, `[input] start_s`; 0 without it).
    pub start_s: f64,
}

impl Specimen {
    /// Read and validate the specimen part of a scene file.
    pub fn load(path: impl AsRef<Path>) -> Result<Specimen, SceneError> {
        let path = path.as_ref();
        Specimen::parse(&read_scene_file(path)?, path)
    }

    /// Parse and validate the specimen part of scene text; `origin` names the file in messages
    /// and anchors relative record paths.
    pub fn parse(text: &str, origin: &Path) -> Result<Specimen, SceneError> {
        let cx = ParseContext { src: text, origin };
        let doc = cx.document(&cx.raw()?, Motion::Optional)?;
        Ok(Specimen {
            name: doc.name,
            source: Some(origin.to_path_buf()),
            gravity_m_s2: doc.structure.g(),
            structure: doc.structure,
            static_friction_coefficient: doc.static_friction_coefficient,
            friction: doc.friction,
            rate_hz: doc.rate_hz,
            sensors: doc.sensors,
            board: doc.board,
            estimator: doc.prior,
            start_s: doc.start_s,
        })
    }
}

impl From<&Scene> for Specimen {
    /// The specimen of a full scene.
    fn from(scene: &Scene) -> Specimen {
        Specimen {
            name: scene.name.clone(),
            source: scene.source.clone(),
            structure: scene.structure,
            static_friction_coefficient: scene.static_friction_coefficient,
            friction: scene.friction,
            gravity_m_s2: scene.structure.g(),
            rate_hz: scene.rate_hz,
            sensors: scene.sensors.clone(),
            board: scene.board,
            estimator: scene.estimator,
            start_s: scene.start_s,
        }
    }
}

impl Specimen {
    /// What the controller is told (`ssvr_proto::Specimen`, the input of its plan): the
    /// estimator's prior of the structure and static friction (`[estimator]`), the sample rate,
    /// sensor noise levels and displacement range.
    pub fn prior(&self) -> ssvr_proto::Specimen {
        ssvr_proto::Specimen {
            structure: self.estimator.params,
            static_friction_coefficient: self.estimator.static_friction_coefficient,
            sample_rate_hz: self.rate_hz,
            disp_noise_rms_m: self.sensors.disp_noise_rms_m,
            accel_noise_rms_m_s2: self.sensors.accel_noise_rms_m_s2,
            disp_range_m: self.sensors.disp_range_m,
            friction: self.estimator.friction,
        }
    }
}
