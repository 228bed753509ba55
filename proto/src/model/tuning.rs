//! The stick-slip model's online tuning: the top oscillator's f and ξ identified from the top
//! and base accelerometers ([`ssvr_core::oscillator_id`]), and adopted by the estimator
//! ([`StickSlipEstimator::retune`](ssvr_core::stick_slip::StickSlipEstimator::retune)) once they
//! are known well enough. Fuse mode only: it reads the top accelerometer.
//!
//! **Adoption policy.** Checked every [`CHECK_EVERY`] samples. A new f is adopted when its
//! relative standard deviation is below [`MAX_REL_STD_F`] and it differs from the f in use by
//! more than [`MIN_REL_CHANGE_F`] and three standard deviations; ξ likewise (relative standard
//! deviation below [`MAX_REL_STD_XI`], change above [`MIN_REL_CHANGE_XI`] and 3σ), adopted with
//! the f of the same check. Estimates outside half to twice the prior's f, or a ξ outside
//! [0, 0.9], are not adopted (a wrong specimen or bad channels, not an identification). The new
//! coefficients are computed in f64 by the same code as the plan's (bit for bit the same on the
//! host and on the M4F).

use ssvr_core::detect::EventStep;
use ssvr_core::oscillator_id::{GainEstimate, GainRows, OscillatorEstimate, OscillatorIdentifier};
use ssvr_core::stick_slip::StickSlipCoefficients;
use ssvr_core::{Structure, StructureParams};

/// Samples between two adoption checks.
pub const CHECK_EVERY: u32 = 1024;
/// Largest relative standard deviation of f̂ for adoption (5e-3: an f known to 0.5 % is far
/// better than a prior several % off, and later checks refine it; with 1e-3 the first adoption
/// came later and the scorecard's f rows had ~25 % more RMS error).
pub const MAX_REL_STD_F: f64 = 5e-3;
/// Smallest relative change of f worth adopting.
pub const MIN_REL_CHANGE_F: f64 = 1e-3;
/// Largest relative standard deviation of ξ̂ for adoption.
pub const MAX_REL_STD_XI: f64 = 0.05;
/// Smallest relative change of ξ worth adopting.
pub const MIN_REL_CHANGE_XI: f64 = 0.05;
/// Forgetting of the identification per sample (a memory of ~10 s at 10 kHz).
pub const FORGETTING_PER_SAMPLE: f64 = 0.99999;

/// Identification and adoption state; `G`: the top accelerometer's gain fit
/// ([`TopGainFit`](ssvr_core::oscillator_id::TopGainFit)), or `()` (none).
#[derive(Debug, Clone)]
pub struct Tuning<G = ()> {
    id: OscillatorIdentifier<f32, G>,
    adoption: Adoption,
    countdown: u32,
    /// The last gain estimate not yet taken.
    gain_estimate: Option<GainEstimate>,
    /// Checks until the next gain estimate.
    gain_countdown: u8,
    /// Samples of the rest before the input still to come: not identified ([`Self::after_rest`]).
    rest: u32,
}

/// Checks between two estimates of the top accelerometer's gain: each solves 4×4 normal
/// equations in f64 (at every check ~6 M4F instructions more per sample); the gain changes
/// slowly (El Centro: adopted at 0.8 s instead of 0.7 s).
pub const GAIN_EVERY_CHECKS: u8 = 4;

/// The adoption policy (module documentation) and the f and ξ in use: shared by the fuse mode's
/// tuning from the top accelerometer and the predict mode's from the base accelerometer
/// ([`BaseTuning`](super::base_tuning::BaseTuning)).
#[derive(Debug, Clone)]
pub struct Adoption {
    /// The prior, with the f and ξ in use.
    params: StructureParams,
    prior_f: f64,
    rate: f64,
    adoptions: u32,
    /// f and ξ in use confirmed or adopted from an estimate known well enough for both
    /// ([`Self::known`]).
    known: bool,
}

