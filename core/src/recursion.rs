//! The estimator: eq (36) as an exact O(1)-per-sample recursion.
//!
//! Between friction reversals the friction is constant, so the relative motion is a free vibration
//! about a shifted equilibrium and its state at any later time is the exact state-transition matrix
//! times the state now. The recursion keeps that state in coordinates where the first component is
//! the free part of ü1 itself,
//!
//! ```text
//! w0 = −(p² d + 2pξ δ'),  w1 = ω0 δ',   d = δ − δ_eq,  δ_eq = −s gμ/p²,   ü1 = s·gμ + w0,
//! Ψ(τ) = [[ecm, −(p²/ω0)·es], [M·ω0·es, ecp]]          (see `free_vibration`)
//! ```
//!
//! and evaluates it without accumulating rounding error:
//!
//! * **Anchored table.** The state is stored once per block of `K` samples (the *anchor*, in f64);
//!   sample k of the block is `ü1 = s·gμ + Ψ00(kΔt)·w0 + Ψ01(kΔt)·w1`, with Ψ(kΔt) tabulated
//!   exactly (computed directly in f64 at construction, not by powers). A steady-state sample is
//!   two loads, a multiply, a fused multiply-add and an add; the error of a sample is the rounding
//!   of that one expression, independent of run length.
//! * **Exact re-anchoring.** Every `K` samples the anchor advances by Ψ(KΔt) in f64 (relative error
//!   ~1e-16 per block, so 10^7 samples drift < 1e-11).
//! * **Reversals.** A reversal to level L at τ = age·Δt before the current sample adds
//!   `(−ΔL·gμ)·(ecm(τ), M·ω0·es(τ))` to the state at the current sample and `ΔL·gμ` to s·gμ
//!   (ü1 stays continuous). The state at the current sample is re-anchored from the table
//!   (one rounding of Ψ per reversal, no accumulation). The transcendentals go through
//!   [`Transcendentals`] (`Libm` or `Micromath`). A late reversal (age > 1) is back-dated exactly:
//!   every sample from the next one on is right.
//!
//! All three damping regimes use the same code (the kernel is continuous across Mξ² = 1), and
//! every coefficient is finite for m2/m1 → 0.

use crate::closed_form::duhamel::ReversalTrain;
use crate::closed_form::free_vibration::Kernel;
use crate::error::{Error, Param};
use crate::math::{Libm, Real, Transcendentals};
use crate::structure::Structure;
use core::marker::PhantomData;

/// Largest accepted back-dating of a reversal, in samples.
pub const MAX_AGE_SAMPLES: f64 = 16_777_216.0;

/// Coefficients of the recursion, computed once (in f64) from a structure and a sample rate.
#[derive(Debug, Clone)]
#[repr(C)]
pub struct Coefficients<T, const K: usize> {
    /// Output row (Ψ00, Ψ01) at kΔt, k = 0..K.
    out: [[T; 2]; K],
    /// Second row (Ψ10, Ψ11) at kΔt, k = 0..K (used at reversals only).
    row1: [[T; 2]; K],
    /// Ψ(KΔt), row-major, in f64 (advances the anchor).
    advance: [f64; 4],
    kernel: Kernel<T>,
    /// M·ω0 (the factor of es in Ψ10).
    m_omega0: T,
    gmu: T,
    dt: T,
}

