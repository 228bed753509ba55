//! The stick-slip aware estimator (beyond the paper): follows the measurement through stick phases
//! and identifies the friction coefficient online.
//!
//! The top-mass state z = (p²δ, pδ') (δ = u1 − u2, units m/s²) is continuous across every phase
//! change, and ü1 = −(z0 + 2ξ z1) in every phase. Only the governing equation changes:
//!
//! * **sliding** (friction level s = ±1): δ'' + 2aδ' + Mp²δ = −s·M·gμ (eq 25), a free vibration
//!   about z_eq = (−s·gμ, 0): z(τ) = Φs(τ)(z − z_eq) + z_eq, Φs = [[ecp, p·es], [−Mp·es, ecm]];
//! * **sticking**: the base moves with the table and the top mass is a fixed-base oscillator driven
//!   by the measured table acceleration, δ'' + 2ξpδ' + p²δ = −ü_g, with ü_g linear between samples
//!   (Nigam–Jennings): for ü_g = c0 + c1·t the particular solution is z_p = (−(c0 + c1 t) + 2ξc1/p,
//!   −c1/p), and z(τ) = Φf(τ)(z − z_p(0)) + z_p(τ) exactly.
//!
//! Per sample both maps are precomputed 2×2 matrices (plus input vectors); a phase change inside
//! a sample interval is integrated exactly in pieces with the kernel. The estimator runs them on
//! the state w = (ü1, z1) = T·z, T = [[−1, −2ξ], [0, 1]] (each map T·Φ·T, computed in f64): the
//! prediction is the state's first component. Phase changes are reported late by the detector: the
//! last `history` samples are kept, and a late event re-simulates from the sample before it, so
//! every later sample is right.
//!
//! **Layout (per-sample cost).** The history lives in `H` ≥ `history` slots of storage (runtime
//! length, [`StickSlipEstimator::with_history`]), 25 bytes per slot in f32: 16 bytes written by
//! every sample (the table acceleration, the measured top acceleration and the state), and the
//! phases of the interval that starts there packed in one byte (start phase, number of switches,
//! the phase after each switch: 2 bits each) with its switch fractions, both written by events
//! only. The phases are kept lazily: every interval from the last event on is in the current
//! phase without a switch (`plain_from`); an event first writes the phase bytes of the intervals
//! since the previous one. The ring runs over the whole storage, after a slot that holds a copy of
//! the ring's last sample when the storage exceeds the history (so that the sample after the wrap
//! finds its predecessor in the slot before it). The per-sample forcing of the current sliding
//! phase (±g·μ times the force vector) is precomputed. The steady-state sliding sample is then one
//! 2×2 map from the slot before, one slot written, and a ring index compared with a precomputed
//! limit (`fast_until`: the mode is plain sliding and no *mark* follows); the stuck sample is the
//! same with the fixed-base map (`stuck_until`), one map of ten coefficients with the observer's
//! correction folded in. Everything else takes the general path: a switch inside the interval, a
//! phase change at its end, a non-finite table acceleration, sample 0, and the marks, where the
//! rare work is done: the ring's wrap and the identification blocks.
//! [`StickSlipEstimator::update_block`] runs a block of samples, bit for bit as many `update`s:
//! its steady runs (up to the next mark, whose work it then does) keep the coefficients and the
//! state in registers and check their inputs once, at the end (a non-finite one redoes the run
//! sample by sample); the firmware runs it on batches of 16 samples.
//!
//! **Stuck-phase observer.** Switching between the sliding and the stuck dynamics at given
//! times (the estimator's situation; the truth switches on its own state) is parametrically
//! unstable for the estimator's errors: undamped, they grow ~20/s. While the base sticks, every
//! interval therefore starts from the state corrected towards the measured top acceleration,
//! z += G·(ü1_pred − ü1_meas), with G giving the stuck error map a double eigenvalue
//! e^(−b·p·Δt) (critically damped error dynamics at b·p, exact in discrete time)
//! ([`StickSlipConfig::observer_bandwidth`] = b, default 2; 0: open loop); the stored state stays
//! the prediction, so a sample's prediction never uses its own measurement.
//!
//! **Friction identification.** While the base slides, z = z_h + μ·z_u, where z_h is the free
//! evolution of the state at the start of the sliding episode and z_u the response to the friction
//! per unit μ: ü1 is linear in μ. The identification runs on blocks of `n` =
//! [`StickSlipConfig::identify_every`] sample intervals once they are final (`history − 2` samples
//! old, when no event can change them any more), at the marks: a block that slides throughout in
//! one direction without a switch advances both parts with the exact n-step maps Φs^n (composed
//! once, in f64, from the per-sample maps) and updates μ̂ by recursive least squares from the
//! measured top acceleration at the block's last sample against the unit-μ prediction (information
//! form, one division per update; forgetting λ^n per update, i.e. λ per sample); its standard
//! deviation comes from the residual variance. A block that slides throughout with reversals on
//! samples inside it continues the episode sample by sample. A block that slides throughout starts
//! an episode at its start if none is going on (z_h = the state there, z_u = 0); any other block
//! ends the episode, or, if the base slides at its end, starts a new one there. Whether a block
//! slides throughout is summarised once its intervals are in the history (at the previous mark)
//! and updated by every later event that reaches into it. With `use_identified_mu` the model adopts
//! μ̂ at the start of an episode once enough blocks were used. Storage for the history in a
//! multiple of `n` samples plus the copy slot ([`storage_for`]) puts the ring's wrap on a block's
//! mark: one mark per `n` samples.
//!
//! The coefficients ([`StickSlipCoefficients`]) are computed in f64 and rounded to `T`; in f32
//! they can also be restored from their bits (a build script computes them, the firmware image
//! then needs no f64 code but the few operations that derive the n-step maps at construction).

mod block;
mod breakaway;
mod coefficients;
mod config;
mod estimator;
mod events;
mod identify;
mod maps;
mod observer;
mod packed;
mod phase;
mod retune;
mod ring;
mod rls;
mod step;
mod update;

#[cfg(test)]
mod tests;

pub use coefficients::StickSlipCoefficients;
pub use config::{history_for_age, storage_for, StickSlipConfig, MAX_IDENTIFY_EVERY};
pub use estimator::StickSlipEstimator;
pub use packed::MAX_SWITCHES;
pub use phase::SlidingPhase;
pub use rls::MuEstimate;
