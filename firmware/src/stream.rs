//! The streaming side: each queued frame as a defmt message ([`drain`],
//! `ssvr_proto::stream::emit_frame`), and the identified μ ([`emit_mu`]).

use crate::plan::ImagePipeline;
use heapless::spsc::Consumer;
use ssvr_proto::Frame;

/// Stream every queued frame; returns how many.
pub fn drain(consumer: &mut Consumer<'_, Frame>) -> u32 {
    let mut n: u32 = 0;
    while let Some(f) = consumer.dequeue() {
        ssvr_proto::stream::emit_frame(&f);
        n = n.wrapping_add(1);
    }
    n
}

/// Report the identified friction coefficient: `mu estimate=.. std=.. samples=..`, or `mu none`
/// (models that identify μ only).
pub fn emit_mu(pipe: &ImagePipeline) {
    use ssvr_proto::Model as _;
    if pipe.model().kind() == ssvr_proto::ModelKind::Rectangular {
        return;
    }
    match pipe.model().mu_estimate() {
        Some(m) => defmt::info!(
            "mu estimate={=f64} std={=f64} samples={=u32}",
            m.mu,
            m.std,
            m.blocks
        ),
        None => defmt::info!("mu none"),
    }
}
