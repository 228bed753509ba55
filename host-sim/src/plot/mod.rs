//! Figures (plotters).
//!
//! * [`run`]: the `run --plot` figure (SVG or PNG); its items are re-exported here
//!   (`plot::render`, `plot::format_of`, …).
//! * [`figure`]: the generic PNG figure (a grid of panels of series) of `bench` and `reproduce`.
//! * [`bench`](mod@bench): the bench's Pareto figures; [`reproduce`]: the paper's figures.
//! * `style`: the embedded font and the colour palette, shared by all.

pub mod bench;
pub mod figure;
pub mod reproduce;
pub mod robustness;
pub mod run;
mod style;

pub use run::{format_of, render, Format, SIZE};