impl<T: Real, const K: usize> Coefficients<T, K> {
    /// Compute the coefficients for `structure` sampled at `sample_rate_hz`.
    pub fn new(structure: &Structure, sample_rate_hz: f64) -> Result<Self, Error> {
        crate::error::check_sample_rate(sample_rate_hz)?;
        if K == 0 {
            return Err(Error::OutOfRange {
                param: Param::TableLength,
                value: 0.0,
                expected: "a table of at least one sample (K >= 1)",
            });
        }
        let dt = 1.0 / sample_rate_hz;
        let k64 = Kernel::<f64>::new(structure);
        let omega0 = libm::sqrt(structure.omega0_sq());
        let m_omega0 = structure.mass_ratio() * omega0;
        let p2_omega0 = structure.p() * structure.p() / omega0;
        let psi = |tau: f64| {
            let f = k64.eval::<Libm>(tau);
            [f.ecm, -p2_omega0 * f.es, m_omega0 * f.es, f.ecp]
        };
        let mut out = [[T::ZERO; 2]; K];
        let mut row1 = [[T::ZERO; 2]; K];
        for (k, (o, r)) in out.iter_mut().zip(row1.iter_mut()).enumerate() {
            let m = psi(k as f64 * dt);
            *o = [T::from_f64(m[0]), T::from_f64(m[1])];
            *r = [T::from_f64(m[2]), T::from_f64(m[3])];
        }
        Ok(Self {
            out,
            row1,
            advance: psi(K as f64 * dt),
            kernel: Kernel::new(structure),
            m_omega0: T::from_f64(m_omega0),
            gmu: T::from_f64(structure.gmu()),
            dt: T::from_f64(dt),
        })
    }

    /// gμ (m/s²) in precision T.
    pub fn gmu(&self) -> T {
        self.gmu
    }

    /// The sample interval Δt (s).
    pub fn dt(&self) -> T {
        self.dt
    }
}

/// State of the recursion (apart from its coefficients).
///
/// Exact part: `anchor` (f64, block start) and `contrib` (the reversals of the current block,
/// anchored at block sample `kc`); they are combined only at block ends, with the exact f64 block
/// transition for `anchor`, so no table rounding ever accumulates. Per-sample part: `current`, the
/// state at block sample `kc` rounded to T, and `j = k − kc`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct State<T> {
    /// Samples since block sample `kc` (the block sample is k = kc + j, 0..=K).
    j: usize,
    /// K − kc: the block ends when j reaches it.
    limit: usize,
    /// The whole state at block sample `kc`, rounded to T (the per-sample expression uses it).
    current: [T; 2],
    /// s·gμ: the friction part of ü1.
    base: T,
    /// Friction level s (units of F0).
    level: T,
    /// Block sample of the last reversal (0 if none).
    kc: usize,
    /// Whether `contrib` holds a reversal of this block.
    has_contrib: bool,
    /// State contributed by the reversals of the current block, at block sample `kc`.
    contrib: [T; 2],
    /// The anchor rounded to T (used at reversals).
    anchor_t: [T; 2],
    /// Anchor state (w0, w1) at the first sample of the block, f64.
    anchor: [f64; 2],
    /// Number of completed blocks.
    blocks: u64,
}

impl<T: Real> State<T> {
    /// At rest, no friction, at the start of a block of `block_len` samples.
    fn at_rest(block_len: usize) -> Self {
        Self {
            anchor: [0.0; 2],
            anchor_t: [T::ZERO; 2],
            contrib: [T::ZERO; 2],
            current: [T::ZERO; 2],
            base: T::ZERO,
            level: T::ZERO,
            j: 0,
            kc: 0,
            limit: block_len,
            has_contrib: false,
            blocks: 0,
        }
    }
}

/// The estimator: predicts top-mass acceleration ü1 (m/s²) sample by sample from friction
/// reversals. `T` is the precision of the per-sample arithmetic, `M` the transcendental functions
/// used at reversals, `K` the block length between exact anchors (table of `K` entries).
// repr(C), state first: the per-sample fields sit at small offsets from the estimator's address and
// the output table right after them (saves the offset arithmetic on the M4F).
#[derive(Debug, Clone)]
#[repr(C)]
pub struct DuhamelRecursion<T: Real, M: Transcendentals<T> = Libm, const K: usize = 256> {
    state: State<T>,
    coef: Coefficients<T, K>,
    _m: PhantomData<M>,
}

