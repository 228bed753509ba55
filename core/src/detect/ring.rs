//! Sample indexing of the detectors' fixed-size rings: times relative to the current sample and
//! ring slots.

/// Time of sample i ≤ k relative to sample k (≤ 0), exact in f32 for any run length (the window
/// is at most the ring long; absolute sample indices would lose sub-sample resolution in f32).
#[inline(always)]
pub(super) fn rel(i: u64, k: u64) -> f32 {
    -(k.saturating_sub(i) as u32 as f32)
}

/// Ring slot of sample i: a mask for power-of-two rings (a 64-bit modulo is a library call on
/// the Cortex-M4F).
#[inline(always)]
pub(super) fn slot<const N: usize>(i: u64) -> usize {
    if N.is_power_of_two() {
        (i as usize) & (N - 1)
    } else {
        (i % N as u64) as usize
    }
}
