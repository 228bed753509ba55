//! host-sim: scenes, the exact stick-slip truth, sensor models, checks of the recursion against the
//! full-precision library, speed-against-error reports and plots.
//!
//! * [`scene`]: scene files (TOML, SI units) and earthquake records (the `ssvr-scene` crate).
//! * [`methods`]: TFM/RFM peaks, traces of ü1 and the recursion-against-closed-form check.
//! * [`table_motion`]: the table (ground) acceleration of a scene (from `ssvr-scene`).
//! * [`pipeline`]: the host's side of the one pipeline (`ssvr_proto`): the plan of a scene and a
//!   model, and the pipeline built from it, which `run` predicts with;
//! * [`qemu`]: `host-sim qemu`, the firmware under QEMU, every prediction against the host's run
//!   of the same pipeline and a full-precision reference.
//! * [`run`]: the main job: truth, sensors, reversal detector and the f32 estimator, sample by
//!   sample, streamed to CSV, with error and detection statistics; [`plot`]: its figure.
//! * [`bench`]: `host-sim bench`, speed against error of every method; [`reproduce`]: `host-sim
//!   reproduce`, the paper's Table 2 and figures; [`plots`]: their PNG figures.
#![deny(missing_docs)]

pub mod bench;
pub mod methods;
pub mod model;
pub mod pipeline;
pub mod plot;
pub mod plots;
pub mod qemu;
pub mod reproduce;
pub mod run;
pub mod sensors;
pub mod truth;

// Scene files live in the ssvr-scene crate (shared with the firmware's build script); these
// re-exports keep the paths `crate::scene::...` and `crate::table_motion::...`.
pub use ssvr_scene as scene;
pub use ssvr_scene::table_motion;