/// The firmware default: f32 with micromath transcendentals at reversals (pure f32: ~270
/// instructions per reversal on the M4F, against ~2500 with libm, whose f32 functions use f64
/// internally; same accuracy at the small arguments of a reversal, see docs/PERFORMANCE.md).
pub type Estimator32 = DuhamelRecursion<f32, crate::math::F32Poly, 256>;
/// f32 with micromath transcendentals (the same as [`Estimator32`]).
pub type Estimator32Micromath = DuhamelRecursion<f32, crate::math::Micromath, 256>;
/// f32 with libm transcendentals.
pub type Estimator32Libm = DuhamelRecursion<f32, Libm, 256>;
/// The f64 estimator.
pub type Estimator64 = DuhamelRecursion<f64, Libm, 256>;

impl<T: Real, M: Transcendentals<T>, const K: usize> DuhamelRecursion<T, M, K> {
    /// Build the estimator for `structure` sampled at `sample_rate_hz`, at rest with no friction.
    pub fn new(structure: &Structure, sample_rate_hz: f64) -> Result<Self, Error> {
        Ok(Self {
            coef: Coefficients::new(structure, sample_rate_hz)?,
            state: State::at_rest(K),
            _m: PhantomData,
        })
    }

    /// The coefficients.
    pub fn coefficients(&self) -> &Coefficients<T, K> {
        &self.coef
    }

    /// The state.
    pub fn state(&self) -> &State<T> {
        &self.state
    }

    /// Back to rest, sample 0, no friction.
    pub fn reset(&mut self) {
        self.state = State::at_rest(K);
    }

    /// The prediction of ü1 (m/s²) at the current sample; then advance one sample.
    #[inline]
    pub fn update(&mut self) -> T {
        if self.state.j >= self.state.limit {
            return self.update_after_block_end();
        }
        let st = &mut self.state;
        let y = match self.coef.out.get(st.j) {
            Some(a) => st.base + a[0] * st.current[0] + a[1] * st.current[1],
            None => st.base,
        };
        st.j += 1;
        y
    }

    #[cold]
    #[inline(never)]
    fn update_after_block_end(&mut self) -> T {
        self.end_block();
        self.update()
    }

    /// Process a block of samples with no reversal inside: `out[i]` is the prediction of the i-th
    /// sample from the current one. Same results as calling [`Self::update`] `out.len()` times.
    pub fn update_block(&mut self, out: &mut [T]) {
        let mut out = out;
        while !out.is_empty() {
            if self.state.j >= self.state.limit {
                self.end_block();
            }
            let st = &mut self.state;
            let n = out.len().min(st.limit - st.j);
            let (head, tail) = out.split_at_mut(n);
            let (base, c0, c1) = (st.base, st.current[0], st.current[1]);
            let Some(rows) = self.coef.out.get(st.j..st.j + n) else {
                return;
            };
            for (y, a) in head.iter_mut().zip(rows) {
                *y = base + a[0] * c0 + a[1] * c1;
            }
            st.j += n;
            out = tail;
        }
    }

    /// Ψ(j·Δt)·v in f64 with the table (j < K) or the exact block transition (j = K).
    fn propagate(&self, j: usize, v0: f64, v1: f64) -> [f64; 2] {
        if let (Some(o), Some(r)) = (self.coef.out.get(j), self.coef.row1.get(j)) {
            [
                o[0].to_f64() * v0 + o[1].to_f64() * v1,
                r[0].to_f64() * v0 + r[1].to_f64() * v1,
            ]
        } else {
            let [a, b, c, d] = self.coef.advance;
            [a * v0 + b * v1, c * v0 + d * v1]
        }
    }

