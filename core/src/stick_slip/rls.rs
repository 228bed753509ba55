//! Recursive least squares for the friction coefficient, and the estimate it gives.

use crate::math::Real;

/// The identified friction coefficient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MuEstimate {
    /// μ̂.
    pub mu: f64,
    /// Standard deviation of μ̂.
    pub std: f64,
    /// Identification blocks used (RLS updates: one per block of
    /// [`StickSlipConfig::identify_every`](super::StickSlipConfig::identify_every) samples).
    pub blocks: u32,
}

#[derive(Debug, Clone, Copy)]
/// Recursive least squares for one parameter with forgetting λ (per update), in information
/// form: a = λa + φ², b = λb + φ·t, μ̂ = b/a (the classic RLS gain form in exact arithmetic,
/// P = 1/a; one division per update instead of two). `e2` tracks the a-priori residual's mean
/// square (smoothing `alpha` per update).
pub(super) struct Rls<T> {
    pub(super) mu: T,
    pub(super) a: T,
    pub(super) b: T,
    pub(super) lambda: T,
    pub(super) e2: T,
    pub(super) alpha: T,
    pub(super) n: u32,
}

impl<T: Real> Rls<T> {
    /// One update with regressor `phi` and target `target`; an update that would leave the
    /// information or the estimate non-finite (an absurd measurement) is skipped, so one bad
    /// sample cannot poison μ̂ for good.
    #[inline(always)]
    pub(super) fn update(&mut self, phi: T, target: T) {
        let e = target - self.mu * phi;
        let a = self.lambda * self.a + phi * phi;
        let b = self.lambda * self.b + phi * target;
        let mu = b / a;
        let e2 = self.e2 + (e * e - self.e2) * self.alpha;
        // (b non-finite makes μ so too.)
        if a.is_finite() && mu.is_finite() && e2.is_finite() {
            (self.a, self.b, self.mu, self.e2) = (a, b, mu, e2);
            self.n = self.n.saturating_add(1);
        }
    }
}