impl<G: GainRows<f32>> Tuning<G> {
    /// Tuning for the prior `params` at `rate` (`None` if the identifier cannot be set up for
    /// them: a natural frequency above an eighth of the rate).
    pub fn new(params: StructureParams, rate: f64) -> Option<Self> {
        // (The model starts at rest, as the specimen does.)
        let id =
            OscillatorIdentifier::new(rate, params.natural_frequency_hz, FORGETTING_PER_SAMPLE)
                .ok()?
                .starting_at_rest();
        Some(Self {
            id,
            adoption: Adoption::new(params, rate),
            countdown: CHECK_EVERY,
            gain_estimate: None,
            gain_countdown: GAIN_EVERY_CHECKS,
            rest: 0,
        })
    }

    /// The identifier skips the first `samples` samples, the rest before the input (the plan's
    /// `rest_samples`): they hold the accelerometers' noise only, which the least squares
    /// would count as information on f and ξ, the oscillator not in it. (On the default scene
    /// with everything combined and 0.5 s of rest, f̂ then came out 0.6 % off 0.11 s into the
    /// motion and was taken for known to 0.5 %.) The identifier then starts at the input's
    /// start, at rest ([`OscillatorIdentifier::starting_at_rest`]).
    #[must_use]
    pub fn after_rest(mut self, samples: u32) -> Self {
        self.rest = samples;
        self
    }

    /// The last estimate of the top accelerometer's gain relative to the base's, once: made
    /// every `GAIN_EVERY_CHECKS` checks with a gain fit ([`OscillatorIdentifier::gain_estimate`]).
    pub fn take_gain(&mut self) -> Option<GainEstimate> {
        self.gain_estimate.take()
    }

    /// A run of samples' top and base accelerations (a top NaN: missing or saturated).
    #[inline(always)]
    pub fn push_run(&mut self, top: &[f32], base: &[f32]) {
        if self.rest > 0 {
            self.push_after_rest(top, base);
        } else {
            self.id.push_run(top, base);
        }
    }

    /// A friction event `age` sample intervals before the next sample pushed, the base
    /// accelerometer's step and kink there: placed at its time in the identifier's block
    /// averages ([`OscillatorIdentifier::jump`]). Not during the rest (no samples identified, no
    /// event).
    pub fn jump(&mut self, age: f32, step: EventStep) {
        if self.rest == 0 {
            self.id.jump(age, step.step, step.kink);
        }
    }

    /// [`Self::push_run`] while the rest lasts: its samples skipped.
    #[cold]
    #[inline(never)]
    fn push_after_rest(&mut self, top: &[f32], base: &[f32]) {
        let n = (self.rest as usize).min(top.len());
        self.rest -= n as u32;
        if let (Some(t), Some(b)) = (top.get(n..), base.get(n..)) {
            self.id.push_run(t, b);
        }
    }

    /// The model's correction of the top accelerometer's gain (1/G), for f and ξ
    /// ([`OscillatorIdentifier::set_top_scale`]).
    #[inline(always)]
    pub fn set_top_scale(&mut self, scale: f32) {
        self.id.set_top_scale(scale);
    }

    /// Count `samples` samples; at a check, the coefficients to adopt, if any.
    pub fn check(&mut self, samples: u32) -> Option<StickSlipCoefficients<f32>> {
        if self.countdown > samples {
            self.countdown -= samples;
            return None;
        }
        self.countdown = CHECK_EVERY;
        self.gain_countdown = self.gain_countdown.saturating_sub(1);
        if self.gain_countdown == 0 {
            self.gain_countdown = GAIN_EVERY_CHECKS;
            self.gain_estimate = self.id.gain_estimate();
        }
        let e = self.id.estimate()?;
        self.adoption.adopt(&e)
    }

    /// Whether the f and ξ in use are known: an estimate with both known well enough adopted or
    /// confirmed them (the adoption policy's `known`).
    #[inline(always)]
    pub fn known(&self) -> bool {
        self.adoption.known()
    }

    /// The identifier's estimate.
    pub fn estimate(&self) -> Option<OscillatorEstimate> {
        self.id.estimate()
    }

    /// The f (Hz) and ξ in use, and how many times they were adopted.
    pub fn in_use(&self) -> (f64, f64, u32) {
        self.adoption.in_use()
    }

    /// A new top mass with the f and ξ in use: its coefficients (`None`: rejected, nothing
    /// changed).
    pub fn with_m1(&mut self, m1_kg: f64) -> Option<StickSlipCoefficients<f32>> {
        self.adoption.with_m1(m1_kg)
    }
}

