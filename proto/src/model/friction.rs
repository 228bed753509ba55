//! The stick-slip model under a velocity-dependent friction law ([`SlipFriction`]): the friction
//! coefficient of every sliding sample from the slip speed, μ(v) = μ_fast − (μ_fast − μ_slow)·
//! e^{−a|v|}, and (fuse mode) the law identified online and adopted.
//!
//! * **Slip speed**: v = ∫(ü2 − ü_g) dt by the trapezoidal rule over the base (offset-corrected
//!   by the detector) and table accelerometers, integrated at every sample (a slip start is
//!   reported a few samples late: the speed gained meanwhile is kept), reset to 0 at every stick
//!   the detector reports, and leaking with a 0.2 s time constant while the model is stuck (an
//!   accelerometer offset the detector has not tracked yet cannot build a speed between slides).
//!   Both are measured channels, so predict mode uses it too.
//! * **Friction per sample**: the interval k − 1 → k slides with μ((v_{k−1} + v_k)/2)
//!   ([`StickSlipEstimator::set_friction`](ssvr_core::stick_slip::StickSlipEstimator::set_friction)).
//! * **Identification** (fuse mode: it reads the top accelerometer): while sliding at
//!   |v| ≥ [`MIN_SPEED`], μ = |r·ü1 + (1 − r)·ü2|/g (eq 4) is one observation of the law
//!   ([`FrictionLawId`]), one sample in [`OBSERVE_EVERY`]; every [`CHECK_EVERY`] samples a fit
//!   is adopted when it exists.
//!
//! All in f32: the firmware and the host run this same code.

use ssvr_core::friction_id::{FrictionLawId, LawFit};
use ssvr_core::math::{F32Poly, Transcendentals};
use ssvr_core::FrictionLaw;

/// Slowest slip speed (m/s) whose friction is an observation: just after a stop the detector
/// still reports sliding while the base is stuck (holding force, not friction).
pub const MIN_SPEED: f32 = 2e-3;
/// Samples between two adoption checks (a multiple of the firmware's batch, so that a check falls
/// on a batch's end whether samples come one at a time or in batches).
pub const CHECK_EVERY: u32 = 1024;
const _: () = assert!(CHECK_EVERY.is_multiple_of(crate::pipeline::BATCH as u32));
/// An identified law is adopted when its μ_slow and μ_fast are within this factor of the
/// prior's (a fit outside means wrong data, not a friction law).
pub const PLAUSIBLE_FACTOR: f32 = 2.0;
/// Time constant of the slip speed's leak while stuck (s).
pub const LEAK_S: f64 = 0.2;
/// One sliding sample in this many is an observation of the law (the identification's cost per
/// sample divided by it; a 10 kHz run still gives thousands of observations per second of
/// sliding).
pub const OBSERVE_EVERY: u8 = 4;

/// The law in use and how it was identified (`run --json` `estimator.identified.friction`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionReport {
    /// The law in use.
    pub mu_slow: f32,
    /// μ_fast in use.
    pub mu_fast: f32,
    /// a in use (s/m).
    pub rate_s_m: f32,
    /// The last fit, if any (fuse mode).
    pub fit: Option<LawFit>,
    /// Times a fit was adopted.
    pub adoptions: u32,
}

/// The velocity-dependent friction of the stick-slip model.
#[derive(Debug, Clone)]
pub struct SlipFriction {
    mu_fast: f32,
    /// μ_fast − μ_slow.
    drop: f32,
    rate: f32,
    /// The prior's μ_slow and μ_fast (the adoption's plausibility bounds).
    prior: (f32, f32),
    /// Half the sample interval (s), and the leak factor per stuck sample.
    half_dt: f32,
    leak: f32,
    /// 1/g and r = m1/(m1 + m2).
    inv_g: f32,
    r: f32,
    v: f32,
    prev_acc: f32,
    id: Option<FrictionLawId>,
    /// Sliding samples until the next observation.
    skip: u8,
    countdown: u32,
    adoptions: u32,
    fit: Option<LawFit>,
}

impl SlipFriction {
    /// The law of a plan's specimen (None for Coulomb): `law` over `mu_fast`, sampled at
    /// `rate_hz`, masses and gravity for eq (4); identified online if `identify`.
    pub fn new(
        law: FrictionLaw,
        mu_fast: f64,
        (m1, m2, g): (f64, f64, f64),
        rate_hz: f64,
        identify: bool,
    ) -> Option<Self> {
        let FrictionLaw::VelocityDependent { mu_slow, rate_s_m } = law else {
            return None;
        };
        if law.is_coulomb(mu_fast) {
            return None;
        }
        let dt = 1.0 / rate_hz;
        Some(Self {
            mu_fast: mu_fast as f32,
            drop: (mu_fast - mu_slow) as f32,
            rate: rate_s_m as f32,
            prior: (mu_slow as f32, mu_fast as f32),
            half_dt: (0.5 * dt) as f32,
            leak: libm::exp(-dt / LEAK_S) as f32,
            inv_g: (1.0 / g) as f32,
            r: (m1 / (m1 + m2)) as f32,
            v: 0.0,
            prev_acc: 0.0,
            id: identify.then(|| FrictionLawId::new(mu_fast as f32)),
            skip: 0,
            countdown: CHECK_EVERY,
            adoptions: 0,
            fit: None,
        })
    }

    /// The coefficient at slip speed `v`.
    #[inline(always)]
    fn mu(&self, v: f32) -> f32 {
        self.mu_fast - self.drop * F32Poly::exp(-self.rate * v.abs())
    }

