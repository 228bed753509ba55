//! The data and measurements of `host-sim bench` (the command: [`crate::cmd::bench`]): speed
//! against error of every method on three fixed scenes.
//!
//! Scenes (see [`scenes()`]):
//!
//! * `harmonic`: the built-in default scene (the paper's Table 1 specimen on 2 m/s² at 0.143 s,
//!   10 s at 10 kHz; `--quick`: 4 s). Errors over the second half (the steady state, so that the
//!   steady-state TFM/RFM can be compared).
//! * `long-train`: the Table 1 specimen made undamped (ξ = 0, so every reversal rings forever and
//!   the full closed form sums every term) under a prescribed alternating friction train every
//!   0.0715 s: 10^4 reversals, 715 s at 10 kHz = 7.15·10^6 samples (`--quick`: 10^3 reversals).
//!   The closed-form methods are timed and compared on 2000 evenly spaced samples (their cost per
//!   sample grows with the number of past reversals; evenly spaced samples give the run average);
//!   the recursion runs over every sample. The friction is prescribed, so there is no stick-slip
//!   truth: the closed form *is* the exact model. As a check of the closed form's own rounding, both
//!   are also compared with a double-double evaluation of the undamped sum.
//! * `earthquake`: `scenes/elcentro.toml` (El Centro 1940 NS on the Table 1 specimen, μ 0.2,
//!   μs 0.25; 32 s at 10 kHz; `--quick`: 12 s).
//!
//! Trains of the RDM methods (recursion, closed form, truncated closed form): on the harmonic scene
//! the paper's train (continuous reciprocating sliding, a reversal every T/2), phase-aligned with the
//! truth: its reversals to +F0 are at the upward zero crossings of the truth's friction force; on the
//! earthquake scene the friction train of the exact stick-slip truth (what the estimator sees from
//! the slip sensor: reversals, breakaways, and sticks as level 0). TFM and RFM are steady-state forms
//! for harmonic input, on the harmonic scene only, with the same phase (t = 0 of their friction
//! wave at the truth's upward zero crossing); they are not applicable to the other scenes (rows
//! skipped). On the harmonic scene RFM converges to the closed form; TFM's difference from it is
//! its trapezoid model.
//!
//! Cost: host nanoseconds per sample, the median of repeated runs after a warm-up run
//! (`std::time::Instant`), including the reversal pushes; for the truth, simulation plus sampling.
//! Error: max and RMS, in units of gμ, against the full f64 closed form (numerical error; for TFM,
//! RFM and the truth this includes their model difference) and against the truth (model error).
//!
//! * `scenes`: the three scenes; `measure`: every method on one scene ([`measure_scene`]);
//!   `double_double`: the double-double reference of `long-train`; `table`: the rows, the report
//!   and its [`markdown`].

mod double_double;
mod measure;
mod scenes;
mod table;

pub use measure::{m4f_instructions_per_sample, measure_scene};
pub use scenes::{elcentro_scene, scenes, BenchScene};
pub use table::{markdown, Report, Row, SceneInfo};
