//! Helpers shared by the host-sim integration tests (`mod common;` in each test file).
#![allow(dead_code)]

/// `acc.max(value)`, failing on a non-finite `value`: `f64::max` drops NaN (`a.max(NaN) == a`), so an
/// estimator returning NaN would pass a bound checked on a plain running maximum. The panic message
/// names the quantity (`what`) and where it occurred (`at`: a sample index, a time, a case).
#[track_caller]
pub fn max_finite(acc: f64, value: f64, what: &str, at: impl std::fmt::Display) -> f64 {
    assert!(value.is_finite(), "{what} at {at} is not finite: {value}");
    acc.max(value)
}