    /// A sample: base and table accelerations `base`, `table` (m/s²), the measured top
    /// acceleration `top` (NaN if unusable) and whether the model slides into it. Returns the
    /// friction coefficient of the interval that ends at this sample (sliding), else None.
    #[inline(always)]
    pub fn sample(&mut self, base: f32, table: f32, top: f32, sliding: bool) -> Option<f32> {
        let acc = if base.is_finite() && table.is_finite() {
            base - table
        } else {
            self.prev_acc
        };
        let v0 = self.v;
        let v1 = v0 + self.half_dt * (self.prev_acc + acc);
        let v1 = if sliding { v1 } else { v1 * self.leak };
        self.v = v1;
        self.prev_acc = acc;
        if !sliding {
            return None;
        }
        if let Some(id) = &mut self.id {
            if self.skip == 0 {
                let speed = v1.abs();
                if speed >= MIN_SPEED && top.is_finite() && base.is_finite() {
                    let mu = (self.r * top + (1.0 - self.r) * base).abs() * self.inv_g;
                    id.push(speed, mu);
                    self.skip = OBSERVE_EVERY;
                }
            }
            self.skip = self.skip.saturating_sub(1);
        }
        Some(self.mu(0.5 * (v0 + v1)))
    }

    /// A stuck sample (base and table accelerations; NaN: unusable): the slip speed only
    /// (integrated and leaking), as [`Self::sample`] does while stuck.
    #[inline(always)]
    pub fn stuck_sample(&mut self, base: f32, table: f32) {
        let acc = if base.is_finite() && table.is_finite() {
            base - table
        } else {
            self.prev_acc
        };
        self.v = (self.v + self.half_dt * (self.prev_acc + acc)) * self.leak;
        self.prev_acc = acc;
    }

    /// A stick reported by the detector: the slip speed is 0.
    pub fn stick(&mut self) {
        self.v = 0.0;
    }

    /// The coefficient for the intervals a late slip start re-simulates (from the start to now):
    /// μ at half the slip speed gained since (the per-sample values are not kept).
    pub fn since_slip_start(&self) -> f32 {
        self.mu(0.5 * self.v)
    }

    /// After `samples` more samples: adopt the identified law when a check is due and a fit
    /// exists.
    pub fn check(&mut self, samples: u32) {
        let Some(id) = &self.id else {
            return;
        };
        if self.countdown > samples {
            self.countdown -= samples;
            return;
        }
        self.countdown = CHECK_EVERY;
        let plausible =
            |x: f32, prior: f32| x * PLAUSIBLE_FACTOR >= prior && x <= prior * PLAUSIBLE_FACTOR;
        if let Some(fit) = id
            .fit()
            .filter(|f| plausible(f.mu_slow, self.prior.0) && plausible(f.mu_fast, self.prior.1))
        {
            self.mu_fast = fit.mu_fast;
            self.drop = fit.mu_fast - fit.mu_slow;
            self.rate = fit.rate_s_m;
            self.adoptions += 1;
            self.fit = Some(fit);
        }
    }

    /// The law in use and the last fit.
    pub fn report(&self) -> FrictionReport {
        FrictionReport {
            mu_slow: self.mu_fast - self.drop,
            mu_fast: self.mu_fast,
            rate_s_m: self.rate,
            fit: self.fit,
            adoptions: self.adoptions,
        }
    }
}

/// Where the stick-slip model keeps a velocity-dependent friction law: `Option<SlipFriction>`
/// (a plan with such a law: `StickSlipLawModel`), or `()` (Coulomb friction, and the fixed-base
/// model, which never slides: no code in the image, no room in the board's static RAM).
pub trait FrictionSlot: Clone + core::fmt::Debug {
    /// Whether it keeps a law (a plan with a velocity-dependent law needs one).
    const FOLLOWS_LAW: bool;
    /// No law.
    fn none() -> Self;
    /// The law of a plan's specimen (identified online in fuse mode).
    fn of_plan(plan: &crate::plan::Plan) -> Self;
    /// The law, if any.
    fn get(&self) -> Option<&SlipFriction>;
    /// The law, if any.
    fn get_mut(&mut self) -> Option<&mut SlipFriction>;
}

impl FrictionSlot for () {
    const FOLLOWS_LAW: bool = false;
    fn none() -> Self {}
    fn of_plan(_: &crate::plan::Plan) -> Self {}
    #[inline(always)]
    fn get(&self) -> Option<&SlipFriction> {
        None
    }
    #[inline(always)]
    fn get_mut(&mut self) -> Option<&mut SlipFriction> {
        None
    }
}

impl FrictionSlot for Option<SlipFriction> {
    const FOLLOWS_LAW: bool = true;
    fn none() -> Self {
        None
    }
    fn of_plan(plan: &crate::plan::Plan) -> Self {
        let p = &plan.specimen.structure;
        SlipFriction::new(
            plan.specimen.friction,
            p.friction_coefficient,
            (p.m1_kg, p.m2_kg, p.gravity_m_s2),
            plan.specimen.sample_rate_hz,
            plan.mode == crate::model::Mode::Fuse,
        )
    }
    #[inline(always)]
    fn get(&self) -> Option<&SlipFriction> {
        self.as_ref()
    }
    #[inline(always)]
    fn get_mut(&mut self) -> Option<&mut SlipFriction> {
        self.as_mut()
    }
}
