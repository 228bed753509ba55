//! A scene document: its top-level layout and the one validation walk that both a full
//! [`Scene`](crate::Scene) and a [`Specimen`](crate::Specimen) go through.
//!
//! The walk checks the parts in a fixed order, so a document with several errors reports the same
//! first one whichever entry point reads it: missing keys and tables (`duration_s`,
//! `[structure]`, `[input]`, `[sampling]`), then `duration_s`, `gravity_m_s2`, `[structure]`,
//! `[estimator]`,
//! `[sampling] rate_hz`, the sample count, `[input]`, `[sensors]` and the board settings. A
//! specimen needs no table motion: `duration_s` and `[input]` may be absent, and are validated
//! when present.

use crate::board::{BoardSettings, RawAdc};
use crate::error::SceneError;
use crate::estimator::{Prior, RawEstimator};
use crate::friction::RawFriction;
use crate::input::{Input, RawInput};
use crate::parse::ParseContext;
use crate::recording::{RawRecording, Recording};
use crate::scene::MAX_SAMPLES;
use crate::sensors::{RawSensors, Sensors};
use crate::structure::RawStructure;
use serde::Deserialize;
use ssvr_core::structure::STANDARD_GRAVITY;
use ssvr_core::{FrictionLaw, Structure};
use std::path::Path;
use toml::Spanned;

/// The text of the scene file `path`.
pub(crate) fn read_scene_file(path: &Path) -> Result<String, SceneError> {
    std::fs::read_to_string(path).map_err(|e| SceneError {
        file: path.to_path_buf(),
        line: None,
        message: format!("cannot read the scene file: {e}"),
    })
}

/// The document's top-level layout. Tables and keys a full scene needs are optional here; the
/// walk reports them missing, as the TOML layer would, where they are required.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScene {
    name: Option<String>,
    duration_s: Option<Spanned<f64>>,
    gravity_m_s2: Option<Spanned<f64>>,
    structure: Option<Spanned<RawStructure>>,
    friction: Option<Spanned<RawFriction>>,
    estimator: Option<Spanned<RawEstimator>>,
    input: Option<Spanned<RawInput>>,
    sampling: Option<Spanned<RawSampling>>,
    recording: Option<Spanned<RawRecording>>,
    // Not spanned: a `[sensors.<channel>]` or `adc.<key>` alone defines them implicitly, and an
    // implicit table has no span.
    sensors: Option<RawSensors>,
    adc: Option<RawAdc>,
}

/// `[sampling]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSampling {
    rate_hz: Spanned<f64>,
}

/// Whether the table motion (`duration_s` and `[input]`) is required.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Motion {
    /// A full scene: both required.
    Required,
    /// A specimen: both optional, validated when present.
    Optional,
    /// A recorded test to replay: `[recording]` required; `duration_s`, `[input]` and
    /// `[sampling]` rejected (the recording sets them).
    Recording,
}

/// The validated parts of a document.
pub(crate) struct Document {
    pub(crate) name: String,
    /// `duration_s` and the sample count, when given.
    pub(crate) duration: Option<(f64, u64)>,
    pub(crate) rate_hz: f64,
    pub(crate) structure: Structure,
    pub(crate) static_friction_coefficient: f64,
    pub(crate) friction: FrictionLaw,
    pub(crate) prior: Prior,
    pub(crate) input: Option<Input>,
    pub(crate) start_s: f64,
    /// `[input] table_lag_s` (s; 0 without it).
    pub(crate) table_lag_s: f64,
    pub(crate) sensors: Sensors,
    pub(crate) board: BoardSettings,
    /// `[recording]` (a replay scene only).
    pub(crate) recording: Option<Recording>,
}