impl Adoption {
    /// The prior `params` in use, coefficients for `rate`.
    pub fn new(params: StructureParams, rate: f64) -> Self {
        Self {
            params,
            prior_f: params.natural_frequency_hz,
            rate,
            adoptions: 0,
            known: false,
        }
    }

    /// The coefficients of an estimate the policy adopts, if it does.
    #[inline(never)]
    pub fn adopt(&mut self, e: &OscillatorEstimate) -> Option<StickSlipCoefficients<f32>> {
        let (f, xi) = (e.natural_frequency_hz, e.damping_ratio);
        let (f_use, xi_use) = (self.params.natural_frequency_hz, self.params.damping_ratio);
        let plausible = f > 0.5 * self.prior_f && f < 2.0 * self.prior_f;
        let known_f = e.natural_frequency_std_hz < MAX_REL_STD_F * f;
        if !(plausible && known_f) {
            return None;
        }
        let df = libm::fabs(f - f_use);
        let new_f = df > MIN_REL_CHANGE_F * f_use && df > 3.0 * e.natural_frequency_std_hz;
        let known_xi = (0.0..0.9).contains(&xi) && e.damping_ratio_std < MAX_REL_STD_XI * xi;
        let dxi = libm::fabs(xi - xi_use);
        let new_xi =
            known_xi && dxi > MIN_REL_CHANGE_XI * xi_use && dxi > 3.0 * e.damping_ratio_std;
        if !(new_f || new_xi) {
            self.known |= known_xi;
            return None;
        }
        let mut params = self.params;
        params.natural_frequency_hz = f;
        if known_xi {
            params.damping_ratio = xi;
        }
        let c = Structure::new(params)
            .and_then(|s| StickSlipCoefficients::<f32>::new(&s, self.rate))
            .ok()?;
        self.params = params;
        self.adoptions = self.adoptions.saturating_add(1);
        self.known |= known_xi;
        Some(c)
    }

    /// Whether the f and ξ in use are known: an estimate with both known well enough (f to
    /// [`MAX_REL_STD_F`], ξ to [`MAX_REL_STD_XI`]) was adopted or confirmed them; until then
    /// they are the prior's (or f alone is known).
    pub fn known(&self) -> bool {
        self.known
    }

    /// The prior with the f, ξ (and m1) in use.
    pub fn params(&self) -> StructureParams {
        self.params
    }

    /// Replace the prior in use (a new m1 with f and ξ rescaled: the base tuning's M).
    pub fn set_params(&mut self, params: StructureParams) {
        self.params = params;
    }

    /// A new top mass `m1_kg` with the f and ξ in use (fuse mode's M from the momentum
    /// balance): its coefficients, `None` (nothing changed) if the structure is rejected.
    pub fn with_m1(&mut self, m1_kg: f64) -> Option<StickSlipCoefficients<f32>> {
        let mut params = self.params;
        params.m1_kg = m1_kg;
        let c = Structure::new(params)
            .and_then(|s| StickSlipCoefficients::<f32>::new(&s, self.rate))
            .ok()?;
        self.params = params;
        Some(c)
    }

    /// The sample rate the coefficients are for (Hz).
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// The f (Hz) and ξ in use, and how many times they were adopted.
    pub fn in_use(&self) -> (f64, f64, u32) {
        (
            self.params.natural_frequency_hz,
            self.params.damping_ratio,
            self.adoptions,
        )
    }
}

/// What the model reports of its tuning.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OscillatorReport {
    /// The identifier's estimate (`None` before it has one).
    pub estimate: Option<OscillatorEstimate>,
    /// The natural frequency in use (Hz).
    pub natural_frequency_hz: f64,
    /// The damping ratio in use.
    pub damping_ratio: f64,
    /// Adoptions so far.
    pub adoptions: u32,
    /// The top mass in use (kg): the prior's, or the one the mass identification took (fuse
    /// mode from the momentum balance, predict mode from the slip starts).
    pub m1_kg: f64,
}

impl<G: GainRows<f32>> Tuning<G> {
    /// The report of [`Model::oscillator`](super::Model::oscillator).
    pub fn report(&self) -> OscillatorReport {
        self.adoption.report(self.estimate())
    }
}

