//! The table input of a scene (`[input]`): harmonic motion, a prescribed friction train or an
//! earthquake record.

use crate::error::{line_of, SceneError};
use crate::parse::ParseContext;
use crate::record::{parse_record, Record};
use crate::table_motion::TableMotion;
use crate::units::Units;
use serde::Deserialize;
use ssvr_core::ReversalTrain;
use std::ops::Range;
use toml::Spanned;

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

// ---------------------------------------------------------------------------------------------
// Raw TOML layout and validation.

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum Kind {
    Harmonic,
    Reversals,
    Record,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawInput {
    kind: Spanned<Kind>,
    amplitude_m_s2: Option<Spanned<f64>>,
    period_s: Option<Spanned<f64>>,
    half_period_s: Option<Spanned<f64>>,
    times_s: Option<Spanned<Vec<Spanned<f64>>>>,
    initial_sign: Option<Spanned<f64>>,
    file: Option<Spanned<String>>,
    units: Option<Spanned<Units>>,
    scale: Option<Spanned<f64>>,
    start_s: Option<Spanned<f64>>,
    table_lag_s: Option<Spanned<f64>>,
}

impl ParseContext<'_> {
    /// `[input] start_s`: the table at rest until then (s; 0 when absent). Table motion only.
    pub(crate) fn start(&self, table: &Spanned<RawInput>) -> Result<f64, SceneError> {
        self.table_seconds(table, "start_s", &table.get_ref().start_s)
    }

    /// `[input] table_lag_s`: how late the table follows the planned input (s; 0 when absent):
    /// the simulated table's motion is the input delayed by it, what the controller is told of
    /// the input is not (a servo table's lag). Table motion only.
    pub(crate) fn table_lag(&self, table: &Spanned<RawInput>) -> Result<f64, SceneError> {
        self.table_seconds(table, "table_lag_s", &table.get_ref().table_lag_s)
    }

    /// A time of the table's motion, `[input] key` (s, finite, ≥ 0; 0 when absent): an error
    /// for a reversals input (a friction train has no table motion).
    fn table_seconds(
        &self,
        table: &Spanned<RawInput>,
        key: &str,
        value: &Option<Spanned<f64>>,
    ) -> Result<f64, SceneError> {
        let Some(v) = value else {
            return Ok(0.0);
        };
        if *table.get_ref().kind.get_ref() == Kind::Reversals {
            return Err(self.err(
                v.span(),
                format!(
                    "[input] {key} = {} does not apply to kind = \"reversals\" (a friction \
                     train has no table motion)",
                    v.get_ref()
                ),
            ));
        }
        self.check(
            Some("input"),
            key,
            v,
            v.get_ref().is_finite() && *v.get_ref() >= 0.0,
            &format!("{key} >= 0 s"),
        )
    }

    /// The `[input]` table.
    pub(crate) fn input(&self, table: &Spanned<RawInput>) -> Result<Input, SceneError> {
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
                let path = self.relative_to_scene(file.get_ref());
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
}
