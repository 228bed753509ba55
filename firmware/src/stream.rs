//! The streaming side: each queued frame as a defmt message ([`drain`],
//! `ssvr_proto::stream::emit_frame`), and the identified μ, f and ξ ([`emit_mu`]).

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
/// (models that identify μ only), then the f and ξ in use: `osc f_hz=.. xi=.. adoptions=..`
/// (models that identify them, fuse mode), and a velocity-dependent friction law in use:
/// `law mu_slow=.. mu_fast=.. rate_s_m=.. adoptions=..` (a model that follows one).
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
    // The top oscillator's f and ξ in use (fuse mode: identified online) and its adoptions:
    // `osc f_hz=.. xi=.. adoptions=..`.
    if let Some(o) = pipe.model().oscillator() {
        defmt::info!(
            "osc f_hz={=f64} xi={=f64} adoptions={=u32}",
            o.natural_frequency_hz,
            o.damping_ratio,
            o.adoptions
        );
    }
    // A velocity-dependent friction law in use (identified online in fuse mode) and its
    // adoptions: `law mu_slow=.. mu_fast=.. rate_s_m=.. adoptions=..`.
    if let Some(l) = pipe.model().friction_law() {
        defmt::info!(
            "law mu_slow={=f32} mu_fast={=f32} rate_s_m={=f32} adoptions={=u32}",
            l.mu_slow,
            l.mu_fast,
            l.rate_s_m,
            l.adoptions
        );
    }
}
