//! ssvr-scene: scene files of the SSVR estimator (TOML, SI units) and earthquake records.
#![deny(missing_docs)]

mod scene;
pub mod table_motion;

pub use scene::{
    parse_record, Input, Record, Reversals, Scene, SceneError, Sensors, Units, MAX_SAMPLES,
};
