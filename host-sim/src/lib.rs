//! host-sim: scenes, the exact stick-slip truth, sensor models, checks of the recursion against the
//! full-precision library, speed-against-error reports and plots.
//!
//! * [`scene`]: scene files (TOML, SI units) and earthquake records.
//! * [`table_motion`]: the table (ground) acceleration of a scene.
//! * [`truth`]: the exact Coulomb stick-slip truth; [`sensors`]: the sensor models.
//! * [`methods`]: TFM/RFM peaks, traces of ü1 and the recursion-against-closed-form check.
//! * [`model`]: the firmware's estimator models (fixed base, rectangular, stick-slip).
//! * [`run`]: the main job: truth, sensors, reversal detector and the f32 estimator, sample by
//!   sample, streamed to CSV, with error and detection statistics.
//! * [`qemu_runner`]: build, run and decode the firmware's QEMU image; [`qemu_cmd`]: `host-sim
//!   qemu`, every firmware prediction against the host and the closed form.
//! * [`report`]: the data of `bench` (speed against error of every method) and `reproduce` (the
//!   paper's Table 2 and figures).
//! * [`plot`]: the figures: `run --plot`'s, and the PNG figures of `bench` and `reproduce`.
//! * [`cmd`]: the command line, one module per command.
#![deny(missing_docs)]

pub mod cmd;
pub mod methods;
pub mod model;
pub mod plot;
pub mod qemu_cmd;
pub mod qemu_runner;
pub mod report;
pub mod run;
pub mod scene;
pub mod sensors;
pub mod table_motion;
pub mod truth;