    /// At the end of a block: advance the anchor by the exact f64 transition Ψ(KΔt) and fold in
    /// the block's reversal contributions.
    #[cold]
    #[inline(never)]
    fn end_block(&mut self) {
        let st = self.state;
        let mut w = self.propagate(K, st.anchor[0], st.anchor[1]);
        if st.has_contrib {
            let c = self.propagate(K - st.kc, st.contrib[0].to_f64(), st.contrib[1].to_f64());
            w = [w[0] + c[0], w[1] + c[1]];
        }
        let st = &mut self.state;
        st.anchor = w;
        st.anchor_t = [T::from_f64(st.anchor[0]), T::from_f64(st.anchor[1])];
        st.current = st.anchor_t;
        st.contrib = [T::ZERO; 2];
        st.has_contrib = false;
        st.j = 0;
        st.kc = 0;
        st.limit = K;
        st.blocks += 1;
    }

    /// A friction reversal: the friction level (units of F0 = μ(m1+m2)g: +1, −1, or 0 when the base
    /// sticks) changed to `level` `age_samples` ≥ 0 sample intervals before the sample the next
    /// [`Self::update`] returns (a fraction for a sub-sample time; more than 1 for a late detection,
    /// which is back-dated exactly). Push several reversals in chronological order.
    pub fn push_reversal(&mut self, level: T, age_samples: T) -> Result<(), Error> {
        // Validation and arithmetic in T: no f64 on the reversal path (soft-float on the M4F).
        if !level.is_finite() {
            return Err(Error::NotFinite(Param::ReversalLevel));
        }
        if level < -T::ONE || level > T::ONE {
            return Err(out_of_range(
                Param::ReversalLevel,
                level,
                "a level in [-1, 1]",
            ));
        }
        if !age_samples.is_finite() {
            return Err(Error::NotFinite(Param::EventTime));
        }
        if age_samples < T::ZERO || age_samples > T::from_f64(MAX_AGE_SAMPLES) {
            return Err(out_of_range(
                Param::EventTime,
                age_samples,
                "0 <= age <= 2^24 samples",
            ));
        }
        let jump = level - self.state.level;
        if jump == T::ZERO {
            return Ok(());
        }
        if self.state.j >= self.state.limit {
            self.end_block();
        }
        let f = self.coef.kernel.eval::<M>(age_samples * self.coef.dt);
        let g = -(jump * self.coef.gmu);
        let st = &mut self.state;
        // The block's reversal contributions, moved to the current sample (small: a few gμ).
        let mut c = st.contrib;
        if let (Some(o), Some(r)) = (self.coef.out.get(st.j), self.coef.row1.get(st.j)) {
            c = [o[0] * c[0] + o[1] * c[1], r[0] * c[0] + r[1] * c[1]];
        }
        c[0] += g * f.ecm;
        c[1] += g * self.coef.m_omega0 * f.es;
        // The anchor's part at the current sample (rounded; used for this block only — the exact
        // f64 anchor is advanced separately at the block end).
        let a = st.anchor_t;
        let k = st.kc + st.j;
        let w = match (self.coef.out.get(k), self.coef.row1.get(k)) {
            (Some(o), Some(r)) => [o[0] * a[0] + o[1] * a[1], r[0] * a[0] + r[1] * a[1]],
            _ => a,
        };
        st.contrib = c;
        st.current = [w[0] + c[0], w[1] + c[1]];
        st.kc = k;
        st.limit = K - k;
        st.j = 0;
        st.has_contrib = true;
        st.level = level;
        st.base = level * self.coef.gmu;
        Ok(())
    }

    /// The current friction level.
    pub fn level(&self) -> T {
        self.state.level
    }

    /// Index of the sample the next [`Self::update`] returns.
    pub fn sample_index(&self) -> u64 {
        self.state.blocks * K as u64 + (self.state.kc + self.state.j) as u64
    }
}

fn out_of_range<T: Real>(param: Param, value: T, expected: &'static str) -> Error {
    Error::OutOfRange {
        param,
        value: value.to_f64(),
        expected,
    }
}

