//! A scene's sensor log for the QEMU image (format `ssvr_proto::log`, version 1): the truth,
//! measured by the sensor model, one record per sample; and what the host keeps of the truth
//! to compare with.

use crate::model::{self, Model};
use crate::pipeline::sample_of;
use crate::scene::Scene;
use crate::sensors;
use crate::truth::{self, TruthInput};
use anyhow::{anyhow, bail, Context, Result};
use ssvr_proto::log::{encode_header, encode_record, Header, MAX_RECORD_LEN};
use ssvr_proto::Sample;
use std::path::Path;

/// The log header of a scene: its sample rate and the structure the controller is told (the
/// estimator's prior, which the image is built for), `options`, `sample_count`.
pub fn header_for(scene: &Scene, options: u16, samples: usize) -> Result<Header> {
    let count = u32::try_from(samples)
        .ok()
        .filter(|&n| n != ssvr_proto::log::COUNT_UNTIL_EOF)
        .ok_or_else(|| anyhow!("too many samples for one log: {samples}"))?;
    Ok(Header::new(
        scene.rate_hz,
        scene.estimator.params,
        options,
        count,
    ))
}

/// Encode a sensor log.
pub fn encode(header: &Header, samples: &[Sample]) -> Vec<u8> {
    let mut b = Vec::with_capacity(80 + samples.len() * 22);
    b.extend_from_slice(&encode_header(header));
    let mut rec = [0u8; MAX_RECORD_LEN];
    for s in samples {
        let n = encode_record(s, &mut rec);
        b.extend_from_slice(&rec[..n]);
    }
    b
}

/// Write a sensor log to `path`.
pub fn write(path: &Path, header: &Header, samples: &[Sample]) -> Result<()> {
    std::fs::write(path, encode(header, samples))
        .with_context(|| format!("cannot write the sensor log {}", path.display()))
}

/// A scene's sensor log and what the host knows of its truth.
#[derive(Debug, Clone)]
pub struct SceneLog {
    /// One sample per record.
    pub samples: Vec<Sample>,
    /// The truth's ü1 per sample (m/s²).
    pub truth_top: Vec<f64>,
    /// The truth's friction changes.
    pub truth_changes: usize,
    /// The model [`model::choose_for`] picks from a simulation of the prior, and why.
    pub model: (Model, String),
}

/// The sensor log of a scene: truth, sensor model, one record per sample; with the truth's ü1
/// per sample, its number of friction changes and the model it calls for.
pub fn scene_log(scene: &Scene) -> Result<SceneLog> {
    let table = scene.table_motion();
    let input = TruthInput::new(&scene.structure, &table, scene.duration_s)
        .with_static_friction(scene.static_friction_coefficient)
        .with_friction(scene.friction);
    let truth = truth::simulate(&input).map_err(|e| anyhow!("truth simulation: {e}"))?;
    let measured = sensors::measure_all(&scene.sensors, &truth, scene.rate_hz, scene.samples);
    if measured.len() as u64 != scene.samples {
        bail!(
            "the truth covers {} of the scene's {} samples",
            measured.len(),
            scene.samples
        );
    }
    Ok(SceneLog {
        samples: measured.iter().map(|(_, f)| sample_of(f)).collect(),
        truth_top: measured.iter().map(|(t, _)| t.top_accel_m_s2).collect(),
        truth_changes: truth.friction_train().len(),
        model: model::choose_for(scene)?,
    })
}
