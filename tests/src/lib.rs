//! Cross-crate integration tests live in `tests/tests/`; this library holds their shared data
//! and the independent reference integrator [`ode`] of the equations of motion (1)-(2).

pub mod ode;

/// One row of the paper's Table 2 (units as printed: s, gal).
#[derive(Debug, Clone, Copy)]
pub struct Table2Row {
    /// Test number.
    pub no: u32,
    /// Natural period of the specimen (s).
    pub natural_period_s: f64,
    /// m1/m2.
    pub mass_ratio_m1_m2: f64,
    /// ξ.
    pub xi: f64,
    /// μ.
    pub mu: f64,
    /// Input amplitude (gal).
    pub a0_gal: f64,
    /// Input period (s).
    pub period_s: f64,
    /// Measured peak (gal).
    pub test_gal: f64,
    /// The paper's TFM peak (gal).
    pub tfm_gal: f64,
    /// The paper's numerical peak (gal).
    pub num_gal: f64,
}

/// The paper's Table 2 (g = 980 gal in the paper).
pub const TABLE2: [Table2Row; 8] = [
    row(
        1, 0.13, 1.0, 0.0144, 0.20, 702.0, 0.125, 497.0, 561.0, 566.0,
    ),
    row(2, 0.184, 2.0, 0.016, 0.20, 125.5, 0.2, 381.0, 388.0, 388.0),
    row(3, 0.065, 2.0, 0.012, 0.20, 331.0, 0.1, 496.0, 528.0, 480.0),
    row(4, 0.065, 2.0, 0.012, 0.20, 436.0, 0.1, 597.0, 551.0, 597.0),
    row(5, 0.184, 2.0, 0.016, 0.20, 209.0, 0.2, 380.0, 393.0, 448.0),
    row(6, 0.20, 3.0, 0.016, 0.20, 158.0, 0.2, 381.0, 392.0, 382.0),
    row(7, 0.20, 3.0, 0.016, 0.20, 167.5, 0.2, 397.0, 392.0, 393.0),
    row(8, 0.09, 3.0, 0.016, 0.20, 192.5, 0.143, 430.0, 472.0, 329.0),
];

#[allow(clippy::too_many_arguments)]
const fn row(
    no: u32,
    natural_period_s: f64,
    mass_ratio_m1_m2: f64,
    xi: f64,
    mu: f64,
    a0_gal: f64,
    period_s: f64,
    test_gal: f64,
    tfm_gal: f64,
    num_gal: f64,
) -> Table2Row {
    Table2Row {
        no,
        natural_period_s,
        mass_ratio_m1_m2,
        xi,
        mu,
        a0_gal,
        period_s,
        test_gal,
        tfm_gal,
        num_gal,
    }
}

/// The paper's gravity, 980 gal, in m/s².
pub const PAPER_GRAVITY_M_S2: f64 = 9.80;

impl Table2Row {
    /// The row's structure (m2 = 1 kg, m1 = ratio; only the ratio matters), in SI with g = 9.80.
    pub fn structure(&self) -> ssvr_core::Structure {
        ssvr_core::Structure::new(ssvr_core::StructureParams {
            m1_kg: self.mass_ratio_m1_m2,
            m2_kg: 1.0,
            natural_frequency_hz: 1.0 / self.natural_period_s,
            damping_ratio: self.xi,
            friction_coefficient: self.mu,
            gravity_m_s2: PAPER_GRAVITY_M_S2,
        })
        .expect("Table 2 parameters are valid")
    }
}
