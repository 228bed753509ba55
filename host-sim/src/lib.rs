//! host-sim: scenes, the exact stick-slip truth, sensor models, checks of the recursion against the
//! full-precision library, speed-against-error reports and plots.
//!
//! * [`scene`]: scene files (TOML, SI units) and earthquake records.
//! * [`methods`]: TFM/RFM peaks, traces of ü1 and the recursion-against-closed-form check.
//! * [`table_motion`]: the table (ground) acceleration of a scene.
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
pub mod scene;
pub mod sensors;
pub mod table_motion;
pub mod truth;
