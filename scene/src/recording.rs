//! A recorded test to replay (`[recording]`, read by `host-sim replay`): the CSV file, which of
//! its columns hold the time and the measured channels, and their units.
//!
//! ```toml
//! [recording]
//! file = "test-07.csv"            # CSV with one header row; relative to the scene file
//! time_column = "Time (s)"        # or rate_hz = 1000.0 (t_k = k / rate_hz): exactly one
//! table_accel_column = "A table"
//! base_accel_column = "A base"    # optional
//! top_accel_column = "A top"      # optional
//! slip_column = "LVDT"            # optional: base-to-table displacement
//! accel_units = "g"               # "g" | "m/s2" | "gal"
//! slip_units = "mm"               # "m" | "mm" (required with slip_column)
//! start_s = 0.5                   # optional: the table at rest until then (offsets zeroed on it)
//! ```
//!
//! The file is only named here (it may be large): `host-sim replay` streams it.

use crate::error::SceneError;
use crate::parse::ParseContext;
use crate::units::Units;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Units of a recorded base-to-table displacement.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum SlipUnits {
    /// Metres.
    #[serde(rename = "m")]
    M,
    /// Millimetres.
    #[serde(rename = "mm")]
    Mm,
}

impl SlipUnits {
    /// Metres per unit.
    pub fn factor(self) -> f64 {
        match self {
            SlipUnits::M => 1.0,
            SlipUnits::Mm => 1e-3,
        }
    }

    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            SlipUnits::M => "m",
            SlipUnits::Mm => "mm",
        }
    }
}

/// Where a recording's sample times come from.
#[derive(Debug, Clone, PartialEq)]
pub enum Timebase {
    /// The named column holds the time (s) of every row.
    Column(String),
    /// Row k (0-based, after the header) is at t_k = k / rate_hz.
    Rate(f64),
}

/// A validated `[recording]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The CSV file, resolved against the scene file's folder.
    pub file: PathBuf,
    /// The file as written in the scene (for messages).
    pub file_as_given: String,
    /// The time column or the fixed rate.
    pub time: Timebase,
    /// The table accelerometer's column.
    pub table_accel_column: String,
    /// The base accelerometer's column (the slip-acceleration detector needs it).
    pub base_accel_column: Option<String>,
    /// The top accelerometer's column (compared with the prediction; the fuse mode reads it).
    pub top_accel_column: Option<String>,
    /// The base-to-table displacement's column.
    pub slip_column: Option<String>,
    /// Units of the accelerometer columns.
    pub accel_units: Units,
    /// Units of the displacement column (metres when there is none).
    pub slip_units: SlipUnits,
    /// The table at rest until then (s, relative to the first row; 0: no rest): the pipeline
    /// zeroes the accelerometers' offsets on it, as `run` does on `[input] start_s`.
    pub start_s: f64,
}

/// `[recording]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRecording {
    file: Spanned<String>,
    time_column: Option<Spanned<String>>,
    rate_hz: Option<Spanned<f64>>,
    table_accel_column: Spanned<String>,
    base_accel_column: Option<Spanned<String>>,
    top_accel_column: Option<Spanned<String>>,
    slip_column: Option<Spanned<String>>,
    accel_units: Spanned<Units>,
    slip_units: Option<Spanned<SlipUnits>>,
    start_s: Option<Spanned<f64>>,
}

