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

/// The environment variable that skips the QEMU tests: `SSVR_SKIP_QEMU=1`.
pub const SKIP_QEMU_VAR: &str = "SSVR_SKIP_QEMU";

/// Whether a test that needs `qemu-system-arm` runs: `false` (with a "SKIPPED" line) only when
/// `SSVR_SKIP_QEMU=1` asks for it; otherwise QEMU must be installed (CI installs it, see
/// `.ci/run`) and its absence fails the test with a message saying how to install or skip.
#[track_caller]
pub fn qemu_tests_run() -> bool {
    if std::env::var(SKIP_QEMU_VAR).is_ok_and(|v| v == "1") {
        eprintln!("SKIPPED: {SKIP_QEMU_VAR}=1");
        return false;
    }
    require_qemu();
    true
}

/// Fails unless `qemu-system-arm` (or `$QEMU_SYSTEM_ARM`) runs.
#[track_caller]
pub fn require_qemu() {
    if let Err(e) = host_sim::qemu::image::require_qemu() {
        panic!(
            "{e}. The QEMU tests need it (CI installs it); set {SKIP_QEMU_VAR}=1 to skip them \
             explicitly."
        );
    }
}
