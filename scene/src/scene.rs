//! Scene files: a structure, a table input, a sample rate and sensor models, in TOML with SI units.
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
//! static_friction_coefficient = 0.25 # optional, >= friction_coefficient
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

use crate::table_motion::TableMotion;
use serde::Deserialize;
use ssvr_core::structure::STANDARD_GRAVITY;
use ssvr_core::{Error as CoreError, Param, ReversalTrain, Structure, StructureParams};
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Largest sample count a scene may ask for (2^53: every index is exact in f64).
pub const MAX_SAMPLES: f64 = 9_007_199_254_740_992.0;

/// A scene-file (or record-file) error: the file, the line (1-based) and a message naming the key.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// The file the error is in (as given, e.g. `scenes/x.toml`).
    pub file: PathBuf,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// What is wrong, starting with the key (e.g. `[structure] damping_ratio = 1.2 is out of ...`).
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{}: {}", self.file.display(), line, self.message),
            None => write!(f, "{}: {}", self.file.display(), self.message),
        }
    }
}

impl std::error::Error for SceneError {}

/// Units of an earthquake record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum Units {
    /// Standard gravity (9.80665 m/s²), whatever the scene's `gravity_m_s2`.
    #[serde(rename = "g")]
    G,
    /// m/s².
    #[serde(rename = "m/s2", alias = "m/s^2")]
    MPerS2,
    /// 1 gal = 0.01 m/s².
    #[serde(rename = "gal")]
    Gal,
}

impl Units {
    /// m/s² per unit.
    pub fn factor(self) -> f64 {
        match self {
            Units::G => STANDARD_GRAVITY,
            Units::MPerS2 => 1.0,
            Units::Gal => 0.01,
        }
    }

    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Units::G => "g",
            Units::MPerS2 => "m/s2",
            Units::Gal => "gal",
        }
    }
}

/// A prescribed friction train (scene `kind = "reversals"`): F = level·μ(m1+m2)g, the level jumping to
/// `initial_sign` at the first reversal and alternating at each following one.
#[derive(Debug, Clone, PartialEq)]
pub enum Reversals {
    /// Reversals at k·`half_period_s`, k = 0, 1, 2, …
    Periodic {
        /// Interval between reversals (s).
        half_period_s: f64,
        /// Level after the first reversal, ±1.
        initial_sign: f64,
    },
    /// Reversals at the given strictly increasing times.
    Times {
        /// Reversal times (s).
        times_s: Vec<f64>,
        /// Level after the first reversal, ±1.
        initial_sign: f64,
    },
}

impl Reversals {
    /// The train as `ssvr-core` takes it.
    pub fn train(&self) -> ReversalTrain<'_> {
        match self {
            Reversals::Periodic {
                half_period_s,
                initial_sign,
            } => ReversalTrain::Periodic {
                first_s: 0.0,
                half_period_s: *half_period_s,
                initial_sign: *initial_sign,
            },
            Reversals::Times {
                times_s,
                initial_sign,
            } => ReversalTrain::Alternating {
                times_s,
                initial_sign: *initial_sign,
            },
        }
    }
}

/// An earthquake record (scene `kind = "record"`).
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// The record file, resolved against the scene file's folder.
    pub path: PathBuf,
    /// Units of the file's acceleration column.
    pub units: Units,
    /// Scale applied on top of the unit conversion.
    pub scale: f64,
    /// The motion (m/s²): piecewise linear between samples, zero after the end.
    pub motion: TableMotion,
}

/// The input of a scene.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// Table acceleration `amplitude_m_s2`·sin(2πt/`period_s`).
    Harmonic {
        /// Amplitude A0 (m/s²).
        amplitude_m_s2: f64,
        /// Period T (s).
        period_s: f64,
    },
    /// The friction train itself (no table motion).
    Reversals(Reversals),
    /// An earthquake record as table acceleration.
    Record(Record),
}

impl Input {
    /// The scene's `kind`.
    pub fn kind(&self) -> &'static str {
        match self {
            Input::Harmonic { .. } => "harmonic",
            Input::Reversals(_) => "reversals",
            Input::Record(_) => "record",
        }
    }
}

/// Sensor models (scene table `[sensors]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Sensors {
    /// Seed of the noise generator.
    pub seed: u64,
    /// White-noise RMS of the table, base and top accelerometers (m/s²).
    pub accel_noise_rms_m_s2: f64,
    /// Accelerometer full scale ± (m/s²).
    pub accel_range_m_s2: f64,
    /// Accelerometer ADC resolution (bits).
    pub accel_adc_bits: u32,
    /// White-noise RMS of the base-to-table displacement sensor (m).
    pub disp_noise_rms_m: f64,
    /// Displacement sensor full scale ± (m).
    pub disp_range_m: f64,
}

