//! A validated scene: structure, table input, duration, sample rate and sensor models.

use crate::board::BoardSettings;
use crate::document::{read_scene_file, Motion};
use crate::error::SceneError;
use crate::estimator::Prior;
use crate::input::Input;
use crate::parse::ParseContext;
use crate::sensors::Sensors;
use crate::table_motion::TableMotion;
use ssvr_core::structure::STANDARD_GRAVITY;
use ssvr_core::{FrictionLaw, ReversalTrain, Structure, StructureParams};
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
    /// Static friction coefficient μs ≥ μ (≥ μ_slow for a velocity-dependent law).
    pub static_friction_coefficient: f64,
    /// The friction law of the interface (`[friction]`; Coulomb without it).
    pub friction: FrictionLaw,
    /// The estimator's prior (`[estimator]`; the specimen itself without it).
    pub estimator: Prior,
    /// The table at rest until then (s, `[input] start_s`; 0: the input starts at once).
    pub start_s: f64,
    /// How late the simulated table follows the planned input (s, `[input] table_lag_s`; 0:
    /// it follows it exactly). The truth's table motion ([`Self::table_motion`]) is delayed by
    /// it, the plan the controller is told ([`Self::planned_motion`]) is not.
    pub table_lag_s: f64,
    /// The input.
    pub input: Input,
    /// Sensor models.
    pub sensors: Sensors,
    /// The board image's ADC configuration and channel scaling (defaults unless the scene sets
    /// `[adc]` or `[sensors.<channel>]`).
    pub board: BoardSettings,
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
            friction: FrictionLaw::Coulomb,
            estimator: Prior::exact(&structure, 0.2, FrictionLaw::Coulomb),
            start_s: 0.0,
            table_lag_s: 0.0,
            input: Input::Harmonic {
                amplitude_m_s2: 2.0,
                period_s: 0.143,
            },
            sensors: Sensors::default(),
            board: BoardSettings::defaults(10_000.0, &Sensors::default()),
        }
    }

    /// Read and validate a scene file. Record files resolve against the scene file's folder.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        Scene::parse(&read_scene_file(path)?, path)
    }

    /// Parse and validate scene text; `origin` names the file in messages and anchors relative
    /// record paths (its parent folder).
    pub fn parse(text: &str, origin: &Path) -> Result<Scene, SceneError> {
        let cx = ParseContext { src: text, origin };
        let doc = cx.document(&cx.raw()?, Motion::Required)?;
        // The walk has required both (this is a full scene).
        let (Some((duration_s, samples)), Some(input)) = (doc.duration, doc.input) else {
            return Err(cx.err(0..0, "missing key `duration_s` or table [input]".into()));
        };
        Ok(Scene {
            name: doc.name,
            source: Some(origin.to_path_buf()),
            duration_s,
            rate_hz: doc.rate_hz,
            samples,
            structure: doc.structure,
            static_friction_coefficient: doc.static_friction_coefficient,
            friction: doc.friction,
            estimator: doc.prior,
            start_s: doc.start_s,
            table_lag_s: doc.table_lag_s,
            input,
            sensors: doc.sensors,
            board: doc.board,
        })
    }

    /// The scene sampled at `rate_hz` instead of its own rate: the same run, its sample count
    /// round(duration_s · rate_hz), and the ADC's oversampling ratio the new rate's default
    /// when the scene used the old one's (a scene's own `[adc] osr` is kept). `None` for a rate
    /// that is not finite and positive, or that gives a sample count outside 1..=2^53.
    /// (`host-sim robustness --rate-hz`: the scorecard at the board's own rate.)
    pub fn at_rate(&self, rate_hz: f64) -> Option<Scene> {
        let n = (self.duration_s * rate_hz).round();
        if !(rate_hz.is_finite() && rate_hz > 0.0 && (1.0..=MAX_SAMPLES).contains(&n)) {
            return None;
        }
        let mut s = self.clone();
        if s.board.osr == BoardSettings::default_osr(self.rate_hz) {
            s.board.osr = BoardSettings::default_osr(rate_hz);
        }
        s.rate_hz = rate_hz;
        s.samples = n as u64;
        Some(s)
    }

    /// Time of sample k (s): k / rate_hz.
    pub fn time(&self, k: u64) -> f64 {
        k as f64 / self.rate_hz
    }

    /// gμ (m/s²), the unit of errors.
    pub fn gmu(&self) -> f64 {
        self.structure.gmu()
    }

    /// The table acceleration (none for a reversals scene): the input from `start_s` on, as
    /// late as the table's lag (`table_lag_s`).
    pub fn table_motion(&self) -> TableMotion {
        self.motion_from(self.start_s + self.table_lag_s)
    }

    /// The planned table acceleration: the input from `start_s` on, without the table's lag
    /// (what the controller is told; its choice of model simulates the prior on it).
    pub fn planned_motion(&self) -> TableMotion {
        self.motion_from(self.start_s)
    }

    fn motion_from(&self, start_s: f64) -> TableMotion {
        let motion = self.input_motion();
        if start_s > 0.0 {
            TableMotion::Delayed {
                start_s,
                motion: Box::new(motion),
            }
        } else {
            motion
        }
    }

    /// The input's own table motion, from its t = 0 (without the rest before `start_s`): the
    /// planned input a controller is told.
    pub fn input_motion(&self) -> TableMotion {
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