impl ParseContext<'_> {
    /// Validate `[recording]`.
    pub(crate) fn recording(&self, table: &Spanned<RawRecording>) -> Result<Recording, SceneError> {
        const S: Option<&str> = Some("recording");
        let r = table.get_ref();
        let time = match (&r.time_column, &r.rate_hz) {
            (Some(c), None) => Timebase::Column(self.column("time_column", c)?),
            (None, Some(rate)) => Timebase::Rate(self.check(
                S,
                "rate_hz",
                rate,
                *rate.get_ref() > 0.0,
                "rate_hz > 0 Hz",
            )?),
            (Some(_), Some(rate)) => {
                return Err(self.err(
                    rate.span(),
                    "[recording] rate_hz: give either `time_column` or `rate_hz`, not both".into(),
                ))
            }
            (None, None) => {
                return Err(self.missing(
                    "recording",
                    table,
                    "missing key `time_column` or `rate_hz` (exactly one)".into(),
                ))
            }
        };
        let optional = |key: &str, v: &Option<Spanned<String>>| -> Result<_, SceneError> {
            v.as_ref().map(|c| self.column(key, c)).transpose()
        };
        let slip_column = optional("slip_column", &r.slip_column)?;
        let slip_units = match (&r.slip_units, &slip_column) {
            (Some(u), _) => *u.get_ref(),
            (None, Some(_)) => {
                return Err(self.missing(
                    "recording",
                    table,
                    "missing key `slip_units` (\"m\" or \"mm\") for `slip_column`".into(),
                ))
            }
            (None, None) => SlipUnits::M,
        };
        let start_s = match &r.start_s {
            Some(v) => self.check(S, "start_s", v, *v.get_ref() >= 0.0, "start_s >= 0 s")?,
            None => 0.0,
        };
        let given = r.file.get_ref();
        if given.trim().is_empty() {
            return Err(self.err(
                r.file.span(),
                "[recording] file must name a CSV file".into(),
            ));
        }
        let file = self.relative_to_scene(given);
        Ok(Recording {
            file,
            file_as_given: given.clone(),
            time,
            table_accel_column: self.column("table_accel_column", &r.table_accel_column)?,
            base_accel_column: optional("base_accel_column", &r.base_accel_column)?,
            top_accel_column: optional("top_accel_column", &r.top_accel_column)?,
            slip_column,
            accel_units: *r.accel_units.get_ref(),
            slip_units,
            start_s,
        })
    }

    /// A column name: not empty.
    fn column(&self, key: &str, v: &Spanned<String>) -> Result<String, SceneError> {
        if v.get_ref().trim().is_empty() {
            Err(self.err(
                v.span(),
                format!("[recording] {key} must name a column of the CSV header"),
            ))
        } else {
            Ok(v.get_ref().clone())
        }
    }
}

/// A scene that replays a recorded test (`host-sim replay`): the specimen as the controller
/// knows it (`[structure]`, optional `[estimator]`, `[sensors]` noise levels for the detector)
/// and a `[recording]` instead of `[input]`, `[sampling]` and `duration_s`.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayScene {
    /// Name (the `name` key, else the file stem).
    pub name: String,
    /// The scene file.
    pub source: PathBuf,
    /// The structure (`[structure]`; its gravity is the scene's `gravity_m_s2`).
    pub structure: ssvr_core::Structure,
    /// Static friction coefficient μs ≥ μ.
    pub static_friction_coefficient: f64,
    /// The friction law of the interface (`[friction]`; Coulomb without it).
    pub friction: ssvr_core::FrictionLaw,
    /// The estimator's prior (`[estimator]`; the specimen itself without it).
    pub estimator: crate::Prior,
    /// Sensor models (their noise levels set the detector's thresholds).
    pub sensors: crate::Sensors,
    /// The recording.
    pub recording: Recording,
}

impl ReplayScene {
    /// Read and validate a replay scene file. The recording's file resolves against the scene
    /// file's folder; it is not opened here.
    pub fn load(path: impl AsRef<Path>) -> Result<ReplayScene, SceneError> {
        let path = path.as_ref();
        ReplayScene::parse(&crate::document::read_scene_file(path)?, path)
    }

    /// Parse and validate replay scene text; `origin` names the file in messages and anchors
    /// the recording's relative path.
    pub fn parse(text: &str, origin: &Path) -> Result<ReplayScene, SceneError> {
        let cx = ParseContext { src: text, origin };
        let doc = cx.document(&cx.raw()?, crate::document::Motion::Recording)?;
        let Some(recording) = doc.recording else {
            return Err(cx.err(0..0, "missing table [recording]".into()));
        };
        Ok(ReplayScene {
            name: doc.name,
            source: origin.to_path_buf(),
            structure: doc.structure,
            static_friction_coefficient: doc.static_friction_coefficient,
            friction: doc.friction,
            estimator: doc.prior,
            sensors: doc.sensors,
            recording,
        })
    }

    /// The specimen at the recording's sample rate `rate_hz` (from `rate_hz` or the time
    /// column), with the rest before the input of `[recording] start_s`: what `host-sim run`
    /// plans its pipeline from.
    pub fn specimen(&self, rate_hz: f64) -> crate::Specimen {
        crate::Specimen {
            name: self.name.clone(),
            source: Some(self.source.clone()),
            structure: self.structure,
            static_friction_coefficient: self.static_friction_coefficient,
            friction: self.friction,
            gravity_m_s2: self.structure.g(),
            rate_hz,
            sensors: self.sensors.clone(),
            board: crate::BoardSettings::defaults(rate_hz, &self.sensors),
            estimator: self.estimator,
            start_s: self.recording.start_s,
        }
    }
}
