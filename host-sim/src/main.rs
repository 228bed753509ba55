//! host-sim: the host-side simulator and harness.
fn main() {}
