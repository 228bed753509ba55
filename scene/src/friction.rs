//! The friction law of the sliding interface (`[friction]`): Coulomb (the default, and the
//! paper's), or velocity-dependent, μ(v) = μ_fast − (μ_fast − μ_slow)·e^{−a|v|} with μ_fast the
//! `[structure] friction_coefficient`.

use crate::error::SceneError;
use crate::parse::{core_message, ParseContext};
use serde::Deserialize;
use ssvr_core::{FrictionLaw, Param};
use toml::Spanned;

/// `[friction]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawFriction {
    law: Spanned<String>,
    mu_slow: Option<Spanned<f64>>,
    rate_s_m: Option<Spanned<f64>>,
}

impl ParseContext<'_> {
    /// The `[friction]` table over the kinetic coefficient `mu_fast` (`[structure]
    /// friction_coefficient`); Coulomb without it.
    pub(crate) fn friction(
        &self,
        table: Option<&Spanned<RawFriction>>,
        mu_fast: f64,
    ) -> Result<FrictionLaw, SceneError> {
        let Some(table) = table else {
            return Ok(FrictionLaw::Coulomb);
        };
        let r = table.get_ref();
        match r.law.get_ref().as_str() {
            "coulomb" => {
                for (key, v) in [("mu_slow", &r.mu_slow), ("rate_s_m", &r.rate_s_m)] {
                    if let Some(v) = v {
                        return Err(self.err(
                            v.span(),
                            format!(
                                "[friction] {key} applies to law = \"velocity-dependent\" only"
                            ),
                        ));
                    }
                }
                Ok(FrictionLaw::Coulomb)
            }
            "velocity-dependent" => {
                let mu_slow = r.mu_slow.as_ref().ok_or_else(|| {
                    self.missing("friction", table, "missing key `mu_slow`".into())
                })?;
                let rate = r.rate_s_m.as_ref().ok_or_else(|| {
                    self.missing("friction", table, "missing key `rate_s_m`".into())
                })?;
                FrictionLaw::velocity_dependent(*mu_slow.get_ref(), *rate.get_ref(), mu_fast)
                    .map_err(|e| {
                        let (key, v) = match e.param() {
                            Param::FrictionRate => ("[friction] rate_s_m", rate),
                            _ => ("[friction] mu_slow", mu_slow),
                        };
                        self.err(v.span(), core_message(key, *v.get_ref(), &e))
                    })
            }
            other => Err(self.err(
                r.law.span(),
                format!(
                    "[friction] law = \"{other}\": expected \"coulomb\" or \"velocity-dependent\""
                ),
            )),
        }
    }
}
