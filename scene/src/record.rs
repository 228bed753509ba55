//! Earthquake records (scene `kind = "record"`): two-column text and PEER NGA `.AT2` files.

use crate::error::SceneError;
use crate::table_motion::TableMotion;
use crate::units::Units;
use std::path::{Path, PathBuf};

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
