//! The CSV of `run`: its header ([`CSV_HEADER`]), the number format ([`Num`]), the default output
//! path ([`default_out_path`]) and the buffered row writer ([`CsvWriter`]) that writes one row per
//! sample as soon as it is computed.

use crate::scene::Scene;
use crate::sensors::SensorFrame;
use anyhow::{anyhow, Result};
use ssvr_proto::Event;
use std::fmt;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

/// The CSV header of `run` (one row per sample follows).
///
/// * `t_s`: t_k = k / rate_hz;
/// * `table_accel_m_s2`, `base_accel_m_s2`, `measured_top_accel_m_s2`: the accelerometers;
/// * `rel_disp_m`: the measured base-to-table displacement (the slip seen by the detector);
/// * `reversal`: the friction level (F/F0, −1 or 1) of a slip start or reversal detected at this
///   sample and pushed into the estimator before this sample's prediction, 0 otherwise (a stick
///   is 0 here whatever the stick policy, see `detected_event`);
/// * `predicted_top_accel_m_s2`: the estimator's ü1 (f32);
/// * `truth_top_accel_m_s2`: the exact ü1;
/// * extras: `ideal_predicted_top_accel_m_s2` (the estimator fed the true events),
///   `truth_slip_m`, `truth_slip_dir` (+1 / −1 sliding, 0 stuck), `detected_event`
///   (`slip_start`, `reversal`, `stick` or empty), `event_age_samples` (the detector's
///   back-dating, empty without an event), `flags` (the sensor `FLAG_*` bits).
pub const CSV_HEADER: &str = "t_s,table_accel_m_s2,base_accel_m_s2,measured_top_accel_m_s2,rel_disp_m,reversal,predicted_top_accel_m_s2,truth_top_accel_m_s2,ideal_predicted_top_accel_m_s2,truth_slip_m,truth_slip_dir,detected_event,event_age_samples,flags";

/// The CSV is flushed every this many rows (an interrupted run keeps what was produced).
pub const FLUSH_EVERY_ROWS: u64 = 4096;

/// The default CSV output: `<scene-stem>.run.csv` next to the scene file, or `default.run.csv` in
/// the working directory for the built-in scene.
pub fn default_out_path(scene: &Scene) -> PathBuf {
    match &scene.source {
        Some(p) => {
            let stem = p
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into());
            p.with_file_name(format!("{stem}.run.csv"))
        }
        None => PathBuf::from("default.run.csv"),
    }
}

/// A CSV number: the shortest representation that reads back to the same f32/f64, in plain
/// decimal for 1e-5 <= |x| < 1e16 (and 0), in exponent form (`1.5e-48`) otherwise.
#[derive(Debug, Clone, Copy)]
pub struct Num<T>(pub T);

macro_rules! num_display {
    ($t:ty) => {
        impl fmt::Display for Num<$t> {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                let a = self.0.abs();
                if a == 0.0 || !a.is_finite() || (1e-5..1e16).contains(&a) {
                    write!(f, "{}", self.0)
                } else {
                    write!(f, "{:e}", self.0)
                }
            }
        }
    };
}
num_display!(f32);
num_display!(f64);

/// One CSV row: a sample's measurement, detection, predictions and truth.
pub(super) struct Row<'a> {
    /// t_k (s).
    pub t: f64,
    /// The measurement.
    pub measured: &'a SensorFrame,
    /// The level of a slip start or reversal pushed at this sample, 0 otherwise.
    pub pushed: i32,
    /// The detected event, if any.
    pub event: Option<Event>,
    /// The estimator's ü1.
    pub predicted: f32,
    /// The exact ü1.
    pub truth_top: f64,
    /// The ideal estimator's ü1.
    pub ideal: f32,
    /// The true slip (m).
    pub truth_slip_m: f64,
    /// The true slip direction (+1 / −1 sliding, 0 stuck).
    pub truth_dir: i32,
}

/// The buffered CSV output: every error names the output, the rows written are counted.
pub(super) struct CsvWriter<'a, W: Write> {
    out: BufWriter<W>,
    name: &'a str,
    rows: u64,
}

impl<'a, W: Write> CsvWriter<'a, W> {
    /// A writer into `w`, called `name` in errors.
    pub fn new(w: W, name: &'a str) -> Self {
        Self {
            out: BufWriter::with_capacity(1 << 16, w),
            name,
            rows: 0,
        }
    }

    fn err(name: &str, e: std::io::Error) -> anyhow::Error {
        anyhow!(e).context(format!("writing {name}"))
    }

    /// The output's name.
    pub fn name(&self) -> &'a str {
        self.name
    }

    /// Rows written so far (header excluded).
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Write [`CSV_HEADER`].
    pub fn header(&mut self) -> Result<()> {
        writeln!(self.out, "{CSV_HEADER}").map_err(|e| Self::err(self.name, e))
    }

    /// Write one row.
    pub fn row(&mut self, r: &Row) -> Result<()> {
        let name = self.name;
        let f = r.measured;
        let (ev_name, age) = match r.event {
            None => ("", None),
            Some(e) => (e.kind.name(), Some(e.age_samples)),
        };
        write!(
            self.out,
            "{},{},{},{},{},{},{},{},{},{},{},{ev_name},",
            Num(r.t),
            Num(f.table_accel_m_s2),
            Num(f.base_accel_m_s2),
            Num(f.top_accel_m_s2),
            Num(f.disp_m),
            r.pushed,
            Num(r.predicted),
            Num(r.truth_top),
            Num(r.ideal),
            Num(r.truth_slip_m),
            r.truth_dir,
        )
        .map_err(|e| Self::err(name, e))?;
        if let Some(a) = age {
            write!(self.out, "{a}").map_err(|e| Self::err(name, e))?;
        }
        writeln!(self.out, ",{}", f.flags).map_err(|e| Self::err(name, e))?;
        self.rows += 1;
        Ok(())
    }

    /// Flush the rows so far.
    pub fn flush(&mut self) -> Result<()> {
        self.out.flush().map_err(|e| Self::err(self.name, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_numbers_round_trip_without_long_zero_runs() {
        for x in [
            0.0f64,
            -0.0,
            0.3,
            1e-5,
            2.5e-6,
            -1.65863499991046e-48,
            1e16,
            123.456,
        ] {
            let s = Num(x).to_string();
            assert_eq!(s.parse::<f64>().unwrap(), x, "{s}");
            assert!(s.len() < 24, "{s}");
        }
        assert_eq!(Num(-1.6586e-48f64).to_string(), "-1.6586e-48");
        assert_eq!(Num(0.0002f64).to_string(), "0.0002");
        assert_eq!(Num(-0.0000011267663f32).to_string(), "-1.1267663e-6");
        assert_eq!(Num(1.5f32).to_string(), "1.5");
    }

    #[test]
    fn default_out_paths() {
        let mut s = Scene::default_scene();
        assert_eq!(default_out_path(&s), PathBuf::from("default.run.csv"));
        s.source = Some(PathBuf::from("dir/elcentro.toml"));
        assert_eq!(default_out_path(&s), PathBuf::from("dir/elcentro.run.csv"));
    }
}