/// Feeds a [`ReversalTrain`] to an estimator sample by sample: before sample k (t_k = k/rate) it
/// pushes every reversal with t_{k−1} < t_j ≤ t_k (t_j ≤ t_0 for k = 0) with its exact age.
#[derive(Debug, Clone, Copy)]
pub struct TrainFeeder {
    next: usize,
    rate_hz: f64,
}

impl TrainFeeder {
    /// A feeder for sample rate `rate_hz`.
    pub fn new(rate_hz: f64) -> Self {
        Self { next: 0, rate_hz }
    }

    /// Push the reversals due at sample `k`; returns how many were pushed.
    pub fn feed<T: Real, M: Transcendentals<T>, const K: usize>(
        &mut self,
        train: &ReversalTrain<'_>,
        est: &mut DuhamelRecursion<T, M, K>,
        k: u64,
    ) -> Result<usize, Error> {
        let t = k as f64 / self.rate_hz;
        let mut pushed = 0;
        while let Some(r) = train.get(self.next) {
            if r.time_s > t {
                break;
            }
            let age = (t - r.time_s) * self.rate_hz;
            est.push_reversal(T::from_f64(r.level), T::from_f64(age))?;
            self.next += 1;
            pushed += 1;
        }
        Ok(pushed)
    }

    /// Number of reversals pushed so far.
    pub fn pushed(&self) -> usize {
        self.next
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::structure::{table1, StructureParams};
    use std::vec::Vec;

    #[test]
    fn block_processing_equals_sample_processing() {
        let s = table1();
        let mut a = Estimator32::new(&s, 1e4).unwrap();
        let mut b = a.clone();
        let mut ya = Vec::new();
        let mut yb = std::vec![0.0f32; 0];
        for (i, len) in [3usize, 700, 1, 256, 513].iter().enumerate() {
            let level = if i % 2 == 0 { 1.0 } else { -1.0 };
            a.push_reversal(level, 0.25).unwrap();
            b.push_reversal(level, 0.25).unwrap();
            for _ in 0..*len {
                ya.push(a.update());
            }
            let mut blk = std::vec![0.0f32; *len];
            b.update_block(&mut blk);
            yb.extend_from_slice(&blk);
        }
        assert_eq!(ya, yb);
        assert_eq!(a.sample_index(), b.sample_index());
        assert_eq!(a.sample_index(), 3 + 700 + 1 + 256 + 513);
    }

    #[test]
    fn bad_events_are_typed_errors() {
        let mut e = Estimator64::new(&table1(), 1e4).unwrap();
        assert_eq!(
            e.push_reversal(1.0, -0.5).unwrap_err().param(),
            Param::EventTime
        );
        assert_eq!(
            e.push_reversal(f64::NAN, 0.5).unwrap_err(),
            Error::NotFinite(Param::ReversalLevel)
        );
        assert_eq!(
            e.push_reversal(2.0, 0.5).unwrap_err().param(),
            Param::ReversalLevel
        );
        assert_eq!(
            Estimator64::new(&table1(), 0.0).unwrap_err().param(),
            Param::SampleRate
        );
        // Nothing was changed by the rejected events.
        assert_eq!(e.update(), 0.0);
    }

    #[test]
    fn reversal_on_a_sample_is_continuous_and_steps_to_gmu() {
        let s = table1();
        let mut e = Estimator64::new(&s, 1e4).unwrap();
        e.push_reversal(1.0, 0.0).unwrap();
        assert!(e.update().abs() < 1e-15);
        // m2 -> 0: the response jumps to gμ within a sample (eq 39).
        let tiny = Structure::new(StructureParams {
            m2_kg: 1e-9,
            ..*table1().params()
        })
        .unwrap();
        let mut e = Estimator64::new(&tiny, 1e4).unwrap();
        e.push_reversal(-1.0, 0.0).unwrap();
        e.update();
        assert!((e.update() + tiny.gmu()).abs() < 1e-6 * tiny.gmu());
    }
}
