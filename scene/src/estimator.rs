//! The estimator's prior (`[estimator]`): what the controller is told about the specimen. Every
//! key is optional and defaults to the `[structure]` value; the truth always uses `[structure]`.
//! The prior's static friction coefficient is `[estimator] static_friction_coefficient` when
//! given, else the `[structure]` one when it is at least the prior's kinetic coefficient, else
//! the prior's kinetic coefficient.

use crate::error::SceneError;
use crate::parse::{core_message, ParseContext};
use serde::Deserialize;
use ssvr_core::{FrictionLaw, Param, Structure, StructureParams};
use toml::Spanned;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawEstimator {
    m1_kg: Option<Spanned<f64>>,
    m2_kg: Option<Spanned<f64>>,
    natural_frequency_hz: Option<Spanned<f64>>,
    natural_period_s: Option<Spanned<f64>>,
    damping_ratio: Option<Spanned<f64>>,
    friction_coefficient: Option<Spanned<f64>>,
    static_friction_coefficient: Option<Spanned<f64>>,
    mu_slow: Option<Spanned<f64>>,
    rate_s_m: Option<Spanned<f64>>,
}

/// The estimator's prior of the specimen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prior {
    /// Masses, natural frequency, damping ratio, kinetic friction coefficient, gravity.
    pub params: StructureParams,
    /// Static friction coefficient (≥ the kinetic one at rest).
    pub static_friction_coefficient: f64,
    /// The friction law of the interface (`[friction]`; its μ_fast is `params`'
    /// friction coefficient).
    pub friction: FrictionLaw,
}

impl Prior {
    /// The prior that is the specimen itself (no `[estimator]` table).
    pub fn exact(
        structure: &Structure,
        static_friction_coefficient: f64,
        friction: FrictionLaw,
    ) -> Self {
        Self {
            params: *structure.params(),
            static_friction_coefficient,
            friction,
        }
    }
}

impl ParseContext<'_> {
    /// The `[estimator]` table over the specimen's `structure` and static coefficient `mu_s`.
    pub(crate) fn estimator(
        &self,
        table: Option<&Spanned<RawEstimator>>,
        structure: &Structure,
        mu_s: f64,
        friction: FrictionLaw,
    ) -> Result<Prior, SceneError> {
        const S: Option<&str> = Some("estimator");
        let Some(table) = table else {
            return Ok(Prior::exact(structure, mu_s, friction));
        };
        let r = table.get_ref();
        let base = structure.params();
        let val =
            |v: &Option<Spanned<f64>>, default: f64| v.as_ref().map_or(default, |v| *v.get_ref());
        let freq =
            match (&r.natural_frequency_hz, &r.natural_period_s) {
                (Some(_), Some(p)) => return Err(self.err(
                    p.span(),
                    "[estimator] natural_period_s: give natural_frequency_hz or natural_period_s, \
                     not both"
                        .into(),
                )),
                (None, Some(p)) => {
                    let period = self.check(
                        S,
                        "natural_period_s",
                        p,
                        *p.get_ref() > 0.0 && (1.0 / p.get_ref()).is_finite(),
                        "natural_period_s > 0 s",
                    )?;
                    1.0 / period
                }
                (f, None) => val(f, base.natural_frequency_hz),
            };
        let params = StructureParams {
            m1_kg: val(&r.m1_kg, base.m1_kg),
            m2_kg: val(&r.m2_kg, base.m2_kg),
            natural_frequency_hz: freq,
            damping_ratio: val(&r.damping_ratio, base.damping_ratio),
            friction_coefficient: val(&r.friction_coefficient, base.friction_coefficient),
            gravity_m_s2: base.gravity_m_s2,
        };
        let prior = Structure::new(params).map_err(|e| {
            let pick = |key: &'static str, v: &Option<Spanned<f64>>| match v {
                Some(v) => (key, v.span(), *v.get_ref()),
                None => (key, table.span(), f64::NAN),
            };
            let (key, span, value) = match e.param() {
                Param::M1 => pick("[estimator] m1_kg", &r.m1_kg),
                Param::M2 => pick("[estimator] m2_kg", &r.m2_kg),
                Param::NaturalFrequency => match &r.natural_period_s {
                    Some(_) => pick("[estimator] natural_period_s", &r.natural_period_s),
                    None => pick("[estimator] natural_frequency_hz", &r.natural_frequency_hz),
                },
                Param::DampingRatio => pick("[estimator] damping_ratio", &r.damping_ratio),
                Param::FrictionCoefficient => {
                    pick("[estimator] friction_coefficient", &r.friction_coefficient)
                }
                _ => ("[estimator]", table.span(), f64::NAN),
            };
            self.err(span, core_message(key, value, &e))
        })?;
        // The law the controller is told: the interface's, its values overridden by
        // `[estimator] mu_slow` and `rate_s_m`.
        let friction = match friction {
            FrictionLaw::Coulomb => {
                for (key, v) in [("mu_slow", &r.mu_slow), ("rate_s_m", &r.rate_s_m)] {
                    if let Some(v) = v {
                        return Err(self.err(
                            v.span(),
                            format!(
                                "[estimator] {key} applies to a [friction] law = \"velocity-dependent\" only"
                            ),
                        ));
                    }
                }
                FrictionLaw::Coulomb
            }
            FrictionLaw::VelocityDependent { mu_slow, rate_s_m } => {
                let slow = val(&r.mu_slow, mu_slow);
                let rate = val(&r.rate_s_m, rate_s_m);
                FrictionLaw::velocity_dependent(slow, rate, prior.mu()).map_err(|e| {
                    let pick = |key: &'static str, v: &Option<Spanned<f64>>| match v {
                        Some(v) => (key, v.span(), *v.get_ref()),
                        None => (key, table.span(), f64::NAN),
                    };
                    let (key, span, value) = match (e.param(), &r.mu_slow, &r.rate_s_m) {
                        (Param::FrictionRate, _, Some(_)) => {
                            pick("[estimator] rate_s_m", &r.rate_s_m)
                        }
                        (Param::MuSlow, Some(_), _) => pick("[estimator] mu_slow", &r.mu_slow),
                        _ => pick("[estimator] friction_coefficient", &r.friction_coefficient),
                    };
                    self.err(span, core_message(key, value, &e))
                })?
            }
        };
        let mu = friction.at_rest(prior.mu());
        let static_friction_coefficient = match &r.static_friction_coefficient {
            Some(v) => self.check(
                S,
                "static_friction_coefficient",
                v,
                *v.get_ref() >= mu,
                "static_friction_coefficient >= the estimator's friction coefficient at rest",
            )?,
            None if mu_s >= mu => mu_s,
            None => mu,
        };
        Ok(Prior {
            params: *prior.params(),
            static_friction_coefficient,
            friction,
        })
    }
}
