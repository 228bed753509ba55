//! Error statistics that fail on non-finite values: `f64::max` drops NaN (`a.max(NaN) == a`), so a
//! method returning NaN would pass a bound checked on a plain running maximum.

/// `acc.max(value)`, failing on a non-finite `value`; the panic message names the quantity (`what`)
/// and where it occurred (`at`: a sample index, a time, a case).
#[track_caller]
pub fn max_finite(acc: f64, value: f64, what: &str, at: impl core::fmt::Display) -> f64 {
    assert!(value.is_finite(), "{what} at {at} is not finite: {value}");
    acc.max(value)
}

/// The maximum of `values` (0 when empty), failing on any non-finite one (reported with its
/// position in `values`).
#[track_caller]
pub fn finite_max(what: &str, values: impl IntoIterator<Item = f64>) -> f64 {
    values.into_iter().enumerate().fold(0.0, |m, (i, v)| {
        max_finite(m, v, what, format_args!("index {i}"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finite_values_give_the_maximum() {
        assert_eq!(finite_max("e", [1e-9, 3e-9, 0.0]), 3e-9);
        assert_eq!(finite_max("e", []), 0.0);
    }

    #[test]
    #[should_panic(expected = "ODE error at index 1 is not finite: NaN")]
    fn a_nan_fails() {
        // `fold(0.0, f64::max)` would return 1e-12.
        finite_max("ODE error", [1e-12, f64::NAN]);
    }

    #[test]
    #[should_panic(expected = "peak at t = 0.5 is not finite: -inf")]
    fn an_infinity_fails() {
        max_finite(0.0, f64::NEG_INFINITY, "peak", "t = 0.5");
    }
}
