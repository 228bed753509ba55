//! The structure (`[structure]`): masses, natural frequency, damping and friction.

use crate::error::SceneError;
use crate::friction::RawFriction;
use crate::parse::{core_message, ParseContext};
use serde::Deserialize;
use ssvr_core::{FrictionLaw, Param, Structure, StructureParams};
use toml::Spanned;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawStructure {
    m1_kg: Spanned<f64>,
    m2_kg: Spanned<f64>,
    natural_frequency_hz: Option<Spanned<f64>>,
    natural_period_s: Option<Spanned<f64>>,
    damping_ratio: Spanned<f64>,
    friction_coefficient: Spanned<f64>,
    static_friction_coefficient: Option<Spanned<f64>>,
}

impl ParseContext<'_> {
    /// The `[structure]` table: the structure (its gravity `gravity`, the document's
    /// `gravity_m_s2` when given), the friction law (`[friction]`, over the structure's
    /// coefficient) and the static friction coefficient (at least the law's coefficient at rest,
    /// and that by default).
    pub(crate) fn structure(
        &self,
        table: &Spanned<RawStructure>,
        friction: Option<&Spanned<RawFriction>>,
        gravity: f64,
        gravity_v: &Option<Spanned<f64>>,
    ) -> Result<(Structure, f64, FrictionLaw), SceneError> {
        const S: Option<&str> = Some("structure");
        let r = table.get_ref();
        let (freq, freq_key, freq_v) =
            match (&r.natural_frequency_hz, &r.natural_period_s) {
                (Some(f), None) => (*f.get_ref(), "natural_frequency_hz", f),
                (None, Some(p)) => {
                    let period = self.check(
                        S,
                        "natural_period_s",
                        p,
                        *p.get_ref() > 0.0 && (1.0 / p.get_ref()).is_finite(),
                        "natural_period_s > 0 s",
                    )?;
                    (1.0 / period, "natural_period_s", p)
                }
                (Some(_), Some(p)) => return Err(self.err(
                    p.span(),
                    "[structure] natural_period_s: give natural_frequency_hz or natural_period_s, \
                     not both"
                        .into(),
                )),
                (None, None) => {
                    return Err(self.missing(
                        "structure",
                        table,
                        "missing key `natural_frequency_hz` (or `natural_period_s`)".into(),
                    ))
                }
            };
        let params = StructureParams {
            m1_kg: *r.m1_kg.get_ref(),
            m2_kg: *r.m2_kg.get_ref(),
            natural_frequency_hz: freq,
            damping_ratio: *r.damping_ratio.get_ref(),
            friction_coefficient: *r.friction_coefficient.get_ref(),
            gravity_m_s2: gravity,
        };
        let structure = Structure::new(params).map_err(|e| {
            let (key, span, value) = match e.param() {
                Param::M1 => ("[structure] m1_kg", r.m1_kg.span(), *r.m1_kg.get_ref()),
                Param::M2 => ("[structure] m2_kg", r.m2_kg.span(), *r.m2_kg.get_ref()),
                Param::NaturalFrequency => {
                    let key = if freq_key == "natural_period_s" {
                        "[structure] natural_period_s"
                    } else {
                        "[structure] natural_frequency_hz"
                    };
                    (key, freq_v.span(), *freq_v.get_ref())
                }
                Param::DampingRatio => (
                    "[structure] damping_ratio",
                    r.damping_ratio.span(),
                    *r.damping_ratio.get_ref(),
                ),
                Param::FrictionCoefficient => (
                    "[structure] friction_coefficient",
                    r.friction_coefficient.span(),
                    *r.friction_coefficient.get_ref(),
                ),
                Param::Gravity => match gravity_v {
                    Some(g) => ("gravity_m_s2", g.span(), gravity),
                    None => ("gravity_m_s2", table.span(), gravity),
                },
                _ => ("[structure]", table.span(), f64::NAN),
            };
            self.err(span, core_message(key, value, &e))
        })?;
        let law = self.friction(friction, structure.mu())?;
        let at_rest = law.at_rest(structure.mu());
        let mu_s = match &r.static_friction_coefficient {
            Some(v) => self.check(
                S,
                "static_friction_coefficient",
                v,
                *v.get_ref() >= at_rest,
                match law {
                    FrictionLaw::Coulomb => "static_friction_coefficient >= friction_coefficient",
                    FrictionLaw::VelocityDependent { .. } => {
                        "static_friction_coefficient >= [friction] mu_slow"
                    }
                },
            )?,
            None => at_rest,
        };
        Ok((structure, mu_s, law))
    }
}
