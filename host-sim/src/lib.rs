//! host-sim: scenes, the exact stick-slip truth, sensor models, checks of the recursion against the
//! full-precision library, speed-against-error reports and plots.
//!
//! * [`scene`]: scene files (TOML, SI units) and earthquake records (the `ssvr-scene` crate);
//!   [`table_motion`]: the table (ground) acceleration of a scene.
//! * [`truth`]: the exact Coulomb stick-slip truth; [`sensors`]: the sensor models.
//! * [`methods`]: TFM/RFM peaks, traces of ü1 and the recursion-against-closed-form check.
//! * [`model`]: which estimator model a scene calls for (the models are `ssvr_proto`'s).
//! * [`pipeline`]: the host's side of the one pipeline (`ssvr_proto`): the plan of a scene and a
//!   model, and the pipeline built from it, which `run` predicts with.
//! * [`run`]: the main job: truth, sensors, the pipeline (detector and the f32 estimator), sample
//!   by sample, streamed to CSV, with error and detection statistics.
//! * [`replay`]: a recorded test (a scene's `[recording]` CSV) through the same pipeline as `run`.
//! * [`monitor`]: the firmware's defmt stream decoded as it arrives into `replay`'s CSV.
//! * [`qemu`]: `host-sim qemu`, the firmware under QEMU, every prediction against the host's run
//!   of the same pipeline and a full-precision reference.
//! * [`report`]: the data of `bench` (speed against error of every method) and `reproduce` (the
//!   paper's Table 2 and figures).
//! * [`plot`]: the figures: `run --plot`'s, and the PNG figures of `bench` and `reproduce`.
//! * [`cmd`]: the command line, one module per command.
#![deny(missing_docs)]

pub mod cmd;
pub mod methods;
pub mod model;
pub mod monitor;
pub mod pipeline;
pub mod plot;
pub mod qemu;
pub mod replay;
pub mod report;
pub mod run;
pub mod sensors;
pub mod truth;

// Scene files live in the ssvr-scene crate (shared with the firmware's build script); these
// re-exports keep the paths `crate::scene::...` and `crate::table_motion::...`.
pub use ssvr_scene as scene;
pub use ssvr_scene::table_motion;