impl Default for Sensors {
    fn default() -> Self {
        Self {
            seed: 1,
            accel_noise_rms_m_s2: 5e-3,
            accel_range_m_s2: 4.0 * STANDARD_GRAVITY,
            accel_adc_bits: 24,
            disp_noise_rms_m: 1e-6,
            disp_range_m: 0.05,
        }
    }
}

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
    /// Static friction coefficient μs ≥ μ.
    pub static_friction_coefficient: f64,
    /// The input.
    pub input: Input,
    /// Sensor models.
    pub sensors: Sensors,
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
            input: Input::Harmonic {
                amplitude_m_s2: 2.0,
                period_s: 0.143,
            },
            sensors: Sensors::default(),
        }
    }

    /// Read and validate a scene file. Record files resolve against the scene file's folder.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: path.to_path_buf(),
            line: None,
            message: format!("cannot read the scene file: {e}"),
        })?;
        Scene::parse(&text, path)
    }

    /// Parse and validate scene text; `origin` names the file in messages and anchors relative
    /// record paths (its parent folder).
    pub fn parse(text: &str, origin: &Path) -> Result<Scene, SceneError> {
        let cx = Cx { src: text, origin };
        let raw: RawScene = toml::from_str(text).map_err(|e| cx.toml_error(&e))?;
        cx.build(raw)
    }

    /// Time of sample k (s): k / rate_hz.
    pub fn time(&self, k: u64) -> f64 {
        k as f64 / self.rate_hz
    }

    /// gμ (m/s²), the unit of errors.
    pub fn gmu(&self) -> f64 {
        self.structure.gmu()
    }

    /// The table acceleration (none for a reversals scene).
    pub fn table_motion(&self) -> TableMotion {
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

// ---------------------------------------------------------------------------------------------
// Raw TOML layout.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    name: Option<String>,
    duration_s: Spanned<f64>,
    gravity_m_s2: Option<Spanned<f64>>,
    structure: Spanned<RawStructure>,
    input: Spanned<RawInput>,
    sampling: Spanned<RawSampling>,
    sensors: Option<Spanned<RawSensors>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStructure {
    m1_kg: Spanned<f64>,
    m2_kg: Spanned<f64>,
    natural_frequency_hz: Option<Spanned<f64>>,
    natural_period_s: Option<Spanned<f64>>,
    damping_ratio: Spanned<f64>,
    friction_coefficient: Spanned<f64>,
    static_friction_coefficient: Option<Spanned<f64>>,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum Kind {
    Harmonic,
    Reversals,
    Record,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInput {
    kind: Spanned<Kind>,
    amplitude_m_s2: Option<Spanned<f64>>,
    period_s: Option<Spanned<f64>>,
    half_period_s: Option<Spanned<f64>>,
    times_s: Option<Spanned<Vec<Spanned<f64>>>>,
    initial_sign: Option<Spanned<f64>>,
    file: Option<Spanned<String>>,
    units: Option<Spanned<Units>>,
    scale: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSampling {
    rate_hz: Spanned<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSensors {
    seed: Option<Spanned<u64>>,
    accel_noise_rms_m_s2: Option<Spanned<f64>>,
    accel_range_m_s2: Option<Spanned<f64>>,
    accel_adc_bits: Option<Spanned<u32>>,
    disp_noise_rms_m: Option<Spanned<f64>>,
    disp_range_m: Option<Spanned<f64>>,
}

// ---------------------------------------------------------------------------------------------
// Validation.

/// 1-based line of byte `offset` in `src`.
fn line_of(src: &str, offset: usize) -> usize {
    let end = offset.min(src.len());
    src.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The parsing context: the source text and the file it came from.
struct Cx<'a> {
    src: &'a str,
    origin: &'a Path,
}

impl Cx<'_> {
    fn err(&self, span: Range<usize>, message: String) -> SceneError {
        SceneError {
            file: self.origin.to_path_buf(),
            line: Some(line_of(self.src, span.start)),
            message,
        }
    }

    /// The `[section]` header in force at byte `offset` (None at top level).
    fn section_at(&self, offset: usize) -> Option<String> {
        let end = offset.min(self.src.len());
        let mut section = None;
        for line in self.src[..end].lines() {
            let l = line.trim();
            if let Some(rest) = l.strip_prefix('[') {
                if !rest.starts_with('[') {
                    if let Some(close) = rest.find(']') {
                        section = Some(rest[..close].trim().to_string());
                    }
                }
            }
        }
        // A header starting exactly at `offset` (a table's span starts at its header).
        let tail = &self.src[end..];
        if let Some(rest) = tail.trim_start_matches([' ', '\t']).strip_prefix('[') {
            if !rest.starts_with('[') {
                if let Some(close) = rest.find(']') {
                    if !rest[..close].contains('\n') {
                        section = Some(rest[..close].trim().to_string());
                    }
                }
            }
        }
        section
    }

    /// The key whose value contains byte `offset`: the identifier before the nearest `=` before it.
    fn key_before(&self, offset: usize) -> Option<String> {
        let end = offset.min(self.src.len());
        let eq = self.src[..end].rfind('=')?;
        let before = self.src[..eq].trim_end();
        let start = before
            .rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '-'))
            .map_or(0, |i| i + 1);
        let key = &before[start..];
        (!key.is_empty()).then(|| key.to_string())
    }

    fn toml_error(&self, e: &toml::de::Error) -> SceneError {
        let mut message = e
            .message()
            .trim()
            .replace('\n', "; ")
            .replace("unknown field", "unknown key")
            .replace("missing field", "missing key");
        for table in ["structure", "input", "sampling"] {
            if message == format!("missing key `{table}`") {
                message = format!("missing table [{table}]");
            }
        }
        let Some(span) = e.span() else {
            return SceneError {
                file: self.origin.to_path_buf(),
                line: None,
                message,
            };
        };
        let section = self.section_at(span.start);
        let value_error = [
            "invalid type",
            "invalid value",
            "unknown variant",
            "invalid length",
        ]
        .iter()
        .any(|p| message.starts_with(p));
        let mut what = String::new();
        if let Some(s) = &section {
            what.push_str(&format!("[{s}] "));
        }
        if value_error {
            if let Some(k) = self.key_before(span.start) {
                what.push_str(&format!("{k}: "));
            }
        }
        what.push_str(&message);
        self.err(span, what)
    }

    /// Check a finite value against a condition, naming `[section] key`.
    fn check(
        &self,
        section: Option<&str>,
        key: &str,
        v: &Spanned<f64>,
        ok: bool,
        expected: &str,
    ) -> Result<f64, SceneError> {
        let name = qualified(section, key);
        let value = *v.get_ref();
        if !value.is_finite() {
            Err(self.err(v.span(), format!("{name} must be a finite number")))
        } else if !ok {
            Err(self.err(
                v.span(),
                format!("{name} = {value} is out of range: expected {expected}"),
            ))
        } else {
            Ok(value)
        }
    }

    fn missing<T>(&self, section: &str, table: &Spanned<T>, message: String) -> SceneError {
        self.err(table.span(), format!("[{section}] {message}"))
    }

    fn build(&self, raw: RawScene) -> Result<Scene, SceneError> {
        let duration = self.check(
            None,
            "duration_s",
            &raw.duration_s,
            *raw.duration_s.get_ref() > 0.0,
            "duration_s > 0 s",
        )?;
        let gravity = match &raw.gravity_m_s2 {
            Some(g) => self.check(
                None,
                "gravity_m_s2",
                g,
                *g.get_ref() > 0.0,
                "gravity_m_s2 > 0 m/s^2",
            )?,
            None => STANDARD_GRAVITY,
        };
        let (structure, mu_s) = self.structure(&raw.structure, gravity, &raw.gravity_m_s2)?;
        let rate_v = &raw.sampling.get_ref().rate_hz;
        let rate = self.check(
            Some("sampling"),
            "rate_hz",
            rate_v,
            *rate_v.get_ref() > 0.0,
            "rate_hz > 0 Hz",
        )?;
        let n = (duration * rate).round();
        if !(1.0..=MAX_SAMPLES).contains(&n) {
            return Err(self.err(
                raw.duration_s.span(),
                format!(
                    "duration_s = {duration} at [sampling] rate_hz = {rate} gives {n} samples: \
                     expected 1 <= round(duration_s * rate_hz) <= 2^53"
                ),
            ));
        }
        let input = self.input(&raw.input)?;
        let sensors = match &raw.sensors {
            Some(s) => self.sensors(s.get_ref())?,
            None => Sensors::default(),
        };
        let name = raw.name.unwrap_or_else(|| {
            self.origin
                .file_stem()
                .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
        });
        Ok(Scene {
            name,
            source: Some(self.origin.to_path_buf()),
            duration_s: duration,
            rate_hz: rate,
            samples: n as u64,
            structure,
            static_friction_coefficient: mu_s,
            input,
            sensors,
        })
    }

    fn structure(
        &self,
        table: &Spanned<RawStructure>,
        gravity: f64,
        gravity_v: &Option<Spanned<f64>>,
    ) -> Result<(Structure, f64), SceneError> {
        const S: Option<&str> = Some("structure");
        let r = table.get_ref();
        let (freq, freq_key, freq_v) =
            match (&r.natural_frequency_hz, &r.natural_period_s) {
                (Some(f), None) => (*f.get_ref(), "natural_frequency_hz", f),
                (None, Some(p)) => {
                    let period = self.check(
                        S,
                        "natural_period_s",
                        p,
                        *p.get_ref() > 0.0 && (1.0 / p.get_ref()).is_finite(),
                        "natural_period_s > 0 s",
                    )?;
                    (1.0 / period, "natural_period_s", p)
                }
                (Some(_), Some(p)) => return Err(self.err(
                    p.span(),
                    "[structure] natural_period_s: give natural_frequency_hz or natural_period_s, \
                     not both"
                        .into(),
                )),
                (None, None) => {
                    return Err(self.missing(
                        "structure",
                        table,
                        "missing key `natural_frequency_hz` (or `natural_period_s`)".into(),
                    ))
                }
            };
        let params = StructureParams {
            m1_kg: *r.m1_kg.get_ref(),
            m2_kg: *r.m2_kg.get_ref(),
            natural_frequency_hz: freq,
            damping_ratio: *r.damping_ratio.get_ref(),
            friction_coefficient: *r.friction_coefficient.get_ref(),
            gravity_m_s2: gravity,
        };
        let structure = Structure::new(params).map_err(|e| {
            let (key, span, value) = match e.param() {
                Param::M1 => ("[structure] m1_kg", r.m1_kg.span(), *r.m1_kg.get_ref()),
                Param::M2 => ("[structure] m2_kg", r.m2_kg.span(), *r.m2_kg.get_ref()),
                Param::NaturalFrequency => {
                    let key = if freq_key == "natural_period_s" {
                        "[structure] natural_period_s"
                    } else {
                        "[structure] natural_frequency_hz"
                    };
                    (key, freq_v.span(), *freq_v.get_ref())
                }
                Param::DampingRatio => (
                    "[structure] damping_ratio",
                    r.damping_ratio.span(),
                    *r.damping_ratio.get_ref(),
                ),
                Param::FrictionCoefficient => (
                    "[structure] friction_coefficient",
                    r.friction_coefficient.span(),
                    *r.friction_coefficient.get_ref(),
                ),
                Param::Gravity => match gravity_v {
                    Some(g) => ("gravity_m_s2", g.span(), gravity),
                    None => ("gravity_m_s2", table.span(), gravity),
                },
                _ => ("[structure]", table.span(), f64::NAN),
            };
            self.err(span, core_message(key, value, &e))
        })?;
        let mu = structure.mu();
        let mu_s = match &r.static_friction_coefficient {
            Some(v) => self.check(
                S,
                "static_friction_coefficient",
                v,
                *v.get_ref() >= mu,
                "static_friction_coefficient >= friction_coefficient",
            )?,
            None => mu,
        };
        Ok((structure, mu_s))
    }

    fn input(&self, table: &Spanned<RawInput>) -> Result<Input, SceneError> {
        const S: Option<&str> = Some("input");
        let r = table.get_ref();
        let kind = *r.kind.get_ref();
        // Reject keys that belong to another kind.
        let kind_name = match kind {
            Kind::Harmonic => "harmonic",
            Kind::Reversals => "reversals",
            Kind::Record => "record",
        };
        let allowed: &[&str] = match kind {
            Kind::Harmonic => &["amplitude_m_s2", "period_s"],
            Kind::Reversals => &["half_period_s", "times_s", "initial_sign"],
            Kind::Record => &["file", "units", "scale"],
        };
        let present: [(&str, Option<Range<usize>>); 8] = [
            (
                "amplitude_m_s2",
                r.amplitude_m_s2.as_ref().map(Spanned::span),
            ),
            ("period_s", r.period_s.as_ref().map(Spanned::span)),
            ("half_period_s", r.half_period_s.as_ref().map(Spanned::span)),
            ("times_s", r.times_s.as_ref().map(Spanned::span)),
            ("initial_sign", r.initial_sign.as_ref().map(Spanned::span)),
            ("file", r.file.as_ref().map(Spanned::span)),
            ("units", r.units.as_ref().map(Spanned::span)),
            ("scale", r.scale.as_ref().map(Spanned::span)),
        ];
        for (key, span) in present {
            if let Some(span) = span {
                if !allowed.contains(&key) {
                    return Err(self.err(
                        span,
                        format!(
                            "[input] {key} does not apply to kind = \"{kind_name}\" \
                             (its keys: {})",
                            allowed.join(", ")
                        ),
                    ));
                }
            }
        }
        let need = |v: &Option<Spanned<f64>>, key: &str| -> Result<Spanned<f64>, SceneError> {
            v.clone().ok_or_else(|| {
                self.missing(
                    "input",
                    table,
                    format!("missing key `{key}` (kind = \"{kind_name}\")"),
                )
            })
        };
        match kind {
            Kind::Harmonic => {
                let a = need(&r.amplitude_m_s2, "amplitude_m_s2")?;
                let p = need(&r.period_s, "period_s")?;
                let amplitude =
                    self.check(S, "amplitude_m_s2", &a, *a.get_ref() >= 0.0, ">= 0 m/s^2")?;
                let period = self.check(S, "period_s", &p, *p.get_ref() > 0.0, "> 0 s")?;
                Ok(Input::Harmonic {
                    amplitude_m_s2: amplitude,
                    period_s: period,
                })
            }
            Kind::Reversals => {
                let initial_sign = match &r.initial_sign {
                    Some(v) => self.check(
                        S,
                        "initial_sign",
                        v,
                        *v.get_ref() == 1.0 || *v.get_ref() == -1.0,
                        "1 or -1",
                    )?,
                    None => 1.0,
                };
                match (&r.half_period_s, &r.times_s) {
                    (Some(h), None) => {
                        let half =
                            self.check(S, "half_period_s", h, *h.get_ref() > 0.0, "> 0 s")?;
                        Ok(Input::Reversals(Reversals::Periodic {
                            half_period_s: half,
                            initial_sign,
                        }))
                    }
                    (None, Some(ts)) => {
                        if ts.get_ref().is_empty() {
                            return Err(self.err(
                                ts.span(),
                                "[input] times_s is empty: expected at least one reversal time"
                                    .into(),
                            ));
                        }
                        let mut times = Vec::with_capacity(ts.get_ref().len());
                        for (i, t) in ts.get_ref().iter().enumerate() {
                            let key = format!("times_s[{i}]");
                            let v = *t.get_ref();
                            let ok = match times.last() {
                                Some(&prev) => v > prev,
                                None => true,
                            };
                            let expected = match times.last() {
                                Some(prev) => format!(
                                    "strictly increasing times (> times_s[{}] = {prev})",
                                    i - 1
                                ),
                                None => String::new(),
                            };
                            times.push(self.check(S, &key, t, ok, &expected)?);
                        }
                        Ok(Input::Reversals(Reversals::Times {
                            times_s: times,
                            initial_sign,
                        }))
                    }
                    (Some(_), Some(ts)) => Err(self.err(
                        ts.span(),
                        "[input] times_s: give half_period_s or times_s, not both".into(),
                    )),
                    (None, None) => Err(self.missing(
                        "input",
                        table,
                        "missing key `half_period_s` or `times_s` (kind = \"reversals\")".into(),
                    )),
                }
            }
            Kind::Record => {
                let file = r.file.as_ref().ok_or_else(|| {
                    self.missing(
                        "input",
                        table,
                        "missing key `file` (kind = \"record\")".into(),
                    )
                })?;
                let units = r.units.as_ref().ok_or_else(|| {
                    self.missing(
                        "input",
                        table,
                        "missing key `units` (kind = \"record\": \"g\", \"m/s2\" or \"gal\")"
                            .into(),
                    )
                })?;
                let scale = match &r.scale {
                    Some(v) => self.check(S, "scale", v, true, "a finite number")?,
                    None => 1.0,
                };
                let rel = Path::new(file.get_ref().as_str());
                let path = if rel.is_absolute() {
                    rel.to_path_buf()
                } else {
                    self.origin
                        .parent()
                        .unwrap_or_else(|| Path::new(""))
                        .join(rel)
                };
                let referenced = format!(
                    "{}:{}",
                    self.origin.display(),
                    line_of(self.src, file.span().start)
                );
                let text = std::fs::read_to_string(&path).map_err(|e| {
                    self.err(
                        file.span(),
                        format!(
                            "[input] file = \"{}\": cannot read {}: {e}",
                            file.get_ref(),
                            path.display()
                        ),
                    )
                })?;
                let factor = units.get_ref().factor() * scale;
                let (times_s, accel_m_s2) =
                    parse_record(&text, &path, factor).map_err(|mut e| {
                        e.message
                            .push_str(&format!(" (record of [input] file at {referenced})"));
                        e
                    })?;
                Ok(Input::Record(Record {
                    path,
                    units: *units.get_ref(),
                    scale,
                    motion: TableMotion::Record {
                        times_s,
                        accel_m_s2,
                    },
                }))
            }
        }
    }

    fn sensors(&self, r: &RawSensors) -> Result<Sensors, SceneError> {
        const S: Option<&str> = Some("sensors");
        let d = Sensors::default();
        let opt = |v: &Option<Spanned<f64>>,
                   key: &str,
                   default: f64,
                   ok: fn(f64) -> bool,
                   expected: &str|
         -> Result<f64, SceneError> {
            match v {
                Some(v) => self.check(S, key, v, ok(*v.get_ref()), expected),
                None => Ok(default),
            }
        };
        let accel_adc_bits = match &r.accel_adc_bits {
            Some(b) => {
                let bits = *b.get_ref();
                if !(1..=32).contains(&bits) {
                    return Err(self.err(
                        b.span(),
                        format!(
                            "[sensors] accel_adc_bits = {bits} is out of range: expected 1 to 32"
                        ),
                    ));
                }
                bits
            }
            None => d.accel_adc_bits,
        };
        Ok(Sensors {
            seed: r.seed.as_ref().map_or(d.seed, |s| *s.get_ref()),
            accel_noise_rms_m_s2: opt(
                &r.accel_noise_rms_m_s2,
                "accel_noise_rms_m_s2",
                d.accel_noise_rms_m_s2,
                |v| v >= 0.0,
                ">= 0 m/s^2",
            )?,
            accel_range_m_s2: opt(
                &r.accel_range_m_s2,
                "accel_range_m_s2",
                d.accel_range_m_s2,
                |v| v > 0.0,
                "> 0 m/s^2",
            )?,
            accel_adc_bits,
            disp_noise_rms_m: opt(
                &r.disp_noise_rms_m,
                "disp_noise_rms_m",
                d.disp_noise_rms_m,
                |v| v >= 0.0,
                ">= 0 m",
            )?,
            disp_range_m: opt(
                &r.disp_range_m,
                "disp_range_m",
                d.disp_range_m,
                |v| v > 0.0,
                "> 0 m",
            )?,
        })
    }
}

fn qualified(section: Option<&str>, key: &str) -> String {
    match section {
        Some(s) => format!("[{s}] {key}"),
        None => key.to_string(),
    }
}

/// A core validation error phrased with the TOML key.
fn core_message(key: &str, value: f64, e: &CoreError) -> String {
    match e {
        CoreError::NotFinite(_) => format!("{key} must be a finite number"),
        CoreError::OutOfRange { expected, .. } => {
            format!("{key} = {value} is out of range: expected {expected}")
        }
        other => format!("{key}: {other}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Record files.

/// Whether `text` looks like a PEER NGA `.AT2` file: "NPTS" in one of its first 4 lines.
fn is_at2(text: &str) -> bool {
    text.lines()
        .take(4)
        .any(|l| l.to_ascii_uppercase().contains("NPTS"))
}

/// Parse an earthquake record: two-column text (time, acceleration; `#` comments and blank lines
/// allowed; whitespace or commas between columns) or a PEER NGA `.AT2` file (4 header lines, the
/// 4th holding NPTS and DT, then the values in rows). Accelerations are multiplied by `factor`.
/// Errors name `path` and the line.
pub fn parse_record(
    text: &str,
    path: &Path,
    factor: f64,
) -> Result<(Vec<f64>, Vec<f64>), SceneError> {
    let err = |line: Option<usize>, message: String| SceneError {
        file: path.to_path_buf(),
        line,
        message,
    };
    let (times, accel) = if is_at2(text) {
        parse_at2(text, &err)?
    } else {
        parse_two_column(text, &err)?
    };
    if times.len() < 2 {
        return Err(err(
            None,
            format!(
                "the record has {} sample(s): expected at least 2",
                times.len()
            ),
        ));
    }
    let accel: Vec<f64> = accel.into_iter().map(|a| a * factor).collect();
    if let Some(i) = accel.iter().position(|a| !a.is_finite()) {
        return Err(err(
            None,
            format!("sample #{i} is not finite after scaling (units × scale)"),
        ));
    }
    Ok((times, accel))
}

type RecordResult = Result<(Vec<f64>, Vec<f64>), SceneError>;

fn number(
    tok: &str,
    line: usize,
    what: &str,
    err: &dyn Fn(Option<usize>, String) -> SceneError,
) -> Result<f64, SceneError> {
    match tok.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(err(Some(line), format!("{what} \"{tok}\" is not finite"))),
        Err(_) => Err(err(Some(line), format!("{what} \"{tok}\" is not a number"))),
    }
}

fn parse_two_column(text: &str, err: &dyn Fn(Option<usize>, String) -> SceneError) -> RecordResult {
    let (mut times, mut accel) = (Vec::new(), Vec::new());
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("");
        let toks: Vec<&str> = content
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|t| !t.is_empty())
            .collect();
        if toks.is_empty() {
            continue;
        }
        if toks.len() != 2 {
            return Err(err(
                Some(line),
                format!(
                    "expected two columns (time, acceleration), found {}",
                    toks.len()
                ),
            ));
        }
        let t = number(toks[0], line, "time", err)?;
        let a = number(toks[1], line, "acceleration", err)?;
        if let Some(&prev) = times.last() {
            if t <= prev {
                return Err(err(
                    Some(line),
                    format!("time {t} is not after the previous time {prev}: times must increase"),
                ));
            }
        }
        times.push(t);
        accel.push(a);
    }
    Ok((times, accel))
}

fn parse_at2(text: &str, err: &dyn Fn(Option<usize>, String) -> SceneError) -> RecordResult {
    let lines: Vec<&str> = text.lines().collect();
    let Some(hi) = lines
        .iter()
        .take(4)
        .position(|l| l.to_ascii_uppercase().contains("NPTS"))
    else {
        return Err(err(Some(4), "AT2 header: no NPTS line".into()));
    };
    let header_line = hi + 1;
    let toks: Vec<String> = lines[hi]
        .to_ascii_uppercase()
        .split(|c: char| c.is_whitespace() || c == ',' || c == '=')
        .filter(|t| !t.is_empty())
        .map(str::to_string)
        .collect();
    let after = |key: &str| {
        toks.iter()
            .position(|t| t == key)
            .and_then(|i| toks.get(i + 1))
            .and_then(|t| t.parse::<f64>().ok())
    };
    let (npts, dt) = match (after("NPTS"), after("DT")) {
        (Some(n), Some(dt)) => (n, dt),
        _ => {
            // Old layout: "4000    .0100    NPTS, DT".
            let nums: Vec<f64> = toks.iter().filter_map(|t| t.parse::<f64>().ok()).collect();
            match nums.as_slice() {
                [n, dt, ..] => (*n, *dt),
                _ => {
                    return Err(err(
                        Some(header_line),
                        "AT2 header: cannot read NPTS and DT (expected e.g. \"NPTS=  4000, DT=   .0100 SEC\")".into(),
                    ))
                }
            }
        }
    };
    if !(npts >= 2.0 && npts.fract() == 0.0 && npts <= 1e9) {
        return Err(err(
            Some(header_line),
            format!("AT2 header: NPTS = {npts} is out of range: expected an integer >= 2"),
        ));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(err(
            Some(header_line),
            format!("AT2 header: DT = {dt} is out of range: expected DT > 0 s"),
        ));
    }
    let npts = npts as usize;
    let mut accel = Vec::with_capacity(npts);
    for (i, raw) in lines.iter().enumerate().skip(hi + 1) {
        let line = i + 1;
        for tok in raw
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|t| !t.is_empty())
        {
            if accel.len() == npts {
                return Err(err(
                    Some(line),
                    format!("more values than NPTS = {npts} (header line {header_line})"),
                ));
            }
            accel.push(number(tok, line, "value", err)?);
        }
    }
    if accel.len() != npts {
        return Err(err(
            Some(lines.len()),
            format!(
                "found {} values, expected NPTS = {npts} (header line {header_line})",
                accel.len()
            ),
        ));
    }
    let times = (0..npts).map(|i| i as f64 * dt).collect();
    Ok((times, accel))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    const BASE: &str = r#"name = "t"
duration_s = 1.0
[structure]
m1_kg = 29.5
m2_kg = 1.75
natural_frequency_hz = 7.0
damping_ratio = 0.05
friction_coefficient = 0.2
[input]
kind = "harmonic"
amplitude_m_s2 = 2.0
period_s = 0.143
[sampling]
rate_hz = 1000.0
"#;

    fn parse(text: &str) -> Result<Scene, SceneError> {
        Scene::parse(text, Path::new("scenes/x.toml"))
    }

    /// The error of `text`, checked to name the file, `line` and every one of `needles`.
    fn error_at(text: &str, line: usize, needles: &[&str]) -> SceneError {
        let e = parse(text).expect_err("the scene must be rejected");
        let msg = e.to_string();
        assert_eq!(e.line, Some(line), "{msg}");
        assert!(msg.starts_with(&format!("scenes/x.toml:{line}: ")), "{msg}");
        for n in needles {
            assert!(msg.contains(n), "{msg:?} lacks {n:?}");
        }
        e
    }

    fn scenes_dir() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join("host-sim")
            .join("scenes")
    }

    #[test]
    fn base_scene_parses() {
        let s = parse(BASE).unwrap();
        assert_eq!(s.name, "t");
        assert_eq!(s.samples, 1000);
        assert_eq!(s.rate_hz, 1000.0);
        assert_eq!(s.structure.g(), STANDARD_GRAVITY);
        assert_eq!(s.static_friction_coefficient, 0.2);
        assert_eq!(s.sensors, Sensors::default());
        assert_eq!(s.time(500), 0.5);
        assert_eq!(
            s.input,
            Input::Harmonic {
                amplitude_m_s2: 2.0,
                period_s: 0.143
            }
        );
        assert_eq!(
            s.rdm_train(),
            Some(ReversalTrain::Periodic {
                first_s: 0.0,
                half_period_s: 0.0715,
                initial_sign: 1.0
            })
        );
        assert_eq!(s.table_motion().accel(0.143 / 4.0), 2.0);
    }

    #[test]
    fn integers_period_gravity_and_name_default() {
        let text = BASE
            .replace("name = \"t\"\n", "")
            .replace("duration_s = 1.0", "duration_s = 2\ngravity_m_s2 = 9.81")
            .replace("natural_frequency_hz = 7.0", "natural_period_s = 0.25")
            .replace("rate_hz = 1000.0", "rate_hz = 999.6");
        let s = parse(&text).unwrap();
        assert_eq!(s.name, "x");
        assert_eq!(s.samples, 1999); // round(1999.2)
        assert_eq!(s.structure.g(), 9.81);
        assert!((s.structure.p() - 2.0 * std::f64::consts::PI * 4.0).abs() < 1e-12);
    }

    #[test]
    fn table1_file_is_the_default_scene() {
        let mut s = Scene::load(scenes_dir().join("table1.toml")).unwrap();
        assert!(s.source.is_some());
        s.source = None;
        assert_eq!(s, Scene::default_scene());
    }

    #[test]
    fn every_example_scene_loads() {
        let mut n = 0;
        for entry in fs::read_dir(scenes_dir()).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
                n += 1;
            }
        }
        assert!(n >= 6);
        let crit = Scene::load(scenes_dir().join("critical.toml")).unwrap();
        assert_eq!(crit.structure.regime(), ssvr_core::Regime::Critical);
        let over = Scene::load(scenes_dir().join("overdamped.toml")).unwrap();
        assert_eq!(over.structure.regime(), ssvr_core::Regime::Overdamped);
    }

    #[test]
    fn elcentro_record_in_g() {
        let s = Scene::load(scenes_dir().join("elcentro.toml")).unwrap();
        assert_eq!(s.static_friction_coefficient, 0.25);
        let Input::Record(r) = &s.input else {
            panic!("not a record")
        };
        assert_eq!(r.units, Units::G);
        let TableMotion::Record {
            times_s,
            accel_m_s2,
        } = &r.motion
        else {
            panic!("not a record motion")
        };
        assert_eq!(times_s.len(), 1560);
        assert_eq!(times_s[1559], 31.18);
        assert_eq!(accel_m_s2[0], 0.0063 * STANDARD_GRAVITY);
        let peak = accel_m_s2.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        assert!((peak / STANDARD_GRAVITY - 0.319).abs() < 1e-3, "{peak}");
        // Piecewise linear between samples, zero after the end.
        let mid = s.table_motion().accel(0.01);
        assert!((mid - 0.5 * (0.0063 + 0.00364) * STANDARD_GRAVITY).abs() < 1e-12);
        assert_eq!(s.table_motion().accel(31.2), 0.0);
        assert!(s.rdm_train().is_none());
    }

    #[test]
    fn reversal_trains() {
        let periodic = BASE.replace(
            "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
            "kind = \"reversals\"\nhalf_period_s = 0.0715\ninitial_sign = -1",
        );
        let s = parse(&periodic).unwrap();
        assert_eq!(
            s.input,
            Input::Reversals(Reversals::Periodic {
                half_period_s: 0.0715,
                initial_sign: -1.0
            })
        );
        assert_eq!(s.table_motion(), TableMotion::None);
        let times = BASE.replace(
            "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
            "kind = \"reversals\"\ntimes_s = [-0.01, 0, 0.03125,\n 0.5]",
        );
        let s = parse(&times).unwrap();
        let train = s.rdm_train().unwrap();
        assert_eq!(train.len(), Some(4));
        assert_eq!(train.get(0).unwrap().level, 1.0);
        assert_eq!(train.get(1).unwrap().level, -1.0);
        assert_eq!(train.get(2).unwrap().time_s, 0.03125);
    }

    #[test]
    fn sensors_table() {
        let text = format!("{BASE}[sensors]\nseed = 7\naccel_adc_bits = 16\ndisp_range_m = 0.1\n");
        let s = parse(&text).unwrap();
        assert_eq!(s.sensors.seed, 7);
        assert_eq!(s.sensors.accel_adc_bits, 16);
        assert_eq!(s.sensors.disp_range_m, 0.1);
        assert_eq!(s.sensors.accel_noise_rms_m_s2, 5e-3);
        assert_eq!(s.sensors.accel_range_m_s2, 39.2266);
        let empty = format!("{BASE}[sensors]\n");
        assert_eq!(parse(&empty).unwrap().sensors, Sensors::default());
    }

    #[test]
    fn unknown_keys_are_named_with_their_line() {
        error_at(
            &BASE.replace("damping_ratio = 0.05", "damping_ratio = 0.05\ndamping = 1"),
            8,
            &["[structure]", "unknown key `damping`"],
        );
        error_at(
            &BASE.replace("duration_s = 1.0", "duration_s = 1.0\nduraton = 2"),
            3,
            &["unknown key `duraton`"],
        );
        error_at(
            &format!("{BASE}[sensors]\nnoise = 1\n"),
            16,
            &["[sensors]", "unknown key `noise`"],
        );
        error_at(
            &format!("{BASE}[extra]\nx = 1\n"),
            15,
            &["unknown key `extra`"],
        );
        // A key of another input kind.
        error_at(
            &BASE.replace("period_s = 0.143", "period_s = 0.143\nhalf_period_s = 0.07"),
            13,
            &["[input] half_period_s", "kind = \"harmonic\""],
        );
    }

    #[test]
    fn missing_keys_are_named() {
        error_at(
            &BASE.replace("m2_kg = 1.75\n", ""),
            3,
            &["[structure]", "missing key `m2_kg`"],
        );
        error_at(
            &BASE.replace("duration_s = 1.0\n", ""),
            1,
            &["missing key `duration_s`"],
        );
        error_at(
            &BASE.replace("[sampling]\nrate_hz = 1000.0\n", ""),
            1,
            &["missing table [sampling]"],
        );
        error_at(
            &BASE.replace("natural_frequency_hz = 7.0\n", ""),
            3,
            &["[structure]", "natural_frequency_hz", "natural_period_s"],
        );
        error_at(
            &BASE.replace("period_s = 0.143\n", ""),
            9,
            &["[input]", "missing key `period_s`"],
        );
        error_at(
            &BASE.replace(
                "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
                "kind = \"reversals\"",
            ),
            9,
            &["[input]", "half_period_s", "times_s"],
        );
        error_at(
            &BASE.replace(
                "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
                "kind = \"record\"\nfile = \"a.txt\"",
            ),
            9,
            &["[input]", "missing key `units`"],
        );
    }

    #[test]
    fn bad_values_are_named_with_their_line() {
        let e = error_at(
            &BASE.replace("damping_ratio = 0.05", "damping_ratio = 1.2"),
            7,
            &["[structure] damping_ratio = 1.2 is out of range: expected 0 <= damping ratio < 1"],
        );
        assert_eq!(e.file, Path::new("scenes/x.toml"));
        let cases: &[(&str, &str, usize, &str)] = &[
            ("m1_kg = 29.5", "m1_kg = 0", 4, "[structure] m1_kg = 0"),
            ("m2_kg = 1.75", "m2_kg = -1", 5, "[structure] m2_kg = -1"),
            (
                "m2_kg = 1.75",
                "m2_kg = nan",
                5,
                "[structure] m2_kg must be a finite",
            ),
            (
                "natural_frequency_hz = 7.0",
                "natural_frequency_hz = 0.0",
                6,
                "[structure] natural_frequency_hz = 0",
            ),
            (
                "natural_frequency_hz = 7.0",
                "natural_period_s = -0.1",
                6,
                "[structure] natural_period_s = -0.1",
            ),
            (
                "friction_coefficient = 0.2",
                "friction_coefficient = 0.0",
                8,
                "[structure] friction_coefficient = 0",
            ),
            (
                "friction_coefficient = 0.2",
                "friction_coefficient = 0.2\nstatic_friction_coefficient = 0.1",
                9,
                "[structure] static_friction_coefficient = 0.1",
            ),
            (
                "duration_s = 1.0",
                "duration_s = -1.0",
                2,
                "duration_s = -1",
            ),
            (
                "duration_s = 1.0",
                "duration_s = 1e-9",
                2,
                "duration_s = 0.000000001",
            ),
            (
                "duration_s = 1.0",
                "duration_s = 1.0\ngravity_m_s2 = 0",
                3,
                "gravity_m_s2 = 0",
            ),
            (
                "rate_hz = 1000.0",
                "rate_hz = 0",
                14,
                "[sampling] rate_hz = 0",
            ),
            (
                "rate_hz = 1000.0",
                "rate_hz = inf",
                14,
                "[sampling] rate_hz must be a finite",
            ),
            (
                "amplitude_m_s2 = 2.0",
                "amplitude_m_s2 = -2.0",
                11,
                "[input] amplitude_m_s2 = -2",
            ),
            (
                "period_s = 0.143",
                "period_s = 0",
                12,
                "[input] period_s = 0",
            ),
            (
                "kind = \"harmonic\"",
                "kind = \"sine\"",
                10,
                "[input] kind: unknown variant `sine`",
            ),
            (
                "m1_kg = 29.5",
                "m1_kg = \"heavy\"",
                4,
                "[structure] m1_kg: invalid type",
            ),
        ];
        for (from, to, line, needle) in cases {
            error_at(&BASE.replace(from, to), *line, &[needle]);
        }
        let rev = |body: &str| {
            BASE.replace(
                "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143",
                &format!("kind = \"reversals\"\n{body}"),
            )
        };
        error_at(
            &rev("times_s = [0.0, 0.1,\n  0.1]"),
            12,
            &["[input] times_s[2] = 0.1", "strictly increasing"],
        );
        error_at(&rev("times_s = []"), 11, &["[input] times_s is empty"]);
        error_at(
            &rev("half_period_s = 0.1\ninitial_sign = 0.5"),
            12,
            &["[input] initial_sign = 0.5", "1 or -1"],
        );
        error_at(
            &rev("half_period_s = 0"),
            11,
            &["[input] half_period_s = 0"],
        );
        error_at(
            &format!("{BASE}[sensors]\naccel_adc_bits = 0\n"),
            16,
            &["[sensors] accel_adc_bits = 0"],
        );
        error_at(
            &format!("{BASE}[sensors]\nseed = -1\n"),
            16,
            &["[sensors] seed: invalid value"],
        );
        error_at(
            &format!("{BASE}[sensors]\ndisp_noise_rms_m = -1e-6\n"),
            16,
            &["[sensors] disp_noise_rms_m = -0.000001"],
        );
        error_at(
            &BASE.replace("damping_ratio = 0.05", "damping_ratio = "),
            7,
            &["[structure]"],
        );
    }

    fn record_scene(dir: &Path, file: &str, units: &str, scale: Option<f64>) -> PathBuf {
        let scale = scale.map_or(String::new(), |s| format!("scale = {s}\n"));
        let text = BASE.replace(
            "kind = \"harmonic\"\namplitude_m_s2 = 2.0\nperiod_s = 0.143\n",
            &format!("kind = \"record\"\nfile = \"{file}\"\nunits = \"{units}\"\n{scale}"),
        );
        let path = dir.join("scene.toml");
        fs::write(&path, text).unwrap();
        path
    }

    fn motion(s: &Scene) -> (Vec<f64>, Vec<f64>) {
        match s.table_motion() {
            TableMotion::Record {
                times_s,
                accel_m_s2,
            } => (times_s, accel_m_s2),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn two_column_record_and_units() {
        let dir = tempfile::tempdir().unwrap();
        fs::create_dir(dir.path().join("data")).unwrap();
        fs::write(
            dir.path().join("data/rec.txt"),
            "# time accel\n\n0.0  1.0\n0.01, -2.0   # comma-separated\n\t0.02\t0.5\n",
        )
        .unwrap();
        for (units, scale, factor) in [
            ("g", None, STANDARD_GRAVITY),
            ("m/s2", None, 1.0),
            ("gal", Some(2.0), 0.02),
            ("m/s2", Some(-0.5), -0.5),
        ] {
            let s = Scene::load(record_scene(dir.path(), "data/rec.txt", units, scale)).unwrap();
            let (t, a) = motion(&s);
            assert_eq!(t, [0.0, 0.01, 0.02]);
            assert_eq!(a, [factor, -2.0 * factor, 0.5 * factor], "{units}");
            let Input::Record(r) = &s.input else { panic!() };
            assert_eq!(r.path, dir.path().join("data/rec.txt"));
            assert_eq!(r.units.name(), units);
        }
    }

    #[test]
    fn at2_record() {
        let dir = tempfile::tempdir().unwrap();
        let at2 = "PEER NGA STRONG MOTION DATABASE RECORD\n\
                   IMPERIAL VALLEY 5/19/40, EL CENTRO ARRAY #9, 180\n\
                   ACCELERATION TIME SERIES IN UNITS OF G\n\
                   NPTS=    7, DT=   .0100 SEC,\n  \
                   .1000000E-01  .2000000E-01 -.3000000E-01  .4000000E-01  .5000000E-01\n  \
                   -.6000000E-01  .7000000E-01\n";
        fs::write(dir.path().join("rec.AT2"), at2).unwrap();
        let s = Scene::load(record_scene(dir.path(), "rec.AT2", "g", None)).unwrap();
        let (t, a) = motion(&s);
        assert_eq!(t.len(), 7);
        assert_eq!(t[6], 0.06);
        assert_eq!(a[2], -0.03 * STANDARD_GRAVITY);
        assert_eq!(a[6], 0.07 * STANDARD_GRAVITY);
        // The old header layout "NPTS, DT" after the numbers.
        let old = at2.replace("NPTS=    7, DT=   .0100 SEC,", "    7    .0100    NPTS, DT");
        fs::write(dir.path().join("old.at2"), old).unwrap();
        let s = Scene::load(record_scene(dir.path(), "old.at2", "g", None)).unwrap();
        assert_eq!(motion(&s).0.len(), 7);
        // Too few values: the record file and NPTS are named.
        fs::write(
            dir.path().join("short.at2"),
            at2.replace("  .7000000E-01", ""),
        )
        .unwrap();
        let e = Scene::load(record_scene(dir.path(), "short.at2", "g", None)).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("short.at2:6:") && msg.contains("NPTS = 7"),
            "{msg}"
        );
        // A bad value: its line.
        fs::write(
            dir.path().join("bad.at2"),
            at2.replace("-.6000000E-01", "-.6E-0x"),
        )
        .unwrap();
        let e = Scene::load(record_scene(dir.path(), "bad.at2", "g", None)).unwrap_err();
        assert!(
            e.to_string().contains("bad.at2:6: value \"-.6E-0x\""),
            "{e}"
        );
    }

    #[test]
    fn record_errors_name_the_record_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        let cases = [
            ("0 1\n0.01 2 3\n", 2, "two columns"),
            ("0 1\n# c\n0.01 abc\n", 3, "acceleration \"abc\""),
            ("0 1\n0.01 2\n0.01 3\n", 3, "not after the previous time"),
            ("0 1\n", 0, "at least 2"),
        ];
        for (i, (text, line, needle)) in cases.iter().enumerate() {
            let name = format!("r{i}.txt");
            fs::write(dir.path().join(&name), text).unwrap();
            let scene = record_scene(dir.path(), &name, "g", None);
            let e = Scene::load(&scene).unwrap_err();
            let msg = e.to_string();
            assert_eq!(e.file, dir.path().join(&name), "{msg}");
            if *line > 0 {
                assert_eq!(e.line, Some(*line), "{msg}");
            }
            assert!(msg.contains(needle), "{msg}");
            assert!(msg.contains("scene.toml:11"), "{msg}"); // the referencing key
        }
        // A missing record file: the scene's `file` key.
        let scene = record_scene(dir.path(), "nope.txt", "g", None);
        let e = Scene::load(&scene).unwrap_err();
        assert_eq!(e.file, scene);
        assert_eq!(e.line, Some(11));
        assert!(e.to_string().contains("[input] file = \"nope.txt\""), "{e}");
        // Bad units.
        let scene = record_scene(dir.path(), "r0.txt", "furlongs", None);
        let e = Scene::load(&scene).unwrap_err();
        assert_eq!(e.line, Some(12));
        assert!(
            e.to_string().contains("[input] units: unknown variant"),
            "{e}"
        );
    }

    #[test]
    fn missing_scene_file() {
        let e = Scene::load("/nonexistent/scene.toml").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("/nonexistent/scene.toml: cannot read"),
            "{e}"
        );
    }
}