impl Adoption {
    /// The report of an identifier's `estimate` and the f, ξ and m1 in use.
    pub fn report(&self, estimate: Option<OscillatorEstimate>) -> OscillatorReport {
        let (f, xi, n) = self.in_use();
        OscillatorReport {
            estimate,
            natural_frequency_hz: f,
            damping_ratio: xi,
            adoptions: n,
            m1_kg: self.params.m1_kg,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::base_tuning::test_params as params;
    use super::*;

    /// (top, base) of sample k: an oscillation from rest (any deterministic signal would do).
    fn sample(k: usize) -> (f32, f32) {
        let t = k as f32 * 1e-4;
        let s = (2.0 * core::f32::consts::PI * 7.0 * t).sin();
        (0.3 * s * t, s + 0.1 * (13.0 * t).sin())
    }

    /// `after_rest(n)`: the first n samples (the rest) are not identified; what follows is,
    /// from the input's start, as by a tuning that never saw the rest: the same estimate bit
    /// for bit, in runs that split the rest's end and one sample at a time.
    #[test]
    fn the_rest_is_not_identified() {
        let rest = 1_234;
        let (mut a, mut b, mut c) = (
            Tuning::<()>::new(params(), 10_000.0)
                .unwrap()
                .after_rest(rest as u32),
            Tuning::<()>::new(params(), 10_000.0).unwrap(),
            Tuning::<()>::new(params(), 10_000.0)
                .unwrap()
                .after_rest(rest as u32),
        );
        // The rest: noise that would bias the fit if it were identified.
        let junk: std::vec::Vec<(f32, f32)> = (0..rest)
            .map(|k| {
                (
                    ((k * 7919) % 13) as f32 - 6.0,
                    ((k * 104_729) % 11) as f32 - 5.0,
                )
            })
            .collect();
        let data: std::vec::Vec<(f32, f32)> = (0..3_000).map(sample).collect();
        let all: std::vec::Vec<(f32, f32)> = junk.iter().chain(&data).copied().collect();
        for run in all.chunks(16) {
            let (t, bs): (std::vec::Vec<f32>, std::vec::Vec<f32>) = run.iter().copied().unzip();
            a.push_run(&t, &bs);
        }
        for &(t, bs) in &data {
            b.push_run(&[t], &[bs]);
        }
        for &(t, bs) in &all {
            c.push_run(&[t], &[bs]);
        }
        let e = b.estimate();
        assert!(e.is_some());
        assert_eq!(a.estimate(), e);
        assert_eq!(c.estimate(), e);
    }

    /// `known`: not from a prior alone, nor from an estimate with f known and ξ not; from one
    /// that confirms the f and ξ in use (nothing adopted), or that is adopted with both known.
    #[test]
    fn known_once_both_are_confirmed_or_adopted() {
        let e = |f: f64, f_std: f64, xi: f64, xi_std: f64| OscillatorEstimate {
            natural_frequency_hz: f,
            natural_frequency_std_hz: f_std,
            damping_ratio: xi,
            damping_ratio_std: xi_std,
            blocks: 100,
        };
        let (f, xi) = (params().natural_frequency_hz, params().damping_ratio);
        let mut a = Adoption::new(params(), 10_000.0);
        assert!(!a.known());
        // f known and confirmed, ξ not known (σ 20 %): not known.
        assert!(a.adopt(&e(f, 1e-4 * f, xi, 0.2 * xi)).is_none());
        assert!(!a.known());
        // Both known, both confirmed: known, nothing adopted.
        assert!(a.adopt(&e(f, 1e-4 * f, xi, 1e-3 * xi)).is_none());
        assert!(a.known());
        assert_eq!(a.in_use().2, 0);
        // A prior 8 % off: adopted with ξ known.
        let mut b = Adoption::new(params(), 10_000.0);
        assert!(b.adopt(&e(1.08 * f, 1e-4 * f, xi, 0.2 * xi)).is_some());
        assert!(!b.known(), "f adopted, ξ not known");
        assert!(b.adopt(&e(f, 1e-4 * f, 2.0 * xi, 1e-3 * xi)).is_some());
        assert!(b.known());
    }
}
