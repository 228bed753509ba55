//! The data and computations behind the reports of `bench` and `reproduce` (the commands are in
//! [`crate::cmd`], the figures in [`crate::plot`]).
//!
//! * [`bench`](mod@bench): the bench scenes, the measurement of every method and the result
//!   tables.
//! * [`reproduce`]: the seed paper's Table 2 and figures, and `report.md`.

pub mod bench;
pub mod reproduce;
pub mod robustness;
