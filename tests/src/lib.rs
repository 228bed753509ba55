//! Cross-crate integration tests live in `tests/tests/`; this library holds their shared data and
//! the independent reference integrator.

pub mod finite;
pub mod ode;

/// The paper's Table 2 (defined once, in host-sim's `report::reproduce`).
pub use host_sim::report::reproduce::{Table2Row, PAPER_G as PAPER_GRAVITY_M_S2, TABLE2};
