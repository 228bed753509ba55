//! The defmt messages the firmware streams (the `emit_*` functions: feature `defmt`). Every message is a name followed
//! by `key={=type}` fields; the host decodes them with `defmt-decoder` by their typed fields
//! (name, key, value), not by parsing the text. The names and keys are listed here
//! ([`FRAME_FIELDS`], [`EVENT_FIELDS`], [`STATS_FIELDS`], [`PLAN_FIELDS`]) for the host decoder.
//!
//! * `sample`: one `Frame`: [`FRAME_FIELDS`], then [`EVENT_FIELDS`] when it has an event;
//! * `stats`: the `Stats` of the run;
//! * `plan`: the plan the image was built with (its digest and sizes).

#[cfg(feature = "defmt")]
use crate::frame::Frame;
#[cfg(feature = "defmt")]
use crate::pipeline::Stats;
#[cfg(feature = "defmt")]
use crate::plan::Plan;

/// Name of a frame's message.
pub const FRAME: &str = "sample";
/// Fields of a frame, in order: index (u32), flags (u8), table, base, top accelerations and
/// displacement (f32, SI), prediction (f32, m/s²).
pub const FRAME_FIELDS: [&str; 7] = ["idx", "flags", "table", "base", "top", "disp", "pred"];
/// Fields of a frame's event, after [`FRAME_FIELDS`]: kind code (u8), level (i8), age (f32,
/// samples).
pub const EVENT_FIELDS: [&str; 3] = ["ev", "level", "age"];
/// Name of the counters' message.
pub const STATS: &str = "stats";
/// Fields of the counters (u32 each), in `Stats` order.
pub const STATS_FIELDS: [&str; 8] = [
    "samples", "invalid", "dropped", "events", "pushed", "rejected", "sticks", "clamped",
];
/// Name of the plan's message.
pub const PLAN: &str = "plan";
/// Fields of the plan: digest (u32), model code (u8), rate (f64, Hz), ring, max_age, history,
/// storage (u32).
pub const PLAN_FIELDS: [&str; 7] = [
    "digest", "model", "rate_hz", "ring", "max_age", "history", "storage",
];

/// Stream one frame.
#[cfg(feature = "defmt")]
pub fn emit_frame(f: &Frame) {
    match &f.event {
        None => defmt::info!(
            "sample idx={=u32} flags={=u8} table={=f32} base={=f32} top={=f32} disp={=f32} pred={=f32}",
            f.index,
            f.flags,
            f.channels[0],
            f.channels[1],
            f.channels[2],
            f.channels[3],
            f.prediction
        ),
        Some(e) => defmt::info!(
            "sample idx={=u32} flags={=u8} table={=f32} base={=f32} top={=f32} disp={=f32} pred={=f32} ev={=u8} level={=i8} age={=f32}",
            f.index,
            f.flags,
            f.channels[0],
            f.channels[1],
            f.channels[2],
            f.channels[3],
            f.prediction,
            e.kind.code(),
            e.level,
            e.age_samples
        ),
    }
}

/// Stream the counters of a run.
#[cfg(feature = "defmt")]
pub fn emit_stats(s: &Stats) {
    defmt::info!(
        "stats samples={=u32} invalid={=u32} dropped={=u32} events={=u32} pushed={=u32} rejected={=u32} sticks={=u32} clamped={=u32}",
        s.samples,
        s.invalid,
        s.dropped,
        s.events,
        s.pushed,
        s.rejected,
        s.sticks,
        s.clamped
    );
}

/// Stream the plan the image runs: its digest ([`Plan::digest`], computed when the image was
/// built) and sizes.
#[cfg(feature = "defmt")]
pub fn emit_plan(p: &Plan, digest: u32) {
    defmt::info!(
        "plan digest={=u32} model={=u8} rate_hz={=f64} ring={=u32} max_age={=u32} history={=u32} storage={=u32}",
        digest,
        p.model as u8,
        p.specimen.sample_rate_hz,
        p.ring as u32,
        p.max_age as u32,
        p.history as u32,
        p.storage as u32
    );
}
