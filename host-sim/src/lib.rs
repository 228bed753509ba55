//! host-sim: scenes, the exact stick-slip truth, sensor models, checks of the recursion against the
//! full-precision library, speed-against-error reports and plots.
//!
//! * [`scene`]: scene files (TOML, SI units) and earthquake records.
//! * [`methods`]: TFM/RFM peaks, traces of ü1 and the recursion-against-closed-form check.
//! * [`table_motion`]: the table (ground) acceleration of a scene.
#![deny(missing_docs)]

pub mod methods;
pub mod scene;
pub mod sensors;
pub mod table_motion;
pub mod truth;
