//! ssvr-scene: scene files of the SSVR estimator, a structure, a table input, a sample rate and
//! sensor models, in TOML with SI units, and the earthquake records they reference. One strict
//! parser, used by host-sim and the firmware's build script.
//!
//! ```toml
//! name = "table 1 specimen"          # optional
//! duration_s = 10.0                  # samples t_k = k / rate_hz, k = 0 .. round(duration_s*rate_hz)-1
//! gravity_m_s2 = 9.80665             # optional, this default
//! [structure]
//! m1_kg = 29.5
//! m2_kg = 1.75
//! natural_frequency_hz = 7.0         # or natural_period_s (exactly one of the two)
//! damping_ratio = 0.05
//! friction_coefficient = 0.2
//! static_friction_coefficient = 0.25 # optional, >= friction_coefficient ([friction] mu_slow)
//! [friction]                         # optional; without it Coulomb friction
//! law = "velocity-dependent"         # or "coulomb"
//! mu_slow = 0.12                     # mu(v) = mu_fast - (mu_fast - mu_slow) exp(-rate_s_m |v|)
//! rate_s_m = 30.0                    # mu_fast = friction_coefficient
//! [input]
//! kind = "harmonic"                  # amplitude_m_s2 * sin(2*pi*t/period_s)
//! amplitude_m_s2 = 2.0
//! period_s = 0.143
//! [sampling]
//! rate_hz = 10000.0
//! [sensors]                          # optional, every key optional
//! seed = 1
//! ```
//!
//! `kind = "reversals"` prescribes the friction train itself (`half_period_s` or `times_s`, optional
//! `initial_sign`); `kind = "record"` reads an earthquake record (`file`, `units`, optional `scale`):
//! two-column text or a PEER NGA `.AT2` file. See the README for the full contract.
//!
//! Every error names the file, the line and the key: `scenes/x.toml:7: [structure] damping_ratio =
//! 1.2 is out of range: expected 0 <= damping ratio < 1`.
//!
//! Board settings, for the firmware's board image, are optional in every scene: `[adc]` (`gains`,
//! `osr`) and `[sensors.<channel>]` (`volts_per_unit`, `offset_volts`) for the channels
//! `table_accel`, `base_accel`, `top_accel` and `displacement`; see [`BoardSettings`].
//!
//! Entry points:
//! * [`Scene::load`] / [`Scene::parse`]: a full scene (host-sim): `duration_s` and `[input]`
//!   required.
//! * [`Specimen::load`] / [`Specimen::parse`]: the specimen part only (the firmware's build
//!   script): structure, friction, gravity, rate, sensors and board settings; `duration_s` and
//!   `[input]` optional, validated when present. Same walk, same messages.
//! * [`parse_record`]: an earthquake record file on its own.
//! * [`ReplayScene::load`] / [`ReplayScene::parse`]: a recorded test to replay (`host-sim
//!   replay`): the specimen and a `[recording]` (see [`Recording`]) instead of `duration_s`,
//!   `[input]` and `[sampling]`; the other entry points reject a `[recording]`.
//!
//! The parser's parts are private modules whose types are re-exported here; [`table_motion`] is
//! the table acceleration of a scene.
#![deny(missing_docs)]

mod board;
mod document;
mod error;
mod estimator;
mod friction;
mod input;
mod parse;
mod record;
mod recording;
mod scene;
mod sensors;
mod specimen;
mod structure;
pub mod table_motion;
mod units;

pub use board::{
    BoardSettings, ChannelScale, ADC_FULL_SCALE_V, ADC_ODR_CLOCK_HZ, ADC_OSRS, CHANNELS,
};
pub use error::SceneError;
pub use estimator::Prior;
pub use input::{Input, Reversals};
pub use record::{parse_record, Record};
pub use recording::{Recording, ReplayScene, SlipUnits, Timebase};
pub use scene::{Scene, MAX_SAMPLES};
pub use sensors::Sensors;
pub use specimen::Specimen;
pub use table_motion::TableMotion;
pub use units::Units;
