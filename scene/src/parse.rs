//! The parse context (the source text and the file it came from) and the messages every table
//! shares: TOML errors located at `file:line` with their `[section] key`, range checks and
//! missing keys.

use crate::error::{line_of, SceneError};
use ssvr_core::Error as CoreError;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// The parse context of one scene document: the source text (for lines and sections) and the
/// file it came from (named in every message; its folder anchors relative record paths).
pub(crate) struct ParseContext<'a> {
    /// The TOML text.
    pub(crate) src: &'a str,
    /// The file named in messages.
    pub(crate) origin: &'a Path,
}

impl ParseContext<'_> {
    pub(crate) fn err(&self, span: Range<usize>, message: String) -> SceneError {
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

    /// The table header (`[a.b]` or `[[a.b]]`) on the line holding byte `offset`, if that line is
    /// one: its dotted name and whether it is an array of tables.
    fn header_at(&self, offset: usize) -> Option<(String, bool)> {
        let end = offset.min(self.src.len());
        let start = self.src[..end].rfind('\n').map_or(0, |i| i + 1);
        let stop = self.src[end..]
            .find('\n')
            .map_or(self.src.len(), |i| end + i);
        let line = self.src[start..stop].trim();
        let (inner, array) = match line.strip_prefix("[[") {
            Some(rest) => (rest.split("]]").next()?, true),
            None => (line.strip_prefix('[')?.split(']').next()?, false),
        };
        Some((inner.trim().to_string(), array))
    }

    /// An unknown key that is a table header (`[friction]`): "unknown table `[friction]`" under
    /// the parent table of the header (none for a top-level table), not under the table before it.
    fn unknown_table(&self, offset: usize, message: &str) -> Option<String> {
        let rest = message.strip_prefix("unknown key `")?;
        let (_, rest) = rest.split_once('`')?;
        let (name, array) = self.header_at(offset)?;
        let (open, close) = if array { ("[[", "]]") } else { ("[", "]") };
        let parent = name
            .rsplit_once('.')
            .map_or(String::new(), |(p, _)| format!("[{}] ", p.trim()));
        Some(format!("{parent}unknown table `{open}{name}{close}`{rest}"))
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

    pub(crate) fn toml_error(&self, e: &toml::de::Error) -> SceneError {
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
        if let Some(what) = self.unknown_table(span.start, &message) {
            return self.err(span, what);
        }
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
    pub(crate) fn check(
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

    pub(crate) fn missing<T>(
        &self,
        section: &str,
        table: &Spanned<T>,
        message: String,
    ) -> SceneError {
        self.err(table.span(), format!("[{section}] {message}"))
    }
}

pub(crate) fn qualified(section: Option<&str>, key: &str) -> String {
    match section {
        Some(s) => format!("[{s}] {key}"),
        None => key.to_string(),
    }
}

/// A core validation error phrased with the TOML key.
pub(crate) fn core_message(key: &str, value: f64, e: &CoreError) -> String {
    match e {
        CoreError::NotFinite(_) => format!("{key} must be a finite number"),
        CoreError::OutOfRange { expected, .. } => {
            format!("{key} = {value} is out of range: expected {expected}")
        }
        other => format!("{key}: {other}"),
    }
}