impl ParseContext<'_> {
    /// Parse the TOML layout of the document.
    pub(crate) fn raw(&self) -> Result<RawScene, SceneError> {
        toml::from_str(self.src).map_err(|e| self.toml_error(&e))
    }

    /// A missing top-level key or table, located as the TOML layer locates it (line 1).
    fn required<'r, T>(&self, v: &'r Option<T>, message: &str) -> Result<&'r T, SceneError> {
        v.as_ref()
            .ok_or_else(|| self.err(0..0, message.to_string()))
    }

    /// Validate the document.
    pub(crate) fn document(&self, raw: &RawScene, motion: Motion) -> Result<Document, SceneError> {
        if motion == Motion::Recording {
            return self.recording_document(raw);
        }
        if let Some(r) = &raw.recording {
            return Err(self.err(
                r.span(),
                "[recording]: a scene with a recording is replayed with `host-sim replay`, \
                 not simulated (it has no [input])"
                    .into(),
            ));
        }
        // Missing keys and tables first, in the order of the layout.
        if motion == Motion::Required {
            self.required(&raw.duration_s, "missing key `duration_s`")?;
        }
        let structure_table = self.required(&raw.structure, "missing table [structure]")?;
        if motion == Motion::Required {
            self.required(&raw.input, "missing table [input]")?;
        }
        let sampling = self.required(&raw.sampling, "missing table [sampling]")?;

        let duration = match &raw.duration_s {
            Some(d) => Some(self.check(
                None,
                "duration_s",
                d,
                *d.get_ref() > 0.0,
                "duration_s > 0 s",
            )?),
            None => None,
        };
        let (structure, mu_s, friction, prior) = self.specimen(raw, structure_table)?;
        let rate_v = &sampling.get_ref().rate_hz;
        let rate = self.check(
            Some("sampling"),
            "rate_hz",
            rate_v,
            *rate_v.get_ref() > 0.0,
            "rate_hz > 0 Hz",
        )?;
        let duration = match (duration, &raw.duration_s) {
            (Some(duration), Some(d)) => {
                let n = (duration * rate).round();
                if !(1.0..=MAX_SAMPLES).contains(&n) {
                    return Err(self.err(
                        d.span(),
                        format!(
                            "duration_s = {duration} at [sampling] rate_hz = {rate} gives {n} \
                             samples: expected 1 <= round(duration_s * rate_hz) <= 2^53"
                        ),
                    ));
                }
                Some((duration, n as u64))
            }
            _ => None,
        };
        let (input, start_s, table_lag_s) = match &raw.input {
            Some(table) => (
                Some(self.input(table)?),
                self.start(table)?,
                self.table_lag(table)?,
            ),
            None => (None, 0.0, 0.0),
        };
        let raw_sensors = raw.sensors.as_ref();
        let sensors = self.sensors_or_default(raw_sensors)?;
        let board = self.board(raw.adc.as_ref(), raw_sensors, &sensors, rate)?;
        let name = self.name(raw);
        Ok(Document {
            name,
            duration,
            rate_hz: rate,
            structure,
            static_friction_coefficient: mu_s,
            friction,
            prior,
            input,
            start_s,
            table_lag_s,
            sensors,
            board,
            recording: None,
        })
    }

    /// The specimen and what the controller is told of it: `gravity_m_s2`, `[structure]` (with
    /// `[friction]`) and `[estimator]`, in that order (simulated and replay scenes alike).
    fn specimen(
        &self,
        raw: &RawScene,
        structure_table: &Spanned<RawStructure>,
    ) -> Result<(Structure, f64, FrictionLaw, Prior), SceneError> {
        let gravity = self.gravity(raw)?;
        let (structure, mu_s, friction) = self.structure(
            structure_table,
            raw.friction.as_ref(),
            gravity,
            &raw.gravity_m_s2,
        )?;
        let prior = self.estimator(raw.estimator.as_ref(), &structure, mu_s, friction)?;
        Ok((structure, mu_s, friction, prior))
    }

    /// `gravity_m_s2` (> 0), or standard gravity.
    fn gravity(&self, raw: &RawScene) -> Result<f64, SceneError> {
        match &raw.gravity_m_s2 {
            Some(g) => self.check(
                None,
                "gravity_m_s2",
                g,
                *g.get_ref() > 0.0,
                "gravity_m_s2 > 0 m/s^2",
            ),
            None => Ok(STANDARD_GRAVITY),
        }
    }

    /// A path given in the scene: as is if absolute, else relative to the scene file's folder.
    pub(crate) fn relative_to_scene(&self, given: &str) -> std::path::PathBuf {
        let rel = std::path::Path::new(given);
        if rel.is_absolute() {
            rel.to_path_buf()
        } else {
            self.origin
                .parent()
                .unwrap_or_else(|| std::path::Path::new(""))
                .join(rel)
        }
    }

    /// `name`, or the file stem.
    fn name(&self, raw: &RawScene) -> String {
        raw.name.clone().unwrap_or_else(|| {
            self.origin
                .file_stem()
                .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
        })
    }

    /// The walk of a replay scene: `[structure]`, `[estimator]`, `[sensors]` and
    /// `[recording]`; the keys a recording sets (`duration_s`, `[input]`, `[sampling]`) are
    /// rejected. Board settings are checked for their keys only (a replay has no board image);
    /// the rate is the recording's.
    fn recording_document(&self, raw: &RawScene) -> Result<Document, SceneError> {
        let structure_table = self.required(&raw.structure, "missing table [structure]")?;
        let recording_table = self.required(&raw.recording, "missing table [recording]")?;
        let set_by_recording = [
            ("duration_s", raw.duration_s.as_ref().map(Spanned::span)),
            ("[input]", raw.input.as_ref().map(Spanned::span)),
            ("[sampling]", raw.sampling.as_ref().map(Spanned::span)),
        ];
        for (what, span) in set_by_recording {
            if let Some(span) = span {
                return Err(self.err(
                    span,
                    format!(
                        "{what} does not apply to a scene with a [recording] (the recording \
                         sets it)"
                    ),
                ));
            }
        }
        let (structure, mu_s, friction, prior) = self.specimen(raw, structure_table)?;
        let recording = self.recording(recording_table)?;
        let sensors = self.sensors_or_default(raw.sensors.as_ref())?;
        let rate_hz = match recording.time {
            crate::recording::Timebase::Rate(r) => r,
            // Set from the time column when the file is read.
            crate::recording::Timebase::Column(_) => f64::NAN,
        };
        let name = self.name(raw);
        Ok(Document {
            name,
            duration: None,
            rate_hz,
            structure,
            static_friction_coefficient: mu_s,
            friction,
            prior,
            input: None,
            start_s: recording.start_s,
            table_lag_s: 0.0,
            board: BoardSettings::defaults(1.0, &sensors),
            sensors,
            recording: Some(recording),
        })
    }
}
